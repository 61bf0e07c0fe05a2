//! Segmentation restricted to a region of a mesh, for incremental recomputation.
//!
//! Input: a mesh, a field, a set of faces (the region) and [`SegmentOptions`]. Output: a
//! [`Segmentation`] of the region alone, in the mesh's face, vertex and edge ids (faces
//! outside the region have segment `NONE`). The region is extracted as a mesh of its
//! own and segmented with [`segment`](super::segment()) (seeding regions measured
//! against the whole mesh's area), so its segments satisfy everything `segment`
//! guarantees (connected, singularity-free, discs) and together cover exactly the
//! region. A caller that keeps the segments outside the region and replaces those
//! inside it still has a covering of the whole mesh by disc segments.
//!
//! The field on the extracted mesh is the mesh's tensors re-projected into the
//! extracted mesh's tangent planes, which differ from the mesh's only at vertices on the
//! region boundary (their normals see fewer faces). Cost: that of [`segment`](super::segment()) on the
//! region, plus O(region) to extract it.

use super::pipeline::segment_sized;
use super::{Segment, SegmentError, SegmentOptions, Segmentation, Singularity};
use crate::field::{FieldError, TensorField};
use crate::mesh::{MeshError, NONE, TriMesh};

/// Errors of [`segment_region`].
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RegionError {
    /// The region is empty or names a face the mesh does not have.
    #[error("region face {face} is not a face of the mesh ({face_count} faces)")]
    BadFace {
        /// The offending face (or `u32::MAX` for an empty region).
        face: u32,
        /// The mesh's face count.
        face_count: usize,
    },
    /// The region could not be extracted as a mesh of its own.
    #[error("extracting the region: {0}")]
    Mesh(#[from] MeshError),
    /// Extraction repaired the region (merged, dropped or reordered faces), so its ids
    /// no longer match the mesh's; segment the whole mesh instead.
    #[error("the extracted region does not keep the mesh's faces one to one")]
    NotOneToOne,
    /// The field is not positive definite in the extracted mesh's tangent planes.
    #[error("field on the region: {0}")]
    Field(#[from] FieldError),
    /// Segmenting the region failed.
    #[error("{0}")]
    Segment(#[from] SegmentError),
}

/// Segments only `faces` of `mesh` (see the module docs). `faces` need not be sorted or
/// connected; duplicates are ignored.
///
/// ```
/// use strata_engine::{field::FieldSpec, mesh::shapes, segment::{segment_region, SegmentOptions}};
/// let mesh = shapes::sphere(1.0, 8)?;
/// let field = FieldSpec::Constant { direction: [1.0, 0.0, 0.0], anisotropy: 2.0, density: 1.0 }
///     .build(&mesh)?;
/// let region: Vec<u32> = (0..mesh.face_count() as u32 / 4).collect();
/// let seg = segment_region(&mesh, &field, &region, &SegmentOptions::default())?;
/// let covered: usize = seg.segments.iter().map(|s| s.faces.len()).sum();
/// assert_eq!(covered, region.len());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn segment_region(
    mesh: &TriMesh,
    field: &TensorField,
    faces: &[u32],
    options: &SegmentOptions,
) -> Result<Segmentation, RegionError> {
    let faces = region_faces(faces, mesh.face_count())?;
    let region = Extracted::new(mesh, field, faces)?;
    // Seeding regions are measured against the whole surface, as in a whole build.
    let local = segment_sized(&region.mesh, &region.field, options, mesh.area())?;
    Ok(region.lift(mesh, local))
}

/// `faces` sorted without duplicates; [`RegionError::BadFace`] if it is empty or names
/// a face at or past `face_count`.
fn region_faces(faces: &[u32], face_count: usize) -> Result<Vec<u32>, RegionError> {
    let mut faces = faces.to_vec();
    faces.sort_unstable();
    faces.dedup();
    match faces.last() {
        None => Err(RegionError::BadFace {
            face: u32::MAX,
            face_count,
        }),
        Some(&f) if f as usize >= face_count => Err(RegionError::BadFace {
            face: f,
            face_count,
        }),
        Some(_) => Ok(faces),
    }
}

/// A region extracted as a mesh of its own, with the field on it and the maps back to
/// the mesh's ids.
struct Extracted {
    /// The region's mesh: local face `i` is mesh face `faces[i]`, local vertex `j` is
    /// mesh vertex `global_of[j]`.
    mesh: TriMesh,
    /// The mesh's tensors re-projected into the region mesh's tangent planes.
    field: TensorField,
    /// Per local face, its mesh face (ascending).
    faces: Vec<u32>,
    /// Per local vertex, its mesh vertex (ascending).
    global_of: Vec<u32>,
}

impl Extracted {
    /// Extracts the region of `faces` (sorted, distinct, all in `mesh`): its vertices
    /// in ascending mesh order. [`RegionError::NotOneToOne`] if building the mesh
    /// repaired it.
    fn new(mesh: &TriMesh, field: &TensorField, faces: Vec<u32>) -> Result<Self, RegionError> {
        let mut local_of = vec![NONE; mesh.vertex_count()];
        for &f in &faces {
            for v in mesh.triangles()[f as usize] {
                local_of[v as usize] = 0;
            }
        }
        let mut global_of = Vec::new();
        for (v, slot) in local_of.iter_mut().enumerate() {
            if *slot != NONE {
                *slot = global_of.len() as u32;
                global_of.push(v as u32);
            }
        }
        let positions = global_of
            .iter()
            .map(|&v| mesh.positions()[v as usize])
            .collect();
        let triangles: Vec<[u32; 3]> = faces
            .iter()
            .map(|&f| mesh.triangles()[f as usize].map(|v| local_of[v as usize]))
            .collect();
        let sub = TriMesh::new(positions, triangles.clone())?;
        // The extracted mesh must be the region face for face, vertex for vertex, so
        // that its edge of corner k is the mesh's edge of corner k.
        let identity = sub
            .input_vertex_map()
            .iter()
            .enumerate()
            .all(|(i, &v)| v == i as u32);
        if !identity || sub.triangles() != triangles.as_slice() {
            return Err(RegionError::NotOneToOne);
        }
        let tensors = global_of
            .iter()
            .map(|&v| field.tensors()[v as usize])
            .collect();
        let sub_field = TensorField::new(&sub, tensors)?;
        Ok(Self {
            mesh: sub,
            field: sub_field,
            faces,
            global_of,
        })
    }

    /// The mesh edge of local edge `local_edge`: read at the same corner of a face
    /// holding it.
    fn mesh_edge(&self, mesh: &TriMesh, local_edge: u32) -> u32 {
        let sub = &self.mesh;
        let [fa, _] = sub.edge_faces()[local_edge as usize];
        let k = sub.face_edges()[fa as usize]
            .iter()
            .position(|&e| e == local_edge)
            .unwrap_or(0);
        mesh.face_edges()[self.faces[fa as usize] as usize][k]
    }

    /// The region's segmentation `local` in `mesh`'s face, vertex and edge ids (faces
    /// outside the region with segment `NONE`).
    fn lift(&self, mesh: &TriMesh, local: Segmentation) -> Segmentation {
        let (faces, global_of) = (&self.faces, &self.global_of);
        let mut face_segment = vec![NONE; mesh.face_count()];
        for (i, &s) in local.face_segment.iter().enumerate() {
            face_segment[faces[i] as usize] = s;
        }
        let segments = local
            .segments
            .into_iter()
            .map(|s| Segment {
                faces: s.faces.iter().map(|&f| faces[f as usize]).collect(),
                boundary_loops: s
                    .boundary_loops
                    .iter()
                    .map(|l| l.iter().map(|&v| global_of[v as usize]).collect())
                    .collect(),
                euler_characteristic: s.euler_characteristic,
                has_singular_face: s.has_singular_face,
            })
            .collect();
        let singularities = local
            .singularities
            .iter()
            .map(|s| Singularity {
                face: faces[s.face as usize],
                index: s.index,
            })
            .collect();
        let mut cut_edges: Vec<u32> = local
            .cut_edges
            .iter()
            .map(|&e| self.mesh_edge(mesh, e))
            .collect();
        cut_edges.sort_unstable();
        Segmentation {
            face_segment,
            segments,
            singularities,
            cut_edges,
        }
    }
}

/// Which of `segments` (each a list of faces) a change of field from `old` to `new`
/// touches: those with a vertex whose tensor differs (compared exactly, so a field
/// rebuilt bit for bit touches nothing). Returns their indices, ascending; their faces
/// are the region to re-segment with [`segment_region`]. Fields of different sizes
/// (another mesh) touch every segment. Cost O(V + faces of the segments).
///
/// ```
/// use strata_engine::{field::FieldSpec, mesh::shapes, segment::touched_segments};
/// let mesh = shapes::plane(1.0, 2)?;
/// let spec = |d| FieldSpec::Constant { direction: d, anisotropy: 2.0, density: 1.0 };
/// let old = spec([1.0, 0.0, 0.0]).build(&mesh)?;
/// let segments: Vec<Vec<u32>> = (0..mesh.face_count() as u32).map(|f| vec![f]).collect();
/// assert!(touched_segments(&mesh, &old, &old, &segments).is_empty());
/// let new = spec([0.0, 1.0, 0.0]).build(&mesh)?;
/// assert_eq!(touched_segments(&mesh, &old, &new, &segments).len(), segments.len());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn touched_segments<S: AsRef<[u32]>>(
    mesh: &TriMesh,
    old: &TensorField,
    new: &TensorField,
    segments: &[S],
) -> Vec<usize> {
    let (a, b) = (old.tensors(), new.tensors());
    if a.len() != b.len() || a.len() != mesh.vertex_count() {
        return (0..segments.len()).collect();
    }
    let changed: Vec<bool> = a.iter().zip(b).map(|(x, y)| x != y).collect();
    let triangles = mesh.triangles();
    (0..segments.len())
        .filter(|&i| {
            segments[i].as_ref().iter().any(|&f| {
                triangles
                    .get(f as usize)
                    .is_none_or(|t| t.iter().any(|&v| changed[v as usize]))
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::FieldSpec;
    use crate::fixtures::{along_x_2to1_on, constant, field_on, isotropic_on};
    use crate::mesh::shapes;
    use crate::segment::segment;

    #[test]
    fn a_changed_vertex_touches_exactly_the_segments_around_it() {
        let mesh = shapes::plane(1.0, 4).expect("plane");
        let old = along_x_2to1_on(&mesh);
        // One segment per row of quads (8 faces each).
        let rows: Vec<Vec<u32>> = (0..4).map(|r| (8 * r..8 * r + 8).collect()).collect();
        assert!(touched_segments(&mesh, &old, &old, &rows).is_empty());
        // A vertex on the line between rows 1 and 2, away from the border.
        let v = (0..mesh.vertex_count())
            .find(|&v| {
                let p = mesh.positions()[v];
                (p.y - 0.5).abs() < 1e-9 && (p.x - 0.5).abs() < 1e-9
            })
            .expect("centre vertex");
        let mut tensors = old.tensors().to_vec();
        tensors[v] *= 2.0;
        let new = TensorField::new(&mesh, tensors).expect("field");
        let around: Vec<usize> = (0..rows.len())
            .filter(|&i| {
                rows[i]
                    .iter()
                    .any(|&f| mesh.triangles()[f as usize].contains(&(v as u32)))
            })
            .collect();
        assert_eq!(around, vec![1, 2], "the plane's rows as assumed");
        assert_eq!(touched_segments(&mesh, &old, &new, &rows), around);
        // Another mesh's field touches everything; so does a face out of range.
        let other = shapes::plane(1.0, 2).expect("plane");
        let small = FieldSpec::default_curvature().build(&other).expect("field");
        assert_eq!(
            touched_segments(&mesh, &old, &small, &rows),
            vec![0, 1, 2, 3]
        );
        assert_eq!(
            touched_segments(&mesh, &old, &old, &[vec![999u32]]),
            vec![0]
        );
    }

    #[test]
    fn whole_mesh_region_equals_segment() {
        let mesh = shapes::torus(1.0, 0.4, 24).expect("torus");
        let field = field_on(&mesh, &constant([1.0, 0.3, 0.0], 3.0));
        let all: Vec<u32> = (0..mesh.face_count() as u32).collect();
        let options = SegmentOptions::default();
        let whole = segment(&mesh, &field, &options).expect("segment");
        let region = segment_region(&mesh, &field, &all, &options).expect("region");
        assert_eq!(region, whole);
    }

    #[test]
    fn region_segments_cover_the_region_only_and_are_connected() {
        let mesh = shapes::sphere(1.0, 8).expect("sphere");
        let field = field_on(&mesh, &constant([0.0, 0.0, 1.0], 2.0));
        // The faces whose barycentre has x > 0.3: a cap.
        let region: Vec<u32> = (0..mesh.face_count() as u32)
            .filter(|&f| mesh.face_positions(f).iter().map(|p| p.x).sum::<f64>() > 0.9)
            .collect();
        assert!(!region.is_empty() && region.len() < mesh.face_count());
        let seg =
            segment_region(&mesh, &field, &region, &SegmentOptions::default()).expect("region");
        let mut covered: Vec<u32> = seg.segments.iter().flat_map(|s| s.faces.clone()).collect();
        covered.sort_unstable();
        assert_eq!(covered, region, "every region face in exactly one segment");
        for (f, &s) in seg.face_segment.iter().enumerate() {
            assert_eq!(s == NONE, region.binary_search(&(f as u32)).is_err());
        }
        for s in &seg.segments {
            assert_eq!(s.boundary_loops.len(), 1, "a disc has one boundary loop");
            assert_eq!(s.euler_characteristic, 1);
        }
        // Cut edges are mesh edges of region faces.
        for &e in &seg.cut_edges {
            let [a, b] = mesh.edge_faces()[e as usize];
            assert!(region.binary_search(&a).is_ok() || region.binary_search(&b).is_ok());
        }
    }

    #[test]
    fn bad_regions_are_errors() {
        let mesh = shapes::plane(1.0, 2).expect("plane");
        let field = isotropic_on(&mesh);
        let o = SegmentOptions::default();
        assert!(matches!(
            segment_region(&mesh, &field, &[], &o),
            Err(RegionError::BadFace { .. })
        ));
        assert!(matches!(
            segment_region(&mesh, &field, &[99], &o),
            Err(RegionError::BadFace { face: 99, .. })
        ));
    }
}
