//! Reading samples back from a PLY point cloud (the format [`write_samples_ply`] writes).
//!
//! [`write_samples_ply`]: super::write_samples_ply

use std::path::Path;

use super::ply;
use crate::mesh::MeshError;
use crate::sample::Sample;

/// The columns of a sample file, in order: the PLY vertex properties of
/// [`write_samples_ply`](super::write_samples_ply) and the CSV header of
/// [`write_samples_csv`](super::write_samples_csv).
///
/// `x y z` position, `nx ny nz` unit normal, `major_x major_y major_z` major axis,
/// `spacing_major spacing_minor` spacing (world units), `face` (uint), `bary1 bary2`
/// barycentric coordinates of corners 1 and 2 of the face (corner 0 has
/// `1 - bary1 - bary2`), `segment` (uint), `index` (uint, rank in the sequence).
pub const SAMPLE_COLUMNS: [&str; 16] = [
    "x",
    "y",
    "z",
    "nx",
    "ny",
    "nz",
    "major_x",
    "major_y",
    "major_z",
    "spacing_major",
    "spacing_minor",
    "face",
    "bary1",
    "bary2",
    "segment",
    "index",
];

/// Reads samples from a PLY file (see [`parse_samples_ply`]).
pub fn read_samples_ply(path: &Path) -> Result<Vec<Sample>, MeshError> {
    parse_samples_ply(&super::read_file(path)?, path)
}

/// Parses samples from PLY bytes with a `vertex` element; `path` only names the source
/// in errors.
///
/// Reads the [`SAMPLE_COLUMNS`] present (`x`, `y`, `z` are required, the others read as
/// 0 when absent), in any PLY encoding and type; other properties and elements are
/// skipped. Values are converted to the [`Sample`] field types with `as` (integer
/// fields saturate). Errors as for [`parse_ply`](super::parse_ply)'s header and body.
pub fn parse_samples_ply(bytes: &[u8], path: &Path) -> Result<Vec<Sample>, MeshError> {
    let request = ply::Request {
        columns: &SAMPLE_COLUMNS,
        required: 3,
        faces: false,
    };
    let data = ply::read(bytes, path, &request)?;
    Ok(data
        .columns
        .chunks_exact(SAMPLE_COLUMNS.len())
        .map(|c| {
            let f = |i: usize| c[i] as f32;
            let u = |i: usize| c[i] as u32;
            Sample {
                position: [f(0), f(1), f(2)],
                normal: [f(3), f(4), f(5)],
                major_axis: [f(6), f(7), f(8)],
                spacing: [f(9), f(10)],
                face: u(11),
                bary: [f(12), f(13)],
                segment: u(14),
                index: u(15),
            }
        })
        .collect())
}
