//! Field-aligned parameterization of one mesh segment (paper sections 5, 5.1 and 5.2).
//!
//! Input: a [`TriMesh`], its [`TensorField`], a segment as a list of mesh faces, and a
//! per-edge `cut` mask of seams along which the segment is cut open. Output: a
//! [`SegmentParam`]: `(u, v)` per vertex of the cut-open segment, such that the
//! gradients of `u` and `v` follow `sqrt(l1) m1` and `sqrt(l2) m2` of the tensor field in
//! the least-squares sense, and a [`ParamReport`] saying whether the result is *valid*
//! (no flipped triangle, no self-overlap, mean angle between the mapped major direction
//! and the u axis below `gamma`).
//!
//! Steps:
//! 1. the cut-open local patch: each mesh vertex splits into one local vertex per fan of
//!    segment faces around it separated by cut or boundary edges; the patch must be a
//!    connected topological disc (Euler characteristic 1, one boundary loop);
//! 2. combing: the per-face major direction (a line field) gets a consistent sign by
//!    breadth-first propagation over the face graph, comparing through a rotation about
//!    the shared edge; non-tree edges that still turn by more than 90 degrees are
//!    counted (they reveal a singularity inside the segment);
//! 3. least squares (section 5.1): the normal equations are the cotangent Laplacian
//!    with the divergence of the two target fields as right-hand sides; one sparse
//!    Cholesky factorization (faer, sequential; ordered by nested dissection from
//!    10k unknowns, `linalg::dissection`) serves both solves;
//! 4. nearly isotropic segments (area-weighted mean of `sqrt(l1 / l2)` below
//!    `isotropy_threshold`) use a smooth fallback frame instead of their undefined
//!    eigenvectors: a tangent axis parallel-transported from face 0 over the
//!    breadth-first tree, with the holonomy of the non-tree edges spread over the
//!    faces by least squares on the frame angle (one more sparse solve, on the face
//!    graph), and `l1 = l2 = sqrt(l1 l2)` per face;
//! 5. validity (section 5.2): flipped triangles (exact orientation predicate),
//!    self-overlap of the parameter mesh (exact boundary self-intersection test over a
//!    uniform grid) and the angle statistics of section 7.3.1.
//! 6. repair of local folds: a map that flips or overlaps only within a few edges (a
//!    sharp corner of the border folded over by the field's stretch) is relaxed there,
//!    a few rounds of moving the vertices around the defect to the mean of their
//!    neighbours, and kept when it then passes step 5 ([`ParamReport::relaxed_vertices`]
//!    says how many moved); otherwise it stays invalid and the caller splits it.
//!
//! Cost, for a segment of `F` faces and `B` boundary edges: O(F) for the patch, the
//! combing and the assembly; the Cholesky factorization of an AMD-ordered planar-like
//! Laplacian is about O(F^1.5) time and O(F log F) memory, each solve O(F log F); the
//! validity test is O(F + B) for well-spread boundaries (a uniform grid of about `B`
//! cells). Measured on one core (release, `large_plane_timing` in the tests): a
//! 200 x 200 grid (80 000 faces, 40 400 unknowns) with a turning field takes 68 ms:
//! patch 4, frames 12, assembly 4 (into the stiffness pattern, no triplet sort),
//! symbolic factorization 11, numeric factorization 19, both solves 6, validity 6;
//! the isotropic fallback (one more solve, on the face graph) brings it to 170 ms.
//!
//! References: Quinn et al., "Generalized Anisotropic Stratified Surface Sampling",
//! sections 5 and 7.3.1; Ray et al. 2006, "Periodic global parameterization" (the
//! energy); Shewchuk 1997, "Adaptive precision floating-point arithmetic and fast
//! robust geometric predicates" (the orientation predicate).

mod comb;
mod face_tensors;
mod patch;
pub mod predicates;
mod solve;
mod spd;
mod untangle;
mod validity;

pub use face_tensors::FaceTensors;
pub use validity::{boundary_edges, boundary_overlaps, count_flipped};

use glam::DVec2;
use rayon::prelude::*;

use crate::field::{Eigen2, TensorField};
use crate::mesh::TriMesh;

/// Settings of the parameterization.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default, deny_unknown_fields))]
pub struct ParamOptions {
    /// Largest mean angle (radians) between the mapped major direction and the u axis
    /// for a segment to be valid (section 5.2's `gamma`). Range (0, pi/2]; default
    /// pi/16.
    pub gamma: f64,
    /// A segment whose area-weighted mean spacing ratio `sqrt(l1 / l2)` is below this
    /// value is treated as isotropic and parameterized with a fallback frame (its
    /// eigenvectors are noise). Range [1, inf); 1 disables the fallback; default 1.05.
    pub isotropy_threshold: f64,
    /// Largest area-weighted mean stretch ([`ParamReport::mean_stretch`]) for a
    /// segment on the isotropic fallback frame to be valid: there the angle test is
    /// waived, and this is what keeps its strata compact. Range [1, inf); default 1.5
    /// (the isotropic bunny's charts measure 1.02 on average, 1.06 at worst).
    pub max_stretch: f64,
}

impl Default for ParamOptions {
    fn default() -> Self {
        Self {
            gamma: std::f64::consts::PI / 16.0,
            isotropy_threshold: 1.05,
            max_stretch: 1.5,
        }
    }
}

impl ParamOptions {
    /// Checks every field's range.
    pub fn validate(&self) -> Result<(), ParamError> {
        let bad = |option, value, expected| {
            Err(ParamError::InvalidOption {
                option,
                value,
                expected,
            })
        };
        if !(self.gamma > 0.0 && self.gamma <= std::f64::consts::FRAC_PI_2) {
            return bad("gamma", self.gamma, "in (0, pi/2]");
        }
        if !(self.isotropy_threshold >= 1.0 && self.isotropy_threshold.is_finite()) {
            return bad(
                "isotropy_threshold",
                self.isotropy_threshold,
                "finite and >= 1",
            );
        }
        if !(self.max_stretch >= 1.0) {
            return bad("max_stretch", self.max_stretch, ">= 1");
        }
        Ok(())
    }
}

/// Errors of the parameterization of one segment.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ParamError {
    /// An option is out of range.
    #[error("parameterization option `{option}` = {value} is invalid: expected {expected}")]
    InvalidOption {
        /// Option name.
        option: &'static str,
        /// Value given.
        value: f64,
        /// Valid range.
        expected: &'static str,
    },
    /// The segment has no faces.
    #[error("the segment has no faces")]
    EmptySegment,
    /// A face index is not a face of the mesh.
    #[error("segment face {face} is out of range: the mesh has {face_count} faces")]
    FaceOutOfRange {
        /// The offending face index.
        face: u32,
        /// Number of mesh faces.
        face_count: usize,
    },
    /// A face is listed twice.
    #[error("segment face {face} is listed more than once")]
    DuplicateFace {
        /// The repeated face.
        face: u32,
    },
    /// The cut mask does not have one entry per mesh edge.
    #[error("the cut mask has {found} entries, the mesh has {expected} edges")]
    CutMaskLength {
        /// Number of mesh edges.
        expected: usize,
        /// Length of the mask.
        found: usize,
    },
    /// Two faces of the segment traverse their shared edge in the same direction.
    #[error(
        "mesh edge {edge} joins two segment faces wound in opposite directions; \
         orient the mesh consistently or cut the segment along this edge"
    )]
    InconsistentOrientation {
        /// The mesh edge.
        edge: u32,
    },
    /// The cut-open segment falls apart into several pieces.
    #[error(
        "the cut-open segment has {components} connected components; \
         parameterize each component as a segment of its own"
    )]
    Disconnected {
        /// Number of components (through non-cut edges).
        components: usize,
    },
    /// The cut-open segment is not a topological disc.
    #[error(
        "the cut-open segment is not a disc: Euler characteristic {euler_characteristic} \
         (a disc has 1) and {boundary_loops} boundary loops (a disc has 1); \
         cut it along paths joining its boundaries (section 4.2)"
    )]
    NotADisc {
        /// V - E + F of the cut-open patch.
        euler_characteristic: i64,
        /// Number of boundary loops of the cut-open patch.
        boundary_loops: usize,
    },
    /// The sparse least-squares solve failed.
    #[error(
        "the least-squares solve failed at {stage}; the segment is probably degenerate \
         (near-zero-area faces)"
    )]
    Solver {
        /// Which step failed: assembly, symbolic or numeric factorization, or a
        /// non-finite solution.
        stage: &'static str,
    },
}

/// Validity and quality of one segment's parameterization (section 5.2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParamReport {
    /// Triangles with non-positive signed area in `uv` (exact predicate).
    pub flipped: usize,
    /// Whether the parameter mesh overlaps itself: its boundary edges intersect
    /// somewhere other than at shared endpoints (exact predicates). Seam sides that
    /// close up to a relative tolerance of 1e-9 (a cut whose two sides map onto each
    /// other) count as glued, not as overlapping.
    pub overlaps: bool,
    /// Area-weighted mean over faces of the angle (degrees, in [0, 90]) between the
    /// image of the major direction `m1` in `uv` and the u axis (section 7.3.1).
    pub mean_angle_deg: f64,
    /// Largest per-face angle (degrees).
    pub max_angle_deg: f64,
    /// `flipped == 0 && !overlaps && mean_angle < gamma`. For an isotropic fallback the
    /// angle condition is waived (the frame it is measured against is arbitrary, and
    /// splitting the segment would not improve it) and `mean_stretch <= max_stretch`
    /// takes its place.
    pub valid: bool,
    /// Whether the segment was nearly isotropic and used the fallback frame.
    pub isotropic_fallback: bool,
    /// Interior edges across which the combed major direction still turns by more than
    /// 90 degrees (non-zero when the segment holds a singularity).
    pub inconsistent_combing: usize,
    /// Area-weighted mean spacing ratio `sqrt(l1 / l2)` of the face tensors.
    pub mean_anisotropy: f64,
    /// Area-weighted mean stretch of the map: per face, the ratio of the singular
    /// values of the map from the field's metric to `uv` (1 where the strata are as
    /// the field asks, `k` where they come out `k` times longer one way than the
    /// other; a degenerate face counts 1000).
    pub mean_stretch: f64,
    /// Vertices moved by the repair of a local fold (0 for the map as solved): a
    /// map that flipped or overlapped only within a few edges is relaxed there and
    /// kept when it then passes the exact test.
    pub relaxed_vertices: usize,
}

/// The parameterization of one segment: its cut-open local mesh with `uv` coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct SegmentParam {
    /// Parameter coordinates per local vertex (raw: not scaled or translated; local
    /// vertex 0 is at the origin). See [`to_unit_square`](Self::to_unit_square).
    pub uv: Vec<DVec2>,
    /// Mesh vertex of each local vertex (a mesh vertex on a cut has several copies).
    pub local_to_mesh: Vec<u32>,
    /// Local triangles, corners in the mesh face's order (counter-clockwise in `uv`
    /// when the parameterization is valid).
    pub triangles: Vec<[u32; 3]>,
    /// Mesh face of each local triangle, in the order the segment was given.
    pub faces: Vec<u32>,
    /// Validity and quality.
    pub report: ParamReport,
}

impl SegmentParam {
    /// `uv` scaled uniformly (aspect kept) and translated into `[0, 1]^2`, as the curve
    /// stage needs: returns `(unit, scale, offset)` with `unit = uv * scale + offset`
    /// (clamped against round-off), the longer side of the bounding box spanning 1.
    pub fn to_unit_square(&self) -> (Vec<DVec2>, f64, DVec2) {
        let (lo, hi) = self.uv.iter().fold(
            (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        let extent = (hi - lo).max_element();
        let scale = if extent > 0.0 && extent.is_finite() {
            1.0 / extent
        } else {
            1.0
        };
        let offset = -lo * scale;
        let unit = self
            .uv
            .iter()
            .map(|p| (*p * scale + offset).clamp(DVec2::ZERO, DVec2::ONE))
            .collect();
        (unit, scale, offset)
    }

    /// Density per corner of each local triangle for the curve stage
    /// ([`CurveDomain::corner_density`](crate::curve::CurveDomain)): the surface density
    /// `sqrt(l1 l2)` at the corner's mesh vertex times `surface area / unit-square uv
    /// area` of the triangle, so that a region's measure in the unit square equals its
    /// surface measure (as in [`planar`](crate::planar)). Triangles with non-positive
    /// `uv` area (an invalid parameterization) get density 0.
    ///
    /// `unit` is [`to_unit_square`](Self::to_unit_square)'s `uv` (passed in because
    /// the caller needs it too). Each local vertex's density (an eigen-decomposition)
    /// is computed once, not once per corner.
    pub fn corner_density(
        &self,
        mesh: &TriMesh,
        field: &TensorField,
        unit: &[DVec2],
    ) -> Vec<[f64; 3]> {
        let density: Vec<f64> = self
            .local_to_mesh
            .iter()
            .map(|&v| field.vertex_density(mesh, v))
            .collect();
        crate::curve::corner_densities(
            unit,
            &self.triangles,
            |i| mesh.face_areas()[self.faces[i] as usize],
            |v| density[v as usize],
        )
    }

    /// Boundary edges of the local mesh as directed local vertex pairs (following the
    /// triangles' orientation).
    pub fn boundary_edges(&self) -> Vec<[u32; 2]> {
        boundary_edges(&self.triangles)
    }
}

/// Parameterizes one segment in alignment with the tensor field (section 5).
///
/// `faces` are the segment's mesh faces (distinct, any order; local triangle `i` is
/// `faces[i]`); `cut` has one entry per mesh edge, `true` for seams inside the segment
/// along which it is cut open (edges to faces outside the segment are boundary anyway).
/// Errors: bad options or input, a cut-open segment that is not a connected disc, a
/// failed solve. A parameterization that is computed but invalid is `Ok`, with
/// `report.valid == false`.
///
/// ```
/// use strata_engine::{field::FieldSpec, mesh::shapes, param};
/// let mesh = shapes::plane(1.0, 8)?;
/// let spec = FieldSpec::Constant { direction: [1.0, 1.0, 0.0], anisotropy: 2.0, density: 1.0 };
/// let field = spec.build(&mesh)?;
/// let faces: Vec<u32> = (0..mesh.face_count() as u32).collect();
/// let cut = vec![false; mesh.edge_count()];
/// let p = param::parameterize(&mesh, &field, &faces, &cut, &param::ParamOptions::default())?;
/// assert!(p.report.valid && p.report.mean_angle_deg < 1e-6);
/// let (unit, _scale, _offset) = p.to_unit_square();
/// assert!(unit.iter().all(|q| (0.0..=1.0).contains(&q.x) && (0.0..=1.0).contains(&q.y)));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn parameterize(
    mesh: &TriMesh,
    field: &TensorField,
    faces: &[u32],
    cut: &[bool],
    options: &ParamOptions,
) -> Result<SegmentParam, ParamError> {
    parameterize_by(mesh, faces, cut, options, |f| {
        comb::face_eigen(mesh, field, f)
    })
}

/// [`parameterize`] with the field's decomposition per face made once for the mesh
/// ([`FaceTensors`]): for callers that parameterize many overlapping face sets of one
/// mesh (splitting, merging). The result is bit for bit [`parameterize`]'s.
pub fn parameterize_with(
    mesh: &TriMesh,
    tensors: &FaceTensors,
    faces: &[u32],
    cut: &[bool],
    options: &ParamOptions,
) -> Result<SegmentParam, ParamError> {
    parameterize_by(mesh, faces, cut, options, |f| tensors.eigen(mesh, f))
}

/// The parameterization with `eigen(f)` the field's decomposition on mesh face `f`.
fn parameterize_by(
    mesh: &TriMesh,
    faces: &[u32],
    cut: &[bool],
    options: &ParamOptions,
    eigen: impl Fn(u32) -> Eigen2,
) -> Result<SegmentParam, ParamError> {
    options.validate()?;
    let patch = patch::Patch::build(mesh, faces, cut)?;
    let eigen = patch.faces.iter().map(|&f| eigen(f)).collect();
    let frames = comb::frames(mesh, eigen, &patch, options)?;
    let mut uv = solve::solve(mesh, &patch, &frames)?;
    let mut report = validity::report(mesh, &patch, &frames, &uv, options);
    // A map that fails by a fold a few edges long is relaxed there (module
    // `untangle`) rather than split.
    if !report.valid
        && (report.flipped > 0 || report.overlaps)
        && let Some((relaxed, r)) = untangle::repair(mesh, &patch, &frames, &uv, options)
    {
        uv = relaxed;
        report = r;
    }
    Ok(SegmentParam {
        uv,
        local_to_mesh: patch.local_to_mesh,
        triangles: patch.triangles,
        faces: patch.faces,
        report,
    })
}

/// [`parameterize`] for many segments, in parallel with rayon. Results come in the
/// order of `segments` and do not depend on the number of threads (each segment is
/// solved sequentially).
pub fn parameterize_all(
    mesh: &TriMesh,
    field: &TensorField,
    segments: &[Vec<u32>],
    cut: &[bool],
    options: &ParamOptions,
) -> Vec<Result<SegmentParam, ParamError>> {
    segments
        .par_iter()
        .map(|faces| parameterize(mesh, field, faces, cut, options))
        .collect()
}

#[cfg(test)]
mod tests;
