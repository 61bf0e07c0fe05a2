//! Section 7.4: spectral analysis. Mean periodograms, RAPSD and anisotropy of strata
//! (isotropic and 4:1 in its metric) beside the baselines, and why the low-frequency
//! energy depends on N (the strata's second moment); writes `spectrum_7_4.json`, the
//! radial plots, periodograms and point sets.

use std::sync::Arc;

use glam::DVec2;
use strata_engine::analysis::baseline;
use strata_engine::analysis::spectrum::{RadialProfile, Spectrum, periodogram};
use strata_engine::analysis::strata::strata_second_moment;
use strata_engine::curve::CurveOptions;
use strata_engine::planar;
use strata_engine::sample::{Sample, Sampler};
use strata_systems::report::plot::{self, Axes, Series};

use crate::BoxError;
use crate::output::Ctx;
use crate::samplers::{
    constant_field, radial_series, rectangle, unit_points, unit_square_sampler, xy,
};
use crate::table::{Row, Section, f3, row};

/// Points per set.
const N: usize = 1500;
/// Realizations averaged per periodogram.
const RUNS: u64 = 8;

struct SpectrumCase {
    name: String,
    spectrum: Spectrum,
    radial: RadialProfile,
}

/// Makes the point set of a seed.
type SetMaker<'a> = Box<dyn Fn(u64) -> Vec<DVec2> + 'a>;

/// Runs 7.4.
pub fn section_7_4(ctx: &mut Ctx) -> Result<Section, BoxError> {
    let (n, runs) = (N, RUNS);
    let iso = unit_square_sampler(1.0)?;
    // 4:1 in a domain that is square in its metric: [0, 1/2] x [0, 2], mapped by (2x, y/2).
    let mesh = Arc::new(rectangle(0.5, 2.0, 32)?);
    let field = Arc::new(constant_field(&mesh, 4.0)?);
    let aniso = planar::sampler(mesh, field, &CurveOptions::default())?.0;
    let to_metric = |s: &[Sample]| -> Vec<DVec2> {
        xy(s)
            .into_iter()
            .map(|p| DVec2::new(2.0 * p.x, 0.5 * p.y).clamp(DVec2::ZERO, DVec2::ONE))
            .collect()
    };
    let cases: Vec<(&str, SetMaker)> = vec![
        (
            "strata isotropic",
            Box::new(|s| unit_points(&iso.sample(n, s))),
        ),
        (
            "strata 4:1 (metric)",
            Box::new(|s| to_metric(&aniso.sample(n, s))),
        ),
        ("jittered grid", Box::new(|s| baseline::jittered_grid(n, s))),
        ("Poisson disk", Box::new(|s| baseline::poisson_disk(n, s))),
        (
            "uniform random",
            Box::new(|s| baseline::uniform_random(n, s)),
        ),
    ];
    let mut results = Vec::new();
    let mut first_sets = Vec::new();
    for (name, make) in &cases {
        let sets: Vec<Vec<DVec2>> = (1..=runs).map(make).collect();
        let spectrum = periodogram(&sets, 2.5)?;
        let radial = spectrum.radial();
        first_sets.push(sets[0].clone());
        results.push(SpectrumCase {
            name: name.to_string(),
            spectrum,
            radial,
        });
    }
    let floor = results[0].spectrum.noise_floor_db();
    let mut rows = case_rows(ctx, &results, floor)?;
    let figures = figures(ctx, &results, &first_sets, floor);
    rows.push(by_n_row(&iso)?);
    Ok(Section {
        title: "7.4 Spectral analysis".into(),
        notes: notes(floor),
        rows,
        figures,
    })
}

/// Per case: low-frequency energy, RAPSD peak and mean anisotropy (also written to
/// `spectrum_7_4.json`); strata are checked against the jittered grid.
fn case_rows(ctx: &Ctx, results: &[SpectrumCase], floor: f64) -> Result<Vec<Row>, BoxError> {
    let mut json = serde_json::Map::new();
    let mut rows = Vec::new();
    let jit_low = results[2].radial.mean_below(0.5);
    for c in results {
        let low = c.radial.mean_below(0.5);
        let (pf, peak) = c.radial.peak();
        let an = c.radial.mean_anisotropy_db(0.25, 2.5);
        json.insert(
            c.name.clone(),
            serde_json::json!({"frequency": c.radial.frequency, "rapsd": c.radial.rapsd,
                "anisotropy_db": c.radial.anisotropy_db, "low_frequency_energy": low,
                "peak": peak, "peak_frequency": pf, "mean_anisotropy_db": an}),
        );
        let ours = c.name.starts_with("strata");
        rows.push(row(
            &format!("{}: low-frequency energy (mean RAPSD, f < 0.5)", c.name),
            f3(low),
            if ours {
                "absence of low frequencies"
            } else {
                ""
            },
            if ours {
                "<= jittered grid"
            } else {
                "reference"
            },
            ours.then_some(low <= jit_low + 1e-9),
        ));
        rows.push(row(
            &format!("{}: RAPSD peak (at f)", c.name),
            format!("{peak:.3} (f = {pf:.2})"),
            if ours {
                "no peak in mid frequencies"
            } else {
                ""
            },
            if ours { "<= 1.15" } else { "reference" },
            ours.then_some(peak <= 1.15),
        ));
        rows.push(row(
            &format!("{}: mean anisotropy, f in [0.25, 2.5] (dB)", c.name),
            format!("{an:.2}"),
            "",
            if ours {
                "noise floor +- 1 dB"
            } else {
                "reference"
            },
            ours.then_some((an - floor).abs() <= 1.0),
        ));
    }
    ctx.json("spectrum_7_4.json", &serde_json::Value::Object(json))?;
    Ok(rows)
}

/// RAPSD and anisotropy of every case; periodogram and points of the first four.
fn figures(
    ctx: &mut Ctx,
    results: &[SpectrumCase],
    first_sets: &[Vec<DVec2>],
    floor: f64,
) -> Vec<(String, String)> {
    let (n, runs) = (N, RUNS);
    let mut figures = Vec::new();
    let series: Vec<Series> = results
        .iter()
        .map(|c| radial_series(&c.name, &c.radial, |r| &r.rapsd))
        .collect();
    let axes = Axes {
        title: format!("RAPSD, {n} points, {runs} runs"),
        x_label: "frequency / sqrt(N)".into(),
        y_label: "power".into(),
        y_range: Some((0.0, 2.2)),
        reference: vec![(1.0, "white noise".into())],
        ..Default::default()
    };
    figures.push(ctx.figure("spectrum_rapsd.png", "RAPSD", |p| {
        plot::line_chart(p, &axes, &series)
    }));
    let series: Vec<Series> = results
        .iter()
        .map(|c| radial_series(&c.name, &c.radial, |r| &r.anisotropy_db))
        .collect();
    let axes = Axes {
        title: "anisotropy".into(),
        x_label: "frequency / sqrt(N)".into(),
        y_label: "dB".into(),
        y_range: Some((-20.0, 10.0)),
        reference: vec![(floor, format!("noise floor ({floor:.1} dB)"))],
        ..Default::default()
    };
    figures.push(ctx.figure("spectrum_anisotropy.png", "anisotropy", |p| {
        plot::line_chart(p, &axes, &series)
    }));
    for (k, (c, set)) in results.iter().zip(first_sets).enumerate().take(4) {
        let slug = ["iso", "aniso", "jittered", "poisson"][k];
        let side = c.spectrum.side();
        let extent = c.spectrum.half_size as f64 / (n as f64).sqrt();
        let name = c.name.clone();
        figures.push(ctx.figure(
            &format!("periodogram_{slug}.png"),
            format!("periodogram, {}", c.name),
            |p| {
                plot::spectrum_image(
                    p,
                    &format!("mean periodogram, {name}"),
                    &c.spectrum.power,
                    side,
                    extent,
                    2.0,
                )
            },
        ));
        figures.push(ctx.figure(
            &format!("points_{slug}.png"),
            format!("points, {}", c.name),
            |p| plot::points(p, &format!("{name}, {n} points"), set, DVec2::ONE),
        ));
    }
    figures
}

/// Why the low-frequency check depends on N: energy and the strata's compactness at
/// N = 4^k (strata are the curve's square cells) and in between.
fn by_n_row(iso: &Sampler) -> Result<Row, BoxError> {
    let mut by_n = Vec::new();
    for m in [1024usize, 1500, 2048, 3000, 4096] {
        let strata: Vec<Vec<DVec2>> = (1..=RUNS).map(|s| unit_points(&iso.sample(m, s))).collect();
        let jit: Vec<Vec<DVec2>> = (1..=RUNS).map(|s| baseline::jittered_grid(m, s)).collect();
        // Frequencies up to 0.6 sqrt(N) hold every annulus below 0.5 whole.
        let a = periodogram(&strata, 0.6)?.radial().mean_below(0.5);
        let b = periodogram(&jit, 0.6)?.radial().mean_below(0.5);
        by_n.push((m, a, b, strata_second_moment(iso, m)));
    }
    Ok(row(
        "low-frequency energy strata / jittered grid, and the strata's second moment relative to a square's, by N",
        by_n.iter()
            .map(|(m, a, b, c)| format!("{m}: {a:.3} / {b:.3}, {c:.2}"))
            .collect::<Vec<_>>()
            .join("; "),
        "",
        "",
        None,
    ))
}

fn notes(floor: f64) -> String {
    let (n, runs) = (N, RUNS);
    format!(
        "{n} points, mean of {runs} periodograms (integer frequencies up to 2.5 sqrt(N)), \
         Schlomer and Deussen's normalisation (white noise = 1; frequency in units of \
         sqrt(N)). The 4:1 sampling is drawn on [0, 1/2] x [0, 2] and analysed in its own \
         metric (x * 2, y / 2). Low-frequency energy: mean RAPSD over 0 < f < 0.5. \
         Anisotropy noise floor for {runs} runs: {floor:.2} dB. Why the low-frequency \
         check fails at N = 1500 (last row): the 1D strata are intervals of the Hilbert \
         curve; at N = 4^k they are its square cells, a jittered grid, and the energy \
         equals the jittered grid's, but at other N they cut across the cells and are \
         less compact (last row: mean tr(Cov) of a stratum over a square's of the \
         same area, 1 / (6 N); `analysis::strata`), and with independent jitter the \
         energy at low frequency grows with that second moment. This is the paper's \
         stratification itself (N stratified values along the curve), not a defect of \
         the analysis, whose normalisation reproduces the jittered grid's 0.22 to 0.24. \
         Tried without reaching the jittered grid at 1500 (numbers in the commit \
         history): jitter shared by pairs of consecutive strata, nested systematic \
         allocation over the curve's quadtree."
    )
}
