//! Field-driven mesh segmentation (paper sections 4, 4.1 and 4.2).
//!
//! Input: a [`TriMesh`](crate::mesh::TriMesh) and a
//! [`TensorField`](crate::field::TensorField). Output: a [`Segmentation`]: every face in
//! exactly one segment; each segment connected, free of field singularities (their
//! faces are flagged and sampled isotropically) and a topological disc, so that it can
//! be parameterized in alignment with the field.
//!
//! Stages:
//! 1. seeds by stepping out in rings until the major direction turns more than `beta`;
//! 2. random-walk assignment (Grady 2006, as modified by the paper): each face joins
//!    the seed a walk from it most probably reaches first, the walk crossing an edge
//!    with weight `|e| exp(-d*/sigma)`; one sparse Cholesky factorization, one
//!    right-hand side per seed;
//! 3. singularities of the line field joined by field-following shortest paths whose
//!    minimum spanning tree the walk may not cross;
//! 4. cuts that make every segment a disc.

pub mod charts;
mod clusters;
mod comb_flips;
mod from_labels;
mod graph_walk;
pub mod multilevel;
pub mod paths;
mod pipeline;
pub mod region;
pub mod seeds;
pub mod singularity;
pub mod topology;
pub mod walk;

pub use charts::{CHART_NORMAL_ANGLE, chart_labels, isotropic_charts};
pub use clusters::{SingularityCluster, singularity_clusters};
pub use comb_flips::comb_flip_vertices;
pub use from_labels::segmentation_from_labels;
pub use pipeline::segment;
pub use region::{RegionError, segment_region, touched_segments};

pub use paths::{
    ShortestPaths, dijkstra, field_edge_costs, field_edge_costs_with, singularity_tree,
    singularity_tree_to,
};
pub use seeds::{FaceField, face_frames, place_seeds};
pub use singularity::{
    LineFieldTransport, detect_singularities, isotropic_faces, line_field_transport,
    singularities_from,
};
pub use topology::{PatchTopology, disc_cuts, is_disc, patch_topology};
pub use walk::{WalkSystem, connected_parts, random_walk, walk_weights};

/// A singularity of the major-direction line field inside a face.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Singularity {
    /// The face containing it.
    pub face: u32,
    /// Its index: +0.5 or -0.5 (a wedge or a trisector); higher multiples are possible
    /// on coarse meshes and are reported as they are.
    pub index: f64,
}

/// Settings of the segmentation.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default, deny_unknown_fields))]
pub struct SegmentOptions {
    /// Largest turn of the major direction (radians, as a line-field angle in
    /// [0, pi/2]) from the reference direction of the region being grown before a new
    /// seed is placed. Range
    /// (0, pi/2]; default pi/4 (section 4).
    pub beta: f64,
    /// Scale of the random walk's edge weights `|e| exp(-d*/sigma)`. Range (0, inf);
    /// default 1 (section 4).
    pub sigma: f64,
    /// Seed of the random choices (the first triangle of each component).
    pub seed: u64,
}

impl Default for SegmentOptions {
    fn default() -> Self {
        Self {
            beta: std::f64::consts::FRAC_PI_4,
            sigma: 1.0,
            seed: 0,
        }
    }
}

/// One segment: a connected set of faces.
#[derive(Clone, Debug, PartialEq)]
pub struct Segment {
    /// Its faces (mesh face indices, ascending).
    pub faces: Vec<u32>,
    /// Boundary loops of the segment as mesh vertex sequences.
    pub boundary_loops: Vec<Vec<u32>>,
    /// Euler characteristic V - E + F of the segment's faces.
    pub euler_characteristic: i64,
    /// Whether the segment contains a singular face.
    pub has_singular_face: bool,
}

/// The result of segmenting a mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct Segmentation {
    /// Segment id of every face.
    pub face_segment: Vec<u32>,
    /// The segments, by id.
    pub segments: Vec<Segment>,
    /// The singularities found (one per singular face).
    pub singularities: Vec<Singularity>,
    /// Mesh edges the segmentation cut along (singularity trees and disc cuts).
    pub cut_edges: Vec<u32>,
}

/// Errors of the segmentation.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SegmentError {
    /// An option is out of range.
    #[error("segmentation option `{option}` = {value} is invalid: expected {expected}")]
    InvalidOption {
        /// Option name.
        option: &'static str,
        /// Value given.
        value: f64,
        /// Valid range.
        expected: &'static str,
    },
    /// A face of the random walk's mask lies in a part (faces joined by edges of
    /// positive weight) that holds no seed: its walk could reach no seed.
    #[error("face {face} lies in a part of the mask that holds no seed")]
    Unseeded {
        /// The lowest such face.
        face: u32,
    },
    /// The sparse solver failed (the walk's system was singular).
    #[error("random-walk solve failed: {what}")]
    Solver {
        /// What failed.
        what: String,
    },
}

impl SegmentOptions {
    /// Checks every field's range.
    pub fn validate(&self) -> Result<(), SegmentError> {
        let bad = |option, value, expected| {
            Err(SegmentError::InvalidOption {
                option,
                value,
                expected,
            })
        };
        if !(self.beta > 0.0 && self.beta <= std::f64::consts::FRAC_PI_2) {
            return bad("beta", self.beta, "in (0, pi/2]");
        }
        if !(self.sigma > 0.0 && self.sigma.is_finite()) {
            return bad("sigma", self.sigma, "finite and > 0");
        }
        Ok(())
    }
}

/// `v` turned by the smallest rotation that takes unit normal `from` onto unit normal
/// `to` (Rodrigues): for two faces sharing an edge this is the rotation about that edge
/// that unfolds one face's plane onto the other's, the discrete Levi-Civita transport
/// between faces. Opposite normals (a folded edge) give `v` unchanged.
#[inline]
pub fn unfold(v: glam::DVec3, from: glam::DVec3, to: glam::DVec3) -> glam::DVec3 {
    let c = from.cross(to);
    let d = from.dot(to);
    if d <= -1.0 + 1e-12 {
        return v;
    }
    v * d + c.cross(v) + c * (c.dot(v) / (1.0 + d))
}

/// The angle between two line-field directions (unit vectors, sign ignored), in
/// `[0, pi/2]`.
#[inline]
pub fn line_angle(a: glam::DVec3, b: glam::DVec3) -> f64 {
    a.dot(b).abs().min(1.0).acos()
}
