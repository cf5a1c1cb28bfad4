#![no_main]
//! `.oni` depth-stream index: never panics; the in-memory and the reader variant agree (times
//! and recorded mirroring); what is accepted is at least one strictly increasing time, no more
//! than the input has room for, and the times alone are the index's.
use libfuzzer_sys::fuzz_target;
use std::io::Cursor;
use symcorr_kinect::oni_index::{depth_frame_times, depth_stream_index, depth_stream_index_in};

fuzz_target!(|data: &[u8]| {
    let from_slice = depth_stream_index(data);
    let from_reader = depth_stream_index_in(Cursor::new(data));
    match (&from_slice, &from_reader) {
        (Ok(a), Ok(b)) => {
            assert_eq!(a, b);
            let t = &a.times_us;
            assert!(!t.is_empty());
            assert!(t.windows(2).all(|w| w[0] < w[1]));
            // A 24-byte file header, then at least 36 bytes per frame record.
            assert!(24 + 36 * t.len() <= data.len());
            assert_eq!(depth_frame_times(data).ok().as_ref(), Some(t));
        }
        (Err(a), Err(b)) => assert_eq!(a.to_string(), b.to_string()),
        _ => panic!("slice {from_slice:?} but reader {from_reader:?}"),
    }
});
