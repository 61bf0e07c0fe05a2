//! The sampler's plain records: the GPU-ready [`Sample`] and [`SampleSite`] it writes,
//! and the [`SegmentSampling`] it is built from (below both the sampler and the chains
//! it links, which read it).

use std::sync::Arc;

use glam::DVec3;

use crate::curve::SegmentCurve;
use crate::mesh::TriMesh;

/// One segment ready for sampling: its cells and the mesh face of each domain triangle.
#[derive(Clone, Debug)]
pub struct SegmentSampling {
    /// Segment id written into the samples.
    pub segment: u32,
    /// Mesh face of each triangle of the curve's domain.
    pub faces: Vec<u32>,
    /// The segment's adaptive Hilbert cells, shared (an engine that keeps them per
    /// segment, like the ECS layer, hands the sampler a reference instead of a copy).
    pub curve: Arc<SegmentCurve>,
}

/// One surface sample, laid out for direct GPU upload (`#[repr(C)]`, 64 bytes, 16-byte
/// aligned groups). Its WGSL twin is `Sample` in `shaders/common.wgsl`.
///
/// Everything a splat renderer and an application need: where the sample is, how the
/// field orients and sizes its ellipse there, and which face and barycentric point it
/// came from (so colours, UVs or any per-vertex attribute can be interpolated).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Sample {
    /// Position in world space.
    pub position: [f32; 3],
    /// The face the sample lies on.
    pub face: u32,
    /// Unit surface normal (interpolated vertex normals).
    pub normal: [f32; 3],
    /// Segment id of the face.
    pub segment: u32,
    /// Unit tangent along the field's major eigenvector m1 (the direction of densest
    /// spacing); the minor axis is `normal x major_axis`.
    pub major_axis: [f32; 3],
    /// Rank of the sample in its stratified sequence (stable across frames for the
    /// same count and seed); for progressive samples
    /// ([`Sampler::progressive_into`](super::Sampler::progressive_into)) its rank in
    /// the progressive sequence, the same for any count.
    pub index: u32,
    /// Barycentric coordinates of corners 1 and 2 of `face`; corner 0 has
    /// `1 - bary[0] - bary[1]`.
    pub bary: [f32; 2],
    /// Expected distance to the next sample along the major and the minor axis
    /// (world units, for this sample count): `sqrt(M / N) / sqrt(l_k)` with `M` the
    /// total density measure and `N` the count.
    pub spacing: [f32; 2],
}

/// Where a sample lies, without the rest of its record: what
/// [`Sampler::sample_sites_into`](super::Sampler::sample_sites_into) writes, 16 bytes
/// (`#[repr(C)]`, a quarter of a [`Sample`]).
///
/// For callers that interpolate the record themselves (in a shader, say) or upload
/// samples compactly. Site `k` of a request holds the `face`, `segment` and `bary` of
/// sample `k` of the same request by [`Sampler::sample_into`](super::Sampler::sample_into),
/// bit for bit, and its index is `k`; [`Sampler::record`](super::Sampler::record) expands it
/// into that sample up to the rounding of `bary` to `f32`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SampleSite {
    /// The face the sample lies on.
    pub face: u32,
    /// Segment id of the face.
    pub segment: u32,
    /// Barycentric coordinates of corners 1 and 2 of `face`; corner 0 has
    /// `1 - bary[0] - bary[1]`.
    pub bary: [f32; 2],
}

impl SampleSite {
    /// The three barycentric coordinates (corner 0, 1, 2).
    pub fn barycentric(&self) -> [f32; 3] {
        [
            1.0 - self.bary[0] - self.bary[1],
            self.bary[0],
            self.bary[1],
        ]
    }

    /// The site's point on `mesh` (the mesh it was drawn on, or a deformation of it
    /// with the same triangles): its face's corners weighted by
    /// [`barycentric`](Self::barycentric) in `f64`. `None` when `face` is not one of
    /// `mesh`'s faces.
    pub fn position_on(&self, mesh: &TriMesh) -> Option<DVec3> {
        let corners = mesh.triangles().get(self.face as usize)?;
        let w = self.barycentric().map(f64::from);
        let p = mesh.positions();
        Some(
            p[corners[0] as usize] * w[0]
                + p[corners[1] as usize] * w[1]
                + p[corners[2] as usize] * w[2],
        )
    }
}

const _: () = assert!(std::mem::size_of::<SampleSite>() == 16);
const _: () = assert!(std::mem::size_of::<Sample>() == 64);
const _: () = assert!(std::mem::align_of::<Sample>() == 4);

impl Sample {
    /// The three barycentric coordinates (corner 0, 1, 2).
    pub fn barycentric(&self) -> [f32; 3] {
        [
            1.0 - self.bary[0] - self.bary[1],
            self.bary[0],
            self.bary[1],
        ]
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::SampleSite;
    use crate::mesh::TriMesh;

    #[test]
    fn a_site_s_position_weights_its_face_s_corners() {
        let positions = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(1.0, 1.0, 2.0)];
        let mesh = TriMesh::new(positions, vec![[0, 1, 2], [1, 3, 2]]).expect("two triangles");
        let site = |face, bary| SampleSite {
            face,
            segment: 0,
            bary,
        };
        // Corner 0 of face 1 is vertex 1; corners 1 and 2 are vertices 3 and 2.
        assert_eq!(site(1, [0.0, 0.0]).position_on(&mesh), Some(DVec3::X));
        assert_eq!(
            site(1, [1.0, 0.0]).position_on(&mesh),
            Some(DVec3::new(1.0, 1.0, 2.0))
        );
        let p = site(1, [0.25, 0.5]).position_on(&mesh).expect("face 1");
        let expected = DVec3::X * 0.25 + DVec3::new(1.0, 1.0, 2.0) * 0.25 + DVec3::Y * 0.5;
        assert!(p.distance(expected) < 1e-12, "{p} against {expected}");
        assert_eq!(site(2, [0.0, 0.0]).position_on(&mesh), None);
    }
}
