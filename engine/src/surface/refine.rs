//! Splitting of invalid segments (paper section 5.2): parameterize every segment, and
//! split in two and parameterize again those whose parameterization is invalid.
//!
//! Input: a mesh, a field, the segments (as face lists) and [`SurfaceOptions`]. Output:
//! the final pieces' [`SegmentParam`]s, ordered by their lowest mesh face, and the
//! split counts of a [`SurfaceReport`].
//!
//! A segment whose parameterization is invalid (flipped or overlapping, or the mapped
//! field off the u axis by more than `gamma` on average), or that cannot be
//! parameterized, is split in two by the random walk restricted to it, seeded at its
//! two most different directions, and both halves are parameterized again. A split
//! whose parts are not discs or are badly unbalanced (an outlier direction next to a
//! singularity seeds a region of a few faces) is redone from two faces far apart, so a
//! segment needs about log2 of its size rounds, not one per outlier. The border between
//! the two parts is smoothed ([`FaceSet::smoothed_parts`]: no face shares two edges
//! with the other part), since a field-aligned map folds one-face zigzags of a border
//! over. Pieces of `WALK_SPLIT_FACES` (4096) faces or more skip the walk and are
//! halved by hops straight away (the walk's split fails that test for most of them). Below
//! `min_segment_faces` a segment is parameterized with an isotropic field (flagged
//! `isotropic_fallback`; it is sampled with the right density but without
//! anisotropy); a piece for which even that flips is halved again, down to single
//! triangles, which are always valid. So every face ends in a parameterized piece.
//! Finally neighbouring pieces whose union is valid are merged back
//! ([`merge`](super::merge); `SurfaceOptions::merge_pieces`), since halving goes past
//! where the segment becomes valid.
//!
//! Cost: one sparse factorization per parameterization, one random walk per split;
//! segments in parallel with rayon, and within a segment each piece as soon as its
//! parent is split (no waiting for the other pieces of a round, so a few large
//! segments keep every thread busy). A piece of [`SPECULATE_FACES`] faces or more is
//! split on an idle thread while it is parameterized, its halves used only if it is
//! invalid: the chain of halvings of one large segment no longer runs on one thread
//! (parameterization of the smooth bunny field's segments, medians of alternated runs,
//! from 50,000 faces: 69k faces 0.164 -> 0.135 s, 278k 0.789 -> 0.705 s, 1.1M
//! 3.66-3.69 -> 3.24-3.34 s).
//! The result does not depend on the thread count.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Mutex, OnceLock, PoisonError};

use glam::{DMat3, DVec3};
use rayon::prelude::*;

use super::merge::{MergeLimit, PieceSet, merge_pieces};
use super::piece::{angle_ok, lowest_face};
use super::{SurfaceError, SurfaceOptions, SurfaceReport};
use crate::field::{FieldError, TensorField, isotropic_copy, outer, principal_axis};
use crate::mesh::{FaceSet, TriMesh};
use crate::param::{FaceTensors, SegmentParam, parameterize_all, parameterize_with};
use crate::segment::{
    FaceField, SegmentError, Segmentation, face_frames, is_disc, random_walk, walk_weights,
};

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
        report.merges += r.merges;
        report.single_face_segments += r.single_face_segments;
        accepted.extend(params);
    }
    // Deterministic order: by lowest mesh face.
    accepted.sort_by_key(lowest_face);
    // One definition, the one each segment's report carries (and `strata segment`
    // counts): isotropic by its own field, by fallback after splitting, or one face.
    report.isotropic_segments = accepted
        .iter()
        .filter(|p| p.report.isotropic_fallback)
        .count();
    Ok((accepted, report))
}

/// What splitting needs besides the segment: the cut edges as a per-edge mask, the
/// per-face field directions and the random walk's edge weights, computed once for
/// the whole mesh and shared by every segment (and the isotropic fallback field, made
/// on first use).
#[derive(Debug)]
pub struct SplitContext {
    cut: Vec<bool>,
    frames: FaceField,
    weights: Vec<f64>,
    tensors: FaceTensors,
    isotropic: OnceLock<TensorField>,
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
            tensors: FaceTensors::new(mesh, field),
            isotropic: OnceLock::new(),
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
    let splitter = Splitter {
        mesh,
        context,
        options,
    };
    let Pieces {
        mut accepted,
        mut small,
        splits,
        invalid,
    } = splitter.split_until_valid(faces.to_vec())?;
    let mut report = SurfaceReport {
        splits,
        ..SurfaceReport::default()
    };
    // The pieces arrive in the order they finish; the fallback below treats each
    // piece on its own and the result is sorted, but keep it independent of timing.
    small.sort_by_key(|f| f.iter().copied().min());
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
                    }
                    accepted.push(p);
                }
                Err(e) if faces.len() == 1 => return Err(e.into()),
                _ => again.extend(halve(mesh, cut, &FaceSet::new(mesh, &faces))),
            }
        }
        small = again;
    }
    let (mut accepted, merges) = if options.merge_pieces {
        let limit = MergeLimit::for_mesh(mesh.face_count());
        merge_pieces(
            mesh,
            &context.tensors,
            cut,
            accepted,
            options,
            limit,
            &invalid,
        )
    } else {
        (accepted, 0)
    };
    report.merges = merges;
    report.single_face_segments = accepted
        .iter()
        .filter(|p| p.faces.len() == 1 && p.report.isotropic_fallback)
        .count();
    accepted.sort_by_key(lowest_face);
    Ok((accepted, report))
}

/// What splitting with the field leaves: valid pieces, pieces too small to split
/// further (for the isotropic fallback), the number of splits and the pieces split
/// because they were invalid (so that merging does not rebuild them).
#[derive(Debug, Default)]
struct Pieces {
    accepted: Vec<SegmentParam>,
    small: Vec<Vec<u32>>,
    splits: usize,
    invalid: PieceSet,
}

/// Parameterizes pieces and splits the invalid ones in two, each piece as soon as its
/// parent is split: a large piece does not wait for the other pieces of its round, so
/// the few large segments of a smooth field keep every thread busy. Each piece's
/// outcome depends on its faces alone, so the pieces do not depend on the threads.
struct Splitter<'a> {
    mesh: &'a TriMesh,
    context: &'a SplitContext,
    options: &'a SurfaceOptions,
}

/// What becomes of one piece.
enum Outcome {
    Accepted(SegmentParam),
    Small(Vec<u32>),
    Split(Vec<Vec<u32>>),
}

impl Splitter<'_> {
    /// Splits `faces` until every piece is valid or too small (see the module docs).
    fn split_until_valid(&self, faces: Vec<u32>) -> Result<Pieces, SurfaceError> {
        // No caller cancels the whole segment, so there is always an answer.
        self.pieces_of(faces, &[])
            .unwrap_or_else(|| Ok(Pieces::default()))
    }

    /// The pieces `faces` ends in; `None` once any of `cancel` is set (an ancestor
    /// turned out valid, so nobody needs them). A piece of [`SPECULATE_FACES`] or more
    /// is split on an idle thread while it is parameterized: most such pieces are
    /// invalid (on the bunny Loop-subdivided twice, its largest smooth-field segment
    /// halves four times in a row), and otherwise the chain of halvings runs on one
    /// thread while the other waits. The halves are used only when the piece is
    /// invalid, and are what splitting it afterwards would give, so the pieces do not
    /// depend on the threads; when it is valid the speculative work stops at its next
    /// check.
    fn pieces_of(
        &self,
        faces: Vec<u32>,
        cancel: &[&AtomicBool],
    ) -> Option<Result<Pieces, SurfaceError>> {
        let cancelled = |flags: &[&AtomicBool]| flags.iter().any(|c| c.load(Ordering::Relaxed));
        if cancelled(cancel) {
            return None;
        }
        if faces.len() < SPECULATE_FACES.max(self.options.min_segment_faces.max(2)) {
            let out = Mutex::new(Ok(Pieces::default()));
            rayon::scope(|scope| self.visit(scope, &out, faces));
            return Some(out.into_inner().unwrap_or_else(PoisonError::into_inner));
        }
        let valid = AtomicBool::new(false);
        let (parent, halves) = rayon::join(
            || {
                let p = self.accepted(&faces);
                if p.is_some() {
                    valid.store(true, Ordering::Relaxed);
                }
                p
            },
            || {
                let mut chain = cancel.to_vec();
                chain.push(&valid);
                if cancelled(&chain) {
                    return None;
                }
                let halves = match self.split(&faces) {
                    Ok(halves) => halves,
                    Err(e) => return Some(Err(e)),
                };
                let parts: Vec<_> = halves
                    .into_par_iter()
                    .map(|half| self.pieces_of(half, &chain))
                    .collect();
                combine(parts)
            },
        );
        if let Some(p) = parent {
            return Some(Ok(Pieces {
                accepted: vec![p],
                ..Pieces::default()
            }));
        }
        // Invalid: the halves were not cancelled by this piece, only (if at all) by an
        // ancestor, in which case this piece is not needed either.
        let mut pieces = match halves? {
            Ok(pieces) => pieces,
            Err(e) => return Some(Err(e)),
        };
        pieces.splits += 1;
        pieces.invalid.insert(&faces);
        Some(Ok(pieces))
    }

    /// `faces`' parameterization when it is valid (and passes the angle test).
    fn accepted(&self, faces: &[u32]) -> Option<SegmentParam> {
        parameterize_with(
            self.mesh,
            &self.context.tensors,
            faces,
            &self.context.cut,
            &self.options.param,
        )
        .ok()
        .filter(|p| p.report.valid && angle_ok(p, self.options))
    }

    /// `faces` split in two (see [`split_in_two`]).
    fn split(&self, faces: &[u32]) -> Result<Vec<Vec<u32>>, SurfaceError> {
        let context = self.context;
        split_in_two(
            self.mesh,
            &context.frames,
            &context.weights,
            &context.cut,
            faces,
        )
    }

    /// Treats one piece and spawns its halves (spawned, not recursed into, so a
    /// long chain of splits does not deepen the stack).
    fn visit<'s>(
        &'s self,
        scope: &rayon::Scope<'s>,
        out: &'s Mutex<Result<Pieces, SurfaceError>>,
        faces: Vec<u32>,
    ) {
        let lock = || out.lock().unwrap_or_else(PoisonError::into_inner);
        if lock().is_err() {
            return; // another piece failed: the whole segment does
        }
        let name = PieceSet::name(&faces);
        match self.outcome(faces) {
            Ok(Outcome::Accepted(p)) => {
                if let Ok(pieces) = &mut *lock() {
                    pieces.accepted.push(p);
                }
            }
            Ok(Outcome::Small(faces)) => {
                if let Ok(pieces) = &mut *lock() {
                    pieces.small.push(faces);
                }
            }
            Ok(Outcome::Split(halves)) => {
                if let Ok(pieces) = &mut *lock() {
                    pieces.splits += 1;
                    pieces.invalid.insert_name(name);
                }
                for half in halves {
                    scope.spawn(move |scope| self.visit(scope, out, half));
                }
            }
            Err(e) => {
                let mut guard = lock();
                if guard.is_ok() {
                    *guard = Err(e);
                }
            }
        }
    }

    /// Parameterizes one piece: accepted if valid, kept for the fallback if too small
    /// to split, split in two otherwise.
    fn outcome(&self, faces: Vec<u32>) -> Result<Outcome, SurfaceError> {
        if let Some(p) = self.accepted(&faces) {
            return Ok(Outcome::Accepted(p));
        }
        if faces.len() < self.options.min_segment_faces.max(2) {
            return Ok(Outcome::Small(faces));
        }
        self.split(&faces).map(Outcome::Split)
    }
}

/// The pieces of the halves of one piece, in order: `None` if any was cancelled, the
/// first error if any failed.
fn combine(
    parts: Vec<Option<Result<Pieces, SurfaceError>>>,
) -> Option<Result<Pieces, SurfaceError>> {
    let mut all = Pieces::default();
    for part in parts {
        match part? {
            Ok(p) => {
                all.accepted.extend(p.accepted);
                all.small.extend(p.small);
                all.splits += p.splits;
                all.invalid.extend(p.invalid);
            }
            Err(e) => return Some(Err(e)),
        }
    }
    Some(Ok(all))
}

/// Pieces of at least this many faces are split on an idle thread while they are
/// parameterized (see the [module docs](self)); their halves are used only when the
/// piece is invalid. Below it a piece costs little next to the bookkeeping. Against
/// 50,000, parameterization of the constant-field bunny (69k faces) took 0.156 s
/// against 0.168 s (medians of five alternated runs), and of the smooth one at 278k
/// faces 0.698 s against 0.727 s (three).
pub const SPECULATE_FACES: usize = 20_000;

/// A split is accepted when every part is a disc (the parameterization needs one) and
/// the smallest part holds at least this share of the faces. Without the balance
/// test, seeds at outlier faces (next to a singularity, say) peel off a few faces per
/// round, often leaving a hole, and splitting a large segment takes hundreds of
/// rounds instead of about log2 of its size.
const MIN_SPLIT_SHARE: usize = 8;

/// Pieces from this many faces are halved by hops ([`halve`]) without trying the
/// walk. The walk's two point seeds rarely split a piece evenly: on the bunny and the
/// bunny Loop-subdivided twice (constant 3:1 and smooth curvature-aligned fields), the
/// paper's seeds gave a split that failed the test below for 88% of the pieces (85%
/// from 20k faces; a part of a few dozen faces beside the rest, in every case
/// printed), and the far pair for 85%, so most large pieces paid two walks (a sparse
/// factorization each, about 70% of a split's time) and were then halved anyway. Halving them directly gives the same final piece counts within a
/// few (bench/README.md, "Halving large pieces").
const WALK_SPLIT_FACES: usize = 4096;

/// Splits a segment in two by the random walk (section 5.2) and returns the connected
/// parts; a piece of [`WALK_SPLIT_FACES`] or more is halved by hops instead.
///
/// The walk is first seeded at the segment's two most different face directions (as
/// lines), as in the paper. If that split is unbalanced (a part under
/// 1/[`MIN_SPLIT_SHARE`] of the faces) or leaves a part that is not a disc, the walk is
/// seeded again at two faces far apart in the segment (a double sweep of
/// breadth-first search), which halves the segment; failing that too, the faces are
/// given to the nearer of those two seeds, and as a last resort halved by face order.
fn split_in_two(
    mesh: &TriMesh,
    frames: &FaceField,
    weights: &[f64],
    cut: &[bool],
    faces: &[u32],
) -> Result<Vec<Vec<u32>>, SurfaceError> {
    if faces.len() >= WALK_SPLIT_FACES {
        return Ok(halve(mesh, cut, &FaceSet::new(mesh, faces)));
    }
    let [a, b] = most_different_faces(frames, faces);
    if a == b {
        return Ok(vec![faces.to_vec()]); // a single face: nothing to split
    }
    let set = FaceSet::new(mesh, faces);
    let good = |parts: &[Vec<u32>]| {
        parts.len() > 1
            && parts
                .iter()
                .all(|p| p.len() * MIN_SPLIT_SHARE >= faces.len() && is_disc(mesh, p, cut))
    };
    let walk = |seeds: [u32; 2]| -> Result<Option<Vec<Vec<u32>>>, SurfaceError> {
        match random_walk(mesh, weights, set.mask(), &seeds) {
            Ok(labels) => Ok(Some(set.smoothed_parts(mesh, cut, &labels))),
            // Parts of the segment unreachable from both seeds (cut off by cut edges).
            Err(SegmentError::Unseeded { .. }) => Ok(None),
            Err(e) => Err(e.into()),
        }
    };
    let first = match walk([a, b])? {
        Some(parts) if good(&parts) => return Ok(parts),
        other => other,
    };
    if let Some([far_a, far_b]) = set.far_pair(mesh, cut)
        && far_a != far_b
        && let Some(parts) = walk([far_a, far_b])?
        && good(&parts)
    {
        return Ok(parts);
    }
    let parts = halve(mesh, cut, &set);
    if good(&parts) {
        return Ok(parts);
    }
    // Keep the paper's split if it split at all (it makes progress).
    match first {
        Some(first) if first.len() > 1 => Ok(first),
        _ => Ok(parts),
    }
}

/// Splits `set` (two or more faces) into the connected parts of the faces nearer (in
/// hops) to one or the other of two faces far apart; by the set's face order if that
/// does not split them (faces unreachable from each other).
fn halve(mesh: &TriMesh, cut: &[bool], set: &FaceSet) -> Vec<Vec<u32>> {
    if let Some([a, b]) = set.far_pair(mesh, cut)
        && a != b
    {
        let nearer_b = set.nearer_to_second(mesh, cut, a, b);
        let labels = set.labels(|i| u32::from(nearer_b[i]));
        let parts = set.smoothed_parts(mesh, cut, &labels);
        if parts.len() > 1 {
            return parts;
        }
    }
    let half = set.len() / 2;
    let labels = set.labels(|i| (i >= half) as u32);
    set.parts(mesh, &labels, cut)
}

/// The face whose direction is farthest from the segment's mean line direction (mean
/// of `m m^T`), then the face farthest from that one (ties to the lower face id).
fn most_different_faces(frames: &FaceField, faces: &[u32]) -> [u32; 2] {
    let mut mean = DMat3::ZERO;
    for &f in faces {
        let m = frames.major[f as usize];
        mean += outer(m, m);
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixtures::field_along;
    use crate::mesh::shapes;

    /// The unit plane of `2 n^2` faces with a 3:1 field along x, turned by 90 degrees
    /// inside the disc of `radius` about `centre`: its split context and all its faces.
    fn turned_disc_plane(
        n: u32,
        centre: glam::DVec2,
        radius: f64,
    ) -> (TriMesh, SplitContext, Vec<u32>) {
        let mesh = shapes::plane(1.0, n).expect("plane");
        let dirs: Vec<DVec3> = mesh
            .positions()
            .iter()
            .map(|p| {
                if (p.truncate() - centre).length() < radius {
                    DVec3::Y
                } else {
                    DVec3::X
                }
            })
            .collect();
        let field = TensorField::from_frames(&mesh, &dirs, &vec![[3.0, 1.0 / 3.0]; dirs.len()])
            .expect("field");
        let context = SplitContext::new(&mesh, &field, &[], &SurfaceOptions::default());
        let faces: Vec<u32> = (0..mesh.face_count() as u32).collect();
        (mesh, context, faces)
    }

    /// The walk's split of the whole mesh from the paper's seeds (the two most
    /// different directions); asserts that it fails the split test, as the cases
    /// below need.
    fn assert_paper_split_fails(mesh: &TriMesh, context: &SplitContext, faces: &[u32]) {
        let [a, b] = most_different_faces(&context.frames, faces);
        let all = FaceSet::all(mesh);
        let labels = random_walk(mesh, &context.weights, all.mask(), &[a, b]).expect("walk");
        let paper = all.parts(mesh, &labels, &context.cut);
        let smallest = paper.iter().map(Vec::len).min().unwrap_or(0);
        assert!(
            smallest * MIN_SPLIT_SHARE < faces.len()
                || paper.iter().any(|p| !is_disc(mesh, p, &context.cut)),
            "the case must exercise the fallback: parts {:?}",
            paper.iter().map(Vec::len).collect::<Vec<_>>()
        );
    }

    fn split_all(mesh: &TriMesh, context: &SplitContext, faces: &[u32]) -> Vec<Vec<u32>> {
        split_in_two(mesh, &context.frames, &context.weights, &context.cut, faces).expect("split")
    }

    /// A plane whose field is constant except in a small disc in the middle, where it
    /// is turned by 90 degrees: the paper's seeds (the two most different directions)
    /// include a face of that disc, and the walk gives that seed just the disc, a hole
    /// in the rest of the plane. The split must still give discs of balanced size.
    #[test]
    fn an_outlier_direction_does_not_peel_a_hole_out_of_the_segment() {
        let (mesh, context, faces) = turned_disc_plane(16, glam::DVec2::splat(0.5), 0.1);
        assert!(faces.len() < WALK_SPLIT_FACES, "the walk must be tried");
        assert_paper_split_fails(&mesh, &context, &faces);
        let parts = split_all(&mesh, &context, &faces);
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

    /// A whole sphere is no disc, so it is split, and its halves again: the pieces
    /// partition it and are the same, bit for bit, on one thread and on four.
    #[test]
    fn splitting_gives_the_same_pieces_on_any_number_of_threads() {
        let mesh = shapes::sphere(1.0, 3).expect("sphere");
        let field = field_along(&mesh, DVec3::X);
        let options = SurfaceOptions::default();
        let context = SplitContext::new(&mesh, &field, &[], &options);
        let faces: Vec<u32> = (0..mesh.face_count() as u32).collect();
        let run = |threads: usize| {
            crate::on_threads(threads, || {
                parameterize_segment_with_splitting(&mesh, &field, &context, &faces, &options)
            })
            .expect("split")
        };
        let (one, report) = run(1);
        assert!(report.splits >= 2, "{} splits", report.splits);
        let mut covered: Vec<u32> = one.iter().flat_map(|p| p.faces.clone()).collect();
        covered.sort_unstable();
        assert_eq!(covered, faces, "every face in exactly one piece");
        assert!(
            one.windows(2)
                .all(|w| lowest_face(&w[0]) < lowest_face(&w[1]))
        );
        let (four, report4) = run(4);
        assert_eq!(report4, report);
        assert_eq!(four, one);
    }

    /// A sphere of more than `SPECULATE_FACES` faces (24,500) is no disc, so it is split while
    /// it is parameterized: the result is exactly its two halves' pieces, each half
    /// split on its own (below `SPECULATE_FACES`, without speculation), plus the one
    /// split, on one thread and on four.
    #[test]
    fn a_large_piece_split_while_parameterized_gives_its_halves_pieces() {
        let mesh = shapes::sphere(1.0, 35).expect("sphere");
        assert!(mesh.face_count() >= SPECULATE_FACES);
        let field = field_along(&mesh, DVec3::X);
        let options = SurfaceOptions {
            merge_pieces: false,
            ..SurfaceOptions::default()
        };
        let context = SplitContext::new(&mesh, &field, &[], &options);
        let faces: Vec<u32> = (0..mesh.face_count() as u32).collect();
        let run = |threads: usize, faces: &[u32]| {
            crate::on_threads(threads, || {
                parameterize_segment_with_splitting(&mesh, &field, &context, faces, &options)
            })
            .expect("split")
        };
        let (whole, report) = run(2, &faces);
        let halves = split_all(&mesh, &context, &faces);
        assert_eq!(halves.len(), 2);
        assert!(halves.iter().all(|h| h.len() < SPECULATE_FACES));
        let mut expected = Vec::new();
        let mut splits = 1;
        for half in &halves {
            let (pieces, r) = run(1, half);
            expected.extend(pieces);
            splits += r.splits;
        }
        expected.sort_by_key(lowest_face);
        assert_eq!(report.splits, splits);
        assert_eq!(whole, expected);
        assert_eq!(run(1, &faces), (whole.clone(), report));
        assert_eq!(run(4, &faces).0, whole);
    }

    /// A valid piece of more than `SPECULATE_FACES` faces (20,402) stays whole: the halves
    /// begun beside it are dropped.
    #[test]
    fn a_valid_large_piece_is_kept_whole() {
        let mesh = shapes::plane(1.0, 101).expect("plane");
        assert!(mesh.face_count() >= SPECULATE_FACES);
        let field = field_along(&mesh, DVec3::new(1.0, 0.5, 0.0).normalize());
        let options = SurfaceOptions::default();
        let context = SplitContext::new(&mesh, &field, &[], &options);
        let faces: Vec<u32> = (0..mesh.face_count() as u32).collect();
        let (pieces, report) = crate::on_threads(2, || {
            parameterize_segment_with_splitting(&mesh, &field, &context, &faces, &options)
        })
        .expect("split");
        assert_eq!(pieces.len(), 1);
        assert_eq!(pieces[0].faces.len(), faces.len());
        assert_eq!((report.splits, report.merges), (0, 0));
    }

    /// From `WALK_SPLIT_FACES` faces a piece is halved by hops: two discs of about half
    /// the faces each, where the paper's seeds (one in the turned disc) fail the split
    /// test.
    #[test]
    fn a_large_piece_is_halved_into_two_even_discs() {
        let (mesh, context, faces) = turned_disc_plane(64, glam::DVec2::new(0.2, 0.3), 0.05);
        assert!(faces.len() >= WALK_SPLIT_FACES);
        assert_paper_split_fails(&mesh, &context, &faces);
        let parts = split_all(&mesh, &context, &faces);
        assert_eq!(parts.len(), 2);
        let mut covered: Vec<u32> = parts.concat();
        covered.sort_unstable();
        assert_eq!(covered, faces);
        for p in &parts {
            assert!(
                p.len() * 5 >= faces.len() * 2,
                "part of {} faces out of {}",
                p.len(),
                faces.len()
            );
            assert!(is_disc(&mesh, p, &context.cut));
        }
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
            let parts = halve(&mesh, &cut, &FaceSet::new(&mesh, &faces));
            assert!(parts.len() >= 2, "{} faces not split", faces.len());
            assert_eq!(parts.iter().map(Vec::len).sum::<usize>(), faces.len());
            pending.extend(parts);
        }
        assert_eq!(singles, mesh.face_count());
    }
}
