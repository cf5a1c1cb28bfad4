//! `symcorr view INPUT [MESH...] --out view.html`: a self-contained HTML page of a result
//! (symcorr::view). INPUT is a `symcorr.correspondence/1` file (then MESH... are the template
//! and target, default: the paths the file names), a `symcorr.labels/1` file (MESH: its mesh)
//! or a `symcorr track` output folder.

use super::CliError;
use std::path::{Path, PathBuf};
use symcorr::formats::{CorrespondenceFile, LabelsFile, CORRESPONDENCE_FORMAT, LABELS_FORMAT};
use symcorr::io::read_mesh;
use symcorr::view::{
    labels_page, pair_page, track_page, LabelsView, PairTruth, PairView, TrackView,
    DEFAULT_MAX_FRAMES,
};
use symcorr_mesh::io::OutputBatch;

/// Arguments of `symcorr view`.
#[derive(clap::Args, Debug)]
#[command(after_help = "Examples:
  symcorr view corr.json --out view.html                      # meshes from the paths in corr.json
  symcorr view corr.json a.ply b.ply --out view.html --truth fixtures/synth/bodies
  symcorr view labels.json body.ply --out labels.html
  symcorr view track-out/ --out track.html")]
pub struct ViewArgs {
    /// A correspondence file, a labels file or a track output folder; then, optionally, the
    /// mesh files (template and target, or the labelled mesh) instead of the paths it names.
    #[arg(required = true, num_args = 1..=3, value_name = "INPUT")]
    pub inputs: Vec<PathBuf>,
    /// The page to write (HTML).
    #[arg(long)]
    pub out: PathBuf,
    /// Benchmark dataset (DESIGN.md's layout) holding both meshes: show each match's true
    /// point and geodesic error.
    #[arg(long, value_name = "DATASET")]
    pub truth: Option<PathBuf>,
    /// Track view: posed frames embedded at most (chosen evenly; the timeline lists all).
    #[arg(long, value_name = "N", default_value_t = DEFAULT_MAX_FRAMES)]
    pub max_frames: usize,
}

/// What an INPUT is.
enum Input {
    Pair(CorrespondenceFile),
    Labels(LabelsFile),
    Track,
}

fn classify(path: &Path) -> Result<Input, CliError> {
    if path.is_dir() {
        if path.join("track.json").is_file() {
            return Ok(Input::Track);
        }
        return Err(CliError(format!(
            "{}: a folder without track.json (not a symcorr track output folder)",
            path.display()
        )));
    }
    let bytes = std::fs::read(path).map_err(|e| CliError::with(path.display(), e))?;
    let file = path.display().to_string();
    let text = String::from_utf8(bytes).unwrap_or_default();
    let format = serde_json::from_str::<serde_json::Value>(&text)
        .ok()
        .and_then(|v| v["format"].as_str().map(str::to_string));
    match format.as_deref() {
        Some(CORRESPONDENCE_FORMAT) => CorrespondenceFile::from_json_str(&text, &file)
            .map(Input::Pair)
            .map_err(|e| CliError(e.to_string())),
        Some(LABELS_FORMAT) => LabelsFile::from_json_str(&text, &file)
            .map(Input::Labels)
            .map_err(|e| CliError(e.to_string())),
        Some(other) => Err(CliError(format!(
            "{file}: format {other:?}; symcorr view shows {CORRESPONDENCE_FORMAT}, {LABELS_FORMAT} files and track output folders"
        ))),
        None => Err(CliError(format!(
            "{file}: not a {CORRESPONDENCE_FORMAT} or {LABELS_FORMAT} file, nor a track output folder"
        ))),
    }
}

/// A mesh path a file names: as written, else relative to the file's folder.
fn named_mesh(named: &str, file: &Path) -> PathBuf {
    let p = PathBuf::from(named);
    if p.is_absolute() || p.exists() {
        return p;
    }
    match file.parent() {
        Some(dir) if dir.join(&p).exists() => dir.join(p),
        _ => p,
    }
}

/// Reads the meshes and makes the page (nothing written).
pub fn build(args: &ViewArgs, max_input_bytes: u64) -> Result<String, CliError> {
    let input = &args.inputs[0];
    let meshes = &args.inputs[1..];
    let read = |p: &Path| read_mesh(p, max_input_bytes).map_err(|e| CliError(e.to_string()));
    let err = |e: symcorr::view::ViewError| CliError(e.to_string());
    let name = input.display().to_string();
    match classify(input)? {
        Input::Pair(corr) => {
            if meshes.len() == 1 {
                return Err(CliError(
                    "a correspondence file takes two meshes (template and target) or none".into(),
                ));
            }
            let template_path = meshes
                .first()
                .cloned()
                .unwrap_or_else(|| named_mesh(&corr.template.path, input));
            let target_path = meshes
                .get(1)
                .cloned()
                .unwrap_or_else(|| named_mesh(&corr.target.path, input));
            pair_html(
                &corr,
                &name,
                (&template_path, &target_path),
                args.truth.as_deref(),
                max_input_bytes,
            )
        }
        Input::Labels(labels) => {
            if args.truth.is_some() {
                return Err(CliError("--truth belongs to a correspondence file".into()));
            }
            if meshes.len() > 1 {
                return Err(CliError("a labels file takes one mesh".into()));
            }
            let mesh_path = meshes
                .first()
                .cloned()
                .unwrap_or_else(|| named_mesh(&labels.mesh.path, input));
            let mesh = read(&mesh_path)?;
            labels_page(&LabelsView {
                mesh: &mesh,
                labels: &labels,
                name: &name,
            })
            .map_err(err)
        }
        Input::Track => {
            if !meshes.is_empty() || args.truth.is_some() {
                return Err(CliError(
                    "a track folder takes no mesh and no --truth (its template is in template_track.glb)".into(),
                ));
            }
            let track = TrackView::read(input, args.max_frames).map_err(err)?;
            Ok(track_page(&track))
        }
    }
}

/// The pair page of a correspondence `doc` (named `name`) between the meshes at `meshes`
/// (template, target), with the ground truth of the benchmark dataset `truth` if given: what
/// `view`, `match --view` and `demo` write.
pub fn pair_html(
    doc: &CorrespondenceFile,
    name: &str,
    meshes: (&Path, &Path),
    truth: Option<&Path>,
    max_input_bytes: u64,
) -> Result<String, CliError> {
    let read = |p: &Path| read_mesh(p, max_input_bytes).map_err(|e| CliError(e.to_string()));
    let err = |e: symcorr::view::ViewError| CliError(e.to_string());
    let template = read(meshes.0)?;
    let target = read(meshes.1)?;
    let mut view = PairView {
        template: &template,
        target: &target,
        correspondence: doc,
        name,
        truth: None,
    };
    let truth = match truth {
        Some(ds) => Some(PairTruth::from_dataset(&view, ds).map_err(err)?),
        None => None,
    };
    view.truth = truth.as_ref();
    pair_page(&view).map_err(err)
}

/// Writes the track page of the run folder `dir` to `page` (`track --view`).
pub fn write_track_page(dir: &Path, page: &Path) -> Result<(), CliError> {
    let track = TrackView::read(dir, DEFAULT_MAX_FRAMES).map_err(|e| CliError(e.to_string()))?;
    let html = track_page(&track);
    let mut batch = OutputBatch::new();
    let cli = |e: symcorr_mesh::MeshError| CliError(e.to_string());
    batch.add(page, html.as_bytes()).map_err(cli)?;
    batch.commit().map_err(cli)?;
    println!("wrote {}", page.display());
    Ok(())
}

pub fn run(args: ViewArgs, max_input_bytes: u64) -> Result<(), CliError> {
    let html = build(&args, max_input_bytes)?;
    let mut batch = OutputBatch::new();
    let cli = |e: symcorr_mesh::MeshError| CliError(e.to_string());
    batch.add(&args.out, html.as_bytes()).map_err(cli)?;
    for f in batch.commit().map_err(cli)? {
        println!("wrote {} ({} bytes)", f.display(), html.len());
    }
    Ok(())
}
