//! Shared helpers for strata benchmarks.

use std::path::PathBuf;

/// The shared meshes, largest first, as the benchmark tables list them.
pub const SHARED_MESHES: [&str; 8] = [
    "stanford-bunny",
    "rocker-arm",
    "fandisk",
    "homer",
    "spot",
    "cow",
    "two-torus",
    "wing",
];

/// The shared test meshes: `STRATA_MESH_DIR`, else `../shared/meshes` beside the
/// project (see [`strata_engine::io::shared_mesh_dir`]); an error naming the folder
/// where it is absent.
pub fn shared_mesh_dir() -> Result<PathBuf, String> {
    strata_engine::io::shared_mesh_dir().ok_or_else(|| {
        format!(
            "{}: mesh folder not found (set STRATA_MESH_DIR)",
            strata_engine::io::shared_mesh_location().display()
        )
    })
}

/// The first command-line argument as a repeat count, or `default`.
pub fn repeats_arg(default: usize) -> Result<usize, std::num::ParseIntError> {
    std::env::args()
        .nth(1)
        .map(|a| a.parse())
        .transpose()
        .map(|r| r.unwrap_or(default))
}
