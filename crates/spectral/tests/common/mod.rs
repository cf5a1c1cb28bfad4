//! Test meshes: the synthetic generators live in `symcorr_spectral::testmesh` (shared with the
//! benches); plus the body fixture.
#![allow(dead_code, unused_imports)]

use symcorr_mesh::TriMesh;
pub use symcorr_spectral::testmesh::{disk, icosphere, union};

/// The realistic body fixture.
pub fn body() -> TriMesh {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/body/body.off");
    symcorr_mesh::io::read(path).unwrap().mesh
}
