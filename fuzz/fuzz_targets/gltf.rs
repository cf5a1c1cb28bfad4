#![no_main]

use libfuzzer_sys::fuzz_target;
use symcorr_mesh::io::Format;

mod common;

// One target for both containers: GLB when the input starts with the GLB magic, JSON otherwise.
fuzz_target!(|data: &[u8]| {
    let format = if data.starts_with(b"glTF") { Format::Glb } else { Format::Gltf };
    common::check(data, format)
});
