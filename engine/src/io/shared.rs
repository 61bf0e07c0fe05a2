//! Where the shared mesh corpus lives: the real meshes (bunny, fandisk, ...) that tests,
//! benchmarks and experiments run on but the repository does not hold.
//!
//! Input: the environment variable [`MESH_DIR_VAR`] (`STRATA_MESH_DIR`). Output: the
//! folder, or `None` where it is absent so that callers can skip. Cost: one `stat`.
//!
//! The default, `<workspace>/../shared/meshes`, is computed from this crate's
//! `CARGO_MANIFEST_DIR` at compile time, so it is the same whichever crate of the
//! workspace asks (the tests, the benchmarks or the engine's own unit tests). It only
//! makes sense inside a checkout of the workspace; elsewhere set [`MESH_DIR_VAR`].

use std::ffi::OsStr;
use std::path::PathBuf;

/// The environment variable that overrides the shared mesh folder (an empty value counts
/// as unset).
pub const MESH_DIR_VAR: &str = "STRATA_MESH_DIR";

/// The folder of the shared mesh corpus: [`shared_mesh_location`] if it is a directory,
/// else `None` (so that tests can skip where the corpus is absent).
///
/// ```
/// if let Some(dir) = strata_engine::io::shared_mesh_dir() {
///     assert!(dir.is_dir());
/// }
/// ```
pub fn shared_mesh_dir() -> Option<PathBuf> {
    existing_dir(shared_mesh_location())
}

/// Where the shared mesh corpus is looked for, whether or not it exists (for messages):
/// `$STRATA_MESH_DIR` if set and non-empty, else [`default_shared_mesh_dir`].
pub fn shared_mesh_location() -> PathBuf {
    location_from(std::env::var_os(MESH_DIR_VAR).as_deref())
}

/// The default shared mesh folder, `<workspace>/../shared/meshes` (not checked).
pub fn default_shared_mesh_dir() -> PathBuf {
    workspace_root().join("../shared/meshes")
}

/// The workspace root: the folder above this crate's manifest.
fn workspace_root() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
}

/// The folder named by the variable's value `var`, or the default where it is unset or
/// empty. Kept apart from the environment read so that tests can pass the value.
fn location_from(var: Option<&OsStr>) -> PathBuf {
    match var {
        Some(dir) if !dir.is_empty() => PathBuf::from(dir),
        _ => default_shared_mesh_dir(),
    }
}

/// `dir` if it is a directory.
fn existing_dir(dir: PathBuf) -> Option<PathBuf> {
    dir.is_dir().then_some(dir)
}

/// Loads mesh `name` (with its extension) of the shared corpus, or prints a note and
/// returns `None` where the corpus or the file is absent. Test code only: a file that
/// is present but does not load is a failure.
#[cfg(test)]
pub(crate) fn shared_mesh(name: &str) -> Option<crate::mesh::TriMesh> {
    let path = shared_mesh_location().join(name);
    if !path.exists() {
        println!("note: {} absent, skipped", path.display());
        return None;
    }
    Some(super::load(&path).expect("shared mesh loads"))
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;

    #[test]
    fn the_variable_wins_over_the_default() {
        let dir = tempfile::tempdir().expect("temp dir");
        let location = location_from(Some(dir.path().as_os_str()));
        assert_eq!(location, dir.path());
        assert_eq!(existing_dir(location), Some(dir.path().to_path_buf()));
    }

    #[test]
    fn unset_or_empty_gives_the_folder_beside_the_workspace() {
        let expected = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("..")
            .join("../shared/meshes");
        assert_eq!(location_from(None), expected);
        assert_eq!(location_from(Some(OsStr::new(""))), expected);
        assert_eq!(default_shared_mesh_dir(), expected);
        // The root is the workspace whichever crate calls: its manifest is the
        // workspace's and lists the engine.
        let manifest =
            std::fs::read_to_string(workspace_root().join("Cargo.toml")).expect("manifest");
        assert!(manifest.contains("[workspace]"), "{manifest}");
        assert!(workspace_root().join("engine/Cargo.toml").is_file());
    }

    #[test]
    fn a_missing_folder_is_none() {
        let dir = tempfile::tempdir().expect("temp dir");
        let missing = dir.path().join("no-such-folder");
        assert_eq!(location_from(Some(missing.as_os_str())), missing);
        assert_eq!(existing_dir(missing), None);
        let file = dir.path().join("a-file");
        std::fs::write(&file, "").expect("write");
        assert_eq!(existing_dir(file), None);
    }
}
