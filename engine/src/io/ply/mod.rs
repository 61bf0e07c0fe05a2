//! PLY reader (our own, no crate): ASCII, binary little- and big-endian.
//!
//! Input: the file's bytes. Output: the columns asked for from the `vertex` element,
//! and polygons from `face` (`vertex_indices` or `vertex_index` list) plus triangles
//! from `tristrips`/`tristrip` (`-1` restarts a strip; odd triangles are flipped to
//! keep the winding). Every other element and property, lists included, is skipped.
//! Cost: O(file size); binary bodies are decoded in place from one buffer.
//!
//! Nothing here panics on bad input: every read is bounds-checked, allocations are
//! bounded by the file size, and lengths and indices are read as i64 so that negative
//! values stay negative instead of wrapping into valid indices.

mod body;
mod header;

use std::path::Path;

use body::{AsciiReader, BinaryReader, BodyError, ValueReader};
use header::{Element, Encoding, Header, PropertyType};

use crate::mesh::MeshError;

/// Names accepted for the vertex-index list of faces and strips.
const INDEX_LISTS: [&str; 2] = ["vertex_indices", "vertex_index"];
/// Names accepted for the triangle-strip element.
const STRIP_ELEMENTS: [&str; 2] = ["tristrips", "tristrip"];

/// What to read from a PLY file.
pub(crate) struct Request<'a> {
    /// Vertex properties to read, in output column order. Missing ones read as 0.
    pub(crate) columns: &'a [&'a str],
    /// How many of the first `columns` must be present.
    pub(crate) required: usize,
    /// Whether faces (or strips) are needed.
    pub(crate) faces: bool,
}

/// What was read from a PLY file. Indices are as in the file (unchecked).
#[derive(Debug, Default)]
pub(crate) struct PlyData {
    /// Number of vertex records.
    pub(crate) vertex_count: usize,
    /// Row-major `vertex_count x columns.len()` values.
    pub(crate) columns: Vec<f64>,
    /// Corners of all faces, concatenated.
    pub(crate) corners: Vec<i64>,
    /// End (exclusive) of each face in `corners`.
    pub(crate) face_ends: Vec<usize>,
    /// Strip entries, concatenated (`-1` restarts).
    pub(crate) strips: Vec<i64>,
    /// End (exclusive) of each strip record in `strips`.
    pub(crate) strip_ends: Vec<usize>,
}

/// How an element's records are used.
enum Role {
    /// The vertex element: per property, its output column.
    Vertex(Vec<Option<usize>>),
    /// Faces: the index of the vertex-index list property.
    Faces(usize),
    /// Triangle strips: the index of the vertex-index list property.
    Strips(usize),
    /// Read past.
    Skip,
}

/// Reads what `request` asks for from PLY `bytes`; `path` only names the file in errors.
pub(crate) fn read(bytes: &[u8], path: &Path, request: &Request<'_>) -> Result<PlyData, MeshError> {
    let syntax = |line: usize, what: String| MeshError::Syntax {
        path: path.to_path_buf(),
        line,
        what,
    };
    let header = header::parse_header(bytes).map_err(|(line, what)| syntax(line, what))?;
    let roles = plan(&header, request).map_err(|(line, what)| syntax(line, what))?;
    let body = bytes.get(header.body_start..).unwrap_or_default();
    match header.encoding {
        Encoding::Ascii => read_body(
            &mut AsciiReader::new(body, header.end_line + 1),
            &header,
            &roles,
            request,
            body.len(),
            path,
        ),
        Encoding::BinaryLittleEndian => read_body(
            &mut BinaryReader::new(body, false),
            &header,
            &roles,
            request,
            body.len(),
            path,
        ),
        Encoding::BinaryBigEndian => read_body(
            &mut BinaryReader::new(body, true),
            &header,
            &roles,
            request,
            body.len(),
            path,
        ),
    }
}

/// Decides the role of each element and checks that the requested data exists.
fn plan(header: &Header, request: &Request<'_>) -> Result<Vec<Role>, (usize, String)> {
    let Some(vertex) = header.element("vertex") else {
        return Err((header.end_line, "no `vertex` element".to_owned()));
    };
    let mut roles: Vec<Role> = header.elements.iter().map(|_| Role::Skip).collect();

    let el = &header.elements[vertex];
    let mut slots = vec![None; el.properties.len()];
    for (c, name) in request.columns.iter().enumerate() {
        match el.property(name) {
            Some(p) => {
                if !matches!(el.properties[p].ty, PropertyType::Scalar(_)) {
                    return Err((
                        el.line,
                        format!("vertex property `{name}` is a list; expected a number"),
                    ));
                }
                slots[p] = Some(c);
            }
            None if c < request.required => {
                return Err((
                    el.line,
                    format!("element `vertex` has no property `{name}`"),
                ));
            }
            None => {}
        }
    }
    roles[vertex] = Role::Vertex(slots);

    if request.faces {
        let face = header.element("face");
        let strips = STRIP_ELEMENTS.iter().find_map(|name| header.element(name));
        if face.is_none() && strips.is_none() {
            return Err((
                header.end_line,
                "no `face` element (a point cloud?)".to_owned(),
            ));
        }
        if let Some(face) = face {
            roles[face] = Role::Faces(index_list(&header.elements[face])?);
        }
        if let Some(strips) = strips {
            roles[strips] = Role::Strips(index_list(&header.elements[strips])?);
        }
    }
    Ok(roles)
}

/// The vertex-index list property of a face or strip element.
fn index_list(el: &Element) -> Result<usize, (usize, String)> {
    let Some(p) = INDEX_LISTS.iter().find_map(|name| el.property(name)) else {
        return Err((
            el.line,
            format!("element `{}` has no `vertex_indices` list", el.name),
        ));
    };
    match el.properties[p].ty {
        PropertyType::List { item, .. } if item.is_integer() => Ok(p),
        _ => Err((
            el.line,
            format!(
                "`{}` of element `{}` must be a list of integers",
                el.properties[p].name, el.name
            ),
        )),
    }
}

fn read_body<R: ValueReader>(
    r: &mut R,
    header: &Header,
    roles: &[Role],
    request: &Request<'_>,
    body_len: usize,
    path: &Path,
) -> Result<PlyData, MeshError> {
    let mut out = PlyData::default();
    let ncols = request.columns.len();
    for (el, role) in header.elements.iter().zip(roles) {
        if el.properties.is_empty() {
            continue; // records without properties take no bytes (and no lines)
        }
        // The file cannot hold more records than this; never trust the declared count.
        let plausible = el
            .count
            .min(body_len / el.min_record_bytes(header.encoding).max(1) + 1);
        let fail = |e: BodyError, index: usize| match e {
            BodyError::End => MeshError::Truncated {
                path: path.to_path_buf(),
                element: el.name.clone(),
                index,
                count: el.count,
            },
            BodyError::Bad(line, what) => MeshError::Syntax {
                path: path.to_path_buf(),
                line,
                what: format!("{} {index}: {what}", el.name),
            },
        };
        match role {
            Role::Vertex(slots) => {
                out.vertex_count = el.count;
                out.columns.reserve(plausible * ncols);
                for i in 0..el.count {
                    read_vertex(r, el, slots, ncols, &mut out.columns).map_err(|e| fail(e, i))?;
                }
            }
            Role::Faces(list) => {
                out.face_ends.reserve(plausible);
                out.corners.reserve(3 * plausible);
                for i in 0..el.count {
                    read_list_record(r, el, *list, &mut out.corners).map_err(|e| fail(e, i))?;
                    out.face_ends.push(out.corners.len());
                }
            }
            Role::Strips(list) => {
                for i in 0..el.count {
                    read_list_record(r, el, *list, &mut out.strips).map_err(|e| fail(e, i))?;
                    out.strip_ends.push(out.strips.len());
                }
            }
            Role::Skip => {
                for i in 0..el.count {
                    r.skip_record(el).map_err(|e| fail(e, i))?;
                }
            }
        }
    }
    Ok(out)
}

fn read_vertex<R: ValueReader>(
    r: &mut R,
    el: &Element,
    slots: &[Option<usize>],
    ncols: usize,
    columns: &mut Vec<f64>,
) -> Result<(), BodyError> {
    r.begin_record()?;
    let base = columns.len();
    columns.resize(base + ncols, 0.0);
    for (p, slot) in el.properties.iter().zip(slots) {
        match (p.ty, slot) {
            (PropertyType::Scalar(s), Some(c)) => columns[base + c] = r.float(s)?,
            (PropertyType::Scalar(s), None) => r.skip(s, 1)?,
            (PropertyType::List { count, item }, _) => {
                let n = r.list_len(count)?;
                r.skip(item, n)?;
            }
        }
    }
    r.end_record()
}

/// Reads one record, appending the items of list property `list` to `items`.
fn read_list_record<R: ValueReader>(
    r: &mut R,
    el: &Element,
    list: usize,
    items: &mut Vec<i64>,
) -> Result<(), BodyError> {
    r.begin_record()?;
    for (p, prop) in el.properties.iter().enumerate() {
        match prop.ty {
            PropertyType::Scalar(s) => r.skip(s, 1)?,
            PropertyType::List { count, item } => {
                let n = r.list_len(count)?;
                if p == list {
                    for _ in 0..n {
                        items.push(r.int(item)?);
                    }
                } else {
                    r.skip(item, n)?;
                }
            }
        }
    }
    r.end_record()
}

#[cfg(test)]
pub(crate) use header::parse_header;
