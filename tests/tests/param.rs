//! Parameterization experiments of the paper (section 7.3.1) through the surface
//! pipeline.

use std::sync::Arc;

use glam::DVec3;
use strata_engine::field::TensorField;
use strata_engine::mesh::shapes;
use strata_engine::param::ParamOptions;
use strata_engine::surface::{AngleCriterion, Preprocessed, SurfaceOptions};

/// A planar field turning faster from left to right: theta(x) = 2.5 x^2 (radians) on
/// the unit square, 3:1 anisotropy.
fn accelerating_field(mesh: &strata_engine::mesh::TriMesh) -> TensorField {
    let dirs: Vec<DVec3> = mesh
        .positions()
        .iter()
        .map(|p| {
            let t = 2.5 * p.x * p.x;
            DVec3::new(t.cos(), t.sin(), 0.0)
        })
        .collect();
    TensorField::from_frames(mesh, &dirs, &vec![[3.0, 1.0 / 3.0]; dirs.len()]).expect("field")
}

fn run(gamma_deg: f64, angle_criterion: AngleCriterion) -> (usize, f64, f64) {
    let mesh = Arc::new(shapes::plane(1.0, 48).expect("plane"));
    let field = Arc::new(accelerating_field(&mesh));
    let options = SurfaceOptions {
        param: ParamOptions {
            gamma: gamma_deg.to_radians(),
            ..Default::default()
        },
        angle_criterion,
        ..Default::default()
    };
    // The surface pipeline on purpose: `build` would take the planar path for this flat
    // mesh, whose one linear map does not follow a turning field.
    let pre = Preprocessed::build_surface(mesh, field, &options).expect("preprocess");
    // Isotropic-fallback segments have no field direction to follow: left out.
    let max = pre
        .params
        .iter()
        .filter(|p| !p.report.isotropic_fallback)
        .map(|p| p.report.max_angle_deg)
        .fold(0.0, f64::max);
    let mean_worst = pre
        .params
        .iter()
        .map(|p| p.report.mean_angle_deg)
        .fold(0.0, f64::max);
    (pre.params.len(), max, mean_worst)
}

#[test]
fn section_7_3_1_angular_error_is_bounded_and_gamma_controls_segmentation() {
    let (segments_5, max_5, mean_5) = run(5.0, AngleCriterion::Max);
    let (segments_m, max_m, mean_m) = run(5.0, AngleCriterion::Mean);
    println!(
        "gamma 5 mean criterion: {segments_m} segments, max angle {max_m:.2}, worst mean {mean_m:.2}"
    );
    let (segments_2, max_2, mean_2) = run(2.0, AngleCriterion::Max);
    println!("gamma 5: {segments_5} segments, max angle {max_5:.2}, worst mean {mean_5:.2}");
    println!("gamma 2: {segments_2} segments, max angle {max_2:.2}, worst mean {mean_2:.2}");
    assert!(mean_5 < 5.0 && mean_2 < 2.0);
    // The per-face criterion bounds the largest angle by gamma. The paper measured
    // under 4.5 degrees for gamma = 5; we measure 4.84 here, and 4.55 to 4.99 over
    // segmentation seeds 1 to 12 (the bound is met, that figure is not: splitting
    // stops as soon as every face of a segment is under gamma, so the worst of some 20
    // segments lands just under gamma).
    assert!(
        max_5 < 5.0,
        "largest angle between field and parameter axes {max_5}"
    );
    assert!(max_2 < 2.0, "largest angle {max_2}");
    assert!(
        segments_2 > segments_5,
        "a smaller gamma gives more segments"
    );
}
