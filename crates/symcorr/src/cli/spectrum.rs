//! `symcorr spectrum MESH --k 100 [--json]`: vertex/face counts, repair report, the k smallest
//! Laplace–Beltrami eigenvalues and the wall time of each stage.
//!
//! The mesh is repaired with the default `symcorr_mesh::RepairOptions` first (load time
//! includes it). JSON keys (stable; benchmarks read them): `mesh`, `vertices` and `triangles`
//! (of the input file), `repair` (counts, plus `vertices_after`/`triangles_after`), `k`,
//! `eigenvalues`, `timings_s` {`load`, `laplacian`, `factorization`, `lanczos`, `hks`, `total`},
//! `lanczos_iterations`, `residual_max`.

use super::CliError;
use serde_json::{json, Value};
use std::path::PathBuf;
use std::time::Instant;
use symcorr_spectral::{eigenpairs, hks, hks_times, si_hks, EigenOptions, Laplacian, SiHksParams};

/// Arguments of `symcorr spectrum`.
#[derive(clap::Args)]
pub struct SpectrumArgs {
    /// Mesh file (OBJ, OFF, PLY, glTF/GLB).
    pub mesh: PathBuf,
    /// Number of eigenpairs.
    #[arg(long, default_value_t = 100)]
    pub k: usize,
    /// Print machine-readable JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: SpectrumArgs, max_input_bytes: u64) -> Result<(), CliError> {
    let (out, text) = compute(&args, max_input_bytes)?;
    if args.json {
        println!("{out}");
    } else {
        print!("{text}");
    }
    Ok(())
}

/// Runs the stages; returns the JSON document and the human-readable table.
fn compute(args: &SpectrumArgs, max_input_bytes: u64) -> Result<(Value, String), CliError> {
    use std::fmt::Write;
    let path = args.mesh.display().to_string();
    let total = Instant::now();

    let clock = Instant::now();
    // MeshError messages already name the file.
    let input =
        symcorr::io::read_mesh(&args.mesh, max_input_bytes).map_err(|e| CliError(e.to_string()))?;
    // Default repair: drop degenerate/zero-area/duplicate triangles and unreferenced vertices
    // (the Laplacian needs every vertex to have positive mass).
    let repaired = symcorr_mesh::repair(&input, &symcorr_mesh::RepairOptions::default())
        .map_err(|e| CliError::with(&path, e))?;
    let mesh = repaired.mesh;
    let load_s = clock.elapsed().as_secs_f64();
    let repair = symcorr::output::repair_json(&repaired.report, &mesh);

    // k ≥ n and k too large for the solver's memory are refused by `eigenpairs` (one
    // source of truth for the bound), before anything is printed.
    if args.k == 0 {
        return Err(CliError(format!("{path}: --k must be at least 1, got 0")));
    }

    let clock = Instant::now();
    let lap = Laplacian::new(&mesh).map_err(|e| CliError::with(&path, e))?;
    let laplacian_s = clock.elapsed().as_secs_f64();

    let eig =
        eigenpairs(&lap, args.k, &EigenOptions::default()).map_err(|e| CliError::with(&path, e))?;

    // HKS at 16 log-spaced times and the default si-HKS: the descriptors matching uses.
    let clock = Instant::now();
    let h = hks(&eig, &hks_times(&eig, 16));
    let s = si_hks(&eig, &SiHksParams::default()).map_err(|e| CliError::with(&path, e))?;
    let hks_s = clock.elapsed().as_secs_f64();
    debug_assert_eq!(h.nrows(), s.nrows());
    let total_s = total.elapsed().as_secs_f64();

    let timings = json!({
        "load": load_s,
        "laplacian": laplacian_s,
        "factorization": eig.factorization_s,
        "lanczos": eig.lanczos_s,
        "hks": hks_s,
        "total": total_s,
    });
    let out = json!({
            "mesh": path,
            "vertices": input.num_vertices(),
            "triangles": input.num_triangles(),
            "repair": repair,
            "k": args.k,
            "eigenvalues": eig.values,
            "timings_s": timings,
            "lanczos_iterations": eig.iterations,
            "residual_max": eig.residual_max,
    });
    let mut t = String::new();
    // Writing to a String cannot fail.
    let _ = writeln!(t, "mesh       {path}");
    let _ = writeln!(t, "vertices   {}", input.num_vertices());
    let _ = writeln!(t, "triangles  {}", input.num_triangles());
    let _ = writeln!(t, "{}", repaired.report);
    let _ = writeln!(
        t,
        "eigenvalues (k = {}, {} Lanczos steps, max residual {:.1e}):",
        args.k, eig.iterations, eig.residual_max
    );
    for (row, chunk) in eig.values.chunks(6).enumerate() {
        let line: Vec<String> = chunk.iter().map(|v| format!("{v:>14.8e}")).collect();
        let _ = writeln!(t, "  {:>4}  {}", row * 6, line.join(" "));
    }
    let _ = writeln!(t, "timings (s):");
    for key in [
        "load",
        "laplacian",
        "factorization",
        "lanczos",
        "hks",
        "total",
    ] {
        let v = out["timings_s"][key].as_f64().unwrap_or(f64::NAN);
        let _ = writeln!(t, "  {key:<14}{v:.4}");
    }
    Ok((out, t))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(mesh: &str, k: usize) -> SpectrumArgs {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        SpectrumArgs {
            mesh: root.join(mesh),
            k,
            json: true,
        }
    }

    #[test]
    fn spectrum_json_has_stable_keys_and_eigenvalues() {
        let (out, text) = compute(
            &args("fixtures/spectral/ref_mesh.off", 8),
            symcorr_mesh::io::DEFAULT_MAX_INPUT_BYTES,
        )
        .unwrap();
        for key in [
            "vertices",
            "triangles",
            "repair",
            "eigenvalues",
            "timings_s",
        ] {
            assert!(out.get(key).is_some(), "missing {key}");
        }
        assert_eq!(out["vertices"], 1002);
        let ev: Vec<f64> = out["eigenvalues"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        assert_eq!(ev.len(), 8);
        assert_eq!(ev[0], 0.0);
        assert!(ev.windows(2).all(|w| w[0] <= w[1]));
        for stage in ["load", "laplacian", "factorization", "lanczos", "hks"] {
            assert!(out["timings_s"][stage].as_f64().unwrap() >= 0.0);
        }
        assert!(text.contains("eigenvalues (k = 8"));
    }

    #[test]
    fn spectrum_errors_are_one_line() {
        let e = compute(
            &args("fixtures/spectral/ref_mesh.off", 0),
            symcorr_mesh::io::DEFAULT_MAX_INPUT_BYTES,
        )
        .unwrap_err();
        assert!(e.0.contains("--k") && !e.0.contains('\n'));
        let e = compute(
            &args("fixtures/spectral/no_such_mesh.off", 5),
            symcorr_mesh::io::DEFAULT_MAX_INPUT_BYTES,
        )
        .unwrap_err();
        assert!(e.0.contains("no_such_mesh.off") && !e.0.contains('\n'));
    }
}
