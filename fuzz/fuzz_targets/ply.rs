#![no_main]

use libfuzzer_sys::fuzz_target;
use symcorr_mesh::io::Format;

mod common;

fuzz_target!(|data: &[u8]| common::check(data, Format::Ply));
