#![no_main]
//! NTU RGB+D .skeleton parser: never panics, never allocates from an untrusted count.
use libfuzzer_sys::fuzz_target;
use symcorr_kinect::joints::BodySelect;
use symcorr_kinect::ntu::parse_ntu;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = parse_ntu(text, "fuzz", BodySelect::MostTracked);
        let _ = parse_ntu(text, "fuzz", BodySelect::Id(1));
    }
});
