//! A [`Segmentation`] from given labels instead of the random walk's, for controlled
//! experiments (a fixed number of segments, a boundary of a chosen shape).
//!
//! Input: a mesh and a segment label per face. Output: one segment per connected part
//! of each label, numbered by lowest face, with its boundary loops and Euler
//! characteristic; no singularities and no cut edges. Cost: O(F) plus the patch
//! topology of each segment, segments in parallel with rayon (the result does not
//! depend on the thread count).

use rayon::prelude::*;

use super::{Segment, Segmentation, patch_topology};
use crate::mesh::{NONE, TriMesh, connected_parts, group_by_label};

/// A [`Segmentation`] from a segment label per face: one segment per connected part of
/// each label (so every segment is connected), numbered by lowest face, with its
/// boundary loops and Euler characteristic; no singularities and no cut edges. Faces
/// labelled `u32::MAX` are left out of every segment.
///
/// ```
/// use strata_engine::{mesh::shapes, segment::segmentation_from_labels};
/// let mesh = shapes::plane(1.0, 4)?;
/// // Columns of quads labelled 0 1 0 1: four segments, since a label's columns are
/// // not connected.
/// let labels: Vec<u32> = (0..mesh.face_count()).map(|f| ((f / 2) % 2) as u32).collect();
/// let seg = segmentation_from_labels(&mesh, &labels);
/// assert_eq!(seg.segments.len(), 4);
/// assert!(seg.segments.iter().all(|s| s.euler_characteristic == 1));
/// # Ok::<(), strata_engine::mesh::MeshError>(())
/// ```
pub fn segmentation_from_labels(mesh: &TriMesh, face_segment: &[u32]) -> Segmentation {
    let no_cut = vec![false; mesh.edge_count()];
    let parts = connected_parts(mesh, face_segment, &no_cut);
    // Parts are numbered by lowest face, so grouping by part number orders the
    // segments by lowest face.
    let faces = group_by_label(&parts, 0..mesh.face_count() as u32);
    let mut labels = vec![NONE; mesh.face_count()];
    for (id, faces) in faces.iter().enumerate() {
        for &f in faces {
            labels[f as usize] = id as u32;
        }
    }
    // Each segment's topology on its own, in parallel; collected in segment order.
    let segments = faces
        .into_par_iter()
        .map(|faces| {
            let top = patch_topology(mesh, &faces, &no_cut);
            Segment {
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
