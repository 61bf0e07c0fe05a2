//! The field's decomposition per mesh face, made once for every parameterization of a
//! mesh: splitting and merging parameterize most faces several times (4 to 5 times
//! per face on a million-face mesh), and the per-face eigen-decomposition was about a
//! ninth of each parameterization.
//!
//! Input: a mesh and a field. Output: per face, the major direction and the two
//! eigenvalues of the mean of its corners' tensors in the face's plane (40 bytes per
//! face), the same numbers [`parameterize`](super::parameterize) computes for its faces.
//! Cost O(F), in parallel with rayon; deterministic (each face on its own).

use glam::DVec3;
use rayon::prelude::*;

use crate::field::{Eigen2, TensorField};
use crate::mesh::TriMesh;

use super::comb::face_eigen;

/// One face's decomposition, without the minor axis (`normal x major`, rebuilt).
#[derive(Clone, Copy, Debug, PartialEq)]
struct FaceEigen {
    major: DVec3,
    l: [f64; 2],
}

/// The field's decomposition on every face of one mesh: per face, the major direction
/// and both eigenvalues of the mean of its corners' tensors in the face's plane, the
/// numbers [`parameterize`](super::parameterize) computes for its own faces.
#[derive(Clone, Debug, PartialEq)]
pub struct FaceTensors {
    faces: Vec<FaceEigen>,
}

impl FaceTensors {
    /// Decomposes `field` on every face of `mesh` (the field must be `mesh`'s: one
    /// tensor per vertex).
    pub fn new(mesh: &TriMesh, field: &TensorField) -> Self {
        let faces = (0..mesh.face_count() as u32)
            .into_par_iter()
            .map(|f| {
                let e = face_eigen(mesh, field, f);
                FaceEigen {
                    major: e.major,
                    l: [e.l1, e.l2],
                }
            })
            .collect();
        Self { faces }
    }

    /// Faces covered.
    pub fn len(&self) -> usize {
        self.faces.len()
    }

    /// Whether there are no faces.
    pub fn is_empty(&self) -> bool {
        self.faces.is_empty()
    }

    /// The decomposition on face `f` of `mesh` (the mesh the table was made for).
    pub(crate) fn eigen(&self, mesh: &TriMesh, f: u32) -> Eigen2 {
        let e = self.faces[f as usize];
        Eigen2 {
            major: e.major,
            minor: mesh.face_normals()[f as usize].cross(e.major),
            l1: e.l[0],
            l2: e.l[1],
        }
    }

    /// Heap bytes held.
    pub fn heap_bytes(&self) -> usize {
        self.faces.capacity() * std::mem::size_of::<FaceEigen>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::FieldSpec;
    use crate::mesh::shapes;

    #[test]
    fn the_table_holds_the_decomposition_each_face_computes() {
        let mesh = shapes::sphere(1.0, 3).expect("sphere");
        let field = FieldSpec::Constant {
            direction: [1.0, 0.2, 0.1],
            anisotropy: 3.0,
            density: 2.0,
        }
        .build(&mesh)
        .expect("field");
        let table = FaceTensors::new(&mesh, &field);
        assert_eq!(table.len(), mesh.face_count());
        for f in 0..mesh.face_count() as u32 {
            let direct = face_eigen(&mesh, &field, f);
            let stored = table.eigen(&mesh, f);
            assert_eq!(stored.major.to_array(), direct.major.to_array());
            assert_eq!(stored.minor.to_array(), direct.minor.to_array());
            assert_eq!([stored.l1, stored.l2], [direct.l1, direct.l2]);
        }
    }
}
