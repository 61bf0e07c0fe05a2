//! Subsets of a mesh's faces and breadth-first tools over the face graph.
//!
//! Input: a [`TriMesh`], a subset of its faces ([`FaceSet`]), a per-edge `cut` (or
//! `blocked`) mask of edges the graph may not cross and, for grouping, a label per face.
//! Output: hop distances from a face, two faces far apart (a double sweep), faces
//! grouped by label, and the connected parts of equal label. Two faces are adjacent
//! when they share a manifold edge (exactly two faces) that is not cut.
//!
//! Cost: O(F) per call for the per-face arrays, plus O(size of the set) for the sweep
//! itself; sequential. The segmentation (its disc fallback) and the split of invalid
//! segments (paper section 5.2) both use these; the disc test itself is
//! [`is_disc`](crate::segment::is_disc), beside the patch topology it reads.

use std::collections::{BTreeMap, VecDeque};

use super::{NONE, TriMesh};

/// The faces of a mask, ascending, and each one's place among them: the index of code
/// that sizes its arrays by a mask rather than the mesh, so that work on a small
/// segment of a large mesh costs in proportion to the segment. Building it is one
/// O(F) scan of the mask; [`index`](Self::index) is the identity when the mask is the
/// whole mesh, a table lookup when the mask holds at least 1/[`DENSE_SHARE`] of the
/// mesh (the table costs O(F) to fill, a small price next to the mask's own work),
/// and a binary search otherwise.
#[derive(Clone, Debug)]
pub(crate) struct MaskFaces {
    faces: Vec<u32>,
    places: Places,
}

/// A mask of at least 1/`DENSE_SHARE` of the mesh gets a per-mesh-face table of places:
/// filling it (one O(F) pass) costs less than the binary searches it saves, which
/// miss the cache once the mask has hundreds of thousands of faces.
pub(crate) const DENSE_SHARE: usize = 16;

/// How [`MaskFaces::index`] finds a face's place.
#[derive(Clone, Debug)]
enum Places {
    /// Every mesh face: the place is the face.
    Whole,
    /// Place per mesh face, `NONE` outside the mask.
    Table(Vec<u32>),
    /// Binary search in the faces.
    Search,
}

impl MaskFaces {
    /// The faces where `mask` holds.
    pub(crate) fn new(mask: &[bool]) -> Self {
        let faces: Vec<u32> = (0..mask.len() as u32)
            .filter(|&f| mask[f as usize])
            .collect();
        Self::from_sorted(faces, mask.len())
    }

    /// `faces` (ascending, distinct, each below `face_count`) of a mesh with
    /// `face_count` faces.
    pub(crate) fn from_sorted(faces: Vec<u32>, face_count: usize) -> Self {
        debug_assert!(faces.windows(2).all(|w| w[0] < w[1]), "ascending faces");
        let places = if faces.len() == face_count {
            Places::Whole
        } else if faces.len() * DENSE_SHARE >= face_count {
            let mut table = vec![NONE; face_count];
            for (i, &f) in faces.iter().enumerate() {
                table[f as usize] = i as u32;
            }
            Places::Table(table)
        } else {
            Places::Search
        };
        Self { faces, places }
    }

    /// The faces, ascending.
    pub(crate) fn faces(&self) -> &[u32] {
        &self.faces
    }

    /// The place of face `f` among the faces; `None` if it is not one.
    #[inline]
    pub(crate) fn index(&self, f: u32) -> Option<usize> {
        match &self.places {
            Places::Whole => (f < self.faces.len() as u32).then_some(f as usize),
            Places::Table(table) => table
                .get(f as usize)
                .filter(|&&i| i != NONE)
                .map(|&i| i as usize),
            Places::Search => self.faces.binary_search(&f).ok(),
        }
    }

    /// The faces, ascending, by value.
    pub(crate) fn into_faces(self) -> Vec<u32> {
        self.faces
    }
}

/// A subset of a mesh's faces: a membership flag per mesh face (built once, O(1) to
/// test) and the member faces in the order given (to iterate).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FaceSet {
    /// Per mesh face, whether it is in the set.
    mask: Vec<bool>,
    /// The member faces, each once, in the order given.
    faces: Vec<u32>,
}

impl FaceSet {
    /// The set of `faces` of `mesh`, in the order given (a face given twice is kept
    /// once, at its first place). Cost O(F).
    ///
    /// # Panics
    /// If a face index is out of range.
    pub fn new(mesh: &TriMesh, faces: &[u32]) -> Self {
        let mut mask = vec![false; mesh.face_count()];
        let mut members = Vec::with_capacity(faces.len());
        for &f in faces {
            if !mask[f as usize] {
                mask[f as usize] = true;
                members.push(f);
            }
        }
        Self {
            mask,
            faces: members,
        }
    }

    /// Every face of `mesh`, ascending.
    pub fn all(mesh: &TriMesh) -> Self {
        Self {
            mask: vec![true; mesh.face_count()],
            faces: (0..mesh.face_count() as u32).collect(),
        }
    }

    /// Whether face `f` is in the set.
    #[inline]
    pub fn contains(&self, f: u32) -> bool {
        self.mask[f as usize]
    }

    /// The member faces, in the order given at construction.
    pub fn faces(&self) -> &[u32] {
        &self.faces
    }

    /// The membership flag per mesh face (the mask that [`random_walk`] and
    /// [`place_seeds`] take).
    ///
    /// [`random_walk`]: crate::segment::random_walk
    /// [`place_seeds`]: crate::segment::place_seeds
    pub fn mask(&self) -> &[bool] {
        &self.mask
    }

    /// Number of member faces.
    pub fn len(&self) -> usize {
        self.faces.len()
    }

    /// Whether the set has no face.
    pub fn is_empty(&self) -> bool {
        self.faces.is_empty()
    }

    /// The lowest member face, `None` for an empty set.
    pub fn lowest(&self) -> Option<u32> {
        self.faces.iter().copied().min()
    }

    /// Breadth-first hop distances from `start` over the set's faces, through manifold
    /// edges not in `cut`. Neighbours are visited in the order of the face's edges, so
    /// [`HopDistances::farthest`] (the last face reached) is deterministic.
    pub fn hop_distances(&self, mesh: &TriMesh, cut: &[bool], start: u32) -> HopDistances {
        let mut dist = vec![u32::MAX; mesh.face_count()];
        let mut queue = VecDeque::from([start]);
        dist[start as usize] = 0;
        let mut last = start;
        while let Some(f) = queue.pop_front() {
            last = f;
            for (k, &g) in mesh.face_neighbors()[f as usize].iter().enumerate() {
                let e = mesh.face_edges()[f as usize][k] as usize;
                if g != NONE && !cut[e] && self.mask[g as usize] && dist[g as usize] == u32::MAX {
                    dist[g as usize] = dist[f as usize] + 1;
                    queue.push_back(g);
                }
            }
        }
        HopDistances {
            farthest: last,
            dist,
        }
    }

    /// Two faces far apart in the set (a double sweep: the farthest face from the
    /// lowest face, then the farthest from that one), not crossing `cut`. Both are
    /// the same face when the lowest face reaches no other. `None` for an empty set.
    pub fn far_pair(&self, mesh: &TriMesh, cut: &[bool]) -> Option<[u32; 2]> {
        let start = self.lowest()?;
        let places = self.places(mesh);
        let a = self.local_hops(mesh, cut, &places, start).1;
        let b = self.local_hops(mesh, cut, &places, a).1;
        Some([a, b])
    }

    /// Per face of the set, in the set's order, whether it is strictly nearer (in hops,
    /// not crossing `cut`) to `b` than to `a`. Equal to comparing two
    /// [`hop_distances`](Self::hop_distances), with arrays the size of the set.
    pub fn nearer_to_second(&self, mesh: &TriMesh, cut: &[bool], a: u32, b: u32) -> Vec<bool> {
        let places = self.places(mesh);
        let (from_a, _) = self.local_hops(mesh, cut, &places, a);
        let (from_b, _) = self.local_hops(mesh, cut, &places, b);
        self.faces
            .iter()
            .map(|&f| {
                // Every set face has a place.
                let i = places.index(f).unwrap_or(0);
                from_b[i] < from_a[i]
            })
            .collect()
    }

    /// The set's faces, ascending, with their places.
    pub(super) fn places(&self, mesh: &TriMesh) -> MaskFaces {
        let mut sorted = self.faces.clone();
        sorted.sort_unstable();
        MaskFaces::from_sorted(sorted, mesh.face_count())
    }

    /// As [`hop_distances`](Self::hop_distances), but distances per place in `places`
    /// (the set's faces, ascending) instead of per mesh face, and the farthest face.
    fn local_hops(
        &self,
        mesh: &TriMesh,
        cut: &[bool],
        places: &MaskFaces,
        start: u32,
    ) -> (Vec<u32>, u32) {
        let mut dist = vec![u32::MAX; places.faces().len()];
        let Some(s) = places.index(start) else {
            return (dist, start);
        };
        let mut queue = VecDeque::from([(start, s)]);
        dist[s] = 0;
        let mut last = start;
        while let Some((f, i)) = queue.pop_front() {
            last = f;
            for (k, &g) in mesh.face_neighbors()[f as usize].iter().enumerate() {
                let e = mesh.face_edges()[f as usize][k] as usize;
                if g == NONE || cut[e] || !self.mask[g as usize] {
                    continue;
                }
                if let Some(j) = places.index(g)
                    && dist[j] == u32::MAX
                {
                    dist[j] = dist[i] + 1;
                    queue.push_back((g, j));
                }
            }
        }
        (dist, last)
    }

    /// Per mesh face, `label(i)` for the `i`-th face of the set and `NONE` elsewhere.
    pub fn labels(&self, label: impl Fn(usize) -> u32) -> Vec<u32> {
        let mut out = vec![NONE; self.mask.len()];
        for (i, &f) in self.faces.iter().enumerate() {
            out[f as usize] = label(i);
        }
        out
    }

    /// The set's faces grouped into the connected parts of equal `labels` (one label
    /// per mesh face, `NONE` outside the set), not crossing `cut`: parts in the order
    /// of their lowest face, faces within a part in the set's order. Every face is in
    /// exactly one group: set faces labelled `NONE` come last, as one group.
    pub fn parts(&self, mesh: &TriMesh, labels: &[u32], cut: &[bool]) -> Vec<Vec<u32>> {
        // As `connected_parts` numbers them (by lowest face), but visiting only the
        // set's faces: O(set log set) instead of O(F) for a small set (which matters
        // when a small segment of a large mesh is split again and again), a table of
        // places for a large one (see `MaskFaces`).
        let mut sorted = self.faces.clone();
        sorted.sort_unstable();
        let sorted = MaskFaces::from_sorted(sorted, mesh.face_count());
        let local = |f: u32| sorted.index(f);
        let faces = sorted.faces();
        let (part, count) = number_parts(mesh, faces.len(), |i| faces[i], local, labels, cut);
        let mut groups = vec![Vec::new(); count as usize];
        let mut unlabelled = Vec::new();
        for &f in &self.faces {
            // Every set face is in `sorted`.
            match local(f).map(|i| part[i]) {
                Some(p) if p != NONE => groups[p as usize].push(f),
                _ => unlabelled.push(f),
            }
        }
        if !unlabelled.is_empty() {
            groups.push(unlabelled);
        }
        groups
    }
}

/// The result of [`FaceSet::hop_distances`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct HopDistances {
    /// The last face reached: one of the farthest (ties go to the first found).
    pub farthest: u32,
    /// Hops from the start per mesh face, `u32::MAX` where unreached.
    pub dist: Vec<u32>,
}

/// `faces` grouped by `labels[f]`: one group per label, groups in increasing label
/// order, faces in the order given; faces labelled `NONE` are left out.
///
/// For the output of [`connected_parts`] (parts numbered by lowest face) over faces
/// in ascending order this is the faces of each part, parts by lowest face.
pub fn group_by_label(labels: &[u32], faces: impl IntoIterator<Item = u32>) -> Vec<Vec<u32>> {
    let mut groups: BTreeMap<u32, Vec<u32>> = BTreeMap::new();
    for f in faces {
        let l = labels[f as usize];
        if l != NONE {
            groups.entry(l).or_default().push(f);
        }
    }
    groups.into_values().collect()
}

/// The root of `i` in the union-find forest `parent` (`parent[r] == r` at a root),
/// halving the path on the way.
pub(crate) fn find(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

/// `faces` (ascending, no repeats) grouped into sets that touch through shared
/// vertices (union-find), each ascending, in order of their lowest face: the clusters
/// of singular faces of the segmentation and of field design.
///
/// ```
/// use strata_engine::mesh::{shapes, touching_groups};
/// let mesh = shapes::plane(1.0, 4)?;
/// // Faces 0 and 1 share an edge; face 31 is the far corner's.
/// assert_eq!(touching_groups(&mesh, &[0, 1, 31]), vec![vec![0, 1], vec![31]]);
/// # Ok::<(), strata_engine::mesh::MeshError>(())
/// ```
///
/// Cost O(sum of the faces' vertex valences, times log of their count).
pub fn touching_groups(mesh: &TriMesh, faces: &[u32]) -> Vec<Vec<u32>> {
    debug_assert!(faces.windows(2).all(|w| w[0] < w[1]), "ascending faces");
    let mut parent: Vec<usize> = (0..faces.len()).collect();
    for (i, &f) in faces.iter().enumerate() {
        for &v in &mesh.triangles()[f as usize] {
            for g in mesh.vertex_faces(v) {
                if let Ok(j) = faces.binary_search(g) {
                    let (a, b) = (find(&mut parent, i), find(&mut parent, j));
                    // The root is the lowest member, so groups come out in order of
                    // their lowest face.
                    parent[a.max(b)] = a.min(b);
                }
            }
        }
    }
    let mut groups: Vec<Vec<u32>> = Vec::new();
    let mut group_of = vec![usize::MAX; faces.len()];
    for (i, &f) in faces.iter().enumerate() {
        let root = find(&mut parent, i);
        if group_of[root] == usize::MAX {
            group_of[root] = groups.len();
            groups.push(Vec::new());
        }
        groups[group_of[root]].push(f);
    }
    groups
}

/// Whether edge `e` joins exactly two faces.
#[inline]
pub(crate) fn is_interior(mesh: &TriMesh, e: usize) -> bool {
    let [a, b] = mesh.edge_faces()[e];
    mesh.edge_valence()[e] == 2 && a != NONE && b != NONE
}

/// Splits labels into connected parts: two faces keep one label only if they are
/// joined by a path of faces of that label through manifold edges that are not
/// `blocked`. New labels are numbered from 0 in order of each part's lowest face;
/// `u32::MAX` (unlabelled) faces stay `u32::MAX`.
///
/// Cost O(F), sequential.
///
/// # Panics
/// If `labels` or `blocked` do not match the mesh.
pub fn connected_parts(mesh: &TriMesh, labels: &[u32], blocked: &[bool]) -> Vec<u32> {
    let n = mesh.face_count();
    assert_eq!(labels.len(), n, "one label per face");
    assert_eq!(
        blocked.len(),
        mesh.edge_count(),
        "one blocked flag per edge"
    );
    number_parts(mesh, n, |i| i as u32, |f| Some(f as usize), labels, blocked).0
}

/// The connected parts of equal label among `count` faces (`face(i)` the `i`-th, in
/// ascending face order; `index(f)` its position, `None` for a face not among them),
/// through manifold edges not `blocked`: per position its part (numbered from 0 by
/// lowest face; `NONE` where unlabelled), and the number of parts. Breadth-first,
/// sequential; O(count) lookups of `index`.
fn number_parts(
    mesh: &TriMesh,
    count: usize,
    face: impl Fn(usize) -> u32,
    index: impl Fn(u32) -> Option<usize>,
    labels: &[u32],
    blocked: &[bool],
) -> (Vec<u32>, u32) {
    let mut part = vec![NONE; count];
    let mut next = 0u32;
    let mut queue = VecDeque::new();
    for start in 0..count {
        let f0 = face(start);
        let label = labels[f0 as usize];
        if label == NONE || part[start] != NONE {
            continue;
        }
        part[start] = next;
        queue.push_back(f0);
        while let Some(f) = queue.pop_front() {
            for &e in &mesh.face_edges()[f as usize] {
                if blocked[e as usize] || !is_interior(mesh, e as usize) {
                    continue;
                }
                if let Some(g) = across(mesh, e, f)
                    && labels[g as usize] == label
                    && let Some(j) = index(g)
                    && part[j] == NONE
                {
                    part[j] = next;
                    queue.push_back(g);
                }
            }
        }
        next += 1;
    }
    (part, next)
}

/// The face across edge `e` from face `f`, if the edge joins two faces.
#[inline]
pub(crate) fn across(mesh: &TriMesh, e: u32, f: u32) -> Option<u32> {
    let [a, b] = mesh.edge_faces()[e as usize];
    let other = if a == f { b } else { a };
    (a != NONE && b != NONE && other != f).then_some(other)
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;

    #[test]
    fn mask_faces_index_their_members_only() {
        let part = MaskFaces::new(&[false, true, true, false, true]);
        assert_eq!(part.faces(), &[1, 2, 4]);
        let places: Vec<Option<usize>> = (0..6).map(|f| part.index(f)).collect();
        assert_eq!(places, [None, Some(0), Some(1), None, Some(2), None]);
        let whole = MaskFaces::new(&[true; 3]);
        assert_eq!((whole.index(2), whole.index(3)), (Some(2), None));
        assert_eq!(whole.into_faces(), vec![0, 1, 2]);
    }

    /// The table (large masks) and the binary search (small ones) give the same
    /// places as a naive scan, for members, non-members and faces past the mesh.
    #[test]
    fn mask_faces_table_and_search_agree_with_a_scan() {
        let face_count = 1000;
        for step in [1usize, 3, 7, 15, 16, 17, 40, 999] {
            let faces: Vec<u32> = (0..face_count as u32).step_by(step).collect();
            let index = MaskFaces::from_sorted(faces.clone(), face_count);
            let expected = match step {
                1 => matches!(index.places, Places::Whole),
                // 63 faces (step 16) fill a table for 1000, 59 (step 17) do not.
                2..=16 => matches!(index.places, Places::Table(_)),
                _ => matches!(index.places, Places::Search),
            };
            assert!(expected, "step {step}: {:?}", index.places);
            for f in 0..face_count as u32 + 2 {
                let want = faces.iter().position(|&g| g == f);
                assert_eq!(index.index(f), want, "step {step}, face {f}");
            }
        }
    }
    use crate::mesh::shapes;

    /// A strip of `n` triangles, face `i` sharing an edge with faces `i - 1` and
    /// `i + 1` only.
    fn strip(n: u32) -> TriMesh {
        let positions = (0..n + 2)
            .map(|v| DVec3::new(f64::from(v / 2), f64::from(v % 2), 0.0))
            .collect();
        let triangles = (0..n)
            .map(|i| {
                if i % 2 == 0 {
                    [i, i + 2, i + 1]
                } else {
                    [i, i + 1, i + 2]
                }
            })
            .collect();
        TriMesh::new(positions, triangles).expect("strip")
    }

    fn no_cut(mesh: &TriMesh) -> Vec<bool> {
        vec![false; mesh.edge_count()]
    }

    /// The edge shared by faces `a` and `b`.
    fn shared_edge(mesh: &TriMesh, a: u32, b: u32) -> u32 {
        let k = mesh.face_neighbors()[a as usize]
            .iter()
            .position(|&g| g == b)
            .expect("adjacent");
        mesh.face_edges()[a as usize][k]
    }

    #[test]
    fn a_face_set_keeps_the_order_given_and_drops_repeats() {
        let mesh = strip(6);
        let set = FaceSet::new(&mesh, &[4, 1, 4, 3]);
        assert_eq!(set.faces(), &[4, 1, 3]);
        assert_eq!(set.len(), 3);
        assert_eq!(set.lowest(), Some(1));
        assert!(set.contains(4) && !set.contains(0) && !set.contains(2));
        assert_eq!(
            set.mask(),
            &[false, true, false, true, true, false],
            "mask per mesh face"
        );
        assert_eq!(set.labels(|i| 10 + i as u32)[4], 10);
        assert_eq!(set.labels(|i| 10 + i as u32)[0], NONE);
        assert!(FaceSet::new(&mesh, &[]).is_empty());
        assert_eq!(FaceSet::all(&mesh).faces(), &[0, 1, 2, 3, 4, 5]);
    }

    #[test]
    fn hop_distances_on_a_strip_count_faces() {
        let mesh = strip(7);
        let all = FaceSet::all(&mesh);
        let hops = all.hop_distances(&mesh, &no_cut(&mesh), 2);
        assert_eq!(hops.dist, vec![2, 1, 0, 1, 2, 3, 4]);
        assert_eq!(hops.farthest, 6);
        assert_eq!(all.far_pair(&mesh, &no_cut(&mesh)), Some([6, 0]));
        // Faces outside the set are neither crossed nor reached.
        let left = FaceSet::new(&mesh, &[0, 1, 2, 4, 5, 6]);
        let hops = left.hop_distances(&mesh, &no_cut(&mesh), 0);
        assert_eq!(hops.dist[..4], [0, 1, 2, u32::MAX]);
        assert_eq!(hops.dist[4..], [u32::MAX; 3]);
        assert_eq!(hops.farthest, 2);
    }

    #[test]
    fn a_cut_disconnects_the_sweep_and_the_parts() {
        let mesh = strip(6);
        let mut cut = no_cut(&mesh);
        cut[shared_edge(&mesh, 2, 3) as usize] = true;
        let all = FaceSet::all(&mesh);
        let hops = all.hop_distances(&mesh, &cut, 0);
        assert_eq!(hops.dist, vec![0, 1, 2, u32::MAX, u32::MAX, u32::MAX]);
        assert_eq!(all.far_pair(&mesh, &cut), Some([2, 0]));
        let one_label = vec![5; mesh.face_count()];
        assert_eq!(
            all.parts(&mesh, &one_label, &cut),
            vec![vec![0, 1, 2], vec![3, 4, 5]]
        );
        assert_eq!(
            all.parts(&mesh, &one_label, &no_cut(&mesh)),
            vec![(0..6).collect::<Vec<_>>()]
        );
    }

    #[test]
    fn grouping_by_label_orders_groups_by_label_and_keeps_face_order() {
        let labels = [2, 0, 2, NONE, 1, 0];
        assert_eq!(
            group_by_label(&labels, 0..6),
            vec![vec![1, 5], vec![4], vec![0, 2]]
        );
        assert_eq!(
            group_by_label(&labels, [5, 2, 1, 0]),
            vec![vec![5, 1], vec![2, 0]]
        );
    }

    #[test]
    fn parts_split_each_label_into_connected_pieces() {
        let mesh = strip(6);
        // Labels a a b a a b: label a is in two pieces.
        let labels = vec![0, 0, 1, 0, 0, 1];
        let set = FaceSet::all(&mesh);
        assert_eq!(
            set.parts(&mesh, &labels, &no_cut(&mesh)),
            vec![vec![0, 1], vec![2], vec![3, 4], vec![5]]
        );
        // Unlabelled faces of the set come last, together.
        let labels = vec![0, NONE, 0, 0, NONE, 0];
        assert_eq!(
            set.parts(&mesh, &labels, &no_cut(&mesh)),
            vec![vec![0], vec![2, 3], vec![5], vec![1, 4]]
        );
    }

    #[test]
    fn connected_parts_splits_and_renumbers() {
        // A 4 x 4 plane: columns of quads labelled 7, 3, 7, unlabelled.
        let mesh = shapes::plane(1.0, 4).expect("plane");
        let labels: Vec<u32> = (0..mesh.face_count())
            .map(|f| [7, 3, 7, NONE][(f / 2) % 4])
            .collect();
        let parts = connected_parts(&mesh, &labels, &no_cut(&mesh));
        for (f, &p) in parts.iter().enumerate() {
            assert_eq!(p, [0, 1, 2, NONE][(f / 2) % 4], "face {f}");
        }
        // A blocked line between rows 1 and 2 splits every column.
        let p = mesh.positions();
        let blocked: Vec<bool> = mesh
            .edges()
            .iter()
            .map(|[a, b]| p[*a as usize].y == 0.5 && p[*b as usize].y == 0.5)
            .collect();
        let parts = connected_parts(&mesh, &labels, &blocked);
        for (f, &p) in parts.iter().enumerate() {
            let top = f / 8 >= 2;
            let expected = [[0, 1, 2, NONE], [3, 4, 5, NONE]][usize::from(top)][(f / 2) % 4];
            assert_eq!(p, expected, "face {f}");
        }
    }

    /// The set-sized sweeps agree with the per-mesh-face ones they replace: far pairs
    /// from two sweeps of `hop_distances`, and the nearer of two faces from comparing
    /// their distances, on small sets (searched places), large ones (a table) and the
    /// whole mesh, with and without a cut.
    #[test]
    fn set_sized_sweeps_equal_the_mesh_sized_ones() {
        let mesh = crate::mesh::shapes::sphere(1.0, 3).expect("sphere");
        let n = mesh.face_count() as u32;
        let p = mesh.positions();
        let blocked: Vec<bool> = mesh
            .edges()
            .iter()
            .map(|[a, b]| p[*a as usize].z.abs() < 0.3 && p[*b as usize].z.abs() < 0.3)
            .collect();
        let sets = [
            (0..n).filter(|f| f % 7 < 3).rev().collect::<Vec<u32>>(),
            (0..n / 20).collect(),
            (0..n).rev().collect(),
        ];
        for cut in [no_cut(&mesh), blocked] {
            for faces in &sets {
                let set = FaceSet::new(&mesh, faces);
                let start = set.lowest().expect("non-empty");
                let a = set.hop_distances(&mesh, &cut, start).farthest;
                let b = set.hop_distances(&mesh, &cut, a).farthest;
                assert_eq!(set.far_pair(&mesh, &cut), Some([a, b]));
                let (x, y) = (faces[0], faces[faces.len() / 2]);
                let dx = set.hop_distances(&mesh, &cut, x).dist;
                let dy = set.hop_distances(&mesh, &cut, y).dist;
                let want: Vec<bool> = set
                    .faces()
                    .iter()
                    .map(|&f| dy[f as usize] < dx[f as usize])
                    .collect();
                assert_eq!(set.nearer_to_second(&mesh, &cut, x, y), want);
            }
        }
    }
}
