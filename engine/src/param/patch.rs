//! The cut-open local mesh of a segment and its topology check.
//!
//! Local vertices are the classes of face corners joined through glued edges (segment
//! faces on both sides, not cut, manifold): one local vertex per fan of faces around a
//! mesh vertex. Cost O(F) with a union-find over corners (plus a hash map from mesh
//! faces to local faces, or a per-mesh-face table for a segment that is a large share
//! of the mesh).

use crate::fast_map::{FastMap, fast_map};
use std::collections::hash_map::Entry;

use crate::mesh::{NONE, TriMesh};

use super::ParamError;

/// A segment cut open along its seams.
#[derive(Clone, Debug)]
pub(crate) struct Patch {
    /// Mesh face of each local face.
    pub faces: Vec<u32>,
    /// Local vertex indices per local face, corners in the mesh face's order.
    pub triangles: Vec<[u32; 3]>,
    /// Mesh vertex of each local vertex.
    pub local_to_mesh: Vec<u32>,
    /// Per local face and side `k` (corners `k`, `k + 1`): the local face glued across
    /// that side and the side's index there, or `NONE` on the boundary.
    pub neighbors: Vec<[(u32, u8); 3]>,
}

/// Union-find with path halving; the root of a class is its smallest member.
struct UnionFind(Vec<u32>);

impl UnionFind {
    fn new(n: usize) -> Self {
        Self((0..n as u32).collect())
    }

    fn find(&mut self, mut x: u32) -> u32 {
        while self.0[x as usize] != x {
            let grand = self.0[self.0[x as usize] as usize];
            self.0[x as usize] = grand;
            x = grand;
        }
        x
    }

    fn union(&mut self, a: u32, b: u32) {
        let (a, b) = (self.find(a), self.find(b));
        let (lo, hi) = (a.min(b), a.max(b));
        self.0[hi as usize] = lo;
    }
}

/// A segment of at least 1/`DENSE_SHARE` of the mesh's faces finds its local faces in
/// a per-mesh-face table (filling it costs O(F), less than hashing a large segment);
/// a smaller one in a hash map, so that its cost stays in proportion to its size.
const DENSE_SHARE: usize = 16;

/// The local face of each mesh face of a segment.
enum LocalFaces {
    /// Local face per mesh face, `NONE` outside the segment.
    Table(Vec<u32>),
    /// Local face by mesh face.
    Map(FastMap<u32, u32>),
}

impl LocalFaces {
    /// Room for `len` faces of a mesh of `face_count` faces.
    fn new(len: usize, face_count: usize) -> Self {
        if len * DENSE_SHARE >= face_count {
            Self::Table(vec![NONE; face_count])
        } else {
            Self::Map(fast_map(len))
        }
    }

    /// Records mesh face `f` (below the mesh's face count) as local face `i`; `false`
    /// (and nothing changed) if `f` was recorded already.
    fn insert(&mut self, f: u32, i: u32) -> bool {
        match self {
            Self::Table(table) => {
                let slot = &mut table[f as usize];
                let fresh = *slot == NONE;
                if fresh {
                    *slot = i;
                }
                fresh
            }
            Self::Map(map) => match map.entry(f) {
                Entry::Occupied(_) => false,
                Entry::Vacant(v) => {
                    v.insert(i);
                    true
                }
            },
        }
    }

    /// The local face of mesh face `f`, `None` if it is not in the segment.
    #[inline]
    fn get(&self, f: u32) -> Option<u32> {
        match self {
            Self::Table(table) => table.get(f as usize).copied().filter(|&i| i != NONE),
            Self::Map(map) => map.get(&f).copied(),
        }
    }
}

impl Patch {
    /// Builds the cut-open patch and checks that it is a connected disc.
    pub fn build(mesh: &TriMesh, faces: &[u32], cut: &[bool]) -> Result<Self, ParamError> {
        if faces.is_empty() {
            return Err(ParamError::EmptySegment);
        }
        if cut.len() != mesh.edge_count() {
            return Err(ParamError::CutMaskLength {
                expected: mesh.edge_count(),
                found: cut.len(),
            });
        }
        let mut local_of = LocalFaces::new(faces.len(), mesh.face_count());
        for (i, &f) in faces.iter().enumerate() {
            if f as usize >= mesh.face_count() {
                return Err(ParamError::FaceOutOfRange {
                    face: f,
                    face_count: mesh.face_count(),
                });
            }
            if !local_of.insert(f, i as u32) {
                return Err(ParamError::DuplicateFace { face: f });
            }
        }

        let tris = mesh.triangles();
        let mut neighbors = vec![[(NONE, 0u8); 3]; faces.len()];
        let mut corners = UnionFind::new(3 * faces.len());
        for (i, &f) in faces.iter().enumerate() {
            let t = tris[f as usize];
            for k in 0..3 {
                let e = mesh.face_edges()[f as usize][k];
                let g = mesh.face_neighbors()[f as usize][k];
                if g == NONE || cut[e as usize] {
                    continue;
                }
                let Some(j) = local_of.get(g) else {
                    continue;
                };
                let Some(kg) = mesh.face_edges()[g as usize].iter().position(|&x| x == e) else {
                    continue;
                };
                let tg = tris[g as usize];
                // Glued sides must run in opposite directions.
                if tg[kg] != t[(k + 1) % 3] || tg[(kg + 1) % 3] != t[k] {
                    return Err(ParamError::InconsistentOrientation { edge: e });
                }
                neighbors[i][k] = (j, kg as u8);
                let c = |face: usize, corner: usize| (3 * face + corner) as u32;
                corners.union(c(i, k), c(j as usize, (kg + 1) % 3));
                corners.union(c(i, (k + 1) % 3), c(j as usize, kg));
            }
        }

        // Local vertices numbered in order of first appearance.
        let mut id_of_root = vec![NONE; 3 * faces.len()];
        let mut local_to_mesh = Vec::new();
        let mut triangles = Vec::with_capacity(faces.len());
        for (i, &f) in faces.iter().enumerate() {
            let t = tris[f as usize];
            let mut lt = [0u32; 3];
            for k in 0..3 {
                let root = corners.find((3 * i + k) as u32) as usize;
                if id_of_root[root] == NONE {
                    id_of_root[root] = local_to_mesh.len() as u32;
                    local_to_mesh.push(t[k]);
                }
                lt[k] = id_of_root[root];
            }
            triangles.push(lt);
        }

        let patch = Self {
            faces: faces.to_vec(),
            triangles,
            local_to_mesh,
            neighbors,
        };
        patch.check_disc()?;
        Ok(patch)
    }

    /// Connected (through glued sides), Euler characteristic 1, one boundary loop.
    fn check_disc(&self) -> Result<(), ParamError> {
        let components = self.component_count();
        if components != 1 {
            return Err(ParamError::Disconnected { components });
        }
        let mut glued = 0i64;
        let mut boundary = 0i64;
        let mut loops = UnionFind::new(self.local_to_mesh.len());
        let mut on_boundary = vec![false; self.local_to_mesh.len()];
        for (t, nb) in self.triangles.iter().zip(&self.neighbors) {
            for k in 0..3 {
                if nb[k].0 == NONE {
                    boundary += 1;
                    let (a, b) = (t[k], t[(k + 1) % 3]);
                    loops.union(a, b);
                    on_boundary[a as usize] = true;
                    on_boundary[b as usize] = true;
                } else {
                    glued += 1;
                }
            }
        }
        let edges = glued / 2 + boundary;
        let chi = self.local_to_mesh.len() as i64 - edges + self.faces.len() as i64;
        let mut boundary_loops = 0;
        for v in 0..self.local_to_mesh.len() as u32 {
            if on_boundary[v as usize] && loops.find(v) == v {
                boundary_loops += 1;
            }
        }
        if chi != 1 || boundary_loops != 1 {
            return Err(ParamError::NotADisc {
                euler_characteristic: chi,
                boundary_loops,
            });
        }
        Ok(())
    }

    /// Number of connected components of the face graph through glued sides.
    fn component_count(&self) -> usize {
        let mut seen = vec![false; self.faces.len()];
        let mut stack = Vec::new();
        let mut components = 0;
        for start in 0..self.faces.len() {
            if seen[start] {
                continue;
            }
            components += 1;
            seen[start] = true;
            stack.push(start);
            while let Some(f) = stack.pop() {
                for &(g, _) in &self.neighbors[f] {
                    if g != NONE && !seen[g as usize] {
                        seen[g as usize] = true;
                        stack.push(g as usize);
                    }
                }
            }
        }
        components
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Both ways of finding local faces (a table for a large share of the mesh, a map
    /// otherwise) record, refuse duplicates and look up alike.
    #[test]
    fn local_faces_table_and_map_agree() {
        let face_count = 100;
        for len in [3, 10] {
            let mut local = LocalFaces::new(len, face_count);
            assert_eq!(
                matches!(local, LocalFaces::Table(_)),
                len == 10,
                "len {len}"
            );
            let faces: Vec<u32> = (0..len as u32).map(|i| 97 - 9 * i).collect();
            for (i, &f) in faces.iter().enumerate() {
                assert!(local.insert(f, i as u32), "face {f}");
            }
            assert!(!local.insert(faces[1], 99), "a duplicate is refused");
            for f in 0..face_count as u32 + 1 {
                let want = faces.iter().position(|&g| g == f).map(|i| i as u32);
                assert_eq!(local.get(f), want, "len {len}, face {f}");
            }
        }
    }
}
