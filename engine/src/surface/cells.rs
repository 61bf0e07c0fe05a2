//! From parameterized segments to their cells: each segment's [`CellInput`] and its
//! cells under the surface's shared budget ([`budget_cells`]).
//!
//! Input: the mesh, the field and the final segments' [`SegmentParam`]s. Output: one
//! [`SegmentCurve`] per segment, in the order of the params (the caller totals the
//! measures and orders the segments with `surface::assemble`). Cost: O(F) for the
//! inputs, then the cells' construction, segments in parallel with rayon (the result
//! does not depend on the thread count).

use rayon::prelude::*;

use super::SurfaceError;
use crate::curve::{CellInput, CurveError, CurveOptions, SegmentCurve, budget_cells};
use crate::field::TensorField;
use crate::mesh::TriMesh;
use crate::param::SegmentParam;

impl CellInput {
    /// Prepares `param` (a segment of `mesh`) with `field` for its cells: its layout
    /// scaled into the unit square and the density per corner. Cost O(segment).
    pub fn new(mesh: &TriMesh, field: &TensorField, param: &SegmentParam) -> Self {
        let (uv, _, _) = param.to_unit_square();
        let corner_density = param.corner_density(mesh, field, &uv);
        Self::from_layout(uv, &param.triangles, corner_density)
    }
}

/// The adaptive Hilbert cells of one segment whose [`CellInput`] is `input`, when all
/// segments together measure `total_measure`: the segment's `max_cell_share` is
/// `options.max_cell_share` divided by its fraction of the total (capped at 1), so that
/// the whole surface gets about `1 / options.max_cell_share` cells, and its boundary
/// refinement follows its cell count ([`budget_cells`]). This is what
/// [`Preprocessed::build`](super::Preprocessed::build) does per segment; a caller that rebuilds only some segments
/// passes the current total.
pub fn segment_cells(
    param: &SegmentParam,
    input: &CellInput,
    total_measure: f64,
    options: &CurveOptions,
) -> Result<SegmentCurve, CurveError> {
    budget_cells(&param.triangles, input, total_measure, options)
}

/// The [`CellInput`] of every parameterized segment, in parallel, in `params` order.
pub(super) fn cell_inputs(
    mesh: &TriMesh,
    field: &TensorField,
    params: &[SegmentParam],
) -> Vec<CellInput> {
    params
        .par_iter()
        .map(|p| CellInput::new(mesh, field, p))
        .collect()
}

/// Cells for every parameterized segment, in parallel, in `params` order. The cell
/// budget is shared: each segment's `max_cell_share` is scaled by its share of
/// `total_measure`, and its boundary refinement by how many cells it gets. An error
/// names the segment by its index in `params`.
pub(super) fn build_cells(
    params: &[SegmentParam],
    inputs: &[CellInput],
    total_measure: f64,
    options: &CurveOptions,
) -> Result<Vec<SegmentCurve>, SurfaceError> {
    params
        .par_iter()
        .zip(inputs.par_iter())
        .enumerate()
        .map(|(id, (p, input))| {
            segment_cells(p, input, total_measure, options).map_err(|source| SurfaceError::Curve {
                segment: id,
                source,
            })
        })
        .collect()
}
