use std::sync::Mutex;

use glam::DVec3;

use super::*;
use crate::field::FieldSpec;
use crate::fixtures::torus_case;
use crate::mesh::NONE;
use crate::surface::Preprocessed;

/// The stages of a build that segments.
const ALL_STAGES: [BuildStage; 4] = [
    BuildStage::Segmentation,
    BuildStage::Parameterization,
    BuildStage::Cells,
    BuildStage::Chains,
];

fn inputs(mesh: &Arc<TriMesh>, field: &Arc<TensorField>, options: SurfaceOptions) -> BuildInputs {
    BuildInputs {
        mesh: mesh.clone(),
        field: field.clone(),
        options,
    }
}

fn build(inputs: BuildInputs, previous: Option<&SurfaceState>) -> BuildOutcome {
    rebuild(inputs, previous, &BuildControl::new()).expect("rebuild")
}

fn stages(outcome: &BuildOutcome) -> Vec<BuildStage> {
    outcome.runs.iter().map(|r| r.stage).collect()
}

/// Bit for bit the whole surface path: same segments, same samples.
fn assert_equals_whole_build(outcome: &BuildOutcome, options: &SurfaceOptions) {
    let i = &outcome.state.inputs;
    let whole =
        Preprocessed::build_surface(i.mesh.clone(), i.field.clone(), options).expect("whole");
    let sampler = outcome.sampler.as_ref().expect("sampler");
    assert_eq!(sampler.segments().len(), whole.sampler.segments().len());
    for (a, b) in sampler.segments().iter().zip(whole.sampler.segments()) {
        assert_eq!(a.faces, b.faces);
        assert_eq!(a.curve.cell_count(), b.curve.cell_count());
    }
    assert_eq!(sampler.chains(), whole.sampler.chains());
    assert!(
        sampler.sample(3000, 7) == whole.sampler.sample(3000, 7),
        "samples differ"
    );
}

/// Every face in exactly one segment, every segment with pieces and cells.
fn assert_covering(state: &SurfaceState) {
    let mut owner = vec![NONE; state.inputs.mesh.face_count()];
    for (i, s) in state.segments.iter().enumerate() {
        assert!(!s.pieces.pieces.is_empty() && s.curves.curves.len() == s.pieces.pieces.len());
        for &f in &s.cut.faces {
            assert_eq!(owner[f as usize], NONE, "face {f} in two segments");
            owner[f as usize] = i as u32;
        }
    }
    assert!(owner.iter().all(|&o| o != NONE), "a face has no segment");
}

/// A 3:1 field on `mesh` along one direction, and the same field turned where `z > 0.2`
/// (every other tensor bit for bit the same).
fn cap_fields(mesh: &TriMesh) -> (Arc<TensorField>, Arc<TensorField>) {
    let base = DVec3::new(1.0, 0.3, 0.2);
    let eigen = vec![[3.0, 1.0 / 3.0]; mesh.vertex_count()];
    let make = |turn: bool| {
        let dirs: Vec<DVec3> = mesh
            .positions()
            .iter()
            .map(|p| {
                if turn && p.z > 0.2 {
                    DVec3::new(0.2, -1.0, 0.3)
                } else {
                    base
                }
            })
            .collect();
        Arc::new(TensorField::from_frames(mesh, &dirs, &eigen).expect("field"))
    };
    (make(false), make(true))
}

#[test]
fn a_first_build_is_the_whole_surface_path_bit_for_bit() {
    let options = SurfaceOptions::default();
    let (mesh, field) = torus_case();
    let out = build(inputs(&mesh, &field, options), None);
    assert_eq!(stages(&out), ALL_STAGES);
    assert!(out.origins.iter().all(Option::is_none));
    assert_equals_whole_build(&out, &options);
    assert_covering(&out.state);
    // An isotropic field takes normal-cone charts, on the field's isotropic copy.
    let iso = FieldSpec::Constant {
        direction: [1.0, 0.0, 0.0],
        anisotropy: 1.0,
        density: 2.0,
    };
    let iso = Arc::new(iso.build(&mesh).expect("field"));
    let out = build(inputs(&mesh, &iso, options), None);
    assert_eq!(out.state.kind, SegmentationKind::IsotropicCharts);
    assert_equals_whole_build(&out, &options);
}

#[test]
fn unchanged_inputs_redo_nothing_and_keep_the_sampler() {
    let options = SurfaceOptions::default();
    let (mesh, field) = torus_case();
    let first = build(inputs(&mesh, &field, options), None);
    // The same content in new allocations counts as unchanged.
    let mesh2 = Arc::new((*mesh).clone());
    let field2 = Arc::new((*field).clone());
    let again = build(inputs(&mesh2, &field2, options), Some(&first.state));
    assert!(again.runs.is_empty(), "{:?}", again.runs);
    assert!(again.sampler.is_none());
    assert_eq!(again.state.chains, first.state.chains);
    let n = first.state.segments.len();
    assert_eq!(again.origins, (0..n).map(Some).collect::<Vec<_>>());
}

#[test]
fn a_cell_setting_rebuilds_every_cell_keeps_the_chains_and_equals_a_whole_build() {
    let mut options = SurfaceOptions::default();
    let (mesh, field) = torus_case();
    let first = build(inputs(&mesh, &field, options), None);
    options.curve.max_cell_share *= 0.25;
    let out = build(inputs(&mesh, &field, options), Some(&first.state));
    assert_eq!(stages(&out), [BuildStage::Cells]);
    assert_eq!(out.runs[0].note, "omega changed");
    assert_eq!(out.runs[0].items, first.state.segments.len());
    for (s, origin) in out.state.segments.iter().zip(&out.origins) {
        let old = &first.state.segments[origin.expect("kept")];
        assert!(Arc::ptr_eq(&s.cut, &old.cut) && Arc::ptr_eq(&s.pieces, &old.pieces));
        assert!(!Arc::ptr_eq(&s.curves, &old.curves));
    }
    assert_eq!(out.state.chains, first.state.chains);
    assert_equals_whole_build(&out, &options);
}

#[test]
fn a_new_segmentation_seed_reuses_equal_segments_and_equals_a_whole_build() {
    let mut options = SurfaceOptions::default();
    let (mesh, field) = torus_case();
    let first = build(inputs(&mesh, &field, options), None);
    options.segment.seed = 5;
    let out = build(inputs(&mesh, &field, options), Some(&first.state));
    assert_eq!(out.runs[0].note, "whole mesh");
    let kept = out.origins.iter().filter(|o| o.is_some()).count();
    assert_eq!(out.runs[0].items, out.state.segments.len() - kept);
    assert_equals_whole_build(&out, &options);
    assert_covering(&out.state);
}

#[test]
fn a_field_change_resegments_only_the_segments_it_touches() {
    let options = SurfaceOptions::default();
    let (mesh, _) = torus_case();
    let (field, turned) = cap_fields(&mesh);
    let first = build(inputs(&mesh, &field, options), None);
    let out = build(inputs(&mesh, &turned, options), Some(&first.state));
    assert_eq!(stages(&out), ALL_STAGES);
    assert!(
        out.runs[0].note.starts_with("region of"),
        "{}",
        out.runs[0].note
    );
    let changed: Vec<bool> = field
        .tensors()
        .iter()
        .zip(turned.tensors())
        .map(|(a, b)| a != b)
        .collect();
    let touches = |faces: &[u32]| {
        faces.iter().any(|&f| {
            mesh.triangles()[f as usize]
                .iter()
                .any(|&v| changed[v as usize])
        })
    };
    let kept: Vec<usize> = out.origins.iter().flatten().copied().collect();
    assert!(!kept.is_empty() && kept.len() < first.state.segments.len());
    for (i, s) in first.state.segments.iter().enumerate() {
        assert_eq!(kept.contains(&i), !touches(&s.cut.faces), "segment {i}");
    }
    let new = out.origins.iter().filter(|o| o.is_none()).count();
    assert_eq!(out.runs[0].items, new);
    assert_eq!(out.runs[1].items, new);
    assert_eq!(out.runs[2].items, new);
    assert_covering(&out.state);
    let sampler = out.sampler.as_ref().expect("sampler");
    assert_eq!(sampler.sample(2000, 3).len(), 2000);

    // The same change from the previous segments in another order: the same result.
    let mut shuffled = first.state.clone();
    shuffled.segments.reverse();
    let again = build(inputs(&mesh, &turned, options), Some(&shuffled));
    let other = again.sampler.as_ref().expect("sampler");
    assert!(other.sample(2000, 3) == sampler.sample(2000, 3));
}

#[test]
fn cancellation_stops_between_stages_and_keeps_the_previous_state_usable() {
    let options = SurfaceOptions::default();
    let (mesh, field) = torus_case();
    // Cancelled before it starts.
    let control = BuildControl::new();
    control.cancel();
    let err = rebuild(inputs(&mesh, &field, options), None, &control).expect_err("cancelled");
    assert!(matches!(err, SurfaceError::Cancelled), "{err}");
    assert_eq!(control.progress().stage, BuildStage::Finished);
    // Cancelled as parameterization starts: no segment is parameterized.
    let entered = Arc::new(Mutex::new(Vec::new()));
    let log = entered.clone();
    let control = BuildControl::with_observer(move |c, stage| {
        log.lock().expect("log").push((stage, c.progress().done));
        if stage == BuildStage::Parameterization {
            c.cancel();
        }
    });
    let err = rebuild(inputs(&mesh, &field, options), None, &control).expect_err("cancelled");
    assert!(matches!(err, SurfaceError::Cancelled));
    assert_eq!(
        *entered.lock().expect("log"),
        [
            (BuildStage::Segmentation, 0),
            (BuildStage::Parameterization, 0)
        ]
    );
    assert_eq!(control.progress().done, 0, "a segment ran after the cancel");
    // A later build from scratch is unaffected.
    let out = build(inputs(&mesh, &field, options), None);
    assert_equals_whole_build(&out, &options);
}

#[test]
fn progress_reports_each_stage_with_its_items() {
    let (mesh, field) = torus_case();
    let seen = Arc::new(Mutex::new(Vec::new()));
    let log = seen.clone();
    let control = BuildControl::with_observer(move |c, stage| {
        log.lock().expect("log").push((stage, c.progress().total));
    });
    let out = rebuild(
        inputs(&mesh, &field, SurfaceOptions::default()),
        None,
        &control,
    )
    .expect("build");
    let n = out.state.segments.len();
    assert_eq!(
        *seen.lock().expect("log"),
        [
            (BuildStage::Segmentation, 1),
            (BuildStage::Parameterization, n),
            (BuildStage::Cells, n),
            (BuildStage::Chains, 1)
        ]
    );
    let p = control.progress();
    assert_eq!((p.stage, p.fraction()), (BuildStage::Finished, 1.0));
}

#[test]
fn the_segment_key_follows_what_parameterization_reads() {
    let (mesh, field) = torus_case();
    let options = SurfaceOptions::default();
    let faces: Vec<u32> = (0..40).collect();
    let key = segment_key(&mesh, &field, &faces, &[3, 9], &options);
    assert_eq!(key, segment_key(&mesh, &field, &faces, &[3, 9], &options));
    assert_ne!(
        key,
        segment_key(&mesh, &field, &faces[1..], &[3, 9], &options)
    );
    assert_ne!(key, segment_key(&mesh, &field, &faces, &[3], &options));
    let mut gamma = options;
    gamma.param.gamma *= 0.5;
    assert_ne!(key, segment_key(&mesh, &field, &faces, &[3, 9], &gamma));
    let mut seed = options;
    seed.segment.seed += 1; // seeding is not read
    assert_eq!(key, segment_key(&mesh, &field, &faces, &[3, 9], &seed));
    // The tensors and positions of its vertices.
    let (base, turned) = cap_fields(&mesh);
    let all: Vec<u32> = (0..mesh.face_count() as u32).collect();
    assert_ne!(
        segment_key(&mesh, &base, &all, &[], &options),
        segment_key(&mesh, &turned, &all, &[], &options)
    );
    let mut positions = mesh.positions().to_vec();
    positions[mesh.triangles()[0][1] as usize].x += 1e-9;
    let moved = TriMesh::new(positions, mesh.triangles().to_vec()).expect("mesh");
    assert_ne!(key, segment_key(&moved, &field, &faces, &[3, 9], &options));
}
