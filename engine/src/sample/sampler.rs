//! The per-frame sampler: maps stratified values through segment curves to samples.

use std::sync::Arc;

use rayon::prelude::*;

use super::chains::link_chains;
use super::faces::{FaceTensors, Staged, expand_staged, face_record};
use super::leaves::{advance, boundary_levels};
use super::stratified::{Allocation, stratified_value_keyed};
// `SegmentSampling` lives below both this module and `chains.rs`; `sample/mod.rs`
// re-exports it from here.
pub use super::types::SegmentSampling;
use super::types::{Sample, SampleSite};
#[cfg(target_arch = "x86_64")]
use crate::cpu::Level;
use crate::curve::{DomainPoint, LeafScratch};
use crate::field::TensorField;
use crate::mesh::TriMesh;

/// Samples are produced in fixed chunks of this many outputs, each chunk on one rayon
/// task; the chunking, not the thread count, decides the work split.
pub(super) const CHUNK: usize = 4096;

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
    /// The field has a tensor count other than the mesh's vertex count.
    #[error("the field has {tensors} tensors, but the mesh has {vertices} vertices")]
    FieldMismatch {
        /// Tensors in the field.
        tensors: usize,
        /// Vertices of the mesh.
        vertices: usize,
    },
    /// Chains given to [`Sampler::with_chains`] do not hold every segment exactly once.
    #[error("chains must hold each of the {segments} segments exactly once (segment {segment})")]
    BadChains {
        /// Number of segments.
        segments: usize,
        /// A segment missing, repeated or out of range.
        segment: u32,
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
    /// The field's corner tensors of every face in the face's frame.
    face_tensors: FaceTensors,
    pub(super) segments: Vec<SegmentSampling>,
    pub(super) total_measure: f64,
    /// Segments one by one: `0..t` as groups of one (order, offsets, measures).
    singles: Groups,
    /// Chains of neighbouring segments (section 6.2), used when `t / N >= 1/3`.
    pub(super) chains: Groups,
    /// The measure before each segment of `chains.order` (and the total at the end):
    /// the progressive sequence runs over the curves concatenated in chain order.
    pub(super) chain_cumulative: Vec<f64>,
    /// Per segment, its position in `chains.order`.
    pub(super) chain_slot: Vec<u32>,
}

/// One sampling request as every chunk of it sees it, with one rayon task's scratch.
#[derive(Clone)]
struct Request<'a> {
    /// Segments one by one, or chains.
    groups: &'a Groups,
    seed: u64,
    /// Samples requested in all.
    n: u64,
    /// `sqrt(M / n)`: the spacing scale written into samples.
    scale: f64,
    /// Made once per task, not per chunk (a few kilobytes to initialise); the samples
    /// do not depend on what it holds (see `LeafScratch`).
    scratch: LeafScratch<'a>,
}

/// Groups of segments sampled with one stratified sequence each, in CSR form.
#[derive(Clone, Debug, Default)]
pub(super) struct Groups {
    pub(super) order: Vec<u32>,
    offsets: Vec<u32>,
    measures: Vec<f64>,
}

impl Groups {
    fn new(groups: &[Vec<u32>], segments: &[SegmentSampling]) -> Self {
        let mut g = Groups {
            offsets: vec![0],
            ..Default::default()
        };
        for group in groups {
            g.order.extend_from_slice(group);
            g.offsets.push(g.order.len() as u32);
            g.measures.push(
                group
                    .iter()
                    .map(|&i| segments[i as usize].curve.measure())
                    .sum(),
            );
        }
        g
    }

    fn len(&self) -> usize {
        self.measures.len()
    }

    pub(super) fn members(&self, i: usize) -> &[u32] {
        &self.order[self.offsets[i] as usize..self.offsets[i + 1] as usize]
    }
}

impl Sampler {
    /// Builds a sampler over `segments` of `mesh` with `field`.
    pub fn new(
        mesh: Arc<TriMesh>,
        field: Arc<TensorField>,
        segments: Vec<SegmentSampling>,
    ) -> Result<Self, SampleError> {
        Self::build(mesh, field, segments, None)
    }

    /// As [`new`](Self::new), with the chains given (segment indices, every segment in
    /// exactly one chain) instead of linked anew: for a caller that changed only the
    /// cells of the same segments (chains follow the segments' adjacency and measures,
    /// which cell refinement leaves as they were), such as the ECS engine after a new
    /// omega.
    pub fn with_chains(
        mesh: Arc<TriMesh>,
        field: Arc<TensorField>,
        segments: Vec<SegmentSampling>,
        chains: &[Vec<u32>],
    ) -> Result<Self, SampleError> {
        let mut seen = vec![false; segments.len()];
        for &i in chains.iter().flatten() {
            match seen.get_mut(i as usize) {
                Some(s) if !*s => *s = true,
                _ => {
                    return Err(SampleError::BadChains {
                        segments: segments.len(),
                        segment: i,
                    });
                }
            }
        }
        if let Some(missing) = seen.iter().position(|s| !s) {
            return Err(SampleError::BadChains {
                segments: segments.len(),
                segment: missing as u32,
            });
        }
        Self::build(mesh, field, segments, Some(chains))
    }

    fn build(
        mesh: Arc<TriMesh>,
        field: Arc<TensorField>,
        segments: Vec<SegmentSampling>,
        chains: Option<&[Vec<u32>]>,
    ) -> Result<Self, SampleError> {
        if field.tensors().len() != mesh.vertex_count() {
            return Err(SampleError::FieldMismatch {
                tensors: field.tensors().len(),
                vertices: mesh.vertex_count(),
            });
        }
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
        let ones: Vec<Vec<u32>> = (0..segments.len() as u32).map(|i| vec![i]).collect();
        let singles = Groups::new(&ones, &segments);
        let chains = match chains {
            Some(c) => Groups::new(c, &segments),
            None => Groups::new(&link_chains(&mesh, &segments), &segments),
        };
        let face_tensors = FaceTensors::new(&mesh, &field);
        let mut chain_cumulative = Vec::with_capacity(segments.len() + 1);
        chain_cumulative.push(0.0);
        for &i in &chains.order {
            let before = chain_cumulative[chain_cumulative.len() - 1];
            chain_cumulative.push(before + segments[i as usize].curve.measure());
        }
        let mut chain_slot = vec![0u32; segments.len()];
        for (slot, &i) in chains.order.iter().enumerate() {
            chain_slot[i as usize] = slot as u32;
        }
        Ok(Self {
            mesh,
            field,
            face_tensors,
            segments,
            total_measure,
            singles,
            chains,
            chain_cumulative,
            chain_slot,
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

    /// Per mesh face, the field's tensor at each corner restricted to the face's frame
    /// `e1 = (p1 - p0) / |p1 - p0|`, `e2 = n x e1` (`n` the face normal): entries
    /// `[a, b, c]` of `[[a, b], [b, c]]` for corner 0, then 1, then 2. What the record
    /// interpolates (linearly in barycentric coordinates) and decomposes per sample;
    /// for callers that expand [`SampleSite`]s themselves, such as a GPU pass.
    pub fn face_tensor_corners(&self) -> &[[f32; 9]] {
        self.face_tensors.corners()
    }

    /// Memory held by the preprocessed data in bytes: every segment's cells, domain
    /// triangles and face map, the chain tables and the per-face tensor table (the mesh
    /// and the field are inputs, shared, and not counted).
    pub fn heap_bytes(&self) -> usize {
        let groups = |g: &Groups| {
            g.order.capacity() * 4 + g.offsets.capacity() * 4 + g.measures.capacity() * 8
        };
        self.segments
            .iter()
            .map(|s| s.curve.heap_bytes() + s.faces.capacity() * 4)
            .sum::<usize>()
            + self.segments.capacity() * std::mem::size_of::<SegmentSampling>()
            + groups(&self.singles)
            + groups(&self.chains)
            + self.chain_cumulative.capacity() * 8
            + self.chain_slot.capacity() * 4
            + self.face_tensors.heap_bytes()
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
        let linked = self.uses_chains(out.len());
        self.sample_into_linked(seed, out, linked);
    }

    /// As [`sample_into`](Self::sample_into), choosing explicitly whether segments are
    /// linked into chains (for experiments such as the paper's section 7.3.3).
    pub fn sample_into_linked(&self, seed: u64, out: &mut [Sample], linked: bool) {
        self.fill(seed, out.len() as u64, 0, out, linked);
    }

    /// As [`sample_into`](Self::sample_into), writing only where each sample lies
    /// ([`SampleSite`]: face, segment, barycentric coordinates; 16 bytes instead of 64):
    /// the same samples, bit for bit in those fields, without interpolating position,
    /// normal and field. For callers that expand samples later or elsewhere (a vertex
    /// or compute shader, or [`record`](Self::record)), and to time the curve and point
    /// location without the record.
    pub fn sample_sites_into(&self, seed: u64, out: &mut [SampleSite]) {
        let linked = self.uses_chains(out.len());
        self.fill(seed, out.len() as u64, 0, out, linked);
    }

    /// Fills `out` with the samples `start..start + out.len()` of an `n`-sample
    /// stratified request for `seed`: the same bits as those entries of
    /// [`sample_into`](Self::sample_into) on `n` outputs, so that a large request can be
    /// drawn (and written) a block at a time in bounded memory. Sample `k` depends only
    /// on `(n, seed, k)`, never on the blocks or the thread count.
    ///
    /// ```
    /// use std::sync::Arc;
    /// use strata_engine::{field::FieldSpec, mesh::shapes, surface};
    /// let spec = FieldSpec::Constant { direction: [1.0, 0.0, 0.0], anisotropy: 2.0, density: 1.0 };
    /// let torus = Arc::new(shapes::torus(1.0, 0.4, 12)?);
    /// let field = Arc::new(spec.build(&torus)?);
    /// let pre = surface::Preprocessed::build(torus, field, &Default::default())?;
    /// let whole = pre.sampler.sample(1000, 7);
    /// let mut block = vec![Default::default(); 300];
    /// pre.sampler.sample_range_into(7, 1000, 600, &mut block);
    /// assert_eq!(block[..], whole[600..900]);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    ///
    /// Panics if `start + out.len()` exceeds `n`.
    pub fn sample_range_into(&self, seed: u64, n: u64, start: u64, out: &mut [Sample]) {
        let end = start.checked_add(out.len() as u64);
        assert!(
            end.is_some_and(|end| end <= n),
            "samples {start}..+{} of a {n}-sample request",
            out.len()
        );
        self.fill(seed, n, start, out, self.uses_chains_for(n));
    }

    /// Fills `out` with the records `start..start + out.len()` of an `n`-sample
    /// request (`start + out.len() <= n`).
    fn fill<T: Record>(&self, seed: u64, n: u64, start: u64, out: &mut [T], linked: bool) {
        if out.is_empty() {
            return;
        }
        let req = self.request(seed, n, linked);
        out.par_chunks_mut(CHUNK).enumerate().for_each_init(
            || req.clone(),
            |req, (chunk, dst)| {
                self.fill_chunk(req, start + (chunk * CHUNK) as u64, dst);
            },
        );
    }

    /// What every chunk of an `n`-sample request for `seed` shares.
    fn request(&self, seed: u64, n: u64, linked: bool) -> Request<'_> {
        Request {
            groups: if linked { &self.chains } else { &self.singles },
            seed,
            n,
            scale: (self.total_measure / n as f64).sqrt(),
            scratch: LeafScratch::default(),
        }
    }

    /// Fills the outputs `start..start + dst.len()` of an `n`-sample request, with the
    /// code compiled for x86-64-v3 (AVX2, FMA, BMI) where the CPU has it: the same
    /// operations, so the same bits (no multiply-add is fused without an explicit
    /// `mul_add`, which this path does not use), in about 10% fewer instructions
    /// (three-operand encodings, fewer register moves). Never inlined: one symbol to
    /// profile the sampling loop by (`valgrind --toggle-collect`), whichever path runs.
    #[inline(never)]
    fn fill_chunk<'s, T: Record>(&'s self, req: &mut Request<'s>, start: u64, dst: &mut [T]) {
        #[cfg(target_arch = "x86_64")]
        if Level::detected() >= Level::V3 {
            // SAFETY: the CPU has every feature of `Level::V3`, which is what
            // `fill_chunk_v3` enables.
            #[allow(unsafe_code)]
            unsafe {
                self.fill_chunk_v3(req, start, dst);
            }
            return;
        }
        self.fill_chunk_body(req, start, dst);
    }

    /// [`fill_chunk_body`](Self::fill_chunk_body) compiled with the x86-64-v3 features
    /// (exactly `Level::V3`'s, see `crate::cpu`).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx,avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
    fn fill_chunk_v3<'s, T: Record>(&'s self, req: &mut Request<'s>, start: u64, dst: &mut [T]) {
        self.fill_chunk_body(req, start, dst);
    }

    /// The records of `dst` in two passes: the per-sample loop
    /// ([`place_chunk`](Self::place_chunk)) writes what [`Record::Placed`] says into
    /// the same memory, then [`Record::finish`] completes the records (for full
    /// samples, in a second loop over the chunk while it is in cache). Always inlined,
    /// so that each caller's target features apply to all of it.
    #[inline(always)]
    fn fill_chunk_body<'s, T: Record>(&'s self, req: &mut Request<'s>, start: u64, dst: &mut [T]) {
        self.place_chunk(req, start, T::placed(dst));
        T::finish(self, dst, start, req.scale);
    }

    /// Section 6.2: segments are sampled one by one unless they are many relative to
    /// the samples (t / N >= 1/3), where rounding per segment would show; then chains
    /// of neighbouring segments are sampled, each with one stratified sequence.
    /// Always inlined, so that each caller's target features apply to all of it.
    #[inline(always)]
    fn place_chunk<'s, T: Record>(&'s self, req: &mut Request<'s>, start: u64, dst: &mut [T]) {
        let (groups, seed, n, scale) = (req.groups, req.seed, req.n, req.scale);
        let scratch = &mut req.scratch;
        // Recompute the allocation up to this chunk (O(groups), no allocation).
        let mut first = 0u64;
        let end = start + dst.len() as u64;
        for (i, count) in Allocation::new(n, groups.measures.iter().copied()) {
            let (grp_lo, grp_hi) = (first, first + count);
            first = grp_hi;
            let lo = grp_lo.max(start);
            let hi = grp_hi.min(end);
            if lo >= hi {
                if grp_lo >= end {
                    break;
                }
                continue;
            }
            let members = groups.members(i);
            let group_measure = groups.measures[i];
            // Position in the group: member index and the measure before it.
            let mut member = 0usize;
            let mut before = 0.0f64;
            let mut leaf = 0usize;
            let mut levels =
                self.leaf_levels(&self.segments[members[0] as usize], count, group_measure);
            let key = crate::rng::stream_key(seed, i as u64);
            // Samples per unit of measure in this group.
            let per_sample = count as f64 / group_measure;
            let value = |g: u64| stratified_value_keyed(key, g - grp_lo, count) * group_measure;
            let mut g = lo;
            let mut m = value(g);
            // One pass of the outer loop per run of values in one leaf.
            'group: loop {
                // Move to the member holding m (values increase along the group).
                while member + 1 < members.len()
                    && m >= before + self.segments[members[member] as usize].curve.measure()
                {
                    before += self.segments[members[member] as usize].curve.measure();
                    member += 1;
                    leaf = 0;
                    levels = self.leaf_levels(
                        &self.segments[members[member] as usize],
                        count,
                        group_measure,
                    );
                }
                let seg = &self.segments[members[member] as usize];
                let curve = &seg.curve;
                let cum = curve.cumulative();
                let top = curve.measure() * (1.0 - f64::EPSILON);
                // The member's end, where the next member begins (none after the last).
                let member_end = if member + 1 < members.len() {
                    before + curve.measure()
                } else {
                    f64::INFINITY
                };
                let ml = (m - before).clamp(0.0, top);
                leaf = advance(cum, leaf, ml);
                let w = &cum[leaf..leaf + 2];
                let (w0, w1) = (w[0], w[1]);
                if curve.leaf_is_full(leaf) {
                    // Values in this leaf: the leaf's data is read once for all. `ml`
                    // is carried from the exit test below to the next point.
                    let view = curve.full_leaf(leaf, levels);
                    let mut ml = ml;
                    loop {
                        let p = view.point(curve, (ml - w0) / (w1 - w0));
                        dst[(g - start) as usize] = T::make(self, seg, &p, g as u32, scale);
                        g += 1;
                        if g >= hi {
                            break 'group;
                        }
                        m = value(g);
                        ml = (m - before).clamp(0.0, top);
                        if ml >= w1 || m >= member_end {
                            break;
                        }
                    }
                } else {
                    let levels = boundary_levels((w1 - w0) * per_sample);
                    let p = curve.point_in_leaf_with(leaf, (ml - w0) / (w1 - w0), levels, scratch);
                    dst[(g - start) as usize] = T::make(self, seg, &p, g as u32, scale);
                    g += 1;
                    if g >= hi {
                        break 'group;
                    }
                    m = value(g);
                }
            }
        }
    }

    /// [`sample_into`](Self::sample_into) on the portable path only (no x86-64-v3
    /// code), to test that both paths give the same bits.
    #[cfg(test)]
    fn sample_into_portable(&self, seed: u64, out: &mut [Sample]) {
        let mut req = self.request(seed, out.len() as u64, self.uses_chains(out.len()));
        for (chunk, dst) in out.chunks_mut(CHUNK).enumerate() {
            self.fill_chunk_body(&mut req, (chunk * CHUNK) as u64, dst);
        }
    }

    /// Whether a request for `n` samples links segments into chains (t / N >= 1/3).
    pub fn uses_chains(&self, n: usize) -> bool {
        self.uses_chains_for(n as u64)
    }

    /// [`uses_chains`](Self::uses_chains) for a count of any size.
    fn uses_chains_for(&self, n: u64) -> bool {
        3 * self.segments.len() as u64 >= n && self.chains.len() < self.segments.len()
    }

    /// The chains of segment indices used when segments are many relative to samples.
    pub fn chains(&self) -> Vec<&[u32]> {
        self.chains_iter().collect()
    }

    /// The chains of [`chains`](Self::chains), in order, without collecting them (for
    /// per-frame checks that must not allocate).
    pub fn chains_iter(&self) -> impl ExactSizeIterator<Item = &[u32]> + '_ {
        (0..self.chains.len()).map(|i| self.chains.members(i))
    }

    /// Levels of the continuous map inside a leaf of `seg` for a group receiving
    /// `count` samples over `group_measure`: enough to separate the samples that share a
    /// leaf (log4 of their number), plus 5 (1024 sub-cells per sample).
    fn leaf_levels(&self, seg: &SegmentSampling, count: u64, group_measure: f64) -> u32 {
        let share = seg.curve.measure() / group_measure;
        let per_leaf = count as f64 * share / seg.curve.cell_count() as f64;
        (per_leaf.max(1.0).log2() * 0.5).ceil() as u32 + 5
    }

    /// The record [`sample_into`](Self::sample_into) writes for a sample at barycentric
    /// coordinates `bary` (corners 0, 1, 2) of mesh face `face`, with `segment` and
    /// `index` copied in and the spacings of an `n`-sample request; `None` for a face
    /// the mesh does not have or a non-finite coordinate (coordinates outside `[0, 1]`
    /// extrapolate linearly). For callers that keep samples compactly (face and
    /// barycentric coordinates) and expand them later, and to measure the cost of the
    /// record alone (the `sample_floor` bench).
    pub fn record(
        &self,
        face: u32,
        bary: [f64; 3],
        segment: u32,
        index: u32,
        n: usize,
    ) -> Option<Sample> {
        let valid = (face as usize) < self.mesh.face_count() && bary.iter().all(|x| x.is_finite());
        valid.then(|| {
            let scale = (self.total_measure / n.max(1) as f64).sqrt();
            self.record_scaled(face, bary, segment, index, scale)
        })
    }

    /// Turns a domain point of `seg` into a surface sample.
    #[inline(always)]
    fn make_sample(
        &self,
        seg: &SegmentSampling,
        p: &DomainPoint,
        index: u32,
        scale: f64,
    ) -> Sample {
        let face = seg.faces[p.triangle as usize];
        self.record_scaled(face, p.bary, seg.segment, index, scale)
    }

    /// [`record`](Self::record) with the spacing scale `sqrt(M / n)` given.
    #[inline(always)]
    fn record_scaled(
        &self,
        face: u32,
        bary: [f64; 3],
        segment: u32,
        index: u32,
        scale: f64,
    ) -> Sample {
        face_record(
            &self.mesh,
            &self.face_tensors,
            face,
            bary,
            segment,
            index,
            scale,
        )
    }
}

/// A record the per-chunk loop writes for each sample: a full [`Sample`] or only its
/// [`SampleSite`] (one loop, compiled once per record type).
pub(super) trait Record: Copy + Send {
    /// What the per-sample loop of [`Sampler::fill_chunk_body`] writes for this record
    /// (the record itself, or a [`Staged`] place that [`finish`](Self::finish) expands
    /// in the same slot).
    type Placed: Record;

    /// The output buffer as the per-sample loop writes it (the same memory).
    fn placed(dst: &mut [Self]) -> &mut [Self::Placed];

    /// Turns what the per-sample loop left in `dst` (samples `start..`) into records.
    fn finish(sampler: &Sampler, dst: &mut [Self], start: u64, scale: f64);

    /// The record of domain point `p` of `seg`, sample `index` of a request whose
    /// spacing scale is `scale`.
    fn make(
        sampler: &Sampler,
        seg: &SegmentSampling,
        p: &DomainPoint,
        index: u32,
        scale: f64,
    ) -> Self;
}

impl Record for Sample {
    type Placed = Staged;

    #[inline(always)]
    fn placed(dst: &mut [Self]) -> &mut [Staged] {
        // The same size, and `Staged` has alignment 1: the cast always succeeds.
        bytemuck::cast_slice_mut(dst)
    }

    #[inline(always)]
    fn finish(sampler: &Sampler, dst: &mut [Self], start: u64, scale: f64) {
        expand_staged(&sampler.mesh, &sampler.face_tensors, dst, start, scale);
    }

    #[inline(always)]
    fn make(
        sampler: &Sampler,
        seg: &SegmentSampling,
        p: &DomainPoint,
        index: u32,
        scale: f64,
    ) -> Self {
        sampler.make_sample(seg, p, index, scale)
    }
}

impl Record for Staged {
    type Placed = Staged;

    #[inline(always)]
    fn placed(dst: &mut [Self]) -> &mut [Staged] {
        dst
    }

    #[inline(always)]
    fn finish(_: &Sampler, _: &mut [Self], _: u64, _: f64) {}

    #[inline(always)]
    fn make(_: &Sampler, seg: &SegmentSampling, p: &DomainPoint, _: u32, _: f64) -> Self {
        Staged::new(seg.faces[p.triangle as usize], seg.segment, p.bary)
    }
}

impl Record for SampleSite {
    type Placed = SampleSite;

    #[inline(always)]
    fn placed(dst: &mut [Self]) -> &mut [SampleSite] {
        dst
    }

    #[inline(always)]
    fn finish(_: &Sampler, _: &mut [Self], _: u64, _: f64) {}

    /// The fields of [`Sampler::make_sample`]'s record that say where the sample is,
    /// computed the same way.
    #[inline(always)]
    fn make(_: &Sampler, seg: &SegmentSampling, p: &DomainPoint, _: u32, _: f64) -> Self {
        let b = p.bary.map(|x| x as f32);
        SampleSite {
            face: seg.faces[p.triangle as usize],
            segment: seg.segment,
            bary: [b[1], b[2]],
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::fixtures::along_x_2to1;
    use crate::sample::leaves::advance;

    #[test]
    fn a_field_of_another_mesh_is_an_error_not_a_panic() {
        use crate::mesh::shapes;
        use std::sync::Arc;
        let spec = along_x_2to1();
        let mesh = Arc::new(shapes::plane(1.0, 4).expect("plane"));
        let field = Arc::new(spec.build(&mesh).expect("field"));
        let (good, _) = crate::planar::sampler(mesh.clone(), field, &Default::default())
            .expect("planar sampler");
        let other = shapes::plane(1.0, 8).expect("plane");
        let wrong = Arc::new(spec.build(&other).expect("field"));
        let err = super::Sampler::new(mesh.clone(), wrong, good.segments().to_vec())
            .expect_err("mismatched field");
        assert!(
            matches!(
                err,
                super::SampleError::FieldMismatch {
                    tensors: 81,
                    vertices: 25
                }
            ),
            "{err}"
        );
    }

    /// The torus fixture of `surface`, preprocessed with the default options.
    fn torus() -> crate::surface::Preprocessed {
        let (mesh, field) = crate::fixtures::torus_case();
        crate::surface::Preprocessed::build(mesh, field, &crate::surface::SurfaceOptions::default())
            .expect("preprocessed")
    }

    /// Issue 22: a request drawn in blocks of any size (here not multiples of the
    /// parallel chunk, and crossing segment and chain boundaries) is the whole request,
    /// bit for bit, with chains (few samples) and without.
    #[test]
    fn blocks_of_a_request_are_the_whole_request() {
        let pre = torus();
        let sampler = &pre.sampler;
        for n in [5u64, 5000, 20011] {
            let whole = sampler.sample(n as usize, 11);
            for block in [1usize, 7, 4095, 4097, 9000] {
                let mut out = vec![super::Sample::default(); block];
                let mut start = 0u64;
                while start < n {
                    let len = block.min((n - start) as usize);
                    sampler.sample_range_into(11, n, start, &mut out[..len]);
                    let s = start as usize;
                    assert!(
                        out[..len] == whole[s..s + len],
                        "n {n}, block {block}, start {start}"
                    );
                    start += len as u64;
                }
            }
        }
        let past = std::panic::catch_unwind(|| {
            sampler.sample_range_into(11, 10, 5, &mut [super::Sample::default(); 6]);
        });
        assert!(past.is_err(), "a range past the request is refused");
    }

    /// Sites are the samples' face, segment and barycentric coordinates, bit for bit,
    /// with chains (few samples) and without, and `record` expands a site back into its
    /// sample up to the rounding of the coordinates to `f32`.
    #[test]
    fn sites_are_the_samples_without_their_records() {
        let pre = torus();
        let sampler = &pre.sampler;
        assert!(sampler.uses_chains(5) && !sampler.uses_chains(5000));
        for n in [5usize, 5000, 20000] {
            let samples = sampler.sample(n, 3);
            let mut sites = vec![super::SampleSite::default(); n];
            sampler.sample_sites_into(3, &mut sites);
            for (k, (s, site)) in samples.iter().zip(&sites).enumerate() {
                assert_eq!(
                    (site.face, site.segment, site.bary),
                    (s.face, s.segment, s.bary),
                    "n {n}, sample {k}"
                );
                assert_eq!(site.barycentric(), s.barycentric());
                let bary = site.barycentric().map(f64::from);
                let r = sampler
                    .record(site.face, bary, site.segment, k as u32, n)
                    .expect("a face of the mesh");
                assert_eq!(r.index, s.index);
                let d = glam::Vec3::from(r.position).distance(glam::Vec3::from(s.position));
                assert!(d < 1e-5, "n {n}, sample {k}: expanded {d} away");
                for (a, b) in r.spacing.iter().zip(&s.spacing) {
                    assert!((a - b).abs() <= 1e-5 * b, "n {n}, sample {k}: {a} vs {b}");
                }
            }
        }
    }

    /// The x86-64-v3 path (taken where the CPU has it) and the portable one give the
    /// same bits: a fused multiply-add or a reordered sum on either path fails this.
    #[test]
    fn both_code_paths_give_the_same_samples() {
        let pre = torus();
        for n in [50usize, 5000, 20000] {
            let fast = pre.sampler.sample(n, 7);
            let mut portable = vec![super::Sample::default(); n];
            pre.sampler.sample_into_portable(7, &mut portable);
            assert!(fast == portable, "n {n}: the two paths differ");
        }
    }

    /// `record` rebuilds what `sample_into` wrote from the face and barycentric
    /// coordinates (up to their rounding to f32 in the record).
    #[test]
    fn records_rebuild_samples() {
        let pre = torus();
        let n = 3000;
        for s in pre.sampler.sample(n, 11) {
            let b = s.barycentric().map(f64::from);
            let r = pre
                .sampler
                .record(s.face, b, s.segment, s.index, n)
                .expect("a face of the mesh");
            assert_eq!((r.face, r.segment, r.index), (s.face, s.segment, s.index));
            for k in 0..3 {
                assert!((r.position[k] - s.position[k]).abs() < 1e-5, "{r:?} {s:?}");
                assert!((r.normal[k] - s.normal[k]).abs() < 1e-4, "{r:?} {s:?}");
            }
            for k in 0..2 {
                assert!(
                    (r.spacing[k] / s.spacing[k] - 1.0).abs() < 1e-4,
                    "{r:?} {s:?}"
                );
            }
        }
        let faces = pre.sampler.mesh().face_count() as u32;
        assert!(
            pre.sampler
                .record(faces, [1.0, 0.0, 0.0], 0, 0, n)
                .is_none()
        );
        assert!(
            pre.sampler
                .record(0, [f64::NAN, 0.5, 0.5], 0, 0, n)
                .is_none()
        );
    }

    /// The place of a sample: everything but the count-dependent spacing.
    fn place(s: &super::Sample) -> ([u32; 3], u32, u32, [u32; 2], u32) {
        (
            s.position.map(f32::to_bits),
            s.face,
            s.segment,
            s.bary.map(f32::to_bits),
            s.index,
        )
    }

    #[test]
    fn progressive_prefixes_nest_bit_for_bit() {
        let pre = torus();
        let sampler = &pre.sampler;
        let mut small = vec![super::Sample::default(); 10_000];
        let mut large = vec![super::Sample::default(); 10_100];
        sampler.progressive_into(7, 0, &mut small);
        sampler.progressive_into(7, 0, &mut large);
        for (a, b) in small.iter().zip(&large) {
            assert_eq!(place(a), place(b));
        }
        // Ranks drawn later on their own are the same samples.
        let mut later = vec![super::Sample::default(); 100];
        sampler.progressive_into(7, 10_000, &mut later);
        for (a, b) in later.iter().zip(&large[10_000..]) {
            assert_eq!(place(a), place(b));
        }
        assert!(large.iter().enumerate().all(|(k, s)| s.index == k as u32));
        // Sites are the same places.
        let mut sites = vec![super::SampleSite::default(); 10_100];
        sampler.progressive_sites_into(7, 0, &mut sites);
        for (site, s) in sites.iter().zip(&large) {
            assert_eq!((site.face, site.segment), (s.face, s.segment));
            assert_eq!(site.bary.map(f32::to_bits), s.bary.map(f32::to_bits));
        }
        // Another seed, other samples.
        let mut other = vec![super::Sample::default(); 100];
        sampler.progressive_into(8, 0, &mut other);
        assert!(other.iter().zip(&large).all(|(a, b)| place(a) != place(b)));
    }

    #[test]
    fn progressive_samples_do_not_depend_on_the_thread_count() {
        let pre = torus();
        let run = |threads: usize| {
            crate::on_threads(threads, || {
                let mut out = vec![super::Sample::default(); 20_000];
                pre.sampler.progressive_into(3, 0, &mut out);
                out.iter().map(place).collect::<Vec<_>>()
            })
        };
        assert_eq!(run(1), run(2));
    }

    #[test]
    fn power_of_two_prefixes_give_each_segment_its_share() {
        // One sample per 2^-m of the measure along the curves: a segment of share s
        // receives N s samples, give or take one at each of its two ends.
        let pre = torus();
        let sampler = &pre.sampler;
        let n = 1usize << 14;
        let mut out = vec![super::SampleSite::default(); n];
        sampler.progressive_sites_into(11, 0, &mut out);
        let segments = sampler.segments();
        assert!(segments.len() > 1, "{}", segments.len());
        for seg in segments {
            let count = out.iter().filter(|s| s.segment == seg.segment).count() as f64;
            let expected = n as f64 * seg.curve.measure() / sampler.total_measure();
            assert!(
                (count - expected).abs() <= 2.0,
                "segment {}: {count} against {expected}",
                seg.segment
            );
        }
    }

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

    proptest::proptest! {
        /// The first leaf at or after `start` whose end exceeds `m` (the last leaf if
        /// none), as a linear scan finds it, on cumulative sums with repeated values
        /// (empty leaves), for targets before, inside and past the range.
        #[test]
        fn advance_matches_a_linear_scan(
            widths in proptest::collection::vec(
                proptest::prop_oneof![proptest::strategy::Just(0.0), 0.0..2.0f64],
                1..400,
            ),
            start_frac in 0.0..1.0f64,
            m_frac in -0.1..1.1f64,
        ) {
            let mut cum = vec![0.0];
            for w in &widths {
                cum.push(cum.last().copied().unwrap_or(0.0) + w);
            }
            let last = cum.len() - 2;
            let start = ((start_frac * (last + 1) as f64) as usize).min(last);
            let m = m_frac * cum[last + 1];
            let want = (start..=last).find(|&l| cum[l + 1] > m).unwrap_or(last);
            proptest::prop_assert_eq!(advance(&cum, start, m), want);
        }
    }
}
