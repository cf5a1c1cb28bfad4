//! Generates bindings to `OniCAPI.h` when feature `openni2` is on; does nothing otherwise.

fn main() {
    #[cfg(feature = "openni2")]
    bind();
}

#[cfg(feature = "openni2")]
fn bind() {
    // Placeholder until the kinect issue fills this crate: find the library so that a
    // missing install fails with pkg-config's message rather than at link time.
    let lib = pkg_config::Config::new()
        .probe("libopenni2")
        .unwrap_or_else(|e| panic!("feature `openni2` needs libopenni2-dev (pkg-config libopenni2): {e}"));
    let _ = (lib, bindgen::builder());
}
