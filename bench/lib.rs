//! Shared helpers for strata benchmarks.

pub mod lod_camera;
pub mod soak;

use std::path::{Path, PathBuf};

use strata_systems::config::SceneConfig;

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
    count_arg(1, default)
}

/// The second command-line argument as a count of Loop subdivision levels, or
/// `default`.
pub fn levels_arg(default: usize) -> Result<usize, std::num::ParseIntError> {
    count_arg(2, default)
}

/// The third command-line argument as a count of segmentation seeds, or `default`.
pub fn seeds_arg(default: usize) -> Result<usize, std::num::ParseIntError> {
    count_arg(3, default)
}

/// Command-line argument `position` as a count, or `default` when absent.
fn count_arg(position: usize, default: usize) -> Result<usize, std::num::ParseIntError> {
    std::env::args()
        .nth(position)
        .map(|a| a.parse())
        .transpose()
        .map(|r| r.unwrap_or(default))
}

/// The bundled scenes `(name, file in configs/)`, loaded, with their names.
pub fn bundled_scenes<'a>(
    scenes: &[(&'a str, &str)],
) -> Result<Vec<(&'a str, SceneConfig)>, Box<dyn std::error::Error>> {
    let configs = Path::new(env!("CARGO_MANIFEST_DIR")).join("../configs");
    scenes
        .iter()
        .map(|(name, file)| Ok((*name, SceneConfig::load(&configs.join(file))?)))
        .collect()
}

/// The height `y` above which about `share` of `mesh`'s faces lie (by their highest
/// vertex): the edge of a cap for edits that touch a known part of a mesh (the reload
/// bench and the hot-reload tests edit the bunny's field above it).
pub fn cap_height(mesh: &strata_engine::mesh::TriMesh, share: f64) -> f64 {
    let mut top: Vec<f64> = (0..mesh.face_count() as u32)
        .map(|f| {
            mesh.face_positions(f)
                .iter()
                .map(|p| p.y)
                .fold(f64::MIN, f64::max)
        })
        .collect();
    top.sort_by(f64::total_cmp);
    let i = ((1.0 - share.clamp(0.0, 1.0)) * top.len() as f64) as usize;
    top.get(i.min(top.len().saturating_sub(1)))
        .copied()
        .unwrap_or(f64::INFINITY)
}

/// A 3:1 field along `(1, 0.3, 0.2)` (projected into the tangent planes), turned to
/// `turned` on the vertices above height `y_min`: an edit of a cap of the mesh, for the
/// reload bench and the engine's tests (every tensor below the cap is the same bits
/// whatever the cap).
pub fn cap_field(
    mesh: &strata_engine::mesh::TriMesh,
    y_min: f64,
    turned: glam::DVec3,
) -> Result<strata_engine::field::TensorField, strata_engine::field::FieldError> {
    let dirs: Vec<glam::DVec3> = mesh
        .positions()
        .iter()
        .map(|p| {
            if p.y > y_min {
                turned
            } else {
                glam::DVec3::new(1.0, 0.3, 0.2)
            }
        })
        .collect();
    let eigenvalues = vec![[3.0, 1.0 / 3.0]; mesh.vertex_count()];
    strata_engine::field::TensorField::from_frames(mesh, &dirs, &eigenvalues)
}

/// The median of `values` (the upper of the two middle ones for an even count; NaN
/// for none), the statistic every benchmark table here quotes.
pub fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    values.get(values.len() / 2).copied().unwrap_or(f64::NAN)
}
