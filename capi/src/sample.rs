//! Sampling into caller-owned buffers: `strata_sample` writes any count of stratified
//! or progressive samples as 64-byte records (`StrataSample`, the engine's `Sample`
//! bit for bit) and/or as separate arrays (positions, normals, major axes, face ids,
//! barycentrics, spacings).
//!
//! Cost: the engine's `sample_into` / `progressive_into` (parallel over fixed chunks),
//! plus one copy per requested array when records are not asked for. No allocation in
//! steady state: the records are drawn straight into the caller's buffer, or into the
//! sampler's scratch, which grows to the largest count asked and is then reused.

#![allow(unsafe_code)] // `#[unsafe(no_mangle)]` exports only; see `handle.rs` for the rest.

use std::mem::offset_of;
use std::sync::Mutex;

use strata_engine::sample::{Sample, Sampler};

use crate::handle::{
    Failure, Handle, Kind, Outcome, StrataStatus, borrow, check_struct_size, guard, release, slice,
    slice_mut,
};

/// A preprocessed surface, ready to sample (opaque). Any thread may sample it,
/// concurrently: calls that write records only run in parallel; calls that ask for
/// separate arrays without records share the sampler's scratch and take turns. Free
/// it once, after the calls that use it (and the level-of-detail pools made from it)
/// are done with it.
pub struct StrataSampler {
    pub(crate) sampler: Sampler,
    scratch: Mutex<Vec<Sample>>,
}

impl StrataSampler {
    /// A handle around `sampler`, with an empty scratch.
    pub(crate) fn new(sampler: Sampler) -> Self {
        Self {
            sampler,
            scratch: Mutex::new(Vec::new()),
        }
    }
}

impl Handle for StrataSampler {
    const KIND: Kind = Kind::Sampler;
}

/// One sample, 64 bytes, the layout of the engine's `Sample` (and of the WGSL
/// `Sample` in strata's shaders), so an array of them can be uploaded to a GPU as is:
///
/// | offset | field | |
/// | --- | --- | --- |
/// | 0 | `position[3]` | world space |
/// | 12 | `face` | the mesh face it lies on |
/// | 16 | `normal[3]` | unit normal |
/// | 28 | `segment` | the face's segment |
/// | 32 | `major_axis[3]` | unit tangent of densest spacing |
/// | 44 | `index` | rank (stratified: in this request; progressive: in the sequence) |
/// | 48 | `bary[2]` | barycentrics of corners 1 and 2 (corner 0: `1 - bary[0] - bary[1]`) |
/// | 56 | `spacing[2]` | expected spacing along the major and minor axis (world units) |
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StrataSample {
    /// Position in world space.
    pub position: [f32; 3],
    /// The face the sample lies on.
    pub face: u32,
    /// Unit surface normal.
    pub normal: [f32; 3],
    /// Segment id of the face.
    pub segment: u32,
    /// Unit tangent along the field's major axis (densest spacing).
    pub major_axis: [f32; 3],
    /// Rank of the sample in its sequence.
    pub index: u32,
    /// Barycentric coordinates of corners 1 and 2 of `face`.
    pub bary: [f32; 2],
    /// Expected spacing along the major and the minor axis (world units).
    pub spacing: [f32; 2],
}

// `StrataSample` is cast to `Sample`: the same size, alignment and field offsets.
const _: () = {
    assert!(size_of::<StrataSample>() == 64 && size_of::<Sample>() == 64);
    assert!(align_of::<StrataSample>() == align_of::<Sample>());
    assert!(offset_of!(StrataSample, face) == offset_of!(Sample, face));
    assert!(offset_of!(StrataSample, normal) == offset_of!(Sample, normal));
    assert!(offset_of!(StrataSample, segment) == offset_of!(Sample, segment));
    assert!(offset_of!(StrataSample, major_axis) == offset_of!(Sample, major_axis));
    assert!(offset_of!(StrataSample, index) == offset_of!(Sample, index));
    assert!(offset_of!(StrataSample, bary) == offset_of!(Sample, bary));
    assert!(offset_of!(StrataSample, spacing) == offset_of!(Sample, spacing));
};

/// `StrataSampleRequest::mode`: `count` samples stratified for exactly that count
/// (the engine's `sample_into`).
pub const STRATA_STRATIFIED: u32 = 0;
/// `StrataSampleRequest::mode`: ranks `first_rank..first_rank + count` of the seed's
/// progressive sequence (fewer samples are a prefix of more; `progressive_into`).
pub const STRATA_PROGRESSIVE: u32 = 1;

/// What to draw, for `strata_sample`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StrataSampleRequest {
    /// `sizeof(StrataSampleRequest)`.
    pub struct_size: u32,
    /// `STRATA_STRATIFIED` or `STRATA_PROGRESSIVE`.
    pub mode: u32,
    /// Samples to draw (0 writes nothing).
    pub count: usize,
    /// The seed: the same seed gives the same samples.
    pub seed: u64,
    /// Progressive mode: the first rank drawn (`first_rank + count` at most 2^32).
    pub first_rank: u32,
}

/// Where `strata_sample` writes: each non-null array receives `count` entries and
/// must hold `capacity` (at least `count`). At least one array must be given.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct StrataSampleOutput {
    /// `sizeof(StrataSampleOutput)`.
    pub struct_size: u32,
    /// Entries each non-null array holds (in samples, not floats).
    pub capacity: usize,
    /// 64-byte records, or null.
    pub records: *mut StrataSample,
    /// 3 floats per sample (x, y, z), or null.
    pub positions: *mut f32,
    /// 3 floats per sample, or null.
    pub normals: *mut f32,
    /// 3 floats per sample, or null.
    pub major_axes: *mut f32,
    /// 1 `uint32_t` per sample, or null.
    pub face_ids: *mut u32,
    /// 2 floats per sample (corners 1 and 2), or null.
    pub barycentrics: *mut f32,
    /// 2 floats per sample (major, minor), or null.
    pub spacings: *mut f32,
}

/// The separate arrays of one request, checked.
struct Arrays<'a> {
    positions: &'a mut [f32],
    normals: &'a mut [f32],
    major_axes: &'a mut [f32],
    face_ids: &'a mut [u32],
    barycentrics: &'a mut [f32],
    spacings: &'a mut [f32],
}

impl Arrays<'_> {
    fn any(&self) -> bool {
        !(self.positions.is_empty()
            && self.normals.is_empty()
            && self.major_axes.is_empty()
            && self.face_ids.is_empty()
            && self.barycentrics.is_empty()
            && self.spacings.is_empty())
    }

    /// Copies `samples` into every array given.
    fn fill(&mut self, samples: &[Sample]) {
        let put = |dst: &mut [f32], width: usize, get: &dyn Fn(&Sample, usize) -> f32| {
            for (chunk, s) in dst.chunks_exact_mut(width).zip(samples) {
                for (i, slot) in chunk.iter_mut().enumerate() {
                    *slot = get(s, i);
                }
            }
        };
        put(self.positions, 3, &|s, i| s.position[i]);
        put(self.normals, 3, &|s, i| s.normal[i]);
        put(self.major_axes, 3, &|s, i| s.major_axis[i]);
        put(self.barycentrics, 2, &|s, i| s.bary[i]);
        put(self.spacings, 2, &|s, i| s.spacing[i]);
        for (slot, s) in self.face_ids.iter_mut().zip(samples) {
            *slot = s.face;
        }
    }
}

/// `count` entries of `width` values in `ptr` (empty when null).
fn array<'a, T>(ptr: *mut T, count: usize, width: usize, what: &str) -> Outcome<&'a mut [T]> {
    if ptr.is_null() {
        return Ok(&mut []);
    }
    slice_mut(ptr, count * width, what)
}

fn draw(sampler: &Sampler, request: &StrataSampleRequest, out: &mut [Sample]) {
    match request.mode {
        STRATA_PROGRESSIVE => sampler.progressive_into(request.seed, request.first_rank, out),
        _ => sampler.sample_into(request.seed, out),
    }
}

fn check_request(request: &StrataSampleRequest, output: &StrataSampleOutput) -> Outcome {
    check_struct_size(
        request.struct_size,
        size_of::<StrataSampleRequest>(),
        "StrataSampleRequest",
    )?;
    check_struct_size(
        output.struct_size,
        size_of::<StrataSampleOutput>(),
        "StrataSampleOutput",
    )?;
    let invalid = |m: String| Err(Failure::new(StrataStatus::InvalidArgument, m));
    match request.mode {
        STRATA_STRATIFIED => {}
        STRATA_PROGRESSIVE => {
            let end = u64::from(request.first_rank) + request.count as u64;
            if end > 1 << 32 {
                return invalid(format!(
                    "progressive ranks {}..{end} pass the sequence's 2^32",
                    request.first_rank
                ));
            }
        }
        other => {
            return invalid(format!(
                "mode is {other}, expected STRATA_STRATIFIED or STRATA_PROGRESSIVE"
            ));
        }
    }
    if output.capacity < request.count {
        return invalid(format!(
            "output capacity is {} samples, the request asks for {}",
            output.capacity, request.count
        ));
    }
    // Widths up to 16 floats per sample stay within usize for any count a request
    // can hold in memory; larger counts are refused here rather than overflowing.
    if request.count > usize::MAX / 16 {
        return invalid(format!("count {} is too large", request.count));
    }
    Ok(())
}

fn sample(
    handle: &StrataSampler,
    request: &StrataSampleRequest,
    output: &StrataSampleOutput,
) -> Outcome {
    check_request(request, output)?;
    let n = request.count;
    let mut arrays = Arrays {
        positions: array(output.positions, n, 3, "positions")?,
        normals: array(output.normals, n, 3, "normals")?,
        major_axes: array(output.major_axes, n, 3, "major_axes")?,
        face_ids: array(output.face_ids, n, 1, "face_ids")?,
        barycentrics: array(output.barycentrics, n, 2, "barycentrics")?,
        spacings: array(output.spacings, n, 2, "spacings")?,
    };
    if output.records.is_null() && !arrays.any() {
        return Err(Failure::new(
            StrataStatus::NullPointer,
            "output: every array is null (give records or at least one array)",
        ));
    }
    if n == 0 {
        return Ok(());
    }
    if !output.records.is_null() {
        let records = slice_mut(output.records.cast::<Sample>(), n, "records")?;
        draw(&handle.sampler, request, records);
        arrays.fill(records);
        return Ok(());
    }
    let mut scratch = handle.scratch.lock().unwrap_or_else(|e| e.into_inner());
    if scratch.len() < n {
        scratch.resize(n, Sample::default());
    }
    let records = &mut scratch[..n];
    draw(&handle.sampler, request, records);
    arrays.fill(records);
    Ok(())
}

/// Draws `request.count` samples into the arrays of `output` (see
/// `StrataSampleOutput`). Stratified samples equal the engine's `sample_into` for the
/// same sampler, count and seed bit for bit; progressive ones its `progressive_into`.
/// No allocation once the sampler's scratch has grown to the count (none at all
/// when `records` is given).
///
/// # Safety
/// `sampler` is a handle from this library; `request` and `output` point to valid
/// structs whose non-null arrays hold `output->capacity` entries each and overlap
/// nothing else given.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn strata_sample(
    sampler: *const StrataSampler,
    request: *const StrataSampleRequest,
    output: *const StrataSampleOutput,
) -> StrataStatus {
    guard(|| {
        let handle = borrow(sampler, "sampler")?;
        let request = &slice(request, 1, "request")?[0];
        let output = &slice(output, 1, "output")?[0];
        sample(handle, request, output)
    })
}

/// The sampler's mesh face count and total density measure (either out-pointer may
/// be null).
///
/// # Safety
/// `sampler` is a handle from this library; non-null out-pointers are writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn strata_sampler_info(
    sampler: *const StrataSampler,
    faces: *mut usize,
    total_measure: *mut f64,
) -> StrataStatus {
    guard(|| {
        let handle = borrow(sampler, "sampler")?;
        if !faces.is_null() {
            crate::handle::write_out(faces, handle.sampler.mesh().face_count(), "faces")?;
        }
        if !total_measure.is_null() {
            let measure = handle.sampler.total_measure();
            crate::handle::write_out(total_measure, measure, "total_measure")?;
        }
        Ok(())
    })
}

/// Frees a sampler (null: nothing); see `strata_mesh_free`.
///
/// # Safety
/// `sampler` is null or a handle from this library, used by no other call now.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn strata_sampler_free(sampler: *mut StrataSampler) -> StrataStatus {
    guard(|| release(sampler, "sampler"))
}
