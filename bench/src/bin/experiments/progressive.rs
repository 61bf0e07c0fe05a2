//! Issue 19: the progressive order against the stratified one, side by side, with the
//! quality measures of 7.2 and 7.4 on the unit square (isotropic, and 4:1 with the
//! 4:1 metric scale) at `N = 2^l, 1.5 x 2^l` (l = 6..13) and `N = 1000, 1500, 3000`.

use std::sync::Arc;

use glam::DVec2;
use strata_engine::analysis::spectrum::periodogram;
use strata_engine::analysis::{Discrepancy, DiscrepancyCurve, ShapeFamily};
use strata_engine::curve::CurveOptions;
use strata_engine::mesh::{TriMesh, shapes};
use strata_engine::planar;
use strata_engine::sample::{Sample, Sampler};

use crate::BoxError;
use crate::output::Ctx;
use crate::samplers::{constant_field, rectangle};
use crate::table::{Row, Section, f3, row};

/// Counts at which the spectra are compared; 1024 and 4096 are powers of 4.
const SPECTRUM_COUNTS: [usize; 6] = [1000, 1024, 1500, 2048, 3000, 4096];

/// The planar sampler of `mesh` with a constant field along x.
fn sampler(mesh: TriMesh, anisotropy: f64) -> Result<Sampler, BoxError> {
    let mesh = Arc::new(mesh);
    let field = Arc::new(constant_field(&mesh, anisotropy)?);
    Ok(planar::sampler(mesh, field, &CurveOptions::default())?.0)
}

/// `n` samples of `s` for `seed` in either order, as points scaled by `scale` and
/// clamped to the unit square.
fn points(s: &Sampler, n: usize, seed: u64, progressive: bool, scale: DVec2) -> Vec<DVec2> {
    let mut out = vec![Sample::default(); n];
    if progressive {
        s.progressive_into(seed, 0, &mut out);
    } else {
        s.sample_into(seed, &mut out);
    }
    out.iter()
        .map(|s| {
            (DVec2::new(f64::from(s.position[0]), f64::from(s.position[1])) * scale)
                .clamp(DVec2::ZERO, DVec2::ONE)
        })
        .collect()
}

/// One order's measures on one field.
struct Measured {
    sup: f64,
    l2: f64,
    /// Low-frequency energy (mean RAPSD below 0.5) and RAPSD peak per spectrum count.
    spectra: Vec<(f64, f64)>,
}

fn measure(
    square: &Sampler,
    axis: DVec2,
    metric: &Sampler,
    to_metric: DVec2,
    progressive: bool,
    runs: u64,
) -> Result<Measured, BoxError> {
    let mut ns: Vec<usize> = (6..=13)
        .flat_map(|l| [1usize << l, (1 << l) + (1 << (l - 1))])
        .chain([1000, 1500, 3000])
        .collect();
    ns.sort_unstable();
    let d = Discrepancy::new(ShapeFamily::Rectangles).with_axis_scale(axis);
    let curve = DiscrepancyCurve::measure(
        &d,
        |n, seed| points(square, n, seed, progressive, DVec2::ONE),
        &ns,
        &[1, 2, 3],
    )?;
    let mut spectra = Vec::new();
    for n in SPECTRUM_COUNTS {
        let sets: Vec<Vec<DVec2>> = (1..=runs)
            .map(|seed| points(metric, n, seed, progressive, to_metric))
            .collect();
        let radial = periodogram(&sets, 2.5)?.radial();
        spectra.push((radial.mean_below(0.5), radial.peak().1));
    }
    Ok(Measured {
        sup: curve.sup_slope(),
        l2: curve.l2_slope(),
        spectra,
    })
}

/// The comparison rows of one field.
fn rows(name: &str, s: &Measured, p: &Measured) -> Vec<Row> {
    // A miss on the better side (a steeper slope, less low-frequency energy) says so.
    let side = |pass: bool, better: bool| {
        if !pass && better {
            ", the better side"
        } else {
            ""
        }
    };
    let slope = |what: &str, a: f64, b: f64| {
        let pass = (a - b).abs() <= 0.02;
        row(
            &format!("{what} slope, {name}: stratified / progressive"),
            format!("{} / {}{}", f3(a), f3(b), side(pass, b > a)),
            "",
            "within 0.02",
            Some(pass),
        )
    };
    let mut out = vec![slope("sup", s.sup, p.sup), slope("L2", s.l2, p.l2)];
    for (i, n) in SPECTRUM_COUNTS.into_iter().enumerate() {
        let (a, b) = (s.spectra[i].0, p.spectra[i].0);
        let power_of_4 = n.is_power_of_two() && n.trailing_zeros() % 2 == 0;
        let bound = if power_of_4 { 0.05 } else { 0.15 };
        let pass = (b / a - 1.0).abs() <= bound;
        out.push(row(
            &format!("low-frequency energy, {name}, N = {n}: stratified / progressive"),
            format!(
                "{} / {} ({:+.1}%{})",
                f3(a),
                f3(b),
                100.0 * (b / a - 1.0),
                side(pass, b < a)
            ),
            "",
            if power_of_4 {
                "within 5%"
            } else {
                "within 15%"
            },
            Some(pass),
        ));
    }
    let peak = |m: &Measured| m.spectra.iter().map(|x| x.1).fold(0.0, f64::max);
    out.push(row(
        &format!("largest RAPSD peak, {name}: stratified / progressive"),
        format!("{:.2} / {:.2}", peak(s), peak(p)),
        "",
        "<= 1.15",
        Some(peak(p) <= 1.15),
    ));
    out
}

/// Runs the comparison and returns its section.
pub fn section_progressive(ctx: &mut Ctx) -> Result<Section, BoxError> {
    let runs = if ctx.quick { 4 } else { 24 };
    let square_iso = sampler(shapes::plane(1.0, 16)?, 1.0)?;
    let square_aniso = sampler(shapes::plane(1.0, 16)?, 4.0)?;
    // 4:1 on a rectangle that is a square in its metric, for the spectrum.
    let metric_aniso = sampler(rectangle(0.5, 2.0, 32)?, 4.0)?;
    let cases = [
        (
            "isotropic",
            &square_iso,
            DVec2::ONE,
            &square_iso,
            DVec2::ONE,
        ),
        (
            "4:1",
            &square_aniso,
            DVec2::new(4.0, 1.0),
            &metric_aniso,
            DVec2::new(2.0, 0.5),
        ),
    ];
    let mut out = Vec::new();
    for (name, square, axis, metric, to_metric) in cases {
        let s = measure(square, axis, metric, to_metric, false, runs)?;
        let p = measure(square, axis, metric, to_metric, true, runs)?;
        out.extend(rows(name, &s, &p));
    }
    Ok(Section {
        title: "Progressive order (issue 19)".into(),
        notes: format!(
            "The progressive order (`Sampler::progressive_into`: the first N ranks of one \
             Owen-scrambled radical-inverse sequence per seed, so fewer samples are a prefix \
             of more) against the stratified order (`Sampler::sample_into`: N strata for \
             exactly N samples) on the unit square, isotropic and 4:1. Slopes: sup and L2 \
             discrepancy over origin rectangles at N = 2^l and 1.5 x 2^l (l = 6..13) and \
             1000, 1500, 3000, seeds 1-3 (4:1 with the metric axis scale, as in 7.2). \
             Spectra: {runs} sets per N, 4:1 on a rectangle that is square in its metric, \
             as in 7.4; low-frequency energy is the mean RAPSD below 0.5 of the normalised \
             frequency. Targets are issue 19's: slopes within 0.02 of the stratified \
             order's, low-frequency energy within 15% (5% at N = 4^k), no peak above 1.15. \
             Between powers of two a progressive prefix holds two values in some dyadic \
             intervals of the curve and one in the others (1500 = 1024 + 476), so its \
             density along the curve is uneven at that scale: the stratified order is the \
             better choice for one fixed N, the progressive order where N changes (level \
             of detail)."
        ),
        rows: out,
        figures: Vec::new(),
    })
}
