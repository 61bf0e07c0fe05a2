//! The report of `strata segment`: what the segmentation and the parameterization with
//! splitting produced, per final segment, as serializable data (the JSON schema is in
//! docs/cli.md), and the per-face colours of the segment mesh.
//!
//! Input: the mesh, its [`Segmentation`] and the final [`SegmentParam`]s (segment id =
//! index). Output: a [`SegmentReport`]; colours with [`segment_colors`]. Cost:
//! O(faces + edges), one disc test per final segment.

use strata_engine::mesh::TriMesh;
use strata_engine::param::SegmentParam;
use strata_engine::segment::Segmentation;

/// The JSON report of `strata segment` (schema in docs/cli.md).
#[derive(Debug, serde::Serialize)]
pub struct SegmentReport {
    /// Faces of the mesh.
    pub faces: usize,
    /// Euler characteristic of the whole mesh.
    pub euler_characteristic: i64,
    /// Segments made by the segmentation (section 4), before splitting.
    pub segments_before_split: usize,
    /// Final segments, after splitting invalid ones (section 5.2).
    pub segment_count: usize,
    /// Of those, isotropic charts ([`SegmentEntry::chart`]); the rest are
    /// field-aligned.
    pub charts: usize,
    /// Splits of invalid segments.
    pub splits: usize,
    /// Singular faces with their index (+0.5 or -0.5).
    pub singularities: Vec<SingularityReport>,
    /// Edges cut inside segments (singularity trees and disc cuts).
    pub cut_edges: usize,
    /// Wall time of the segmentation, seconds.
    pub segmentation_s: f64,
    /// Wall time of parameterization with splitting, seconds.
    pub parameterization_s: f64,
    /// Per final segment.
    pub segments: Vec<SegmentEntry>,
}

/// One singularity in the report.
#[derive(Debug, serde::Serialize)]
pub struct SingularityReport {
    /// Face index.
    pub face: u32,
    /// Index of the line-field singularity.
    pub index: f64,
}

/// One final segment in the report.
#[derive(Debug, serde::Serialize)]
pub struct SegmentEntry {
    /// Segment id (as in the coloured mesh, the atlas and the samples).
    pub id: usize,
    /// Number of faces.
    pub faces: usize,
    /// Euler characteristic after cutting (1 for a disc).
    pub euler_characteristic: i64,
    /// Number of boundary loops after cutting (1 for a disc).
    pub boundary_loops: usize,
    /// Whether the segment holds a singular face.
    pub has_singular_face: bool,
    /// Valid parameterization: no flip, no overlap, mean angle under gamma.
    pub valid: bool,
    /// Faces flipped in the parameter plane.
    pub flipped: usize,
    /// Whether the parameter mesh overlaps itself.
    pub overlaps: bool,
    /// Area-weighted mean angle between the mapped major direction and the u axis.
    pub mean_angle_deg: f64,
    /// Largest per-face angle.
    pub max_angle_deg: f64,
    /// Area-weighted mean stretch of the map (the strata's aspect ratio in the field's
    /// metric, 1 when they are as the field asks; `ParamReport::mean_stretch`).
    pub mean_stretch: f64,
    /// Vertices moved by the repair of a local fold (0 for a map as solved;
    /// `ParamReport::relaxed_vertices`).
    pub relaxed_vertices: usize,
    /// Parameterized with the isotropic fallback frame.
    pub isotropic_fallback: bool,
    /// An isotropic chart: most of its faces have all three vertices isotropic in the
    /// scene's field (spacing ratio under `surface.isotropy_threshold`). A field
    /// isotropic everywhere is covered by normal-cone charts; in a mixed field such a
    /// segment followed the smooth direction given to isotropic regions (issue 18).
    /// Otherwise a field-aligned segment.
    pub chart: bool,
}

impl SegmentReport {
    /// Builds the report of a segmentation and its final parameterizations;
    /// `isotropic` (per vertex of the scene's field, before isotropic regions took a
    /// smooth direction; empty for none) tells charts from field-aligned segments
    /// ([`SegmentEntry::chart`]).
    pub fn new(
        mesh: &TriMesh,
        seg: &Segmentation,
        params: &[SegmentParam],
        splits: usize,
        segmentation_s: f64,
        parameterization_s: f64,
        isotropic: &[bool],
    ) -> Self {
        let mut cut = vec![false; mesh.edge_count()];
        for &e in &seg.cut_edges {
            cut[e as usize] = true;
        }
        let mut singular = vec![false; mesh.face_count()];
        for s in &seg.singularities {
            singular[s.face as usize] = true;
        }
        let is_chart = |p: &SegmentParam| {
            let isotropic_faces = p
                .faces
                .iter()
                .filter(|&&f| {
                    mesh.triangles()[f as usize]
                        .iter()
                        .all(|&v| isotropic.get(v as usize).copied().unwrap_or(false))
                })
                .count();
            2 * isotropic_faces > p.faces.len()
        };
        let charts = params.iter().filter(|p| is_chart(p)).count();
        Self {
            faces: mesh.face_count(),
            charts,
            euler_characteristic: mesh.euler_characteristic(),
            segments_before_split: seg.segments.len(),
            segment_count: params.len(),
            splits,
            singularities: seg
                .singularities
                .iter()
                .map(|s| SingularityReport {
                    face: s.face,
                    index: s.index,
                })
                .collect(),
            cut_edges: seg.cut_edges.len(),
            segmentation_s,
            parameterization_s,
            segments: params
                .iter()
                .enumerate()
                .map(|(id, p)| {
                    let topo = strata_engine::segment::patch_topology(mesh, &p.faces, &cut);
                    let r = &p.report;
                    SegmentEntry {
                        id,
                        faces: p.faces.len(),
                        euler_characteristic: topo.euler_characteristic,
                        boundary_loops: topo.boundary_loops.len(),
                        has_singular_face: p.faces.iter().any(|&f| singular[f as usize]),
                        valid: r.valid,
                        flipped: r.flipped,
                        overlaps: r.overlaps,
                        mean_angle_deg: r.mean_angle_deg,
                        max_angle_deg: r.max_angle_deg,
                        mean_stretch: r.mean_stretch,
                        relaxed_vertices: r.relaxed_vertices,
                        isotropic_fallback: r.isotropic_fallback,
                        chart: is_chart(p),
                    }
                })
                .collect(),
        }
    }
}

/// The colour of every face of the segment mesh: its final segment's colour
/// ([`segment_color`]), singular faces near black.
pub fn segment_colors(mesh: &TriMesh, seg: &Segmentation, params: &[SegmentParam]) -> Vec<[u8; 3]> {
    let mut singular = vec![false; mesh.face_count()];
    for s in &seg.singularities {
        singular[s.face as usize] = true;
    }
    let mut final_segment = vec![0u32; mesh.face_count()];
    for (id, p) in params.iter().enumerate() {
        for &f in &p.faces {
            final_segment[f as usize] = id as u32;
        }
    }
    (0..mesh.face_count())
        .map(|f| {
            if singular[f] {
                SINGULAR_COLOR
            } else {
                segment_color(final_segment[f])
            }
        })
        .collect()
}

/// The colour of singular faces in the segment mesh.
pub const SINGULAR_COLOR: [u8; 3] = [16, 16, 16];

/// A bright, deterministic colour per segment id (the atlas's hues, lifted to
/// 60..=255 per channel).
pub fn segment_color(id: u32) -> [u8; 3] {
    super::atlas::segment_hue(id as usize).map(|c| (60.0 + 195.0 * c) as u8)
}

#[cfg(test)]
mod tests {
    use strata_engine::fixtures::along_x_2to1_on;
    use strata_engine::mesh::shapes;
    use strata_engine::segment::{SegmentOptions, segment};
    use strata_engine::surface::{SurfaceOptions, parameterize_with_splitting};

    use super::*;

    #[test]
    fn colors_follow_the_final_segments_and_mark_singular_faces() {
        let mesh = shapes::sphere(1.0, 4).expect("sphere");
        let field = along_x_2to1_on(&mesh);
        let seg = segment(&mesh, &field, &SegmentOptions::default()).expect("segment");
        let (params, split) =
            parameterize_with_splitting(&mesh, &field, &seg, &SurfaceOptions::default())
                .expect("parameterize");
        // A constant direction on a sphere is singular somewhere (index sum 2).
        assert!(!seg.singularities.is_empty());
        let colors = segment_colors(&mesh, &seg, &params);
        assert_eq!(colors.len(), mesh.face_count());
        for s in &seg.singularities {
            assert_eq!(colors[s.face as usize], SINGULAR_COLOR);
        }
        for (id, p) in params.iter().enumerate() {
            for &f in &p.faces {
                if !seg.singularities.iter().any(|s| s.face == f) {
                    assert_eq!(colors[f as usize], segment_color(id as u32));
                }
            }
        }
        let none = vec![false; mesh.vertex_count()];
        let report = SegmentReport::new(&mesh, &seg, &params, split.splits, 0.0, 0.0, &none);
        assert_eq!(report.faces, mesh.face_count());
        // No isotropic vertex: every segment is field-aligned. All isotropic: every
        // one is a chart. The upper half isotropic: exactly the segments with most of
        // their faces there.
        assert_eq!(report.charts, 0);
        assert!(report.segments.iter().all(|s| !s.chart));
        let all = vec![true; mesh.vertex_count()];
        let charts = SegmentReport::new(&mesh, &seg, &params, split.splits, 0.0, 0.0, &all);
        assert_eq!(charts.charts, params.len());
        assert!(charts.segments.iter().all(|s| s.chart));
        let upper: Vec<bool> = mesh.positions().iter().map(|p| p.z > 0.0).collect();
        let half = SegmentReport::new(&mesh, &seg, &params, split.splits, 0.0, 0.0, &upper);
        for (entry, p) in half.segments.iter().zip(&params) {
            let up = p
                .faces
                .iter()
                .filter(|&&f| {
                    mesh.triangles()[f as usize]
                        .iter()
                        .all(|&v| upper[v as usize])
                })
                .count();
            assert_eq!(entry.chart, 2 * up > p.faces.len(), "segment {}", entry.id);
        }
        assert_eq!(report.segment_count, params.len());
        assert_eq!(
            report.segments.iter().map(|s| s.faces).sum::<usize>(),
            mesh.face_count()
        );
        assert_eq!(report.singularities.len(), seg.singularities.len());
        let index_sum: f64 = report.singularities.iter().map(|s| s.index).sum();
        assert_eq!(index_sum, mesh.euler_characteristic() as f64);
    }

    #[test]
    fn segment_colors_are_bright_and_differ_between_neighbours() {
        for id in 0..50 {
            let c = segment_color(id);
            assert!(c.iter().all(|&v| v >= 60), "{c:?}");
            assert_ne!(c, segment_color(id + 1));
        }
    }
}
