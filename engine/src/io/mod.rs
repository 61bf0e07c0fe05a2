//! File formats: OBJ and PLY mesh readers, PLY and CSV writers for meshes and samples,
//! and the atomic file writing that every writer (here and in the applications) uses.
//!
//! Input: a path (or bytes plus a name for messages). Output: a validated
//! [`TriMesh`], or [`Sample`]s; writers go the other way. Cost: O(file size); a
//! whole file is read into memory once and parsed from there.
//!
//! - [`load`] picks the reader by extension (`.obj`, `.ply`, any case).
//! - OBJ ([`parse_obj`]): our own one-pass reader, by position index, so UV and
//!   normal seams never split a vertex; all objects and groups become one mesh; polygons are
//!   fan-triangulated (reported as [`MeshWarning::TriangulatedPolygons`]); negative
//!   (relative) indices work; errors name the line. Polylines (`l`) and points are
//!   ignored.
//! - PLY ([`parse_ply`]): our own reader for ASCII and binary little/big-endian with
//!   every scalar type; faces from `face` (`vertex_indices` or `vertex_index`) and
//!   triangle strips from `tristrips` (`-1` restarts a strip, winding alternates); all
//!   other elements and properties are skipped.
//! - Writers ([`write_mesh_ply`], [`write_samples_ply`], [`write_samples_csv`]) go
//!   through [`write_atomically`] (a temporary file beside the target, synced, then
//!   renamed over it), so a reader never sees half a file; the `_to` variants write to
//!   any [`Write`](std::io::Write). Applications write their own files (reports,
//!   images) with [`write_atomically`] too. [`write_samples_in_blocks`] writes any
//!   number of samples in the memory of one block.
//! - The shared mesh corpus ([`shared_mesh_dir`]): `$STRATA_MESH_DIR`, else
//!   `<workspace>/../shared/meshes`, for tests and benchmarks.
//!
//! Errors say where: the file, and the line (text), or the element and record
//! (binary). Content that makes no valid mesh (an out-of-range or negative index, a
//! non-finite coordinate) comes back as [`MeshError::InFile`] wrapping the
//! construction error, with indices in file order. Nothing here panics on bad input.
//!
//! [`MeshWarning::TriangulatedPolygons`]: crate::mesh::MeshWarning::TriangulatedPolygons

mod atomic;
mod obj;
mod obj_chunks;
mod ply;
mod samples;
mod shared;
mod write;

use std::path::Path;

use glam::DVec3;

use crate::mesh::{MeshError, TriMesh};
#[cfg(doc)]
use crate::sample::Sample;

pub use atomic::write_atomically;
pub use samples::{SAMPLE_COLUMNS, parse_samples_ply, read_samples_ply};
#[cfg(test)]
pub(crate) use shared::shared_mesh;
pub use shared::{MESH_DIR_VAR, default_shared_mesh_dir, shared_mesh_dir, shared_mesh_location};
pub use write::{
    SampleFormat, write_mesh_ply, write_mesh_ply_to, write_samples_csv, write_samples_csv_to,
    write_samples_in_blocks, write_samples_ply, write_samples_ply_to,
};

/// Loads a triangle mesh from an `.obj` or `.ply` file, chosen by the extension (any
/// case).
///
/// Errors: [`MeshError::UnknownFormat`] for another extension, [`MeshError::Io`] if
/// the file cannot be read, and the readers' errors (see [`parse_obj`], [`parse_ply`]).
///
/// ```
/// use strata_engine::io;
/// let dir = tempfile::tempdir()?;
/// let path = dir.path().join("quad.obj");
/// std::fs::write(&path, "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n")?;
/// let mesh = io::load(&path)?;
/// assert_eq!((mesh.vertex_count(), mesh.face_count()), (4, 2));
/// assert_eq!(mesh.boundary_loops().len(), 1);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn load(path: &Path) -> Result<TriMesh, MeshError> {
    // A folder or a name without an extension is no mesh file: say so before trying to
    // read it (reading a folder fails with a bare "Is a directory").
    let not_a_mesh = |what: &str| MeshError::Io {
        path: path.to_path_buf(),
        source: std::io::Error::other(format!("{what}; give a mesh file ending in .obj or .ply")),
    };
    if path.is_dir() {
        return Err(not_a_mesh("is a folder, not a mesh file"));
    }
    if path.extension().is_none() {
        return Err(not_a_mesh("has no extension, so its format is unknown"));
    }
    let extension = path
        .extension()
        .map(|e| e.to_string_lossy().into_owned())
        .unwrap_or_default();
    match extension.to_ascii_lowercase().as_str() {
        "obj" => load_obj(path),
        "ply" => load_ply(path),
        _ => Err(MeshError::UnknownFormat {
            path: path.to_path_buf(),
            extension,
        }),
    }
}

/// Loads a Wavefront OBJ file (see [`parse_obj`]).
pub fn load_obj(path: &Path) -> Result<TriMesh, MeshError> {
    parse_obj(&read_file(path)?, path)
}

/// Loads a PLY file (see [`parse_ply`]).
pub fn load_ply(path: &Path) -> Result<TriMesh, MeshError> {
    parse_ply(&read_file(path)?, path)
}

/// Parses OBJ text; `path` only names the source in errors.
///
/// Reads `v` positions (with optional weight `w` or colour) and `f` polygons by
/// position index; texture coordinates and normals are checked for valid indices but
/// not kept. Objects, groups and material switches are merged into one mesh. Vertices
/// keep their file order, so [`TriMesh::input_vertex_map`] is indexed by `v` record
/// (from 0); unused and duplicated vertices are repaired as by [`TriMesh::new`].
///
/// Errors: [`MeshError::Syntax`] with the line (a malformed number or corner, index 0,
/// an index past the vertices), [`MeshError::InFile`] for a non-finite coordinate
/// (vertex numbered in file order, from 0) or an empty mesh.
pub fn parse_obj(bytes: &[u8], path: &Path) -> Result<TriMesh, MeshError> {
    // Large files on every thread; the sequential pass for small ones and to find and
    // report a problem.
    let scan = obj_chunks::scan(bytes).unwrap_or_else(|| obj::scan(bytes));
    if let Some((line, what)) = scan.problem {
        return Err(MeshError::Syntax {
            path: path.to_path_buf(),
            line,
            what,
        });
    }
    build_mesh(
        path,
        scan.positions,
        scan.corners,
        &scan.face_ends,
        scan.skipped,
    )
}

/// Parses a PLY file's bytes; `path` only names the source in errors.
///
/// Needs a `vertex` element with scalar `x`, `y`, `z` (any type) and a `face` element
/// with a `vertex_indices` (or `vertex_index`) list of any integer types, or a
/// `tristrips` element. Other elements and properties are skipped; data after the last
/// element is ignored. Faces come first, then strip triangles (strip triangles that
/// repeat a vertex, used to join strips, are left out).
///
/// Errors: [`MeshError::Syntax`] with the header line (bad magic or format line,
/// unknown type, missing `x`/`y`/`z` or `face`) or, in the body, with the line (ASCII)
/// or line 0 (binary) and the element and record; [`MeshError::Truncated`] when the body
/// ends early; [`MeshError::InFile`] wrapping [`MeshError::IndexOutOfRange`] (negative
/// or too large index; faces numbered from 0, then strip triangles),
/// [`MeshError::NonFiniteVertex`], [`MeshError::TooFewCorners`] or [`MeshError::Empty`].
pub fn parse_ply(bytes: &[u8], path: &Path) -> Result<TriMesh, MeshError> {
    let request = ply::Request {
        columns: &["x", "y", "z"],
        required: 3,
        faces: true,
    };
    let data = ply::read(bytes, path, &request)?;
    let positions: Vec<DVec3> = data
        .columns
        .chunks_exact(3)
        .map(DVec3::from_slice)
        .collect();
    let vertex_count = positions.len();
    let in_file = |source: MeshError| MeshError::InFile {
        path: path.to_path_buf(),
        source: Box::new(source),
    };
    let check = |face: usize, index: i64| {
        u32::try_from(index)
            .ok()
            .filter(|&i| (i as usize) < vertex_count)
            .ok_or_else(|| {
                in_file(MeshError::IndexOutOfRange {
                    face,
                    index,
                    vertex_count,
                })
            })
    };
    let mut corners = Vec::with_capacity(data.corners.len());
    for (face, range) in face_ranges(&data.face_ends).enumerate() {
        for &index in data.corners.get(range).unwrap_or_default() {
            corners.push(check(face, index)?);
        }
    }
    let mut face_ends = data.face_ends;
    for range in face_ranges(&data.strip_ends) {
        let strip = data.strips.get(range).unwrap_or_default();
        // `-1` restarts; triangle k of a run is (k, k+1, k+2), flipped for odd k.
        for run in strip.split(|&i| i == -1) {
            for (k, w) in run.windows(3).enumerate() {
                let face = face_ends.len();
                let [a, b, c] = [check(face, w[0])?, check(face, w[1])?, check(face, w[2])?];
                if a == b || b == c || c == a {
                    continue; // a join between strips, not a face
                }
                corners.extend(if k % 2 == 0 { [a, b, c] } else { [b, a, c] });
                face_ends.push(corners.len());
            }
        }
    }
    build_mesh(path, positions, corners, &face_ends, Skipped::default())
}

/// Consecutive ranges `ends[i-1]..ends[i]` (from 0).
fn face_ranges(ends: &[usize]) -> impl Iterator<Item = std::ops::Range<usize>> + '_ {
    ends.iter().scan(0, |start, &end| {
        let range = *start..end;
        *start = end;
        Some(range)
    })
}

/// Builds the mesh from checked polygons, wrapping construction errors with the file.
/// Faces of one or two corners an OBJ reader skipped: how many, and the lines of the
/// first few.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Skipped {
    pub(crate) count: usize,
    pub(crate) lines: Vec<usize>,
}

impl Skipped {
    /// Notes a skipped face on `line` (from 1).
    pub(crate) fn push(&mut self, line: usize) {
        self.count += 1;
        if self.lines.len() < 5 {
            self.lines.push(line);
        }
    }
}

fn build_mesh(
    path: &Path,
    positions: Vec<DVec3>,
    corners: Vec<u32>,
    face_ends: &[usize],
    skipped: Skipped,
) -> Result<TriMesh, MeshError> {
    let all_triangles = face_ranges(face_ends).all(|r| r.len() == 3);
    let built = if all_triangles {
        let triangles = corners
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect();
        TriMesh::new(positions, triangles)
    } else {
        let polygons: Vec<Vec<u32>> = face_ranges(face_ends)
            .map(|r| corners.get(r).unwrap_or_default().to_vec())
            .collect();
        TriMesh::from_polygons(positions, &polygons)
    };
    let mut mesh = built.map_err(|source| match (&source, skipped.lines.first()) {
        // Nothing usable, and faces were skipped: the line of the first says why.
        (MeshError::Empty { faces: 0, .. }, Some(&line)) => MeshError::Syntax {
            path: path.to_path_buf(),
            line,
            what: format!(
                "no usable face: the face on this line has fewer than 3 corners (a point or a line, which a surface cannot use); {} such faces were skipped and no face of 3 or more corners remains",
                skipped.count
            ),
        },
        _ => MeshError::InFile {
            path: path.to_path_buf(),
            source: Box::new(source),
        },
    })?;
    if skipped.count > 0 {
        mesh.warnings.insert(
            0,
            crate::mesh::MeshWarning::SkippedPointsAndLines {
                count: skipped.count,
                first_lines: skipped.lines,
            },
        );
    }
    Ok(mesh)
}

fn read_file(path: &Path) -> Result<Vec<u8>, MeshError> {
    std::fs::read(path).map_err(|source| MeshError::Io {
        path: path.to_path_buf(),
        source,
    })
}

#[cfg(test)]
mod tests;
