//! Wavefront OBJ reader: one pass over the text, line-accurate errors.
//!
//! Input: the file's bytes. Output: positions in file order and polygons by *position*
//! index (texture and normal indices are checked, then dropped, so UV and normal seams
//! never split a vertex), all objects and groups merged into one mesh. Cost: O(file
//! size), with no allocation per line: the text is checked as UTF-8 once, lines are
//! found with `str::split` (a memchr search), coordinates are parsed with `str::parse`
//! (core's Eisel-Lemire parser, the algorithm of the `fast-float` crate, exact) and
//! indices with a digit loop.
//!
//! The rules are those of the `tobj`-based reader this replaces (kept as the test
//! reference in `io/tests/obj_reference.rs`), so meshes, repairs and errors are the
//! same: positive indices may point anywhere in the file, negative ones count back
//! from the records read so far; texture and normal indices are ignored when the file
//! has no texture coordinates or normals; faces of one or two corners are skipped (as
//! points and lines, with a warning that names their lines), a face with no corner is
//! an empty polygon; `l` records are
//! ignored. Where `tobj` failed on valid input (a vertex colour on some vertices only,
//! a positive index to a vertex defined after the next `o`/`g`), this reader loads it.

use glam::DVec3;

/// What is wrong with an index that does not parse: an integer too large for any
/// file, or not an integer at all.
pub(super) fn bad_index(part: &str) -> &'static str {
    let digits = part.strip_prefix('-').unwrap_or(part);
    if !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit()) {
        "an index out of range"
    } else {
        "a non-integer index"
    }
}

/// What one pass over the text finds.
#[derive(Debug, PartialEq)]
pub(crate) struct Scan {
    /// First malformed line: 1-based line and what is wrong.
    pub(crate) problem: Option<(usize, String)>,
    /// All `v` positions in file order (divided by their weight `w`).
    pub(crate) positions: Vec<DVec3>,
    /// Position indices (from 0) of every face's corners, concatenated.
    pub(crate) corners: Vec<u32>,
    /// End (exclusive) of each face in `corners`.
    pub(crate) face_ends: Vec<usize>,
    /// Faces of one or two corners, skipped.
    pub(crate) skipped: super::Skipped,
}

const BOM: &[u8] = b"\xEF\xBB\xBF";

/// Reads OBJ text: positions and faces, or the first problem. Never panics.
pub(crate) fn scan(bytes: &[u8]) -> Scan {
    // Check UTF-8 once; a bad line is reported where it is, after the lines before it.
    let (text, bad_line) = match std::str::from_utf8(bytes) {
        Ok(text) => (text, None),
        Err(e) => {
            let valid = bytes.get(..e.valid_up_to()).unwrap_or_default();
            let line_start = valid.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
            let newlines = valid[..line_start].iter().filter(|&&b| b == b'\n').count();
            let text = std::str::from_utf8(&valid[..line_start]).unwrap_or_default();
            (text, Some(newlines + 1))
        }
    };
    // A byte-order mark is whitespace before the first keyword.
    let body = if bytes.starts_with(BOM) {
        text.get(BOM.len()..).unwrap_or_default()
    } else {
        text
    };
    let mut reader = Reader {
        bytes,
        totals: None,
        seen: [0; 3],
        faces: 0,
        nameless_usemtl: None,
    };
    let mut scan = Scan {
        problem: None,
        // Pre-sized for a typical scan: about 30 bytes per vertex and per face line.
        positions: Vec::with_capacity(bytes.len() / 64),
        corners: Vec::with_capacity(bytes.len() / 12),
        face_ends: Vec::with_capacity(bytes.len() / 32),
        skipped: super::Skipped::default(),
    };
    for (k, line) in body.split('\n').enumerate() {
        if let Some(what) = reader.line(k + 1, line, &mut scan) {
            scan.problem = Some((k + 1, what));
            return scan;
        }
    }
    scan.problem = match (bad_line, reader.nameless_usemtl) {
        (Some(line), _) => Some((line, "line is not valid UTF-8".to_owned())),
        (None, Some(line)) => Some((line, "`usemtl` needs a material name".to_owned())),
        (None, None) => None,
    };
    scan
}

/// The state of the pass: records seen so far, and the file's totals once needed.
struct Reader<'a> {
    bytes: &'a [u8],
    /// Totals of `v`, `vt`, `vn` records in the whole file: counted only when an index
    /// points past the records read so far (a forward reference) or at a kind not yet
    /// seen, which files written in the usual order never do.
    totals: Option<[usize; 3]>,
    /// `v`, `vt`, `vn` records read so far, the current one included.
    seen: [usize; 3],
    /// Faces of three or more corners read so far (how messages number faces).
    faces: usize,
    /// The first `usemtl` line without a name, which `tobj` rejected once the rest of
    /// the file was fine (the name is what follows the first space, trimmed).
    nameless_usemtl: Option<usize>,
}

impl Reader<'_> {
    /// Reads line `number` (from 1) into `scan`; the problem, if any.
    fn line(&mut self, number: usize, line: &str, scan: &mut Scan) -> Option<String> {
        let mut words = line.split_ascii_whitespace();
        match words.next()? {
            "v" => {
                self.seen[0] += 1;
                match vertex(words) {
                    Ok(p) => {
                        scan.positions.push(p);
                        None
                    }
                    Err(what) => Some(what),
                }
            }
            "vt" => {
                self.seen[1] += 1;
                check_numbers(words, 2, "texture coordinate")
            }
            "vn" => {
                self.seen[2] += 1;
                check_numbers(words, 3, "normal")
            }
            "f" => self.face(number, words, scan),
            "usemtl" => {
                let name = line.split_once(' ').map_or("", |(_, name)| name);
                if name.trim().is_empty() && self.nameless_usemtl.is_none() {
                    self.nameless_usemtl = Some(number);
                }
                None
            }
            _ => None,
        }
    }

    fn face<'w>(
        &mut self,
        number: usize,
        words: impl Iterator<Item = &'w str>,
        scan: &mut Scan,
    ) -> Option<String> {
        let start = scan.corners.len();
        let mut count = 0;
        for corner in words {
            count += 1;
            match self.corner(corner) {
                Ok(v) => scan.corners.push(v),
                Err(what) => return Some(what),
            }
        }
        match count {
            // One or two corners are a point or a line, which a mesh leaves out (with
            // a warning: a file cut short in a face line ends with one).
            1 | 2 => {
                scan.corners.truncate(start);
                scan.skipped.push(number);
            }
            // No corner: an empty polygon, which the mesh rejects (TooFewCorners).
            0 => scan.face_ends.push(start),
            _ => {
                scan.face_ends.push(scan.corners.len());
                self.faces += 1;
            }
        }
        None
    }

    /// One face corner `v`, `v/vt`, `v//vn` or `v/vt/vn`: its position index from 0.
    fn corner(&mut self, corner: &str) -> Result<u32, String> {
        const KINDS: [(&str, &str); 3] = [
            ("vertex", "vertices"),
            ("texture coordinate", "texture coordinates"),
            ("normal", "normals"),
        ];
        let face = self.faces;
        let mut parts = corner.split('/');
        let all = [parts.next(), parts.next(), parts.next()];
        if parts.next().is_some() || all[0].is_none_or(str::is_empty) {
            return Err(format!("face {face}: malformed corner `{corner}`"));
        }
        let mut position = 0;
        for (kind, part) in all.into_iter().enumerate() {
            let Some(part) = part.filter(|p| !p.is_empty()) else {
                continue;
            };
            let Some(index) = parse_index(part) else {
                return Err(format!(
                    "face {face}: corner `{corner}` has {}",
                    bad_index(part)
                ));
            };
            let seen = self.seen[kind];
            // Decided without the totals where the records read so far settle it.
            let settled = if kind > 0 && seen == 0 {
                None
            } else if index <= 0 || index as u64 <= seen as u64 {
                Some(seen)
            } else {
                None
            };
            let available = match settled {
                Some(seen) => seen,
                None => {
                    let totals = *self.totals.get_or_insert_with(|| count_records(self.bytes));
                    if kind > 0 && totals[kind] == 0 {
                        continue; // no texture coordinates or normals: ignored
                    }
                    if index > 0 { totals[kind] } else { seen }
                }
            };
            let (name, plural) = KINDS[kind];
            let ok = match index {
                0 => {
                    return Err(format!(
                        "face {face} refers to {name} 0 (OBJ indices start at 1)"
                    ));
                }
                i if i > 0 => i as u64 <= available as u64,
                i => i.unsigned_abs() <= available as u64,
            };
            if !ok {
                return Err(format!(
                    "face {face} refers to {name} {index}, but {available} {plural} are defined{}",
                    if index < 0 { " before it" } else { "" }
                ));
            }
            if kind == 0 {
                let from_zero = if index > 0 {
                    index - 1
                } else {
                    seen as i64 + index
                };
                // In range of the records, so of a u32 for any mesh that fits memory.
                position = u32::try_from(from_zero).unwrap_or(u32::MAX);
            }
        }
        Ok(position)
    }
}

/// Totals of `v`, `vt` and `vn` records over every line that is valid UTF-8.
fn count_records(bytes: &[u8]) -> [usize; 3] {
    let body = bytes.strip_prefix(BOM).unwrap_or(bytes);
    let mut totals = [0; 3];
    for line in body.split(|&b| b == b'\n') {
        let Ok(line) = std::str::from_utf8(line) else {
            continue;
        };
        match line.split_ascii_whitespace().next() {
            Some("v") => totals[0] += 1,
            Some("vt") => totals[1] += 1,
            Some("vn") => totals[2] += 1,
            _ => {}
        }
    }
    totals
}

/// An integer as `i64::from_str` reads it; plain digits (with an optional `-`) take a
/// short loop, anything else (`+`, 19 digits or more, junk) goes to `from_str`.
pub(super) fn parse_index(s: &str) -> Option<i64> {
    let b = s.as_bytes();
    let (negative, digits) = match b.split_first() {
        Some((b'-', rest)) => (true, rest),
        _ => (false, b),
    };
    if digits.is_empty() || digits.len() > 18 || !digits.iter().all(u8::is_ascii_digit) {
        return s.parse().ok();
    }
    let value = digits
        .iter()
        .fold(0i64, |v, &d| v * 10 + i64::from(d - b'0'));
    Some(if negative { -value } else { value })
}

/// A `v` record: three numbers, then nothing, a non-zero weight, or an RGB colour
/// (whose values are not checked).
pub(super) fn vertex<'a>(mut values: impl Iterator<Item = &'a str>) -> Result<DVec3, String> {
    let mut p = [0.0; 3];
    for (i, c) in p.iter_mut().enumerate() {
        let Some(value) = values.next() else {
            return Err(format!("a vertex needs 3 coordinates, this one has {i}"));
        };
        *c = value
            .parse()
            .map_err(|_| format!("vertex coordinate `{value}` is not a number"))?;
    }
    let Some(fourth) = values.next() else {
        return Ok(DVec3::from_array(p));
    };
    let extra = 1 + values.count();
    match (extra, fourth.parse::<f64>().ok()) {
        (3, _) => Ok(DVec3::from_array(p)),
        (1, Some(w)) if w != 0.0 => Ok(DVec3::from_array(p.map(|c| c / w))),
        (1, Some(_)) => Err("vertex weight w is 0".to_owned()),
        (1, None) => Err("vertex weight w is not a number".to_owned()),
        _ => Err(format!(
            "vertex has {} values; expected 3, 4 (x y z w) or 6 (x y z r g b)",
            3 + extra
        )),
    }
}

pub(super) fn check_numbers<'a>(
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
