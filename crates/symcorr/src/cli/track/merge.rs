//! `symcorr track-merge DIR... --out DIR [--allow-gaps]`: the output folders of slices of one
//! run (`symcorr track --frames A..B`, e.g. the tasks of a job array) merged into one folder,
//! itself a run folder over the union of their frames.
//!
//! Refused, before anything is written: slices of different runs (their journal headers differ
//! in anything but the frame list: recording, joint log, template, its vertex count, joint
//! offset, scan option), an unfinished slice (fewer frame lines than its frame list), slices
//! whose frame ranges overlap, and — unless `--allow-gaps` — frames between two slices that
//! none of them holds (an array task that never ran leaves no folder, so its frames would
//! silently be missing). With `--allow-gaps` the summary lists them under `gaps`.
//!
//! The arrays are streamed a row at a time from the slices into staged files
//! ([`symcorr::npy::NpyReader`] → [`NpyWriter::streaming`]); `template_track.glb` is built from
//! the staged `posed.npy`; `track.json`/`track.svg` come from the track command's own report
//! code; the scans are hard-linked (copied where the file system cannot link) into a staging
//! folder. Everything appears at the end — the scans folder by one rename, then the files of an
//! [`OutputBatch`], the journal last — and an error before that leaves `--out` as it was (a
//! folder the command created is removed again). The slices are only read.
//!
//! Each slice started without a previous frame (no warm start, smoothing or swap continuity at
//! its first frame), exactly as a run resumed there would: the merged folder equals a single
//! run over the same frames interrupted and resumed at the slices' starts.

use super::{header_difference, parse_journal, posed, report, CliError, BUNDLED_TEMPLATE, JOURNAL};
use clap::Args;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use symcorr::npy::{NpyError, NpyReader, NpyType, NpyWriter};
use symcorr_mesh::io::OutputBatch;
use symcorr_mesh::TriMesh;

const EXAMPLES: &str = "Examples:
  symcorr track-merge parts/* --out track/
  symcorr track-merge part0/ part1/ part3/ --out track/ --allow-gaps";

/// Arguments of `symcorr track-merge`.
#[derive(Args, Debug)]
#[command(after_help = EXAMPLES)]
pub struct TrackMergeArgs {
    /// Output folders of `symcorr track` over slices of one recording (any order).
    #[arg(required = true, value_name = "DIR")]
    pub slices: Vec<PathBuf>,
    /// Output folder: new, or empty.
    #[arg(long)]
    pub out: PathBuf,
    /// Merge even when frames between two slices are in none of them (listed in the summary's
    /// `gaps`).
    #[arg(long)]
    pub allow_gaps: bool,
}

/// Why slices are not merged.
#[derive(Debug, thiserror::Error)]
pub enum MergeError {
    /// `--out` exists and is not an empty folder.
    #[error("{}: --out must be a new or empty folder", out.display())]
    OutNotEmpty {
        /// The folder.
        out: PathBuf,
    },
    /// A folder without a readable journal of `symcorr track`.
    #[error("{}: not a folder of `symcorr track`: {reason}", dir.display())]
    NotASlice {
        /// The folder.
        dir: PathBuf,
        /// What is wrong with it.
        reason: String,
    },
    /// A slice whose run stopped before its last frame.
    #[error(
        "{}: unfinished: {missing} of its {frames} frames are missing (`symcorr track … --resume` finishes it)",
        dir.display()
    )]
    Unfinished {
        /// The slice.
        dir: PathBuf,
        /// Frames of its list without a journal line.
        missing: usize,
        /// Frames in its list.
        frames: usize,
    },
    /// Two slices whose journal headers differ in more than the frame list.
    #[error(
        "{} and {} are not slices of one run: their journals' {key} differ ({this} vs {other})",
        dir.display(),
        other_dir.display()
    )]
    DifferentRun {
        /// The slice that differs.
        dir: PathBuf,
        /// The slice it is compared with (the first given).
        other_dir: PathBuf,
        /// The header entry that differs.
        key: String,
        /// Its value in `dir`.
        this: String,
        /// Its value in `other_dir`.
        other: String,
    },
    /// Two slices holding the same frames (or interleaved ones).
    #[error(
        "{} (frames {}..{}) and {} (frames {}..{}) overlap",
        a.0.display(), a.1, a.2, b.0.display(), b.1, b.2
    )]
    Overlap {
        /// A slice and its frame range (`A..B`, B excluded).
        a: (PathBuf, usize, usize),
        /// The slice after it (by first frame) and its range.
        b: (PathBuf, usize, usize),
    },
    /// Frames between two slices that neither holds, without `--allow-gaps`.
    #[error(
        "frames {from}..{to} are in no slice (between {} and {}); --allow-gaps merges anyway",
        before.display(),
        after.display()
    )]
    Gap {
        /// The slice before the gap.
        before: PathBuf,
        /// The slice after it.
        after: PathBuf,
        /// First missing frame.
        from: usize,
        /// The frame after the last missing one.
        to: usize,
    },
    /// The template the journals name cannot be read, or has another vertex count.
    #[error("template {name}: {reason}")]
    Template {
        /// The journal's name of the template.
        name: String,
        /// Why.
        reason: String,
    },
    /// A slice's array is not the one its journal describes, or ends early.
    #[error(transparent)]
    Npy(#[from] NpyError),
    /// Reading a slice or writing the output failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The error.
        source: std::io::Error,
    },
    /// Staging or committing an output file failed.
    #[error("{0}")]
    Output(String),
}

impl From<MergeError> for CliError {
    fn from(e: MergeError) -> CliError {
        CliError(e.to_string())
    }
}

fn io_err(path: &Path) -> impl Fn(std::io::Error) -> MergeError + '_ {
    move |source| MergeError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Frames `A..B` of the recording, B excluded.
type FrameRange = (usize, usize);

/// A finished slice: its folder, journal header, frame list and frame lines.
#[derive(Debug)]
struct Slice {
    dir: PathBuf,
    header: Value,
    frames: Vec<usize>,
    lines: Vec<Value>,
}

impl Slice {
    /// The frames that have a scan in a run with scans: the matched ones (a skipped frame
    /// has none).
    fn scanned_frames(&self) -> impl Iterator<Item = usize> + '_ {
        self.frames
            .iter()
            .zip(&self.lines)
            .filter(|(_, l)| l["status"] == "ok")
            .map(|(&f, _)| f)
    }

    /// The slice's frame range, `A..B` with B excluded. Invariant: `frames` is not empty
    /// (checked by [`Slice::read`]).
    fn range(&self) -> FrameRange {
        (self.frames[0], self.frames[self.frames.len() - 1] + 1)
    }

    fn range_of(&self) -> (PathBuf, usize, usize) {
        let (a, b) = self.range();
        (self.dir.clone(), a, b)
    }

    /// Reads `dir`'s journal (only complete lines; the file is not touched) and checks that it
    /// is a finished run.
    fn read(dir: &Path) -> Result<Slice, MergeError> {
        let bad = |reason: String| MergeError::NotASlice {
            dir: dir.to_path_buf(),
            reason,
        };
        let path = dir.join(JOURNAL);
        let text = std::fs::read_to_string(&path).map_err(|e| bad(format!("{JOURNAL}: {e}")))?;
        let (header, lines, _) =
            parse_journal(&text).map_err(|e| bad(format!("{JOURNAL}: {e}")))?;
        if header["format"] != "symcorr.track-journal/1" {
            return Err(bad(format!(
                "{JOURNAL}: not a symcorr.track-journal/1 header"
            )));
        }
        let frames: Vec<usize> = header["frames"]
            .as_array()
            .and_then(|a| {
                a.iter()
                    .map(|f| f.as_u64().and_then(|f| usize::try_from(f).ok()))
                    .collect()
            })
            .ok_or_else(|| bad(format!("{JOURNAL}: the header has no frame list")))?;
        if frames.is_empty() || !frames.windows(2).all(|w| w[0] < w[1]) {
            return Err(bad(format!(
                "{JOURNAL}: the frame list is empty or not increasing"
            )));
        }
        if lines.len() < frames.len() {
            return Err(MergeError::Unfinished {
                dir: dir.to_path_buf(),
                missing: frames.len() - lines.len(),
                frames: frames.len(),
            });
        }
        if lines.len() > frames.len() {
            return Err(bad(format!(
                "{JOURNAL}: {} frame lines for {} frames",
                lines.len(),
                frames.len()
            )));
        }
        if let Some((line, f)) = lines
            .iter()
            .zip(&frames)
            .find(|(l, &f)| l["frame"].as_u64() != Some(f as u64))
        {
            return Err(bad(format!(
                "{JOURNAL}: the line of frame {f} says frame {}",
                line["frame"]
            )));
        }
        Ok(Slice {
            dir: dir.to_path_buf(),
            header,
            frames,
            lines,
        })
    }
}

/// The slices in frame order, checked to be one run, finished and disjoint; and the frames
/// between consecutive slices that none holds (`from..to`), refused unless `allow_gaps`.
fn order(
    mut slices: Vec<Slice>,
    allow_gaps: bool,
) -> Result<(Vec<Slice>, Vec<FrameRange>), MergeError> {
    // Invariant: clap requires at least one DIR, and every one was read into a slice.
    let first = &slices[0];
    for s in &slices[1..] {
        if let Some((key, this, other)) = header_difference(&s.header, &first.header, &["frames"]) {
            return Err(MergeError::DifferentRun {
                dir: s.dir.clone(),
                other_dir: first.dir.clone(),
                key,
                this,
                other,
            });
        }
    }
    slices.sort_by_key(|s| s.frames[0]);
    // The step between frames within a slice (`--every`): a smaller distance between two
    // slices is no gap.
    let step = slices
        .iter()
        .flat_map(|s| s.frames.windows(2).map(|w| w[1] - w[0]))
        .min()
        .unwrap_or(1);
    let mut gaps = Vec::new();
    for w in slices.windows(2) {
        let (last, next) = (w[0].range().1 - 1, w[1].frames[0]);
        if next <= last {
            return Err(MergeError::Overlap {
                a: w[0].range_of(),
                b: w[1].range_of(),
            });
        }
        if next - last > step {
            if !allow_gaps {
                return Err(MergeError::Gap {
                    before: w[0].dir.clone(),
                    after: w[1].dir.clone(),
                    from: last + 1,
                    to: next,
                });
            }
            gaps.push((last + 1, next));
        }
    }
    Ok((slices, gaps))
}

/// The mesh of the template the journals name, checked against their vertex count.
fn template_mesh(header: &Value, max_input_bytes: u64) -> Result<TriMesh, MergeError> {
    let name = header["template"].as_str().unwrap_or_default().to_string();
    let err = |reason: String| MergeError::Template {
        name: name.clone(),
        reason,
    };
    let mesh = if name == BUNDLED_TEMPLATE {
        super::bundled_template_mesh().map_err(|e| err(e.0))?
    } else {
        symcorr::io::read_mesh(Path::new(&name), max_input_bytes).map_err(|e| err(e.to_string()))?
    };
    let n = header["template_vertices"].as_u64();
    if n != Some(mesh.num_vertices() as u64) {
        return Err(err(format!(
            "{} vertices, the journals say {}",
            mesh.num_vertices(),
            header["template_vertices"]
        )));
    }
    Ok(mesh)
}

/// One array of the run folder: its name, element type and row shape for a template of `n`
/// vertices.
fn arrays(n: usize) -> [(&'static str, NpyType, Vec<usize>); 3] {
    [
        ("correspondence.npy", NpyType::I32, vec![n]),
        ("confidence.npy", NpyType::F32, vec![n]),
        (posed::POSED_NPY, NpyType::F32, vec![n, 3]),
    ]
}

fn scan_name(frame: usize) -> String {
    format!("{frame:06}.ply")
}

/// Everything about the inputs that can be checked without writing: each slice's arrays open
/// with the shape its journal gives, and the scans of its matched frames exist.
fn check_files(slices: &[Slice], n: usize, scans: bool) -> Result<(), MergeError> {
    for s in slices {
        for (name, ty, shape) in arrays(n) {
            NpyReader::open(&s.dir.join(name), ty, s.frames.len(), &shape)?;
        }
        if scans {
            for frame in s.scanned_frames() {
                let p = s.dir.join("scans").join(scan_name(frame));
                std::fs::metadata(&p).map_err(io_err(&p))?;
            }
        }
    }
    Ok(())
}

/// Stages `out/name`: the slices' rows of that array, in order, streamed.
fn stage_array(
    batch: &mut OutputBatch,
    out: &Path,
    (name, ty, shape): (&str, NpyType, Vec<usize>),
    slices: &[Slice],
) -> Result<(), MergeError> {
    let path = out.join(name);
    let total = slices.iter().map(|s| s.frames.len()).sum();
    // add_streamed reports a failed write as an io::Error of the output; keep the slice's own
    // error, which names the input at fault.
    let mut failure = None;
    let staged = batch.add_streamed(&path, |w| {
        let copy = || -> Result<(), NpyError> {
            let mut writer = NpyWriter::streaming(w, &path, ty, total, &shape)?;
            let (mut ints, mut floats) = (Vec::new(), Vec::new());
            for s in slices {
                let rows = s.frames.len();
                let mut reader = NpyReader::open(&s.dir.join(name), ty, rows, &shape)?;
                for row in 0..rows {
                    match ty {
                        NpyType::I32 => {
                            reader.read_i32(row, &mut ints)?;
                            writer.push_i32(&ints)?;
                        }
                        NpyType::F32 => {
                            reader.read_f32(row, &mut floats)?;
                            writer.push_f32(&floats)?;
                        }
                    }
                }
            }
            writer.finish().map(|_| ())
        };
        copy().map_err(|e| {
            let io = std::io::Error::other(e.to_string());
            failure = Some(e);
            io
        })
    });
    match (staged, failure) {
        (Ok(()), _) => Ok(()),
        (Err(_), Some(e)) => Err(e.into()),
        (Err(e), None) => Err(MergeError::Output(e.to_string())),
    }
}

/// The merged scans in a staging folder inside `out` (removed when dropped): each slice's scans
/// hard-linked — the outputs are replaced by renames, never rewritten in place, so a link
/// never sees a later change — or copied where the file system cannot link.
fn stage_scans(out: &Path, slices: &[Slice]) -> Result<tempfile::TempDir, MergeError> {
    let staging = tempfile::Builder::new()
        .prefix(".symcorr-tmp-scans-")
        .tempdir_in(out)
        .map_err(io_err(out))?;
    for s in slices {
        for frame in s.scanned_frames() {
            let name = scan_name(frame);
            let (from, to) = (s.dir.join("scans").join(&name), staging.path().join(&name));
            if std::fs::hard_link(&from, &to).is_err() {
                std::fs::copy(&from, &to).map_err(io_err(&from))?;
                std::fs::File::open(&to)
                    .and_then(|f| f.sync_all())
                    .map_err(io_err(&to))?;
            }
        }
    }
    Ok(staging)
}

/// What the merge found, for the summary line.
struct Merged {
    summary: Value,
    slices: usize,
}

/// Writes the merged folder into `out` (an existing, empty folder).
fn write(
    out: &Path,
    slices: &[Slice],
    gaps: &[FrameRange],
    template: &TriMesh,
) -> Result<Merged, MergeError> {
    let n = template.num_vertices();
    let out_err = |e: symcorr_mesh::MeshError| MergeError::Output(e.to_string());
    let frames: Vec<usize> = slices
        .iter()
        .flat_map(|s| s.frames.iter().copied())
        .collect();
    let lines: Vec<Value> = slices
        .iter()
        .flat_map(|s| s.lines.iter().cloned())
        .collect();
    let total = frames.len();
    let mut header = slices[0].header.clone();
    header["frames"] = json!(frames);
    let mut batch = OutputBatch::new();
    for array in arrays(n) {
        stage_array(&mut batch, out, array, slices)?;
    }
    let posed_path = out.join(posed::POSED_NPY);
    // Invariant: stage_array staged it just above, into a temporary file.
    let staged_posed = batch
        .staged_file(&posed_path)
        .map(Path::to_path_buf)
        .ok_or_else(|| MergeError::Output(format!("{}: not staged", posed_path.display())))?;
    let digests: Vec<report::FrameDigest> = lines.iter().map(report::FrameDigest::of).collect();
    let glb = posed::stage_glb(&mut batch, out, &staged_posed, template, &digests, total)
        .map_err(|e| MergeError::Output(e.0))?;
    let mut summary = report::summary(&digests, total);
    summary["frames_per_second_this_run"] = Value::Null;
    summary["template_track"] = glb;
    summary["merged_from"] = json!(slices
        .iter()
        .map(|s| {
            let (a, b) = s.range();
            json!({"dir": s.dir.display().to_string(), "frames": format!("{a}..{b}")})
        })
        .collect::<Vec<_>>());
    summary["gaps"] = json!(gaps
        .iter()
        .map(|(a, b)| format!("{a}..{b}"))
        .collect::<Vec<_>>());
    let frame_lines = |emit: &mut dyn FnMut(&str) -> std::io::Result<()>| {
        lines.iter().try_for_each(|l| emit(&l.to_string()))
    };
    report::stage(
        &mut batch,
        out,
        &header,
        frame_lines,
        &digests,
        total,
        &summary,
    )
    .map_err(|e| MergeError::Output(e.0))?;
    // The journal last: a folder with a journal is a complete run folder.
    let journal = out.join(JOURNAL);
    batch
        .add_streamed(&journal, |w| {
            writeln!(w, "{header}")?;
            lines.iter().try_for_each(|l| writeln!(w, "{l}"))
        })
        .map_err(out_err)?;
    let scans = if header["scans"] == true {
        Some(stage_scans(out, slices)?)
    } else {
        None
    };
    if let Some(staging) = scans {
        let to = out.join("scans");
        std::fs::rename(staging.path(), &to).map_err(io_err(&to))?;
        // Renamed into place: nothing left to remove.
        let _kept = staging.keep();
    }
    batch.commit().map_err(out_err)?;
    Ok(Merged {
        summary,
        slices: slices.len(),
    })
}

/// Runs `symcorr track-merge`.
pub fn run(args: TrackMergeArgs, max_input_bytes: u64) -> Result<(), CliError> {
    let out = &args.out;
    let existed = out.exists();
    if existed {
        let empty = std::fs::read_dir(out).map(|mut d| d.next().is_none());
        if !matches!(empty, Ok(true)) {
            return Err(MergeError::OutNotEmpty { out: out.clone() }.into());
        }
    }
    let slices = args
        .slices
        .iter()
        .map(PathBuf::as_path)
        .map(Slice::read)
        .collect::<Result<Vec<_>, _>>()?;
    let (slices, gaps) = order(slices, args.allow_gaps)?;
    let header = &slices[0].header;
    let template = template_mesh(header, max_input_bytes)?;
    check_files(&slices, template.num_vertices(), header["scans"] == true)?;
    std::fs::create_dir_all(out).map_err(io_err(out))?;
    let merged = write(out, &slices, &gaps, &template).inspect_err(|_| {
        // The batch and the scans' staging folder removed their files when dropped; a folder
        // this command created goes too (remove_dir: only if empty, never anything else).
        if !existed {
            let _ = std::fs::remove_dir(out);
        }
    })?;
    let s = &merged.summary;
    let gaps = if gaps.is_empty() {
        "no gaps".to_string()
    } else {
        format!(
            "gaps: frames {}",
            gaps.iter()
                .map(|(a, b)| format!("{a}..{b}"))
                .collect::<Vec<_>>()
                .join(", ")
        )
    };
    println!(
        "merged {} slices into {}: {} frames ({} matched, {} skipped), {gaps}",
        merged.slices,
        out.display(),
        s["frames"],
        s["ok"],
        s["skipped"],
    );
    Ok(())
}
