#![no_main]
//! Azure Kinect body tracking JSON parser: never panics; whatever it accepts is finite, and
//! written back (`to_k4abt_json`) reads to the same joints.
use libfuzzer_sys::fuzz_target;
use symcorr_kinect::joints::BodySelect;
use symcorr_kinect::k4abt::{parse_k4abt, to_k4abt_json};

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    for select in [BodySelect::MostTracked, BodySelect::Id(1)] {
        let Ok(log) = parse_k4abt(&text, "fuzz", select) else {
            continue;
        };
        assert!(!log.frames.is_empty());
        for f in &log.frames {
            assert!(f.time_s.is_finite() && f.time_s >= 0.0);
            assert!(f.skeleton.positions.iter().all(|p| p.iter().all(|c| c.is_finite())));
        }
        // Written and read back: the same tracked joints (to a micrometre: the file is in mm).
        let again = parse_k4abt(&to_k4abt_json(&log), "again", BodySelect::MostTracked)
            .expect("a written log reads back");
        assert_eq!(again.frames.len(), log.frames.len());
        for (a, b) in log.frames.iter().zip(&again.frames) {
            assert_eq!(a.skeleton.tracks_any(), b.skeleton.tracks_any());
            if a.skeleton.tracks_any() {
                for (p, q) in a.skeleton.positions.iter().zip(&b.skeleton.positions) {
                    for k in 0..3 {
                        assert!((p[k] - q[k]).abs() <= 1e-6 * (1.0 + p[k].abs()));
                    }
                }
            }
        }
    }
});
