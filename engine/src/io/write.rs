//! Writers: meshes and samples as binary little-endian PLY, samples as CSV.
//!
//! The path-taking writers are atomic ([`write_atomically`]: a temporary file in the
//! same folder, synced, then renamed over `path`), so a reader sees the old file or the
//! whole new one. The `_to` variants write to any [`Write`] (wrap unbuffered sinks in a
//! `BufWriter`: they issue one small write per record).

use std::io::{self, Write};
use std::path::Path;

use super::{SAMPLE_COLUMNS, write_atomically};
use crate::mesh::{MeshError, TriMesh};
use crate::sample::Sample;

/// Writes `mesh` as binary little-endian PLY, atomically (see [`write_mesh_ply_to`]).
///
/// Errors: [`MeshError::Io`] naming `path` (also for a wrong number of colours).
pub fn write_mesh_ply(
    path: &Path,
    mesh: &TriMesh,
    face_colors: Option<&[[u8; 3]]>,
) -> Result<(), MeshError> {
    write_atomically(path, |w| write_mesh_ply_to(w, mesh, face_colors)).map_err(|source| {
        MeshError::Io {
            path: path.to_path_buf(),
            source,
        }
    })
}

/// Writes `mesh` as binary little-endian PLY to `w`: element `vertex` with `float x y z`
/// (positions rounded to f32), element `face` with `list uchar int vertex_indices`, and
/// `uchar red green blue` per face when `face_colors` is given.
///
/// Errors: [`io::ErrorKind::InvalidInput`] if `face_colors` does not have one colour per
/// face, or a vertex index does not fit an `int`; any error of `w`.
pub fn write_mesh_ply_to<W: Write>(
    mut w: W,
    mesh: &TriMesh,
    face_colors: Option<&[[u8; 3]]>,
) -> io::Result<()> {
    if let Some(colors) = face_colors
        && colors.len() != mesh.face_count()
    {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!(
                "{} face colours for {} faces",
                colors.len(),
                mesh.face_count()
            ),
        ));
    }
    if i32::try_from(mesh.vertex_count()).is_err() {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            "too many vertices for PLY `int` indices",
        ));
    }
    let mut header = format!(
        "ply\nformat binary_little_endian 1.0\ncomment written by strata\n\
         element vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         element face {}\nproperty list uchar int vertex_indices\n",
        mesh.vertex_count(),
        mesh.face_count()
    );
    if face_colors.is_some() {
        header.push_str("property uchar red\nproperty uchar green\nproperty uchar blue\n");
    }
    header.push_str("end_header\n");
    w.write_all(header.as_bytes())?;
    for p in mesh.positions() {
        let mut record = [0u8; 12];
        for (chunk, c) in record.chunks_exact_mut(4).zip(p.as_vec3().to_array()) {
            chunk.copy_from_slice(&c.to_le_bytes());
        }
        w.write_all(&record)?;
    }
    for (f, t) in mesh.triangles().iter().enumerate() {
        let mut record = [0u8; 16];
        record[0] = 3;
        for (chunk, v) in record[1..13].chunks_exact_mut(4).zip(t) {
            // In range: the vertex count fits an i32 (checked above).
            chunk.copy_from_slice(&(*v as i32).to_le_bytes());
        }
        let len = match face_colors {
            Some(colors) => {
                record[13..16].copy_from_slice(&colors[f]);
                16
            }
            None => 13,
        };
        w.write_all(&record[..len])?;
    }
    w.flush()
}

/// Writes samples as a binary little-endian PLY point cloud, atomically (see
/// [`write_samples_ply_to`]). Read it back with [`read_samples_ply`](super::read_samples_ply).
///
/// Errors: [`MeshError::Io`] naming `path`.
pub fn write_samples_ply(path: &Path, samples: &[Sample]) -> Result<(), MeshError> {
    write_atomically(path, |w| write_samples_ply_to(w, samples)).map_err(|source| MeshError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// Writes samples as a binary little-endian PLY point cloud to `w`: one element `vertex`
/// with the [`SAMPLE_COLUMNS`] as properties, `float` except `face`, `segment` and
/// `index` (`uint`); 64 bytes per sample.
///
/// ```
/// use strata_engine::{io, sample::Sample};
/// let samples = vec![Sample { position: [1.0, 2.0, 3.0], face: 7, ..Default::default() }];
/// let mut bytes = Vec::new();
/// io::write_samples_ply_to(&mut bytes, &samples)?;
/// let back = io::parse_samples_ply(&bytes, "memory.ply".as_ref())?;
/// assert_eq!(back, samples);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn write_samples_ply_to<W: Write>(mut w: W, samples: &[Sample]) -> io::Result<()> {
    write_ply_header(&mut w, samples.len() as u64)?;
    write_ply_rows(&mut w, samples)?;
    w.flush()
}

/// The header of a samples PLY of `count` samples.
fn write_ply_header<W: Write>(w: &mut W, count: u64) -> io::Result<()> {
    let mut header = format!(
        "ply\nformat binary_little_endian 1.0\ncomment written by strata: samples\nelement vertex {count}\n"
    );
    for name in SAMPLE_COLUMNS {
        let ty = if matches!(name, "face" | "segment" | "index") {
            "uint"
        } else {
            "float"
        };
        header.push_str(&format!("property {ty} {name}\n"));
    }
    header.push_str("end_header\n");
    w.write_all(header.as_bytes())
}

/// The 64-byte records of `samples`.
fn write_ply_rows<W: Write>(w: &mut W, samples: &[Sample]) -> io::Result<()> {
    for s in samples {
        check_finite(s)?;
        let mut record = [0u8; 64];
        for (chunk, word) in record.chunks_exact_mut(4).zip(sample_row(s)) {
            chunk.copy_from_slice(&word.to_le_bytes());
        }
        w.write_all(&record)?;
    }
    Ok(())
}

/// Writes samples as CSV, atomically (see [`write_samples_csv_to`]).
///
/// Errors: [`MeshError::Io`] naming `path`.
pub fn write_samples_csv(path: &Path, samples: &[Sample]) -> Result<(), MeshError> {
    write_atomically(path, |w| write_samples_csv_to(w, samples)).map_err(|source| MeshError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// Writes samples as CSV to `w`: a header row of the [`SAMPLE_COLUMNS`] (`x,y,z` first),
/// then one row per sample; floats in Rust's shortest round-trip notation.
pub fn write_samples_csv_to<W: Write>(mut w: W, samples: &[Sample]) -> io::Result<()> {
    write_csv_header(&mut w)?;
    write_csv_rows(&mut w, samples)?;
    w.flush()
}

/// The header row of a samples CSV.
fn write_csv_header<W: Write>(w: &mut W) -> io::Result<()> {
    writeln!(w, "{}", SAMPLE_COLUMNS.join(","))
}

/// The CSV rows of `samples`.
fn write_csv_rows<W: Write>(w: &mut W, samples: &[Sample]) -> io::Result<()> {
    for s in samples {
        check_finite(s)?;
        let [x, y, z] = s.position;
        let [nx, ny, nz] = s.normal;
        let [mx, my, mz] = s.major_axis;
        let [s1, s2] = s.spacing;
        let [b1, b2] = s.bary;
        writeln!(
            w,
            "{x},{y},{z},{nx},{ny},{nz},{mx},{my},{mz},{s1},{s2},{},{b1},{b2},{},{}",
            s.face, s.segment, s.index
        )?;
    }
    Ok(())
}

/// The sample file formats: what [`write_samples_ply`] and [`write_samples_csv`] write.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SampleFormat {
    /// Binary little-endian PLY, 64 bytes per sample.
    Ply,
    /// CSV with a header row.
    Csv,
}

/// Writes `count` samples to `path` atomically, drawing them a block at a time:
/// `fill(start, block)` fills `block` with samples `start..start + block.len()`. The
/// file is the same, byte for byte, as [`write_samples_ply`] or [`write_samples_csv`]
/// of all of them, while memory holds one block of at most `block` samples whatever
/// the count. `fill` may also report progress; an error it returns (or one writing)
/// leaves `path` as it was.
///
/// ```
/// use strata_engine::io::{self, SampleFormat};
/// use strata_engine::sample::Sample;
/// let all: Vec<Sample> = (0..10).map(|i| Sample { index: i, ..Default::default() }).collect();
/// let dir = tempfile::tempdir()?;
/// let (a, b) = (dir.path().join("a.ply"), dir.path().join("b.ply"));
/// io::write_samples_ply(&a, &all)?;
/// io::write_samples_in_blocks(&b, SampleFormat::Ply, 10, 3, |start, block| {
///     block.copy_from_slice(&all[start as usize..start as usize + block.len()]);
///     Ok(())
/// })?;
/// assert_eq!(std::fs::read(&a)?, std::fs::read(&b)?);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// Errors: [`MeshError::Io`] naming `path`, for a write error or one from `fill`; a
/// `block` of 0 is taken as 1.
pub fn write_samples_in_blocks(
    path: &Path,
    format: SampleFormat,
    count: u64,
    block: usize,
    mut fill: impl FnMut(u64, &mut [Sample]) -> io::Result<()>,
) -> Result<(), MeshError> {
    let block = block
        .max(1)
        .min(usize::try_from(count).unwrap_or(usize::MAX));
    write_atomically(path, |w| {
        let mut buffer = Vec::new();
        buffer
            .try_reserve_exact(block)
            .map_err(|e| io::Error::new(io::ErrorKind::OutOfMemory, e))?;
        buffer.resize(block, Sample::default());
        match format {
            SampleFormat::Ply => write_ply_header(w, count)?,
            SampleFormat::Csv => write_csv_header(w)?,
        }
        let mut start = 0u64;
        while start < count {
            let len = block.min(usize::try_from(count - start).unwrap_or(usize::MAX));
            let samples = &mut buffer[..len];
            fill(start, samples)?;
            match format {
                SampleFormat::Ply => write_ply_rows(w, samples)?,
                SampleFormat::Csv => write_csv_rows(w, samples)?,
            }
            start += len as u64;
        }
        w.flush()
    })
    .map_err(|source| MeshError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// Refuses a sample with a non-finite position or spacing
/// ([`io::ErrorKind::InvalidData`]): a file never holds one (coordinates beyond `f32`'s
/// range overflow to infinity when samples are made).
fn check_finite(s: &Sample) -> io::Result<()> {
    let values = s.position.iter().chain(&s.spacing);
    if values.clone().all(|v| v.is_finite()) {
        return Ok(());
    }
    Err(io::Error::new(
        io::ErrorKind::InvalidData,
        format!(
            "sample {} has a non-finite position {:?} or spacing {:?} (beyond the 32-bit floats samples are written in); nothing was written",
            s.index, s.position, s.spacing
        ),
    ))
}

/// The 16 values of a sample row as 32-bit words (float bits or uint), in
/// [`SAMPLE_COLUMNS`] order.
fn sample_row(s: &Sample) -> [u32; 16] {
    let f = f32::to_bits;
    [
        f(s.position[0]),
        f(s.position[1]),
        f(s.position[2]),
        f(s.normal[0]),
        f(s.normal[1]),
        f(s.normal[2]),
        f(s.major_axis[0]),
        f(s.major_axis[1]),
        f(s.major_axis[2]),
        f(s.spacing[0]),
        f(s.spacing[1]),
        s.face,
        f(s.bary[0]),
        f(s.bary[1]),
        s.segment,
        s.index,
    ]
}
