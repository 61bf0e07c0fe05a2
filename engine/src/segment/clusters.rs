//! Singularities seen at the scale of the mesh: singular faces that touch (share a
//! vertex) form one cluster, and the cluster's index is the sum of theirs, which is the
//! winding of the field around the cluster's outline. A `+1/2` face next to a `-1/2`
//! face is a dipole: around both the field does not wind at all, so at any scale above
//! one face it is no singularity. Dipoles appear where the discretisation cannot
//! resolve the field (vertex tangent planes nearly perpendicular to a face at a sharp
//! crease, a field that nearly vanishes); a sampler treats them like any singular face
//! (isotropically), but they say nothing about the field's topology.
//!
//! Input: a mesh and its [`Singularity`] list. Output: [`SingularityCluster`]s in
//! order of their lowest face. Cost: a union-find over the singular faces
//! ([`touching_groups`]).

use super::Singularity;
use crate::mesh::{TriMesh, touching_groups};

/// A group of singular faces joined through shared vertices.
#[derive(Clone, Debug, PartialEq)]
pub struct SingularityCluster {
    /// Its faces, ascending.
    pub faces: Vec<u32>,
    /// The sum of their indices: the field's winding around the group, a multiple of
    /// 1/2; 0 for a dipole (or any group whose windings cancel).
    pub index: f64,
}

impl SingularityCluster {
    /// Whether the field winds around the cluster (its index is not zero).
    pub fn is_singular(&self) -> bool {
        self.index != 0.0
    }
}

/// Groups `singularities` (faces of `mesh`, as from
/// [`detect_singularities`](super::detect_singularities)) into clusters of faces that
/// share a vertex, in order of each cluster's lowest face.
///
/// ```
/// use strata_engine::{field::FieldSpec, mesh::shapes, segment::{detect_singularities, singularity_clusters}};
/// let mesh = shapes::sphere(1.0, 6)?;
/// let spec = FieldSpec::Constant { direction: [1.0, 0.3, 0.2], anisotropy: 2.0, density: 1.0 };
/// let found = detect_singularities(&mesh, &spec.build(&mesh)?);
/// let clusters = singularity_clusters(&mesh, &found);
/// let total: f64 = clusters.iter().map(|c| c.index).sum();
/// assert_eq!(total, 2.0); // clustering keeps the index sum
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn singularity_clusters(
    mesh: &TriMesh,
    singularities: &[Singularity],
) -> Vec<SingularityCluster> {
    let mut faces: Vec<(u32, f64)> = singularities.iter().map(|s| (s.face, s.index)).collect();
    faces.sort_by_key(|&(f, _)| f);
    let ids: Vec<u32> = faces.iter().map(|&(f, _)| f).collect();
    touching_groups(mesh, &ids)
        .into_iter()
        .map(|group| {
            let index = group
                .iter()
                .map(|f| faces[ids.binary_search(f).expect("a listed face")].1)
                .sum();
            SingularityCluster {
                faces: group,
                index,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::shapes;

    #[test]
    fn touching_faces_merge_and_their_indices_add() {
        let mesh = shapes::plane(1.0, 4).expect("plane");
        // Faces 0 and 1 share an edge; face 31 is the far corner's.
        let found = [
            Singularity {
                face: 31,
                index: 0.5,
            },
            Singularity {
                face: 1,
                index: -0.5,
            },
            Singularity {
                face: 0,
                index: 0.5,
            },
        ];
        let clusters = singularity_clusters(&mesh, &found);
        assert_eq!(clusters.len(), 2);
        assert_eq!(clusters[0].faces, vec![0, 1]);
        assert_eq!(clusters[0].index, 0.0);
        assert!(!clusters[0].is_singular());
        assert_eq!(clusters[1].faces, vec![31]);
        assert_eq!(clusters[1].index, 0.5);
        assert!(singularity_clusters(&mesh, &[]).is_empty());
    }

    #[test]
    fn faces_sharing_only_a_vertex_merge_and_distant_ones_do_not() {
        let mesh = shapes::plane(1.0, 8).expect("plane");
        let share = |a: u32, b: u32| {
            let (ta, tb) = (mesh.triangles()[a as usize], mesh.triangles()[b as usize]);
            ta.iter().any(|v| tb.contains(v))
        };
        let f = 20;
        let touching = (0..mesh.face_count() as u32)
            .find(|&g| {
                g != f && share(f, g) && {
                    let fe = mesh.face_edges();
                    !fe[f as usize].iter().any(|e| fe[g as usize].contains(e))
                }
            })
            .expect("a face meeting face 20 at a vertex only");
        let far = (0..mesh.face_count() as u32)
            .find(|&g| {
                !share(f, g)
                    && !mesh.triangles()[g as usize]
                        .iter()
                        .any(|&v| mesh.vertex_faces(v).iter().any(|&h| share(h, f)))
            })
            .expect("a distant face");
        let at = |face, index| Singularity { face, index };
        let c = singularity_clusters(&mesh, &[at(f, 0.5), at(touching, 0.5), at(far, -0.5)]);
        assert_eq!(c.len(), 2, "{c:?}");
        assert_eq!(c.iter().map(|c| c.faces.len()).sum::<usize>(), 3);
        assert!(c.iter().any(|c| c.index == 1.0 && c.faces.len() == 2));
    }
}
