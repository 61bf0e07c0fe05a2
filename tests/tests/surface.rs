//! Surface preprocessing and sampling end to end (segmentation, parameterization with
//! splitting, cells, samples) on built-in shapes and the shared meshes.

use std::sync::Arc;

use strata_engine::field::FieldSpec;
use strata_engine::fixtures::{constant, isotropic, oblique};
use strata_engine::mesh::{TriMesh, shapes};
use strata_engine::surface::{Preprocessed, SurfaceOptions};
use strata_tests::shared_mesh_dir;

fn projected() -> FieldSpec {
    oblique(3.0)
}

/// Preprocesses, then checks: every face in exactly one final segment, every final
/// segment valid (no flips, no overlap, mean angle under gamma unless it fell back to
/// isotropic), samples exact in count, on their faces, and the sampled density
/// follows the measure per segment.
fn check(mesh: TriMesh, spec: &FieldSpec, name: &str) -> Preprocessed {
    let mesh = Arc::new(mesh);
    let field = Arc::new(spec.build(&mesh).expect("field"));
    let options = SurfaceOptions::default();
    let pre = Preprocessed::build(mesh.clone(), field, &options).expect("preprocess");
    let mut owner = vec![usize::MAX; mesh.face_count()];
    for (i, p) in pre.params.iter().enumerate() {
        assert!(
            p.report.flipped == 0 && !p.report.overlaps,
            "{name}: segment {i}: {:?}",
            p.report
        );
        if !p.report.isotropic_fallback {
            assert!(p.report.valid, "{name}: segment {i}: {:?}", p.report);
            assert!(
                p.report.mean_angle_deg < options.param.gamma.to_degrees(),
                "{name}"
            );
        }
        for &f in &p.faces {
            assert_eq!(
                owner[f as usize],
                usize::MAX,
                "{name}: face {f} in two segments"
            );
            owner[f as usize] = i;
        }
    }
    assert!(
        owner.iter().all(|&o| o != usize::MAX),
        "{name}: a face has no segment"
    );
    // One count of fallback segments: the report's is the segments' flags (`strata
    // sample` printed the one, `strata segment` the other: 72 and 111 on the fandisk).
    assert_eq!(
        pre.report.isotropic_segments,
        pre.params
            .iter()
            .filter(|p| p.report.isotropic_fallback)
            .count(),
        "{name}"
    );
    let n = 20_000;
    let samples = pre.sampler.sample(n, 7);
    assert_eq!(samples.len(), n);
    let mut per_segment = vec![0f64; pre.params.len()];
    for s in &samples {
        let b = s.barycentric();
        assert!(
            b.iter().all(|&x| (-1e-4..=1.0 + 1e-4).contains(&x)),
            "{name}: {s:?}"
        );
        assert!(
            s.position.iter().all(|x| x.is_finite())
                && s.spacing.iter().all(|x| x.is_finite() && *x > 0.0)
        );
        assert_eq!(
            owner[s.face as usize], s.segment as usize,
            "{name}: sample's face is in its segment"
        );
        let p = mesh.face_positions(s.face);
        let back = p[0] * b[0] as f64 + p[1] * b[1] as f64 + p[2] * b[2] as f64;
        let pos = glam::DVec3::from(s.position.map(|x| x as f64));
        assert!(
            (back - pos).length() < 1e-4 * (1.0 + pos.length()),
            "{name}"
        );
        per_segment[s.segment as usize] += 1.0;
    }
    // Each segment gets floor(N share + carry): within one sample of its share.
    let total = pre.sampler.total_measure();
    for (i, seg) in pre.sampler.segments().iter().enumerate() {
        let want = n as f64 * seg.curve.measure() / total;
        assert!(
            (per_segment[i] - want).abs() <= 1.0 + 1e-9,
            "{name}: segment {i}: {} vs {want}",
            per_segment[i]
        );
    }
    pre
}

#[test]
fn built_in_shapes_preprocess_and_sample() {
    check(
        shapes::sphere(1.0, 10).expect("sphere"),
        &projected(),
        "sphere",
    );
    check(
        shapes::torus(1.0, 0.35, 24).expect("torus"),
        &projected(),
        "torus",
    );
    check(
        shapes::genus2(1.0, 2).expect("genus2"),
        &projected(),
        "genus2",
    );
    check(
        shapes::cylinder(0.5, 2.0, 32).expect("cylinder"),
        &projected(),
        "cylinder",
    );
}

#[test]
fn isotropic_fields_give_valid_parameterizations() {
    let iso = isotropic();
    let pre = check(
        shapes::sphere(1.0, 10).expect("sphere"),
        &iso,
        "isotropic sphere",
    );
    assert!(
        pre.params
            .iter()
            .all(|p| p.uv.iter().all(|q| q.is_finite()))
    );
    if let Some(dir) = shared_mesh_dir() {
        let mesh = strata_engine::io::load(&dir.join("stanford-bunny.obj")).expect("bunny");
        let pre = check(mesh, &iso, "isotropic bunny");
        // Issue 18: an isotropic field is covered with normal-cone charts, so the
        // bunny is a few dozen charts with no singularity (3,506 segments and 17,791
        // singular faces before), each a compact, valid fallback parameterization.
        println!(
            "isotropic bunny: {} charts, {} splits, worst mean stretch {:.3}",
            pre.report.segments,
            pre.report.splits,
            pre.params
                .iter()
                .map(|p| p.report.mean_stretch)
                .fold(0.0, f64::max)
        );
        assert!(
            pre.report.segments <= 64,
            "{} segments",
            pre.report.segments
        );
        assert!(pre.segmentation.singularities.is_empty());
        for p in &pre.params {
            assert!(
                p.report.isotropic_fallback && p.report.valid,
                "{:?}",
                p.report
            );
            assert!(p.report.mean_stretch <= 1.5, "{:?}", p.report);
        }
    }
}

#[test]
fn every_shared_mesh_preprocesses_into_valid_segments() {
    let Some(dir) = shared_mesh_dir() else {
        eprintln!("shared meshes not found: skipping");
        return;
    };
    for name in strata_tests::SHARED_MESHES {
        let mesh = strata_engine::io::load(&dir.join(format!("{name}.obj"))).expect("mesh");
        let faces = mesh.face_count();
        let pre = check(mesh, &projected(), name);
        println!("{name}: {:?}", pre.report);
        // The last resort (single-triangle segments) stays rare. Measured: 0 on five
        // meshes, 0.02% of faces on the bunny, 0.07% on the rocker arm, 0.45% on the
        // cow (around its pinched vertex); bound at 1%.
        assert!(
            pre.report.single_face_segments * 100 <= faces,
            "{name}: {:?}",
            pre.report
        );
    }
}

#[test]
fn surface_samples_are_deterministic_across_thread_counts() {
    let mesh = Arc::new(shapes::torus(1.0, 0.4, 16).expect("torus"));
    let field = Arc::new(projected().build(&mesh).expect("field"));
    let run = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool")
            .install(|| {
                let pre =
                    Preprocessed::build(mesh.clone(), field.clone(), &SurfaceOptions::default())
                        .expect("preprocess");
                pre.sampler.sample(30_000, 5)
            })
    };
    assert!(run(1) == run(2));
}

#[test]
fn scaling_the_mesh_scales_the_samples() {
    let base = shapes::torus(1.0, 0.4, 16).expect("torus");
    let sample = |scale: f64| {
        let positions: Vec<glam::DVec3> = base.positions().iter().map(|p| *p * scale).collect();
        let mesh = Arc::new(TriMesh::new(positions, base.triangles().to_vec()).expect("mesh"));
        let field = Arc::new(projected().build(&mesh).expect("field"));
        let pre = Preprocessed::build(mesh, field, &SurfaceOptions::default()).expect("preprocess");
        (pre.params.len(), pre.sampler.sample(5000, 3))
    };
    let (segments, reference) = sample(1.0);
    for scale in [1e-3, 1e3] {
        let (s, scaled) = sample(scale);
        assert_eq!(s, segments, "scale {scale}: segments");
        let same = reference
            .iter()
            .zip(&scaled)
            .filter(|(a, b)| {
                a.face == b.face
                    && (0..3)
                        .all(|k| (a.position[k] as f64 - b.position[k] as f64 / scale).abs() < 1e-4)
            })
            .count();
        // Round-off may move a handful of samples to a neighbouring leaf; all but a few
        // must coincide.
        assert!(
            same >= 4990,
            "scale {scale}: {same} of 5000 samples coincide"
        );
    }
}

#[test]
fn cylinder_four_to_one_along_the_axis() {
    // A 4:1 field along the axis of an open cylinder: samples four times closer along
    // z than around. Measured like the planar test: spacing from the nearest
    // neighbours in the field's metric, in the unrolled (angle * r, z) plane.
    let spec = constant([0.0, 0.0, 1.0], 4.0);
    // sqrt(l): 2 along z, 1/2 around (the metric stretches z by 2 and the angle by 1/2).
    let ratio = cylinder_spacing_ratio(spec, [0.5, 2.0]);
    assert!((ratio - 4.0).abs() <= 0.4, "ratio {ratio}");
}

#[test]
fn designed_cylinder_field_spaces_samples_three_to_one_around() {
    // Issue 17: the designed (curvature-aligned, 3:1) field runs its major direction
    // around the cylinder, so samples are three times closer around than along z.
    // sqrt(l): sqrt(3) around, 1/sqrt(3) along.
    let ratio = cylinder_spacing_ratio(designed(), [3f64.sqrt(), 1.0 / 3f64.sqrt()]);
    assert!((ratio - 1.0 / 3.0).abs() <= 1.0 / 30.0, "ratio {ratio}");
}

/// Samples 6000 points of `spec` on an open cylinder (radius 1, height 6) and returns
/// the mean spacing around over the mean spacing along the axis, from the 4 nearest
/// neighbours of each sample away from the ends in the metric that scales the unrolled
/// `(angle, z)` offsets by `metric`.
fn cylinder_spacing_ratio(spec: FieldSpec, metric: [f64; 2]) -> f64 {
    let mesh = Arc::new(shapes::cylinder(1.0, 6.0, 96).expect("cylinder"));
    let field = Arc::new(spec.build(&mesh).expect("field"));
    let pre = Preprocessed::build(mesh, field, &SurfaceOptions::default()).expect("preprocess");
    assert!(
        pre.params.iter().all(|p| p.report.valid),
        "{:?}",
        pre.report
    );
    let samples = pre.sampler.sample(6000, 1);
    let pts: Vec<glam::DVec2> = samples
        .iter()
        .map(|s| {
            glam::DVec2::new(
                (s.position[1] as f64).atan2(s.position[0] as f64),
                s.position[2] as f64,
            )
        })
        .collect();
    let (mut around, mut along, mut count) = (0.0, 0.0, 0usize);
    for (i, p) in pts.iter().enumerate() {
        if p.y.abs() > 2.0 {
            continue; // away from the open ends
        }
        let mut near: Vec<(f64, glam::DVec2)> = pts
            .iter()
            .enumerate()
            .filter(|(j, q)| *j != i && (q.y - p.y).abs() < 0.5)
            .map(|(_, q)| {
                let mut d = *q - *p;
                d.x = (d.x + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                    - std::f64::consts::PI;
                (
                    glam::DVec2::new(d.x * metric[0], d.y * metric[1]).length(),
                    d,
                )
            })
            .collect();
        near.select_nth_unstable_by(4, |a, b| a.0.total_cmp(&b.0));
        for (_, d) in &near[..4] {
            around += d.x.abs();
            along += d.y.abs();
        }
        count += 4;
    }
    let ratio = around / along;
    println!("cylinder spacing ratio around/along = {ratio:.3} over {count} neighbours");
    ratio
}

/// The designed field of the `<mesh>-smooth.ron` scenes (issue 17): curvature-aligned,
/// 3:1, uniform density.
fn designed() -> FieldSpec {
    FieldSpec::Designed(strata_engine::field::Design::default())
}

#[test]
fn seams_show_neither_gaps_nor_clusters() {
    // Samples per unit of measure in thin bands along segment boundaries against the
    // interior: within 10%. Uniform density on a torus with a field that segments it,
    // and on the genus-2 surface with a designed field (issue 17: the checks keep
    // passing on the new scenes).
    seam_check(shapes::torus(1.0, 0.4, 40).expect("torus"), projected());
    seam_check(shapes::genus2(2.0, 3).expect("genus2"), designed());
    // Issue 18: an isotropic field, covered with normal-cone charts.
    seam_check(shapes::genus2(2.0, 3).expect("genus2"), isotropic());
}

fn seam_check(mesh: TriMesh, spec: FieldSpec) {
    let mesh = Arc::new(mesh);
    let field = Arc::new(spec.build(&mesh).expect("field"));
    let pre =
        Preprocessed::build(mesh.clone(), field, &SurfaceOptions::default()).expect("preprocess");
    assert!(pre.params.len() > 4, "the test needs several segments");
    let mut owner = vec![0usize; mesh.face_count()];
    for (i, p) in pre.params.iter().enumerate() {
        for &f in &p.faces {
            owner[f as usize] = i;
        }
    }
    // Faces touching another segment (through an edge or a vertex) form the seam band.
    let mut seam = vec![false; mesh.face_count()];
    for v in 0..mesh.vertex_count() as u32 {
        let faces = mesh.vertex_faces(v);
        if faces
            .iter()
            .any(|&f| owner[f as usize] != owner[faces[0] as usize])
        {
            for &f in faces {
                seam[f as usize] = true;
            }
        }
    }
    let area = |band: bool| -> f64 {
        mesh.face_areas()
            .iter()
            .zip(&seam)
            .filter(|(_, s)| **s == band)
            .map(|(a, _)| a)
            .sum()
    };
    // The stratified order, and progressive prefixes (issue 19: rank thresholding
    // across segment boundaries draws no lines), at a power of two and between.
    for (n, progressive) in [(200_000, false), (131_072, true), (200_000, true)] {
        let samples = if progressive {
            let mut out = vec![strata_engine::sample::Sample::default(); n];
            pre.sampler.progressive_into(9, 0, &mut out);
            out
        } else {
            pre.sampler.sample(n, 9)
        };
        let in_seam = samples.iter().filter(|s| seam[s.face as usize]).count() as f64;
        let (seam_area, inner_area) = (area(true), area(false));
        let seam_rate = in_seam / seam_area;
        let inner_rate = (n as f64 - in_seam) / inner_area;
        println!(
            "seam band {:.1}% of the area, {n} {}: {seam_rate:.1} vs interior {inner_rate:.1} samples per unit area",
            100.0 * seam_area / (seam_area + inner_area),
            if progressive {
                "progressive"
            } else {
                "stratified"
            },
        );
        assert!(
            (seam_rate / inner_rate - 1.0).abs() < 0.1,
            "seam {seam_rate} vs interior {inner_rate} ({n}, progressive {progressive})"
        );
    }
}

#[test]
fn counts_over_random_patches_beat_random_sampling_threefold() {
    // Patches: breadth-first balls of 60 faces around random faces, not aligned with
    // segments. Expected count: N times the patch's share of the measure (uniform
    // density: of the area). Random sampling of the same density: faces by area,
    // uniform inside. The RMS deviation of strata's counts must be at most a third of
    // random sampling's, with the projected field and with a designed one (issue 17).
    let genus2 = || shapes::genus2(2.0, 3).expect("genus2");
    patch_check(genus2(), projected());
    patch_check(genus2(), designed());
    // Issue 18: an isotropic field, covered with normal-cone charts, on the genus-2
    // surface and on the bunny.
    patch_check(genus2(), isotropic());
    if let Some(dir) = shared_mesh_dir() {
        let bunny = strata_engine::io::load(&dir.join("stanford-bunny.obj")).expect("bunny");
        patch_check(bunny, isotropic());
    }
}

fn patch_check(mesh: TriMesh, spec: FieldSpec) {
    let mesh = Arc::new(mesh);
    let field = Arc::new(spec.build(&mesh).expect("field"));
    let pre =
        Preprocessed::build(mesh.clone(), field, &SurfaceOptions::default()).expect("preprocess");
    let n = 100_000;
    let ours = pre.sampler.sample(n, 4);
    let total: f64 = mesh.face_areas().iter().sum();
    let mut rng = strata_engine::rng::Rng::new(77, 0);
    // Random sampling: count per face.
    let mut cum = vec![0.0];
    for a in mesh.face_areas() {
        cum.push(cum.last().copied().unwrap_or(0.0) + a);
    }
    let mut random_per_face = vec![0u32; mesh.face_count()];
    for _ in 0..n {
        let u = rng.next_f64() * total;
        let f = cum.partition_point(|&c| c <= u) - 1;
        random_per_face[f.min(mesh.face_count() - 1)] += 1;
    }
    let mut ours_per_face = vec![0u32; mesh.face_count()];
    for s in &ours {
        ours_per_face[s.face as usize] += 1;
        // Unit normals on the sample's side of its face.
        let nrm = glam::DVec3::from(s.normal.map(|x| x as f64));
        assert!(
            (nrm.length() - 1.0).abs() < 1e-5
                && nrm.dot(mesh.face_normals()[s.face as usize]) > 0.0
        );
    }
    let (mut se_ours, mut se_random) = (0.0, 0.0);
    let patches = 300;
    for _ in 0..patches {
        let start = rng.below(mesh.face_count() as u64) as u32;
        let mut patch = vec![start];
        let mut seen = std::collections::HashSet::from([start]);
        let mut i = 0;
        while patch.len() < 60 && i < patch.len() {
            for &nb in &mesh.face_neighbors()[patch[i] as usize] {
                if nb != strata_engine::mesh::NONE && patch.len() < 60 && seen.insert(nb) {
                    patch.push(nb);
                }
            }
            i += 1;
        }
        let area: f64 = patch.iter().map(|&f| mesh.face_areas()[f as usize]).sum();
        let expect = n as f64 * area / total;
        let count = |per: &[u32]| patch.iter().map(|&f| per[f as usize] as f64).sum::<f64>();
        se_ours += (count(&ours_per_face) - expect).powi(2);
        se_random += (count(&random_per_face) - expect).powi(2);
    }
    let (rms_ours, rms_random) = (
        (se_ours / patches as f64).sqrt(),
        (se_random / patches as f64).sqrt(),
    );
    println!("patch count RMS deviation: strata {rms_ours:.2}, random {rms_random:.2}");
    assert!(
        rms_ours * 3.0 <= rms_random,
        "strata {rms_ours} vs random {rms_random}"
    );
}

#[test]
fn designed_bunny_segments_do_not_depend_on_the_resolution() {
    // Issue 17: the bunny Loop-subdivided once gives segments within 1.3x of the
    // bunny's with the same designed field. One seed's count jumps with small changes
    // (the default options' seed gave 12 and 20 after trees moved before the walk),
    // so the medians over segmentation seeds 1 to 5 are compared: 32 and 38 since
    // seeding regions stop at an eighth of the surface where they wrap (14 and 17
    // before; bench/README.md, "Seeding regions of at most an eighth of the surface").
    let Some(dir) = shared_mesh_dir() else {
        eprintln!("shared meshes not found: skipping");
        return;
    };
    let coarse = strata_engine::io::load(&dir.join("stanford-bunny.obj")).expect("mesh");
    let fine = strata_engine::mesh::loop_subdivide(&coarse).expect("subdivided");
    let median_segments = |mesh: TriMesh| {
        let mesh = Arc::new(mesh);
        let field = Arc::new(designed().build(&mesh).expect("field"));
        let mut counts: Vec<usize> = (1..=5u64)
            .map(|seed| {
                let mut options = SurfaceOptions::default();
                options.segment.seed = seed;
                Preprocessed::build(mesh.clone(), field.clone(), &options)
                    .expect("preprocess")
                    .report
                    .segments
            })
            .collect();
        counts.sort_unstable();
        (counts[2], counts)
    };
    let ((a, coarse_counts), (b, fine_counts)) = (median_segments(coarse), median_segments(fine));
    println!("designed bunny: segments {coarse_counts:?}; Loop-subdivided once: {fine_counts:?}");
    assert!(
        a.max(b) as f64 <= 1.3 * a.min(b) as f64,
        "medians {a} against {b} segments"
    );
}

#[test]
fn shading_density_gathers_samples_in_shadow() {
    // Issue 21's tone density on a unit sphere lit from +z: 0.5 facing the light, 4 on
    // the back. Samples per unit area on the back over those on the lit cap (z > 0.9,
    // where the density is 0.5 + 3.5 (1 - z), 0.675 on average by area) should be about
    // 4 / 0.675 = 5.9.
    use strata_engine::field::{Anisotropy, Density, Design, Guidance};
    let spec = FieldSpec::Designed(Design {
        guidance: Guidance::Smoothest,
        anisotropy: Anisotropy::Constant(1.0),
        density: Density::Shading {
            light: [0.0, 0.0, 1.0],
            lit: 0.5,
            shadow: 4.0,
            exponent: 1.0,
        },
        ..Design::default()
    });
    let mesh = Arc::new(shapes::sphere(1.0, 16).expect("sphere"));
    let field = Arc::new(spec.build(&mesh).expect("field"));
    let pre = Preprocessed::build(mesh, field, &SurfaceOptions::default()).expect("preprocess");
    let samples = pre.sampler.sample(40_000, 3);
    let cap = samples.iter().filter(|s| s.position[2] > 0.9).count() as f64;
    let back = samples.iter().filter(|s| s.position[2] < -0.1).count() as f64;
    // Zone areas on the unit sphere: 2 pi h.
    let ratio =
        (back / (2.0 * std::f64::consts::PI * 0.9)) / (cap / (2.0 * std::f64::consts::PI * 0.1));
    println!("shadow over lit samples per area: {ratio:.2} (expected about 5.9)");
    assert!((5.0..7.0).contains(&ratio), "{ratio}");
}
