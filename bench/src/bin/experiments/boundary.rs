//! Section 7.3.2: boundary error. The unit square cut into two segments along a wave,
//! against the same square as one segment and two straight cuts, with the strata's
//! count variance explaining the difference; writes `boundary_7_3_2.json`, a segment
//! map and the discrepancy curves.

use std::sync::Arc;

use glam::{DVec2, DVec3};
use strata_engine::analysis::seed_ratio::jackknife_ratio;
use strata_engine::analysis::strata::{StrataVariance, strata_variance};
use strata_engine::analysis::{Discrepancy, DiscrepancyCurve, baseline};
use strata_engine::mesh::{TriMesh, shapes};
use strata_engine::sample::Sampler;
use strata_engine::surface::{Preprocessed, SurfaceOptions, segmentation_from_labels};
use strata_systems::report::plot::{self, Series};

use crate::BoxError;
use crate::output::{Ctx, discrepancy_axes};
use crate::samplers::{constant_field, sizes, unit_points};
use crate::table::{Row, Section, row};

/// The complex boundary: a wave with two frequencies and a deep fold.
fn boundary(x: f64) -> f64 {
    0.5 + 0.22 * (2.0 * std::f64::consts::PI * 2.0 * x).sin()
        + 0.08 * (2.0 * std::f64::consts::PI * 7.0 * x).sin()
}

/// Face labels 0 / 1 below / above `boundary(x)` (by face centroid), with triangles cut
/// off from their side (joined by a vertex only, where the boundary is steep) moved to
/// the other side, so that there are exactly two segments.
fn labels_below(mesh: &TriMesh, boundary: impl Fn(f64) -> f64) -> Vec<u32> {
    let mut two: Vec<u32> = (0..mesh.face_count() as u32)
        .map(|f| {
            let c = mesh.face_positions(f).iter().sum::<DVec3>() / 3.0;
            (c.y > boundary(c.x)) as u32
        })
        .collect();
    for _ in 0..4 {
        let seg = segmentation_from_labels(mesh, &two);
        if seg.segments.len() <= 2 {
            break;
        }
        let mut order: Vec<usize> = (0..seg.segments.len()).collect();
        order.sort_by_key(|&i| std::cmp::Reverse(seg.segments[i].faces.len()));
        for &i in &order[2..] {
            for &f in &seg.segments[i].faces {
                two[f as usize] = 1 - two[f as usize];
            }
        }
    }
    two
}

/// Box discrepancies of `sampler` per seed: `(l2[seed][n], sup[seed][n])`.
type PerSeed = (Vec<Vec<f64>>, Vec<Vec<f64>>);

fn per_seed_discrepancy(
    sampler: &Sampler,
    ns: &[usize],
    seeds: &[u64],
) -> Result<PerSeed, BoxError> {
    let d = Discrepancy::default();
    let mut l2 = Vec::new();
    let mut sup = Vec::new();
    for &seed in seeds {
        let c =
            DiscrepancyCurve::measure(&d, |n, s| unit_points(&sampler.sample(n, s)), ns, &[seed])?;
        l2.push(c.l2);
        sup.push(c.sup);
    }
    Ok((l2, sup))
}

/// The four segmentations of the square, through the surface pipeline.
struct Cuts {
    /// Two segments along [`boundary`]; `labels` are its face labels.
    two: Preprocessed,
    labels: Vec<u32>,
    /// The whole square as one segment.
    one: Preprocessed,
    /// Straight cuts along y = 0.5 and y = 0.4.
    half: Preprocessed,
    at_04: Preprocessed,
    mesh: Arc<TriMesh>,
}

fn cuts() -> Result<Cuts, BoxError> {
    let mesh = Arc::new(shapes::plane(1.0, 64)?);
    let field = Arc::new(constant_field(&mesh, 1.0)?);
    let labels = labels_below(&mesh, boundary);
    let options = SurfaceOptions::default();
    let build = |labels: &[u32]| {
        Preprocessed::from_segmentation(
            mesh.clone(),
            field.clone(),
            segmentation_from_labels(&mesh, labels),
            &options,
        )
    };
    let two = build(&labels)?;
    let one = build(&vec![0; mesh.face_count()])?;
    // Controls: straight cuts along y = 0.5 (each half is two quadrants of the curve's
    // square) and y = 0.4 (not aligned with the quadrants).
    let half = build(&labels_below(&mesh, |_| 0.5))?;
    let at_04 = build(&labels_below(&mesh, |_| 0.4))?;
    Ok(Cuts {
        two,
        labels,
        one,
        half,
        at_04,
        mesh,
    })
}

/// A ratio to the single segment and its jackknife standard error.
type Ratio = (f64, f64);

/// The discrepancy measurements of 7.3.2.
struct Measured {
    ns: Vec<usize>,
    seeds: usize,
    /// Seed means, one segment and two.
    one: DiscrepancyCurve,
    two: DiscrepancyCurve,
    l2: Ratio,
    sup: Ratio,
    /// L2 at N = 2^l and at N = 1.5 2^l.
    l2_pow2: Ratio,
    l2_other: Ratio,
    /// L2 of the straight cuts y = 0.5 and y = 0.4.
    half: Ratio,
    at_04: Ratio,
}

fn measure(cuts: &Cuts, quick: bool) -> Result<Measured, BoxError> {
    let ns = sizes(if quick { 2048 } else { 4096 });
    let seeds: Vec<u64> = (1..=if quick { 4 } else { 32 }).collect();
    let (one_l2, one_sup) = per_seed_discrepancy(&cuts.one.sampler, &ns, &seeds)?;
    let (two_l2, two_sup) = per_seed_discrepancy(&cuts.two.sampler, &ns, &seeds)?;
    let (half_l2, _) = per_seed_discrepancy(&cuts.half.sampler, &ns, &seeds)?;
    let (l04_l2, _) = per_seed_discrepancy(&cuts.at_04.sampler, &ns, &seeds)?;
    let all = |_: usize| true;
    // ns alternates 2^l, 2^l + 2^(l-1).
    let pow2 = |i: usize| i.is_multiple_of(2);
    let other = |i: usize| i % 2 == 1;
    let seed_mean = |x: &[Vec<f64>]| -> Vec<f64> {
        (0..ns.len())
            .map(|i| x.iter().map(|s| s[i]).sum::<f64>() / x.len() as f64)
            .collect()
    };
    Ok(Measured {
        seeds: seeds.len(),
        l2: jackknife_ratio(&two_l2, &one_l2, all),
        sup: jackknife_ratio(&two_sup, &one_sup, all),
        l2_pow2: jackknife_ratio(&two_l2, &one_l2, pow2),
        l2_other: jackknife_ratio(&two_l2, &one_l2, other),
        half: jackknife_ratio(&half_l2, &one_l2, all),
        at_04: jackknife_ratio(&l04_l2, &one_l2, all),
        one: DiscrepancyCurve {
            ns: ns.clone(),
            sup: seed_mean(&one_sup),
            l2: seed_mean(&one_l2),
        },
        two: DiscrepancyCurve {
            ns: ns.clone(),
            sup: seed_mean(&two_sup),
            l2: seed_mean(&two_l2),
        },
        ns,
    })
}

/// Where the excess comes from: the strata's count variance by class, one segment and
/// two, at N = 1024 and 1536, over 2000 random origin-anchored boxes.
fn attribution(cuts: &Cuts) -> Result<Vec<(usize, StrataVariance, StrataVariance)>, BoxError> {
    let boxes: Vec<DVec2> = baseline::uniform_random(2000, 77);
    let no_seam = |_: DVec2| false;
    let mut attribution = Vec::new();
    for n in [1024usize, 1536] {
        let seam_n = |p: DVec2| (p.y - boundary(p.x)).abs() < 1.5 / (n as f64).sqrt();
        let a = strata_variance(&cuts.one.sampler, n, &boxes, &no_seam)?;
        let b = strata_variance(&cuts.two.sampler, n, &boxes, &seam_n)?;
        attribution.push((n, a, b));
    }
    Ok(attribution)
}

/// Table rows and JSON entries of the attribution.
fn attribution_rows(
    attribution: &[(usize, StrataVariance, StrataVariance)],
) -> (Vec<Row>, Vec<serde_json::Value>) {
    let mut rows = Vec::new();
    let mut json = Vec::new();
    for (n, a, b) in attribution {
        let classes = b.classes();
        // Excess of each class over what as many single-segment strata carry.
        let per = a.total / *n as f64;
        let excess: Vec<f64> = classes
            .iter()
            .map(|c| c.variance - c.strata as f64 * per)
            .collect();
        let total_excess = b.total - a.total;
        rows.push(row(
            &format!(
                "N = {n}: strata count variance two / one segment; excess from strata straddling a curve jump / touching the seam / elsewhere"
            ),
            format!(
                "{:.3} (sqrt {:.3}); {} strata {:.0}% / {} strata {:.0}% / {} strata {:.0}%",
                b.total / a.total,
                (b.total / a.total).sqrt(),
                classes[0].strata,
                100.0 * excess[0] / total_excess,
                classes[1].strata,
                100.0 * excess[1] / total_excess,
                classes[2].strata,
                100.0 * excess[2] / total_excess,
            ),
            "",
            "",
            None,
        ));
        json.push(
            serde_json::json!({"n": n, "one_total": a.total, "two_total": b.total,
            "classes": ["straddling a jump", "touching the seam", "elsewhere"],
            "two_counts": classes.iter().map(|c| c.strata).collect::<Vec<_>>(),
            "two_variance": classes.iter().map(|c| c.variance).collect::<Vec<_>>()}),
        );
    }
    (rows, json)
}

/// Runs 7.3.2.
pub fn section_7_3_2(ctx: &mut Ctx) -> Result<Section, BoxError> {
    let cuts = cuts()?;
    let m = measure(&cuts, ctx.quick)?;
    let (attribution_rows, attribution_json) = attribution_rows(&attribution(&cuts)?);
    let two = &cuts.two;
    ctx.json(
        "boundary_7_3_2.json",
        &serde_json::json!({"n": m.ns, "seeds": m.seeds, "one_segment": {"sup": m.one.sup, "l2": m.one.l2},
            "two_segments": {"sup": m.two.sup, "l2": m.two.l2, "segments": two.params.len(),
                "splits": two.report.splits, "isotropic_segments": two.report.isotropic_segments,
                "single_face_segments": two.report.single_face_segments},
            "geometric_mean_ratio_l2": m.l2.0, "standard_error_l2": m.l2.1,
            "geometric_mean_ratio_sup": m.sup.0, "standard_error_sup": m.sup.1,
            "ratio_l2_n_power_of_two": m.l2_pow2.0, "ratio_l2_n_three_halves_power_of_two": m.l2_other.0,
            "control_cut_y_0_5_ratio_l2": m.half.0, "control_cut_y_0_4_ratio_l2": m.at_04.0,
            "strata_variance": attribution_json}),
    )?;
    let figures = figures(ctx, &cuts, &m);
    Ok(Section {
        title: "7.3.2 Boundary error".into(),
        notes: notes(two.params.len(), &m),
        rows: [ratio_rows(&m), attribution_rows, vec![slope_row(&m)]]
            .into_iter()
            .flatten()
            .collect(),
        figures,
    })
}

/// The two-segment ratios and the controls.
fn ratio_rows(m: &Measured) -> Vec<Row> {
    let ((r_l2, se_l2), (r_sup, se_sup)) = (m.l2, m.sup);
    let ((r_pow2, se_pow2), (r_other, se_other)) = (m.l2_pow2, m.l2_other);
    let ((r_half, se_half), (r_04, se_04)) = (m.half, m.at_04);
    vec![
        row(
            "L2 ratio two / one segment (+- standard error)",
            format!("{r_l2:.3} +- {se_l2:.3}"),
            "not worse",
            "within 5% (<= 1.05)",
            Some(r_l2 <= 1.05),
        ),
        row(
            "sup ratio two / one segment (+- standard error)",
            format!("{r_sup:.3} +- {se_sup:.3}"),
            "not worse",
            "within 5% (<= 1.05)",
            Some(r_sup <= 1.05),
        ),
        row(
            "L2 ratio at N = 2^l / at N = 1.5 2^l",
            format!("{r_pow2:.3} +- {se_pow2:.3} / {r_other:.3} +- {se_other:.3}"),
            "",
            "",
            None,
        ),
        row(
            "control: straight cut y = 0.5 / y = 0.4, L2 ratio to one segment",
            format!("{r_half:.3} +- {se_half:.3} / {r_04:.3} +- {se_04:.3}"),
            "",
            "",
            None,
        ),
    ]
}

fn slope_row(m: &Measured) -> Row {
    row(
        "L2 slope one / two segments",
        format!("{:.3} / {:.3}", m.one.l2_slope(), m.two.l2_slope()),
        "",
        "",
        None,
    )
}

/// The segment map and the four discrepancy curves.
fn figures(ctx: &mut Ctx, cuts: &Cuts, m: &Measured) -> Vec<(String, String)> {
    let labels: Vec<f64> = cuts.labels.iter().map(|&l| l as f64).collect();
    let f1 = ctx.figure("boundary_segments.png", "segments", |p| {
        plot::face_map(
            p,
            "two segments along a complex boundary",
            &cuts.mesh,
            &labels,
            1.0,
        )
    });
    let (one, two) = (&m.one, &m.two);
    let series = vec![
        Series::line(
            format!("one segment, L2 ({:.2})", one.l2_slope()),
            one.ns_f64(),
            one.l2.clone(),
        )
        .with_markers(),
        Series::line(
            format!("two segments, L2 ({:.2})", two.l2_slope()),
            two.ns_f64(),
            two.l2.clone(),
        )
        .with_markers(),
        Series::line(
            format!("one segment, sup ({:.2})", one.sup_slope()),
            one.ns_f64(),
            one.sup.clone(),
        )
        .with_markers(),
        Series::line(
            format!("two segments, sup ({:.2})", two.sup_slope()),
            two.ns_f64(),
            two.sup.clone(),
        )
        .with_markers(),
    ];
    let axes = discrepancy_axes("discrepancy with and without a segment boundary".into());
    let f2 = ctx.figure("boundary_discrepancy.png", "discrepancy curves", |p| {
        plot::line_chart(p, &axes, &series)
    });
    vec![f1, f2]
}

fn notes(segments: usize, m: &Measured) -> String {
    format!(
        "Unit square (64 x 64 quads), constant isotropic field, cut into two segments along \
         y = 0.5 + 0.22 sin(4 pi x) + 0.08 sin(14 pi x) ({} segments after \
         parameterization), against the same mesh as one segment, both through the surface \
         pipeline (`Preprocessed::from_segmentation`). Box discrepancy, N = {} to {}, {} \
         seeds; the ratio is the geometric mean over N of the ratio of the seed means, \
         two-segment / one-segment, +- its jackknife standard error over the seeds \
         (`analysis::seed_ratio`). \
         Why it is above 5%: the single segment is the whole square of its curve, so at \
         N = 4^k its 1D strata are the curve's square cells (a jittered grid) and at \
         N = 2 4^k pairs of them, while a segment bounded by the wave fills its square \
         only in part, so its strata are unaligned curve intervals at every N; and where \
         the curve leaves a segment and re-enters it elsewhere, the stratum across the \
         jump is two distant pieces sharing one sample. The rows below separate the \
         two: the ratio at N = 2^l (single segment aligned) and at N = 1.5 2^l (not \
         aligned); two straight cuts, y = 0.5 (each half is two quadrants of its curve's \
         square: strata stay aligned) and y = 0.4 (unaligned, few jumps); and, at \
         N = 1024 and 1536, the count variance of the strata over origin-anchored boxes \
         (independent jitter: sum over strata of E[p (1 - p)], p the share of the \
         stratum in the box; its square root tracks the L2 ratio; `analysis::strata`) split \
         into strata \
         straddling a jump of the curve (extent above three stratum sizes), strata \
         within 1.5 stratum sizes of the seam, and the rest, each class's excess being \
         its variance minus that of as many single-segment strata. The remainders \
         between the two segments are not a cause: counts are exact (each side has half \
         the measure), and the y = 0.5 cut, which has the same remainders, matches the \
         single segment. Tried without success (numbers in the commit history): \
         restarting the strata at the curve's jumps, reordering the curve's runs, \
         rotating or shifting each segment's layout in its square.",
        segments,
        m.ns[0],
        m.ns[m.ns.len() - 1],
        m.seeds
    )
}
