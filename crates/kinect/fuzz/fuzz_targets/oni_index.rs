#![no_main]
//! `.oni` depth-frame index: never panics; the in-memory and the reader variant agree; what is
//! accepted is at least one strictly increasing time, no more than the input has room for.
use libfuzzer_sys::fuzz_target;
use std::io::Cursor;
use symcorr_kinect::oni_index::{depth_frame_times, depth_frame_times_in};

fuzz_target!(|data: &[u8]| {
    let from_slice = depth_frame_times(data);
    let from_reader = depth_frame_times_in(Cursor::new(data));
    match (&from_slice, &from_reader) {
        (Ok(a), Ok(b)) => {
            assert_eq!(a, b);
            assert!(!a.is_empty());
            assert!(a.windows(2).all(|w| w[0] < w[1]));
            // A 24-byte file header, then at least 36 bytes per frame record.
            assert!(24 + 36 * a.len() <= data.len());
        }
        (Err(a), Err(b)) => assert_eq!(a.to_string(), b.to_string()),
        _ => panic!("slice {from_slice:?} but reader {from_reader:?}"),
    }
});
