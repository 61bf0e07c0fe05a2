//! Shared pieces of the field sources ([`FieldSpec`](super::FieldSpec), the curvature
//! field and [`PlanarWarp`](super::PlanarWarp)): the parameter checks that build
//! [`FieldError::InvalidParameter`] and the `(density, spacing ratio) -> (l1, l2)` map.
//!
//! Input: one option value (or point) and its name. Output: `Ok(())` or the error naming
//! it; for [`eigenvalues`], the two eigenvalues. Cost: O(1). Kept below `spec`,
//! `curvature` and `warp` so none of them has to reach into another for these.

use super::FieldError;

/// Eigenvalues `(l1, l2)` for density `sqrt(l1 l2)` and spacing ratio `sqrt(l1 / l2)`.
pub(crate) fn eigenvalues(density: f64, anisotropy: f64) -> [f64; 2] {
    [density * anisotropy, density / anisotropy]
}

/// The error for option `parameter` holding `value` where `expected` was required.
pub(crate) fn invalid(parameter: &'static str, value: f64, expected: &'static str) -> FieldError {
    FieldError::InvalidParameter {
        parameter,
        value,
        expected,
    }
}

/// Checks that both coordinates of point `p` (option `parameter`) are finite; the error
/// carries the first non-finite coordinate.
pub(crate) fn finite_point(parameter: &'static str, p: [f64; 2]) -> Result<(), FieldError> {
    match p.into_iter().find(|c| !c.is_finite()) {
        Some(c) => Err(invalid(parameter, c, "finite coordinates")),
        None => Ok(()),
    }
}

/// Largest accepted `smoothing_iterations` of a curvature estimate.
pub(crate) const MAX_SMOOTHING_ITERATIONS: u32 = 1000;

/// Checks that option `parameter` is finite and `>= 0`.
pub(crate) fn non_negative(parameter: &'static str, value: f64) -> Result<(), FieldError> {
    if value >= 0.0 && value.is_finite() {
        Ok(())
    } else {
        Err(invalid(parameter, value, "a finite value >= 0"))
    }
}

/// Checks a spacing ratio option: finite and `>= 1`.
pub(crate) fn spacing_ratio(parameter: &'static str, value: f64) -> Result<(), FieldError> {
    if value >= 1.0 && value.is_finite() {
        Ok(())
    } else {
        Err(invalid(parameter, value, "a finite spacing ratio >= 1"))
    }
}

/// Checks a world direction option: finite and non-zero (the error carries its length).
pub(crate) fn direction(parameter: &'static str, d: [f64; 3]) -> Result<(), FieldError> {
    let v = glam::DVec3::from(d);
    if v.is_finite() && v.length_squared() > 0.0 {
        Ok(())
    } else {
        Err(invalid(parameter, v.length(), "a finite non-zero vector"))
    }
}

/// Checks `smoothing_iterations` of a curvature estimate: at most
/// [`MAX_SMOOTHING_ITERATIONS`].
pub(crate) fn smoothing_iterations(value: u32) -> Result<(), FieldError> {
    if value > MAX_SMOOTHING_ITERATIONS {
        Err(invalid(
            "smoothing_iterations",
            f64::from(value),
            "at most 1000",
        ))
    } else {
        Ok(())
    }
}

/// Checks that option `parameter` is finite and strictly positive.
pub(crate) fn positive(parameter: &'static str, value: f64) -> Result<(), FieldError> {
    if value > 0.0 && value.is_finite() {
        Ok(())
    } else {
        Err(invalid(parameter, value, "a finite value > 0"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eigenvalues_have_the_asked_density_and_spacing_ratio() {
        let [l1, l2] = eigenvalues(8.0, 2.0);
        assert_eq!([l1, l2], [16.0, 4.0]);
        assert_eq!((l1 * l2).sqrt(), 8.0);
        assert_eq!((l1 / l2).sqrt(), 2.0);
        assert_eq!(eigenvalues(3.0, 1.0), [3.0, 3.0]);
    }

    #[test]
    fn finite_point_reports_the_first_bad_coordinate() {
        assert!(finite_point("center", [0.0, -1.5]).is_ok());
        match finite_point("center", [1.0, f64::INFINITY]) {
            Err(FieldError::InvalidParameter {
                parameter, value, ..
            }) => {
                assert_eq!(parameter, "center");
                assert_eq!(value, f64::INFINITY);
            }
            other => panic!("expected InvalidParameter, got {other:?}"),
        }
        match finite_point("origin", [f64::NAN, f64::INFINITY]) {
            Err(FieldError::InvalidParameter { value, .. }) => assert!(value.is_nan()),
            other => panic!("expected InvalidParameter, got {other:?}"),
        }
    }

    #[test]
    fn shared_checks_accept_their_ranges_and_name_the_option() {
        assert!(non_negative("scale", 0.0).is_ok() && non_negative("scale", 5.0).is_ok());
        assert!(spacing_ratio("min", 1.0).is_ok() && direction("d", [0.0, 0.0, 2.0]).is_ok());
        assert!(smoothing_iterations(MAX_SMOOTHING_ITERATIONS).is_ok());
        let name = |r: Result<(), FieldError>| match r {
            Err(FieldError::InvalidParameter { parameter, .. }) => parameter,
            other => panic!("expected InvalidParameter, got {other:?}"),
        };
        assert_eq!(name(non_negative("scale", -1e-300)), "scale");
        assert_eq!(name(non_negative("weight", f64::NAN)), "weight");
        assert_eq!(name(spacing_ratio("max", 0.999)), "max");
        assert_eq!(
            name(direction("guidance direction", [0.0; 3])),
            "guidance direction"
        );
        assert_eq!(name(direction("d", [f64::INFINITY, 0.0, 0.0])), "d");
        assert_eq!(
            name(smoothing_iterations(MAX_SMOOTHING_ITERATIONS + 1)),
            "smoothing_iterations"
        );
    }

    #[test]
    fn positive_rejects_zero_negative_infinite_and_nan() {
        assert!(positive("sigma", 1e-300).is_ok());
        for bad in [0.0, -1.0, f64::INFINITY, f64::NAN] {
            match positive("sigma", bad) {
                Err(FieldError::InvalidParameter {
                    parameter,
                    value,
                    expected,
                }) => {
                    assert_eq!(parameter, "sigma");
                    assert!(value.to_bits() == bad.to_bits());
                    assert_eq!(expected, "a finite value > 0");
                }
                other => panic!("{bad}: expected InvalidParameter, got {other:?}"),
            }
        }
    }
}
