//! Prints what a mesh file holds and what validation finds.
//!
//! `cargo run --release -p symcorr-mesh --example meshinfo -- MESH [OUT]` — with OUT, also
//! writes the repaired mesh (format by OUT's extension).

use std::time::Instant;

use symcorr_mesh::{io, repair, RepairOptions};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(path) = args.first() else {
        eprintln!("usage: meshinfo MESH [OUT]");
        std::process::exit(2);
    };
    let t = Instant::now();
    let loaded = match io::read(path) {
        Ok(m) => m,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    let read_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let fixed = match repair(&loaded.mesh, &RepairOptions::default()) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {path}: {e}");
            std::process::exit(1);
        }
    };
    let repair_s = t.elapsed().as_secs_f64();
    println!(
        "{path}: {} vertices, {} triangles, colours: {}, area {:.6}",
        loaded.mesh.num_vertices(),
        loaded.mesh.num_triangles(),
        loaded.colors.is_some(),
        loaded.mesh.total_area()
    );
    println!("{}", fixed.report);
    println!("read {read_s:.4} s, validate+repair {repair_s:.4} s");
    if let Some(out) = args.get(1) {
        let colors: Option<Vec<[u8; 3]>> = loaded
            .colors
            .map(|c| fixed.vertex_map.iter().map(|&v| c[v as usize]).collect());
        let t = Instant::now();
        if let Err(e) = io::write(out, &fixed.mesh, colors.as_deref()) {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
        println!("wrote {out} in {:.4} s", t.elapsed().as_secs_f64());
    }
}
