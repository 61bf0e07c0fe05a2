//! Merging the pieces that splitting left (the over-segmentation of paper section 8).
//!
//! Splitting halves an invalid segment without knowing where it will become valid, so
//! it often goes one level too far: two neighbouring pieces that were cut apart would
//! have been valid together, and pieces of a few dozen faces are left next to a
//! singularity. This pass tries to glue neighbouring pieces of one segment back
//! together: a pair is merged when their union parameterizes validly (the same test
//! as splitting: no flip, no overlap, mean angle under `gamma`, and the optional max
//! criterion). Each merge removes a segment, so the surface has fewer seams and
//! longer curves.
//!
//! Order: in rounds, the untried adjacent pairs by increasing size of their union
//! (small fragments first), each piece in at most one pair per round (taken greedily
//! in that order); the round's unions are parameterized in parallel and the valid ones
//! replace their pair. A pair that failed is not tried again while both pieces stay
//! as they are. Only unions of at most [`MergeLimit`] faces are tried, so the cost is
//! bounded by a few small factorizations per piece. Nor is a union whose faces are a
//! piece splitting already found invalid (named by size and an order-free hash of its
//! faces): two halves that both came out valid would otherwise be glued back into
//! their failed parent and parameterized again. The result depends on the pieces (and
//! those names) alone, never on the thread count.

use std::collections::{BTreeSet, HashSet};

use crate::fast_map::{FastMap, fast_map};

use rayon::prelude::*;

use super::SurfaceOptions;
use super::piece::{angle_ok, lowest_face};
use crate::mesh::{NONE, TriMesh};
use crate::param::{FaceTensors, SegmentParam, parameterize_with};
use crate::rng::mix64;

/// Unions larger than this many faces are not tried: `max(MERGE_MIN_FACES, faces /
/// MERGE_SHARE)` for a mesh of `faces` faces, so the largest merge attempted covers
/// the same share of the surface at every resolution.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MergeLimit(pub usize);

/// The share of the mesh the largest union tried may cover (see [`MergeLimit`]).
pub const MERGE_SHARE: usize = 32;
/// The largest union tried on any mesh covers at least this many faces.
pub const MERGE_MIN_FACES: usize = 2048;

impl MergeLimit {
    /// The limit for a mesh of `face_count` faces.
    pub fn for_mesh(face_count: usize) -> Self {
        Self((face_count / MERGE_SHARE).max(MERGE_MIN_FACES))
    }
}

/// Face sets named by their size and an order-free hash of their faces (the wrapping
/// sum of a mix of each face), so that the name of a union of two disjoint sets is the
/// sum of theirs. Two different sets share a name with probability about 2^-64; the
/// merge pass only uses the set to skip unions known to be invalid, so a collision
/// would cost one merge, never a wrong piece.
#[derive(Clone, Debug, Default)]
pub(crate) struct PieceSet(HashSet<(usize, u64)>);

impl PieceSet {
    /// The name of the face set `faces` (no face twice).
    pub(crate) fn name(faces: &[u32]) -> (usize, u64) {
        (
            faces.len(),
            faces.iter().fold(0u64, |h, &f| h.wrapping_add(mix(f))),
        )
    }

    /// Adds the face set `faces`.
    pub(crate) fn insert(&mut self, faces: &[u32]) {
        self.insert_name(Self::name(faces));
    }

    /// Adds every name of `other`.
    pub(crate) fn extend(&mut self, other: PieceSet) {
        self.0.extend(other.0);
    }

    /// Adds the face set named `name` (see [`name`](Self::name)).
    pub(crate) fn insert_name(&mut self, name: (usize, u64)) {
        self.0.insert(name);
    }

    fn contains(&self, name: (usize, u64)) -> bool {
        self.0.contains(&name)
    }
}

/// A face's contribution to a [`PieceSet`] name: SplitMix64's finaliser of a
/// multiple of the golden ratio, so that face 0 contributes too.
fn mix(f: u32) -> u64 {
    mix64(
        u64::from(f)
            .wrapping_add(1)
            .wrapping_mul(0x9E37_79B9_7F4A_7C15),
    )
}

/// Merges neighbouring pieces of one segment whose union is valid (see the module
/// docs). `pieces` are the segment's final pieces and `invalid` the face sets already
/// found invalid (unions equal to one are not tried); returns the pieces after
/// merging, ordered by their lowest face, and the number of merges.
pub(crate) fn merge_pieces(
    mesh: &TriMesh,
    tensors: &FaceTensors,
    cut: &[bool],
    mut pieces: Vec<SegmentParam>,
    options: &SurfaceOptions,
    limit: MergeLimit,
    invalid: &PieceSet,
) -> (Vec<SegmentParam>, usize) {
    if pieces.len() < 2 {
        return (pieces, 0);
    }
    pieces.sort_by_key(lowest_face);
    let mut merges = 0;
    // Pairs that failed, each piece named by its lowest face and its size: a piece only
    // grows, so a merged piece is never mistaken for the piece it grew from.
    let mut failed: BTreeSet<PairKey> = BTreeSet::new();
    let name = |p: &SegmentParam| (lowest_face(p), p.faces.len());
    loop {
        let pairs = adjacent_pairs(mesh, cut, &pieces);
        // Each piece's set name once per round (a piece has many neighbours).
        let sets: Vec<(usize, u64)> = pieces.iter().map(|p| PieceSet::name(&p.faces)).collect();
        let mut candidates: Vec<(usize, PairKey, usize, usize)> = pairs
            .into_iter()
            .filter_map(|(i, j)| {
                let key = [name(&pieces[i]), name(&pieces[j])];
                let size = pieces[i].faces.len() + pieces[j].faces.len();
                let (a, b) = (sets[i], sets[j]);
                let known = invalid.contains((a.0 + b.0, a.1.wrapping_add(b.1)));
                (size <= limit.0 && !known && !failed.contains(&key)).then_some((size, key, i, j))
            })
            .collect();
        if candidates.is_empty() {
            break;
        }
        candidates.sort_unstable();
        let mut used = vec![false; pieces.len()];
        let mut round = Vec::new();
        for &(_, key, i, j) in &candidates {
            if !used[i] && !used[j] {
                used[i] = true;
                used[j] = true;
                round.push((key, i, j));
            }
        }
        let unions: Vec<Option<SegmentParam>> = round
            .par_iter()
            .map(|&(_, i, j)| {
                let faces: Vec<u32> = pieces[i]
                    .faces
                    .iter()
                    .chain(&pieces[j].faces)
                    .copied()
                    .collect();
                parameterize_with(mesh, tensors, &faces, cut, &options.param)
                    .ok()
                    .filter(|p| acceptable(p, options))
            })
            .collect();
        let mut gone = vec![false; pieces.len()];
        let mut merged = Vec::new();
        for (&(key, i, j), union) in round.iter().zip(unions) {
            match union {
                Some(p) => {
                    gone[i] = true;
                    gone[j] = true;
                    merged.push(p);
                    merges += 1;
                }
                None => {
                    failed.insert(key);
                }
            }
        }
        if merged.is_empty() {
            continue; // every pair of the round failed; the next round tries others
        }
        let mut next: Vec<SegmentParam> = pieces
            .into_iter()
            .zip(gone)
            .filter_map(|(p, g)| (!g).then_some(p))
            .collect();
        next.extend(merged);
        next.sort_by_key(lowest_face);
        pieces = next;
    }
    (pieces, merges)
}

/// A pair of pieces, each by its lowest face and its number of faces.
type PairKey = [(u32, usize); 2];

/// Whether a union may replace its pair: valid by the field's frame (or, if the union
/// is nearly isotropic and used the fallback frame, valid by that frame's test).
fn acceptable(p: &SegmentParam, options: &SurfaceOptions) -> bool {
    p.report.valid && angle_ok(p, options)
}

/// Pairs `(i, j)`, `i < j`, of pieces that share an edge that is not cut, ascending.
fn adjacent_pairs(mesh: &TriMesh, cut: &[bool], pieces: &[SegmentParam]) -> Vec<(usize, usize)> {
    let size: usize = pieces.iter().map(|p| p.faces.len()).sum();
    let mut owner: FastMap<u32, u32> = fast_map(size);
    for (i, p) in pieces.iter().enumerate() {
        for &f in &p.faces {
            owner.insert(f, i as u32);
        }
    }
    let mut pairs: BTreeSet<(usize, usize)> = BTreeSet::new();
    for (i, p) in pieces.iter().enumerate() {
        for &f in &p.faces {
            for (k, &e) in mesh.face_edges()[f as usize].iter().enumerate() {
                let g = mesh.face_neighbors()[f as usize][k];
                if g == NONE || cut[e as usize] {
                    continue;
                }
                if let Some(&j) = owner.get(&g)
                    && j as usize > i
                {
                    pairs.insert((i, j as usize));
                }
            }
        }
    }
    pairs.into_iter().collect()
}

#[cfg(test)]
mod tests {
    use crate::field::TensorField;
    use crate::fixtures::field_along;
    use crate::param::parameterize;
    use std::collections::BTreeMap;

    use glam::DVec3;

    use super::*;
    use crate::mesh::shapes;

    /// The mesh's faces grouped by `key` of their centroid (groups by increasing key).
    fn groups(mesh: &TriMesh, key: impl Fn(DVec3) -> usize) -> Vec<Vec<u32>> {
        let mut out: BTreeMap<usize, Vec<u32>> = BTreeMap::new();
        for f in 0..mesh.face_count() as u32 {
            let [a, b, c] = mesh.face_positions(f);
            out.entry(key((a + b + c) / 3.0)).or_default().push(f);
        }
        out.into_values().collect()
    }

    /// [`merge_pieces`] with the field's table made for the call.
    fn merge(
        mesh: &TriMesh,
        field: &TensorField,
        cut: &[bool],
        pieces: Vec<SegmentParam>,
        limit: MergeLimit,
    ) -> (Vec<SegmentParam>, usize) {
        merge_known(mesh, field, cut, pieces, limit, &PieceSet::default())
    }

    /// [`merge`] with face sets known to be invalid.
    fn merge_known(
        mesh: &TriMesh,
        field: &TensorField,
        cut: &[bool],
        pieces: Vec<SegmentParam>,
        limit: MergeLimit,
        invalid: &PieceSet,
    ) -> (Vec<SegmentParam>, usize) {
        let tensors = FaceTensors::new(mesh, field);
        merge_pieces(
            mesh,
            &tensors,
            cut,
            pieces,
            &SurfaceOptions::default(),
            limit,
            invalid,
        )
    }

    /// Parameterizes every group, each of which must be valid on its own.
    fn valid_pieces(
        mesh: &TriMesh,
        field: &TensorField,
        cut: &[bool],
        parts: &[Vec<u32>],
    ) -> Vec<SegmentParam> {
        let options = SurfaceOptions::default();
        parts
            .iter()
            .map(|faces| {
                let p = parameterize(mesh, field, faces, cut, &options.param).expect("param");
                assert!(p.report.valid, "each piece is valid alone: {:?}", p.report);
                p
            })
            .collect()
    }

    #[test]
    fn quadrants_of_a_plane_with_a_constant_field_merge_into_one_piece() {
        let mesh = shapes::plane(1.0, 16).expect("plane");
        let field = field_along(&mesh, DVec3::X);
        let cut = vec![false; mesh.edge_count()];
        let parts = groups(&mesh, |c| {
            usize::from(c.x > 0.5) + 2 * usize::from(c.y > 0.5)
        });
        assert_eq!(parts.len(), 4);
        let pieces = valid_pieces(&mesh, &field, &cut, &parts);
        let limit = MergeLimit(mesh.face_count());
        let (merged, merges) = merge(&mesh, &field, &cut, pieces, limit);
        assert_eq!(merges, 3);
        assert_eq!(merged.len(), 1);
        assert!(merged[0].report.valid);
        let mut faces = merged[0].faces.clone();
        faces.sort_unstable();
        assert_eq!(faces, (0..mesh.face_count() as u32).collect::<Vec<_>>());
    }

    #[test]
    fn unions_known_to_be_invalid_are_not_tried() {
        let mesh = shapes::plane(1.0, 16).expect("plane");
        let field = field_along(&mesh, DVec3::X);
        let cut = vec![false; mesh.edge_count()];
        let parts = groups(&mesh, |c| usize::from(c.x > 0.5));
        let pieces = valid_pieces(&mesh, &field, &cut, &parts);
        let limit = MergeLimit(mesh.face_count());
        // The two halves' union is valid; named as invalid (in another face order than
        // the pieces give it), it is left alone.
        let mut union: Vec<u32> = parts.concat();
        union.reverse();
        let mut invalid = PieceSet::default();
        invalid.insert(&union);
        let (kept, merges) = merge_known(&mesh, &field, &cut, pieces.clone(), limit, &invalid);
        assert_eq!((kept.len(), merges), (2, 0));
        // A set that is not their union does not stop the merge.
        let mut other = PieceSet::default();
        other.insert(&union[1..]);
        other.insert(&parts[0]);
        let (merged, merges) = merge_known(&mesh, &field, &cut, pieces, limit, &other);
        assert_eq!((merged.len(), merges), (1, 1));
    }

    #[test]
    fn union_names_add_up() {
        let a = [3u32, 17, 4, 250];
        let b = [9u32, 1000, 0];
        let (na, nb) = (PieceSet::name(&a), PieceSet::name(&b));
        let mut ab: Vec<u32> = a.iter().chain(&b).copied().collect();
        assert_eq!(PieceSet::name(&ab), (na.0 + nb.0, na.1.wrapping_add(nb.1)));
        ab.sort_unstable();
        assert_eq!(PieceSet::name(&ab), (7, na.1.wrapping_add(nb.1)));
        assert_ne!(PieceSet::name(&a[..3]).1, PieceSet::name(&[3u32, 17, 5]).1);
    }

    #[test]
    fn unions_over_the_limit_are_not_tried() {
        let mesh = shapes::plane(1.0, 16).expect("plane");
        let field = field_along(&mesh, DVec3::X);
        let cut = vec![false; mesh.edge_count()];
        let parts = groups(&mesh, |c| {
            usize::from(c.x > 0.5) + 2 * usize::from(c.y > 0.5)
        });
        let pieces = valid_pieces(&mesh, &field, &cut, &parts);
        let smallest_union = mesh.face_count() / 2;
        let limit = MergeLimit(smallest_union - 1);
        let (merged, merges) = merge(&mesh, &field, &cut, pieces.clone(), limit);
        assert_eq!((merges, merged.len()), (0, 4));
        let mut sorted = pieces.clone();
        sorted.sort_by_key(lowest_face);
        assert_eq!(merged, sorted, "untouched, in order of lowest face");
        // At exactly the size of two quadrants, pairs merge but not all four.
        let (merged, merges) = merge(&mesh, &field, &cut, pieces, MergeLimit(smallest_union));
        assert_eq!((merges, merged.len()), (2, 2));
    }

    /// Two halves of a tube are valid discs, but together they are an annulus, which
    /// no map to the plane covers without overlap: they stay apart.
    #[test]
    fn halves_of_a_tube_are_not_merged_into_an_annulus() {
        let mesh = shapes::cylinder(1.0, 2.0, 16).expect("tube");
        let field = field_along(&mesh, DVec3::Z);
        let cut = vec![false; mesh.edge_count()];
        let parts = groups(&mesh, |c| usize::from(c.x > 0.0));
        assert_eq!(parts.len(), 2);
        let pieces = valid_pieces(&mesh, &field, &cut, &parts);
        let limit = MergeLimit(mesh.face_count());
        let (merged, merges) = merge(&mesh, &field, &cut, pieces.clone(), limit);
        assert_eq!((merges, merged.len()), (0, 2));
        let mut sorted = pieces;
        sorted.sort_by_key(lowest_face);
        assert_eq!(merged, sorted, "untouched, in order of lowest face");
    }

    /// Pieces cut apart by a cut edge are not neighbours.
    #[test]
    fn pieces_meet_only_across_edges_that_are_not_cut() {
        let mesh = shapes::plane(1.0, 8).expect("plane");
        let field = field_along(&mesh, DVec3::X);
        let parts = groups(&mesh, |c| usize::from(c.x > 0.5));
        let pieces = valid_pieces(&mesh, &field, &vec![false; mesh.edge_count()], &parts);
        let open = vec![false; mesh.edge_count()];
        assert_eq!(adjacent_pairs(&mesh, &open, &pieces), vec![(0, 1)]);
        let mut cut = open;
        for (e, c) in cut.iter_mut().enumerate() {
            let [a, b] = mesh.edge_faces()[e];
            if a != NONE && b != NONE {
                let side = |f: u32| {
                    let [p, q, r] = mesh.face_positions(f);
                    (p + q + r).x / 3.0 > 0.5
                };
                *c = side(a) != side(b);
            }
        }
        assert!(adjacent_pairs(&mesh, &cut, &pieces).is_empty());
    }
}
