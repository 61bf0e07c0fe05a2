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
