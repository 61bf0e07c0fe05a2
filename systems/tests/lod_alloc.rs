//! A level-of-detail pool that lists ranks only (`Placement::Elsewhere`, the pool a
//! GPU-placed copy is synced from) allocates per frame no more than the pool that
//! places its entries on the CPU, and nothing once warm (the per-chunk lists of its
//! parallel listing sized by the frames before): a counting global allocator around
//! the system's, both pools updated along the same orbit, listing the same ranks. The
//! binary holds this one test, so no other test allocates while it counts.

use std::alloc::System;

use glam::DVec3;
use stats_alloc::{INSTRUMENTED_SYSTEM, Region, StatsAlloc};
use strata_engine::fixtures::lod::view;
use strata_engine::fixtures::torus_sampler;
use strata_engine::sample::lod::{Budget, LodPool, Placement, PoolChange};

/// The system allocator, counting allocations and reallocations.
#[global_allocator]
static GLOBAL: &StatsAlloc<System> = &INSTRUMENTED_SYSTEM;

/// Allocations (reallocations included) while `f` runs, and its result.
fn counted<T>(f: impl FnOnce() -> T) -> (usize, T) {
    let region = Region::new(GLOBAL);
    let out = f();
    let change = region.change();
    (change.allocations + change.reallocations, out)
}

#[test]
fn a_ranks_only_pool_allocates_no_more_than_a_placing_one() {
    let s = torus_sampler();
    let (seed, base, prefix) = (4, 10_000.0, 80_000);
    let room = 4_000_000;
    let mut placed = LodPool::new(&s, seed, prefix, room).with_splitting(false);
    let mut listed =
        LodPool::new_with(&s, seed, (prefix, room), Placement::Elsewhere).with_splitting(false);
    // An orbit, a degree a frame: every frame appends entries, within the room
    // reserved up front (as many entries again as the prefix).
    let eye = |t: i32| {
        let a = f64::from(t).to_radians();
        DVec3::new(1.6 * a.sin(), 0.4, 1.6 * a.cos())
    };
    let (mut totals, mut appended) = ([0; 2], 0);
    for t in -150..20 {
        let v = view(eye(t), 10.0);
        let (a, update) = counted(|| placed.update(&s, &v, Budget::Base(base)));
        let update = update.expect("the pool's sampler");
        let (b, same) = counted(|| listed.update(&s, &v, Budget::Base(base)));
        assert_eq!(same.expect("the pool's sampler"), update, "frame {t}");
        assert_eq!(placed.ranks(), listed.ranks(), "frame {t}");
        if t >= 0 {
            totals[0] += a;
            totals[1] += b;
            if let PoolChange::Appended(r) = update.change {
                appended += r.len();
            }
        }
    }
    assert!(appended > 1000, "the dolly appended {appended} entries");
    assert!(totals[1] <= totals[0], "{totals:?}");
    assert_eq!(totals[1], 0, "allocations of the warm ranks-only pool");
}
