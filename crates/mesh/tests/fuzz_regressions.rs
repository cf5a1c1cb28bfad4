//! Every input the fuzzers (fuzz/, `cargo fuzz`) ever crashed on is kept in
//! fixtures/mesh/fuzz-regressions/ and must now parse or fail with a typed error, in every
//! format (the file extension names the format the crash was found with).

use symcorr_mesh::io::{self, Format};

#[test]
fn fuzz_crash_inputs_no_longer_panic() {
    let dir = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/mesh/fuzz-regressions"
    );
    let mut seen = 0;
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let bytes = std::fs::read(&path).unwrap();
        let own = Format::from_path(&path).expect("regression files carry a format extension");
        for f in [
            own,
            Format::Off,
            Format::Obj,
            Format::Ply,
            Format::Gltf,
            Format::Glb,
        ] {
            // Must return (Ok or Err), not panic; the crash's own format must give a typed error.
            let r = io::read_from_bytes(&bytes, f);
            if f == own {
                assert!(r.is_err(), "{}: malformed input accepted", path.display());
            }
        }
        seen += 1;
    }
    assert!(seen >= 1);
}
