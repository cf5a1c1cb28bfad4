//! Prints attachment stage timings on a synth body, joint planes and the learned MakeHuman
//! convention side by side: `cargo run --release -p symcorr-attach
//! --example attach_timing [MESH.ply JOINTS.json]`.

use symcorr_attach::{attach, AttachOptions, BoundaryConvention, Joint, Skeleton};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/synth/bodies");
    let mesh_path = args
        .get(1)
        .cloned()
        .unwrap_or(format!("{root}/meshes/s0_walk-10.ply"));
    let joints_path = args
        .get(2)
        .cloned()
        .unwrap_or(format!("{root}/joints/s0_walk-10.json"));
    let mesh = match symcorr_mesh::io::read(&mesh_path) {
        Ok(m) => m.mesh,
        Err(e) => return eprintln!("{e}"),
    };
    let text = std::fs::read_to_string(&joints_path).unwrap_or_default();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap_or_default();
    let mut sk = Skeleton::from_arrays([[0.0; 3]; 20]);
    for j in Joint::ALL {
        if let Some(a) = v["frames"][0]["joints"][j.name()].as_array() {
            sk.positions[j.index()] =
                nalgebra::Point3::from(std::array::from_fn(|k| a[k].as_f64().unwrap_or(f64::NAN)));
        }
    }
    // Side by side in one run: the default joint planes and the learned MakeHuman convention.
    let variants = [
        ("joint planes", AttachOptions::default()),
        (
            "makehuman convention",
            AttachOptions {
                convention: Some(BoundaryConvention::makehuman()),
                ..AttachOptions::default()
            },
        ),
    ];
    for rep in 0..5 {
        for (name, options) in &variants {
            let t = std::time::Instant::now();
            match attach(&mesh, &sk, options) {
                Ok(a) => {
                    if rep == 0 && name == &"joint planes" {
                        for m in &a.diagnostics.joint_moves {
                            println!(
                                "{:?} {:?} -> {:?} {:.4} {}",
                                m.joint,
                                m.from,
                                m.to,
                                m.distance(),
                                m.reason
                            );
                        }
                    }
                    println!(
                        "{name}: {} vertices: {:.3} s total, stages {:?}",
                        mesh.num_vertices(),
                        t.elapsed().as_secs_f64(),
                        a.diagnostics.timings_s
                    );
                }
                Err(e) => return eprintln!("{e}"),
            }
        }
    }
}
