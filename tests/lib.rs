//! Helpers shared by strata's integration tests (see `tests/`): where the test meshes
//! live.

use std::path::PathBuf;

/// The shared meshes (`<name>.obj` in [`shared_mesh_dir`]) the tests run on.
pub const SHARED_MESHES: [&str; 8] = [
    "spot",
    "two-torus",
    "stanford-bunny",
    "rocker-arm",
    "fandisk",
    "homer",
    "cow",
    "wing",
];

/// The folder of real test meshes (`shared/meshes` beside the project, see its
/// README), or `None` where it is absent so that tests can skip.
///
/// `STRATA_MESH_DIR` overrides the default `<workspace>/../shared/meshes`; see
/// [`strata_engine::io::shared_mesh_dir`], which this forwards to.
pub fn shared_mesh_dir() -> Option<PathBuf> {
    strata_engine::io::shared_mesh_dir()
}

/// The project's own small mesh corpus, `tests/data/meshes`.
pub fn corpus_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/meshes")
}

/// The project's bundled scene files, `configs/*.ron`, sorted.
pub fn config_files() -> Vec<PathBuf> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../configs");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .map(|entries| {
            entries
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|e| e == "ron"))
                .collect()
        })
        .unwrap_or_default();
    files.sort();
    files
}
