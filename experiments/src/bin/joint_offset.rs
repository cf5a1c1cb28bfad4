//! The joint-log clock offset `symcorr track --joint-offset auto` estimates
//! ([`symcorr_kinect::clock::estimate_joint_offset`]) on one recording and log (a
//! `symcorr-synth` recording's `recording.json` holds the offset it was made with).
//!
//! ```text
//! joint_offset REC --joints LOG [--frames K] [--curve]
//! ```

use clap::Parser;
use std::path::PathBuf;
use symcorr_kinect::clock::{estimate_joint_offset, OffsetSearch};
use symcorr_kinect::{DepthFrame, DepthSource, JointTrack};

/// The joint-log clock offset estimated from a recording's frames
#[derive(Parser, Debug)]
struct Args {
    /// Recording folder (or .oni with the openni2 feature)
    recording: PathBuf,
    /// Joint log
    #[arg(long)]
    joints: PathBuf,
    /// Frames used, spread over the recording
    #[arg(long, default_value_t = 30)]
    frames: usize,
    /// Also print the score of every offset tried
    #[arg(long)]
    curve: bool,
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = Args::parse();
    let mut source = DepthSource::open(&args.recording)?;
    let track = JointTrack::new(symcorr_kinect::read_joints(&args.joints)?, 0.0)?;
    let (n, k) = (source.len(), args.frames.min(source.len()));
    let mut sample: Vec<(f64, DepthFrame)> = Vec::new();
    for i in (0..k).map(|i| (2 * i + 1) * n / (2 * k)) {
        if let Some(t) = source.time(i) {
            sample.push((t, source.frame(i)?));
        }
    }
    let estimate = estimate_joint_offset(
        &sample,
        source.intrinsics(),
        &track,
        &OffsetSearch::default(),
    );
    match estimate {
        Some(e) => {
            if args.curve {
                for (o, s, m) in &e.curve {
                    println!("offset {o:.3} score {s:.5} lookups {m}");
                }
            }
            println!("estimate {:.3} s score {:.5} m", e.offset_s, e.score_m);
        }
        None => println!("no estimate: the log covers no frame"),
    }
    Ok(())
}
