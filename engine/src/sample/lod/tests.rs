//! Tests of the level-of-detail pool's parts through the pool: the splits of its bins
//! and the point budget's estimate of views.

use glam::DVec3;

use super::split::{SPLIT_ROOM, SPLIT_WAYS};
use super::{LodError, LodPool, PoolChange, ViewLod};
use crate::fixtures::lod::{Frame, check_held, held_visible, moved};
use crate::fixtures::torus_sampler;
use crate::mesh::TriMesh;
use crate::sample::faces::position_normal;
use crate::sample::{SampleSite, Sampler};

/// The splits of close views.
mod splits {
    use super::*;

    /// The clamp of the views' multiplier (far above a close view's), and the base
    /// count: 0.05 above the torus the nearest bins ask for about 2 x 10^8 ranks, some
    /// ten thousand in each (splits need 1024).
    const MAX: f64 = 1e5;
    const BASE: f64 = 10_000.0;

    /// The clip-from-world matrix of a camera at `eye` looking at `target`, `up` up,
    /// with vertical field of view `fov` (radians), a square image.
    fn clip(eye: DVec3, target: DVec3, up: DVec3, fov: f64) -> glam::DMat4 {
        let proj = glam::dcamera::rh::proj::directx::perspective(fov, 1.0, 1e-3, 100.0);
        proj * glam::dcamera::rh::view::look_at_mat4(eye, target, up)
    }

    /// A camera `distance` above the torus's highest vertex (lowest: `below`) along its
    /// normal, looking at it, its multiplier clamped at [`MAX`].
    fn close_view(s: &Sampler, distance: f64, below: bool) -> ViewLod {
        let mesh = s.mesh();
        let height = |p: &DVec3| if below { -p.z } else { p.z };
        let (i, &p) = mesh
            .positions()
            .iter()
            .enumerate()
            .max_by(|a, b| height(a.1).total_cmp(&height(b.1)))
            .expect("vertices");
        let eye = p + mesh.vertex_normals()[i] * distance;
        let fov = 50f64.to_radians();
        ViewLod {
            clip_from_world: clip(eye, p, DVec3::Y, fov),
            eye,
            focal_pixels: 500.0 / (2.0 * (fov / 2.0).tan()),
            reference: 5000.0,
            max: MAX,
            cull_back_faces: true,
        }
    }

    #[test]
    fn a_close_view_splits_bins_and_holds_fewer_ranks_showing_the_same_samples() {
        let s = torus_sampler();
        let (seed, base) = (6, BASE);
        let mut split = LodPool::new(&s, seed, 0, usize::MAX / 4);
        let mut whole = split.clone().with_splitting(false);
        assert!(split.splitting() && !whole.splitting());
        let roots = split.bins();
        // A dolly in towards the surface.
        for (t, distance) in [0.4, 0.2, 0.1, 0.05, 0.03].into_iter().enumerate() {
            let v = close_view(&s, distance, false);
            let before = split.len();
            let change = split.frame(&s, &v, base);
            whole.frame(&s, &v, base);
            assert!(
                change == PoolChange::Unchanged
                    || change == PoolChange::Appended(before..split.len()),
                "step {t}: {change:?}"
            );
            assert!(
                split.complete(&v, base) && whole.complete(&v, base),
                "step {t}"
            );
            let shown = held_visible(&split, &s, &v, base);
            assert!(shown.len() > 1000, "step {t}: {}", shown.len());
            assert_eq!(shown, held_visible(&whole, &s, &v, base), "step {t}");
            check_held(&split, &s, 1);
            // A child's bound is within its parent's, and it reaches at least as far.
            for (parent, children) in split.groups() {
                let p = *parent as usize;
                for c in children.start as usize..children.end as usize {
                    assert!(split.bounded_multiplier(c) <= split.bounded_multiplier(p));
                    assert!(split.reach(c) >= split.reach(p));
                    let (segment, leaves) = split.bin(c);
                    assert_eq!(segment, split.bin(p).0);
                    assert!(
                        split.bin(p).1.start <= leaves.start && leaves.end <= split.bin(p).1.end
                    );
                }
            }
        }
        assert_eq!(whole.bins(), roots);
        assert!(split.bins() > roots + 100, "{} bins", split.bins());
        assert!(split.bins() <= roots * SPLIT_ROOM);
        assert!(
            (split.len() as f64) < 0.6 * whole.len() as f64,
            "{} entries split, {} whole",
            split.len(),
            whole.len()
        );
    }

    #[test]
    fn at_its_limit_the_pool_stops_splitting_and_still_shows_every_sample() {
        let s = torus_sampler();
        let base = BASE;
        let unlimited = LodPool::new(&s, 8, 0, usize::MAX / 4);
        let roots = unlimited.bins();
        // Room for two splits of eight children, not for a third.
        let limit = roots + 2 * SPLIT_WAYS + SPLIT_WAYS / 2;
        let mut capped = unlimited.clone().with_max_bins(limit);
        let mut whole = unlimited.clone().with_splitting(false);
        let mut unlimited = unlimited;
        assert!(capped.splitting() && !whole.splitting() && capped.max_bins() == limit);
        // A dolly in towards the top of the ring, then a close view of its bottom,
        // which would split bins of its own.
        let views = [0.2, 0.1, 0.05, 0.03]
            .map(|d| close_view(&s, d, false))
            .into_iter()
            .chain([close_view(&s, 0.03, true)]);
        for (t, v) in views.enumerate() {
            for pool in [&mut capped, &mut whole, &mut unlimited] {
                let before = pool.len();
                let change = pool.frame(&s, &v, base);
                assert!(
                    change == PoolChange::Unchanged
                        || change == PoolChange::Appended(before..pool.len()),
                    "step {t}: {change:?}"
                );
                assert!(pool.complete(&v, base), "step {t}");
            }
            assert!(capped.bins() <= limit, "step {t}: {} bins", capped.bins());
            let shown = held_visible(&capped, &s, &v, base);
            assert!(shown.len() > 1000, "step {t}: {}", shown.len());
            assert_eq!(shown, held_visible(&whole, &s, &v, base), "step {t}");
            assert_eq!(shown, held_visible(&unlimited, &s, &v, base), "step {t}");
            check_held(&capped, &s, 1);
        }
        // The limit held: two splits made, where the unlimited pool made many.
        assert_eq!(capped.groups().len(), 2);
        assert!(capped.bins() > roots + SPLIT_WAYS);
        assert!(
            unlimited.groups().len() > 10,
            "{}",
            unlimited.groups().len()
        );
        // The splits made are the unlimited pool's first.
        assert_eq!(capped.groups()[..], unlimited.groups()[..2]);
        // A lower limit keeps the splits made until a rebuild.
        let lowered = capped.clone().with_max_bins(roots);
        assert!(!lowered.splitting());
        assert_eq!(lowered.bins(), capped.bins());
    }

    #[test]
    fn splits_are_the_same_for_any_thread_count() {
        let s = torus_sampler();
        let run = |threads: usize| {
            let workers = rayon::ThreadPoolBuilder::new().num_threads(threads).build();
            workers.expect("threads").install(|| {
                let mut pool = LodPool::new(&s, 2, 0, usize::MAX / 4);
                for distance in [0.2, 0.05, 0.03] {
                    pool.frame(&s, &close_view(&s, distance, false), BASE);
                }
                pool
            })
        };
        let (one, three) = (run(1), run(3));
        assert!(one.bins() > one.roots());
        assert_eq!(one.groups(), three.groups());
        assert_eq!(one.ranks(), three.ranks());
        assert_eq!(one.sites(), three.sites());
    }

    #[test]
    fn a_rebuild_drops_the_splits_and_a_deformation_rebounds_them() {
        let s = torus_sampler();
        let base = BASE;
        // Close views of the top and the bottom of the ring.
        let (near, side) = (close_view(&s, 0.05, false), close_view(&s, 0.05, true));
        let needed = [near, side].map(|v| {
            let mut probe = LodPool::new(&s, 4, 0, usize::MAX / 4);
            probe.frame(&s, &v, base);
            probe.len()
        });
        // Room for either view, not for both.
        let room = needed[0].max(needed[1]) * 5 / 4;
        assert!(room < needed[0] + needed[1], "{needed:?}");
        let mut pool = LodPool::new(&s, 4, 0, room);
        pool.frame(&s, &near, base);
        let split = pool.bins();
        assert!(split > pool.roots());
        assert_eq!(pool.frame(&s, &side, base), PoolChange::Rebuilt);
        assert!(pool.complete(&side, base));
        // The splits of the first view are gone: those of the second alone are left.
        let mut fresh = LodPool::new(&s, 4, 0, usize::MAX / 4);
        fresh.frame(&s, &side, base);
        assert_eq!(pool.groups(), fresh.groups());
        check_held(&pool, &s, 1);
        // Splits made on a deformed mesh are bounded on it.
        let tall = moved(s.mesh(), |p| DVec3::new(p.x, p.y, 1.5 * p.z));
        let mut bent = LodPool::new(&s, 4, 0, usize::MAX / 4);
        bent.set_geometry(&s, &tall).expect("same topology");
        // The close view of the stretched torus's top, 0.05 above it.
        let top = tall
            .positions()
            .iter()
            .copied()
            .max_by(|a, b| a.z.total_cmp(&b.z));
        let top = top.expect("vertices");
        let eye = top + DVec3::Z * 0.05;
        let v = ViewLod {
            eye,
            clip_from_world: clip(eye, top, DVec3::Y, 50f64.to_radians()),
            ..near
        };
        bent.frame(&s, &v, base);
        assert!(bent.bins() > bent.roots(), "no split");
        // The first ranks each child holds, placed on the stretched torus.
        let mut checked = 0;
        for (_, children) in bent.groups() {
            for c in children.start as usize..children.end as usize {
                let (segment, leaves) = bent.bin(c);
                let mut ranks = Vec::new();
                s.progressive_ranks_in_leaves(
                    4,
                    segment,
                    leaves,
                    0,
                    bent.reach(c),
                    500,
                    &mut ranks,
                );
                let mut sites = vec![SampleSite::default(); ranks.len()];
                s.progressive_sites_of(4, &ranks, &mut sites);
                for site in sites {
                    let (p, n) =
                        position_normal(&tall, site.face, site.barycentric().map(f64::from));
                    let m = v.multiplier(p, n);
                    assert!(m <= bent.bound(c, &v) * (1.0 + 1e-9));
                    checked += usize::from(m > 0.0);
                }
            }
        }
        assert!(checked > 100, "{checked}");
    }
}

/// The point budget's estimate, refined in the pool's bins.
mod estimates {
    use super::*;
    use crate::fixtures::lod::{close_view, count, culled_view as view, multipliers};
    use crate::sample::lod::{IN_VIEW, PROBES, REFINE_LIMIT};

    /// The samples `pool` shows under `v` with base `base`, once it holds them all.
    fn shown(pool: &mut LodPool, s: &Sampler, v: &ViewLod, base: f64) -> usize {
        pool.frame(s, v, base);
        assert!(pool.complete(v, base));
        let mut fades = vec![0.0; pool.len()];
        pool.fades_into(s, v, base, &mut fades);
        fades.iter().filter(|&&f| f > 0.0).count()
    }

    #[test]
    fn the_estimate_is_close_to_the_visible_count() {
        let s = torus_sampler();
        let mut pool = LodPool::new(&s, 7, 0, 1 << 22);
        // Far and near, from above and from the side, part of the torus out of view.
        for (eye, target) in [
            (DVec3::new(0.0, 3.0, 3.0), DVec3::ZERO),
            (DVec3::new(2.5, 0.5, 0.0), DVec3::ZERO),
            (DVec3::new(1.6, 0.6, 0.6), DVec3::new(1.0, 0.0, 0.0)),
        ] {
            let v = view(eye, target);
            let estimate = pool.mean_multiplier(&s, &v).expect("the pool\'s sampler");
            // A base under which at most max * base ranks can show: the scan covers them.
            let base = 20_000.0;
            let exact = count(&s, 7, (base * v.max) as u32 + 1, &v, base) as f64;
            let guess = base * estimate.mean;
            assert!(exact > 1000.0, "{eye}: {exact} shown");
            assert!(
                (guess / exact - 1.0).abs() < 0.03,
                "{eye}: estimate {guess} against {exact} ({estimate:?})"
            );
            let b = pool
                .base_for_shown(&s, &v, exact)
                .expect("the pool\'s sampler")
                .expect("in view");
            assert!((b / base - 1.0).abs() < 0.03, "{eye}: base {b}");
            // A smaller budget, a proportionally smaller base.
            let half = pool
                .base_for_shown(&s, &v, exact / 2.0)
                .expect("the pool\'s sampler")
                .expect("in view");
            assert!((half / b - 0.5).abs() < 1e-12);
        }
    }

    #[test]
    fn a_close_view_refines_the_estimate() {
        let s = torus_sampler();
        let mut pool = LodPool::new(&s, 7, 0, 1 << 22);
        for distance in [0.05, 0.02] {
            let v = close_view(&s, distance);
            let probes = pool.shown_estimate().probe(&v);
            let estimate = pool.mean_multiplier(&s, &v).expect("the pool\'s sampler");
            assert!(probes.in_view < 100, "{distance}: {probes:?}");
            assert!(estimate.ranks > PROBES as u64 && estimate.evaluated > 0);
            assert!(
                estimate.evaluated <= REFINE_LIMIT,
                "{distance}: {estimate:?}"
            );
            // Refined to IN_VIEW ranks in view (0.05), or until the next doubling would
            // pass the limit (0.02: the view sees a small part of its bins).
            assert!(
                estimate.in_view >= IN_VIEW || estimate.evaluated > REFINE_LIMIT / 2,
                "{distance}: {estimate:?}"
            );
            // The budget is shown, within 3%, where the probes alone are far off.
            let budget = 20_000.0;
            let base = pool
                .base_for_shown(&s, &v, budget)
                .expect("the pool\'s sampler")
                .expect("in view");
            let exact = shown(&mut pool, &s, &v, base) as f64;
            assert!(
                (exact / budget - 1.0).abs() < 0.03,
                "{distance}: {exact} shown for {budget} ({estimate:?})"
            );
            let guess = probes.mean * base;
            assert!(
                (guess / exact - 1.0).abs() > 0.1,
                "{distance}: the probes alone guess {guess} against {exact}"
            );
            // The same view again: the kept estimate.
            assert_eq!(
                pool.mean_multiplier(&s, &v).expect("the pool\'s sampler"),
                estimate
            );
        }
    }

    #[test]
    fn the_refined_estimate_is_the_mean_over_a_prefix_for_any_thread_count() {
        let s = torus_sampler();
        let v = close_view(&s, 0.3);
        let on = |threads: usize| {
            let workers = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("thread pool");
            workers.install(|| {
                LodPool::new(&s, 7, 0, 1 << 20)
                    .mean_multiplier(&s, &v)
                    .expect("the pool\'s sampler")
            })
        };
        let estimate = on(1);
        assert_eq!(on(3), estimate, "bit for bit");
        assert!(estimate.ranks > PROBES as u64 && estimate.ranks <= 1 << 20);
        let lods = multipliers(&s, 7, estimate.ranks as u32, &v);
        let mean = lods.iter().sum::<f64>() / lods.len() as f64;
        // The same ranks, summed in another order.
        assert!(
            (estimate.mean / mean - 1.0).abs() < 1e-12,
            "{estimate:?} against {mean}"
        );
        let in_view = lods.iter().filter(|&&m| m > 0.0).count();
        assert_eq!(estimate.in_view, in_view);
        // One fewer doubling would have seen fewer than IN_VIEW.
        let half = estimate.ranks as usize / 2;
        assert!(lods[..half].iter().filter(|&&m| m > 0.0).count() < IN_VIEW);
    }

    #[test]
    fn kept_sites_change_the_cost_never_the_estimate() {
        let s = torus_sampler();
        let mut pool = LodPool::new(&s, 7, 0, 1 << 20);
        let far = close_view(&s, 0.3);
        let first = pool.mean_multiplier(&s, &far).expect("the pool\'s sampler");
        assert_eq!(first.placed, first.evaluated);
        assert!(first.evaluated > 0);
        // A camera coming nearer, 3% a step, then back: each estimate equals a fresh
        // pool's, bit for bit; a step that averages as many ranks as the last reads
        // most of its sites from the last one.
        let (mut last, mut same) = (first, 0);
        for step in (1..16).chain([0]) {
            let v = close_view(&s, 0.3 * 0.97f64.powi(step));
            let estimate = pool.mean_multiplier(&s, &v).expect("the pool\'s sampler");
            let fresh = LodPool::new(&s, 7, 0, 1 << 20)
                .mean_multiplier(&s, &v)
                .expect("the pool\'s sampler");
            assert_eq!(
                (estimate.mean.to_bits(), estimate.ranks, estimate.in_view),
                (fresh.mean.to_bits(), fresh.ranks, fresh.in_view),
                "{step}"
            );
            assert_eq!(estimate.evaluated, fresh.evaluated);
            assert_eq!(fresh.placed, fresh.evaluated);
            if step > 0 && estimate.ranks == last.ranks {
                assert!(
                    estimate.placed * 4 < estimate.evaluated,
                    "{step}: {estimate:?}"
                );
                same += 1;
            }
            last = estimate;
        }
        assert!(same >= 8, "{same} steps at the same doubling");
    }

    #[test]
    fn a_view_of_nothing_has_no_base() {
        let s = torus_sampler();
        let mut pool = LodPool::new(&s, 7, 0, 1 << 20);
        let away = view(DVec3::new(0.0, 0.0, 3.0), DVec3::new(0.0, 0.0, 6.0));
        let estimate = pool
            .mean_multiplier(&s, &away)
            .expect("the pool\'s sampler");
        assert_eq!(
            (estimate.mean, estimate.evaluated),
            (0.0, 0),
            "{estimate:?}"
        );
        assert_eq!(pool.base_for_shown(&s, &away, 1e6), Ok(None));
        // A tiny multiplier: the base is capped at the sequence's length.
        let far = ViewLod {
            reference: 1e300,
            ..view(DVec3::new(0.0, 3.0, 3.0), DVec3::ZERO)
        };
        assert_eq!(
            pool.base_for_shown(&s, &far, 1e6),
            Ok(Some(4_294_967_296.0))
        );
    }

    #[test]
    fn deformed_probes_follow_the_mesh() {
        let s = torus_sampler();
        let mut pool = LodPool::new(&s, 7, 0, 1 << 20);
        let v = view(DVec3::new(0.0, 3.0, 3.0), DVec3::ZERO);
        let before = pool
            .mean_multiplier(&s, &v)
            .expect("the pool\'s sampler")
            .mean;
        let base = pool
            .base_for_shown(&s, &v, 1e4)
            .expect("the pool\'s sampler")
            .expect("in view");
        // The torus moved away from the camera: it shows less.
        let rest = s.mesh();
        let shift = DVec3::new(0.0, 1.0, 1.0);
        let shifted: Vec<DVec3> = rest.positions().iter().map(|&p| p - shift).collect();
        let moved = TriMesh::new(shifted, rest.triangles().to_vec()).expect("mesh");
        pool.set_geometry(&s, &moved).expect("same topology");
        let after = pool
            .mean_multiplier(&s, &v)
            .expect("the pool\'s sampler")
            .mean;
        assert!(after < 0.8 * before, "{after} against {before}");
        // The kept estimate of the view is dropped with the old geometry.
        let moved_base = pool
            .base_for_shown(&s, &v, 1e4)
            .expect("the pool\'s sampler")
            .expect("in view");
        assert!((moved_base * after / (base * before) - 1.0).abs() < 1e-12);
        // The refinement follows the moved surface: a close view moved with it sees
        // what it saw on the rest geometry bounded alike (up to rounding).
        let near = close_view(&s, 0.05);
        let near_moved = ViewLod {
            clip_from_world: near.clip_from_world * glam::DMat4::from_translation(shift),
            eye: near.eye - shift,
            ..near
        };
        let close_moved = pool
            .mean_multiplier(&s, &near_moved)
            .expect("the pool\'s sampler");
        let mut at_rest = LodPool::new(&s, 7, 0, 1 << 20);
        at_rest.set_geometry(&s, rest).expect("the rest mesh");
        let close = at_rest
            .mean_multiplier(&s, &near)
            .expect("the pool\'s sampler");
        assert!(close.evaluated > 0 && close_moved.ranks == close.ranks);
        assert_eq!(close_moved.in_view, close.in_view);
        assert!((close_moved.mean / close.mean - 1.0).abs() < 1e-9);
        // Moved back (the probes' columns and the bins' bounds rewritten in place): the
        // same bits as the pool set on the rest mesh once.
        pool.set_geometry(&s, rest).expect("the rest mesh");
        let probes = |p: &LodPool| p.shown_estimate().mean_multiplier(&v).to_bits();
        assert_eq!(probes(&pool), probes(&at_rest));
        assert_eq!(pool.bins(), at_rest.bins());
        for b in 0..pool.bins() {
            assert_eq!(pool.bound(b, &v).to_bits(), at_rest.bound(b, &v).to_bits());
        }
        pool.set_geometry(&s, &moved).expect("same topology");
        let other = TriMesh::new(vec![DVec3::ZERO, DVec3::X, DVec3::Y], vec![[0, 1, 2]])
            .expect("a triangle");
        assert!(matches!(
            pool.shown_estimate().clone().set_geometry(&s, &other),
            Err(LodError::Mismatch { .. })
        ));
        assert!(matches!(
            pool.set_geometry(&s, &other),
            Err(LodError::Mismatch { .. })
        ));
        assert_eq!(
            pool.mean_multiplier(&s, &v)
                .expect("the pool\'s sampler")
                .mean,
            after
        );
    }
}

/// Pools that place their entries on the CPU and pools that list ranks only.
mod placement {
    use super::*;
    use crate::fixtures::lod::{close_view, view, view_at};
    use crate::sample::lod::{Budget, FrameUpdate, Placement};

    /// One update of both pools: the same change and base count, the same ranks in
    /// the same order, the same bins and reaches; the placing pool's sites are its
    /// ranks' (every `step`-th checked), the other holds none.
    fn step(
        (placed, listed): (&mut LodPool, &mut LodPool),
        s: &Sampler,
        v: &ViewLod,
        budget: Budget,
    ) -> FrameUpdate {
        let update = placed.update(s, v, budget).expect("the pool's sampler");
        assert_eq!(listed.update(s, v, budget).expect("the same"), update);
        assert_eq!(placed.ranks(), listed.ranks());
        assert_eq!(
            (placed.len(), listed.len()),
            (placed.ranks().len(), placed.len())
        );
        assert!(listed.sites().is_empty());
        assert_eq!(placed.bins(), listed.bins());
        assert!((0..placed.bins()).all(|b| placed.reach(b) == listed.reach(b)));
        let (ranks, sites): (Vec<u32>, Vec<SampleSite>) = (placed.ranks().iter())
            .zip(placed.sites())
            .step_by(37)
            .map(|(&k, &site)| (k, site))
            .unzip();
        let mut expected = vec![SampleSite::default(); ranks.len()];
        s.progressive_sites_of(placed.seed(), &ranks, &mut expected);
        assert_eq!(sites, expected);
        update
    }

    #[test]
    fn a_pool_that_places_nothing_lists_the_placing_pools_entries() {
        let s = torus_sampler();
        let (seed, prefix, base) = (6, 5_000, 5_000.0);
        // Room for a close view of one side, not for two: appends, a rebuild, and a
        // view served in bin order until the budget is spent.
        let near = view_at(DVec3::new(1.0, 0.0, 1.2), DVec3::X, 50.0);
        let other = view_at(DVec3::new(-1.0, 0.0, 1.2), -DVec3::X, 50.0);
        let mut probe = LodPool::new(&s, seed, prefix, usize::MAX / 4);
        probe.frame(&s, &near, base);
        let room = (probe.len() - prefix as usize) * 5 / 4;
        let mut placed = LodPool::new(&s, seed, prefix, room);
        let mut listed = LodPool::new_with(&s, seed, (prefix, room), Placement::Elsewhere);
        assert_eq!(
            (placed.placement(), listed.placement()),
            (Placement::Cpu, Placement::Elsewhere)
        );
        let mut path: Vec<(ViewLod, Budget)> = Vec::new();
        // A dolly in, an orbit, a growing count, a point budget.
        for t in 0..6 {
            let d = 4.0 * 0.85f64.powi(t);
            path.push((view(DVec3::new(0.3, 0.1, d), 10.0), Budget::Base(base)));
        }
        for t in 0..6 {
            let a = f64::from(t) * 0.05;
            let eye = DVec3::new(2.0 * a.sin(), 0.2, 2.0 * a.cos());
            path.push((
                view(eye, 10.0),
                Budget::Base(base * (1.0 + 0.1 * f64::from(t))),
            ));
        }
        for shown in [2_000, 8_000, 30_000] {
            path.push((close_view(&s, 0.3), Budget::new(base, Some(shown))));
        }
        let greedy = view_at(DVec3::new(1.0, 0.0, 0.7), DVec3::X, 1e6);
        path.extend([near, other, greedy, greedy].map(|v| (v, Budget::Base(base))));
        let mut seen = [0; 3];
        for (v, budget) in &path {
            let update = step((&mut placed, &mut listed), &s, v, *budget);
            seen[match update.change {
                PoolChange::Unchanged => 0,
                PoolChange::Appended(_) => 1,
                PoolChange::Rebuilt => 2,
            }] += 1;
        }
        assert!(seen.iter().all(|&n| n > 0), "{seen:?}");
        assert!(!listed.complete(&greedy, base));
        // A deformed surface, and close views that split bins.
        let tall = moved(s.mesh(), |p| DVec3::new(p.x, p.y, 1.5 * p.z));
        placed.set_geometry(&s, &tall).expect("same topology");
        listed.set_geometry(&s, &tall).expect("same topology");
        let roots = placed.bins();
        for d in [0.4, 0.2, 0.1] {
            let v = ViewLod {
                max: 1e4,
                ..close_view(&s, d)
            };
            step((&mut placed, &mut listed), &s, &v, Budget::Base(base));
        }
        assert!(listed.bins() > roots, "no split");
        check_held(&listed, &s, 1);
        // The reference cull places the listed pool's entries itself.
        let v = view(DVec3::new(0.3, 0.1, 2.0), 10.0);
        let mut fades = [vec![0.0; placed.len()], vec![0.0; listed.len()]];
        placed.fades_into(&s, &v, base, &mut fades[0]);
        listed.fades_into(&s, &v, base, &mut fades[1]);
        assert_eq!(fades[0], fades[1]);
        assert!(fades[1].iter().any(|&f| f > 0.0));
        // A clone keeps the mode.
        assert_eq!(listed.clone().placement(), Placement::Elsewhere);
    }
}

/// The fused survey of the bins against separate passes over all of them.
mod survey {
    use super::*;
    use crate::fixtures::lod::{close_view, culled_view, view_at};
    use crate::sample::lod::{Budget, Placement};

    /// A generator of numbers in `[0, 1)` (a linear congruential one: the test needs
    /// a fixed, varied path, not quality).
    struct Walk(u64);

    impl Walk {
        fn next(&mut self) -> f64 {
            self.0 = (self.0.wrapping_mul(6_364_136_223_846_793_005))
                .wrapping_add(1_442_695_040_888_963_407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    #[test]
    fn a_random_camera_path_updates_the_pool_as_separate_passes_do() {
        let s = torus_sampler();
        let (seed, prefix) = (11, 4_000);
        // A roomy pool (appends, splits), and a tight one (the budget spent bin by
        // bin, rebuilds), each against its reference; one of them lists ranks only.
        let room = [usize::MAX / 4, 60_000];
        let mut pools: Vec<(LodPool, LodPool)> = room
            .iter()
            .enumerate()
            .map(|(i, &room)| {
                let placement = [Placement::Cpu, Placement::Elsewhere][i];
                let pool = LodPool::new_with(&s, seed, (prefix, room), placement);
                (pool.clone(), pool.with_full_scans())
            })
            .collect();
        let mut walk = Walk(0x5eed);
        // Spherical camera coordinates around the torus, a base count, a budget.
        let (mut azimuth, mut height, mut distance) = (0.3f64, 0.4f64, 3.0f64);
        let mut base = 5_000.0f64;
        let mut changes = [0usize; 3];
        let mut split = false;
        for frame in 0..160 {
            let r = walk.next();
            match (r * 6.0) as u32 {
                // Dollies of a few percent, in and out, down to close views.
                0 | 1 => distance = (distance * (0.9 + 0.2 * walk.next())).clamp(0.05, 6.0),
                // Orbits.
                2 => azimuth += 0.2 * (walk.next() - 0.5),
                3 => height = (height + 0.3 * (walk.next() - 0.5)).clamp(-1.2, 1.2),
                // The base count.
                4 => base *= 0.9 + 0.25 * walk.next(),
                // A jump elsewhere.
                _ => {
                    azimuth = 6.3 * walk.next();
                    distance = 0.1 + 3.0 * walk.next();
                }
            }
            let dir = DVec3::new(azimuth.cos(), height.sin(), azimuth.sin());
            let eye = DVec3::new(0.0, 0.0, 0.0) + dir * (1.0 + distance);
            let target = dir * 0.8 * walk.next();
            let v = if frame % 3 == 0 {
                view_at(eye, target, 1e3)
            } else if frame % 5 == 1 {
                // Close above the top: bins split.
                ViewLod {
                    max: 1e5,
                    ..close_view(&s, 0.03 + 0.3 * walk.next())
                }
            } else {
                ViewLod {
                    max: 1e4,
                    ..culled_view(eye, target)
                }
            };
            let budget = if frame % 7 == 6 {
                Budget::new(base, Some((2_000.0 + 20_000.0 * walk.next()) as u32))
            } else {
                Budget::Base(base)
            };
            for (fused, reference) in &mut pools {
                let update = fused.update(&s, &v, budget).expect("the pool's sampler");
                let expected = reference
                    .update(&s, &v, budget)
                    .expect("the pool's sampler");
                assert_eq!(update, expected, "frame {frame}");
                assert_eq!(fused.ranks(), reference.ranks(), "frame {frame}");
                assert_eq!(fused.sites(), reference.sites(), "frame {frame}");
                assert_eq!(fused.bins(), reference.bins(), "frame {frame}");
                let reach = |p: &LodPool| (0..p.bins()).map(|b| p.reach(b)).collect::<Vec<_>>();
                assert_eq!(reach(fused), reach(reference), "frame {frame}");
                split |= fused.bins() > fused.roots();
                changes[match update.change {
                    PoolChange::Unchanged => 0,
                    PoolChange::Appended(_) => 1,
                    PoolChange::Rebuilt => 2,
                }] += 1;
            }
        }
        // The path took every kind of update, and split bins.
        assert!(changes.iter().all(|&n| n > 0), "{changes:?}");
        assert!(split);
    }
}
