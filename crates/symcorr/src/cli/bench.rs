//! `symcorr bench DATASET [--pairs FILE] [--mode sparse|dense] [--json OUT] [--out-dir DIR]
//! [--cache | --cache-dir DIR]`

use super::match_cmd::{CacheArgs, CacheCounts, MethodArgs};
use super::progress::Bar;
use super::CliError;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use symcorr::bench::{run_bench, BenchReport, Progress};
use symcorr::output::{correspondence_json, curve_svg};
use symcorr::Pipeline;
use symcorr_eval::Dataset;
use symcorr_mesh::io::OutputBatch;

/// Sparse or dense matching.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModeArg {
    /// A farthest-point sample of template points (--samples).
    Sparse,
    /// Every template vertex.
    Dense,
}

/// Arguments of `symcorr bench`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "A dataset is a folder: meshes/NAME.{off,ply,obj} (same vertex order in every mesh),
joints/NAME.json, optional mirror.txt (line i: mirror vertex of vertex i), pairs.txt
(`template target` per line).

Examples:
  symcorr bench fixtures/synth/bodies
  symcorr bench fixtures/synth/bodies --mode dense --json summary.json --out-dir results/
  symcorr bench fixtures/synth/bodies --method paper --json paper.json
  symcorr bench fixtures/synth/bodies --method paper --no-skeleton-filter --json ablation.json
  symcorr bench fixtures/synth/bodies --cache     # eigenpairs kept in fixtures/synth/bodies/meshes/*.symcorr-eigs"
)]
pub struct BenchArgs {
    /// Dataset folder.
    pub dataset: PathBuf,
    /// Pairs file (default: DATASET/pairs.txt).
    #[arg(long)]
    pub pairs: Option<PathBuf>,
    /// Sparse or dense matching.
    #[arg(long, value_enum, default_value_t = ModeArg::Sparse)]
    pub mode: ModeArg,
    #[command(flatten)]
    pub method: MethodArgs,
    /// Write the JSON summary here.
    #[arg(long, value_name = "OUT")]
    pub json: Option<PathBuf>,
    /// Write each pair's correspondence as DIR/TEMPLATE__TARGET.json, and the plot as DIR/curve.svg.
    #[arg(long, value_name = "DIR")]
    pub out_dir: Option<PathBuf>,
    /// Write the cumulative error curve (SVG) here (default: next to --json as OUT.svg, or
    /// DIR/curve.svg with --out-dir).
    #[arg(long, value_name = "SVG")]
    pub plot: Option<PathBuf>,
    /// Frame of the joint logs to use (default: the first).
    #[arg(long)]
    pub frame: Option<usize>,
    #[command(flatten)]
    pub cache: CacheArgs,
}

/// The JSON summary (keys fixed by DESIGN.md: `mean_error`, `flip_rate`, `within_0.05`,
/// `within_0.10`, `table1_row`, `seconds_per_pair`, `pairs`).
pub fn summary_json(report: &BenchReport, pipeline: &Pipeline, dataset: &Path) -> Value {
    let pairs: Vec<Value> = report
        .pairs
        .iter()
        .map(|p| {
            let (counted, flips) = p.evaluation.flip_counts();
            json!({
                "template": p.template,
                "target": p.target,
                "matches": p.evaluation.errors.len(),
                "mean_error": p.evaluation.mean_error(),
                "surface_mean_error": p.surface_errors.as_ref().map(|e| e.iter().sum::<f64>() / e.len().max(1) as f64),
                "flip_rate": p.evaluation.flip_rate(),
                "flips": flips,
                "flip_counted": counted,
                "within_0.05": p.evaluation.within(0.05),
                "within_0.10": p.evaluation.within(0.10),
                "table1_row": p.table1_row,
                "seconds": p.seconds,
                "match_seconds": p.match_seconds,
                "skeleton_filter_fallbacks": p.correspondence.filter_stats().fallbacks,
                "target_vertices_hit": p.correspondence.coverage(),
                "view_held": p.correspondence.view_held(),
                "turned_about_spine": p.turned_target.is_some(),
                "scan": p.scan.map(scan_json),
            })
        })
        .collect();
    let o = &pipeline.options;
    // The articulated method uses no spectral data and no candidates: those settings are null.
    let spectral = o.method != symcorr::Method::Articulated;
    json!({
        "dataset": dataset.display().to_string(),
        "mode": match o.mode { symcorr::Mode::Dense => "dense".to_string(), symcorr::Mode::Sparse { samples } => format!("sparse:{samples}") },
        "method": match o.method { symcorr::Method::Paper => "paper", symcorr::Method::Refined => "refined", symcorr::Method::Articulated => "articulated" },
        "skeleton_filter": o.matching.filter != symcorr_correspond::PaperFilter::Off,
        "paper_filter": (o.method == symcorr::Method::Paper).then_some(match o.matching.filter {
            symcorr_correspond::PaperFilter::Off => "off",
            symcorr_correspond::PaperFilter::Strict => "strict",
            symcorr_correspond::PaperFilter::Extended { .. } => "extended",
        }),
        "candidates": spectral.then(|| json!({"nearest": o.matching.candidates.nearest, "threshold": o.matching.candidates.threshold})),
        "eigenpairs": spectral.then_some(o.prepare.eigenpairs),
        "base_radius": spectral.then_some(o.prepare.base_radius),
        "mean_error": report.mean_error(),
        "surface_mean_error": report.surface_mean_error(),
        "flip_rate": report.flip_rate(),
        "within_0.05": report.within(0.05),
        "within_0.10": report.within(0.10),
        "table1_row": report.table1_row(),
        "seconds_per_pair": report.seconds_per_pair(),
        "wall_seconds": report.wall_seconds,
        "skeleton_filter_fallbacks": report.fallbacks(),
        "curve": report.curve(),
        "scan": report.scan_scores().map(scan_json),
        "pairs": pairs,
    })
}

/// A single-view target's scores (symcorr-eval's `ScanScores`): coverage of the shown
/// template points, `no_counterpart` precision and recall, and the counts behind them.
fn scan_json(s: symcorr_eval::ScanScores) -> Value {
    json!({
        "coverage": s.coverage(),
        "no_counterpart_precision": s.precision(),
        "no_counterpart_recall": s.recall(),
        "shown": s.shown,
        "shown_matched": s.shown_matched,
        "hidden": s.hidden,
        "listed": s.listed,
        "listed_hidden": s.listed_hidden,
    })
}

fn opt_pct(x: Option<f64>) -> String {
    x.map_or_else(|| "    n/a".to_string(), pct)
}

fn pct(x: f64) -> String {
    format!("{:5.1}%", 100.0 * x)
}

fn flip_str(f: Option<f64>) -> String {
    f.map_or_else(|| "    n/a".to_string(), |f| format!("{:6.2}%", 100.0 * f))
}

/// The table printed by `bench` and `demo`.
pub fn table(report: &BenchReport, total: bool) -> String {
    // Single-view targets add coverage and the `no_counterpart` precision and recall.
    let scans = report.scan_scores().is_some();
    let scan_cols = |c: Option<symcorr_eval::ScanScores>| match c {
        Some(c) if scans => format!(
            " {:>7} {:>7} {:>7}",
            opt_pct(c.coverage()),
            opt_pct(c.precision()),
            opt_pct(c.recall())
        ),
        _ if scans => format!(" {:>7} {:>7} {:>7}", "n/a", "n/a", "n/a"),
        _ => String::new(),
    };
    let mut s = format!(
        "{:<34} {:>8} {:>8} {:>7} {:>7} {:>7}{}\n",
        "pair",
        "mean err",
        "flips",
        "≤0.05",
        "≤0.10",
        "s/pair",
        if scans {
            format!(" {:>7} {:>7} {:>7}", "cover", "nc P", "nc R")
        } else {
            String::new()
        }
    );
    for p in &report.pairs {
        let name = format!("{} → {}", p.template, p.target);
        s += &format!(
            "{:<34} {:>8.4} {:>8} {:>7} {:>7} {:>7.2}{}\n",
            name,
            p.evaluation.mean_error(),
            flip_str(p.evaluation.flip_rate()),
            pct(p.evaluation.within(0.05)),
            pct(p.evaluation.within(0.10)),
            p.seconds,
            scan_cols(p.scan)
        );
    }
    if !total {
        return s;
    }
    s += &format!(
        "{:<34} {:>8.4} {:>8} {:>7} {:>7} {:>7.2}{}\n",
        format!("all ({} pairs)", report.pairs.len()),
        report.mean_error(),
        flip_str(report.flip_rate()),
        pct(report.within(0.05)),
        pct(report.within(0.10)),
        report.seconds_per_pair(),
        scan_cols(report.scan_scores())
    );
    let row: Vec<String> = report
        .table1_row()
        .iter()
        .map(|x| format!("{x:.3}"))
        .collect();
    s += &format!(
        "Table 1 row (best 10 %…100 % by confidence): {}\n",
        row.join(" ")
    );
    if let Some(e) = report.surface_mean_error() {
        s += &format!("mean error of the matches as surface points: {e:.4}\n");
    }
    s
}

/// Stages the per-pair correspondence files into `dir` (created if needed) in `batch`.
pub fn stage_pair_files(
    batch: &mut OutputBatch,
    report: &BenchReport,
    dataset: &Dataset,
    dir: &Path,
) -> Result<(), CliError> {
    std::fs::create_dir_all(dir).map_err(|e| CliError::with(dir.display(), e))?;
    for p in &report.pairs {
        let a = &report.prepared[&p.template];
        let b = p
            .turned_target
            .as_ref()
            .unwrap_or(&report.prepared[&p.target]);
        let mut doc = correspondence_json(
            &dataset.meshes[&p.template].display().to_string(),
            a,
            &dataset.meshes[&p.target].display().to_string(),
            b,
            &p.correspondence,
            &symcorr::output::pair_timings(a, b, &p.correspondence),
        );
        if let Some(fit) = doc.fit.as_mut() {
            fit.target.turned_about_spine = p.turned_target.is_some();
        }
        let path = dir.join(format!("{}__{}.json", p.template, p.target));
        batch
            .add(&path, doc.to_json().as_bytes())
            .map_err(|e| CliError(e.to_string()))?;
    }
    Ok(())
}

pub fn run(args: BenchArgs, max_input_bytes: u64) -> Result<(), CliError> {
    let mut pipeline = args.method.pipeline(args.mode == ModeArg::Dense)?;
    let counts = std::sync::Arc::new(CacheCounts::default());
    let meshes = args.dataset.join("meshes");
    pipeline.options.prepare.cache = args.cache.policy(&meshes, Some(&meshes), &counts);
    // Outputs are checked before any work: a summary or plot that would land on a dataset
    // file (pairs list) or a directory is refused.
    let inputs: Vec<&Path> = args.pairs.iter().map(PathBuf::as_path).collect();
    for out in [args.json.as_ref(), args.plot.as_ref()]
        .into_iter()
        .flatten()
    {
        symcorr_mesh::io::check_output(out, &inputs).map_err(|e| CliError(e.to_string()))?;
    }
    if let Some(d) = args.out_dir.as_ref().filter(|d| d.exists() && !d.is_dir()) {
        return Err(CliError(format!(
            "{}: --out-dir exists and is not a directory",
            d.display()
        )));
    }
    let dataset =
        Dataset::open(&args.dataset, args.pairs.as_deref()).map_err(|e| CliError(e.to_string()))?;
    let bar = Bar::new();
    let report = run_bench(
        &dataset,
        &pipeline,
        args.frame,
        max_input_bytes,
        &|p| match p {
            Progress::Prepared { done, total } => bar.update("preparing meshes", done, total),
            Progress::Matched { done, total } => bar.update("matching pairs", done, total),
        },
    )
    .map_err(|e| CliError(e.to_string()))?;
    bar.finish();
    print!("{}", table(&report, true));
    if let Some(s) = counts.summary() {
        println!("{s}");
    }
    let label = if pipeline.options.method == symcorr::Method::Articulated {
        "articulated (skinning + ICP)"
    } else if pipeline.options.method == symcorr::Method::Refined {
        "refined (landmarks + ZoomOut)"
    } else {
        match pipeline.options.matching.filter {
            symcorr_correspond::PaperFilter::Off => "no skeleton filter",
            symcorr_correspond::PaperFilter::Strict => "skeleton filter as in the paper",
            symcorr_correspond::PaperFilter::Extended { .. } => "with skeleton filter",
        }
    };
    let svg = curve_svg(
        &format!("symcorr bench {}", args.dataset.display()),
        &[(label.to_string(), report.curve())],
        0.25,
    );
    let plot = args.plot.clone().or_else(|| {
        args.out_dir
            .as_ref()
            .map(|d| d.join("curve.svg"))
            .or_else(|| args.json.as_ref().map(|j| j.with_extension("svg")))
    });
    // Every file is staged, then committed together: an error leaves none of them.
    let cli = |e: symcorr_mesh::MeshError| CliError(e.to_string());
    let mut batch = OutputBatch::new();
    if let Some(dir) = &args.out_dir {
        stage_pair_files(&mut batch, &report, &dataset, dir)?;
    }
    if let Some(p) = &plot {
        batch.add(p, svg.as_bytes()).map_err(cli)?;
    }
    if let Some(j) = &args.json {
        let doc = summary_json(&report, &pipeline, &args.dataset);
        let text = serde_json::to_string_pretty(&doc).map_err(|e| CliError(e.to_string()))?;
        batch.add(j, text.as_bytes()).map_err(cli)?;
    }
    batch.commit().map_err(cli)?;
    if let Some(dir) = &args.out_dir {
        println!(
            "wrote {} correspondence files to {}",
            report.pairs.len(),
            dir.display()
        );
    }
    for p in [plot.as_ref(), args.json.as_ref()].into_iter().flatten() {
        println!("wrote {}", p.display());
    }
    Ok(())
}
