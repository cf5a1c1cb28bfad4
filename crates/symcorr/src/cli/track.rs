//! `symcorr track RECORDING --joints LOG --out DIR [--template MESH --template-joints J]
//! [--frames A..B] [--every N] [--joint-offset S] [--threads N] [--resume] [--scans]`:
//! a recorded session matched frame by frame ([`symcorr::track::Tracker`]).
//!
//! DIR is written as frames complete, never with all frames in memory:
//! * `journal.jsonl` — a header line (what is being run), then one line per processed frame,
//!   appended and synced after the frame's rows: the record `--resume` continues from;
//! * `correspondence.npy` (int32, frames × template vertices: the scan vertex each template
//!   vertex matches, −1 where the frame does not show it) and `confidence.npy` (float32);
//! * `posed.npy` (float32, frames × template vertices × 3: the template posed onto the frame,
//!   camera space in metres; NaN rows for frames without a pose);
//! * with `--scans`, `scans/NNNNNN.ply` (the frame's scan in camera space, its vertex ids those
//!   of `correspondence.npy`, segment colours);
//! * `track.json` (`symcorr.track/1`) and `track.svg` (coverage, confidence and time per frame),
//!   written when the run ends: every frame and a summary; with them `template_track.glb`,
//!   the template following the recording (morph targets and their animation, `posed`).
//!
//! The folders of slices of one run (`--frames A..B`, one per job of an array) are joined into
//! one by `symcorr track-merge` ([`merge`]); both write track.json and track.svg through
//! `report`.

pub mod merge;
mod posed;
mod report;
use report::FrameDigest;

use super::progress::Bar;
use super::CliError;
use clap::Args;
use serde_json::{json, Value};
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;
use symcorr::npy::{NpyType, NpyWriter};
use symcorr::track::log_check::{check_log, LOG_CHECK_FRAMES};
use symcorr::track::{FrameOutcome, TrackOptions, TrackedFrame, Tracker};
use symcorr::{Pipeline, PipelineOptions};
use symcorr_kinect::clock::JointOffset;
use symcorr_kinect::{DepthSource, Intrinsics, JointTrack};

const EXAMPLES: &str = "Examples:
  symcorr track fixtures/synth/recording --joints fixtures/synth/recording/joints.json --out track/
  symcorr track rec/ --joints rec/joints.json --out part3/ --frames 300..400
  symcorr track rec/ --joints rec/joints.json --out track/ --resume";

/// Arguments of `symcorr track`.
#[derive(Args, Debug)]
#[command(after_help = EXAMPLES)]
pub struct TrackArgs {
    /// The recording: a folder with intrinsics.json, depth/000000.png, … and depth_times.txt,
    /// or an OpenNI2 .oni file (needs the `openni2` feature).
    pub recording: PathBuf,
    /// The skeleton tracker's joint log (any joint format symcorr reads).
    #[arg(long)]
    pub joints: PathBuf,
    /// The depth camera's intrinsics (symcorr.intrinsics/1), replacing the recording's: a
    /// calibration (an .oni file gives a field of view and its recorded mirroring only), or
    /// `"mirrored": false` for an .oni file whose stream recorded no mirroring property.
    #[arg(long, value_name = "K.json")]
    pub intrinsics: Option<PathBuf>,
    /// Output folder.
    #[arg(long)]
    pub out: PathBuf,
    /// Template mesh (default: the bundled CC0 body with its exact joints).
    #[arg(long, requires = "template_joints")]
    pub template: Option<PathBuf>,
    /// Joints of the template.
    #[arg(long, requires = "template")]
    pub template_joints: Option<PathBuf>,
    /// Frames to process, `A..B` (B excluded; either end may be left out): a slice of a long
    /// recording for one job of an array.
    #[arg(long, value_name = "A..B")]
    pub frames: Option<String>,
    /// Process every N-th frame of the slice.
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub every: usize,
    /// Seconds added to every depth frame's time before the joint log is read, or `auto`:
    /// estimated from the frames (the offset whose joints lie least in front of the surface
    /// the camera saw, within ±2 s; recorded in track.json's `run`).
    #[arg(
        long,
        value_name = "SECONDS|auto",
        default_value = "0",
        value_parser = parse_joint_offset,
        allow_hyphen_values = true
    )]
    pub joint_offset: JointOffset,
    /// Weight of the head twist prior, which holds the head's twist at the chest's where one
    /// view does not pin it (a body turning into profile); 0 turns it off for a subject who
    /// turns the head against the body.
    #[arg(
        long,
        value_name = "W",
        default_value_t = symcorr_correspond::DEFAULT_HEAD_TWIST_PRIOR,
        allow_hyphen_values = true
    )]
    pub head_twist_prior: f64,
    /// Weight of the prior that holds the head at the turn against the chest the joint log
    /// reports, where it reports one (an Azure Kinect log: its nose and ears); it replaces the
    /// head twist prior there. 0 turns it off.
    #[arg(
        long,
        value_name = "W",
        default_value_t = symcorr_correspond::DEFAULT_HEAD_TURN_PRIOR,
        allow_hyphen_values = true
    )]
    pub head_turn_prior: f64,
    /// Share of its unturned score a turned head must reach to be kept, when the head's twist
    /// is searched again in every frame (a subject looking aside, which the joints do not
    /// show); in (0, 1], 0 turns the search off.
    #[arg(
        long,
        value_name = "G",
        default_value_t = symcorr_correspond::DEFAULT_HEAD_WARM_TWIST,
        allow_hyphen_values = true
    )]
    pub head_warm_twist: f64,
    /// Worker threads in all (default: every core): half for the observer, the others for
    /// the matcher, which takes them all while the observer's frames are light.
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
    /// Continue an interrupted run in DIR after its last complete frame.
    #[arg(long)]
    pub resume: bool,
    /// Also write each frame's scan as scans/NNNNNN.ply.
    #[arg(long)]
    pub scans: bool,
    /// Also write a self-contained HTML page of the run (as `symcorr view DIR` makes it).
    #[arg(long, value_name = "HTML")]
    pub view: Option<PathBuf>,
    /// Run without first checking on a few frames that the joint log fits the depth frames
    /// (a log of another recording or clock, or mirrored, is otherwise refused).
    #[arg(long)]
    pub no_log_check: bool,
}

/// `--joint-offset`: seconds, or `auto` (estimated from the frames).
fn parse_joint_offset(s: &str) -> Result<JointOffset, String> {
    if s == "auto" {
        return Ok(JointOffset::Auto);
    }
    match s.parse::<f64>() {
        Ok(x) if x.is_finite() => Ok(JointOffset::Seconds(x)),
        _ => Err(format!("{s:?}: expected seconds (e.g. 0.04) or auto")),
    }
}

/// The bundled template: the CC0 MakeHuman body in its rest pose and its exact joints.
const TEMPLATE_MESH: &[u8] = include_bytes!("../../../../fixtures/synth/bodies/meshes/s0_rest.ply");
const TEMPLATE_JOINTS: &str = include_str!("../../../../fixtures/synth/bodies/joints/s0_rest.json");

/// `A..B` → the frame indices of a recording of `len` frames, every `every`-th.
fn frame_list(spec: Option<&str>, every: usize, len: usize) -> Result<Vec<usize>, CliError> {
    if every == 0 {
        return Err(CliError("--every 0: expected at least 1".into()));
    }
    let (a, b) = match spec {
        None => (0, len),
        Some(s) => {
            let (a, b) = s.split_once("..").ok_or_else(|| {
                CliError(format!(
                    "--frames {s:?}: expected A..B (B excluded), e.g. 0..300"
                ))
            })?;
            let num = |t: &str, default: usize| -> Result<usize, CliError> {
                if t.is_empty() {
                    return Ok(default);
                }
                t.parse()
                    .map_err(|_| CliError(format!("--frames {s:?}: {t:?} is not a frame number")))
            };
            (num(a, 0)?, num(b, len)?)
        }
    };
    if a >= b || b > len {
        return Err(CliError(format!(
            "--frames {a}..{b}: the recording has frames 0..{len}"
        )));
    }
    Ok((a..b).step_by(every).collect())
}

/// The journal's name of the bundled template.
const BUNDLED_TEMPLATE: &str = "bundled:s0_rest";

/// The bundled template's mesh as read (the vertices of the arrays' columns).
fn bundled_template_mesh() -> Result<symcorr_mesh::TriMesh, CliError> {
    Ok(
        symcorr_mesh::io::read_from_bytes(TEMPLATE_MESH, symcorr_mesh::io::Format::Ply)
            .map_err(|e| CliError::with("bundled template", e))?
            .mesh,
    )
}

fn load_template(
    args: &TrackArgs,
    pipeline: &Pipeline,
    max_input_bytes: u64,
) -> Result<(symcorr::PreparedMesh, String), CliError> {
    match (&args.template, &args.template_joints) {
        (Some(m), Some(j)) => {
            let p = super::match_cmd::load_prepared(pipeline, m, j, None, None, max_input_bytes)?;
            Ok((p, m.display().to_string()))
        }
        _ => {
            let mesh = bundled_template_mesh()?;
            let (log, _) =
                symcorr_kinect::joints::parse_joints(TEMPLATE_JOINTS, "bundled template joints")
                    .map_err(|e| CliError(e.to_string()))?;
            let sk = log
                .frames
                .into_iter()
                .next()
                .map(|f| f.skeleton)
                .ok_or_else(|| CliError("bundled template joints: no frame".into()))?;
            let p = pipeline
                .prepare(mesh, &sk)
                .map_err(|e| CliError::with("bundled template", e))?;
            Ok((p, BUNDLED_TEMPLATE.to_string()))
        }
    }
}

/// The journal's first line: what the run is, so `--resume` continues only the same run.
/// `method`: [`method_fingerprint`] of the run's options; `intrinsics`: the camera the frames
/// are read with (the recording's, or `--intrinsics`), so that a run does not go on with
/// frames unprojected another way.
fn journal_header(
    args: &TrackArgs,
    frames: &[usize],
    (template, vertices): (&str, usize),
    method: &str,
    joint_offset_s: f64,
    intrinsics: &Intrinsics,
) -> Result<Value, CliError> {
    let intrinsics: Value = serde_json::to_value(intrinsics).unwrap_or(Value::Null);
    Ok(json!({
        "format": "symcorr.track-journal/1",
        "recording": args.recording.display().to_string(),
        "recording_digest": recording_digest(&args.recording)?,
        "intrinsics": intrinsics,
        "joints": args.joints.display().to_string(),
        "joints_digest": file_digest(&args.joints)?,
        "template": template,
        "template_vertices": vertices,
        "frames": frames,
        "joint_offset_s": joint_offset_s,
        "joint_offset_estimated": args.joint_offset == JointOffset::Auto,
        "head_twist_prior": args.head_twist_prior,
        "head_turn_prior": args.head_turn_prior,
        "head_warm_twist": args.head_warm_twist,
        "scans": args.scans,
        "method": method,
    }))
}

/// The first 64 bits of a digest, in hex: the journal header's fingerprints.
fn hex64(digest: &[u8]) -> String {
    digest.iter().take(8).map(|b| format!("{b:02x}")).collect()
}

/// [`hex64`] of a SHA-256 digest of `parts`, each prefixed by its length (so that no two lists
/// of parts hash alike by where one ends).
fn digest_hex(parts: impl IntoIterator<Item = Vec<u8>>) -> String {
    use sha2::{Digest, Sha256};
    let mut h = Sha256::new();
    for b in parts {
        h.update((b.len() as u64).to_le_bytes());
        h.update(&b);
    }
    hex64(&h.finalize())
}

/// [`digest_hex`] of a file's content (the joint log: a few MB to tens of MB).
fn file_digest(path: &Path) -> Result<String, CliError> {
    let bytes = std::fs::read(path).map_err(|e| CliError::with(path.display(), e))?;
    Ok(digest_hex([bytes]))
}

/// What identifies a recording's content without reading every depth frame: a folder's
/// `intrinsics.json` and `depth_times.txt` and the name and size of every file under `depth/`;
/// a file's (`.oni`) size and first and last MiB. `--resume` and `track-merge` compare it
/// rather than the path, which another working folder spells otherwise.
fn recording_digest(path: &Path) -> Result<String, CliError> {
    let io = |p: &Path, e: std::io::Error| CliError::with(p.display(), e);
    if path.is_dir() {
        let mut parts = Vec::new();
        for name in ["intrinsics.json", "depth_times.txt"] {
            let p = path.join(name);
            parts.push(std::fs::read(&p).map_err(|e| io(&p, e))?);
        }
        let depth = path.join("depth");
        let mut files = Vec::new();
        for e in std::fs::read_dir(&depth).map_err(|e| io(&depth, e))? {
            let e = e.map_err(|e| io(&depth, e))?;
            let len = e.metadata().map_err(|err| io(&e.path(), err))?.len();
            files.push((e.file_name().to_string_lossy().into_owned(), len));
        }
        files.sort();
        parts.extend(
            files
                .into_iter()
                .map(|(name, len)| format!("{name} {len}").into_bytes()),
        );
        Ok(digest_hex(parts))
    } else {
        use std::io::{Read, Seek, SeekFrom};
        const MIB: u64 = 1 << 20;
        let mut f = std::fs::File::open(path).map_err(|e| io(path, e))?;
        let len = f.metadata().map_err(|e| io(path, e))?.len();
        let mut head = Vec::new();
        (&mut f)
            .take(MIB)
            .read_to_end(&mut head)
            .map_err(|e| io(path, e))?;
        let mut tail = Vec::new();
        f.seek(SeekFrom::Start(len.saturating_sub(MIB)))
            .map_err(|e| io(path, e))?;
        f.take(MIB)
            .read_to_end(&mut tail)
            .map_err(|e| io(path, e))?;
        Ok(digest_hex([len.to_le_bytes().to_vec(), head, tail]))
    }
}

/// The first entry, other than `ignore`'s, in which two journal headers differ, with both
/// values (`null` for a missing one). The recording's and the log's paths count only where a
/// header lacks their digests (a journal written before them): the content decides, not the
/// spelling of the path.
pub(super) fn header_difference(
    a: &Value,
    b: &Value,
    ignore: &[&str],
) -> Option<(String, String, String)> {
    let (Some(a), Some(b)) = (a.as_object(), b.as_object()) else {
        return Some(("header".into(), a.to_string(), b.to_string()));
    };
    let digests = ["recording_digest", "joints_digest"]
        .iter()
        .all(|k| a.contains_key(*k) && b.contains_key(*k));
    a.keys()
        .chain(b.keys())
        .filter(|k| !ignore.contains(&k.as_str()))
        .filter(|k| !(digests && matches!(k.as_str(), "recording" | "joints")))
        .find(|k| a.get(*k) != b.get(*k))
        .map(|k| {
            let v =
                |m: &serde_json::Map<String, Value>| m.get(k).unwrap_or(&Value::Null).to_string();
            (k.clone(), v(a), v(b))
        })
}

/// The first 64 bits (hex) of a SHA-256 digest of every option the run matches with (their
/// `Debug` text: the pipeline's and the tracker's, defaults included): a build whose method
/// changed — another default, a new step — neither resumes nor merges with a run of the one
/// before, whose frames it would not reproduce.
fn method_fingerprint(pipeline: &PipelineOptions, track: &TrackOptions) -> String {
    use sha2::{Digest, Sha256};
    hex64(&Sha256::digest(
        format!("{pipeline:?}\n{track:?}").as_bytes(),
    ))
}

/// The journal's name in a run folder.
pub(super) const JOURNAL: &str = "journal.jsonl";

/// A journal's text → its header, its complete frame lines and the length of the text they
/// span: a last line cut short by an interruption is left out.
fn parse_journal(text: &str) -> Result<(Value, Vec<Value>, usize), String> {
    let complete = match text.rfind('\n') {
        Some(i) => &text[..=i],
        None => "",
    };
    let mut lines = complete.lines();
    let first: Value = lines
        .next()
        .and_then(|l| serde_json::from_str(l).ok())
        .ok_or("no header line")?;
    let frames = lines
        .map(|l| serde_json::from_str(l).map_err(|e| format!("bad line: {e}")))
        .collect::<Result<Vec<Value>, _>>()?;
    Ok((first, frames, complete.len()))
}

/// The complete frame lines of an existing journal whose header is `header`; a last line cut
/// short by an interruption is dropped (and cut from the file).
fn read_journal(path: &Path, header: &Value) -> Result<Vec<Value>, CliError> {
    let err = |m: String| CliError(format!("{}: cannot resume: {m}", path.display()));
    let text = std::fs::read_to_string(path).map_err(|e| err(e.to_string()))?;
    let (first, frames, complete) = parse_journal(&text).map_err(err)?;
    if let Some((key, then, now)) = header_difference(&first, header, &[]) {
        return Err(err(format!(
            "its `{key}` is {then}, this run's {now}: it was written for another recording (its \
             content: `recording_digest`) or intrinsics, template, joint log (`joints_digest`), \
             frame list or options, or by a build whose method differs (`method`)"
        )));
    }
    if complete < text.len() {
        let f = std::fs::OpenOptions::new()
            .write(true)
            .open(path)
            .map_err(|e| err(e.to_string()))?;
        f.set_len(complete as u64).map_err(|e| err(e.to_string()))?;
    }
    Ok(frames)
}

/// The files a run writes in its folder.
const RUN_FILES: [&str; 7] = [
    JOURNAL,
    report::TRACK_JSON,
    report::TRACK_SVG,
    posed::POSED_NPY,
    posed::TEMPLATE_GLB,
    "correspondence.npy",
    "confidence.npy",
];

/// `--view`'s page, checked before any work like every output: not a folder, in a folder that
/// exists, not an input (the joint log, the intrinsics, the template, an `.oni` file), not a file
/// of the recording folder, and not one of the run's own outputs in `--out`.
fn check_view_page(page: &Path, args: &TrackArgs) -> Result<(), CliError> {
    let outputs: Vec<PathBuf> = RUN_FILES.iter().map(|name| args.out.join(name)).collect();
    let mut inputs: Vec<&Path> = vec![&args.joints, &args.recording];
    inputs.extend(args.intrinsics.as_deref());
    inputs.extend(args.template.as_deref());
    inputs.extend(args.template_joints.as_deref());
    inputs.extend(outputs.iter().map(PathBuf::as_path));
    // A page in the --out folder that this run creates: only the run's own names are taken.
    let in_new_out = !args.out.exists()
        && page
            .parent()
            .is_some_and(|d| d.components().eq(args.out.components()));
    if in_new_out {
        if outputs.iter().any(|o| o.file_name() == page.file_name()) {
            return Err(CliError(format!(
                "--view {}: one of the run's own outputs",
                page.display()
            )));
        }
        return Ok(());
    }
    let dest = symcorr_mesh::io::check_output(page, &inputs)
        .map_err(|e| CliError(format!("--view {e}")))?;
    // Anywhere in the recording folder: its depth frames, times and intrinsics are inputs, and
    // files it may gain are not ours to overwrite.
    let canonical_dir = |p: &Path| {
        let dir = p.parent().filter(|d| !d.as_os_str().is_empty());
        std::fs::canonicalize(dir.unwrap_or(Path::new("."))).ok()
    };
    if let (Some(dir), Ok(rec)) = (
        canonical_dir(dest.path()),
        std::fs::canonicalize(&args.recording),
    ) {
        if rec.is_dir() && dir.starts_with(&rec) {
            return Err(CliError(format!(
                "--view {}: inside the recording folder {}; write the page elsewhere",
                page.display(),
                args.recording.display()
            )));
        }
    }
    Ok(())
}

/// Runs `symcorr track`.
pub fn run(args: TrackArgs, max_input_bytes: u64) -> Result<(), CliError> {
    if let Some(n) = args.threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n.max(1))
            .build_global()
            .map_err(|e| CliError(format!("--threads {n}: {e}")))?;
    }
    for (flag, w) in [
        ("--head-twist-prior", args.head_twist_prior),
        ("--head-turn-prior", args.head_turn_prior),
    ] {
        if !(w >= 0.0 && w.is_finite()) {
            return Err(CliError(format!(
                "{flag} {w}: expected a finite weight ≥ 0"
            )));
        }
    }
    if !(0.0..=1.0).contains(&args.head_warm_twist) {
        return Err(CliError(format!(
            "--head-warm-twist {}: expected a share in (0, 1], or 0 for off",
            args.head_warm_twist
        )));
    }
    if args.out.exists() && !args.out.is_dir() {
        return Err(CliError(format!(
            "{}: --out must be a folder",
            args.out.display()
        )));
    }
    if let Some(page) = &args.view {
        check_view_page(page, &args)?;
    }
    let journal_path = args.out.join(JOURNAL);
    if journal_path.exists() && !args.resume {
        return Err(CliError(format!(
            "{}: holds a previous run; pass --resume to continue it or choose another folder",
            args.out.display()
        )));
    }
    // Files of a run's names without its journal are not a run this command wrote or can
    // continue: written over, they would be lost.
    if !journal_path.exists() {
        let taken: Vec<&str> = (RUN_FILES.iter().copied())
            .chain(["scans"])
            .filter(|name| args.out.join(name).exists())
            .collect();
        if !taken.is_empty() {
            return Err(CliError(format!(
                "{}: holds {} but no {JOURNAL}, so no run to continue; choose a new or empty \
                 folder",
                args.out.display(),
                taken.join(", ")
            )));
        }
    }
    let mut recording = DepthSource::open(&args.recording).map_err(|e| CliError(e.to_string()))?;
    if let Some(path) = &args.intrinsics {
        let k = Intrinsics::read(path).map_err(|e| CliError(e.to_string()))?;
        recording
            .set_intrinsics(k)
            .map_err(|e| CliError::with(path.display(), e))?;
    }
    let frames = frame_list(args.frames.as_deref(), args.every, recording.len())?;
    let log = symcorr_kinect::read_joints(&args.joints).map_err(|e| CliError(e.to_string()))?;
    let joints = JointTrack::new(log, 0.0).map_err(|e| CliError::with(args.joints.display(), e))?;
    let mut options = PipelineOptions {
        mode: symcorr::Mode::Dense,
        ..PipelineOptions::default()
    };
    options.articulated.head_twist_prior =
        (args.head_twist_prior > 0.0).then_some(args.head_twist_prior);
    options.articulated.head_turn_prior =
        (args.head_turn_prior > 0.0).then_some(args.head_turn_prior);
    options.articulated.head_warm_twist =
        (args.head_warm_twist > 0.0).then_some(args.head_warm_twist);
    // Estimated on frames spread over the whole recording, so that slices of one run merge.
    let joint_offset_s = (args.joint_offset)
        .resolve(&mut recording, &joints)
        .map_err(|e| CliError(format!("--joint-offset auto: {e}")))?;
    let track_options = TrackOptions {
        joint_offset_s,
        ..TrackOptions::default()
    };
    let method = method_fingerprint(&options, &track_options);
    let pipeline = Pipeline::new(options);
    let (template, template_name) = load_template(&args, &pipeline, max_input_bytes)?;
    let n = template.input_mesh().num_vertices();
    let header = journal_header(
        &args,
        &frames,
        (&template_name, n),
        &method,
        joint_offset_s,
        recording.intrinsics(),
    )?;
    let resuming = args.resume && journal_path.exists();
    // The log against the frames, before anything is written (a resumed run was checked when
    // it started).
    if !resuming && !args.no_log_check {
        let check = check_log(
            &pipeline,
            &template,
            &mut recording,
            &joints,
            &track_options,
            &frames,
            LOG_CHECK_FRAMES,
        );
        check.verdict().map_err(|e| {
            CliError(format!(
                "{}: {e} (--no-log-check runs anyway)",
                args.joints.display()
            ))
        })?;
        for w in check.warnings() {
            eprintln!("symcorr: warning: {}: {w}", args.joints.display());
        }
    }
    std::fs::create_dir_all(&args.out).map_err(|e| CliError::with(args.out.display(), e))?;
    let (corr_path, conf_path) = (
        args.out.join("correspondence.npy"),
        args.out.join("confidence.npy"),
    );
    let npy = |e: symcorr::npy::NpyError| CliError(e.to_string());
    // What stays in memory of each frame done: a few numbers (the frame lines are on disk, in
    // the journal), so that memory does not grow with the recording.
    let (mut done, mut corr_npy, mut conf_npy) = if resuming {
        let done: Vec<FrameDigest> = read_journal(&journal_path, &header)?
            .iter()
            .map(FrameDigest::of)
            .collect();
        let k = done.len();
        // posed.npy is NaN-filled for a folder whose run started before the file was written,
        // never for one whose journal says its rows were.
        let posed_rows = done.iter().filter(|d| d.posed).count();
        let posed_path = args.out.join(posed::POSED_NPY);
        if posed_rows > 0 && !posed_path.exists() {
            return Err(CliError(format!(
                "{}: missing, but the journal records posed rows for {posed_rows} frames; the \
                 folder cannot be resumed (start the run in a new folder)",
                posed_path.display()
            )));
        }
        (
            done,
            NpyWriter::resume(&corr_path, NpyType::I32, frames.len(), n, k).map_err(npy)?,
            NpyWriter::resume(&conf_path, NpyType::F32, frames.len(), n, k).map_err(npy)?,
        )
    } else {
        let mut j = std::fs::File::create(&journal_path)
            .map_err(|e| CliError::with(journal_path.display(), e))?;
        writeln!(j, "{header}").map_err(|e| CliError::with(journal_path.display(), e))?;
        (
            Vec::new(),
            NpyWriter::create(&corr_path, NpyType::I32, frames.len(), n).map_err(npy)?,
            NpyWriter::create(&conf_path, NpyType::F32, frames.len(), n).map_err(npy)?,
        )
    };
    if args.scans {
        let d = args.out.join("scans");
        std::fs::create_dir_all(&d).map_err(|e| CliError::with(d.display(), e))?;
    }
    let mut posed_npy = posed::open(&args.out, frames.len(), n, resuming.then_some(done.len()))?;
    let mut journal = std::fs::OpenOptions::new()
        .append(true)
        .open(&journal_path)
        .map_err(|e| CliError::with(journal_path.display(), e))?;
    let mut tracker = Tracker::new(
        &pipeline,
        &template,
        *recording.intrinsics(),
        joints,
        track_options,
    );
    // Ctrl-C stops after the frame in progress; track.json then covers the frames done and
    // --resume continues. A second Ctrl-C (or any other kill) leaves the journal and the
    // arrays consistent all the same.
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    {
        let stop = stop.clone();
        // Fails only if a handler is already set (a second run in one process): then Ctrl-C
        // simply ends the process, which the journal survives.
        let _ = ctrlc::set_handler(move || {
            if stop.swap(true, std::sync::atomic::Ordering::SeqCst) {
                std::process::exit(130);
            }
        });
    }
    let bar = Bar::frames();
    let start = Instant::now();
    let done_before = done.len();
    let total = frames.len();
    let skipped_rows = (vec![-1i32; n], vec![0f32; n]);
    // One frame's rows, journal line and scan, written once it is matched (or skipped).
    let mut write = |f: TrackedFrame| -> Result<(), CliError> {
        let TrackedFrame {
            index: i,
            time_s: time,
            started: t0,
            outcome,
        } = f;
        let entry = match &outcome {
            FrameOutcome::Matched(m) => {
                corr_npy.push_i32(&m.target_of).map_err(npy)?;
                conf_npy.push_f32(&m.confidence).map_err(npy)?;
                posed::push(&mut posed_npy, m.posed.as_deref(), n)?;
                if args.scans {
                    let colours: Vec<[u8; 3]> = m
                        .scan_labels
                        .iter()
                        .map(
                            |l| match l.and_then(|x| symcorr_attach::Segment::ALL.get(x)) {
                                Some(s) => symcorr_attach::palette::colour(*s),
                                None => [128, 128, 128],
                            },
                        )
                        .collect();
                    let p = args.out.join("scans").join(format!("{i:06}.ply"));
                    let mut batch = symcorr_mesh::io::OutputBatch::new();
                    batch
                        .add_mesh(&p, &m.scan.mesh, Some(&colours))
                        .map_err(|e| CliError(e.to_string()))?;
                    batch.commit().map_err(|e| CliError(e.to_string()))?;
                }
                json!({
                    "frame": i,
                    "time_s": time,
                    "status": "ok",
                    "corrections": m.corrections.iter().map(|c| c.name()).collect::<Vec<_>>(),
                    "coverage": m.coverage,
                    "mean_confidence": m.mean_confidence,
                    "fit_score": m.fit_score,
                    "view_held": m.view_held,
                    "posed": m.posed.is_some(),
                    "scan_vertices": m.scan.mesh.num_vertices(),
                    "timings_s": m.timings.iter().map(|(s, t)| (s.to_string(), json!(t))).collect::<serde_json::Map<_, _>>(),
                    "seconds": t0.elapsed().as_secs_f64(),
                })
            }
            FrameOutcome::Skipped(reason) => {
                corr_npy.push_i32(&skipped_rows.0).map_err(npy)?;
                conf_npy.push_f32(&skipped_rows.1).map_err(npy)?;
                posed::push(&mut posed_npy, None, n)?;
                json!({
                    "frame": i,
                    "time_s": time,
                    "status": format!("skipped: {reason}"),
                    "seconds": t0.elapsed().as_secs_f64(),
                })
            }
        };
        // Rows first, then the journal line: a frame is done once its line is on disk.
        corr_npy.sync().map_err(npy)?;
        conf_npy.sync().map_err(npy)?;
        posed_npy.sync().map_err(npy)?;
        writeln!(journal, "{entry}").map_err(|e| CliError::with(journal_path.display(), e))?;
        journal
            .sync_data()
            .map_err(|e| CliError::with(journal_path.display(), e))?;
        done.push(FrameDigest::of(&entry));
        bar.update("tracking", done.len(), total);
        Ok(())
    };
    // Two threads, frame k + 1 observed while frame k is matched (`Tracker::run`).
    let todo: Vec<usize> = frames.iter().skip(done_before).copied().collect();
    tracker.run(&mut recording, &todo, &stop, &mut write)?;
    bar.finish();
    let seconds = start.elapsed().as_secs_f64();
    let mut summary = report::summary(&done, total);
    summary["frames_per_second_this_run"] = if seconds > 0.0 {
        json!(((done.len() - done_before) as f64) / seconds)
    } else {
        Value::Null
    };
    // The animated template is committed with track.json; if it fails, track.json says why.
    let mut batch = symcorr_mesh::io::OutputBatch::new();
    let glb = posed::stage_glb(
        &mut batch,
        &args.out,
        &args.out.join(posed::POSED_NPY),
        template.input_mesh(),
        &done,
        total,
    );
    summary["template_track"] = match &glb {
        Ok(v) => v.clone(),
        Err(e) => json!({ "error": e.0 }),
    };
    let journal_lines = |emit: &mut dyn FnMut(&str) -> std::io::Result<()>| {
        let reader = std::io::BufReader::new(std::fs::File::open(&journal_path)?);
        // The header first, then one line per frame done.
        for line in std::io::BufRead::lines(reader).skip(1) {
            emit(&line?)?;
        }
        Ok(())
    };
    report::stage(
        &mut batch,
        &args.out,
        &header,
        journal_lines,
        &done,
        total,
        &summary,
    )?;
    batch.commit().map_err(|e| CliError(e.to_string()))?;
    println!(
        "tracked {} frames ({} matched, {} skipped) into {}",
        summary["frames"],
        summary["ok"],
        summary["skipped"],
        args.out.display()
    );
    glb?;
    if let Some(page) = &args.view {
        super::view::write_track_page(&args.out, page)?;
    }
    if done.len() < total {
        return Err(CliError(format!(
            "interrupted after {} of {total} frames; {} holds them, --resume continues (the \
             .npy arrays are sized for the whole run: numpy loads them once it has finished)",
            done.len(),
            args.out.display()
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::frame_list;

    #[test]
    fn frame_slices_parse_and_are_checked_against_the_recording() {
        assert_eq!(frame_list(None, 1, 3).unwrap(), vec![0, 1, 2]);
        assert_eq!(frame_list(Some("1..3"), 1, 5).unwrap(), vec![1, 2]);
        assert_eq!(frame_list(Some("..4"), 2, 5).unwrap(), vec![0, 2]);
        assert_eq!(frame_list(Some("3.."), 1, 5).unwrap(), vec![3, 4]);
        for bad in ["3..3", "0..9", "a..2", "2"] {
            assert!(frame_list(Some(bad), 1, 5).is_err(), "{bad}");
        }
        assert!(frame_list(None, 0, 5).is_err());
    }
}
