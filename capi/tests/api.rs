//! The C API through its exported symbols: good and bad input for every function,
//! samples bit for bit the engine's, background builds polled, cancelled and taken,
//! level-of-detail changes consistent with the visible sets.

#![allow(unsafe_code)] // Calling the C ABI from Rust; each call says why it is valid.

mod common;

use std::ffi::CString;
use std::ptr::{null, null_mut};
use std::sync::Arc;

use common::*;
use strata::StrataStatus;
use strata::build::*;
use strata::lod::*;
use strata::mesh::*;
use strata::sample::*;
use strata_engine::fixtures;
use strata_engine::mesh::shapes;
use strata_engine::sample::Sample;
use strata_engine::surface::{Preprocessed, SurfaceOptions};

/// A unit square as two triangles, in the caller's types.
fn square_arrays<P: Copy, I: Copy>(
    positions: &[P],
    indices: &[I],
    position_type: u32,
    index_type: u32,
) -> StrataMeshArrays {
    StrataMeshArrays {
        struct_size: size_of::<StrataMeshArrays>() as u32,
        position_type,
        positions: positions.as_ptr().cast(),
        vertex_count: positions.len() / 3,
        index_type,
        indices: indices.as_ptr().cast(),
        index_count: indices.len(),
    }
}

fn from_arrays(arrays: &StrataMeshArrays) -> (StrataStatus, *mut StrataMesh) {
    let mut mesh = null_mut();
    // SAFETY: `arrays` points at live arrays of the counts it gives (or at values the
    // library must refuse before reading them); `mesh` is writable.
    let status = unsafe { strata_mesh_from_arrays(arrays, &mut mesh) };
    (status, mesh)
}

fn counts(mesh: *const StrataMesh) -> (usize, usize) {
    let (mut v, mut f) = (0, 0);
    // SAFETY: a live mesh handle and writable counts.
    ok(unsafe { strata_mesh_counts(mesh, &mut v, &mut f) });
    (v, f)
}

#[test]
fn the_version_is_the_headers() {
    assert_eq!(strata::strata_version(), strata::STRATA_API_VERSION);
    let header = include_str!("../include/strata.h");
    let line = format!("#define STRATA_API_VERSION {}", strata::STRATA_API_VERSION);
    assert!(header.contains(&line), "the header defines {line}");
}

#[test]
fn meshes_from_f32_u32_and_f64_u64_arrays_are_the_same_mesh() {
    let p32: [f32; 12] = [0., 0., 0., 1., 0., 0., 1., 1., 0., 0., 1., 0.];
    let p64: Vec<f64> = p32.iter().map(|&x| f64::from(x)).collect();
    let i32s: [u32; 6] = [0, 1, 2, 0, 2, 3];
    let i64s: Vec<u64> = i32s.iter().map(|&i| u64::from(i)).collect();
    let (s, a) = from_arrays(&square_arrays(&p32, &i32s, STRATA_F32, STRATA_U32));
    ok(s);
    let (s, b) = from_arrays(&square_arrays(&p64, &i64s, STRATA_F64, STRATA_U64));
    ok(s);
    assert_eq!(counts(a), (4, 2));
    assert_eq!(counts(b), (4, 2));
    // SAFETY: live handles, each freed once; the second free of `a` must be refused.
    unsafe {
        ok(strata_mesh_free(a));
        ok(strata_mesh_free(b));
        assert_eq!(strata_mesh_free(a), StrataStatus::InvalidHandle);
        assert_eq!(strata_mesh_free(null_mut()), StrataStatus::Ok);
    }
}

#[test]
fn bad_mesh_arrays_are_refused_with_a_message() {
    let p: [f32; 12] = [0., 0., 0., 1., 0., 0., 1., 1., 0., 0., 1., 0.];
    let i: [u32; 6] = [0, 1, 2, 0, 2, 3];
    let good = square_arrays(&p, &i, STRATA_F32, STRATA_U32);
    let cases: Vec<(StrataMeshArrays, StrataStatus, &str)> = vec![
        (
            StrataMeshArrays {
                positions: null(),
                ..good
            },
            StrataStatus::NullPointer,
            "positions is null",
        ),
        (
            StrataMeshArrays {
                indices: null(),
                ..good
            },
            StrataStatus::NullPointer,
            "indices is null",
        ),
        (
            StrataMeshArrays {
                struct_size: 8,
                ..good
            },
            StrataStatus::InvalidArgument,
            "struct_size is 8",
        ),
        (
            StrataMeshArrays {
                vertex_count: 0,
                ..good
            },
            StrataStatus::InvalidArgument,
            "vertex_count is 0",
        ),
        (
            StrataMeshArrays {
                index_count: 4,
                ..good
            },
            StrataStatus::InvalidArgument,
            "index_count is 4",
        ),
        (
            StrataMeshArrays {
                vertex_count: 3,
                ..good
            },
            StrataStatus::InvalidArgument,
            "index 3 is not a vertex",
        ),
        (
            StrataMeshArrays {
                position_type: 7,
                ..good
            },
            StrataStatus::InvalidArgument,
            "position_type is 7",
        ),
        (
            StrataMeshArrays {
                index_type: STRATA_F32,
                ..good
            },
            StrataStatus::InvalidArgument,
            "index_type is 1",
        ),
    ];
    for (arrays, status, message) in cases {
        let (s, mesh) = from_arrays(&arrays);
        assert_eq!(s, status, "{message}: {}", last_error());
        assert!(mesh.is_null());
        assert!(last_error().contains(message), "{}", last_error());
    }
    // A degenerate triangle: the engine's own message.
    let flat: [f32; 9] = [0., 0., 0., 1., 0., 0., 2., 0., 0.];
    let (s, _) = from_arrays(&square_arrays(&flat, &[0u32, 1, 2], STRATA_F32, STRATA_U32));
    assert_eq!(s, StrataStatus::Mesh, "{}", last_error());
    assert!(last_error().starts_with("mesh: "), "{}", last_error());
    // SAFETY: null arguments, which the library must refuse.
    unsafe {
        let mut mesh = null_mut();
        assert_eq!(
            strata_mesh_from_arrays(null(), &mut mesh),
            StrataStatus::NullPointer
        );
        assert_eq!(
            strata_mesh_from_arrays(&good, null_mut()),
            StrataStatus::NullPointer
        );
        assert_eq!(
            strata_mesh_load(null(), &mut mesh),
            StrataStatus::NullPointer
        );
        let missing = CString::new("/nonexistent/mesh.obj").expect("no NUL");
        assert_eq!(
            strata_mesh_load(missing.as_ptr(), &mut mesh),
            StrataStatus::Mesh
        );
        let bad_shape = CString::new("Cube()").expect("no NUL");
        assert_eq!(
            strata_mesh_shape(bad_shape.as_ptr(), &mut mesh),
            StrataStatus::Config
        );
    }
}

#[test]
fn fields_are_checked_and_a_handle_of_another_kind_is_refused() {
    let mesh = shape("Sphere(radius: 1.0, resolution: 3)");
    let (s, _) = field(
        mesh,
        "Constant(direction: (1.0, 0.0, 0.0), anisotropy: 0.5)",
    );
    assert_eq!(s, StrataStatus::Field, "{}", last_error());
    let (s, _) = field(mesh, "NoSuchField()");
    assert_eq!(s, StrataStatus::Config, "{}", last_error());
    // A mesh handle where a field is expected.
    let (s, _) = build(mesh.cast());
    assert_eq!(s, StrataStatus::InvalidHandle);
    assert!(
        last_error().contains("is a mesh handle"),
        "{}",
        last_error()
    );
    let (mut v, mut f) = (0, 0);
    // SAFETY: a live mesh handle and writable out-pointers; wrong tensor lengths must
    // be refused before the (short) array is read.
    unsafe {
        ok(strata_mesh_counts(mesh, &mut v, &mut f));
        let tensors = vec![0.0; 9 * v];
        let mut out = null_mut();
        assert_eq!(
            strata_field_from_tensors(mesh, tensors.as_ptr(), 9 * v - 1, &mut out),
            StrataStatus::InvalidArgument
        );
        assert_eq!(
            strata_field_from_tensors(mesh, tensors.as_ptr(), 9 * v, &mut out),
            StrataStatus::Field,
            "zero tensors are not positive definite"
        );
        let identity: Vec<f64> = (0..v)
            .flat_map(|_| [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0])
            .collect();
        ok(strata_field_from_tensors(
            mesh,
            identity.as_ptr(),
            9 * v,
            &mut out,
        ));
        ok(strata_field_free(out));
        ok(strata_mesh_free(mesh));
    }
}

#[test]
fn samples_equal_the_engines_bit_for_bit() {
    let sampler = sphere_sampler(6);
    let mesh = Arc::new(shapes::sphere(1.0, 6).expect("sphere"));
    let field = Arc::new(fixtures::field_on(&mesh, &fixtures::along_x_2to1()));
    let engine = Preprocessed::build(mesh, field, &SurfaceOptions::default())
        .expect("build")
        .sampler;
    for count in [1, 7, 1000, 4097] {
        let ours = records(sampler, &request(STRATA_STRATIFIED, count, 11, 0));
        let mut theirs = vec![Sample::default(); count];
        engine.sample_into(11, &mut theirs);
        assert_eq!(ours.len(), theirs.len());
        for (a, b) in ours.iter().zip(&theirs) {
            assert_eq!(a.position.map(f32::to_bits), b.position.map(f32::to_bits));
            assert_eq!((a.face, a.index, a.segment), (b.face, b.index, b.segment));
            assert_eq!(a.bary.map(f32::to_bits), b.bary.map(f32::to_bits));
            assert_eq!(a.spacing.map(f32::to_bits), b.spacing.map(f32::to_bits));
            assert_eq!(a.normal.map(f32::to_bits), b.normal.map(f32::to_bits));
            assert_eq!(
                a.major_axis.map(f32::to_bits),
                b.major_axis.map(f32::to_bits)
            );
        }
    }
    let ours = records(sampler, &request(STRATA_PROGRESSIVE, 500, 3, 100));
    let mut theirs = vec![Sample::default(); 500];
    engine.progressive_into(3, 100, &mut theirs);
    for (a, b) in ours.iter().zip(&theirs) {
        assert_eq!(a.position.map(f32::to_bits), b.position.map(f32::to_bits));
        assert_eq!(a.index, b.index);
    }
    assert_eq!(ours[0].index, 100);
    ok(free_sampler(sampler));
}

#[test]
fn separate_arrays_hold_the_records_fields() {
    let sampler = sphere_sampler(4);
    let n = 777;
    let req = request(STRATA_STRATIFIED, n, 5, 0);
    let recs = records(sampler, &req);
    let (mut pos, mut nor, mut maj) = (vec![0f32; 3 * n], vec![0f32; 3 * n], vec![0f32; 3 * n]);
    let (mut faces, mut bary, mut spacing) = (vec![0u32; n], vec![0f32; 2 * n], vec![0f32; 2 * n]);
    let mut o = output(n);
    o.positions = pos.as_mut_ptr();
    o.normals = nor.as_mut_ptr();
    o.major_axes = maj.as_mut_ptr();
    o.face_ids = faces.as_mut_ptr();
    o.barycentrics = bary.as_mut_ptr();
    o.spacings = spacing.as_mut_ptr();
    // Twice: the second call reuses the scratch the first grew.
    for _ in 0..2 {
        ok(sample(sampler, &req, &o));
        for (k, r) in recs.iter().enumerate() {
            assert_eq!(pos[3 * k..3 * k + 3], r.position);
            assert_eq!(nor[3 * k..3 * k + 3], r.normal);
            assert_eq!(maj[3 * k..3 * k + 3], r.major_axis);
            assert_eq!(faces[k], r.face);
            assert_eq!(bary[2 * k..2 * k + 2], r.bary);
            assert_eq!(spacing[2 * k..2 * k + 2], r.spacing);
        }
    }
    ok(free_sampler(sampler));
}

#[test]
fn bad_sample_requests_are_refused() {
    let sampler = sphere_sampler(3);
    let mut buf = vec![StrataSample::default(); 10];
    let mut o = output(10);
    o.records = buf.as_mut_ptr();
    let good = request(STRATA_STRATIFIED, 10, 1, 0);
    let cases = [
        (
            request(STRATA_STRATIFIED, 11, 1, 0),
            StrataStatus::InvalidArgument,
        ),
        (request(9, 10, 1, 0), StrataStatus::InvalidArgument),
        (
            request(STRATA_PROGRESSIVE, 10, 1, u32::MAX - 3),
            StrataStatus::InvalidArgument,
        ),
        (
            StrataSampleRequest {
                struct_size: 4,
                ..good
            },
            StrataStatus::InvalidArgument,
        ),
    ];
    for (req, status) in cases {
        assert_eq!(sample(sampler, &req, &o), status, "{}", last_error());
    }
    // No array at all; a zero count writes nothing and succeeds.
    assert_eq!(
        sample(sampler, &good, &output(10)),
        StrataStatus::NullPointer
    );
    ok(sample(sampler, &request(STRATA_STRATIFIED, 0, 1, 0), &o));
    // SAFETY: null structs, which the library must refuse.
    unsafe {
        assert_eq!(
            strata_sample(sampler, null(), &o),
            StrataStatus::NullPointer
        );
        assert_eq!(
            strata_sample(sampler, &good, null()),
            StrataStatus::NullPointer
        );
        assert_eq!(strata_sample(null(), &good, &o), StrataStatus::NullPointer);
    }
    ok(free_sampler(sampler));
    // A freed sampler is refused, whether sampled or freed again.
    assert_eq!(sample(sampler, &good, &o), StrataStatus::InvalidHandle);
    assert_eq!(free_sampler(sampler), StrataStatus::InvalidHandle);
}

#[test]
fn a_background_build_is_polled_and_taken_once_and_equals_the_blocking_one() {
    let mesh = shape("Torus(major_radius: 1.0, minor_radius: 0.4, resolution: 24)");
    let (s, f) = field(
        mesh,
        "Constant(direction: (1.0, 0.0, 0.0), anisotropy: 2.0, density: 1.0)",
    );
    ok(s);
    let mut job = null_mut();
    let mut taken = null_mut();
    // SAFETY: live handles, null options, writable out-pointers; each handle freed once.
    unsafe {
        ok(strata_build_start(f, null(), &mut job));
        let p = wait(job);
        assert_eq!((p.finished, p.stage), (1, STRATA_STAGE_FINISHED));
        ok(strata_build_take(job, &mut taken));
        assert_eq!(
            strata_build_take(job, &mut taken),
            StrataStatus::InvalidArgument
        );
        ok(strata_build_free(job));
    }
    let (s, blocking) = build(f);
    ok(s);
    let req = request(STRATA_STRATIFIED, 2000, 9, 0);
    assert_eq!(records(taken, &req), records(blocking, &req));
    ok(free_sampler(taken));
    ok(free_sampler(blocking));
    // SAFETY: live handles, freed once.
    unsafe {
        ok(strata_field_free(f));
        ok(strata_mesh_free(mesh));
    }
}

#[test]
fn a_cancelled_build_says_so_and_bad_options_are_refused() {
    let mesh = shape("Sphere(radius: 1.0, resolution: 40)");
    let (s, f) = field(
        mesh,
        "Constant(direction: (1.0, 0.0, 0.0), anisotropy: 3.0, density: 1.0)",
    );
    ok(s);
    let mut job = null_mut();
    let mut sampler = null_mut();
    // SAFETY: live handles, valid or deliberately wrong options, writable out-pointers.
    unsafe {
        ok(strata_build_start(f, null(), &mut job));
        ok(strata_build_cancel(job));
        wait(job);
        assert_eq!(
            strata_build_take(job, &mut sampler),
            StrataStatus::Cancelled
        );
        assert!(sampler.is_null());
        ok(strata_build_free(job));
        assert_eq!(strata_build_free(job), StrataStatus::InvalidHandle);
        assert_eq!(strata_build_cancel(job), StrataStatus::InvalidHandle);
        let bad = CString::new("(min_segment_faces: 0)").expect("no NUL");
        let options = StrataBuildOptions {
            struct_size: size_of::<StrataBuildOptions>() as u32,
            surface_ron: bad.as_ptr(),
        };
        assert_eq!(
            strata_build(f, &options, &mut sampler),
            StrataStatus::InvalidArgument
        );
        assert!(
            last_error().contains("min_segment_faces"),
            "{}",
            last_error()
        );
        let old = StrataBuildOptions {
            struct_size: 4,
            ..options
        };
        assert_eq!(
            strata_build(f, &old, &mut sampler),
            StrataStatus::InvalidArgument
        );
        ok(strata_field_free(f));
        ok(strata_mesh_free(mesh));
    }
}

fn lod_update(lod: *const StrataLod, view: &StrataView) -> (StrataStatus, StrataLodFrame) {
    let mut frame = StrataLodFrame::default();
    // SAFETY: a live pool, a valid view and a writable frame.
    let status = unsafe { strata_lod_update(lod, view, &mut frame) };
    (status, frame)
}

fn changes(lod: *const StrataLod, which: u32) -> Vec<u32> {
    let mut n = 0;
    // SAFETY: a live pool; first the count alone, then a buffer of that count.
    unsafe {
        ok(strata_lod_changes(lod, which, null_mut(), 0, &mut n));
        let mut ranks = vec![0; n];
        ok(strata_lod_changes(
            lod,
            which,
            ranks.as_mut_ptr(),
            n,
            &mut n,
        ));
        ranks
    }
}

#[test]
fn level_of_detail_reports_what_became_visible_and_hidden() {
    let sampler = sphere_sampler(8);
    let mut lod = null_mut();
    // SAFETY: a live sampler and a writable out-pointer.
    ok(unsafe { strata_lod_create(sampler, 7, 2000, 20_000, &mut lod) });
    let mut visible: Vec<u32> = Vec::new();
    for eye in [
        [0.0, 0.5, 3.0],
        [0.0, 0.5, 2.0],
        [2.0, 0.5, 1.5],
        [0.0, 0.5, 3.0],
    ] {
        let (s, frame) = lod_update(lod, &view(eye, 2000.0));
        ok(s);
        let (shown, hidden) = (
            changes(lod, STRATA_LOD_SHOWN),
            changes(lod, STRATA_LOD_HIDDEN),
        );
        assert_eq!(frame.became_visible as usize, shown.len());
        assert_eq!(frame.became_hidden as usize, hidden.len());
        visible.retain(|r| hidden.binary_search(r).is_err());
        assert!(shown.iter().all(|r| visible.binary_search(r).is_err()));
        visible.extend(&shown);
        visible.sort_unstable();
        assert_eq!(visible.len() as u64, frame.visible);
        assert!(frame.visible > 0 && frame.visible < frame.entries);
        let mut recs = vec![StrataSample::default(); shown.len()];
        // SAFETY: a live pool and a buffer of the shown count.
        ok(unsafe { strata_lod_shown_records(lod, recs.as_mut_ptr(), recs.len()) });
        assert!(recs.iter().zip(&shown).all(|(r, &k)| r.index == k));
    }
    // The camera came back: what the second view showed was hidden again.
    let bad = StrataView {
        viewport_height: 0.0,
        ..view([0.0, 0.5, 3.0], 2000.0)
    };
    assert_eq!(lod_update(lod, &bad).0, StrataStatus::InvalidArgument);
    let behind = StrataView {
        struct_size: 3,
        ..view([0.0, 0.5, 3.0], 2000.0)
    };
    assert_eq!(lod_update(lod, &behind).0, StrataStatus::InvalidArgument);
    let mut n = 0;
    // SAFETY: a live pool and deliberately bad arguments the library must refuse.
    unsafe {
        assert_eq!(
            strata_lod_changes(lod, 5, null_mut(), 0, &mut n),
            StrataStatus::InvalidArgument
        );
        let mut one = [0u32; 1];
        let shown = changes(lod, STRATA_LOD_SHOWN).len();
        if shown > 1 {
            assert_eq!(
                strata_lod_changes(lod, STRATA_LOD_SHOWN, one.as_mut_ptr(), 1, &mut n),
                StrataStatus::InvalidArgument
            );
        }
        ok(strata_lod_free(lod));
        assert_eq!(strata_lod_free(lod), StrataStatus::InvalidHandle);
        let mut none = null_mut();
        assert_eq!(
            strata_lod_create(sampler, 7, 0, 10, &mut none),
            StrataStatus::InvalidArgument
        );
    }
    ok(free_sampler(sampler));
}
