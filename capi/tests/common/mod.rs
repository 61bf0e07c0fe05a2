//! Calls through the exported `strata_` symbols for the tests, as a C host makes them:
//! each wrapper passes valid pointers (the C contract) and returns the status with the
//! handle or value.

#![allow(unsafe_code)] // Calling the C ABI from Rust; each call says why it is valid.
#![allow(dead_code)] // Each test binary uses its own part of these helpers.

use std::ffi::{CStr, CString};
use std::ptr::null_mut;

use strata::StrataStatus;
use strata::build::*;
use strata::lod::*;
use strata::mesh::*;
use strata::sample::*;

/// The last error of this thread.
pub fn last_error() -> String {
    // SAFETY: the library returns a NUL-terminated string it owns, valid until this
    // thread's next failing call; it is copied at once.
    unsafe { CStr::from_ptr(strata::strata_last_error()) }
        .to_string_lossy()
        .into_owned()
}

/// Asserts `status` is OK, with the last error in the message.
pub fn ok(status: StrataStatus) {
    assert_eq!(status, StrataStatus::Ok, "{}", last_error());
}

/// A mesh from a built-in shape's RON.
pub fn shape(ron: &str) -> *mut StrataMesh {
    let ron = CString::new(ron).expect("no NUL");
    let mut mesh = null_mut();
    // SAFETY: a NUL-terminated string and a writable out-pointer.
    ok(unsafe { strata_mesh_shape(ron.as_ptr(), &mut mesh) });
    mesh
}

/// A field from its RON spec.
pub fn field(mesh: *const StrataMesh, spec: &str) -> (StrataStatus, *mut StrataField) {
    let spec = CString::new(spec).expect("no NUL");
    let mut field = null_mut();
    // SAFETY: a handle from the library (or a value under test the library checks), a
    // NUL-terminated string and a writable out-pointer.
    let status = unsafe { strata_field_from_spec(mesh, spec.as_ptr(), &mut field) };
    (status, field)
}

/// A blocking build with the field's settings.
pub fn build(field: *const StrataField) -> (StrataStatus, *mut StrataSampler) {
    let mut sampler = null_mut();
    // SAFETY: a field handle (or a value the library checks), null options, a
    // writable out-pointer.
    let status = unsafe { strata_build(field, std::ptr::null(), &mut sampler) };
    (status, sampler)
}

/// A sampler of the 2:1 field along x on a sphere with `resolution`.
pub fn sphere_sampler(resolution: u32) -> *mut StrataSampler {
    let mesh = shape(&format!("Sphere(radius: 1.0, resolution: {resolution})"));
    let (status, f) = field(
        mesh,
        "Constant(direction: (1.0, 0.0, 0.0), anisotropy: 2.0, density: 1.0)",
    );
    ok(status);
    let (status, sampler) = build(f);
    ok(status);
    // SAFETY: handles from the library, freed once; the sampler keeps its own data.
    unsafe {
        ok(strata_field_free(f));
        ok(strata_mesh_free(mesh));
    }
    sampler
}

/// A stratified or progressive request.
pub fn request(mode: u32, count: usize, seed: u64, first_rank: u32) -> StrataSampleRequest {
    StrataSampleRequest {
        struct_size: size_of::<StrataSampleRequest>() as u32,
        mode,
        count,
        seed,
        first_rank,
    }
}

/// An output with no arrays and `capacity`.
pub fn output(capacity: usize) -> StrataSampleOutput {
    StrataSampleOutput {
        struct_size: size_of::<StrataSampleOutput>() as u32,
        capacity,
        records: null_mut(),
        positions: null_mut(),
        normals: null_mut(),
        major_axes: null_mut(),
        face_ids: null_mut(),
        barycentrics: null_mut(),
        spacings: null_mut(),
    }
}

/// `strata_sample` on structs the caller made valid.
pub fn sample(
    sampler: *const StrataSampler,
    request: &StrataSampleRequest,
    output: &StrataSampleOutput,
) -> StrataStatus {
    // SAFETY: the structs are valid; the tests give arrays of `capacity` entries (or
    // values the library must refuse before touching them).
    unsafe { strata_sample(sampler, request, output) }
}

/// Records of a request, drawn through the C API.
pub fn records(sampler: *const StrataSampler, req: &StrataSampleRequest) -> Vec<StrataSample> {
    let mut out = vec![StrataSample::default(); req.count];
    let mut o = output(out.len());
    o.records = out.as_mut_ptr();
    ok(sample(sampler, req, &o));
    out
}

/// Frees a sampler.
pub fn free_sampler(sampler: *mut StrataSampler) -> StrataStatus {
    // SAFETY: a handle from the library or one freed already (which it must refuse).
    unsafe { strata_sampler_free(sampler) }
}

/// Polls a build until it finishes (60 s at most).
pub fn wait(build: *const StrataBuild) -> StrataBuildProgress {
    let start = std::time::Instant::now();
    loop {
        let mut p = StrataBuildProgress::default();
        // SAFETY: a live build handle and a writable progress struct.
        ok(unsafe { strata_build_poll(build, &mut p) });
        if p.finished == 1 || start.elapsed().as_secs() > 60 {
            return p;
        }
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
}

/// A view of the unit sphere from `eye`, looking at the origin, 800 x 600 pixels.
pub fn view(eye: [f64; 3], base_count: f64) -> StrataView {
    let eye = glam::DVec3::from(eye);
    let proj = glam::dcamera::rh::proj::directx::perspective(0.8, 800.0 / 600.0, 0.01, 100.0);
    let look = glam::dcamera::rh::view::look_at_mat4(eye, glam::DVec3::ZERO, glam::DVec3::Y);
    StrataView {
        struct_size: size_of::<StrataView>() as u32,
        cull_back_faces: 1,
        view_projection: (proj * look).to_cols_array(),
        viewport_width: 800.0,
        viewport_height: 600.0,
        reference: 2000.0,
        max: 4.0,
        base_count,
        shown: 0,
    }
}
