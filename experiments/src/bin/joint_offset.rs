//! The joint-log clock offset `symcorr track --joint-offset auto` estimates
//! ([`symcorr_kinect::clock::estimate_recording_offset`]) on one recording and log (a
//! `symcorr-synth` recording's `recording.json` holds the offset it was made with).
//!
//! ```text
//! joint_offset REC --joints LOG [--frames K] [--curve]
//! ```

use clap::Parser;
use std::path::PathBuf;
use symcorr_kinect::clock::{estimate_recording_offset, OffsetSearch};
use symcorr_kinect::{DepthSource, JointTrack};

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
    let estimate =
        estimate_recording_offset(&mut source, &track, args.frames, &OffsetSearch::default());
    match estimate {
        Ok(e) => {
            if args.curve {
                for (o, s, m) in &e.curve {
                    println!("offset {o:.3} score {s:.5} lookups {m}");
                }
            }
            println!("estimate {:.3} s score {:.5} m", e.offset_s, e.score_m);
        }
        Err(e) => println!("no estimate: {e}"),
    }
    Ok(())
}
