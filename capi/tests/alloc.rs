//! No allocation per sampling call in steady state: a counting global allocator around
//! the system's, and `strata_sample` called again and again, with records (drawn into
//! the caller's buffer) and with separate arrays (through the sampler's scratch),
//! stratified and progressive. The test binary holds this one test, so no other test
//! allocates while it counts. The test thread joins the pool first
//! (`strata_join_thread_pool`), as a host's frame thread should: from a thread outside
//! the pool, each call hands its work over through rayon's queue, which allocates a
//! block every 63 calls.

#![allow(unsafe_code)] // Calls through the C interface; each block says why it holds.

mod common;

use std::alloc::System;

use stats_alloc::{INSTRUMENTED_SYSTEM, StatsAlloc};

use common::*;
use strata::sample::{STRATA_PROGRESSIVE, STRATA_STRATIFIED, StrataSample};

/// The system allocator, counting allocations and reallocations.
#[global_allocator]
static GLOBAL: &StatsAlloc<System> = &INSTRUMENTED_SYSTEM;

/// Allocations so far, reallocations included.
fn allocations() -> usize {
    let stats = GLOBAL.stats();
    stats.allocations + stats.reallocations
}

#[test]
fn sampling_calls_allocate_nothing_in_steady_state() {
    let mut threads = 0;
    // SAFETY: a writable count.
    ok(unsafe { strata::strata_join_thread_pool(&mut threads) });
    assert!(threads >= 2, "the test thread and at least one worker");
    // SAFETY: as above; a second call is refused.
    let again = unsafe { strata::strata_join_thread_pool(std::ptr::null_mut()) };
    assert_eq!(again, strata::StrataStatus::InvalidArgument);
    let sampler = sphere_sampler(8);
    let n = 10_000;
    let mut recs = vec![StrataSample::default(); n];
    let (mut pos, mut nor, mut faces) = (vec![0f32; 3 * n], vec![0f32; 3 * n], vec![0u32; n]);
    let mut with_records = output(n);
    with_records.records = recs.as_mut_ptr();
    let mut with_arrays = output(n);
    with_arrays.positions = pos.as_mut_ptr();
    with_arrays.normals = nor.as_mut_ptr();
    with_arrays.face_ids = faces.as_mut_ptr();
    for (mode, out) in [
        (STRATA_STRATIFIED, &with_records),
        (STRATA_STRATIFIED, &with_arrays),
        (STRATA_PROGRESSIVE, &with_arrays),
        (STRATA_PROGRESSIVE, &with_records),
    ] {
        // Warm up: the thread pool starts, the scratch grows to the count.
        for seed in 0..3 {
            ok(sample(sampler, &request(mode, n, seed, 0), out));
        }
        let before = allocations();
        for seed in 0..20 {
            let count = n - seed as usize * 100;
            ok(sample(sampler, &request(mode, count, seed, 0), out));
        }
        let allocations = allocations() - before;
        assert_eq!(allocations, 0, "mode {mode}: allocations in 20 calls");
    }
    // The counter does count: a failing call allocates its message.
    let before = allocations();
    let status = sample(sampler, &request(7, n, 0, 0), &with_records);
    assert_ne!(status, strata::StrataStatus::Ok);
    assert!(allocations() > before);
    ok(free_sampler(sampler));
}
