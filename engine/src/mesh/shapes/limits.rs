//! Limits of the built-in shapes' parameters and the checks every generator runs first.
//!
//! Input: a length or a resolution (with the face count it implies). Output: `Ok(())` or
//! [`MeshError::InvalidShapeParameter`] naming the shape, the parameter and what was
//! expected. Cost: O(1).

use crate::mesh::MeshError;

/// The most faces a built-in shape may have (2^24, about 2 GB of mesh with adjacency).
pub const MAX_SHAPE_FACES: u64 = 1 << 24;

/// The smallest length (size, radius, height) a built-in shape accepts.
///
/// Lengths are bounded so that squared edge lengths and cross products neither underflow
/// nor overflow `f64`.
pub const MIN_SHAPE_LENGTH: f64 = 1e-30;

/// The largest length (size, radius, height) a built-in shape accepts.
pub const MAX_SHAPE_LENGTH: f64 = 1e30;

const LENGTH_EXPECTED: &str = "a finite length in [1e-30, 1e30]";

/// The error for `parameter` of `shape` holding `value` where `expected` was required.
pub(super) fn invalid(
    shape: &'static str,
    parameter: &'static str,
    value: f64,
    expected: &'static str,
) -> MeshError {
    MeshError::InvalidShapeParameter {
        shape,
        parameter,
        value,
        expected,
    }
}

/// Accepts a length (size, radius, height) in
/// `[MIN_SHAPE_LENGTH, MAX_SHAPE_LENGTH]` (which also rejects NaN and infinities).
pub(super) fn check_length(
    shape: &'static str,
    parameter: &'static str,
    value: f64,
) -> Result<(), MeshError> {
    if (MIN_SHAPE_LENGTH..=MAX_SHAPE_LENGTH).contains(&value) {
        Ok(())
    } else {
        Err(invalid(shape, parameter, value, LENGTH_EXPECTED))
    }
}

/// Accepts `resolution` if it is at least `min` and the shape has at most
/// [`MAX_SHAPE_FACES`] faces (`faces` is computed in `f64` so that it cannot overflow).
pub(super) fn check_resolution(
    shape: &'static str,
    resolution: u32,
    min: u32,
    faces: f64,
    expected: &'static str,
) -> Result<(), MeshError> {
    if resolution < min || faces > MAX_SHAPE_FACES as f64 {
        Err(invalid(
            shape,
            "resolution",
            f64::from(resolution),
            expected,
        ))
    } else {
        Ok(())
    }
}
