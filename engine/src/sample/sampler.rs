//! The per-frame sampler: maps stratified values through segment curves to samples.

use std::sync::Arc;

use rayon::prelude::*;

use super::faces::FaceRecord;
use super::stratified::{allocate, stratified_value};
use super::types::Sample;
use crate::curve::{DomainPoint, SegmentCurve};
use crate::field::TensorField;
use crate::mesh::TriMesh;

/// Samples are produced in fixed chunks of this many outputs, each chunk on one rayon
/// task; the chunking, not the thread count, decides the work split.
const CHUNK: usize = 4096;

/// One segment ready for sampling: its cells and the mesh face of each domain triangle.
#[derive(Clone, Debug)]
pub struct SegmentSampling {
    /// Segment id written into the samples.
    pub segment: u32,
    /// Mesh face of each triangle of the curve's domain.
    pub faces: Vec<u32>,
    /// The segment's adaptive Hilbert cells.
    pub curve: SegmentCurve,
}

/// Errors building a [`Sampler`].
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SampleError {
    /// There is nothing to sample.
    #[error("no segment with positive measure to sample")]
    Empty,
    /// A segment refers to a face the mesh does not have.
    #[error("segment {segment} refers to face {face}, but the mesh has {face_count} faces")]
    BadFace {
        /// Segment id.
        segment: u32,
        /// The face.
        face: u32,
        /// Mesh face count.
        face_count: usize,
    },
}

/// Draws any number of stratified samples from preprocessed segments.
///
/// Built once; [`sample_into`](Self::sample_into) then writes exactly `out.len()`
/// samples per call, in O(N + cells), without allocating. The same seed and count give
/// bit-identical samples whatever the number of threads.
#[derive(Clone, Debug)]
pub struct Sampler {
    mesh: Arc<TriMesh>,
    field: Arc<TensorField>,
    segments: Vec<SegmentSampling>,
    faces: Vec<FaceRecord>,
    total_measure: f64,
}

impl Sampler {
    /// Builds a sampler over `segments` of `mesh` with `field`.
    pub fn new(
        mesh: Arc<TriMesh>,
        field: Arc<TensorField>,
        segments: Vec<SegmentSampling>,
    ) -> Result<Self, SampleError> {
        for s in &segments {
            if let Some(&face) = s.faces.iter().find(|&&f| f as usize >= mesh.face_count()) {
                return Err(SampleError::BadFace {
                    segment: s.segment,
                    face,
                    face_count: mesh.face_count(),
                });
            }
        }
        let total_measure: f64 = segments.iter().map(|s| s.curve.measure()).sum();
        if !(total_measure > 0.0) {
            return Err(SampleError::Empty);
        }
        let faces = FaceRecord::build_all(&mesh, &field);
        Ok(Self {
            mesh,
            field,
            segments,
            faces,
            total_measure,
        })
    }

    /// Total measure: the integral of the density over all segments.
    pub fn total_measure(&self) -> f64 {
        self.total_measure
    }

    /// The segments.
    pub fn segments(&self) -> &[SegmentSampling] {
        &self.segments
    }

    /// The mesh.
    pub fn mesh(&self) -> &Arc<TriMesh> {
        &self.mesh
    }

    /// The field.
    pub fn field(&self) -> &Arc<TensorField> {
        &self.field
    }

    /// Memory held by the cells, in bytes (the mesh and field are shared).
    pub fn heap_bytes(&self) -> usize {
        self.segments
            .iter()
            .map(|s| s.curve.heap_bytes() + s.faces.capacity() * 4)
            .sum()
    }

    /// Returns `n` samples for `seed` in a new vector.
    pub fn sample(&self, n: usize, seed: u64) -> Vec<Sample> {
        let mut out = vec![Sample::default(); n];
        self.sample_into(seed, &mut out);
        out
    }

    /// Fills `out` with `out.len()` stratified samples for `seed`.
    ///
    /// Segment `s` receives `floor(N share_s + carry)` samples (section 6.2); inside it,
    /// value `k` of its stratified sequence is mapped through the cumulative measure to
    /// a leaf cell and along the continuous Hilbert curve to a point.
    pub fn sample_into(&self, seed: u64, out: &mut [Sample]) {
        let n = out.len() as u64;
        if n == 0 {
            return;
        }
        let scale = (self.total_measure / n as f64).sqrt();
        out.par_chunks_mut(CHUNK)
            .enumerate()
            .for_each(|(chunk, dst)| {
                let start = (chunk * CHUNK) as u64;
                self.fill_chunk(seed, n, start, scale, dst);
            });
    }

    /// Fills the outputs `start..start + dst.len()` of an `n`-sample request.
    fn fill_chunk(&self, seed: u64, n: u64, start: u64, scale: f64, dst: &mut [Sample]) {
        // Recompute the allocation up to this chunk (O(segments), no allocation).
        let mut first = 0u64;
        let end = start + dst.len() as u64;
        allocate(
            n,
            self.segments.iter().map(|s| s.curve.measure()),
            |i, count| {
                let (seg_lo, seg_hi) = (first, first + count);
                first = seg_hi;
                let lo = seg_lo.max(start);
                let hi = seg_hi.min(end);
                if lo >= hi {
                    return;
                }
                let seg = &self.segments[i];
                let curve = &seg.curve;
                let cum = curve.cumulative();
                let measure = curve.measure();
                // Levels of the continuous map inside a leaf: enough to separate the
                // samples that share a leaf (log4 of their number), plus 5 (1024
                // sub-cells per sample) to place them evenly.
                let per_leaf = count as f64 / curve.cell_count() as f64;
                let levels = (per_leaf.max(1.0).log2() * 0.5).ceil() as u32 + 5;
                let mut leaf = 0usize;
                for g in lo..hi {
                    let k = g - seg_lo;
                    let m = stratified_value(seed, seg.segment as u64, k, count) * measure;
                    leaf = advance(cum, leaf, m);
                    let local = (m - cum[leaf]) / (cum[leaf + 1] - cum[leaf]);
                    let p = curve.point_in_leaf_to(leaf, local, levels);
                    dst[(g - start) as usize] = self.make_sample(seg, &p, g as u32, scale);
                }
            },
        );
    }

    /// Turns a domain point of `seg` into a surface sample.
    #[inline]
    fn make_sample(
        &self,
        seg: &SegmentSampling,
        p: &DomainPoint,
        index: u32,
        scale: f64,
    ) -> Sample {
        let face = seg.faces[p.triangle as usize];
        let b = p.bary.map(|x| x as f32);
        let fp = self.faces[face as usize].at(b);
        let scale = scale as f32;
        let spacing = [
            scale / fp.l1.sqrt(),
            scale / fp.l2.max(f32::MIN_POSITIVE).sqrt(),
        ];
        Sample {
            position: fp.position.to_array(),
            face,
            normal: fp.normal.to_array(),
            segment: seg.segment,
            major_axis: fp.major.to_array(),
            index,
            bary: [b[1], b[2]],
            spacing,
        }
    }
}

/// The leaf holding cumulative measure `m`, searching forward from `leaf`: a few
/// linear steps (consecutive samples are usually in the same or the next leaf), then
/// a binary search over the rest.
#[inline]
fn advance(cum: &[f64], mut leaf: usize, m: f64) -> usize {
    let last = cum.len() - 2;
    for _ in 0..8 {
        if leaf >= last || cum[leaf + 1] > m {
            return leaf.min(last);
        }
        leaf += 1;
    }
    let rest = &cum[leaf + 1..];
    (leaf + rest.partition_point(|&c| c <= m)).min(last)
}

#[cfg(test)]
mod tests {
    use super::advance;

    #[test]
    fn advance_finds_the_leaf() {
        let cum = [0.0, 1.0, 1.5, 4.0, 4.1, 9.0];
        for (m, want) in [
            (0.0, 0),
            (0.99, 0),
            (1.0, 1),
            (3.9, 2),
            (4.05, 3),
            (8.99, 4),
        ] {
            assert_eq!(advance(&cum, 0, m), want, "m {m}");
        }
        // Long jumps use the binary search.
        let cum: Vec<f64> = (0..1000).map(|i| i as f64).collect();
        assert_eq!(advance(&cum, 3, 700.5), 700);
        assert_eq!(advance(&cum, 3, 5000.0), 998);
    }
}
