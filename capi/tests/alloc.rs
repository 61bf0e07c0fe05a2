//! No allocation per sampling call in steady state: a counting global allocator around
//! the system's, and `strata_sample` called again and again, with records (drawn into
//! the caller's buffer) and with separate arrays (through the sampler's scratch),
//! stratified and progressive. The test binary holds this one test, so no other test
//! allocates while it counts. The test thread joins the pool first
//! (`strata_join_thread_pool`), as a host's frame thread should: from a thread outside
//! the pool, each call hands its work over through rayon's queue, which allocates a
//! block every 63 calls.

#![allow(unsafe_code)] // A global allocator; each block says why it holds.

mod common;

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use common::*;
use strata::sample::{STRATA_PROGRESSIVE, STRATA_STRATIFIED, StrataSample};

/// The system allocator, counting allocations and reallocations.
struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

// SAFETY: every method forwards to `System` with the same arguments, so `System`'s
// guarantees hold; the counter has no effect on the memory returned.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: forwarded with the caller's layout (the caller upholds `alloc`'s
        // contract).
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` came from `System` through this allocator with `layout`.
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: as `dealloc`, with the caller's new size.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

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
        let before = ALLOCATIONS.load(Ordering::Relaxed);
        for seed in 0..20 {
            let count = n - seed as usize * 100;
            ok(sample(sampler, &request(mode, count, seed, 0), out));
        }
        let allocations = ALLOCATIONS.load(Ordering::Relaxed) - before;
        assert_eq!(allocations, 0, "mode {mode}: allocations in 20 calls");
    }
    // The counter does count: a failing call allocates its message.
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    let status = sample(sampler, &request(7, n, 0, 0), &with_records);
    assert_ne!(status, strata::StrataStatus::Ok);
    assert!(ALLOCATIONS.load(Ordering::Relaxed) > before);
    ok(free_sampler(sampler));
}
