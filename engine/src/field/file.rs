//! Per-vertex tensors from a text file.
//!
//! Format (UTF-8 text, one record per line):
//!
//! ```text
//! # Anything after '#' is a comment; blank lines are ignored.
//! strata-field 1
//! # One line per vertex of the mesh file, in the file's vertex order, either
//! # eigenvalues and major direction:   l1 l2 mx my mz
//! # or the symmetric tensor's entries:  t xx xy xz yy yz zz
//! 4.0 0.25 1 0 0
//! t 1 0 0 1 0 1
//! ```
//!
//! - The first non-comment line is the header `strata-field 1` (format version 1).
//! - `l1 l2 mx my mz`: the tensor `l1 m m^T + l2 m' m'^T` with `m` the direction
//!   `(mx, my, mz)` projected into the vertex's tangent plane and normalised, and `m'`
//!   the tangent perpendicular to it. `l1, l2 > 0`; `m` is the eigenvector of `l1`
//!   (the major one when `l1 >= l2`). Where `m` is parallel to the normal a
//!   deterministic tangent is used (as for [`FieldSpec::Constant`](super::FieldSpec)).
//! - `t xx xy xz yy yz zz`: the world-space symmetric 3x3 tensor with those upper-
//!   triangle entries; it is projected into the tangent plane (`P T P`) and must be
//!   positive definite there.
//! - Numbers are anything Rust's `f64` parser accepts (`1`, `-2.5e-3`, ...); `NaN` and
//!   infinities parse but are rejected with an error naming the vertex.
//!
//! Vertex order is the order of the vertices in the mesh file (or of the positions given
//! to [`TriMesh::new`]), mapped through [`TriMesh::input_vertex_map`]: vertices merged as
//! duplicates take the first line's value, dropped vertices (used by no face) are
//! parsed and checked but ignored. The file must have exactly one line per input vertex.
//!
//! Errors: [`FieldError::Io`] (cannot read), [`FieldError::Syntax`] (1-based line and
//! what was expected), [`FieldError::BadValue`] (line and file vertex of a NaN, a
//! non-positive eigenvalue, a zero direction or a tensor not positive definite in the
//! tangent plane), [`FieldError::CountMismatch`] (wrong number of vertex lines).
//! Cost: O(file length).

use std::fmt::Write as _;
use std::path::Path;

use glam::{DMat3, DVec3};

use super::{FieldError, TensorField, eigen_in_plane, outer, project_direction};
use crate::mesh::{NONE, TriMesh};

/// The header line's first word.
const MAGIC: &str = "strata-field";
/// The format version this reader understands.
const VERSION: &str = "1";

/// One vertex line, parsed but not yet checked.
enum Entry {
    /// `l1 l2 mx my mz`.
    Frame { l1: f64, l2: f64, direction: DVec3 },
    /// `t xx xy xz yy yz zz`.
    Tensor(DMat3),
}

/// Reads per-vertex tensors for `mesh` from the file at `path` (format in the module
/// docs: header `strata-field 1`, then `l1 l2 mx my mz` or `t xx xy xz yy yz zz` per
/// vertex of the mesh file). `path` is opened as given.
///
/// ```
/// use strata_engine::{field::{format_field_file, read_field_file, FieldSpec}, mesh::shapes};
/// let mesh = shapes::plane(1.0, 2)?;
/// let field = FieldSpec::Constant { direction: [1.0, 0.0, 0.0], anisotropy: 2.0, density: 1.0 }
///     .build(&mesh)?;
/// let path = std::env::temp_dir().join("strata_doc_example.field");
/// std::fs::write(&path, format_field_file(&field))?;
/// assert_eq!(read_field_file(&path, &mesh)?, field);
/// # std::fs::remove_file(&path)?;
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn read_field_file(path: &Path, mesh: &TriMesh) -> Result<TensorField, FieldError> {
    let text = std::fs::read_to_string(path).map_err(|source| FieldError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_field_file(&text, path, mesh)
}

/// Parses the text of a field file (see [`read_field_file`]); `path` only names the
/// file in errors.
pub fn parse_field_file(
    text: &str,
    path: &Path,
    mesh: &TriMesh,
) -> Result<TensorField, FieldError> {
    let map = mesh.input_vertex_map();
    let normals = mesh.vertex_normals();
    let mut tensors: Vec<Option<DMat3>> = vec![None; mesh.vertex_count()];
    let mut header_seen = false;
    // Rank of the next vertex line: the input vertex it describes.
    let mut vertex = 0usize;
    let mut last_line = 0usize;
    for (index, raw) in text.trim_start_matches('\u{feff}').lines().enumerate() {
        let line = index + 1;
        last_line = line;
        let content = raw.split_once('#').map_or(raw, |(before, _)| before);
        let (words, count) = split_words(content);
        if count == 0 {
            continue;
        }
        let syntax = |what: String| FieldError::Syntax {
            path: path.to_path_buf(),
            line,
            what,
        };
        if !header_seen {
            check_header(&words, count, content).map_err(syntax)?;
            header_seen = true;
            continue;
        }
        let entry = parse_entry(&words[..count.min(words.len())], count).map_err(syntax)?;
        let bad = |what: String| FieldError::BadValue {
            path: path.to_path_buf(),
            line,
            vertex,
            what,
        };
        check_entry(&entry).map_err(bad)?;
        let target = map.get(vertex).copied().unwrap_or(NONE);
        if target != NONE && tensors[target as usize].is_none() {
            let tensor = entry_tensor(entry, normals[target as usize], target).map_err(bad)?;
            tensors[target as usize] = Some(tensor);
        }
        vertex += 1;
    }
    if !header_seen {
        return Err(FieldError::Syntax {
            path: path.to_path_buf(),
            line: last_line.max(1),
            what: format!("missing the header `{MAGIC} {VERSION}` (no data in the file)"),
        });
    }
    if vertex != map.len() {
        return Err(FieldError::CountMismatch {
            expected: map.len(),
            found: vertex,
        });
    }
    let filled: Option<Vec<DMat3>> = tensors.into_iter().collect();
    match filled {
        Some(t) => TensorField::new(mesh, t),
        // Every mesh vertex comes from some input vertex, so this means the mesh's
        // input map is inconsistent; report it rather than panic.
        None => Err(FieldError::CountMismatch {
            expected: mesh.vertex_count(),
            found: map.iter().filter(|&&v| v != NONE).count(),
        }),
    }
}

/// The first eight whitespace-separated words of `content` and the count of all its
/// words.
fn split_words(content: &str) -> ([&str; 8], usize) {
    let mut words = [""; 8];
    let mut count = 0;
    for word in content.split_whitespace() {
        if count < words.len() {
            words[count] = word;
        }
        count += 1;
    }
    (words, count)
}

/// Checks the header line (`count` words, the first of them in `words`).
fn check_header(words: &[&str], count: usize, content: &str) -> Result<(), String> {
    if words[0] != MAGIC {
        return Err(format!(
            "expected the header `{MAGIC} {VERSION}`, found `{}`",
            content.trim()
        ));
    }
    if count != 2 || words[1] != VERSION {
        return Err(format!(
            "unsupported header `{}`: this reader understands `{MAGIC} {VERSION}`",
            content.trim()
        ));
    }
    Ok(())
}

/// The tensor of a checked entry at mesh vertex `target` with unit normal `n`, in its
/// tangent plane. Errors: eigenvalues outside [`EIGENVALUE_RANGE`](super::EIGENVALUE_RANGE),
/// a tensor not positive definite in the plane.
fn entry_tensor(entry: Entry, n: DVec3, target: u32) -> Result<DMat3, String> {
    let range = |l1: f64, l2: f64| {
        if super::out_of_range(l1, l2) {
            return Err(format!(
                "eigenvalues {l1:.3e} and {l2:.3e} are outside the supported range \
                 [1e-100, 1e100]; densities are relative, so scale every density \
                 of the file by one factor into it"
            ));
        }
        Ok(())
    };
    Ok(match entry {
        Entry::Frame { l1, l2, direction } => {
            range(l1.max(l2), l1.min(l2))?;
            let m1 = project_direction(direction, n);
            let m2 = n.cross(m1);
            outer(m1, m1) * l1 + outer(m2, m2) * l2
        }
        Entry::Tensor(t) => {
            let p = DMat3::IDENTITY - outer(n, n);
            let restricted = p * t * p;
            let e = eigen_in_plane(&restricted, n);
            if !(e.l2 > 0.0) {
                return Err(format!(
                    "tensor is not positive definite in the tangent plane of mesh \
                     vertex {target} (eigenvalues {}, {})",
                    e.l1, e.l2
                ));
            }
            range(e.l1, e.l2)?;
            restricted
        }
    })
}

/// Parses the words of one vertex line (`count` may exceed `words.len()` when the line
/// is too long).
fn parse_entry(words: &[&str], count: usize) -> Result<Entry, String> {
    let numbers = |words: &[&str]| -> Result<Vec<f64>, String> {
        words
            .iter()
            .map(|w| {
                w.parse::<f64>()
                    .map_err(|_| format!("`{w}` is not a number"))
            })
            .collect()
    };
    if words[0] == "t" {
        if count != 7 {
            return Err(format!(
                "expected `t xx xy xz yy yz zz` (6 numbers after `t`), found {} value(s)",
                count - 1
            ));
        }
        let v = numbers(&words[1..])?;
        let (xx, xy, xz, yy, yz, zz) = (v[0], v[1], v[2], v[3], v[4], v[5]);
        return Ok(Entry::Tensor(DMat3::from_cols(
            DVec3::new(xx, xy, xz),
            DVec3::new(xy, yy, yz),
            DVec3::new(xz, yz, zz),
        )));
    }
    if count != 5 {
        return Err(format!(
            "expected `l1 l2 mx my mz` (5 numbers) or `t xx xy xz yy yz zz`, found {count} value(s)"
        ));
    }
    let v = numbers(words)?;
    Ok(Entry::Frame {
        l1: v[0],
        l2: v[1],
        direction: DVec3::new(v[2], v[3], v[4]),
    })
}

/// Value checks that need no mesh data.
fn check_entry(entry: &Entry) -> Result<(), String> {
    match *entry {
        Entry::Frame { l1, l2, direction } => {
            if !l1.is_finite() || !l2.is_finite() || !direction.is_finite() {
                return Err(format!(
                    "non-finite value in `{l1} {l2} {} {} {}`",
                    direction.x, direction.y, direction.z
                ));
            }
            if !(l1 > 0.0) {
                return Err(format!("eigenvalue l1 = {l1} must be > 0"));
            }
            if !(l2 > 0.0) {
                return Err(format!("eigenvalue l2 = {l2} must be > 0"));
            }
            if !(direction.length_squared() > 0.0) {
                return Err("major direction (mx, my, mz) is zero".to_owned());
            }
            Ok(())
        }
        Entry::Tensor(t) => {
            if t.is_finite() {
                Ok(())
            } else {
                Err("non-finite tensor entry".to_owned())
            }
        }
    }
}

/// Writes `field` in the field-file format, one `t` line per mesh vertex in the mesh's
/// vertex order, with shortest round-trip number formatting. Reading it back gives the
/// same field on a mesh whose [`TriMesh::input_vertex_map`] is the identity (no
/// repairs), for example the same mesh built again from its own arrays.
pub fn format_field_file(field: &TensorField) -> String {
    let mut out = String::with_capacity(32 + 64 * field.tensors().len());
    out.push_str("strata-field 1\n# t xx xy xz yy yz zz, one line per vertex\n");
    for t in field.tensors() {
        let c = t.to_cols_array_2d();
        // Symmetric: write the upper triangle, symmetrised against round-off.
        let e = |i: usize, j: usize| 0.5 * (c[j][i] + c[i][j]);
        // Writing into a String cannot fail.
        let _ = writeln!(
            out,
            "t {} {} {} {} {} {}",
            e(0, 0),
            e(0, 1),
            e(0, 2),
            e(1, 1),
            e(1, 2),
            e(2, 2)
        );
    }
    out
}
