//! `symcorr spectrum MESH --k 100 [--json]` (filled by the core issue's spectral work).

use super::CliError;
use std::path::PathBuf;

/// Arguments of `symcorr spectrum`.
#[derive(clap::Args)]
pub struct SpectrumArgs {
    /// Mesh file (OBJ, OFF, PLY, glTF/GLB).
    pub mesh: PathBuf,
    /// Number of eigenpairs.
    #[arg(long, default_value_t = 100)]
    pub k: usize,
    /// Print machine-readable JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: SpectrumArgs) -> Result<(), CliError> {
    Err(CliError(format!(
        "{}: spectrum is not built yet (k = {}, json = {})",
        args.mesh.display(),
        args.k,
        args.json
    )))
}
