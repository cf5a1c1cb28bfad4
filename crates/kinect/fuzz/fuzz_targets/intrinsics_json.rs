#![no_main]
//! `symcorr.intrinsics/1` reader (`Intrinsics::from_json_str`, which `Intrinsics::read` calls) on
//! arbitrary bytes decoded as lossy UTF-8: never panics, every error is a `KinectError::Json`
//! naming the file; accepted intrinsics validate, and written (`to_json`) read back equal.
use libfuzzer_sys::fuzz_target;
use symcorr_kinect::{Intrinsics, KinectError};

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    match Intrinsics::from_json_str(&text, "fuzz") {
        Err(KinectError::Json { file, .. }) => assert_eq!(file, "fuzz"),
        Err(e) => panic!("not a Json error: {e:?}"),
        Ok(k) => {
            assert!(k.validate().is_ok(), "accepted but invalid: {k:?}");
            let json = k.to_json();
            let back = Intrinsics::from_json_str(&json, "fuzz").expect("writer output parses");
            assert_eq!(back, k, "JSON round trip changed the intrinsics: {json}");
            assert_eq!(back.to_json(), json);
        }
    }
});
