//! Samplers, domains and point conversions that several experiments share.

use std::sync::Arc;

use glam::{DVec2, DVec3};
use strata_engine::analysis::spectrum::RadialProfile;
use strata_engine::curve::CurveOptions;
use strata_engine::field::{FieldSpec, TensorField};
use strata_engine::mesh::{TriMesh, shapes};
use strata_engine::planar;
use strata_engine::sample::{Sample, Sampler};
use strata_systems::report::plot::Series;

use crate::BoxError;

/// A constant field along x with the given anisotropy and density 1.
pub fn constant_field(mesh: &TriMesh, anisotropy: f64) -> Result<TensorField, BoxError> {
    Ok(FieldSpec::Constant {
        direction: [1.0, 0.0, 0.0],
        anisotropy,
        density: 1.0,
    }
    .build(mesh)?)
}

/// The planar sampler of the unit square with a constant field.
pub fn unit_square_sampler(anisotropy: f64) -> Result<Sampler, BoxError> {
    let mesh = Arc::new(shapes::plane(1.0, 16)?);
    let field = Arc::new(constant_field(&mesh, anisotropy)?);
    Ok(planar::sampler(mesh, field, &CurveOptions::default())?.0)
}

/// A flat mesh of `[0, w] x [0, h]`.
pub fn rectangle(w: f64, h: f64, res: u32) -> Result<TriMesh, BoxError> {
    let m = shapes::plane(1.0, res)?;
    let pos = m
        .positions()
        .iter()
        .map(|p| DVec3::new(p.x * w, p.y * h, 0.0))
        .collect();
    Ok(TriMesh::new(pos, m.triangles().to_vec())?)
}

/// A planar field turning faster from left to right: theta(x) = 2.5 x^2, 3:1 (the
/// field of 7.3.1 and 7.3.3).
pub fn accelerating_field(mesh: &TriMesh) -> Result<TensorField, BoxError> {
    let dirs: Vec<DVec3> = mesh
        .positions()
        .iter()
        .map(|p| {
            let t = 2.5 * p.x * p.x;
            DVec3::new(t.cos(), t.sin(), 0.0)
        })
        .collect();
    Ok(TensorField::from_frames(
        mesh,
        &dirs,
        &vec![[3.0, 1.0 / 3.0]; dirs.len()],
    )?)
}

/// Samples' xy.
pub fn xy(samples: &[Sample]) -> Vec<DVec2> {
    samples
        .iter()
        .map(|s| DVec2::new(s.position[0] as f64, s.position[1] as f64))
        .collect()
}

/// Samples' xy in the unit square (closed; float rounding clamped).
pub fn unit_points(samples: &[Sample]) -> Vec<DVec2> {
    xy(samples)
        .into_iter()
        .map(|p| p.clamp(DVec2::ZERO, DVec2::ONE))
        .collect()
}

/// Sample counts `2^l` and `2^l + 2^(l-1)` from 64 up to `max`.
pub fn sizes(max: usize) -> Vec<usize> {
    (6..=13)
        .flat_map(|l| [1usize << l, (1 << l) + (1 << (l - 1))])
        .filter(|&n| n <= max)
        .collect()
}

/// One line of a radial plot: `value` of `radial` against its frequencies.
pub fn radial_series(
    name: &str,
    radial: &RadialProfile,
    value: impl Fn(&RadialProfile) -> &Vec<f64>,
) -> Series {
    Series::line(name, radial.frequency.clone(), value(radial).clone())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_alternate_powers_of_two_and_three_halves() {
        assert_eq!(sizes(400), vec![64, 96, 128, 192, 256, 384]);
        assert_eq!(*sizes(8192).last().unwrap_or(&0), 8192);
    }

    #[test]
    fn rectangle_spans_its_sides() -> Result<(), BoxError> {
        let m = rectangle(0.5, 2.0, 4)?;
        let (lo, hi) = m
            .positions()
            .iter()
            .fold((DVec3::MAX, DVec3::MIN), |(a, b), p| (a.min(*p), b.max(*p)));
        assert_eq!((lo.x, lo.y, hi.x, hi.y), (0.0, 0.0, 0.5, 2.0));
        assert!((m.area() - 1.0).abs() < 1e-12);
        Ok(())
    }
}
