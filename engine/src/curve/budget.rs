//! The cell budget shared by the segments of one surface.
//!
//! Input: each segment's parameter layout scaled into the unit square, its density per
//! triangle corner, and the total measure of all segments. Output: the segment's
//! adaptive Hilbert cells ([`SegmentCurve`]) built with its share of the budget: its
//! `max_cell_share` is the surface's divided by the segment's fraction of the total
//! measure (capped at 1), so the whole surface gets about `1 / max_cell_share` cells
//! however many segments it has, and its boundary refinement follows its cell count.
//! Cost: O(triangles) for the measure, then the cells' construction.
//!
//! Slice-level on purpose: the parameterization (which calls
//! [`corner_densities`](super::corner_densities)) sits below the cells, so this file
//! does not name its types; the surface pipeline feeds it from each `SegmentParam`.

use glam::DVec2;

use super::{CurveDomain, CurveError, CurveOptions, SegmentCurve};

/// One parameterized segment prepared for its cells: its parameter layout scaled into
/// the unit square, the density per triangle corner, and its measure (the integral of
/// the density over it), which sets its share of the cell budget. Built with
/// [`from_layout`](Self::from_layout), or from a parameterized segment with
/// `CellInput::new` (defined in [`surface`](crate::surface), which knows the
/// parameterization's types).
#[derive(Clone, Debug, PartialEq)]
pub struct CellInput {
    /// Parameter coordinates in the unit square, per parameter vertex.
    pub uv: Vec<DVec2>,
    /// Density per unit of parameter area at each triangle's corners.
    pub corner_density: Vec<[f64; 3]>,
    /// The segment's measure.
    pub measure: f64,
}

impl CellInput {
    /// A segment's layout: `uv` in the unit square per parameter vertex, its
    /// `triangles` (indices into `uv`) and the density per triangle corner. Computes
    /// the measure, O(triangles).
    pub fn from_layout(
        uv: Vec<DVec2>,
        triangles: &[[u32; 3]],
        corner_density: Vec<[f64; 3]>,
    ) -> Self {
        let measure = triangles
            .iter()
            .zip(&corner_density)
            .map(|(t, c)| {
                let q = t.map(|v| uv[v as usize]);
                0.5 * (q[1] - q[0]).perp_dot(q[2] - q[0]) * (c[0] + c[1] + c[2]) / 3.0
            })
            .sum();
        Self {
            uv,
            corner_density,
            measure,
        }
    }
}

/// The options one segment's cells are built with when it measures `measure` of a
/// surface measuring `total_measure`: `max_cell_share` divided by the segment's
/// fraction (capped at 1), and boundary refinement to about the size of its cells
/// (never deeper than `options.boundary_level`).
pub fn budget_options(measure: f64, total_measure: f64, options: &CurveOptions) -> CurveOptions {
    let fraction = (measure / total_measure).max(f64::MIN_POSITIVE);
    let share = (options.max_cell_share / fraction).min(1.0);
    // Cells this segment may get, and boundary refinement to about their size.
    let cells = 1.0 / share;
    let level =
        ((cells.log2() * 0.5).ceil() as i64 + 2).clamp(1, options.boundary_level as i64) as u8;
    CurveOptions {
        max_cell_share: share,
        boundary_level: level,
        ..*options
    }
}

/// The adaptive Hilbert cells of one segment (its `triangles` over `input.uv`) with
/// its share of the budget of a surface measuring `total_measure` (see
/// [`budget_options`]).
pub fn budget_cells(
    triangles: &[[u32; 3]],
    input: &CellInput,
    total_measure: f64,
    options: &CurveOptions,
) -> Result<SegmentCurve, CurveError> {
    SegmentCurve::build(
        &CurveDomain {
            uv: &input.uv,
            triangles,
            corner_density: &input.corner_density,
        },
        &budget_options(input.measure, total_measure, options),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The unit square as two triangles.
    fn square(density: f64) -> (Vec<DVec2>, Vec<[u32; 3]>, Vec<[f64; 3]>) {
        let uv = vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y];
        let triangles = vec![[0, 1, 2], [0, 2, 3]];
        (uv, triangles, vec![[density; 3]; 2])
    }

    #[test]
    fn the_measure_integrates_the_corner_density() {
        let (uv, triangles, density) = square(3.0);
        let input = CellInput::from_layout(uv, &triangles, density);
        assert!((input.measure - 3.0).abs() < 1e-12);
        // A density rising linearly across a triangle averages its corners.
        let uv = vec![DVec2::ZERO, DVec2::X, DVec2::Y];
        let input = CellInput::from_layout(uv, &[[0, 1, 2]], vec![[0.0, 3.0, 6.0]]);
        assert!((input.measure - 0.5 * 3.0).abs() < 1e-12);
    }

    #[test]
    fn a_segment_gets_the_share_of_its_measure() {
        let options = CurveOptions::default();
        // The whole surface: the surface's own share, boundary refinement to the size
        // of 2^16 cells (level 8 + 2).
        let whole = budget_options(2.0, 2.0, &options);
        assert_eq!(whole.max_cell_share, options.max_cell_share);
        assert_eq!(
            options.max_cell_share,
            0.5f64.powi(16),
            "the default this expects"
        );
        assert_eq!(whole.boundary_level, 10);
        // A quarter of the surface: four times the share of its measure per cell, so
        // a quarter of the cells, and boundary refinement for that many.
        let quarter = budget_options(1.0, 4.0, &options);
        assert_eq!(quarter.max_cell_share, options.max_cell_share * 4.0);
        let cells = 1.0 / quarter.max_cell_share;
        let level = (cells.log2() * 0.5).ceil() as u8 + 2;
        assert_eq!(quarter.boundary_level, level.min(options.boundary_level));
        // A tiny segment: at most one cell's share, boundary level at least 1.
        let tiny = budget_options(1e-300, 1.0, &options);
        assert_eq!(tiny.max_cell_share, 1.0);
        assert_eq!(tiny.boundary_level, 2.min(options.boundary_level));
        assert_eq!(tiny.max_level, options.max_level);
    }

    #[test]
    fn budget_cells_follow_the_share() {
        let options = CurveOptions {
            max_cell_share: 1.0 / 64.0,
            ..Default::default()
        };
        let (uv, triangles, density) = square(1.0);
        let input = CellInput::from_layout(uv, &triangles, density);
        let whole = budget_cells(&triangles, &input, input.measure, &options).expect("cells");
        // A quarter of the surface's measure: a share of 1/16 per cell.
        let quarter =
            budget_cells(&triangles, &input, 4.0 * input.measure, &options).expect("cells");
        assert!((whole.measure() - 1.0).abs() < 1e-9);
        // Uniform density on the unit square: 8 x 8 cells of 1/64 each.
        assert_eq!(whole.cell_count(), 64);
        assert!(
            quarter.cell_count() < whole.cell_count(),
            "{} cells for a quarter of the budget, {} for all of it",
            quarter.cell_count(),
            whole.cell_count()
        );
    }
}
