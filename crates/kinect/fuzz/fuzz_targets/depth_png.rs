#![no_main]
//! PNG-16 depth decoder: never panics; a decoded frame has width × height values.
use libfuzzer_sys::fuzz_target;
use symcorr_kinect::depth::decode_depth_png16;

fuzz_target!(|data: &[u8]| {
    if let Ok(f) = decode_depth_png16(data, "fuzz") {
        assert_eq!(f.data_mm.len(), f.width as usize * f.height as usize);
    }
});
