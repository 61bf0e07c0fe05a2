//! Surface preprocessing and sampling end to end (segmentation, parameterization with
//! splitting, cells, samples) on built-in shapes and the shared meshes.

use std::sync::Arc;

use strata_engine::field::FieldSpec;
use strata_engine::mesh::{TriMesh, shapes};
use strata_engine::surface::{Preprocessed, SurfaceOptions};
use strata_tests::shared_mesh_dir;

fn projected() -> FieldSpec {
    FieldSpec::Constant {
        direction: [1.0, 0.3, 0.2],
        anisotropy: 3.0,
        density: 1.0,
    }
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
    let iso = FieldSpec::Constant {
        direction: [1.0, 0.0, 0.0],
        anisotropy: 1.0,
        density: 1.0,
    };
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
        check(mesh, &iso, "isotropic bunny");
    }
}

#[test]
fn every_shared_mesh_preprocesses_into_valid_segments() {
    let Some(dir) = shared_mesh_dir() else {
        eprintln!("shared meshes not found: skipping");
        return;
    };
    for name in [
        "spot",
        "two-torus",
        "stanford-bunny",
        "rocker-arm",
        "fandisk",
        "homer",
        "cow",
        "wing",
    ] {
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
