//! `symcorr demo [--out DIR]`: the whole pipeline on a bundled pair of posed bodies with
//! different shapes, with and without the skeleton filter.

use super::bench::table;
use super::match_cmd::write_coloured;
use super::progress::Spinner;
use super::CliError;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;
use symcorr::bench::{evaluate_pair, evaluate_surface_points, BenchReport, PairResult};
use symcorr::io::{read_mesh, read_skeleton};
use symcorr::output::{correspondence_json, curve_svg, pair_timings};
use symcorr::{Method, Mode, Pipeline, PipelineOptions};
use symcorr_correspond::PaperFilter;
use symcorr_eval::{cumulative_curve, table1_row, Dataset, EvalGraph};
use symcorr_mesh::io::OutputBatch;

/// Arguments of `symcorr demo`.
#[derive(clap::Args, Debug)]
#[command(after_help = "Examples:
  symcorr demo
  symcorr demo --out /tmp/demo --dense")]
pub struct DemoArgs {
    /// Output folder.
    #[arg(long, default_value = "symcorr-demo")]
    pub out: PathBuf,
    /// Bundled dataset folder (default: the repository's fixtures/synth/bodies).
    #[arg(long, value_name = "DIR")]
    pub fixtures: Option<PathBuf>,
    /// Match every template vertex instead of a 1,000-point sample.
    #[arg(long)]
    pub dense: bool,
    /// Template points in sparse mode.
    #[arg(long, default_value_t = symcorr::DEFAULT_SAMPLES)]
    pub samples: usize,
}

/// The demo's default fixture folder: the repository's copy (path fixed at compile time).
fn default_fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/synth/bodies")
}

/// The pair shown: the first pair of the fixtures' pairs file whose two bodies have different
/// shapes (names `SHAPE_POSE…`), else the first pair.
fn demo_pair(ds: &Dataset) -> (String, String) {
    let shape = |n: &str| n.split('_').next().unwrap_or(n).to_string();
    ds.pairs
        .iter()
        .find(|(a, b)| shape(a) != shape(b))
        .or(ds.pairs.first())
        .cloned()
        // Invariant: Dataset::open refuses a dataset without pairs.
        .unwrap_or_default()
}

pub fn run(args: DemoArgs, max_input_bytes: u64) -> Result<(), CliError> {
    if args.samples == 0 {
        return Err(CliError("--samples must be at least 1".into()));
    }
    let fixtures = args.fixtures.clone().unwrap_or_else(default_fixtures);
    let ds = Dataset::open(&fixtures, None).map_err(|e| {
        CliError(format!(
            "{e} (bundled fixtures not found; pass --fixtures DIR)"
        ))
    })?;
    let (a_name, b_name) = demo_pair(&ds);
    let options = PipelineOptions {
        mode: if args.dense {
            Mode::Dense
        } else {
            Mode::Sparse {
                samples: args.samples,
            }
        },
        ..PipelineOptions::default()
    };
    // Every method runs on the same prepared meshes: prepare the data of each.
    let methods = [Method::Articulated, Method::Refined, Method::Paper];
    let start = Instant::now();
    let spin = Spinner::new("preparing meshes");
    let load = |name: &str| -> Result<(symcorr::PreparedMesh, f64), CliError> {
        let t = Instant::now();
        let mesh =
            read_mesh(&ds.meshes[name], max_input_bytes).map_err(|e| CliError(e.to_string()))?;
        let sk = read_skeleton(&ds.joints[name], None).map_err(|e| CliError(e.to_string()))?;
        let p = symcorr::PreparedMesh::new(mesh, &sk, &methods, &options.prepare)
            .map_err(|e| CliError::with(ds.meshes[name].display(), e))?;
        Ok((p, t.elapsed().as_secs_f64()))
    };
    let (a, b) = rayon::join(|| load(&a_name), || load(&b_name));
    let ((a, ta), (b, tb)) = (a?, b?);
    let graph = EvalGraph::new(&b.mesh);
    let mut results = Vec::new();
    // symcorr's default method first (its output is written), its spectral method, then the
    // paper's pipeline with and without its skeleton filter (the ablation).
    let variants = [
        (
            Method::Articulated,
            PaperFilter::DEFAULT,
            "articulated",
            "symcorr articulated",
        ),
        (
            Method::Refined,
            PaperFilter::DEFAULT,
            "refined",
            "symcorr refined (spectral)",
        ),
        (
            Method::Paper,
            PaperFilter::DEFAULT,
            "paper",
            "paper, skeleton filter",
        ),
        (
            Method::Paper,
            PaperFilter::Off,
            "paper, no filter",
            "paper, no filter (ablation)",
        ),
    ];
    for (method, filter, tag, _) in variants {
        spin.set(&format!("matching ({tag})"));
        let mut o = options.clone();
        o.method = method;
        o.matching.filter = filter;
        let t = Instant::now();
        let corr = Pipeline::new(o)
            .run(&a, &b)
            .map_err(|e| CliError(e.to_string()))?;
        let match_seconds = t.elapsed().as_secs_f64();
        let (evaluation, conf) = evaluate_pair(&a, &b, None, &graph, &corr, ds.mirror.as_deref());
        let row = table1_row(&evaluation.errors, &conf);
        results.push(PairResult {
            template: a_name.clone(),
            target: format!("{b_name} ({tag})"),
            surface_errors: evaluate_surface_points(&a, &b, None, &graph, &corr),
            correspondence: corr,
            // Two whole bodies: no view to turn a skeleton towards.
            turned_target: None,
            evaluation,
            table1_row: row,
            scan: None,
            seconds: ta + tb + match_seconds,
            match_seconds,
        });
    }
    spin.finish();
    std::fs::create_dir_all(&args.out).map_err(|e| CliError::with(args.out.display(), e))?;
    let main = &results[0];
    // Staged, then committed together: an error leaves none of the demo's files.
    let mut batch = OutputBatch::new();
    let cli = |e: symcorr_mesh::MeshError| CliError(e.to_string());
    let corr_path = args.out.join("correspondence.json");
    let doc = correspondence_json(
        &ds.meshes[&a_name].display().to_string(),
        &a,
        &ds.meshes[&b_name].display().to_string(),
        &b,
        &main.correspondence,
        &pair_timings(&a, &b, &main.correspondence),
    );
    batch
        .add(&corr_path, doc.to_json().as_bytes())
        .map_err(cli)?;
    write_coloured(&mut batch, &args.out, &a, &b, &main.correspondence)?;
    // The pair page, with the dataset's ground truth (`symcorr view`).
    let page = super::view::pair_html(
        &doc,
        &corr_path.display().to_string(),
        (&ds.meshes[&a_name], &ds.meshes[&b_name]),
        Some(&fixtures),
        max_input_bytes,
    )?;
    batch
        .add(&args.out.join("view.html"), page.as_bytes())
        .map_err(cli)?;
    let curves: Vec<(String, Vec<(f64, f64)>)> = results
        .iter()
        .zip(variants.iter().map(|v| v.3))
        .map(|(r, l)| {
            (
                l.to_string(),
                cumulative_curve(&r.evaluation.errors, 0.25, 100),
            )
        })
        .collect();
    let plot = args.out.join("curve.svg");
    let svg = curve_svg(&format!("{a_name} → {b_name}"), &curves, 0.25);
    batch.add(&plot, svg.as_bytes()).map_err(cli)?;
    let files = batch.commit().map_err(cli)?;
    let report = BenchReport {
        pairs: results,
        prepare_seconds: BTreeMap::new(),
        wall_seconds: start.elapsed().as_secs_f64(),
        prepared: BTreeMap::new(),
    };
    println!(
        "symcorr demo: {} ({} vertices) → {} ({} vertices), {} mode",
        a_name,
        a.num_vertices(),
        b_name,
        b.num_vertices(),
        if args.dense { "dense" } else { "sparse" }
    );
    print!("{}", table(&report, false));
    let row: Vec<String> = report.pairs[0]
        .table1_row
        .iter()
        .map(|x| format!("{x:.3}"))
        .collect();
    println!(
        "Table 1 row (best 10 %…100 % by confidence): {}",
        row.join(" ")
    );
    println!("seconds per pair include preparing both meshes once for all methods (Laplacian, eigenpairs, si-HKS, base set, landmarks, attachment); the files are symcorr articulated's");
    for f in files {
        println!("wrote {}", f.display());
    }
    Ok(())
}
