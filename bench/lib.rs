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
/// project; an error naming the folder where it is absent.
pub fn shared_mesh_dir() -> Result<PathBuf, String> {
    let dir = std::env::var_os("STRATA_MESH_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/meshes"));
    if dir.is_dir() {
        Ok(dir)
    } else {
        Err(format!(
            "{}: mesh folder not found (set STRATA_MESH_DIR)",
            dir.display()
        ))
    }
}

/// The first command-line argument as a repeat count, or `default`.
pub fn repeats_arg(default: usize) -> Result<usize, std::num::ParseIntError> {
    std::env::args()
        .nth(1)
        .map(|a| a.parse())
        .transpose()
        .map(|r| r.unwrap_or(default))
}
