//! The joint-log check of `symcorr track` on one recording and log, frame by frame: the
//! skeleton's fit checks in each sampled frame, the median share of bone points outside the
//! body the camera sees, the scans' heights against the skeletons' (`height_ratio`), and the
//! verdict. Run it on
//! recordings with their own logs and with logs made wrong (mirrored, shifted in time) to see
//! where [`symcorr::track::log_check::MAX_LOG_OUTSIDE`] sits between them.
//!
//! ```text
//! log_check REC --joints LOG [--joint-offset S] [--samples K]
//! ```

use clap::Parser;
use std::path::PathBuf;
use symcorr::track::log_check::{check_log, LOG_CHECK_FRAMES};
use symcorr::track::TrackOptions;
use symcorr::{Pipeline, PipelineOptions};
use symcorr_kinect::{DepthSource, JointTrack};

/// The joint-log check of `symcorr track`, frame by frame
#[derive(Parser, Debug)]
struct Args {
    /// Recording folder (or .oni with the openni2 feature)
    recording: PathBuf,
    /// Joint log
    #[arg(long)]
    joints: PathBuf,
    /// Seconds added to every depth frame's time before the joint log is read
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    joint_offset: f64,
    /// Frames fitted, spread over the recording
    #[arg(long, default_value_t = LOG_CHECK_FRAMES)]
    samples: usize,
    /// Template body folder (meshes/, joints/)
    #[arg(long, default_value = "fixtures/synth/bodies")]
    bodies: PathBuf,
    /// Template name in the body folder
    #[arg(long, default_value = "s0_rest")]
    template: String,
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = Args::parse();
    let mesh = symcorr_mesh::io::read(
        args.bodies
            .join("meshes")
            .join(format!("{}.ply", args.template)),
    )?
    .mesh;
    let sk = symcorr::io::read_skeleton(
        &args
            .bodies
            .join("joints")
            .join(format!("{}.json", args.template)),
        None,
    )?;
    let pipeline = Pipeline::new(PipelineOptions {
        mode: symcorr::Mode::Dense,
        ..PipelineOptions::default()
    });
    let template = pipeline.prepare(mesh, &sk)?;
    let mut source = DepthSource::open(&args.recording)?;
    let joints = JointTrack::new(symcorr_kinect::read_joints(&args.joints)?, 0.0)?;
    let options = TrackOptions {
        joint_offset_s: args.joint_offset,
        ..TrackOptions::default()
    };
    let frames: Vec<usize> = (0..source.len()).collect();
    let started = std::time::Instant::now();
    let check = check_log(
        &pipeline,
        &template,
        &mut source,
        &joints,
        &options,
        &frames,
        args.samples,
    );
    for (i, fit) in &check.frames {
        match fit {
            Ok(f) => {
                let checks: Vec<String> = f
                    .checks
                    .iter()
                    .map(|c| format!("{} {:.3}/{:.3}", c.kind.name(), c.value, c.limit))
                    .collect();
                println!("frame {i} score {:.3} {}", f.score, checks.join(" "));
            }
            Err(reason) => println!("frame {i} skipped: {reason}"),
        }
    }
    let verdict = match check.verdict() {
        Ok(()) => "pass".to_string(),
        Err(e) => format!("refused: {e}"),
    };
    let seconds = started.elapsed().as_secs_f64();
    let mut heights = check.heights.clone();
    heights.sort_by(f64::total_cmp);
    // As the check's median: the mean of the middle two for an even count.
    let median_height = match heights.len() {
        0 => "-".to_string(),
        n if n % 2 == 1 => format!("{:.3}", heights[n / 2]),
        n => format!("{:.3}", 0.5 * (heights[n / 2 - 1] + heights[n / 2])),
    };
    println!(
        "ALL fits {} median_outside {} median_height_ratio {median_height} (of {:.3?}) seconds {seconds:.2} {verdict}",
        check.outside().len(),
        check
            .median_outside()
            .map_or("-".to_string(), |m| format!("{m:.3}")),
        heights,
    );
    Ok(())
}
