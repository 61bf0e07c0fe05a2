//! Section 7.3.3: quantization error. The 7.3.1 field on the unit square cut into more
//! and more segments (a Voronoi partition, square blocks), sampled with chains and with
//! independent segments; writes `quantization_7_3_3.json` and a plot against the
//! segment count.

use std::sync::Arc;

use glam::{DVec2, DVec3};
use rayon::prelude::*;
use strata_engine::analysis::{Discrepancy, baseline};
use strata_engine::field::TensorField;
use strata_engine::mesh::{TriMesh, shapes};
use strata_engine::sample::Sample;
use strata_engine::surface::{Preprocessed, SurfaceOptions, segmentation_from_labels};
use strata_systems::report::plot::{self, Axes, Series};

use crate::BoxError;
use crate::output::Ctx;
use crate::samplers::{accelerating_field, unit_points};
use crate::table::{Row, Section, f3, row};

/// Labels of a Voronoi partition of the faces into `t` cells around seeded random
/// sites (distances between face centroids and sites).
fn voronoi_labels(mesh: &TriMesh, t: usize, seed: u64) -> Vec<u32> {
    let sites = baseline::uniform_random(t, seed);
    (0..mesh.face_count() as u32)
        .map(|f| {
            let c = mesh.face_positions(f).iter().sum::<DVec3>() / 3.0;
            let c = DVec2::new(c.x, c.y);
            sites
                .iter()
                .enumerate()
                .min_by(|a, b| a.1.distance_squared(c).total_cmp(&b.1.distance_squared(c)))
                .map_or(0, |(i, _)| i as u32)
        })
        .collect()
}

/// Labels of `k x k` square blocks of the unit square (face centroids).
fn block_labels(mesh: &TriMesh, k: usize) -> Vec<u32> {
    (0..mesh.face_count() as u32)
        .map(|f| {
            let c = mesh.face_positions(f).iter().sum::<DVec3>() / 3.0;
            let i = ((c.x * k as f64) as usize).min(k - 1);
            let j = ((c.y * k as f64) as usize).min(k - 1);
            (j * k + i) as u32
        })
        .collect()
}

/// One segmentation of 7.3.3: requested count, final segments, chains, and the mean
/// L2 / sup discrepancy linked and independent.
struct Quantization {
    requested: usize,
    segments: usize,
    chains: usize,
    linked_l2: f64,
    linked_sup: f64,
    independent_l2: f64,
    independent_sup: f64,
}

fn quantization(
    mesh: &Arc<TriMesh>,
    field: &Arc<TensorField>,
    labels: &[u32],
    requested: usize,
    n: usize,
    seeds: &[u64],
) -> Result<Quantization, BoxError> {
    let options = SurfaceOptions {
        min_segment_faces: 4,
        ..Default::default()
    };
    let pre = Preprocessed::from_segmentation(
        mesh.clone(),
        field.clone(),
        segmentation_from_labels(mesh, labels),
        &options,
    )?;
    let runs: Vec<[f64; 4]> = seeds
        .par_iter()
        .map(|&s| {
            let d = Discrepancy::default();
            let mut buf = vec![Sample::default(); n];
            pre.sampler.sample_into_linked(s, &mut buf, true);
            let p = unit_points(&buf);
            let (ll2, lsup) = (d.l2(&p), d.sup(&p));
            pre.sampler.sample_into_linked(s, &mut buf, false);
            let p = unit_points(&buf);
            [ll2, lsup, d.l2(&p), d.sup(&p)]
        })
        .collect();
    let mean = |k: usize| runs.iter().map(|r| r[k]).sum::<f64>() / runs.len() as f64;
    Ok(Quantization {
        requested,
        segments: pre.params.len(),
        chains: pre.sampler.chains().len(),
        linked_l2: mean(0),
        linked_sup: mean(1),
        independent_l2: mean(2),
        independent_sup: mean(3),
    })
}

/// Runs 7.3.3.
pub fn section_7_3_3(ctx: &mut Ctx) -> Result<Section, BoxError> {
    let res = 96;
    let mesh = Arc::new(shapes::plane(1.0, res)?);
    let field = Arc::new(accelerating_field(&mesh)?);
    let n = 1000;
    let seeds: Vec<u64> = (1..=if ctx.quick { 4 } else { 8 }).collect();
    let voronoi_counts: Vec<usize> = if ctx.quick {
        vec![25, 100, 400, 1000]
    } else {
        vec![25, 50, 100, 200, 300, 400, 600, 800, 1000]
    };
    let block_sides: Vec<usize> = if ctx.quick {
        vec![5, 10, 20, 32]
    } else {
        vec![5, 7, 10, 14, 17, 20, 25, 32]
    };
    let mut voronoi = Vec::new();
    for &t in &voronoi_counts {
        voronoi.push(quantization(
            &mesh,
            &field,
            &voronoi_labels(&mesh, t, 77),
            t,
            n,
            &seeds,
        )?);
    }
    let mut blocks = Vec::new();
    for &k in &block_sides {
        blocks.push(quantization(
            &mesh,
            &field,
            &block_labels(&mesh, k),
            k * k,
            n,
            &seeds,
        )?);
    }
    let random_l2 = seeds
        .iter()
        .map(|&s| Discrepancy::default().l2(&baseline::uniform_random(n, s)))
        .sum::<f64>()
        / seeds.len() as f64;
    let to_json = |rows: &[Quantization]| -> Vec<serde_json::Value> {
        rows.iter()
            .map(|q| {
                serde_json::json!({"requested": q.requested, "segments": q.segments,
                    "chains": q.chains, "linked_l2": q.linked_l2, "linked_sup": q.linked_sup,
                    "independent_l2": q.independent_l2, "independent_sup": q.independent_sup})
            })
            .collect()
    };
    ctx.json(
        "quantization_7_3_3.json",
        &serde_json::json!({"n": n, "voronoi": to_json(&voronoi), "blocks": to_json(&blocks),
            "random_l2": random_l2}),
    )?;
    let fig = figure(ctx, n, &voronoi, &blocks, random_l2);
    Ok(Section {
        title: "7.3.3 Quantization error".into(),
        notes: format!(
            "{n} samples on the unit square ({res} x {res} quads) with the 7.3.1 field, cut into (a) a Voronoi partition of 25 to 1000 random sites and (b) k x k square blocks, k = 5 to 32 (the paper varied gamma to get 25 to 1000 segments; a partition fixes the count directly), then parameterized (invalid segments split, so the final count can be higher). Each segmentation is sampled with chains (`sample_into_linked(.., true)`) and with independent segments; box L2 discrepancy, mean of {} seeds. Independent segments still get `floor(N share + carried remainder)` samples in segment order (section 6.2), which already limits the quantization error when consecutive segments are neighbours.",
            seeds.len()
        ),
        rows: rows(&voronoi, &blocks, random_l2),
        figures: vec![fig],
    })
}

/// L2 discrepancy against the final segment count, linked and independent.
fn figure(
    ctx: &mut Ctx,
    n: usize,
    voronoi: &[Quantization],
    blocks: &[Quantization],
    random_l2: f64,
) -> (String, String) {
    let xs = |rows: &[Quantization]| rows.iter().map(|q| q.segments as f64).collect::<Vec<_>>();
    let series = vec![
        Series::line(
            "Voronoi, linked",
            xs(voronoi),
            voronoi.iter().map(|q| q.linked_l2).collect(),
        )
        .with_markers(),
        Series::line(
            "Voronoi, independent",
            xs(voronoi),
            voronoi.iter().map(|q| q.independent_l2).collect(),
        )
        .with_markers(),
        Series::line(
            "blocks, linked",
            xs(blocks),
            blocks.iter().map(|q| q.linked_l2).collect(),
        )
        .with_markers(),
        Series::line(
            "blocks, independent",
            xs(blocks),
            blocks.iter().map(|q| q.independent_l2).collect(),
        )
        .with_markers(),
    ];
    let axes = Axes {
        title: format!("L2 discrepancy of {n} samples vs segments (random: {random_l2:.4})"),
        x_label: "segments".into(),
        y_label: "L2 box discrepancy".into(),
        ..Default::default()
    };
    ctx.figure(
        "quantization_segments.png",
        "discrepancy against segment count",
        |p| plot::line_chart(p, &axes, &series),
    )
}

/// Per segmentation, linked against the coarsest; whether independent segments get
/// worse; uniform random for reference.
fn rows(voronoi: &[Quantization], blocks: &[Quantization], random_l2: f64) -> Vec<Row> {
    let mut rows = Vec::new();
    for (kind, table) in [("Voronoi", voronoi), ("blocks", blocks)] {
        let base = &table[0];
        for q in table.iter() {
            rows.push(row(
                &format!(
                    "{kind}: {} requested -> {} segments ({} chains): L2 linked / independent",
                    q.requested, q.segments, q.chains
                ),
                format!("{:.5} / {:.5}", q.linked_l2, q.independent_l2),
                "",
                &format!("linked <= 1.1 x {:.5}", base.linked_l2),
                Some(q.linked_l2 <= 1.1 * base.linked_l2),
            ));
        }
        let last = &table[table.len() - 1];
        rows.push(row(
            &format!(
                "{kind}: independent L2 at {} / at {} segments",
                last.segments, base.segments
            ),
            f3(last.independent_l2 / base.independent_l2),
            "rises above ~300 segments",
            "> 1 (rises)",
            Some(last.independent_l2 > base.independent_l2),
        ));
    }
    rows.push(row(
        "uniform random L2",
        format!("{random_l2:.5}"),
        "",
        "reference",
        None,
    ));
    rows
}
