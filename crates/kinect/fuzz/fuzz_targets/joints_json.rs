#![no_main]
//! symcorr.joints/1 JSON parser (and content detection): never panics; a parsed log has only
//! finite positions and confidences in [0, 1], and re-serialising it parses again.
use libfuzzer_sys::fuzz_target;
use symcorr_kinect::joints::{parse_joints, parse_joints_json, to_json_string};

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = parse_joints(text, "fuzz");
        if let Ok(log) = parse_joints_json(text, "fuzz") {
            for f in &log.frames {
                assert!(f.skeleton.positions.iter().flatten().all(|c| c.is_finite()));
                assert!(f
                    .skeleton
                    .confidence
                    .iter()
                    .all(|c| (0.0..=1.0).contains(c)));
            }
            let again =
                parse_joints_json(&to_json_string(&log), "fuzz").expect("writer output parses");
            assert_eq!(again.frames.len(), log.frames.len());
        }
    }
});
