//! What a C call costs beyond the Rust call: `strata_sample` through the exported
//! symbol against the engine's `Sampler::sample_into` on the same sampler, count and
//! seed, alternating the two (and which goes first), median of each: 1 sample (the
//! call's own cost), 10^4 and 10^6 samples, on the torus of the tests with a 2:1 field. Both run on a thread that joined the pool
//! (`strata_join_thread_pool`), as a host's frame thread would.
//!
//! `cargo run --release -p strata-capi --example call_overhead [repeats]`

#![allow(unsafe_code)] // Calling the C ABI from Rust; each call says why it is valid.

use std::ffi::CString;
use std::ptr::{null, null_mut};
use std::time::Instant;

use strata::sample::*;
use strata::{StrataStatus, build::strata_build, mesh::*};
use strata_engine::sample::Sample;

fn main() {
    let repeats: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(301);
    // SAFETY: every pointer below is valid (NUL-terminated strings, writable
    // out-pointers, buffers of the count requested) and every handle is the library's.
    unsafe {
        assert_eq!(
            strata::strata_join_thread_pool(null_mut()),
            StrataStatus::Ok
        );
        let shape = CString::new("Torus(major_radius: 1.0, minor_radius: 0.4, resolution: 48)")
            .expect("no NUL");
        let spec =
            CString::new("Constant(direction: (1.0, 0.0, 0.0), anisotropy: 2.0)").expect("no NUL");
        let (mut mesh, mut field, mut sampler) = (null_mut(), null_mut(), null_mut());
        assert_eq!(
            strata_mesh_shape(shape.as_ptr(), &mut mesh),
            StrataStatus::Ok
        );
        assert_eq!(
            strata_field_from_spec(mesh, spec.as_ptr(), &mut field),
            StrataStatus::Ok
        );
        assert_eq!(strata_build(field, null(), &mut sampler), StrataStatus::Ok);
        // The engine's sampler from the same inputs (the same bits: tests/api.rs).
        let torus =
            std::sync::Arc::new(strata_engine::mesh::shapes::torus(1.0, 0.4, 48).expect("torus"));
        let spec = strata_engine::field::FieldSpec::Constant {
            direction: [1.0, 0.0, 0.0],
            anisotropy: 2.0,
            density: 1.0,
        };
        let torus_field = std::sync::Arc::new(spec.build(&torus).expect("field"));
        let engine =
            strata_engine::surface::Preprocessed::build(torus, torus_field, &Default::default())
                .expect("build")
                .sampler;
        for n in [1usize, 10_000, 1_000_000] {
            let reps = match n {
                1 => repeats * 20,
                1_000_000 => repeats / 10 + 1,
                _ => repeats,
            };
            let mut buf = vec![StrataSample::default(); n];
            let mut ours = vec![Sample::default(); n];
            let mut output = StrataSampleOutput {
                struct_size: size_of::<StrataSampleOutput>() as u32,
                capacity: n,
                records: buf.as_mut_ptr(),
                positions: null_mut(),
                normals: null_mut(),
                major_axes: null_mut(),
                face_ids: null_mut(),
                barycentrics: null_mut(),
                spacings: null_mut(),
            };
            output.capacity = n;
            let (mut c, mut rust) = (Vec::new(), Vec::new());
            for rep in 0..reps + 5 {
                let request = StrataSampleRequest {
                    struct_size: size_of::<StrataSampleRequest>() as u32,
                    mode: STRATA_STRATIFIED,
                    count: n,
                    seed: rep as u64,
                    first_rank: 0,
                };
                let c_call = || {
                    let t = Instant::now();
                    assert_eq!(strata_sample(sampler, &request, &output), StrataStatus::Ok);
                    t.elapsed().as_secs_f64()
                };
                let mut rust_call = || {
                    let t = Instant::now();
                    engine.sample_into(rep as u64, &mut ours);
                    t.elapsed().as_secs_f64()
                };
                // Alternating which goes first, so that neither always finds the
                // workers just woken.
                let (tc, tr) = if rep % 2 == 0 {
                    let tc = c_call();
                    (tc, rust_call())
                } else {
                    let tr = rust_call();
                    (c_call(), tr)
                };
                if rep >= 5 {
                    c.push(tc);
                    rust.push(tr);
                }
            }
            let median = |v: &mut Vec<f64>| {
                v.sort_by(f64::total_cmp);
                v[v.len() / 2]
            };
            let (mc, mr) = (median(&mut c), median(&mut rust));
            println!(
                "{n} samples, {reps} alternating calls: C {:.1} us, Rust {:.1} us, \
                 difference {:+.2} us (medians)",
                mc * 1e6,
                mr * 1e6,
                (mc - mr) * 1e6
            );
        }
        assert_eq!(strata_sampler_free(sampler), StrataStatus::Ok);
        assert_eq!(strata_field_free(field), StrataStatus::Ok);
        assert_eq!(strata_mesh_free(mesh), StrataStatus::Ok);
    }
}
