//! Segmentation (paper section 4) on built-in shapes, the project's corpus and the
//! shared meshes: partition, connectivity, disc topology, singularity indices.

use std::collections::{HashSet, VecDeque};

use strata_engine::field::{FieldSpec, TensorField};
use strata_engine::fixtures::{along_x, field_on, isotropic_on, oblique, torus_case};
use strata_engine::mesh::{NONE, TriMesh, shapes};
use strata_engine::segment::topology::patch_topology;
use strata_engine::segment::{SegmentOptions, Segmentation, segment};
use strata_tests::{corpus_dir, shared_mesh_dir};

/// Every invariant the parameterization relies on.
fn check(mesh: &TriMesh, seg: &Segmentation, name: &str) {
    assert_eq!(seg.face_segment.len(), mesh.face_count(), "{name}");
    let mut seen = vec![false; mesh.face_count()];
    for (id, s) in seg.segments.iter().enumerate() {
        assert!(!s.faces.is_empty(), "{name}: empty segment {id}");
        for &f in &s.faces {
            assert!(!seen[f as usize], "{name}: face {f} in two segments");
            seen[f as usize] = true;
            assert_eq!(seg.face_segment[f as usize] as usize, id, "{name}");
        }
        // Connected through edges that are not cut.
        let cut: HashSet<u32> = seg.cut_edges.iter().copied().collect();
        let inside: HashSet<u32> = s.faces.iter().copied().collect();
        let mut reached = HashSet::from([s.faces[0]]);
        let mut queue = VecDeque::from([s.faces[0]]);
        while let Some(f) = queue.pop_front() {
            for (k, &n) in mesh.face_neighbors()[f as usize].iter().enumerate() {
                let e = mesh.face_edges()[f as usize][k];
                if n != NONE && inside.contains(&n) && !cut.contains(&e) && reached.insert(n) {
                    queue.push_back(n);
                }
            }
        }
        assert_eq!(
            reached.len(),
            s.faces.len(),
            "{name}: segment {id} is not connected"
        );
        assert_eq!(
            (s.euler_characteristic, s.boundary_loops.len()),
            (1, 1),
            "{name}: segment {id} ({} faces) is not a disc",
            s.faces.len()
        );
        // Independent check of the reported topology.
        let mut cut_mask = vec![false; mesh.edge_count()];
        for &e in &seg.cut_edges {
            cut_mask[e as usize] = true;
        }
        let topo = patch_topology(mesh, &s.faces, &cut_mask);
        assert_eq!(topo.euler_characteristic, s.euler_characteristic, "{name}");
    }
    assert!(seen.iter().all(|&s| s), "{name}: a face is in no segment");
    for s in &seg.singularities {
        assert!(
            s.index == 0.5
                || s.index == -0.5
                || s.index.fract() == 0.0
                || (2.0 * s.index).fract() == 0.0
        );
        assert!(seg.segments[seg.face_segment[s.face as usize] as usize].has_singular_face);
    }
}

fn index_sum(seg: &Segmentation) -> f64 {
    seg.singularities.iter().map(|s| s.index).sum()
}

#[test]
fn constant_field_on_a_plane_is_one_segment() {
    let mesh = shapes::plane(1.0, 24).expect("plane");
    let field = field_on(&mesh, &along_x(3.0));
    let seg = segment(&mesh, &field, &SegmentOptions::default()).expect("segment");
    check(&mesh, &seg, "plane");
    assert_eq!(seg.segments.len(), 1);
    assert!(seg.singularities.is_empty() && seg.cut_edges.is_empty());
}

#[test]
fn turning_field_gives_several_segments() {
    // theta = pi x: the major direction turns by pi across the unit square.
    let mesh = shapes::plane(1.0, 32).expect("plane");
    let dirs: Vec<_> = mesh
        .positions()
        .iter()
        .map(|p| {
            glam::DVec3::new(
                (std::f64::consts::PI * p.x).cos(),
                (std::f64::consts::PI * p.x).sin(),
                0.0,
            )
        })
        .collect();
    let field =
        TensorField::from_frames(&mesh, &dirs, &vec![[3.0, 1.0 / 3.0]; dirs.len()]).expect("field");
    let seg = segment(&mesh, &field, &SegmentOptions::default()).expect("segment");
    check(&mesh, &seg, "turning plane");
    assert!(seg.segments.len() >= 3, "{} segments", seg.segments.len());
}

#[test]
fn closed_shapes_have_index_sum_equal_to_euler_characteristic() {
    for (name, mesh) in [
        ("sphere", shapes::sphere(1.0, 10).expect("sphere")),
        ("torus", shapes::torus(1.0, 0.35, 24).expect("torus")),
        ("genus2", shapes::genus2(1.0, 2).expect("genus2")),
    ] {
        let field = oblique(3.0).build(&mesh).expect("field");
        let seg = segment(&mesh, &field, &SegmentOptions::default()).expect("segment");
        check(&mesh, &seg, name);
        assert_eq!(
            index_sum(&seg),
            mesh.euler_characteristic() as f64,
            "{name}"
        );
    }
}

#[test]
fn every_shared_mesh_segments_into_discs() {
    let Some(dir) = shared_mesh_dir() else {
        eprintln!("shared meshes not found: skipping");
        return;
    };
    for name in strata_tests::SHARED_MESHES {
        let mesh = strata_engine::io::load(&dir.join(format!("{name}.obj"))).expect("mesh");
        let field = oblique(3.0).build(&mesh).expect("field");
        let seg = segment(&mesh, &field, &SegmentOptions::default()).expect("segment");
        check(&mesh, &seg, name);
        // Poincare-Hopf on closed meshes, against the Euler characteristic of the
        // surface with pinched (non-manifold) vertices split: cow's pinched vertex makes
        // V - E + F = 1, but its surface is a sphere and the field sees 2.
        let all: Vec<u32> = (0..mesh.face_count() as u32).collect();
        let surface = patch_topology(&mesh, &all, &vec![false; mesh.edge_count()]);
        if surface.boundary_loops.is_empty() {
            assert_eq!(
                index_sum(&seg),
                surface.euler_characteristic as f64,
                "{name}"
            );
        }
    }
}

#[test]
fn curvature_field_on_spot_keeps_poincare_hopf() {
    let Some(dir) = shared_mesh_dir() else {
        eprintln!("shared meshes not found: skipping");
        return;
    };
    let mesh = strata_engine::io::load(&dir.join("spot.obj")).expect("mesh");
    let field = FieldSpec::default_curvature().build(&mesh).expect("field");
    let seg = segment(&mesh, &field, &SegmentOptions::default()).expect("segment");
    check(&mesh, &seg, "spot curvature");
    assert_eq!(index_sum(&seg), 2.0);
}

#[test]
fn same_seed_same_segments_whatever_the_thread_count() {
    let (mesh, field) = torus_case();
    let run = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool")
            .install(|| segment(&mesh, &field, &SegmentOptions::default()).expect("segment"))
    };
    assert_eq!(run(1), run(2));
}

#[test]
fn awkward_inputs_still_segment_into_discs() {
    // Isotropic everywhere: directions are arbitrary, the walk must still partition.
    let mesh = shapes::sphere(1.0, 6).expect("sphere");
    let iso = isotropic_on(&mesh);
    let seg = segment(&mesh, &iso, &SegmentOptions::default()).expect("segment");
    check(&mesh, &seg, "isotropic sphere");
    // Corpus meshes: several components, boundaries, non-manifold edges, slivers.
    for file in [
        "two-components.obj",
        "non-manifold.obj",
        "sliver.obj",
        "open-disk.obj",
        "cube.obj",
    ] {
        let path = corpus_dir().join(file);
        let mesh = strata_engine::io::load(&path).unwrap_or_else(|e| panic!("{file}: {e}"));
        let field = oblique(3.0).build(&mesh).expect("field");
        let seg = segment(&mesh, &field, &SegmentOptions::default())
            .unwrap_or_else(|e| panic!("{file}: {e}"));
        check(&mesh, &seg, file);
        // Several components never share a segment.
        for s in &seg.segments {
            let c = mesh.face_components()[s.faces[0] as usize];
            assert!(
                s.faces
                    .iter()
                    .all(|&f| mesh.face_components()[f as usize] == c),
                "{file}"
            );
        }
    }
    let bad = SegmentOptions {
        beta: 0.0,
        ..Default::default()
    };
    assert!(segment(&mesh, &iso, &bad).is_err());
}
