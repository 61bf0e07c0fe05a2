//! Preprocessing a curved surface for sampling: segmentation, parameterization with
//! splitting of invalid segments, and adaptive Hilbert cells per segment.
//!
//! Input: a mesh, a field and [`SurfaceOptions`]. Output: [`Preprocessed`], holding the
//! final segments, their parameterizations and a [`Sampler`] that draws any count.
//!
//! Splitting (paper section 5.2): a segment whose parameterization is invalid (flipped
//! or overlapping, or the mapped field off the u axis by more than `gamma` on average),
//! or that cannot be parameterized, is split in two by the random walk restricted to
//! it, seeded at its two most different directions, and both halves are parameterized
//! again. A split whose parts are not discs or are badly unbalanced (an outlier
//! direction next to a singularity seeds a region of a few faces) is redone from two
//! faces far apart, so a segment needs about log2 of its size rounds, not one per
//! outlier. Below `min_segment_faces` a segment is parameterized with an isotropic
//! field (flagged `isotropic_fallback`; it is sampled with the right density but
//! without anisotropy); a piece for which even that flips is halved again, down to
//! single triangles, which are always valid. So preprocessing always covers every
//! face.
//!
//! Cost: the segmentation, then one sparse factorization per parameterized segment
//! (segments in parallel with rayon), then the cells.

use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::DVec3;
use rayon::prelude::*;

use crate::curve::{CurveDomain, CurveError, CurveOptions, SegmentCurve};
use crate::field::{FieldError, TensorField};
use crate::mesh::{NONE, TriMesh};
use crate::param::{ParamError, ParamOptions, SegmentParam, parameterize_all};
use crate::sample::{SampleError, Sampler, SegmentSampling};
use crate::segment::{
    SegmentError, SegmentOptions, Segmentation, connected_parts, face_frames, random_walk, segment,
    walk_weights,
};

/// Settings of the whole preprocessing.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default, deny_unknown_fields))]
pub struct SurfaceOptions {
    /// Segmentation settings.
    pub segment: SegmentOptions,
    /// Parameterization settings (gamma, isotropy threshold).
    pub param: ParamOptions,
    /// Cell settings. `max_cell_share` is a share of the whole surface's measure here,
    /// so the number of cells does not grow with the number of segments.
    pub curve: CurveOptions,
    /// Segments with fewer faces are not split further (isotropic fallback instead).
    /// Range >= 1; default 16.
    pub min_segment_faces: usize,
    /// Which angle between the mapped field and the u axis must stay below `gamma`:
    /// the area-weighted mean over the segment's faces (section 5.2, the default) or
    /// the largest per-face angle (section 7.3.1's "no angle greater than gamma"),
    /// which splits more.
    pub angle_criterion: AngleCriterion,
}

/// The angle that the validity test compares with `gamma`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum AngleCriterion {
    /// Area-weighted mean angle over the segment (section 5.2).
    #[default]
    Mean,
    /// Largest per-face angle (section 7.3.1).
    Max,
}

impl Default for SurfaceOptions {
    fn default() -> Self {
        Self {
            segment: SegmentOptions::default(),
            param: ParamOptions::default(),
            curve: CurveOptions::default(),
            min_segment_faces: 16,
            angle_criterion: AngleCriterion::Mean,
        }
    }
}

impl SurfaceOptions {
    /// Checks the options that preprocessing reads before any work starts: the
    /// minimum segment size, the cell settings and the parameterization settings.
    pub fn validate(&self) -> Result<(), SurfaceError> {
        if self.min_segment_faces == 0 {
            return Err(SurfaceError::InvalidMinSegmentFaces);
        }
        self.curve
            .validate()
            .map_err(|source| SurfaceError::Curve { segment: 0, source })?;
        self.param.validate()?;
        Ok(())
    }
}

/// Errors of the surface preprocessing.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SurfaceError {
    /// Segmentation failed.
    #[error("segmentation: {0}")]
    Segment(#[from] SegmentError),
    /// A parameterization failed in a way splitting cannot fix.
    #[error("parameterization: {0}")]
    Param(#[from] ParamError),
    /// The isotropic fallback field could not be built.
    #[error("isotropic fallback field: {0}")]
    Field(#[from] FieldError),
    /// Cells could not be built for a segment.
    #[error("cells of segment {segment}: {source}")]
    Curve {
        /// Segment id.
        segment: usize,
        /// The cause.
        #[source]
        source: CurveError,
    },
    /// The sampler could not be built.
    #[error("sampler: {0}")]
    Sample(#[from] SampleError),
    /// `min_segment_faces` is 0.
    #[error("min_segment_faces must be at least 1")]
    InvalidMinSegmentFaces,
}

/// Counts describing what the preprocessing did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SurfaceReport {
    /// Segments after segmentation, before splitting.
    pub segments_before_split: usize,
    /// Final segments.
    pub segments: usize,
    /// Segments split because their parameterization was invalid.
    pub splits: usize,
    /// Final segments parameterized with the isotropic fallback.
    pub isotropic_segments: usize,
    /// Faces that ended as single-triangle segments (last resort).
    pub single_face_segments: usize,
    /// Total cells over all segments.
    pub cells: usize,
}

/// A surface ready to sample.
#[derive(Debug)]
pub struct Preprocessed {
    /// The segmentation (before splitting).
    pub segmentation: Segmentation,
    /// The final segments' parameterizations; segment `i` of the samples is `params[i]`.
    pub params: Vec<SegmentParam>,
    /// The per-frame sampler.
    pub sampler: Sampler,
    /// What happened.
    pub report: SurfaceReport,
    /// Wall time per stage, in order.
    pub stages: Vec<(&'static str, Duration)>,
}

/// A preprocessing stage starting or finishing, reported to a caller's callback (the
/// engine does not log; an application shows progress from these).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Progress {
    /// A stage starts.
    Start(&'static str),
    /// A stage finished after this long.
    Done(&'static str, Duration),
}

impl Preprocessed {
    /// Runs segmentation, parameterization (with splitting) and cell construction.
    pub fn build(
        mesh: Arc<TriMesh>,
        field: Arc<TensorField>,
        options: &SurfaceOptions,
    ) -> Result<Self, SurfaceError> {
        Self::build_with_progress(mesh, field, options, &|_| {})
    }

    /// As [`build`](Self::build), calling `progress` when each stage starts and ends
    /// (`"segmentation"`, `"parameterization"`, `"cells"`).
    pub fn build_with_progress(
        mesh: Arc<TriMesh>,
        field: Arc<TensorField>,
        options: &SurfaceOptions,
        progress: &dyn Fn(Progress),
    ) -> Result<Self, SurfaceError> {
        options.validate()?;
        let mut stages = Vec::new();
        let mut stage = |name: &'static str, t: Instant| {
            let d = t.elapsed();
            progress(Progress::Done(name, d));
            stages.push((name, d));
        };
        progress(Progress::Start("segmentation"));
        let t = Instant::now();
        let segmentation = segment(&mesh, &field, &options.segment)?;
        stage("segmentation", t);

        progress(Progress::Start("parameterization"));
        let t = Instant::now();
        let (params, mut report) =
            parameterize_with_splitting(&mesh, &field, &segmentation, options)?;
        report.segments_before_split = segmentation.segments.len();
        report.segments = params.len();
        stage("parameterization", t);

        progress(Progress::Start("cells"));
        let t = Instant::now();
        let segments = build_cells(&mesh, &field, &params, &options.curve)?;
        report.cells = segments.iter().map(|s| s.curve.cell_count()).sum();
        stage("cells", t);
        let sampler = Sampler::new(mesh, field, segments)?;
        Ok(Self {
            segmentation,
            params,
            sampler,
            report,
            stages,
        })
    }
}

impl Preprocessed {
    /// As [`build`](Self::build), but with a given segmentation instead of the random
    /// walk's (for controlled experiments: a fixed number of segments, a boundary of a
    /// chosen shape). Invalid segments are still split, so the final segments may be
    /// more than given. Build `segmentation` with [`segmentation_from_labels`].
    ///
    /// ```
    /// use std::sync::Arc;
    /// use strata_engine::{field::FieldSpec, mesh::shapes, surface};
    /// let mesh = Arc::new(shapes::plane(1.0, 8)?);
    /// let spec = FieldSpec::Constant { direction: [1.0, 0.0, 0.0], anisotropy: 1.0, density: 1.0 };
    /// let field = Arc::new(spec.build(&mesh)?);
    /// // Left and right halves.
    /// let labels: Vec<u32> = (0..mesh.face_count() as u32)
    ///     .map(|f| (mesh.face_positions(f)[0].x + mesh.face_positions(f)[1].x
    ///         + mesh.face_positions(f)[2].x > 1.5) as u32)
    ///     .collect();
    /// let seg = surface::segmentation_from_labels(&mesh, &labels);
    /// let pre = surface::Preprocessed::from_segmentation(mesh, field, seg, &Default::default())?;
    /// assert_eq!(pre.params.len(), 2);
    /// assert_eq!(pre.sampler.sample(100, 1).len(), 100);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn from_segmentation(
        mesh: Arc<TriMesh>,
        field: Arc<TensorField>,
        segmentation: Segmentation,
        options: &SurfaceOptions,
    ) -> Result<Self, SurfaceError> {
        options.validate()?;
        let t = Instant::now();
        let (params, mut report) =
            parameterize_with_splitting(&mesh, &field, &segmentation, options)?;
        report.segments_before_split = segmentation.segments.len();
        report.segments = params.len();
        let mut stages = vec![("parameterization", t.elapsed())];
        let t = Instant::now();
        let segments = build_cells(&mesh, &field, &params, &options.curve)?;
        report.cells = segments.iter().map(|s| s.curve.cell_count()).sum();
        stages.push(("cells", t.elapsed()));
        let sampler = Sampler::new(mesh, field, segments)?;
        Ok(Self {
            segmentation,
            params,
            sampler,
            report,
            stages,
        })
    }
}

/// A [`Segmentation`] from a segment label per face: one segment per connected part of
/// each label (so every segment is connected), numbered by lowest face, with its
/// boundary loops and Euler characteristic; no singularities and no cut edges.
pub fn segmentation_from_labels(mesh: &TriMesh, face_segment: &[u32]) -> Segmentation {
    let no_cut = vec![false; mesh.edge_count()];
    let parts = connected_parts(mesh, face_segment, &no_cut);
    let mut groups: std::collections::BTreeMap<u32, Vec<u32>> = Default::default();
    for (f, &p) in parts.iter().enumerate() {
        if p != NONE {
            groups.entry(p).or_default().push(f as u32);
        }
    }
    let mut faces: Vec<Vec<u32>> = groups.into_values().collect();
    faces.sort_by_key(|g| g[0]);
    let mut labels = vec![NONE; mesh.face_count()];
    let segments = faces
        .into_iter()
        .enumerate()
        .map(|(id, faces)| {
            for &f in &faces {
                labels[f as usize] = id as u32;
            }
            let top = crate::segment::patch_topology(mesh, &faces, &no_cut);
            crate::segment::Segment {
                faces,
                boundary_loops: top.boundary_loops,
                euler_characteristic: top.euler_characteristic,
                has_singular_face: false,
            }
        })
        .collect();
    Segmentation {
        face_segment: labels,
        segments,
        singularities: Vec::new(),
        cut_edges: Vec::new(),
    }
}

/// Parameterizes every segment of `segmentation`, splitting invalid ones (see the
/// module docs). Returns the final segments' parameterizations, ordered by their lowest
/// mesh face, and what happened (`segments_before_split` and `cells` are left 0).
pub fn parameterize_with_splitting(
    mesh: &TriMesh,
    field: &TensorField,
    segmentation: &Segmentation,
    options: &SurfaceOptions,
) -> Result<(Vec<SegmentParam>, SurfaceReport), SurfaceError> {
    let context = SplitContext::new(mesh, field, &segmentation.cut_edges, options);
    let results: Vec<Result<(Vec<SegmentParam>, SurfaceReport), SurfaceError>> = segmentation
        .segments
        .par_iter()
        .map(|s| parameterize_segment_with_splitting(mesh, field, &context, &s.faces, options))
        .collect();
    let mut report = SurfaceReport::default();
    let mut accepted: Vec<SegmentParam> = Vec::new();
    for result in results {
        let (params, r) = result?;
        report.splits += r.splits;
        report.isotropic_segments += r.isotropic_segments;
        report.single_face_segments += r.single_face_segments;
        accepted.extend(params);
    }
    // Deterministic order: by lowest mesh face.
    accepted.sort_by_key(lowest_face);
    Ok((accepted, report))
}

/// The lowest mesh face of a parameterized segment: the key that orders segments.
pub fn lowest_face(p: &SegmentParam) -> u32 {
    p.faces.iter().copied().min().unwrap_or(u32::MAX)
}

/// What splitting needs besides the segment: the cut edges as a per-edge mask, the
/// per-face field directions and the random walk's edge weights, computed once for
/// the whole mesh and shared by every segment (and the isotropic fallback field, made
/// on first use).
#[derive(Debug)]
pub struct SplitContext {
    cut: Vec<bool>,
    frames: crate::segment::FaceField,
    weights: Vec<f64>,
    isotropic: std::sync::OnceLock<TensorField>,
}

impl SplitContext {
    /// Prepares splitting on `mesh` with `field`, the walk not crossing `cut_edges`
    /// (the segmentation's cuts). Cost O(F).
    pub fn new(
        mesh: &TriMesh,
        field: &TensorField,
        cut_edges: &[u32],
        options: &SurfaceOptions,
    ) -> Self {
        let mut cut = vec![false; mesh.edge_count()];
        for &e in cut_edges {
            if let Some(c) = cut.get_mut(e as usize) {
                *c = true;
            }
        }
        let frames = face_frames(mesh, field);
        let weights = walk_weights(mesh, &frames, options.segment.sigma, &cut);
        Self {
            cut,
            frames,
            weights,
            isotropic: std::sync::OnceLock::new(),
        }
    }

    fn isotropic(&self, mesh: &TriMesh, field: &TensorField) -> Result<&TensorField, FieldError> {
        if let Some(iso) = self.isotropic.get() {
            return Ok(iso);
        }
        let iso = isotropic_copy(mesh, field)?;
        Ok(self.isotropic.get_or_init(|| iso))
    }
}

/// Parameterizes one segment (its `faces`), splitting it while invalid, as
/// [`parameterize_with_splitting`] does for every segment: the result for a segment
/// does not depend on the other segments, so a caller may redo only the segments that
/// changed. Returns the final pieces' parameterizations, ordered by their lowest face,
/// and the split counts.
///
/// ```
/// use strata_engine::{field::FieldSpec, mesh::shapes, segment::segment};
/// use strata_engine::surface::{parameterize_segment_with_splitting, SplitContext, SurfaceOptions};
/// let mesh = shapes::sphere(1.0, 4)?;
/// let field = FieldSpec::Constant { direction: [1.0, 0.0, 0.0], anisotropy: 2.0, density: 1.0 }
///     .build(&mesh)?;
/// let options = SurfaceOptions::default();
/// let seg = segment(&mesh, &field, &options.segment)?;
/// let context = SplitContext::new(&mesh, &field, &seg.cut_edges, &options);
/// let (pieces, _) = parameterize_segment_with_splitting(
///     &mesh, &field, &context, &seg.segments[0].faces, &options)?;
/// let faces: usize = pieces.iter().map(|p| p.faces.len()).sum();
/// assert_eq!(faces, seg.segments[0].faces.len());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn parameterize_segment_with_splitting(
    mesh: &TriMesh,
    field: &TensorField,
    context: &SplitContext,
    faces: &[u32],
    options: &SurfaceOptions,
) -> Result<(Vec<SegmentParam>, SurfaceReport), SurfaceError> {
    let cut = &context.cut;
    let mut report = SurfaceReport::default();
    let mut accepted: Vec<SegmentParam> = Vec::new();
    let mut pending: Vec<Vec<u32>> = vec![faces.to_vec()];
    let mut small: Vec<Vec<u32>> = Vec::new();
    while !pending.is_empty() {
        let results = parameterize_all(mesh, field, &pending, cut, &options.param);
        let mut to_split = Vec::new();
        for (faces, result) in pending.into_iter().zip(results) {
            match result {
                Ok(p) if p.report.valid && angle_ok(&p, options) => accepted.push(p),
                _ if faces.len() < options.min_segment_faces.max(2) => small.push(faces),
                _ => to_split.push(faces),
            }
        }
        report.splits += to_split.len();
        // Each split is one random walk over its segment: independent, so in parallel;
        // the halves are collected in order, so the result does not depend on threads.
        let halves: Vec<Vec<Vec<u32>>> = to_split
            .par_iter()
            .map(|faces| split_in_two(mesh, &context.frames, &context.weights, cut, faces))
            .collect::<Result<_, _>>()?;
        pending = halves.into_iter().flatten().collect();
    }
    // Isotropic fallback: the same density, no anisotropy. A piece whose fallback
    // parameterization still flips or overlaps (around a sharp cone, say) is halved
    // again; a single triangle is always valid.
    while !small.is_empty() {
        let iso = context.isotropic(mesh, field)?;
        let results = parameterize_all(mesh, iso, &small, cut, &options.param);
        let mut again = Vec::new();
        for (faces, result) in small.into_iter().zip(results) {
            match result {
                Ok(mut p) if faces.len() == 1 || (p.report.flipped == 0 && !p.report.overlaps) => {
                    p.report.isotropic_fallback = true;
                    if faces.len() == 1 {
                        report.single_face_segments += 1;
                    } else {
                        report.isotropic_segments += 1;
                    }
                    accepted.push(p);
                }
                Err(e) if faces.len() == 1 => return Err(e.into()),
                _ => again.extend(halve(mesh, cut, &faces)),
            }
        }
        small = again;
    }
    accepted.sort_by_key(lowest_face);
    Ok((accepted, report))
}

/// The optional stricter angle test (the mean is part of `report.valid` already).
fn angle_ok(p: &SegmentParam, options: &SurfaceOptions) -> bool {
    match options.angle_criterion {
        AngleCriterion::Mean => true,
        AngleCriterion::Max => {
            p.report.isotropic_fallback || p.report.max_angle_deg < options.param.gamma.to_degrees()
        }
    }
}

/// A split is accepted when every part is a disc (the parameterization needs one) and
/// the smallest part holds at least this share of the faces. Without the balance
/// test, seeds at outlier faces (next to a singularity, say) peel off a few faces per
/// round, often leaving a hole, and splitting a large segment takes hundreds of
/// rounds instead of about log2 of its size.
const MIN_SPLIT_SHARE: usize = 8;

/// Splits a segment in two by the random walk (section 5.2) and returns the connected
/// parts.
///
/// The walk is first seeded at the segment's two most different face directions (as
/// lines), as in the paper. If that split is unbalanced (a part under
/// 1/[`MIN_SPLIT_SHARE`] of the faces) or leaves a part that is not a disc, the walk is
/// seeded again at two faces far apart in the segment (a double sweep of
/// breadth-first search), which halves the segment; failing that too, the faces are
/// given to the nearer of those two seeds, and as a last resort halved by face order.
fn split_in_two(
    mesh: &TriMesh,
    frames: &crate::segment::FaceField,
    weights: &[f64],
    cut: &[bool],
    faces: &[u32],
) -> Result<Vec<Vec<u32>>, SurfaceError> {
    let [a, b] = most_different_faces(frames, faces);
    if a == b {
        return Ok(vec![faces.to_vec()]); // a single face: nothing to split
    }
    let mut mask = vec![false; mesh.face_count()];
    for &f in faces {
        mask[f as usize] = true;
    }
    let good = |parts: &[Vec<u32>]| {
        parts.len() > 1
            && parts
                .iter()
                .all(|p| p.len() * MIN_SPLIT_SHARE >= faces.len() && is_disc(mesh, p, cut))
    };
    let walk = |seeds: [u32; 2]| -> Result<Option<Vec<Vec<u32>>>, SurfaceError> {
        match random_walk(mesh, weights, &mask, &seeds) {
            Ok(labels) => Ok(Some(parts_of(mesh, faces, &labels, cut))),
            // Parts of the segment unreachable from both seeds (cut off by cut edges).
            Err(SegmentError::Unseeded { .. }) => Ok(None),
            Err(e) => Err(e.into()),
        }
    };
    let first = match walk([a, b])? {
        Some(parts) if good(&parts) => return Ok(parts),
        other => other,
    };
    let [far_a, far_b] = far_apart(mesh, &mask, cut, faces);
    if far_a != far_b
        && let Some(parts) = walk([far_a, far_b])?
        && good(&parts)
    {
        return Ok(parts);
    }
    let parts = halve(mesh, cut, faces);
    if good(&parts) {
        return Ok(parts);
    }
    // Keep the paper's split if it split at all (it makes progress).
    match first {
        Some(first) if first.len() > 1 => Ok(first),
        _ => Ok(parts),
    }
}

/// Two faces far apart in the patch `mask` (a double sweep of breadth-first search
/// from the lowest face of `faces`).
fn far_apart(mesh: &TriMesh, mask: &[bool], cut: &[bool], faces: &[u32]) -> [u32; 2] {
    let start = faces.iter().copied().min().unwrap_or(0);
    let (a, _) = hop_distances(mesh, mask, cut, start);
    let (b, _) = hop_distances(mesh, mask, cut, a);
    [a, b]
}

/// Splits `faces` (two or more) into the connected parts of the faces nearer (in
/// hops) to one or the other of two faces far apart; by face order if that does not
/// split them (faces unreachable from each other).
fn halve(mesh: &TriMesh, cut: &[bool], faces: &[u32]) -> Vec<Vec<u32>> {
    let mut mask = vec![false; mesh.face_count()];
    for &f in faces {
        mask[f as usize] = true;
    }
    let [a, b] = far_apart(mesh, &mask, cut, faces);
    if a != b {
        let (_, from_a) = hop_distances(mesh, &mask, cut, a);
        let (_, from_b) = hop_distances(mesh, &mask, cut, b);
        let labels = mask_labels(mesh, faces, |i| {
            let f = faces[i] as usize;
            (from_b[f] < from_a[f]) as u32
        });
        let parts = parts_of(mesh, faces, &labels, cut);
        if parts.len() > 1 {
            return parts;
        }
    }
    let half = faces.len() / 2;
    let labels = mask_labels(mesh, faces, |i| (i >= half) as u32);
    parts_of(mesh, faces, &labels, cut)
}

/// The face whose direction is farthest from the segment's mean line direction (mean
/// of `m m^T`), then the face farthest from that one (ties to the lower face id).
fn most_different_faces(frames: &crate::segment::FaceField, faces: &[u32]) -> [u32; 2] {
    let mut mean = glam::DMat3::ZERO;
    for &f in faces {
        let m = frames.major[f as usize];
        mean += crate::field::outer(m, m);
    }
    let axis = principal_axis(mean);
    let farthest = |from: DVec3| {
        faces
            .iter()
            .copied()
            .min_by(|&a, &b| {
                let da = frames.major[a as usize].dot(from).abs();
                let db = frames.major[b as usize].dot(from).abs();
                da.total_cmp(&db).then(a.cmp(&b))
            })
            .unwrap_or(faces[0])
    };
    let a = farthest(axis);
    let mut b = farthest(frames.major[a as usize]);
    if a == b {
        b = faces.iter().copied().find(|&f| f != a).unwrap_or(a);
    }
    [a, b]
}

/// Whether `faces`, cut open along `cut`, form a topological disc.
fn is_disc(mesh: &TriMesh, faces: &[u32], cut: &[bool]) -> bool {
    let top = crate::segment::patch_topology(mesh, faces, cut);
    top.euler_characteristic == 1 && top.boundary_loops.len() == 1
}

/// Breadth-first hop distances over the faces of `mask` (through manifold edges not
/// in `cut`) from `start`: the last face reached (farthest; ties to the first found)
/// and the distance per mesh face (`u32::MAX` where unreached).
fn hop_distances(mesh: &TriMesh, mask: &[bool], cut: &[bool], start: u32) -> (u32, Vec<u32>) {
    let mut dist = vec![u32::MAX; mesh.face_count()];
    let mut queue = std::collections::VecDeque::from([start]);
    dist[start as usize] = 0;
    let mut last = start;
    while let Some(f) = queue.pop_front() {
        last = f;
        for (k, &g) in mesh.face_neighbors()[f as usize].iter().enumerate() {
            let e = mesh.face_edges()[f as usize][k] as usize;
            if g != NONE && !cut[e] && mask[g as usize] && dist[g as usize] == u32::MAX {
                dist[g as usize] = dist[f as usize] + 1;
                queue.push_back(g);
            }
        }
    }
    (last, dist)
}

/// Per mesh face, `label(i)` for the `i`-th face of `faces` and `NONE` elsewhere.
fn mask_labels(mesh: &TriMesh, faces: &[u32], label: impl Fn(usize) -> u32) -> Vec<u32> {
    let mut l = vec![NONE; mesh.face_count()];
    for (i, &f) in faces.iter().enumerate() {
        l[f as usize] = label(i);
    }
    l
}

/// `faces` grouped into the connected parts of their labels (not crossing `cut`),
/// in order of each part's lowest face.
fn parts_of(mesh: &TriMesh, faces: &[u32], labels: &[u32], cut: &[bool]) -> Vec<Vec<u32>> {
    let parts = connected_parts(mesh, labels, cut);
    let mut groups: std::collections::BTreeMap<u32, Vec<u32>> = Default::default();
    for &f in faces {
        groups.entry(parts[f as usize]).or_default().push(f);
    }
    groups.into_values().collect()
}

/// The unit eigenvector of the largest eigenvalue of a symmetric 3x3 matrix (power
/// iteration from the column of largest norm; enough to pick a seed direction).
fn principal_axis(m: glam::DMat3) -> DVec3 {
    let mut v = [m.x_axis, m.y_axis, m.z_axis]
        .into_iter()
        .max_by(|a, b| a.length_squared().total_cmp(&b.length_squared()))
        .unwrap_or(DVec3::X)
        .try_normalize()
        .unwrap_or(DVec3::X);
    for _ in 0..32 {
        v = (m * v).try_normalize().unwrap_or(v);
    }
    v
}

/// The field with each tensor replaced by its density times the identity of the
/// tangent plane.
fn isotropic_copy(mesh: &TriMesh, field: &TensorField) -> Result<TensorField, FieldError> {
    let density = field.vertex_densities(mesh);
    let dirs: Vec<DVec3> = mesh
        .vertex_normals()
        .iter()
        .map(|n| crate::field::tangent_frame(*n).0)
        .collect();
    let ev: Vec<[f64; 2]> = density.iter().map(|&d| [d, d]).collect();
    TensorField::from_frames(mesh, &dirs, &ev)
}

/// Cells for every parameterized segment, in parallel. The cell budget is shared:
/// each segment's `max_cell_share` is scaled by its share of the total measure, and
/// its boundary refinement by how many cells it gets.
fn build_cells(
    mesh: &TriMesh,
    field: &TensorField,
    params: &[SegmentParam],
    options: &CurveOptions,
) -> Result<Vec<SegmentSampling>, SurfaceError> {
    let inputs: Vec<CellInput> = params
        .par_iter()
        .map(|p| CellInput::new(mesh, field, p))
        .collect();
    let total: f64 = inputs.iter().map(|c| c.measure).sum();
    params
        .par_iter()
        .zip(inputs.par_iter())
        .enumerate()
        .map(|(id, (p, input))| {
            let curve =
                segment_cells(p, input, total, options).map_err(|source| SurfaceError::Curve {
                    segment: id,
                    source,
                })?;
            Ok(SegmentSampling {
                segment: id as u32,
                faces: p.faces.clone(),
                curve: Arc::new(curve),
            })
        })
        .collect()
}

/// One parameterized segment prepared for its cells: its parameter layout scaled into
/// the unit square, the density per triangle corner, and its measure (the integral of
/// the density over it), which sets its share of the cell budget.
#[derive(Clone, Debug, PartialEq)]
pub struct CellInput {
    /// Parameter coordinates in the unit square, per parameter vertex.
    pub uv: Vec<glam::DVec2>,
    /// Density per unit of parameter area at each triangle's corners.
    pub corner_density: Vec<[f64; 3]>,
    /// The segment's measure.
    pub measure: f64,
}

impl CellInput {
    /// Prepares `param` (a segment of `mesh`) with `field`. Cost O(segment).
    pub fn new(mesh: &TriMesh, field: &TensorField, param: &SegmentParam) -> Self {
        let (uv, _, _) = param.to_unit_square();
        let corner_density = param.corner_density(mesh, field, &uv);
        let measure = param
            .triangles
            .iter()
            .zip(&corner_density)
            .map(|(t, c)| {
                let q = t.map(|v| uv[v as usize]);
                0.5 * (q[1] - q[0]).perp_dot(q[2] - q[0]) * (c[0] + c[1] + c[2]) / 3.0
            })
            .sum();
        Self {
            uv,
            corner_density,
            measure,
        }
    }
}

/// The adaptive Hilbert cells of one segment whose [`CellInput`] is `input`, when all
/// segments together measure `total_measure`: the segment's `max_cell_share` is
/// `options.max_cell_share` divided by its fraction of the total (capped at 1), so that
/// the whole surface gets about `1 / options.max_cell_share` cells, and its boundary
/// refinement follows its cell count. This is what [`Preprocessed::build`] does per
/// segment; a caller that rebuilds only some segments passes the current total.
pub fn segment_cells(
    param: &SegmentParam,
    input: &CellInput,
    total_measure: f64,
    options: &CurveOptions,
) -> Result<SegmentCurve, CurveError> {
    let fraction = (input.measure / total_measure).max(f64::MIN_POSITIVE);
    let share = (options.max_cell_share / fraction).min(1.0);
    // Cells this segment may get, and boundary refinement to about their size.
    let cells = 1.0 / share;
    let level =
        ((cells.log2() * 0.5).ceil() as i64 + 2).clamp(1, options.boundary_level as i64) as u8;
    let seg_options = CurveOptions {
        max_cell_share: share,
        boundary_level: level,
        ..*options
    };
    SegmentCurve::build(
        &CurveDomain {
            uv: &input.uv,
            triangles: &param.triangles,
            corner_density: &input.corner_density,
        },
        &seg_options,
    )
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::field::FieldSpec;
    use crate::mesh::shapes;

    /// A torus with a constant 3:1 field: a small curved case with several segments.
    pub(crate) fn torus_case() -> (Arc<TriMesh>, Arc<TensorField>) {
        let mesh = Arc::new(shapes::torus(1.0, 0.4, 20).expect("torus"));
        let field = FieldSpec::Constant {
            direction: [1.0, 0.3, 0.2],
            anisotropy: 3.0,
            density: 1.0,
        }
        .build(&mesh)
        .expect("field");
        (mesh, Arc::new(field))
    }

    #[test]
    fn per_segment_parameterization_and_cells_equal_the_whole_build() {
        let (mesh, field) = torus_case();
        let options = SurfaceOptions::default();
        let pre = Preprocessed::build(mesh.clone(), field.clone(), &options).expect("build");
        let seg = &pre.segmentation;
        let context = SplitContext::new(&mesh, &field, &seg.cut_edges, &options);
        let mut pieces = Vec::new();
        for s in &seg.segments {
            let (p, _) =
                parameterize_segment_with_splitting(&mesh, &field, &context, &s.faces, &options)
                    .expect("segment");
            assert!(
                p.windows(2)
                    .all(|w| lowest_face(&w[0]) < lowest_face(&w[1]))
            );
            pieces.extend(p);
        }
        pieces.sort_by_key(lowest_face);
        assert_eq!(pieces.len(), pre.params.len());
        for (a, b) in pieces.iter().zip(&pre.params) {
            assert_eq!(a.faces, b.faces);
            assert_eq!(a.uv, b.uv);
        }
        let inputs: Vec<CellInput> = pieces
            .iter()
            .map(|p| CellInput::new(&mesh, &field, p))
            .collect();
        let total: f64 = inputs.iter().map(|c| c.measure).sum();
        // The cells' exact measures sum to the same total up to rounding.
        assert!((total / pre.sampler.total_measure() - 1.0).abs() < 1e-9);
        for ((p, c), s) in pieces.iter().zip(&inputs).zip(pre.sampler.segments()) {
            let curve = segment_cells(p, c, total, &options.curve).expect("cells");
            assert_eq!(curve.cell_count(), s.curve.cell_count());
            assert_eq!(curve.measure(), s.curve.measure());
        }
    }

    /// A plane whose field is constant except in a small disc in the middle, where it
    /// is turned by 90 degrees: the paper's seeds (the two most different directions)
    /// include a face of that disc, and the walk gives that seed just the disc, a hole
    /// in the rest of the plane. The split must still give discs of balanced size.
    #[test]
    fn an_outlier_direction_does_not_peel_a_hole_out_of_the_segment() {
        let mesh = shapes::plane(1.0, 16).expect("plane");
        let dirs: Vec<DVec3> = mesh
            .positions()
            .iter()
            .map(|p| {
                let r = (p.truncate() - glam::DVec2::splat(0.5)).length();
                if r < 0.1 { DVec3::Y } else { DVec3::X }
            })
            .collect();
        let field = TensorField::from_frames(&mesh, &dirs, &vec![[3.0, 1.0 / 3.0]; dirs.len()])
            .expect("field");
        let options = SurfaceOptions::default();
        let context = SplitContext::new(&mesh, &field, &[], &options);
        let faces: Vec<u32> = (0..mesh.face_count() as u32).collect();
        // The paper's seeds alone: one seed region is a small island.
        let [a, b] = most_different_faces(&context.frames, &faces);
        let mask = vec![true; mesh.face_count()];
        let labels = random_walk(&mesh, &context.weights, &mask, &[a, b]).expect("walk");
        let paper = parts_of(&mesh, &faces, &labels, &context.cut);
        let smallest = paper.iter().map(Vec::len).min().unwrap_or(0);
        assert!(
            smallest * MIN_SPLIT_SHARE < faces.len()
                || paper.iter().any(|p| !is_disc(&mesh, p, &context.cut)),
            "the case must exercise the fallback: parts {:?}",
            paper.iter().map(Vec::len).collect::<Vec<_>>()
        );
        let parts = split_in_two(
            &mesh,
            &context.frames,
            &context.weights,
            &context.cut,
            &faces,
        )
        .expect("split");
        assert!(parts.len() >= 2);
        assert_eq!(parts.iter().map(Vec::len).sum::<usize>(), faces.len());
        for p in &parts {
            assert!(
                p.len() * MIN_SPLIT_SHARE >= faces.len(),
                "part of {} faces",
                p.len()
            );
            assert!(is_disc(&mesh, p, &context.cut));
        }
    }

    #[test]
    fn bad_options_are_errors_before_any_work() {
        let (mesh, field) = torus_case();
        let good = SurfaceOptions::default();
        let seg = segment(&mesh, &field, &good.segment).expect("segmentation");
        let zero = SurfaceOptions {
            min_segment_faces: 0,
            ..good
        };
        let mut bad_gamma = good;
        bad_gamma.param.gamma = -1.0;
        for options in [zero, bad_gamma] {
            assert!(Preprocessed::build(mesh.clone(), field.clone(), &options).is_err());
            assert!(
                Preprocessed::from_segmentation(mesh.clone(), field.clone(), seg.clone(), &options)
                    .is_err()
            );
        }
        assert!(matches!(
            zero.validate(),
            Err(SurfaceError::InvalidMinSegmentFaces)
        ));
    }

    #[test]
    fn halving_always_makes_progress_and_keeps_every_face() {
        let mesh = shapes::plane(1.0, 6).expect("plane");
        let cut = vec![false; mesh.edge_count()];
        let mut pending = vec![(0..mesh.face_count() as u32).collect::<Vec<_>>()];
        let mut singles = 0;
        while let Some(faces) = pending.pop() {
            if faces.len() == 1 {
                singles += 1;
                continue;
            }
            let parts = halve(&mesh, &cut, &faces);
            assert!(parts.len() >= 2, "{} faces not split", faces.len());
            assert_eq!(parts.iter().map(Vec::len).sum::<usize>(), faces.len());
            pending.extend(parts);
        }
        assert_eq!(singles, mesh.face_count());
    }
}
