//! Section 7.1, Fig. 3 as a measurement: 500 samples of the unit square under a uniform
//! 8:1 field, each drawn as an 8:1 brush stroke, and the strokes' coverage of the square
//! for isotropic and anisotropic strata placement and Poisson-disk baselines; writes
//! `strokes_7_1.json` and two coverage images.

use std::sync::Arc;

use glam::DVec2;
use strata_engine::analysis::mesh_baseline::mesh_poisson_disk;
use strata_engine::analysis::poisson_disk;
use strata_engine::analysis::strokes::{self, Coverage, StrokeStyle};
use strata_engine::mesh::shapes;
use strata_engine::sample::Sample;
use strata_systems::report::plot;

use crate::BoxError;
use crate::output::Ctx;
use crate::samplers::{constant_field, unit_points, unit_square_sampler};
use crate::table::{Row, Section, f3, row};

/// Samples per set (Fig. 3).
const N: usize = 500;
/// The field's spacing ratio and the strokes' aspect ratio (Fig. 3).
const RATIO: f64 = 8.0;
/// Relative stroke size variation: each stroke scaled by a factor in `[0.75, 1.25]`.
const VARIATION: f64 = 0.25;
/// Raster side of the coverage measures.
const RASTER: usize = 1024;
/// Raster side of the coverage images.
const IMAGE: usize = 256;
/// Total nominal stroke area over the square's area.
const AREA_FACTORS: [f64; 2] = [1.0, 2.0];

/// The placements compared, in table order.
const PLACEMENTS: [&str; 4] = [
    "isotropic strata",
    "anisotropic strata 8:1",
    "Poisson disk",
    "Poisson disk 8:1",
];

/// Median of a non-empty slice.
fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let m = s.len() / 2;
    if s.len() % 2 == 1 {
        s[m]
    } else {
        0.5 * (s[m - 1] + s[m])
    }
}

/// Sample positions, per placement and per seed.
type Sets = Vec<Vec<Vec<[f64; 2]>>>;

/// The sample positions of every placement and seed, and one record of the 8:1 sampler.
fn placements(seeds: &[u64]) -> Result<(Sets, Sample), BoxError> {
    let iso = unit_square_sampler(1.0)?;
    let aniso = unit_square_sampler(RATIO)?;
    let mesh = shapes::plane(1.0, 16)?;
    let field = Arc::new(constant_field(&mesh, RATIO)?);
    let to_xy = |p: Vec<DVec2>| p.into_iter().map(|p| [p.x, p.y]).collect::<Vec<_>>();
    let mut out = vec![Vec::new(); PLACEMENTS.len()];
    let mut record = Sample::default();
    let mut buf = vec![Sample::default(); N];
    for &seed in seeds {
        iso.sample_into(seed, &mut buf);
        out[0].push(to_xy(unit_points(&buf)));
        aniso.sample_into(seed, &mut buf);
        record = buf[0];
        out[1].push(to_xy(unit_points(&buf)));
        out[2].push(to_xy(poisson_disk(N, seed)));
        out[3].push(to_xy(unit_points(&mesh_poisson_disk(
            &mesh, &field, N, seed,
        ))));
    }
    Ok((out, record))
}

/// The stroke direction and length from a sample of the 8:1 field: along the axis of
/// the larger expected spacing, as long as that spacing.
fn long_axis(s: &Sample) -> ([f64; 2], f64) {
    let major = [f64::from(s.major_axis[0]), f64::from(s.major_axis[1])];
    let [dense, sparse] = s.spacing.map(f64::from);
    if sparse >= dense {
        // The minor axis, normal x major with the normal +z.
        ([-major[1], major[0]], sparse)
    } else {
        (major, dense)
    }
}

/// One placement's medians, per seed values and rows.
struct Measured {
    covered: f64,
    overlap: f64,
    hole: f64,
    per_seed: Vec<Coverage>,
}

/// Runs 7.1.
pub fn section_7_1(ctx: &mut Ctx) -> Result<Section, BoxError> {
    let seeds: Vec<u64> = (1..=if ctx.quick { 4 } else { 10 }).collect();
    let (sets, record) = placements(&seeds)?;
    let (direction, spacing) = long_axis(&record);
    let mean_spacing = (1.0 / N as f64).sqrt();
    let mut rows: Vec<Row> = Vec::new();
    let mut json = Vec::new();
    for k in AREA_FACTORS {
        let length = k.sqrt() * spacing;
        let style = StrokeStyle {
            length,
            width: length / RATIO,
            variation: VARIATION,
        };
        let measured = sets
            .iter()
            .map(|per_seed_sets| measure(per_seed_sets, &seeds, direction, &style, mean_spacing))
            .collect::<Result<Vec<Measured>, BoxError>>()?;
        rows.extend(rows_of(k, &measured));
        json.push(factor_json(k, length, &measured, mean_spacing));
    }
    ctx.json(
        "strokes_7_1.json",
        &serde_json::json!({"n": N, "ratio": RATIO, "variation": VARIATION, "raster": RASTER,
            "seeds": seeds, "mean_spacing": mean_spacing, "stroke_direction": direction,
            "factors": json}),
    )?;
    let figures = coverage_figures(ctx, &sets, seeds[0], direction, spacing)?;
    Ok(Section {
        title: "7.1 Brush strokes (Fig. 3)".into(),
        notes: notes(seeds.len(), spacing, mean_spacing),
        rows,
        figures,
    })
}

/// One placement's strokes of `style` along `direction` on each seed's set, their
/// coverage, and its medians over the seeds.
fn measure(
    per_seed_sets: &[Vec<[f64; 2]>],
    seeds: &[u64],
    direction: [f64; 2],
    style: &StrokeStyle,
    mean_spacing: f64,
) -> Result<Measured, BoxError> {
    let per_seed = per_seed_sets
        .iter()
        .zip(seeds)
        .map(|(xy, &seed)| {
            let s = strokes::strokes_from_samples(xy, &vec![direction; N], style, seed)?;
            strokes::coverage(&s, RASTER)
        })
        .collect::<Result<Vec<Coverage>, _>>()?;
    let med = |f: fn(&Coverage) -> f64| median(&per_seed.iter().map(f).collect::<Vec<_>>());
    Ok(Measured {
        covered: med(|c| c.covered_fraction),
        overlap: med(|c| c.mean_overlap),
        hole: med(|c| c.largest_hole) / mean_spacing,
        per_seed,
    })
}

/// The JSON entry of area factor `k` (strokes `length` long): every placement's
/// medians and per-seed values.
fn factor_json(k: f64, length: f64, measured: &[Measured], mean_spacing: f64) -> serde_json::Value {
    serde_json::json!({
        "area_factor": k, "stroke_length": length, "stroke_width": length / RATIO,
        "placements": PLACEMENTS.iter().zip(measured).map(|(name, m)| serde_json::json!({
            "placement": name,
            "median_covered_fraction": m.covered,
            "median_mean_overlap": m.overlap,
            "median_largest_hole_over_spacing": m.hole,
            "covered_fraction": m.per_seed.iter().map(|c| c.covered_fraction).collect::<Vec<_>>(),
            "mean_overlap": m.per_seed.iter().map(|c| c.mean_overlap).collect::<Vec<_>>(),
            "largest_hole_over_spacing":
                m.per_seed.iter().map(|c| c.largest_hole / mean_spacing).collect::<Vec<_>>(),
        })).collect::<Vec<_>>(),
    })
}

/// The isotropic and anisotropic placements' strokes at area factor 1 for `seed`, as
/// images of strokes per pixel.
fn coverage_figures(
    ctx: &mut Ctx,
    sets: &Sets,
    seed: u64,
    direction: [f64; 2],
    spacing: f64,
) -> Result<Vec<(String, String)>, BoxError> {
    let mut figures = Vec::new();
    for (p, name) in [(0, "isotropic"), (1, "anisotropic")] {
        let style = StrokeStyle {
            length: spacing,
            width: spacing / RATIO,
            variation: VARIATION,
        };
        let s = strokes::strokes_from_samples(&sets[p][0], &vec![direction; N], &style, seed)?;
        let raster = strokes::rasterise(&s, IMAGE)?;
        let values: Vec<f64> = raster.counts.iter().map(|&c| f64::from(c)).collect();
        figures.push(ctx.figure(
            &format!("strokes_{name}.png"),
            format!(
                "{name} placement, seed 1, area factor 1: strokes per pixel (axes: the square \
                 shifted to centre 0)"
            ),
            |path| {
                plot::spectrum_image(
                    path,
                    &format!("{name}: black = hole, white = 3+ strokes"),
                    &values,
                    IMAGE,
                    0.5,
                    3.0,
                )
            },
        ));
    }
    Ok(figures)
}

/// The section's notes: the set-up and what is measured.
fn notes(seeds: usize, spacing: f64, mean_spacing: f64) -> String {
    format!(
        "Unit square, uniform field along x with spacing ratio 8:1 (density 1), N = {N} \
         samples per set, {} seeds. Each sample is drawn as an 8:1 stroke \
         (`analysis::strokes`) along the axis of the field's larger spacing (y here: \
         strata's major eigenvector is the direction of densest spacing), centred on \
         the sample; every placement gets the same strokes (sample k of seed s has \
         the same size whatever the placement), so only placement differs. Stroke \
         length = sqrt(k) x the larger expected spacing of the 8:1 field ({:.4} = \
         sqrt(8 / N)), width = length / 8, each scaled by a factor uniform in [0.75, \
         1.25]. The area factor k is the total nominal stroke area over the square's: \
         at k = 1 a perfect tiling covers the square exactly once, at k = 2 twice. \
         Placements: strata's sampler isotropic and 8:1, Bridson's Poisson disk \
         (isotropic, `analysis::poisson_disk`) and sample elimination under the 8:1 \
         field (`mesh_baseline::mesh_poisson_disk`). Measured on a {RASTER} x {RASTER} \
         raster of pixel centres: covered fraction (pixels under at least one stroke), \
         mean overlap (strokes per covered pixel) and the largest hole, the largest \
         distance from an uncovered pixel to the nearest covered one (the square's \
         border does not count as covered), over the mean spacing sqrt(area / N) = \
         {:.4}. Numbers are medians over the seeds; \"seeds\" counts the seeds where \
         anisotropic beats isotropic. The paper's claim (section 1 and Fig. 3): \
         isotropic placement shows considerable overlap and many large holes, \
         anisotropic placement covers better with the same number of points.",
        seeds, spacing, mean_spacing
    )
}

/// The rows of one area factor: one per placement, then the paper's three claims.
fn rows_of(k: f64, m: &[Measured]) -> Vec<Row> {
    let mut out: Vec<Row> = PLACEMENTS
        .iter()
        .zip(m)
        .enumerate()
        .map(|(i, (name, m))| {
            row(
                &format!("k = {k}, {name}: covered / overlap / largest hole over spacing"),
                format!("{} / {} / {:.2}", f3(m.covered), f3(m.overlap), m.hole),
                if i == 1 {
                    "better coverage, fewer holes than isotropic"
                } else {
                    ""
                },
                if i == 1 { "" } else { "reference" },
                None,
            )
        })
        .collect();
    let (iso, aniso) = (&m[0], &m[1]);
    let seeds_better = |f: &dyn Fn(&Coverage, &Coverage) -> bool| {
        let wins = iso
            .per_seed
            .iter()
            .zip(&aniso.per_seed)
            .filter(|(i, a)| f(i, a))
            .count();
        format!("{wins}/{} seeds", iso.per_seed.len())
    };
    out.push(row(
        &format!("k = {k}, covered fraction: anisotropic vs isotropic"),
        format!(
            "{} vs {} ({})",
            f3(aniso.covered),
            f3(iso.covered),
            seeds_better(&|i, a| a.covered_fraction > i.covered_fraction)
        ),
        "better coverage",
        "higher",
        Some(aniso.covered > iso.covered),
    ));
    out.push(row(
        &format!("k = {k}, mean overlap: anisotropic vs isotropic"),
        format!(
            "{} vs {} ({})",
            f3(aniso.overlap),
            f3(iso.overlap),
            seeds_better(&|i, a| a.mean_overlap < i.mean_overlap)
        ),
        "considerable overlap (isotropic)",
        "lower",
        Some(aniso.overlap < iso.overlap),
    ));
    out.push(row(
        &format!("k = {k}, largest hole over spacing: anisotropic vs isotropic"),
        format!(
            "{:.2} vs {:.2} ({})",
            aniso.hole,
            iso.hole,
            seeds_better(&|i, a| a.largest_hole < i.largest_hole)
        ),
        "many large holes (isotropic)",
        "smaller",
        Some(aniso.hole < iso.hole),
    ));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_of_odd_and_even_counts() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 3.0, 2.0]), 2.5);
    }

    #[test]
    fn strokes_lie_along_the_larger_spacing() {
        let s = Sample {
            major_axis: [1.0, 0.0, 0.0],
            spacing: [0.01, 0.08],
            ..Default::default()
        };
        assert_eq!(long_axis(&s), ([0.0, 1.0], f64::from(0.08f32)));
    }
}
