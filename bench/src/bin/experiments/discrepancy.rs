//! Section 7.2: discrepancy decay of strata (isotropic and 4:1) beside the jittered
//! grid, Poisson disk and uniform random samplers, over rectangles, origin triangles
//! and quarter discs; writes `discrepancy_7_2.json` and six log-log plots.

use glam::DVec2;
use strata_engine::analysis::{Discrepancy, DiscrepancyCurve, ShapeFamily, baseline};
use strata_systems::report::plot::{self, Series};

use crate::BoxError;
use crate::output::{Ctx, discrepancy_axes};
use crate::samplers::{sizes, unit_points, unit_square_sampler};
use crate::table::{Row, Section, f3, row};

/// A point sampler of the unit square: `(n, seed) -> n points`.
type PointSampler<'a> = Box<dyn Fn(usize, u64) -> Vec<DVec2> + Sync + 'a>;

/// The shape families, with their names in files and tables.
const FAMILIES: [(ShapeFamily, &str); 3] = [
    (ShapeFamily::Rectangles, "rectangles"),
    (ShapeFamily::OriginTriangles, "triangles"),
    (ShapeFamily::QuarterDiscs, "quarter discs"),
];

/// Index of each sampler in `curves[family][sampler]`.
const ISO: usize = 0;
const ANISO: usize = 1;
const JITTERED: usize = 2;
const POISSON: usize = 3;
const RANDOM: usize = 4;

/// Runs 7.2.
pub fn section_7_2(ctx: &mut Ctx) -> Result<Section, BoxError> {
    let ns = sizes(if ctx.quick { 2048 } else { 8192 });
    let seeds = [1u64, 2, 3];
    let iso = unit_square_sampler(1.0)?;
    let aniso = unit_square_sampler(4.0)?;
    let ours_iso = |n: usize, s: u64| unit_points(&iso.sample(n, s));
    let ours_aniso = |n: usize, s: u64| unit_points(&aniso.sample(n, s));
    let samplers: Vec<(&str, PointSampler, DVec2)> = vec![
        ("strata isotropic", Box::new(ours_iso), DVec2::ONE),
        // Spacing along x is a quarter of that along y: the metric frame scales x by 4.
        ("strata 4:1", Box::new(ours_aniso), DVec2::new(4.0, 1.0)),
        (
            "jittered grid",
            Box::new(baseline::jittered_grid),
            DVec2::ONE,
        ),
        ("Poisson disk", Box::new(baseline::poisson_disk), DVec2::ONE),
        (
            "uniform random",
            Box::new(baseline::uniform_random),
            DVec2::ONE,
        ),
    ];
    let curves = measure(ctx, &samplers, &ns, &seeds)?;
    let names: Vec<&str> = samplers.iter().map(|s| s.0).collect();
    let figures = figures(ctx, &names, &curves);
    Ok(Section {
        title: "7.2 Discrepancy".into(),
        notes: notes(&ns),
        rows: rows(&curves),
        figures,
    })
}

/// `curves[family][sampler]`, also written to `discrepancy_7_2.json`.
fn measure(
    ctx: &Ctx,
    samplers: &[(&str, PointSampler, DVec2)],
    ns: &[usize],
    seeds: &[u64],
) -> Result<Vec<Vec<DiscrepancyCurve>>, BoxError> {
    let mut curves: Vec<Vec<DiscrepancyCurve>> = Vec::new();
    let mut json = serde_json::Map::new();
    for (family, fname) in FAMILIES {
        let mut per = Vec::new();
        for (name, sampler, scale) in samplers {
            let d = Discrepancy::new(family).with_axis_scale(*scale);
            let c = DiscrepancyCurve::measure(&d, sampler, ns, seeds)?;
            json.insert(
                format!("{fname} / {name}"),
                serde_json::json!({"n": c.ns, "sup": c.sup, "l2": c.l2,
                    "sup_slope": c.sup_slope(), "l2_slope": c.l2_slope()}),
            );
            per.push(c);
        }
        curves.push(per);
    }
    ctx.json("discrepancy_7_2.json", &serde_json::Value::Object(json))?;
    Ok(curves)
}

/// Sup and L2 discrepancy against N per family, one line per sampler.
fn figures(
    ctx: &mut Ctx,
    names: &[&str],
    curves: &[Vec<DiscrepancyCurve>],
) -> Vec<(String, String)> {
    let mut figures = Vec::new();
    for (fi, (_, fname)) in FAMILIES.iter().enumerate() {
        for (measure, pick) in [("sup", 0), ("L2", 1)] {
            let series: Vec<Series> = names
                .iter()
                .zip(&curves[fi])
                .map(|(name, c)| {
                    let (vals, slope) = if pick == 0 {
                        (c.sup.clone(), c.sup_slope())
                    } else {
                        (c.l2.clone(), c.l2_slope())
                    };
                    Series::line(format!("{name} ({slope:.2})"), c.ns_f64(), vals).with_markers()
                })
                .collect();
            let file = format!(
                "discrepancy_{}_{}.png",
                fname.replace(' ', "_"),
                measure.to_lowercase()
            );
            let axes = discrepancy_axes(format!("{measure} discrepancy, {fname} (fitted slopes)"));
            figures.push(
                ctx.figure(&file, format!("{measure} discrepancy over {fname}"), |p| {
                    plot::line_chart(p, &axes, &series)
                }),
            );
        }
    }
    figures
}

/// The paper's slopes, strata against the jittered grid and Poisson disk, and the
/// baselines' slopes for reference.
fn rows(curves: &[Vec<DiscrepancyCurve>]) -> Vec<Row> {
    let slope = |fi: usize, si: usize, sup: bool| {
        if sup {
            curves[fi][si].sup_slope()
        } else {
            curves[fi][si].l2_slope()
        }
    };
    let mut rows = Vec::new();
    let (iso_l2, an_l2) = (slope(0, ISO, false), slope(0, ANISO, false));
    rows.push(row(
        "L2 slope, rectangles, isotropic",
        f3(iso_l2),
        "0.74",
        ">= 0.74",
        Some(iso_l2 >= 0.74),
    ));
    rows.push(row(
        "L2 slope, rectangles, 4:1",
        f3(an_l2),
        "0.72",
        ">= 0.72",
        Some(an_l2 >= 0.72),
    ));
    let jit_sup = slope(0, JITTERED, true);
    for (si, label) in [(ISO, "isotropic"), (ANISO, "4:1")] {
        let s = slope(0, si, true);
        rows.push(row(
            &format!("sup slope, rectangles, {label}"),
            f3(s),
            "",
            &format!(">= jittered grid ({jit_sup:.3})"),
            Some(s >= jit_sup - 0.005),
        ));
    }
    for (fi, (_, fname)) in FAMILIES.iter().enumerate() {
        let pd = slope(fi, POISSON, true);
        for (si, label) in [(ISO, "isotropic"), (ANISO, "4:1")] {
            let s = slope(fi, si, true);
            rows.push(row(
                &format!("sup slope, {fname}, {label}"),
                f3(s),
                "steeper than Poisson disk (Table 2)",
                &format!("> Poisson disk ({pd:.3})"),
                Some(s > pd),
            ));
        }
        for (si, name) in [
            (JITTERED, "jittered grid"),
            (POISSON, "Poisson disk"),
            (RANDOM, "uniform random"),
        ] {
            rows.push(row(
                &format!("sup / L2 slope, {fname}, {name}"),
                format!("{:.3} / {:.3}", slope(fi, si, true), slope(fi, si, false)),
                "",
                "reference",
                None,
            ));
        }
        rows.push(row(
            &format!("L2 slope, {fname}, strata isotropic / 4:1"),
            format!(
                "{:.3} / {:.3}",
                slope(fi, ISO, false),
                slope(fi, ANISO, false)
            ),
            "",
            "reference",
            None,
        ));
    }
    rows
}

fn notes(ns: &[usize]) -> String {
    format!(
        "N = 2^l and 2^l + 2^(l-1), {} to {}, 3 seeds each (as the paper). Sup: exact \
         supremum over the family's critical shapes. L2: root mean square over the \
         family's parameters (rectangles: Warnock's exact formula; quarter discs: exact; \
         triangles: 512 jittered strata in one leg, exact in the other, within 1% of exact). \
         Triangles have one vertex at the origin and legs along the axes \
         `(0,0), (a,0), (0,b)`; quarter discs are centred at the origin. The 4:1 sampling \
         has x spacing a quarter of y spacing; boxes and triangles are invariant under \
         its axis-aligned metric, quarter discs are taken in the metric (quarter ellipses). \
         Slopes are least-squares slopes of log discrepancy against log N.",
        ns[0],
        ns[ns.len() - 1]
    )
}
