//! `symcorr match TEMPLATE TARGET --template-joints J1 --target-joints J2 --out corr.json
//! [--dense] [--samples N] [--frame N] [--ply-out DIR] [--cache | --cache-dir DIR]`

use super::CliError;
use std::path::{Path, PathBuf};
use std::time::Instant;
use symcorr::cache::{CacheLocation, CachePolicy};
use symcorr::io::{read_mesh, read_skeleton_as};
use symcorr::output::{
    correspondence_json, explain_file, input_colours, match_colours, pair_timings, repair_json,
    segment_colours,
};
use symcorr::{figures, Mode, OptionError, Pipeline, PipelineOptions, PreparedMesh};
use symcorr_correspond::{CandidateOptions, PaperFilter};
use symcorr_mesh::io::{check_output, OutputBatch};

/// Arguments of `symcorr match`.
#[derive(clap::Args, Debug)]
#[command(after_help = "Examples:
  symcorr match a.off b.off --template-joints a.json --target-joints b.json --out corr.json
  symcorr match a.ply b.ply --template-joints a.json --target-joints b.txt --out corr.json --dense --ply-out colours/
  symcorr match a.off b.off --template-joints a.json --target-joints b.json --out ablation.json --method paper --no-skeleton-filter
  symcorr match a.off b.off --template-joints a.json --target-joints b.json --out corr.json --dense --method refined
  symcorr match a.off b.off --template-joints a.json --target-joints b.json --out corr.json --cache   # reuses a.off.symcorr-eigs, b.off.symcorr-eigs")]
pub struct MatchArgs {
    /// Template mesh (OBJ, OFF, PLY, glTF/GLB).
    pub template: PathBuf,
    /// Target mesh.
    pub target: PathBuf,
    /// Joints of the template (symcorr.joints/1 JSON, Kinect SDK text, NTU .skeleton).
    #[arg(long)]
    pub template_joints: PathBuf,
    /// Joints of the target.
    #[arg(long)]
    pub target_joints: PathBuf,
    /// Output correspondence file (symcorr.correspondence/1 JSON).
    #[arg(long)]
    pub out: PathBuf,
    /// Match every template vertex instead of a sample.
    #[arg(long)]
    pub dense: bool,
    #[command(flatten)]
    pub method: MethodArgs,
    /// Frame of both joint logs to use (default: the first).
    #[arg(long, conflicts_with_all = ["template_frame", "target_frame"])]
    pub frame: Option<usize>,
    /// Frame of the template's joint log (default: the first).
    #[arg(long, value_name = "N")]
    pub template_frame: Option<usize>,
    /// Frame of the target's joint log (default: the first).
    #[arg(long, value_name = "N")]
    pub target_frame: Option<usize>,
    /// Force the joint files' format instead of detecting it from content:
    /// json, kinect-text, ntu or k4abt.
    #[arg(long, value_name = "FORMAT")]
    pub joints_format: Option<String>,
    /// Also write coloured meshes into DIR: matched points share colours
    /// (template_matches.ply, target_matches.ply) and segment colours
    /// (template_segments.ply, target_segments.ply), plus .glb copies.
    #[arg(long, value_name = "DIR")]
    pub ply_out: Option<PathBuf>,
    /// Also write a self-contained HTML page of the result (as `symcorr view` makes it).
    #[arg(long, value_name = "HTML")]
    pub view: Option<PathBuf>,
    /// Explain one template point (an id of the template file), the paper's Fig. 2: writes
    /// OUT's name with `.explain-POINT.json` (`symcorr.explain/1`: its candidates before and
    /// after the skeleton filter and the selected match) and `.explain-POINT.ply` (both bodies
    /// side by side, the point in blue, removed candidates red, kept green, the selected one
    /// black). Only with --method paper.
    #[arg(long, value_name = "POINT")]
    pub explain: Option<u32>,
    /// Also write the base vertex set (the paper's Fig. 4) as one mesh (PLY, GLB, OBJ or OFF
    /// by extension): template and target side by side in pale segment colours, the base
    /// vertices marked in black. Only with --method paper.
    #[arg(long, value_name = "FILE")]
    pub base_set_out: Option<PathBuf>,
    /// Also write template and target side by side joined by lines for a sample of matches
    /// (the paper's Figs. 1 and 6) as one mesh (PLY, GLB, OBJ or OFF by extension): lines in
    /// the template point's segment colour, red where a match joins left to right.
    #[arg(long, value_name = "FILE")]
    pub lines_out: Option<PathBuf>,
    /// Matches drawn by --lines-out (a farthest-point sample of the matched template points).
    #[arg(long, value_name = "N", default_value_t = 60, requires = "lines_out")]
    pub lines: usize,
    /// Print a machine-readable summary (JSON) on stdout instead of the text lines: `matches`,
    /// `template_points`, `fallbacks`, `seconds`, `timings_s`, `repair` (per mesh), `files`.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub cache: CacheArgs,
}

/// `--cache` / `--cache-dir`: the on-disk eigenpair cache (`match` and `bench`).
#[derive(clap::Args, Debug, Clone, Default)]
pub struct CacheArgs {
    /// Keep each mesh's Laplace–Beltrami eigenpairs next to it as MESH.symcorr-eigs and reuse
    /// them in later runs (for `bench`: in DATASET/meshes/, one HASH.symcorr-eigs per mesh).
    /// A file is used only for exactly the mesh and settings it was written for; a stale or
    /// corrupted one is recomputed and rewritten (with a warning if corrupted). Timings then
    /// show `eigenpairs_cached` instead of `eigenpairs`. Only the methods with spectral data
    /// (`refined`, `paper`) compute eigenpairs; `articulated` has nothing to cache.
    #[arg(long, conflicts_with = "cache_dir")]
    pub cache: bool,
    /// Like --cache, but every mesh's eigenpairs go into DIR (created if needed), named by a
    /// hash of the mesh and the solver settings.
    #[arg(long, value_name = "DIR")]
    pub cache_dir: Option<PathBuf>,
}

/// Counts of the eigenpair cache's outcomes in one run (for the summary line).
#[derive(Debug, Default)]
pub struct CacheCounts {
    /// Meshes whose eigenpairs came from the cache.
    pub hits: std::sync::atomic::AtomicUsize,
    /// Meshes whose eigenpairs were computed (and written).
    pub computed: std::sync::atomic::AtomicUsize,
}

impl CacheCounts {
    /// `"eigenpair cache: H of N meshes read from it"`, or `None` when the cache was not used.
    pub fn summary(&self) -> Option<String> {
        use std::sync::atomic::Ordering::Relaxed;
        let (h, c) = (self.hits.load(Relaxed), self.computed.load(Relaxed));
        (h + c > 0).then(|| format!("eigenpair cache: {h} of {} meshes read from it", h + c))
    }
}

impl CacheArgs {
    /// The cache policy for `mesh` (`None` without --cache/--cache-dir): `next_to` is the
    /// directory used by --cache in place of the mesh's own file (bench), `None` for
    /// MESH.symcorr-eigs. Corruption and failed writes are warned about on stderr; `counts`
    /// records hits.
    pub fn policy(
        &self,
        mesh: &Path,
        next_to: Option<&Path>,
        counts: &std::sync::Arc<CacheCounts>,
    ) -> Option<CachePolicy> {
        let location = match (&self.cache_dir, self.cache, next_to) {
            (Some(dir), _, _) => CacheLocation::Dir(dir.clone()),
            (None, true, Some(dir)) => CacheLocation::Dir(dir.to_path_buf()),
            (None, true, None) => {
                let mut p = mesh.as_os_str().to_owned();
                p.push(format!(".{}", symcorr::cache::EXTENSION));
                CacheLocation::File(PathBuf::from(p))
            }
            (None, false, _) => return None,
        };
        let counts = counts.clone();
        Some(CachePolicy::new(location).with_notify(move |o| {
            use std::sync::atomic::Ordering::Relaxed;
            if o.is_hit() {
                counts.hits.fetch_add(1, Relaxed);
            } else {
                counts.computed.fetch_add(1, Relaxed);
            }
            if let Some(w) = o.warning() {
                eprintln!("symcorr: warning: {w}");
            }
        }))
    }
}

/// `--method`: symcorr's articulated alignment (default), the refined spectral method or the
/// paper's pipeline.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum MethodArg {
    /// The template skinned onto the target's skeleton, fitted bone by bone, nearest point
    /// within each segment (the default: the most accurate and the fastest, and the one for
    /// single-view scans; see the README).
    #[default]
    Articulated,
    /// Skeleton-landmark initial map + segment-constrained ZoomOut (whole surfaces).
    Refined,
    /// si-HKS candidates, skeleton filter, eq. 8 selection (the paper).
    Paper,
}

/// `--paper-filter`: the paper's skeleton filter as written, or with symcorr's midline extensions.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum PaperFilterArg {
    /// Same segment only (§3.2).
    Strict,
    /// Same segment, same sagittal half on the midline segments, sagittal band (the default).
    Extended,
}

/// Method options shared by `match` and `bench`.
#[derive(clap::Args, Debug, Clone)]
pub struct MethodArgs {
    /// Matching method: `articulated` (skeleton-driven articulated alignment, beyond the
    /// paper; default; whole bodies and single-view scans, whose unseen template points are
    /// listed under `no_counterpart`), `refined` (landmark coordinates and segment-constrained
    /// ZoomOut, beyond the paper) or `paper` (the paper's pipeline, Table 1).
    #[arg(long, value_enum, default_value_t = MethodArg::Articulated)]
    pub method: MethodArg,
    /// Template points in sparse mode (farthest-point sample).
    #[arg(long, default_value_t = symcorr::DEFAULT_SAMPLES)]
    pub samples: usize,
    /// Ablation: skip the skeleton filter (the paper's method without its contribution).
    #[arg(long, conflicts_with = "paper_filter")]
    pub no_skeleton_filter: bool,
    /// The paper method's skeleton filter: `strict` keeps a candidate only on the point's own
    /// segment (the paper's §3.2, nothing more); `extended` (default) also separates the left
    /// and right halves of the pelvis, torso and head by the joints' sagittal planes (the skull
    /// by its own symmetry plane) and keeps a midline point's candidates on its side of a
    /// sagittal band (beyond the paper). Only with --method paper.
    #[arg(long, value_enum, value_name = "FILTER")]
    pub paper_filter: Option<PaperFilterArg>,
    /// Candidates per point: the N nearest by si-HKS.
    #[arg(long, value_name = "N", default_value_t = symcorr_correspond::DEFAULT_NEAREST)]
    pub candidates: usize,
    /// Candidates per point: only those within FACTOR × the nearest si-HKS distance (≥ 1).
    #[arg(long, value_name = "FACTOR")]
    pub threshold: Option<f64>,
    /// Laplace–Beltrami eigenpairs behind the si-HKS.
    #[arg(long, default_value_t = symcorr::DEFAULT_EIGENPAIRS)]
    pub eigenpairs: usize,
    /// Base vertex set radius, in units of sqrt(area).
    #[arg(long, default_value_t = symcorr::DEFAULT_BASE_RADIUS)]
    pub base_radius: f64,
    /// Use a skeleton that fails a fit check instead of refusing it (the outputs' `fit` block
    /// then says `accepted_poor_fit`).
    #[arg(long)]
    pub accept_poor_fit: bool,
}

impl MethodArgs {
    /// The pipeline these options describe.
    pub fn pipeline(&self, dense: bool) -> Result<Pipeline, CliError> {
        let mut o = PipelineOptions {
            mode: if dense {
                Mode::Dense
            } else {
                Mode::Sparse {
                    samples: self.samples,
                }
            },
            ..PipelineOptions::default()
        };
        // An explicit --paper-filter with another method is refused even when it names the
        // default, which the library cannot tell from no choice.
        if self.paper_filter.is_some() && self.method != MethodArg::Paper {
            return Err(CliError(flag_message(OptionError::PaperFilterNeedsPaper)));
        }
        o.matching.filter = match (self.no_skeleton_filter, self.paper_filter) {
            (true, _) => PaperFilter::Off,
            (false, Some(PaperFilterArg::Strict)) => PaperFilter::Strict,
            (false, Some(PaperFilterArg::Extended) | None) => PaperFilter::DEFAULT,
        };
        o.method = match self.method {
            MethodArg::Paper => symcorr::Method::Paper,
            MethodArg::Refined => symcorr::Method::Refined,
            MethodArg::Articulated => symcorr::Method::Articulated,
        };
        o.matching.candidates = CandidateOptions {
            nearest: Some(self.candidates),
            threshold: self.threshold,
        };
        o.prepare.eigenpairs = self.eigenpairs;
        o.prepare.base_radius = self.base_radius;
        if self.accept_poor_fit {
            o.prepare.attach.poor_fit = symcorr_attach::PoorFitPolicy::Accept;
        }
        // The library's rules, checked before any file is read; the message names the flags.
        o.check().map_err(|e| CliError(flag_message(e)))?;
        Ok(Pipeline::new(o))
    }
}

/// A refused option in the words of the command line: the flag, and what it needs.
fn flag_message(e: OptionError) -> String {
    match e {
        OptionError::NoSamples => "--samples must be at least 1".into(),
        OptionError::NoCandidates => "--candidates must be at least 1".into(),
        OptionError::CandidateThreshold(t) => format!("--threshold {t}: must be a factor ≥ 1"),
        OptionError::BaseRadius(r) => format!("--base-radius {r}: must be positive"),
        OptionError::TooFewEigenpairs(k) => format!("--eigenpairs {k}: need at least 2"),
        OptionError::AblationNeedsPaper => {
            "--no-skeleton-filter is the paper pipeline's ablation: add --method paper".into()
        }
        OptionError::PaperFilterNeedsPaper => {
            "--paper-filter chooses the paper pipeline's filter: add --method paper".into()
        }
        other => other.to_string(),
    }
}

/// Reads a mesh and its joints and prepares it, naming the files in errors.
pub fn load_prepared(
    pipeline: &Pipeline,
    mesh: &Path,
    joints: &Path,
    frame: Option<usize>,
    format: Option<symcorr_kinect::JointFormat>,
    max_input_bytes: u64,
) -> Result<PreparedMesh, CliError> {
    let m = read_mesh(mesh, max_input_bytes).map_err(|e| CliError(e.to_string()))?;
    let sk = read_skeleton_as(joints, frame, format).map_err(|e| CliError(e.to_string()))?;
    pipeline.prepare(m, &sk).map_err(|e| blame(mesh, joints, e))
}

/// Names the file an error of preparing `mesh` with `joints` concerns: the joints for a
/// skeleton that is unusable on its own, both for a skeleton that does not fit the mesh, the
/// mesh otherwise.
pub fn blame(mesh: &Path, joints: &Path, e: symcorr::PipelineError) -> CliError {
    use symcorr::PipelineError::{Attach, FacingUndetermined, ViewNotHeld};
    use symcorr_attach::AttachError as A;
    match &e {
        Attach(A::EmptySkeleton { .. }) => CliError::with(joints.display(), e),
        Attach(
            A::PoorFit { .. }
            | A::AlignmentFailed { .. }
            | A::ScaleMismatch { .. }
            | A::MirroredSkeleton { .. },
        )
        | ViewNotHeld { .. }
        | FacingUndetermined { .. } => {
            CliError(format!("{} with {}: {e}", mesh.display(), joints.display()))
        }
        _ => CliError::with(mesh.display(), e),
    }
}

/// Stages the four coloured meshes, as PLY and GLB, into `dir` (created if needed) in `batch`.
pub fn write_coloured(
    batch: &mut OutputBatch,
    dir: &Path,
    template: &PreparedMesh,
    target: &PreparedMesh,
    corr: &symcorr::Correspondence,
) -> Result<(), CliError> {
    std::fs::create_dir_all(dir).map_err(|e| CliError::with(dir.display(), e))?;
    let (tc, uc) = match_colours(template, target, corr);
    let ts = segment_colours(template);
    let us = segment_colours(target);
    // Written on the input meshes, so vertex `i` of each file is vertex `i` of the input.
    for (name, side, colours) in [
        ("template_matches", template, &tc),
        ("target_matches", target, &uc),
        ("template_segments", template, &ts),
        ("target_segments", target, &us),
    ] {
        let mesh = side.input_mesh();
        let colours = &input_colours(side, colours);
        for ext in ["ply", "glb"] {
            let path = dir.join(format!("{name}.{ext}"));
            batch
                .add_mesh(&path, mesh, Some(colours))
                .map_err(|e| CliError(e.to_string()))?;
        }
    }
    Ok(())
}

pub fn run(args: MatchArgs, max_input_bytes: u64) -> Result<(), CliError> {
    let pipeline = args.method.pipeline(args.dense)?;
    let format = super::joints_format(args.joints_format.as_deref())?;
    // Every output is checked before any work: its directory exists, it is not a directory,
    // and it is none of the inputs.
    let inputs = [
        args.template.as_path(),
        &args.target,
        &args.template_joints,
        &args.target_joints,
    ];
    let explain_paths = args.explain.map(|p| explain_paths(&args.out, p));
    let outputs = [
        Some(&args.out),
        args.base_set_out.as_ref(),
        args.lines_out.as_ref(),
        args.view.as_ref(),
    ]
    .into_iter()
    .flatten()
    .chain(explain_paths.iter().flat_map(|(j, p)| [j, p]));
    for out in outputs {
        check_output(out, &inputs).map_err(|e| CliError(e.to_string()))?;
    }
    if let Some(dir) = args.ply_out.as_ref().filter(|d| d.exists() && !d.is_dir()) {
        return Err(CliError(format!(
            "--ply-out {}: exists and is not a directory",
            dir.display()
        )));
    }
    // Figures that need the paper's data are refused before any work.
    let paper = args.method.method == MethodArg::Paper;
    if args.base_set_out.is_some() && !paper {
        return Err(CliError(
            "--base-set-out draws the paper pipeline's base vertex set: add --method paper".into(),
        ));
    }
    if args.explain.is_some() && !paper {
        return Err(CliError(
            "--explain follows a point through the paper pipeline's stages: add --method paper"
                .into(),
        ));
    }
    let start = Instant::now();
    let counts = std::sync::Arc::new(CacheCounts::default());
    let with_cache = |mesh: &Path| {
        let mut p = pipeline.clone();
        p.options.prepare.cache = args.cache.policy(mesh, None, &counts);
        p
    };
    let (pa, pb) = (with_cache(&args.template), with_cache(&args.target));
    let progress = super::progress::Spinner::new("preparing meshes");
    let (a, b) = rayon::join(
        || {
            load_prepared(
                &pa,
                &args.template,
                &args.template_joints,
                args.frame.or(args.template_frame),
                format,
                max_input_bytes,
            )
        },
        || {
            load_prepared(
                &pb,
                &args.target,
                &args.target_joints,
                args.frame.or(args.target_frame),
                format,
                max_input_bytes,
            )
        },
    );
    let (a, b) = (a?, b?);
    progress.set("matching");
    // A scan's skeleton facing away from the camera is turned back (`run_on_view`): the
    // outputs then describe the target prepared on the turned joints.
    let matched = pipeline
        .run_on_view(&a, &b)
        .map_err(|e| blame(&args.target, &args.target_joints, e))?;
    let turned = matched.turned_target.is_some();
    let b = matched.turned_target.unwrap_or(b);
    let corr = matched.correspondence;
    let mut timings = pair_timings(&a, &b, &corr);
    timings.push(("total".into(), start.elapsed().as_secs_f64()));
    progress.finish();
    let mut doc = correspondence_json(
        &args.template.display().to_string(),
        &a,
        &args.target.display().to_string(),
        &b,
        &corr,
        &timings,
    );
    if let Some(fit) = doc.fit.as_mut() {
        fit.target.turned_about_spine = turned;
    }
    let text = serde_json::to_string(&doc).map_err(|e| CliError(e.to_string()))?;
    // All outputs are staged, then committed together: an error leaves none of them.
    let mut batch = OutputBatch::new();
    let cli = |e: symcorr_mesh::MeshError| CliError(e.to_string());
    batch.add(&args.out, text.as_bytes()).map_err(cli)?;
    if let Some(dir) = &args.ply_out {
        write_coloured(&mut batch, dir, &a, &b, &corr)?;
    }
    if let Some(path) = &args.view {
        let name = args.out.display().to_string();
        let meshes = (args.template.as_path(), args.target.as_path());
        let html = super::view::pair_html(&doc, &name, meshes, None, max_input_bytes)?;
        batch.add(path, html.as_bytes()).map_err(cli)?;
    }
    if let (Some(point), Some(paths)) = (args.explain, &explain_paths) {
        write_explanation(&mut batch, &args, &pipeline, (&a, &b), point, paths)?;
    }
    if let Some(path) = &args.base_set_out {
        let (mesh, colours) =
            figures::base_set_figure(&a, &b).map_err(|e| CliError(e.to_string()))?;
        batch.add_mesh(path, &mesh, Some(&colours)).map_err(cli)?;
    }
    if let Some(path) = &args.lines_out {
        let (mesh, colours) = figures::lines_figure(&a, &b, &corr, args.lines)
            .map_err(|e| CliError(e.to_string()))?;
        batch.add_mesh(path, &mesh, Some(&colours)).map_err(cli)?;
    }
    let files = batch.commit().map_err(cli)?;
    let seconds = start.elapsed().as_secs_f64();
    let points = corr.filter_stats().points.max(corr.pairs.len());
    let unseen = corr
        .has_counterpart()
        .map(|h| h.iter().filter(|&&x| !x).count());
    let matched = corr.pairs.len() - unseen.unwrap_or(0);
    if args.json {
        let doc = serde_json::json!({
            "matches": matched,
            "no_counterpart": unseen,
            "template_points": points,
            "fallbacks": corr.filter_stats().fallbacks,
            "fit": doc.fit,
            "seconds": seconds,
            "timings_s": timings.iter().map(|(n, s)| (n.clone(), serde_json::json!(s))).collect::<serde_json::Map<_, _>>(),
            "repair": {
                "template": repair_json(&a.repair, &a.mesh),
                "target": repair_json(&b.repair, &b.mesh),
            },
            "files": files.iter().map(|f| f.display().to_string()).collect::<Vec<_>>(),
        });
        println!("{doc}");
        return Ok(());
    }
    for (side, p) in [("template", &a), ("target", &b)] {
        if !p.repair.unchanged() {
            println!("{side}: {}", p.repair.to_string().replace('\n', "; "));
        }
        let fit = &p.attachment.diagnostics.fit;
        if let Some(c) = fit.worst().filter(|_| fit.accepted_poor_fit) {
            println!(
                "{side}: poor skeleton fit accepted: {} is {:.3} (at most {})",
                c.kind.name(),
                c.value,
                c.limit
            );
        }
        if p.unreached > 0 {
            println!(
                "{side}: {} vertices in components no bone reaches: not labelled, not matched",
                p.unreached
            );
        }
    }
    if turned {
        println!(
            "target: the joints faced away from the camera (the fit on them held too little of \
             the scan): matched with them turned half a turn about their spine"
        );
    }
    match unseen {
        Some(u) => println!(
            "partial target: {matched} matches, {u} of {points} template points not shown by it, in {seconds:.2} s"
        ),
        None => println!(
            "{matched} matches ({points} template points, {} skeleton-filter fallbacks) in {seconds:.2} s",
            corr.filter_stats().fallbacks,
        ),
    }
    if let Some(s) = counts.summary() {
        println!("{s}");
    }
    for f in files {
        println!("wrote {}", f.display());
    }
    Ok(())
}

/// `--explain POINT`: the point's explanation as `symcorr.explain/1` JSON and as a figure, named
/// after `--out` (`corr.json` → `corr.explain-POINT.json`, `corr.explain-POINT.ply`).
fn write_explanation(
    batch: &mut OutputBatch,
    args: &MatchArgs,
    pipeline: &Pipeline,
    (a, b): (&PreparedMesh, &PreparedMesh),
    point: u32,
    (json, ply): &(PathBuf, PathBuf),
) -> Result<(), CliError> {
    let vertices = a.input_mesh().num_vertices();
    let prepared = a
        .prepared_ids()
        .get(point as usize)
        .copied()
        .ok_or_else(|| {
            CliError(format!(
                "--explain {point}: the template has {vertices} vertices (ids 0..{vertices})"
            ))
        })?
        .ok_or_else(|| {
            CliError(format!(
                "--explain {point}: the mesh repair removed that template vertex (degenerate or unreferenced)"
            ))
        })?;
    let e = pipeline
        .explain(a, b, prepared)
        .map_err(|e| CliError(e.to_string()))?;
    let doc = explain_file(
        (&args.template.display().to_string(), a),
        (&args.target.display().to_string(), b),
        pipeline.options.matching.filter,
        &e,
    );
    let text = serde_json::to_string(&doc).map_err(|e| CliError(e.to_string()))?;
    batch
        .add(json, text.as_bytes())
        .map_err(|e| CliError(e.to_string()))?;
    let (mesh, colours) = figures::explain_figure(a, b, &e).map_err(|e| CliError(e.to_string()))?;
    batch
        .add_mesh(ply, &mesh, Some(&colours))
        .map_err(|e| CliError(e.to_string()))
}

/// The two files of `--explain POINT`, named after `--out` (`corr.json` →
/// `corr.explain-POINT.json`, `corr.explain-POINT.ply`).
fn explain_paths(out: &Path, point: u32) -> (PathBuf, PathBuf) {
    let stem = out.with_extension("");
    let named = |ext: &str| {
        let mut p = stem.as_os_str().to_owned();
        p.push(format!(".explain-{point}.{ext}"));
        PathBuf::from(p)
    };
    (named("json"), named("ply"))
}
