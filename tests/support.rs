//! What the end-to-end test binaries share: the `symcorr` binary, running it with its output
//! shown when it fails, and reading a JSON file.

use serde_json::Value;
use std::path::Path;
use std::process::{Command, Output};

/// The `symcorr` binary under test.
pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_symcorr"))
}

/// Runs `cmd`; on failure its stdout and stderr are printed (the test's own message follows).
pub fn run(cmd: &mut Command) -> Output {
    let out = cmd.output().expect("symcorr runs");
    if !out.status.success() {
        eprintln!(
            "stdout:\n{}\nstderr:\n{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
    }
    out
}

/// The JSON file at `p`.
pub fn read_json(p: &Path) -> Value {
    serde_json::from_slice(&std::fs::read(p).unwrap()).unwrap()
}
