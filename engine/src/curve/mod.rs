//! Hilbert curves and adaptive Hilbert cells over a parameter domain (paper section
//! 6.1, with DESIGN.md's continuous mapping).
//!
//! Input: a parameterized segment scaled into the unit square (triangles in `uv` with a
//! density per corner). Output: a [`SegmentCurve`]: the leaves of an adaptive quadtree
//! in Hilbert order with the exact measure (integral of density) of the domain inside
//! each, their cumulative sum, and what is needed to map a 1D curve parameter back to
//! a point and a triangle. Build cost: O(cells x triangles per cell).
//!
//! Files: `key.rs` (the packed [`CellKey`]), `segment_curve.rs` (the [`SegmentCurve`]
//! type), `refine.rs` (building it from a [`CurveDomain`]), `locate.rs` (measure to
//! point, full leaves), `boundary.rs` and `pieces.rs` (the boundary-leaf descents and
//! their [`LeafScratch`]), `clip.rs` (polygon clipping and barycentric coordinates, below the rest), [`hilbert`] (the curve itself).
//!
//! # Inlining contract of the per-sample path
//!
//! The sampler's loop (`Sampler::fill_chunk_body`, compiled once more with x86-64-v3
//! features) maps each value through [`SegmentCurve::point_in_leaf_with`] or, for a run
//! of values in one full leaf, `SegmentCurve::full_leaf` and `FullLeaf::point`. These,
//! `SegmentCurve::leaf_is_full` and `SegmentCurve::point_location` (the triangle search
//! every point ends in) are `#[inline(always)]`: inlined into that loop they are
//! compiled with its target features, and the full leaf's data stays in registers over
//! the run. Kept out of line with `#[inline(never)]`: the boundary-leaf descents
//! `descend_pieces` and `descend_partial` (boundary leaves hold a few percent of the
//! samples, and a small full-leaf loop saves fewer registers per sample) and
//! `point_location_nearest` (rare: a point on an edge up to round-off). Small helpers
//! (`CellKey` accessors, Hilbert steps, polygon and piece-set steps) are `#[inline]`,
//! a few one-line bit tricks in `hilbert.rs` and `clip.rs` `#[inline(always)]`.
//! The attributes were tuned by instruction counts: change one only with a callgrind
//! comparison of `fill_chunk` before and after, and do not repeat this note at each
//! function.

mod boundary;
mod budget;
mod clip;
mod flat;
pub mod hilbert;
mod key;
mod locate;
mod pieces;
mod refine;
mod segment_curve;

pub use budget::{CellInput, budget_cells, budget_options};
pub use clip::{Poly, barycentric, clip_triangle};
pub use flat::DescentNode;
pub use key::CellKey;
pub use pieces::LeafScratch;
pub use refine::CurveDomain;
pub use segment_curve::{DomainPoint, SegmentCurve};

/// Per triangle, the density per unit of parameter area at its corners: the surface
/// density at each corner times `surface area / parameter area` of the triangle, so
/// that a region's measure in the parameter domain equals its measure on the surface.
/// Triangles with non-positive parameter area get 0 (the cells reject them).
///
/// `surface_area(i)` is the surface area of triangle `i`; `density(v)` the surface
/// density at parameter vertex `v`.
pub fn corner_densities(
    uv: &[glam::DVec2],
    triangles: &[[u32; 3]],
    surface_area: impl Fn(usize) -> f64,
    density: impl Fn(u32) -> f64,
) -> Vec<[f64; 3]> {
    triangles
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let p = t.map(|v| uv[v as usize]);
            let area_uv = 0.5 * (p[1] - p[0]).perp_dot(p[2] - p[0]);
            if !(area_uv > 0.0) {
                return [0.0; 3];
            }
            let ratio = surface_area(i) / area_uv;
            t.map(|v| density(v) * ratio)
        })
        .collect()
}

/// Settings of the adaptive Hilbert cells.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default, deny_unknown_fields))]
pub struct CurveOptions {
    /// Largest share of the segment's measure one leaf may hold; smaller values give
    /// more cells and follow density variation more closely. Range (0, 1]; default
    /// 2^-16 (about 65 000 cells for a uniform square).
    pub max_cell_share: f64,
    /// Level down to which cells crossed by the domain boundary are refined (section
    /// 6.1's boundary refinement). Range 0..=max_level; default 12.
    pub boundary_level: u8,
    /// Deepest level of the quadtree. Range 1..=30; default 20.
    pub max_level: u8,
    /// Levels of the continuous Hilbert map resolved inside a leaf when placing a
    /// sample. Range 1..=24; default 12.
    pub leaf_levels: u8,
}

impl Default for CurveOptions {
    fn default() -> Self {
        Self {
            max_cell_share: 1.0 / 65536.0,
            boundary_level: 12,
            max_level: 20,
            leaf_levels: 12,
        }
    }
}

impl CurveOptions {
    /// Smallest `max_cell_share` accepted: 2^-24, about 34 million cells and 0.8 GB of
    /// cell data for a surface. Smaller shares grow memory without bound (1e-9 would
    /// need about 50 GB), so they are refused up front instead of failing mid-build.
    pub const MIN_CELL_SHARE: f64 = 1.0 / (1u64 << 24) as f64;

    /// Cells a surface gets for `max_cell_share`, for budget checks: about twice
    /// `1 / max_cell_share` once boundary refinement and per-segment rounding are
    /// counted (measured: 2.0x on the plane, 2.2x on the fandisk).
    pub fn predicted_cells(&self) -> f64 {
        2.0 / self.max_cell_share
    }

    /// Bytes of cell data per cell (key, cumulative measure, candidate lists; 24-25
    /// measured on the plane and the fandisk), for budget checks.
    pub const CELL_BYTES: f64 = 25.0;

    /// Checks every field's range, and that the cell budget is bounded
    /// ([`MIN_CELL_SHARE`](Self::MIN_CELL_SHARE)).
    pub fn validate(&self) -> Result<(), CurveError> {
        let bad = |option: &'static str, value: f64, expected: &'static str| {
            Err(CurveError::InvalidOption {
                option,
                value,
                expected,
            })
        };
        if !(self.max_cell_share > 0.0 && self.max_cell_share <= 1.0) {
            return bad("max_cell_share", self.max_cell_share, "in (0, 1]");
        }
        if self.max_cell_share < Self::MIN_CELL_SHARE {
            let cells = self.predicted_cells();
            return Err(CurveError::CellBudget {
                share: self.max_cell_share,
                cells,
                bytes: cells * Self::CELL_BYTES,
            });
        }
        if !(1..=30).contains(&self.max_level) {
            return bad("max_level", self.max_level as f64, "in 1..=30");
        }
        if self.boundary_level > self.max_level {
            return bad(
                "boundary_level",
                self.boundary_level as f64,
                "at most max_level",
            );
        }
        if !(1..=24).contains(&self.leaf_levels) {
            return bad("leaf_levels", self.leaf_levels as f64, "in 1..=24");
        }
        Ok(())
    }
}

/// Errors building the cells of a segment.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CurveError {
    /// An option is out of range.
    #[error("curve option `{option}` = {value} is invalid: expected {expected}")]
    InvalidOption {
        /// Option name.
        option: &'static str,
        /// Value given.
        value: f64,
        /// Valid range.
        expected: &'static str,
    },
    /// `max_cell_share` is so small that the cells would not fit in memory.
    #[error(
        "curve option `max_cell_share` = {share:e} asks for about {cells:.1e} cells ({:.1} GB); \
         the smallest allowed is 2^-24 = 5.96e-8 (about 34 million cells, 0.8 GB)",
        bytes / 1e9
    )]
    CellBudget {
        /// Value given.
        share: f64,
        /// Cells predicted for it.
        cells: f64,
        /// Bytes predicted for them.
        bytes: f64,
    },
    /// The domain has no triangles or zero total measure.
    #[error("the parameter domain has zero measure (no triangles, or zero density everywhere)")]
    ZeroMeasure,
    /// The number of corner-density triples differs from the number of triangles.
    #[error("{densities} corner densities for {triangles} triangles")]
    DensityCount {
        /// Triangles.
        triangles: usize,
        /// Density triples.
        densities: usize,
    },
    /// A parameter vertex lies outside the unit square (or is not finite).
    #[error("parameter vertex {vertex} at ({u}, {v}) is outside the unit square")]
    OutsideUnitSquare {
        /// Vertex index.
        vertex: usize,
        /// u coordinate.
        u: f64,
        /// v coordinate.
        v: f64,
    },
    /// A triangle has an out-of-range index or is not counter-clockwise in `uv`.
    #[error("parameter triangle {triangle} is flipped, degenerate or has an invalid index")]
    BadTriangle {
        /// Triangle index.
        triangle: usize,
    },
    /// A triangle has a negative or non-finite corner density.
    #[error("parameter triangle {triangle} has a negative or non-finite density")]
    BadDensity {
        /// Triangle index.
        triangle: usize,
    },
}

#[cfg(test)]
mod tests;
