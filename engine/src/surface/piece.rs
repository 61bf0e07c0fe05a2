//! What the splitting ([`refine`](super::refine)) and merging ([`merge`](super::merge))
//! passes both ask of a parameterized piece: the key that orders pieces and segments
//! ([`lowest_face`]) and the optional stricter angle test ([`angle_ok`]). Below both
//! passes, so neither depends on the other for them. Cost: O(faces) and O(1).

use super::{AngleCriterion, SurfaceOptions};
use crate::param::SegmentParam;

/// The lowest mesh face of a parameterized segment: the key that orders segments.
pub fn lowest_face(p: &SegmentParam) -> u32 {
    p.faces.iter().copied().min().unwrap_or(u32::MAX)
}

/// The optional stricter angle test (the mean is part of `report.valid` already).
pub(super) fn angle_ok(p: &SegmentParam, options: &SurfaceOptions) -> bool {
    match options.angle_criterion {
        AngleCriterion::Mean => true,
        AngleCriterion::Max => {
            p.report.isotropic_fallback || p.report.max_angle_deg < options.param.gamma.to_degrees()
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;
    use crate::field::TensorField;
    use crate::mesh::shapes;
    use crate::param::parameterize_all;

    #[test]
    fn the_max_criterion_rejects_what_the_mean_accepts() {
        let mesh = shapes::plane(1.0, 4).expect("plane");
        let field = TensorField::from_frames(
            &mesh,
            &vec![DVec3::X; mesh.vertex_count()],
            &vec![[2.0, 0.5]; mesh.vertex_count()],
        )
        .expect("field");
        let faces: Vec<u32> = (0..mesh.face_count() as u32).collect();
        let cut = vec![false; mesh.edge_count()];
        let mut options = SurfaceOptions::default();
        let results = parameterize_all(&mesh, &field, &[faces], &cut, &options.param);
        let mut p = results
            .into_iter()
            .next()
            .expect("one result")
            .expect("the plane parameterizes");
        p.report.max_angle_deg = options.param.gamma.to_degrees() + 1.0;
        assert!(angle_ok(&p, &options), "the mean criterion ignores the max");
        options.angle_criterion = AngleCriterion::Max;
        assert!(!angle_ok(&p, &options));
        p.report.isotropic_fallback = true;
        assert!(angle_ok(&p, &options), "fallback pieces have no direction");
    }
}
