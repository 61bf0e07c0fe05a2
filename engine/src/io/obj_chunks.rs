//! The OBJ reader's parallel fast path: the text cut at line ends into chunks parsed on
//! rayon's threads, for files of a few megabytes and more.
//!
//! A chunk does not know how many records come before it, so it keeps what depends on
//! that aside: a negative (relative) index is stored relative to the chunk's own
//! records and resolved once the chunks are counted, and the range of every index is
//! checked after all chunks are read, against the file's totals and the records
//! before each corner. The fast path only ever returns a scan without problems, equal
//! to [`scan`](super::obj::scan)'s: on anything unusual (a malformed line, an index out
//! of range or 0, a nameless `usemtl`, text that is not UTF-8, a face of one or two
//! corners) it returns `None` and the caller runs the sequential pass, which finds the
//! problem, or the skipped faces, and their lines. The
//! result does not depend on the thread count (chunks are fixed by the file and merged
//! in order).
//!
//! Cost: O(file size), split over the threads; the merge copies the arrays once.

use glam::DVec3;
use rayon::prelude::*;

use super::obj::{Scan, check_numbers, parse_index, vertex};

/// Files smaller than this are read by the sequential pass (the threads would not pay
/// for themselves).
pub(crate) const PARALLEL_MIN_BYTES: usize = 1 << 21;

/// Target size of one chunk: large enough that a chunk's fixed costs vanish, small
/// enough for several chunks per thread to even out the load.
const CHUNK_BYTES: usize = 1 << 20;

/// What one chunk holds.
#[derive(Default)]
struct Chunk {
    positions: Vec<DVec3>,
    /// Position indices from 0; for a relative corner the slot holds 0 until resolved.
    corners: Vec<u32>,
    /// (slot in `corners`, `v` records of this chunk before the corner + index), for
    /// negative position indices.
    relative: Vec<(usize, i64)>,
    /// End (exclusive, within this chunk's `corners`) of each face.
    face_ends: Vec<usize>,
    /// `v`, `vt`, `vn` records in this chunk.
    seen: [usize; 3],
    /// Largest positive index per kind (0 when none).
    max_index: [i64; 3],
    /// Smallest `records of this chunk before the corner + index` over the negative
    /// indices per kind (`i64::MAX` when none): with the records before the chunk
    /// added, it must stay >= 0.
    min_relative: [i64; 3],
    /// An index 0 of a texture coordinate or normal (valid only when the file has none
    /// of that kind, when the sequential reader ignores such indices).
    zero: [bool; 3],
}

/// Scans `bytes` on rayon's threads; `None` if the file is small, or has anything for
/// the sequential pass to report (see the module docs).
pub(crate) fn scan(bytes: &[u8]) -> Option<Scan> {
    if bytes.len() < PARALLEL_MIN_BYTES {
        return None;
    }
    scan_in_chunks(bytes, CHUNK_BYTES)
}

/// [`scan`] with chunks of about `chunk_bytes` (at least 1), whatever the file's size.
pub(crate) fn scan_in_chunks(bytes: &[u8], chunk_bytes: usize) -> Option<Scan> {
    let text = std::str::from_utf8(bytes).ok()?;
    let body = text.strip_prefix("\u{feff}").unwrap_or(text);
    let chunks: Vec<Chunk> = split_lines(body, chunk_bytes.max(1))
        .par_iter()
        .map(|part| read_chunk(part))
        .collect::<Option<_>>()?;
    merge(chunks)
}

/// `text` cut after newlines into pieces of about `size` bytes.
fn split_lines(text: &str, size: usize) -> Vec<&str> {
    let mut parts = Vec::with_capacity(text.len() / size + 1);
    let mut rest = text;
    while rest.len() > size {
        // The first newline at or after the target; the piece ends just after it.
        let end = match rest.as_bytes()[size..].iter().position(|&b| b == b'\n') {
            Some(i) => size + i + 1,
            None => rest.len(),
        };
        let (piece, tail) = rest.split_at(end);
        parts.push(piece);
        rest = tail;
    }
    if !rest.is_empty() {
        parts.push(rest);
    }
    parts
}

/// Reads one chunk; `None` at a line the sequential pass would report.
fn read_chunk(text: &str) -> Option<Chunk> {
    let mut c = Chunk {
        positions: Vec::with_capacity(text.len() / 64),
        corners: Vec::with_capacity(text.len() / 12),
        face_ends: Vec::with_capacity(text.len() / 32),
        min_relative: [i64::MAX; 3],
        ..Chunk::default()
    };
    for line in text.split('\n') {
        let mut words = line.split_ascii_whitespace();
        match words.next() {
            Some("v") => {
                c.seen[0] += 1;
                c.positions.push(vertex(words).ok()?);
            }
            Some("vt") => {
                c.seen[1] += 1;
                if check_numbers(words, 2, "texture coordinate").is_some() {
                    return None;
                }
            }
            Some("vn") => {
                c.seen[2] += 1;
                if check_numbers(words, 3, "normal").is_some() {
                    return None;
                }
            }
            Some("f") => face(&mut c, words)?,
            Some("usemtl") => {
                let name = line.split_once(' ').map_or("", |(_, name)| name);
                if name.trim().is_empty() {
                    return None;
                }
            }
            _ => {}
        }
    }
    Some(c)
}

/// One `f` line, as the sequential reader's `face`, ranges left for the merge.
fn face<'w>(c: &mut Chunk, words: impl Iterator<Item = &'w str>) -> Option<()> {
    let start = c.corners.len();
    let mut count = 0;
    for corner in words {
        count += 1;
        let mut parts = corner.split('/');
        let all = [parts.next(), parts.next(), parts.next()];
        if parts.next().is_some() || all[0].is_none_or(str::is_empty) {
            return None;
        }
        let mut position = None;
        for (kind, part) in all.into_iter().enumerate() {
            let Some(part) = part.filter(|p| !p.is_empty()) else {
                continue;
            };
            let index = parse_index(part)?;
            match index {
                0 if kind == 0 => return None,
                0 => c.zero[kind] = true,
                i if i > 0 => c.max_index[kind] = c.max_index[kind].max(i),
                i => {
                    let local = c.seen[kind] as i64 + i;
                    c.min_relative[kind] = c.min_relative[kind].min(local);
                }
            }
            if kind == 0 {
                position = Some(index);
            }
        }
        // The first part is never empty, so the position index was read.
        let index = position?;
        if index > 0 {
            c.corners.push(u32::try_from(index - 1).ok()?);
        } else {
            c.relative.push((c.corners.len(), c.seen[0] as i64 + index));
            c.corners.push(0);
        }
    }
    match count {
        // A point or a line: the sequential pass skips it and names its line.
        1 | 2 => return None,
        0 => c.face_ends.push(start),
        _ => c.face_ends.push(c.corners.len()),
    }
    Some(())
}

/// Checks every index against the file's totals and the records before it, resolves
/// the relative ones and concatenates the chunks; `None` if an index is out of range.
fn merge(chunks: Vec<Chunk>) -> Option<Scan> {
    let mut totals = [0usize; 3];
    for c in &chunks {
        for (total, seen) in totals.iter_mut().zip(c.seen) {
            *total += seen;
        }
    }
    let mut before = [0usize; 3];
    for c in &chunks {
        for kind in 0..3 {
            // Texture and normal indices are ignored when the file has none of them.
            let checked = kind == 0 || totals[kind] > 0;
            let relative_ok =
                c.min_relative[kind] == i64::MAX || before[kind] as i64 + c.min_relative[kind] >= 0;
            if checked
                && (c.max_index[kind] as u64 > totals[kind] as u64 || c.zero[kind] || !relative_ok)
            {
                return None;
            }
            before[kind] += c.seen[kind];
        }
    }
    let (positions_len, corners_len, faces_len) = chunks.iter().fold((0, 0, 0), |(p, q, f), c| {
        (
            p + c.positions.len(),
            q + c.corners.len(),
            f + c.face_ends.len(),
        )
    });
    let mut scan = Scan {
        problem: None,
        positions: Vec::with_capacity(positions_len),
        corners: Vec::with_capacity(corners_len),
        face_ends: Vec::with_capacity(faces_len),
        skipped: super::Skipped::default(),
    };
    let mut vertices_before = 0usize;
    for c in chunks {
        let offset = scan.corners.len();
        scan.positions.extend_from_slice(&c.positions);
        scan.corners.extend_from_slice(&c.corners);
        for (slot, local) in c.relative {
            // In range: checked above (local >= -vertices_before).
            scan.corners[offset + slot] = u32::try_from(vertices_before as i64 + local).ok()?;
        }
        scan.face_ends
            .extend(c.face_ends.iter().map(|&e| e + offset));
        vertices_before += c.seen[0];
    }
    Some(scan)
}
