#![no_main]
//! Joint-file format detection (`JointFormat::detect`, `parse_joints`) on arbitrary bytes decoded
//! as lossy UTF-8: never panics; an unrecognised file gets one line saying what was tried; a
//! recognised one parses exactly as its format's parser does, and an accepted log written as
//! symcorr.joints/1 reads back to the same frames.
use libfuzzer_sys::fuzz_target;
use symcorr_kinect::joints::{parse_joints, parse_joints_as, to_json_string, BodySelect};
use symcorr_kinect::{JointFormat, KinectError};

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let detected = JointFormat::detect(&text);
    match parse_joints(&text, "fuzz") {
        Err(KinectError::UnknownFormat { message, .. }) => {
            assert!(
                detected.is_none(),
                "detected {detected:?} but UnknownFormat"
            );
            assert!(
                !message.contains('\n') && !message.contains('\r'),
                "{message:?}"
            );
            assert!(message.chars().count() < 300, "{message:?}");
        }
        Err(e) => {
            let f = detected.expect("a parse error other than UnknownFormat has a format");
            let direct = parse_joints_as(&text, "fuzz", f, BodySelect::MostTracked);
            assert_eq!(direct.map_err(|d| d.to_string()).err(), Some(e.to_string()));
        }
        Ok((log, format)) => {
            assert_eq!(Some(format), detected);
            let json = to_json_string(&log);
            let (back, back_format) = parse_joints(&json, "fuzz").expect("writer output parses");
            assert_eq!(back_format, JointFormat::Json);
            assert_eq!(
                back.frames, log.frames,
                "JSON round trip changed the frames"
            );
        }
    }
});
