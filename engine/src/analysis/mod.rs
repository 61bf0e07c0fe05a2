//! Planar quality measures for point sets in the unit square, and planar baselines.
//!
//! Input: points in `[0, 1]^2` as [`glam::DVec2`]. Output: numbers (discrepancies,
//! log-log slopes) and small plain structs ([`DiscrepancyCurve`]).
//!
//! - [`discrepancy`]: the exact supremum star discrepancy (O(N^2)), the L2 star
//!   discrepancy by Warnock's closed form (O(N^2)), exact sup discrepancies for origin
//!   triangles (O(N^2 log N)) and quarter discs (O(N log N)), and log-log slopes of
//!   discrepancy against N, as in section 7.2 of Quinn et al. ("Generalized Anisotropic
//!   Stratified Surface Sampling") and Niederreiter, "Random Number Generation and
//!   Quasi-Monte Carlo Methods" (SIAM 1992), chapter 2.
//! - [`baseline`]: reference samplers of the unit square (uniform random, jittered grid,
//!   Poisson disk) that the method is compared against; each returns exactly `n` points
//!   ([`planar_samples`] wraps them as [`Sample`](crate::sample::Sample)s).
//! - [`mesh_baseline`]: uniform random and Poisson-disk samplers of a mesh under a field,
//!   returning `Sample`s.
//! - [`spectrum`]: periodogram, RAPSD and anisotropy (section 7.4).
//! - [`dda`]: differential domain analysis of non-uniform, anisotropic and surface
//!   samplings (section 7.5).
//! - [`alignment`]: per-face angle between the field and the parameter axes (7.3.1).
//! - [`strata`]: where a sampler's 1D strata lie, how compact they are and the count
//!   variance they put into boxes (7.3.2, 7.4).
//! - [`seed_ratio`]: geometric mean ratio of two curves over N with its jackknife
//!   error over the seeds (7.3.2).
//! - [`radial_band`]: a radial profile over a frequency band against a reference
//!   (7.5).
//! - [`strokes`]: coverage of the square by brush strokes made from samples: covered
//!   fraction, mean overlap and largest hole on a raster (7.1, Fig. 3).
//!
//! Points outside the unit square (or NaN) are a caller error: the `try_` functions
//! return [`AnalysisError`], their twins panic with the same message.

pub mod alignment;
pub mod baseline;
pub mod dda;
pub mod discrepancy;
pub mod mesh_baseline;
pub mod radial_band;
pub mod seed_ratio;
pub mod spectrum;
pub mod strata;
pub mod strokes;

pub use baseline::{jittered_grid, planar_samples, poisson_disk, uniform_random};
pub use discrepancy::{
    Discrepancy, DiscrepancyCurve, ShapeFamily, loglog_slope, star_discrepancy_l2,
    star_discrepancy_sup, try_star_discrepancy_l2, try_star_discrepancy_sup,
};
pub use strokes::{Coverage, Stroke, StrokeError, StrokeStyle};

use glam::DVec2;

/// What can go wrong measuring a point set.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum AnalysisError {
    /// A point is NaN or lies outside `[0, 1]^2`.
    #[error("point {index} = ({x}, {y}) is not in the unit square [0, 1]^2")]
    PointOutsideUnitSquare {
        /// Index of the point in the input slice.
        index: usize,
        /// Its x coordinate.
        x: f64,
        /// Its y coordinate.
        y: f64,
    },
    /// An axis scale of [`Discrepancy`] is not finite and positive.
    #[error("axis scale ({x}, {y}) must be finite and positive")]
    InvalidAxisScale {
        /// Scale along x.
        x: f64,
        /// Scale along y.
        y: f64,
    },
    /// A sampler given to [`DiscrepancyCurve`] returned the wrong number of points.
    #[error("sampler returned {returned} points for n = {n}, seed = {seed}")]
    WrongSampleCount {
        /// Requested count.
        n: usize,
        /// Seed of the call.
        seed: u64,
        /// Points returned.
        returned: usize,
    },
    /// A sampler given to [`DiscrepancyCurve`] returned a point outside the unit square.
    #[error("sampler output for n = {n}, seed = {seed}: {source}")]
    SamplerPoint {
        /// Requested count.
        n: usize,
        /// Seed of the call.
        seed: u64,
        /// Which point, and where.
        #[source]
        source: Box<AnalysisError>,
    },
    /// [`DiscrepancyCurve`] was given no sample counts or no seeds.
    #[error("a discrepancy curve needs at least one n and one seed ({ns} n, {seeds} seeds)")]
    EmptyCurve {
        /// Number of sample counts given.
        ns: usize,
        /// Number of seeds given.
        seeds: usize,
    },
    /// [`strata::strata_variance`] was given no boxes to average over.
    #[error("the strata's count variance needs at least one box")]
    NoBoxes,
}

/// Checks that every point is finite and lies in the closed unit square `[0, 1]^2`.
///
/// # Errors
/// [`AnalysisError::PointOutsideUnitSquare`] for the first point that is not.
pub fn check_unit_square(points: &[DVec2]) -> Result<(), AnalysisError> {
    let inside = |v: f64| (0.0..=1.0).contains(&v);
    match points.iter().position(|p| !(inside(p.x) && inside(p.y))) {
        None => Ok(()),
        Some(index) => Err(AnalysisError::PointOutsideUnitSquare {
            index,
            x: points[index].x,
            y: points[index].y,
        }),
    }
}

#[cfg(test)]
mod tests;
