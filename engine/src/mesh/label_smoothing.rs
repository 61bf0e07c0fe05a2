//! Smoothing of the borders between labelled parts of a face set: faces that stick
//! out of their part into another (ears) or fill one-face notches of it move to the
//! part that holds two of their edges.
//!
//! A field-aligned map of a piece stretches and turns its border; a border that zigzags
//! by single faces (an ear hanging by one edge, a notch one face wide) folds over
//! itself under that map, and the piece fails the overlap test for a defect a few
//! edges long (bench/README.md, "Borders that fold"). Splits by hop distance and by
//! the random walk leave such zigzags; moving each face that shares two edges with
//! another part into that part removes them.
//!
//! Each move shortens the total border by at least one edge, so the smoothing ends
//! after at most as many moves as there are border edges; a move never disconnects a part nor
//! changes its Euler characteristic (see [`FaceSet::smooth_labels`]). Cost: O(size of
//! the set) plus O(1) per move; sequential, in a fixed order, so deterministic.

use std::collections::VecDeque;

use super::{FaceSet, NONE, TriMesh};

impl FaceSet {
    /// Moves faces of the set between labels (`labels`, one per mesh face, `NONE`
    /// outside the set) until no face shares two or more edges with faces of one other
    /// label. Two faces are adjacent across a manifold edge not in `cut` when both are in
    /// the set. Returns the number of moves.
    ///
    /// A face is moved only when the move keeps both parts' topology: its old part
    /// holds at most one of its edges (so it hangs by that edge and stays connected
    /// without it), and every other face around the corner between the two shared
    /// edges already has the new label, across edges that are neither cut nor on the
    /// border of the mesh (so the new part does not close a ring around that corner).
    /// A face that is a part on its own joins its neighbours' label.
    ///
    /// ```
    /// use strata_engine::mesh::{FaceSet, NONE, shapes};
    /// let mesh = shapes::plane(1.0, 4)?; // 32 faces, two per grid square
    /// let set = FaceSet::all(&mesh);
    /// // Left half 0, right half 1, and one face of the right half labelled 0:
    /// // it shares two edges with the right half, so it moves back.
    /// let mut labels: Vec<u32> = (0..32).map(|f| u32::from(f % 8 >= 4)).collect();
    /// labels[13] = 0;
    /// let cut = vec![false; mesh.edge_count()];
    /// assert_eq!(set.smooth_labels(&mesh, &cut, &mut labels), 1);
    /// assert_eq!(labels[13], 1);
    /// # Ok::<(), strata_engine::mesh::MeshError>(())
    /// ```
    pub fn smooth_labels(&self, mesh: &TriMesh, cut: &[bool], labels: &mut [u32]) -> usize {
        let places = self.places(mesh);
        let faces = places.faces();
        let mut queued = vec![true; faces.len()];
        let mut queue: VecDeque<u32> = faces.iter().copied().collect();
        let neighbors = mesh.face_neighbors();
        let mut moves = 0;
        while let Some(f) = queue.pop_front() {
            if let Some(i) = places.index(f) {
                queued[i] = false;
            }
            let Some(to) = self.target_label(mesh, cut, labels, f) else {
                continue;
            };
            labels[f as usize] = to;
            moves += 1;
            for &g in &neighbors[f as usize] {
                if g != NONE
                    && let Some(j) = places.index(g)
                    && !queued[j]
                {
                    queued[j] = true;
                    queue.push_back(g);
                }
            }
        }
        moves
    }

    /// The set split into the connected parts of equal `labels` (as
    /// [`parts`](Self::parts)), with the borders between parts smoothed first: each
    /// part gets a label of its own, so that a move never joins two parts of one label
    /// around another (which would make a ring), then
    /// [`smooth_labels`](Self::smooth_labels). Parts in the order of their lowest face.
    pub fn smoothed_parts(&self, mesh: &TriMesh, cut: &[bool], labels: &[u32]) -> Vec<Vec<u32>> {
        let parts = self.parts(mesh, labels, cut);
        let mut own = vec![NONE; labels.len()];
        for (id, part) in parts.iter().enumerate() {
            for &f in part {
                own[f as usize] = id as u32;
            }
        }
        if self.smooth_labels(mesh, cut, &mut own) == 0 {
            return parts;
        }
        self.parts(mesh, &own, cut)
    }

    /// The label face `f` should move to, if any (see [`smooth_labels`](Self::smooth_labels)).
    fn target_label(&self, mesh: &TriMesh, cut: &[bool], labels: &[u32], f: u32) -> Option<u32> {
        let own = labels[f as usize];
        let mut adjacent = [NONE; 3];
        for (k, slot) in adjacent.iter_mut().enumerate() {
            let g = mesh.face_neighbors()[f as usize][k];
            let e = mesh.face_edges()[f as usize][k] as usize;
            if g != NONE && !cut[e] && self.contains(g) {
                *slot = labels[g as usize];
            }
        }
        let count = |l: u32| adjacent.iter().filter(|&&a| a == l).count();
        let to = adjacent
            .iter()
            .copied()
            .find(|&l| l != NONE && l != own && count(l) >= 2)?;
        // The corner between the two shared edges. Joining it must not close the new
        // part around something else: every other face around it is already in it.
        let Some(k) = adjacent.iter().position(|&l| l != to) else {
            return Some(to); // all three edges shared: f fills a one-face hole
        };
        let tip = mesh.triangles()[f as usize][(k + 2) % 3];
        let valence = mesh.edge_valence();
        let closed = mesh
            .vertex_edges(tip)
            .iter()
            .all(|&e| valence[e as usize] == 2 && !cut[e as usize]);
        let surrounded = mesh
            .vertex_faces(tip)
            .iter()
            .all(|&g| g == f || (self.contains(g) && labels[g as usize] == to));
        (closed && surrounded).then_some(to)
    }
}

#[cfg(test)]
mod tests {
    use crate::mesh::{FaceSet, NONE, TriMesh, connected_parts, group_by_label, shapes};
    use crate::rng::mix64;
    use crate::segment::patch_topology;

    /// Labels of the `n` x `n` unit plane: the nearest of `seeds` (points in the unit
    /// square) to each face's centre, with every face's label swapped for a
    /// neighbour's with probability `noise` (a hash of the face and `salt`).
    fn noisy_voronoi(mesh: &TriMesh, seeds: &[[f64; 2]], noise: f64, salt: u64) -> Vec<u32> {
        let centre = |f: usize| {
            let t = mesh.triangles()[f];
            t.iter()
                .map(|&v| mesh.positions()[v as usize])
                .sum::<glam::DVec3>()
                / 3.0
        };
        let nearest: Vec<u32> = (0..mesh.face_count())
            .map(|f| {
                let c = centre(f);
                (0..seeds.len() as u32)
                    .min_by(|&a, &b| {
                        let d = |s: [f64; 2]| (c.x - s[0]).powi(2) + (c.y - s[1]).powi(2);
                        d(seeds[a as usize]).total_cmp(&d(seeds[b as usize]))
                    })
                    .unwrap_or(0)
            })
            .collect();
        (0..mesh.face_count())
            .map(|f| {
                let h = mix64(f as u64 ^ salt.rotate_left(17));
                let g = mesh.face_neighbors()[f][(h % 3) as usize];
                if ((h >> 11) as f64) / ((1u64 << 53) as f64) < noise && g != NONE {
                    nearest[g as usize]
                } else {
                    nearest[f]
                }
            })
            .collect()
    }

    /// Edges between faces of different labels (both in the set).
    fn border_edges(mesh: &TriMesh, labels: &[u32]) -> usize {
        mesh.edge_faces()
            .iter()
            .filter(|&&[a, b]| a != NONE && b != NONE && labels[a as usize] != labels[b as usize])
            .count()
    }

    #[test]
    fn an_ear_and_a_notch_move_to_the_part_that_holds_two_of_their_edges() {
        // Plane 4 x 4: faces 2k and 2k + 1 share square k (row-major). Left columns 0,
        // right columns 1. Either face of square 5 (row 1, column 1, beside the
        // border) given to the right part sticks out of it (an ear) and leaves a notch
        // in the left part: it goes back, and the border gets shorter.
        let mesh = shapes::plane(1.0, 4).expect("plane");
        let column = |f: usize| (f / 2) % 4;
        let base: Vec<u32> = (0..32).map(|f| u32::from(column(f) >= 2)).collect();
        let set = FaceSet::all(&mesh);
        let cut = vec![false; mesh.edge_count()];
        for f in [10, 11] {
            let mut labels = base.clone();
            labels[f] = 1;
            let before = border_edges(&mesh, &labels);
            let moves = set.smooth_labels(&mesh, &cut, &mut labels);
            assert_eq!(moves, 1, "face {f}");
            assert_eq!(labels, base, "face {f}");
            assert!(border_edges(&mesh, &labels) < before, "face {f}");
        }
        // Straight borders do not move.
        let mut labels = base.clone();
        assert_eq!(set.smooth_labels(&mesh, &cut, &mut labels), 0);
        assert_eq!(labels, base);
    }

    #[test]
    fn cut_edges_do_not_count_as_shared() {
        let mesh = shapes::plane(1.0, 4).expect("plane");
        let set = FaceSet::all(&mesh);
        let base: Vec<u32> = (0..32).map(|f| u32::from((f / 2) % 4 >= 2)).collect();
        let mut ear = base.clone();
        ear[11] = 1;
        let moved = {
            let mut labels = ear.clone();
            set.smooth_labels(&mesh, &vec![false; mesh.edge_count()], &mut labels);
            labels
        };
        assert_eq!(moved, base);
        // Cut every edge of face 11: nothing is adjacent to it, nothing moves.
        let mut cut = vec![false; mesh.edge_count()];
        for &e in &mesh.face_edges()[11] {
            cut[e as usize] = true;
        }
        let mut labels = ear.clone();
        assert_eq!(set.smooth_labels(&mesh, &cut, &mut labels), 0);
        assert_eq!(labels, ear);
    }

    #[test]
    fn smoothing_keeps_every_part_connected_with_its_topology_and_leaves_no_movable_face() {
        let mesh = shapes::plane(1.0, 24).expect("plane");
        let set = FaceSet::all(&mesh);
        let cut = vec![false; mesh.edge_count()];
        let seeds = [[0.2, 0.3], [0.7, 0.2], [0.5, 0.8], [0.85, 0.75], [0.4, 0.5]];
        for salt in 0..6 {
            let noisy = noisy_voronoi(&mesh, &seeds, 0.15, salt);
            let mut labels = connected_parts(&mesh, &noisy, &cut);
            let parts_before = group_by_label(&labels, 0..mesh.face_count() as u32);
            let topology_before: Vec<i64> = parts_before
                .iter()
                .map(|p| patch_topology(&mesh, p, &cut).euler_characteristic)
                .collect();
            let borders = border_edges(&mesh, &labels);
            let moves = set.smooth_labels(&mesh, &cut, &mut labels);
            assert!(moves > 0, "salt {salt}: the noise leaves ears");
            // Every move removes at least one border edge.
            assert!(
                border_edges(&mesh, &labels) + moves <= borders,
                "salt {salt}"
            );
            // Parts stay connected (a label is still one part) with their Euler
            // characteristic; a part may vanish (a single face joins its neighbours).
            let relabelled = connected_parts(&mesh, &labels, &cut);
            let after = group_by_label(&labels, 0..mesh.face_count() as u32);
            assert_eq!(
                after.len(),
                group_by_label(&relabelled, 0..mesh.face_count() as u32).len(),
                "salt {salt}: a label split into two parts"
            );
            for part in &after {
                let label = labels[part[0] as usize];
                // `connected_parts` numbers parts 0.., so label i was part i.
                let now = patch_topology(&mesh, part, &cut).euler_characteristic;
                assert_eq!(
                    now, topology_before[label as usize],
                    "salt {salt}: label {label}"
                );
            }
            // A fixed point: nothing more moves.
            let mut again = labels.clone();
            assert_eq!(set.smooth_labels(&mesh, &cut, &mut again), 0, "salt {salt}");
        }
    }

    #[test]
    fn smoothed_parts_cover_the_set_once_and_do_not_depend_on_the_face_order() {
        let mesh = shapes::sphere(1.0, 3).expect("sphere");
        let cut = vec![false; mesh.edge_count()];
        let labels: Vec<u32> = (0..mesh.face_count())
            .map(|f| {
                let c = mesh.triangles()[f]
                    .iter()
                    .map(|&v| mesh.positions()[v as usize])
                    .sum::<glam::DVec3>();
                let jitter = (mix64(f as u64) % 7) as f64 * 0.02;
                u32::from(c.x + jitter > 0.0)
            })
            .collect();
        let forward: Vec<u32> = (0..mesh.face_count() as u32).collect();
        let mut backward = forward.clone();
        backward.reverse();
        let a = FaceSet::new(&mesh, &forward).smoothed_parts(&mesh, &cut, &labels);
        let b = FaceSet::new(&mesh, &backward).smoothed_parts(&mesh, &cut, &labels);
        let sorted = |parts: &[Vec<u32>]| -> Vec<Vec<u32>> {
            parts
                .iter()
                .map(|p| {
                    let mut p = p.clone();
                    p.sort_unstable();
                    p
                })
                .collect()
        };
        assert_eq!(sorted(&a), sorted(&b));
        let mut all: Vec<u32> = a.concat();
        all.sort_unstable();
        assert_eq!(all, forward);
        // Two hemispheres with jagged borders: still two discs.
        assert_eq!(a.len(), 2);
        assert!(a.iter().all(|p| patch_topology(&mesh, p, &cut).is_disc()));
    }
}
