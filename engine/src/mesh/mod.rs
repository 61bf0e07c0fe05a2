//! Triangle meshes with adjacency, built once and then read by every later stage.
//!
//! Input: vertex positions and polygons (from arrays, [`io::load`](crate::io::load) for
//! OBJ/PLY files, or a built-in [`shapes`] generator). Output: a validated [`TriMesh`]
//! whose adjacency (edges, edge-to-face, face neighbours, vertex one-rings, boundary
//! loops, connected components), face areas and area-weighted vertex normals are
//! computed once in O(F log F). Repairs (merged duplicate vertices, removed degenerate
//! faces) and findings (non-manifold edges, several components) come back as
//! [`MeshWarning`]s.
//!
//! Once a `TriMesh` exists it is known-valid: indices are in range, coordinates are
//! finite, every face has positive area. Later stages do not re-check.

mod error;
pub(crate) mod face_set;
mod label_smoothing;
pub mod shapes;
mod subdivide;
pub(crate) mod topology;

pub use error::{MeshError, MeshWarning};
pub use face_set::{FaceSet, HopDistances, connected_parts, group_by_label, touching_groups};
pub use subdivide::loop_subdivide;
pub use topology::{MAX_COORDINATE, MIN_EXTENT};

use glam::DVec3;

/// Marker for "no face" / "no edge" in adjacency arrays.
pub const NONE: u32 = u32::MAX;

/// A validated triangle mesh with adjacency.
///
/// Vertices and faces are indexed by `u32`. Edge `k` of face `f` joins corners `k` and
/// `(k + 1) % 3` of `triangles[f]`.
#[derive(Clone, Debug)]
pub struct TriMesh {
    pub(crate) positions: Vec<DVec3>,
    pub(crate) triangles: Vec<[u32; 3]>,
    /// Undirected edges as sorted vertex pairs.
    pub(crate) edges: Vec<[u32; 2]>,
    /// Per edge, its first two faces (`NONE` where absent).
    pub(crate) edge_faces: Vec<[u32; 2]>,
    /// Per edge, how many faces use it (1 boundary, 2 interior, more: non-manifold).
    pub(crate) edge_valence: Vec<u32>,
    /// Per face, the edge index of each of its three edges.
    pub(crate) face_edges: Vec<[u32; 3]>,
    /// Per face, the neighbour across each edge (`NONE` at boundary or non-manifold edges).
    pub(crate) face_neighbors: Vec<[u32; 3]>,
    /// CSR of faces around each vertex.
    pub(crate) vertex_face_offsets: Vec<u32>,
    pub(crate) vertex_faces: Vec<u32>,
    /// CSR of vertices adjacent to each vertex (sorted).
    pub(crate) vertex_neighbor_offsets: Vec<u32>,
    pub(crate) vertex_neighbors: Vec<u32>,
    /// Per entry of `vertex_neighbors`, the edge joining the two vertices.
    pub(crate) vertex_neighbor_edges: Vec<u32>,
    pub(crate) boundary_loops: Vec<Vec<u32>>,
    pub(crate) face_component: Vec<u32>,
    pub(crate) component_count: usize,
    pub(crate) face_areas: Vec<f64>,
    pub(crate) face_normals: Vec<DVec3>,
    pub(crate) vertex_normals: Vec<DVec3>,
    pub(crate) warnings: Vec<MeshWarning>,
    /// Per input vertex, its index in this mesh (`NONE` if dropped).
    pub(crate) input_vertex_map: Vec<u32>,
}

impl TriMesh {
    /// Builds a mesh from triangles, repairing what can be repaired.
    ///
    /// Vertices at bitwise-identical positions are merged, faces with a repeated vertex
    /// or zero area and duplicated faces are removed, vertices used by no face are
    /// dropped; each repair is listed in [`warnings`](Self::warnings). Errors: empty
    /// mesh, out-of-range index, non-finite coordinate.
    ///
    /// ```
    /// use glam::DVec3;
    /// use strata_engine::mesh::TriMesh;
    /// let mesh = TriMesh::new(
    ///     vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z],
    ///     vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
    /// )?;
    /// assert_eq!(mesh.euler_characteristic(), 2);
    /// assert!(mesh.boundary_loops().is_empty());
    /// # Ok::<(), strata_engine::mesh::MeshError>(())
    /// ```
    pub fn new(positions: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> Result<Self, MeshError> {
        topology::build(positions, triangles, Vec::new())
    }

    /// Builds a mesh from polygons of any size (fan-triangulated), as [`new`](Self::new).
    pub fn from_polygons(positions: Vec<DVec3>, polygons: &[Vec<u32>]) -> Result<Self, MeshError> {
        let mut triangles = Vec::with_capacity(polygons.len());
        let mut triangulated = 0;
        for (face, poly) in polygons.iter().enumerate() {
            if poly.len() < 3 {
                return Err(MeshError::TooFewCorners {
                    face,
                    corners: poly.len(),
                });
            }
            if poly.len() > 3 {
                triangulated += 1;
            }
            for k in 1..poly.len() - 1 {
                triangles.push([poly[0], poly[k], poly[k + 1]]);
            }
        }
        let mut warnings = Vec::new();
        if triangulated > 0 {
            warnings.push(MeshWarning::TriangulatedPolygons {
                count: triangulated,
            });
        }
        topology::build(positions, triangles, warnings)
    }

    /// Vertex positions.
    pub fn positions(&self) -> &[DVec3] {
        &self.positions
    }

    /// Triangles as vertex index triples (counter-clockwise seen from the normal side).
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// Number of faces.
    pub fn face_count(&self) -> usize {
        self.triangles.len()
    }

    /// Number of undirected edges.
    pub fn edge_count(&self) -> usize {
        self.edges.len()
    }

    /// The three corner positions of face `f`.
    pub fn face_positions(&self, f: u32) -> [DVec3; 3] {
        let t = self.triangles[f as usize];
        t.map(|v| self.positions[v as usize])
    }

    /// Undirected edges as sorted vertex pairs.
    pub fn edges(&self) -> &[[u32; 2]] {
        &self.edges
    }

    /// Per edge, its first two faces ([`NONE`] where absent).
    pub fn edge_faces(&self) -> &[[u32; 2]] {
        &self.edge_faces
    }

    /// Per edge, the number of faces that use it (1: boundary, 2: interior, more:
    /// non-manifold).
    pub fn edge_valence(&self) -> &[u32] {
        &self.edge_valence
    }

    /// Per face, the indices of its edges (edge `k` joins corners `k` and `k + 1`).
    pub fn face_edges(&self) -> &[[u32; 3]] {
        &self.face_edges
    }

    /// Per face, the neighbouring face across each edge, or [`NONE`] at boundary and
    /// non-manifold edges.
    pub fn face_neighbors(&self) -> &[[u32; 3]] {
        &self.face_neighbors
    }

    /// The faces around vertex `v`.
    pub fn vertex_faces(&self, v: u32) -> &[u32] {
        let r = self.vertex_face_offsets[v as usize] as usize
            ..self.vertex_face_offsets[v as usize + 1] as usize;
        &self.vertex_faces[r]
    }

    /// The vertices adjacent to vertex `v` (its one-ring), sorted by index.
    pub fn vertex_neighbors(&self, v: u32) -> &[u32] {
        let r = self.vertex_neighbor_offsets[v as usize] as usize
            ..self.vertex_neighbor_offsets[v as usize + 1] as usize;
        &self.vertex_neighbors[r]
    }

    /// The edges around vertex `v`, in the order of [`vertex_neighbors`](Self::vertex_neighbors):
    /// entry `i` joins `v` and `vertex_neighbors(v)[i]`.
    pub fn vertex_edges(&self, v: u32) -> &[u32] {
        let r = self.vertex_neighbor_offsets[v as usize] as usize
            ..self.vertex_neighbor_offsets[v as usize + 1] as usize;
        &self.vertex_neighbor_edges[r]
    }

    /// Boundary loops as vertex sequences, each following its faces' orientation.
    pub fn boundary_loops(&self) -> &[Vec<u32>] {
        &self.boundary_loops
    }

    /// Connected component of each face (components are numbered from 0 in order of
    /// their lowest face).
    pub fn face_components(&self) -> &[u32] {
        &self.face_component
    }

    /// Number of connected components (faces joined through manifold edges).
    pub fn component_count(&self) -> usize {
        self.component_count
    }

    /// Euler characteristic V - E + F.
    pub fn euler_characteristic(&self) -> i64 {
        self.positions.len() as i64 - self.edges.len() as i64 + self.triangles.len() as i64
    }

    /// Face areas.
    pub fn face_areas(&self) -> &[f64] {
        &self.face_areas
    }

    /// Total surface area.
    pub fn area(&self) -> f64 {
        self.face_areas.iter().sum()
    }

    /// Unit face normals.
    pub fn face_normals(&self) -> &[DVec3] {
        &self.face_normals
    }

    /// Unit area-weighted vertex normals.
    pub fn vertex_normals(&self) -> &[DVec3] {
        &self.vertex_normals
    }

    /// Repairs made and findings, in the order they were found.
    pub fn warnings(&self) -> &[MeshWarning] {
        &self.warnings
    }

    /// For each vertex of the input (as given to the constructor or read from a file),
    /// its index in this mesh, or [`NONE`] if it was dropped. Use it to carry
    /// per-vertex input data (for example tensors read from a file) over repairs.
    pub fn input_vertex_map(&self) -> &[u32] {
        &self.input_vertex_map
    }

    /// Axis-aligned bounding box `(min, max)`.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        self.positions.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        )
    }

    /// Mean edge length (a natural length scale of the mesh).
    pub fn mean_edge_length(&self) -> f64 {
        let sum: f64 = self
            .edges
            .iter()
            .map(|[a, b]| self.positions[*a as usize].distance(self.positions[*b as usize]))
            .sum();
        sum / self.edges.len().max(1) as f64
    }
}

#[cfg(test)]
mod tests;
