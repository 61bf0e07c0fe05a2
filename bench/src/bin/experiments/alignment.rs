//! Section 7.3.1: angular error of the segments' parameterizations against a field
//! that turns faster from left to right; writes `alignment_7_3_1.json`, an angle map and
//! a segment map.

use std::sync::Arc;

use strata_engine::analysis::alignment;
use strata_engine::mesh::{TriMesh, shapes};
use strata_engine::param::ParamOptions;
use strata_engine::surface::{AngleCriterion, Preprocessed, SurfaceOptions};
use strata_systems::report::plot;

use crate::BoxError;
use crate::output::Ctx;
use crate::samplers::accelerating_field;
use crate::table::{Section, row};

/// Runs 7.3.1.
pub fn section_7_3_1(ctx: &mut Ctx) -> Result<Section, BoxError> {
    let mesh = Arc::new(shapes::plane(1.0, 48)?);
    let field = Arc::new(accelerating_field(&mesh)?);
    let options = SurfaceOptions {
        param: ParamOptions {
            gamma: 5f64.to_radians(),
            ..Default::default()
        },
        angle_criterion: AngleCriterion::Max,
        ..Default::default()
    };
    // The surface pipeline on purpose: this field turns, so the planar path's one
    // linear map would not be aligned, and 7.3.1 measures the segmentation and splits.
    let pre = Preprocessed::build_surface(mesh.clone(), field.clone(), &options)?;
    let angles = alignment::face_angles(&mesh, &field, &pre.params);
    let (max, mean) = max_and_mean(&mesh, &angles);
    // Segment map: faces coloured by segment id (scrambled so neighbours differ).
    let mut seg_of = vec![f64::NAN; mesh.face_count()];
    for (i, p) in pre.params.iter().enumerate() {
        for &f in &p.faces {
            seg_of[f as usize] = ((i * 7919) % 97) as f64;
        }
    }
    ctx.json(
        "alignment_7_3_1.json",
        &serde_json::json!({"segments": pre.params.len(), "max_angle_deg": max,
            "mean_angle_deg": mean, "face_angle_deg": angles}),
    )?;
    let f1 = ctx.figure("alignment_angle_map.png", "angular error map", |p| {
        plot::face_map(
            p,
            &format!("angle field vs u axis (max {max:.2} deg; red = 5)"),
            &mesh,
            &angles,
            5.0,
        )
    });
    let f2 = ctx.figure("alignment_segments.png", "segments", |p| {
        plot::face_map(
            p,
            &format!("{} segments, gamma = 5 deg", pre.params.len()),
            &mesh,
            &seg_of,
            96.0,
        )
    });
    Ok(Section {
        title: "7.3.1 Angular error".into(),
        notes: "Unit square (48 x 48 quads), direction theta = 2.5 x^2 (turning faster to the \
                right), 3:1; gamma = 5 degrees with the per-face criterion. Angle per face \
                between the field's major direction mapped into its segment's parameter \
                domain and the u axis (`analysis::alignment`)."
            .into(),
        rows: vec![
            row("segments", pre.params.len().to_string(), "", "", None),
            row(
                "largest per-face angle (deg)",
                format!("{max:.2}"),
                "< 4.5",
                "< gamma = 5",
                Some(max < 5.0),
            ),
            row(
                "area-weighted mean angle (deg)",
                format!("{mean:.2}"),
                "",
                "",
                None,
            ),
        ],
        figures: vec![f1, f2],
    })
}

/// The largest finite per-face angle and the area-weighted mean over the whole mesh
/// (faces without an angle count as area, not as angle).
fn max_and_mean(mesh: &TriMesh, angles: &[f64]) -> (f64, f64) {
    let finite: Vec<f64> = angles.iter().copied().filter(|a| a.is_finite()).collect();
    let max = finite.iter().copied().fold(0.0, f64::max);
    let area: f64 = mesh.face_areas().iter().sum();
    let mean = angles
        .iter()
        .zip(mesh.face_areas())
        .filter(|(a, _)| a.is_finite())
        .map(|(a, w)| a * w)
        .sum::<f64>()
        / area;
    (max, mean)
}
