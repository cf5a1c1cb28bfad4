//! Generates bindings to `OniCAPI.h` when feature `openni2` is on; does nothing otherwise, so the
//! default workspace build needs no system library.

fn main() {
    #[cfg(feature = "openni2")]
    bind();
}

#[cfg(feature = "openni2")]
fn bind() {
    use std::path::PathBuf;

    println!("cargo:rerun-if-changed=wrapper.h");
    // pkg-config emits the link line (-lOpenNI2) and gives the include path (/usr/include/openni2
    // on Debian's libopenni2-dev).
    let lib = match pkg_config::Config::new().probe("libopenni2") {
        Ok(lib) => lib,
        Err(e) => {
            println!(
                "cargo:warning=feature `openni2` needs libopenni2-dev (pkg-config name libopenni2) \
                 and libclang-dev: {e}"
            );
            std::process::exit(1);
        }
    };
    let mut builder = bindgen::Builder::default()
        .header("wrapper.h")
        // OniCAPI.h uses C++-only constructs in the headers it includes (OniPlatform.h selects
        // its platform header by C++ macros; `ONI_C_API` expands to `extern "C"`).
        .clang_args(["-x", "c++", "-std=c++11"])
        .allowlist_function("oni.*")
        .allowlist_type("Oni.*|_Oni.*")
        .allowlist_var("ONI_.*|XN_.*")
        // Newtype enums, not Rust enums: a value the C library returns outside the listed
        // variants (a newer driver, a corrupt file) must not be undefined behaviour.
        .newtype_enum("_?OniStatus|_?OniSensorType|_?OniPixelFormat")
        .layout_tests(false)
        .generate_comments(false)
        .parse_callbacks(Box::new(bindgen::CargoCallbacks::new()));
    for p in &lib.include_paths {
        builder = builder.clang_arg(format!("-I{}", p.display()));
    }
    let bindings = match builder.generate() {
        Ok(b) => b,
        Err(e) => {
            println!("cargo:warning=bindgen failed on OniCAPI.h (is libclang-dev installed?): {e}");
            std::process::exit(1);
        }
    };
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    if let Err(e) = bindings.write_to_file(out.join("bindings.rs")) {
        println!("cargo:warning=writing the OpenNI2 bindings failed: {e}");
        std::process::exit(1);
    }
}
