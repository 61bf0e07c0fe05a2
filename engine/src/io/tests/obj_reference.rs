//! The OBJ reader before issue 18, kept as the reference the one-pass reader
//! (`io/obj.rs`) is tested against: `tobj` (a dev-dependency now) with a prescan for
//! line-accurate errors. Test code only.
//!
//! Input: the file's bytes. Output: positions and polygons by *position* index (`tobj`'s
//! multi-index mode, so texture and normal seams never split a vertex), all objects and
//! groups merged into one mesh. Cost: O(file size).
//!
//! `tobj` reports errors without a line, so a light scan of the text ([`prescan`]) runs
//! first and reports the first wrong line (bad number, index 0, index out of range,
//! malformed corner) with its number; should `tobj` still fail, the line where it
//! stopped is reported with its message.

use std::borrow::Cow;
use std::collections::HashMap;
use std::io::Cursor;
use std::path::Path;

use glam::DVec3;

use crate::mesh::{MeshError, TriMesh};

/// Parses OBJ `bytes` into a mesh; `path` only names the file in errors.
pub(super) fn parse(bytes: &[u8], path: &Path) -> Result<TriMesh, MeshError> {
    let text = prepare_text(bytes);
    // `..Default::default()` covers the fields tobj adds under its `merging` and
    // `reordering` features, should any crate in a build enable them.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        single_index: false,
        triangulate: false,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    // Scan first: line-accurate errors, and tobj never sees an index it could
    // overflow on (it multiplies texture/normal indices unchecked).
    let scan = prescan(&text);
    if let Some((line, what)) = scan.problem {
        return Err(MeshError::Syntax {
            path: path.to_path_buf(),
            line,
            what,
        });
    }
    let mut cursor = Cursor::new(&text[..]);
    // Materials are irrelevant here: never open .mtl files.
    let loaded = tobj::load_obj_buf(&mut cursor, &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    });
    let models = match loaded {
        Ok((models, _materials)) => models,
        Err(e) => {
            let consumed = usize::try_from(cursor.position())
                .unwrap_or(usize::MAX)
                .min(text.len());
            return Err(MeshError::Syntax {
                path: path.to_path_buf(),
                line: line_of_offset(&text, consumed),
                what: format!("{e} (reported by tobj)"),
            });
        }
    };

    // tobj numbers vertices per object in order of first use; map them back to the
    // file's numbering through their positions (bitwise, as parsed by both). Equal
    // positions map to their first occurrence, which TriMesh would merge them into
    // anyway, so repairs, warnings and the input vertex map are as for file indices.
    let key = |p: DVec3| [p.x + 0.0, p.y + 0.0, p.z + 0.0].map(f64::to_bits);
    let mut first_at: HashMap<[u64; 3], u32> = HashMap::with_capacity(scan.positions.len());
    for (i, p) in scan.positions.iter().enumerate() {
        first_at.entry(key(*p)).or_insert(i as u32);
    }
    let mut corners: Vec<u32> = Vec::new();
    let mut face_ends: Vec<usize> = Vec::new();
    for model in &models {
        let mesh = &model.mesh;
        let file_index: Option<Vec<u32>> = mesh
            .positions
            .chunks_exact(3)
            .map(|p| first_at.get(&key(DVec3::new(p[0], p[1], p[2]))).copied())
            .collect();
        let mut start = 0;
        let mut push_face = |arity: usize| -> Option<()> {
            for &i in mesh.indices.get(start..start + arity)? {
                corners.push(*file_index.as_ref()?.get(i as usize)?);
            }
            start += arity;
            face_ends.push(corners.len());
            Some(())
        };
        let complete = if mesh.face_arities.is_empty() {
            (0..mesh.indices.len() / 3).try_for_each(|_| push_face(3))
        } else {
            mesh.face_arities
                .iter()
                .try_for_each(|&a| push_face(a as usize))
        };
        if complete.is_none() {
            // Not reachable unless tobj and our scan read a vertex differently.
            return Err(MeshError::Syntax {
                path: path.to_path_buf(),
                line: 0,
                what: format!(
                    "tobj's faces of object `{}` do not match the file's vertices",
                    model.name
                ),
            });
        }
    }
    crate::io::build_mesh(path, scan.positions, corners, &face_ends, scan.skipped)
}

/// Prepares the text for `tobj`, keeping every byte offset and line number: a UTF-8
/// byte-order mark becomes spaces (else the first keyword is not recognised), and `l`
/// (polyline) records become comments (`tobj` reads them like faces, so a polyline of
/// three or more points would become a triangle).
fn prepare_text(bytes: &[u8]) -> Cow<'_, [u8]> {
    const BOM: &[u8] = b"\xEF\xBB\xBF";
    let is_polyline = |line: &[u8]| {
        let mut words = line
            .split(|b| b.is_ascii_whitespace())
            .filter(|w| !w.is_empty());
        words.next() == Some(b"l".as_slice())
    };
    let bom = bytes.starts_with(BOM);
    if !bom && !bytes.split(|&b| b == b'\n').any(is_polyline) {
        return Cow::Borrowed(bytes);
    }
    let mut owned = bytes.to_vec();
    if bom {
        owned[..BOM.len()].fill(b' ');
    }
    let mut polylines = Vec::new();
    let mut start = 0;
    for line in owned.split(|&b| b == b'\n') {
        if is_polyline(line)
            && let Some(k) = line.iter().position(|&b| b == b'l')
        {
            polylines.push(start + k);
        }
        start += line.len() + 1;
    }
    for at in polylines {
        owned[at] = b'#';
    }
    Cow::Owned(owned)
}

/// 1-based line containing the last consumed byte (`consumed` bytes read).
fn line_of_offset(text: &[u8], consumed: usize) -> usize {
    let newlines = text[..consumed].iter().filter(|&&b| b == b'\n').count();
    if consumed > 0 && text[consumed - 1] != b'\n' {
        newlines + 1
    } else {
        newlines.max(1)
    }
}

/// What a light scan of the text finds.
#[derive(Debug, Default, PartialEq)]
pub(super) struct Prescan {
    /// First malformed line: 1-based line and what is wrong.
    pub(super) problem: Option<(usize, String)>,
    /// All `v` positions in file order (divided by their weight `w`, as `tobj` does).
    pub(super) positions: Vec<DVec3>,
    /// Faces of one or two corners, which `tobj` drops as points and lines.
    pub(super) skipped: crate::io::Skipped,
}

/// Scans OBJ text for the first problem `tobj` would stop at (or overflow on), following
/// `tobj`'s rules: positive indices may point anywhere in the file, negative ones count
/// back from the records read so far. Collects the positions on the way.
pub(super) fn prescan(text: &[u8]) -> Prescan {
    let lines = || {
        text.split(|&b| b == b'\n')
            .map(|l| std::str::from_utf8(l).ok())
    };
    // Totals of v, vt, vn records (positive indices are checked against these).
    let mut totals = [0usize; 3];
    for line in lines().flatten() {
        match line.split_ascii_whitespace().next() {
            Some("v") => totals[0] += 1,
            Some("vt") => totals[1] += 1,
            Some("vn") => totals[2] += 1,
            _ => {}
        }
    }
    let mut scan = Prescan {
        problem: None,
        positions: Vec::with_capacity(totals[0]),
        skipped: crate::io::Skipped::default(),
    };
    let mut seen = [0usize; 3];
    let mut faces = 0usize;
    for (k, line) in lines().enumerate() {
        let Some(line) = line else {
            scan.problem = Some((k + 1, "line is not valid UTF-8".to_owned()));
            break;
        };
        let mut words = line.split_ascii_whitespace();
        let problem = match words.next() {
            Some("v") => {
                seen[0] += 1;
                match check_vertex(words) {
                    Ok(p) => {
                        scan.positions.push(p);
                        None
                    }
                    Err(what) => Some(what),
                }
            }
            Some("vt") => {
                seen[1] += 1;
                check_numbers(words, 2, "texture coordinate")
            }
            Some("vn") => {
                seen[2] += 1;
                check_numbers(words, 3, "normal")
            }
            Some("f") => {
                let mut corners = 0;
                let problem = words.find_map(|c| {
                    corners += 1;
                    check_corner(c, faces, &seen, &totals)
                });
                if corners >= 3 {
                    faces += 1;
                } else if corners > 0 && problem.is_none() {
                    scan.skipped.push(k + 1);
                }
                problem
            }
            _ => None,
        };
        if let Some(what) = problem {
            scan.problem = Some((k + 1, what));
            break;
        }
    }
    scan
}

/// A `v` record: three numbers, then nothing, a non-zero weight, or an RGB colour.
fn check_vertex<'a>(values: impl Iterator<Item = &'a str>) -> Result<DVec3, String> {
    let mut p = [0.0; 3];
    let mut count = 0;
    let mut weight = None;
    for (i, value) in values.enumerate() {
        count += 1;
        match i {
            0..3 => {
                p[i] = value
                    .parse()
                    .map_err(|_| format!("vertex coordinate `{value}` is not a number"))?;
            }
            // tobj ignores colour values it cannot parse, but not a bad weight.
            3 => weight = value.parse::<f64>().ok(),
            _ => {}
        }
    }
    match (count, weight) {
        (0..3, _) => Err(format!(
            "a vertex needs 3 coordinates, this one has {count}"
        )),
        (3, _) | (6, _) => Ok(DVec3::from_array(p)),
        (4, Some(w)) if w != 0.0 => Ok(DVec3::from_array(p.map(|c| c / w))),
        (4, Some(_)) => Err("vertex weight w is 0".to_owned()),
        (4, None) => Err("vertex weight w is not a number".to_owned()),
        _ => Err(format!(
            "vertex has {count} values; expected 3, 4 (x y z w) or 6 (x y z r g b)"
        )),
    }
}

fn check_numbers<'a>(
    mut words: impl Iterator<Item = &'a str>,
    n: usize,
    what: &str,
) -> Option<String> {
    for _ in 0..n {
        match words.next() {
            Some(w) if w.parse::<f64>().is_ok() => {}
            Some(w) => return Some(format!("{what} value `{w}` is not a number")),
            None => return Some(format!("{what} needs {n} values")),
        }
    }
    None
}

/// One face corner `v`, `v/vt`, `v//vn` or `v/vt/vn`.
fn check_corner(
    corner: &str,
    face: usize,
    seen: &[usize; 3],
    totals: &[usize; 3],
) -> Option<String> {
    const KINDS: [(&str, &str); 3] = [
        ("vertex", "vertices"),
        ("texture coordinate", "texture coordinates"),
        ("normal", "normals"),
    ];
    let parts: Vec<&str> = corner.split('/').collect();
    if parts.len() > 3 || parts[0].is_empty() {
        return Some(format!("face {face}: malformed corner `{corner}`"));
    }
    for (kind, part) in parts.iter().enumerate() {
        if part.is_empty() {
            continue;
        }
        let Ok(index) = part.parse::<i64>() else {
            let digits = part.strip_prefix('-').unwrap_or(part);
            let what = if !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit()) {
                "an index out of range"
            } else {
                "a non-integer index"
            };
            return Some(format!("face {face}: corner `{corner}` has {what}"));
        };
        let (name, plural) = KINDS[kind];
        if kind > 0 && totals[kind] == 0 {
            continue; // tobj ignores texture/normal indices when there are none
        }
        let (ok, available) = match index {
            0 => {
                return Some(format!(
                    "face {face} refers to {name} 0 (OBJ indices start at 1)"
                ));
            }
            i if i > 0 => (i as u64 <= totals[kind] as u64, totals[kind]),
            i => (i.unsigned_abs() <= seen[kind] as u64, seen[kind]),
        };
        if !ok {
            return Some(format!(
                "face {face} refers to {name} {index}, but {available} {plural} are defined{}",
                if index < 0 { " before it" } else { "" }
            ));
        }
    }
    None
}
