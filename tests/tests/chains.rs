//! Section 7.3.3: many segments sampled sparsely. Linking neighbouring segments into
//! chains (section 6.2) keeps the discrepancy down where independent segments raise it.

use std::sync::Arc;

use glam::DVec2;
use strata_engine::analysis::{star_discrepancy_l2, star_discrepancy_sup};
use strata_engine::curve::{CurveDomain, CurveOptions, SegmentCurve};
use strata_engine::fixtures::isotropic_on;
use strata_engine::mesh::shapes;
use strata_engine::sample::{Sample, Sampler, SegmentSampling};

/// The unit square (a `4k x 4k` quad plane) cut into `k x k` square segments, each
/// parameterized by its own translation and scale into the unit square.
fn blocks(k: u32) -> Sampler {
    let res = 4 * k;
    let mesh = Arc::new(shapes::plane(1.0, res).expect("plane"));
    let field = Arc::new(isotropic_on(&mesh));
    let mut groups: Vec<Vec<u32>> = vec![Vec::new(); (k * k) as usize];
    for (f, t) in mesh.triangles().iter().enumerate() {
        let c = t
            .iter()
            .map(|&v| mesh.positions()[v as usize])
            .sum::<glam::DVec3>()
            / 3.0;
        let (i, j) = (
            ((c.x * k as f64) as u32).min(k - 1),
            ((c.y * k as f64) as u32).min(k - 1),
        );
        groups[(j * k + i) as usize].push(f as u32);
    }
    let options = CurveOptions {
        max_cell_share: 1.0 / 256.0,
        boundary_level: 4,
        ..Default::default()
    };
    let segments = groups
        .iter()
        .enumerate()
        .map(|(id, faces)| {
            let (i, j) = ((id as u32 % k) as f64, (id as u32 / k) as f64);
            let mut local = std::collections::HashMap::new();
            let mut uv = Vec::new();
            let tris: Vec<[u32; 3]> = faces
                .iter()
                .map(|&f| {
                    mesh.triangles()[f as usize].map(|v| {
                        *local.entry(v).or_insert_with(|| {
                            let p = mesh.positions()[v as usize];
                            uv.push(
                                DVec2::new(p.x * k as f64 - i, p.y * k as f64 - j)
                                    .clamp(DVec2::ZERO, DVec2::ONE),
                            );
                            uv.len() as u32 - 1
                        })
                    })
                })
                .collect();
            // Uniform density 1 on the surface: per unit of parameter area, 1 / k^2.
            let density = vec![[1.0 / (k * k) as f64; 3]; tris.len()];
            let curve = SegmentCurve::build(
                &CurveDomain {
                    uv: &uv,
                    triangles: &tris,
                    corner_density: &density,
                },
                &options,
            )
            .expect("cells");
            SegmentSampling {
                segment: id as u32,
                faces: faces.clone(),
                curve: std::sync::Arc::new(curve),
            }
        })
        .collect();
    Sampler::new(mesh, field, segments).expect("sampler")
}

fn points(s: &[Sample]) -> Vec<DVec2> {
    s.iter()
        .map(|s| {
            DVec2::new(s.position[0] as f64, s.position[1] as f64)
                .clamp(DVec2::ZERO, DVec2::splat(1.0 - 1e-9))
        })
        .collect()
}

#[test]
fn chains_link_neighbours_and_cover_every_segment_once() {
    let sampler = blocks(12);
    let chains = sampler.chains();
    let mut seen = vec![false; sampler.segments().len()];
    for c in &chains {
        for &s in *c {
            assert!(!seen[s as usize], "segment {s} in two chains");
            seen[s as usize] = true;
        }
        // Consecutive segments in a chain are grid neighbours.
        for w in c.windows(2) {
            let (a, b) = (w[0] as i64, w[1] as i64);
            let d = ((a % 12) - (b % 12)).abs() + ((a / 12) - (b / 12)).abs();
            assert_eq!(d, 1, "{a} -> {b} are not neighbours");
        }
    }
    assert!(seen.iter().all(|&s| s));
    assert!(
        chains.len() < sampler.segments().len() / 4,
        "{} chains for 144 segments",
        chains.len()
    );
    assert!(sampler.uses_chains(400) && !sampler.uses_chains(1000));
}

#[test]
fn section_7_3_3_linking_reduces_the_quantization_error() {
    // 400 segments, 1000 samples: t / N = 0.4 >= 1/3.
    let sampler = blocks(20);
    let n = 1000;
    let (mut linked, mut independent) = ((0.0, 0.0), (0.0, 0.0));
    let seeds = 8;
    for seed in 0..seeds {
        let mut buf = vec![Sample::default(); n];
        sampler.sample_into_linked(seed, &mut buf, true);
        let p = points(&buf);
        linked.0 += star_discrepancy_l2(&p) / seeds as f64;
        linked.1 += star_discrepancy_sup(&p) / seeds as f64;
        sampler.sample_into_linked(seed, &mut buf, false);
        let p = points(&buf);
        independent.0 += star_discrepancy_l2(&p) / seeds as f64;
        independent.1 += star_discrepancy_sup(&p) / seeds as f64;
    }
    let random: f64 = (0..seeds)
        .map(|s| star_discrepancy_l2(&strata_engine::analysis::baseline::uniform_random(n, s)))
        .sum::<f64>()
        / seeds as f64;
    println!(
        "L2 / sup discrepancy: linked {linked:?}, independent {independent:?}, random L2 {random}"
    );
    assert!(
        linked.0 < independent.0,
        "L2: linked {} vs independent {}",
        linked.0,
        independent.0
    );
    assert!(linked.0 < 0.5 * random);
}

/// Chains handed back to `Sampler::with_chains` give the same samples as linking them
/// anew; chains that miss or repeat a segment are refused.
#[test]
fn given_chains_reproduce_linked_sampling_and_bad_chains_are_refused() {
    let sampler = blocks(8);
    let chains: Vec<Vec<u32>> = sampler.chains().iter().map(|c| c.to_vec()).collect();
    assert!(chains.iter().map(Vec::len).sum::<usize>() == 64 && chains[0].len() > 1);
    let rebuilt = Sampler::with_chains(
        sampler.mesh().clone(),
        sampler.field().clone(),
        sampler.segments().to_vec(),
        &chains,
    )
    .expect("same chains");
    for n in [100usize, 150, 5000] {
        assert_eq!(rebuilt.uses_chains(n), sampler.uses_chains(n));
        assert!(rebuilt.sample(n, 3) == sampler.sample(n, 3), "n {n}");
    }
    let mut missing = chains.clone();
    let dropped = missing[0].pop().expect("non-empty chain");
    let mut repeated = chains.clone();
    repeated[0].push(chains[0][0]);
    for (bad, segment) in [(missing, dropped), (repeated, chains[0][0])] {
        match Sampler::with_chains(
            sampler.mesh().clone(),
            sampler.field().clone(),
            sampler.segments().to_vec(),
            &bad,
        ) {
            Err(strata_engine::sample::SampleError::BadChains { segment: s, .. }) => {
                assert_eq!(s, segment)
            }
            other => panic!("expected BadChains, got {:?}", other.map(|_| ())),
        }
    }
}
