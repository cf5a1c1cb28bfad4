//! The `symcorr` command. Each subcommand lives in its own module under `cli/`; this file only
//! parses arguments and maps errors to exit codes (DESIGN.md: 0 success, 1 user error with one
//! line on stderr, 2 usage error — clap exits with 2 itself).

use clap::{Parser, Subcommand};
use std::process::ExitCode;

mod cli;

/// Skeleton-aware human shape correspondence.
#[derive(Parser)]
#[command(name = "symcorr", version, about, long_about = None)]
struct Args {
    /// Largest mesh input read, in bytes or with a K/M/G suffix (powers of 1024); a .gltf's
    /// external buffers count with it.
    #[arg(long, global = true, value_name = "BYTES", default_value = "1G",
          value_parser = symcorr::io::parse_byte_size)]
    max_input_size: u64,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Laplace–Beltrami spectrum of a mesh: counts, repair report, eigenvalues, timings.
    Spectrum(cli::spectrum::SpectrumArgs),
    /// Correspondence between two meshes with their skeletons (symcorr.correspondence/1 JSON).
    Match(cli::match_cmd::MatchArgs),
    /// Run every pair of a benchmark dataset: mean error, flip rate, Table 1 row, plot.
    Bench(cli::bench::BenchArgs),
    /// The whole pipeline on bundled fixtures, with outputs in ./symcorr-demo/.
    Demo(cli::demo::DemoArgs),
    /// Depth frame (.oni recording, PNG-16, or device) + joints → scan mesh.
    Scan(cli::scan::ScanArgs),
    /// Attach a skeleton to a mesh: 17 segment labels (symcorr.labels/1) and a coloured mesh.
    Label(cli::label::LabelArgs),
    /// A recorded session (depth frames + joint log) matched frame by frame (symcorr.track/1).
    Track(cli::track::TrackArgs),
    /// Merge the output folders of slices of one track run (`track --frames A..B`) into one.
    TrackMerge(cli::track::merge::TrackMergeArgs),
    /// A self-contained HTML page of a correspondence, labels or track result (three.js).
    View(cli::view::ViewArgs),
}

fn main() -> ExitCode {
    restore_sigpipe();
    let args = Args::parse();
    let limit = args.max_input_size;
    let result = match args.command {
        Command::Spectrum(a) => cli::spectrum::run(a, limit),
        Command::Match(a) => cli::match_cmd::run(a, limit),
        Command::Bench(a) => cli::bench::run(a, limit),
        Command::Demo(a) => cli::demo::run(a, limit),
        Command::Scan(a) => cli::scan::run(a),
        Command::Label(a) => cli::label::run(a, limit),
        Command::Track(a) => cli::track::run(a, limit),
        Command::TrackMerge(a) => cli::track::merge::run(a, limit),
        Command::View(a) => cli::view::run(a, limit),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("symcorr: {e}");
            ExitCode::from(1)
        }
    }
}

/// Rust ignores SIGPIPE, so `symcorr spectrum … | head` would make `println!` panic on the closed
/// pipe. Restore the default action: the process ends quietly when its reader goes away, like
/// every other Unix filter.
#[allow(unsafe_code)] // one libc call, see SAFETY below
fn restore_sigpipe() {
    #[cfg(unix)]
    // SAFETY: called first thing in main, before any thread exists; SIG_DFL is a valid handler.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}
