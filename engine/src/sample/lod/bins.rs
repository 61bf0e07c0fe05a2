//! Finer bins where a view asks for many ranks (issue 19).
//!
//! A pool's bins ([`LodPool`]) are about 16,384 runs of cells of equal measure, each
//! with one bound of a view's multiplier. Close to the surface a bin is wider than the
//! view's distance to it, and its bound (the multiplier at its nearest point) lies far
//! above the multiplier over most of it: 0.012 bounding radii above the bunny the pool
//! held 9.5 times the ranks the view showed, and drawing them was most of a close
//! frame's update.
//!
//! A bin whose need asks for many ranks (`need x share` at least [`SPLIT_ENTRIES`]) and
//! whose bound is loose (at least [`SPLIT_LOOSE`] times the multiplier at its centre)
//! is therefore split into [`SPLIT_WAYS`] children: runs of its cells of about equal
//! measure, each with its own tight bound (the lesser of its own and its parent's:
//! both bound it), its own rank cover, and the parent's reach. From then on the
//! children hold the parent's ranks and the parent needs none; a child can split
//! again. A split is kept until the pool is rebuilt (merging children that reach
//! different ranks would list some ranks twice), and the bins stop splitting at
//! [`SPLIT_ROOM`] times the roots (or the limit
//! [`with_max_bins`](LodPool::with_max_bins) sets), so that the bounds of an update
//! stay within a few times their cost.
//!
//! Splits change which ranks the pool holds, never which are visible: the roots still
//! partition the surface (the point budget's refinement enumerates ranks in them), and
//! every bin still holds every rank below its reach. Which bins split depends on the
//! views and base counts of the updates only, in order, never on the thread count.

use std::ops::Range;

use rayon::prelude::*;

use crate::sample::Sampler;
use super::view::ViewLod;
use super::bounds::{Frustum, RegionBound, bin_bound};
use super::pool::{Bin, LodPool, need_of};

/// A bin splits when its need asks for at least this many ranks in it (its need times
/// its share of the measure).
pub const SPLIT_ENTRIES: f64 = 1024.0;

/// A bin splits when its bound is at least this many times the multiplier at its
/// sphere's centre with its cone's axis for normal: a bin wide next to its distance
/// to the eye, cut by the frustum or turning away from the eye. Tighter bins are
/// left whole: with the whole bunny in view at 10^6 samples, splitting every bin that
/// asked for 256 ranks, tight or not, saved 3% of the entries and doubled the update,
/// whose bounds it quadrupled.
pub const SPLIT_LOOSE: f64 = 2.0;

/// The children of a split: runs of the parent's cells of about equal measure (fewer
/// when it has fewer cells).
pub const SPLIT_WAYS: usize = 8;

/// By default the bins stop splitting at this many times the roots
/// ([`LodPool::with_max_bins`]).
pub const SPLIT_ROOM: usize = 4;

/// The cuts of `leaves` into at most `ways` non-empty runs of about equal measure, by
/// the curve's cumulative measure `cumulative` (`cumulative[i]` before leaf `i`).
fn cuts(cumulative: &[f64], leaves: Range<usize>, ways: usize) -> Vec<Range<usize>> {
    let ways = ways.min(leaves.len());
    let (lo, hi) = (cumulative[leaves.start], cumulative[leaves.end]);
    let mut runs = Vec::with_capacity(ways);
    let mut start = leaves.start;
    for j in 1..ways {
        let at = lo + (hi - lo) * j as f64 / ways as f64;
        // The first leaf boundary at or past `at`, or the one before it if nearer,
        // leaving a leaf for each run to come.
        let mut end = start + cumulative[start..leaves.end].partition_point(|&c| c < at);
        if end > start + 1 && at - cumulative[end - 1] < cumulative[end] - at {
            end -= 1;
        }
        let end = end.clamp(start + 1, leaves.end - (ways - j));
        runs.push(start..end);
        start = end;
    }
    runs.push(start..leaves.end);
    runs
}

/// Finer bins for close views: see the module docs.
impl LodPool {
    /// The same pool, splitting bins for close views or not (the default: it does,
    /// up to [`SPLIT_ROOM`] times the roots). Without splits a view close to the
    /// surface draws several times the ranks it shows; with them the bins' bounds cost
    /// up to [`SPLIT_ROOM`] times as much.
    pub fn with_splitting(self, splitting: bool) -> Self {
        let roots = self.roots;
        self.with_max_bins(if splitting { roots * SPLIT_ROOM } else { roots })
    }

    /// The same pool, its bins splitting until there are `max_bins` of them, the
    /// roots included (default [`SPLIT_ROOM`] times the roots; at most the roots, no
    /// bin splits). More bins hold fewer entries in views close to the surface, and
    /// each costs its bound in every view's update and estimate. Splits already made
    /// stay until the pool is rebuilt, whatever the new limit.
    pub fn with_max_bins(mut self, max_bins: usize) -> Self {
        self.max_bins = max_bins;
        self
    }

    /// Whether bins split for close views: the limit on the bins leaves room past the
    /// roots.
    pub fn splitting(&self) -> bool {
        self.max_bins > self.roots
    }

    /// The most bins splits may make, the roots included
    /// ([`with_max_bins`](Self::with_max_bins)).
    pub fn max_bins(&self) -> usize {
        self.max_bins
    }

    /// Lowers each split bin's children's bounds in `out` to their parent's, parents
    /// first (both bound a child: it lies inside its parent).
    pub(super) fn bound_by_parents(&self, out: &mut [f64]) {
        for (parent, children) in &self.groups {
            let bound = out[*parent as usize];
            for m in &mut out[children.start as usize..children.end as usize] {
                *m = m.min(bound);
            }
        }
    }

    /// Whether bin `b`, whose need asks for many ranks, splits under `view`.
    fn splits(&self, b: usize, view: &ViewLod) -> bool {
        !self.split[b] && self.bins[b].leaves.len() >= 2 && {
            let (centre, axis) = self.bounds.centre_axis(b);
            view.multiplier(centre, axis) * SPLIT_LOOSE <= self.multipliers[b]
        }
    }

    /// Splits the bins whose needs (of the last bounded view, base count `base`) ask
    /// for many ranks, and their children that do, while there is room: see the module
    /// docs. The children's bounds are computed in parallel.
    pub(super) fn split_for(&mut self, sampler: &Sampler, base: f64) {
        let Some(view) = self.bounded.filter(|_| self.splitting()) else {
            return;
        };
        let mut from = 0;
        loop {
            // Splits that fit however many children they make.
            let room = self.max_bins.saturating_sub(self.bins.len()) / SPLIT_WAYS;
            // The columns first, in one pass: most bins are far from asking for many
            // ranks, and a bin's record is a few cache lines.
            let wanted: Vec<usize> = (self.needs[from..].iter())
                .zip(&self.shares[from..])
                .enumerate()
                .filter(|(_, (need, share))| f64::from(**need) * **share >= SPLIT_ENTRIES)
                .map(|(i, _)| from + i)
                .filter(|&b| self.splits(b, &view))
                .take(room)
                .collect();
            if wanted.is_empty() {
                return;
            }
            from = self.bins.len();
            // Tight bounds on the sampler's mesh, quick ones on a deformation (as
            // `set_geometry` bounds the other bins).
            let (geometry, deformed) = self.estimate.vertices(sampler);
            let (tight, seed) = (!deformed, self.seed());
            let bins = &self.bins;
            let made: Vec<Vec<(Bin, f64, RegionBound)>> = wanted
                .par_iter()
                .map_init(Default::default, |buffers, &b| {
                    let (segment, leaves) = (bins[b].segment as usize, &bins[b].leaves);
                    let cumulative = sampler.segments()[segment].curve.cumulative();
                    let leaves = leaves.start as usize..leaves.end as usize;
                    cuts(cumulative, leaves, SPLIT_WAYS)
                        .into_iter()
                        .map(|run| {
                            let bound =
                                bin_bound(sampler, geometry, segment, run.clone(), tight, buffers);
                            let share = (cumulative[run.end] - cumulative[run.start])
                                / sampler.total_measure();
                            let cover = sampler.progressive_cover(seed, segment, run.clone());
                            let bin = Bin {
                                segment: segment as u32,
                                leaves: run.start as u32..run.end as u32,
                                cover,
                            };
                            (bin, share, bound)
                        })
                        .collect()
                })
                .collect();
            let frustum = Frustum::new(&view);
            for (&parent, children) in wanted.iter().zip(made) {
                let first = self.bins.len();
                for (bin, share, bound) in children {
                    self.bins.push(bin);
                    self.shares.push(share);
                    self.bounds.push(&bound);
                    self.reach.push(self.reach[parent]);
                    self.split.push(false);
                }
                let group = first as u32..self.bins.len() as u32;
                self.groups.push((parent as u32, group.clone()));
                self.split[parent] = true;
                self.needs[parent] = 0;
                // The children's bounds and needs under the bounded view.
                let bound = self.multipliers[parent];
                self.multipliers.resize(self.bins.len(), 0.0);
                let dst = &mut self.multipliers[first..];
                if bound > 0.0 {
                    self.bounds.multipliers_into(&frustum, first, dst);
                    dst.iter_mut().for_each(|m| *m = m.min(bound));
                }
                let needs = self.multipliers[first..].iter().map(|&m| need_of(base, m));
                self.needs.extend(needs);
                debug_assert_eq!(group.end as usize, self.needs.len());
            }
        }
    }

    /// Drops every split: the roots alone, as the pool was made (their reaches kept).
    pub(super) fn unsplit(&mut self) {
        let roots = self.roots;
        self.bins.truncate(roots);
        self.shares.truncate(roots);
        self.bounds.truncate(roots);
        self.reach.truncate(roots);
        self.needs.truncate(roots);
        self.multipliers.truncate(roots);
        self.split.clear();
        self.split.resize(roots, false);
        self.groups.clear();
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;
    use crate::sample::faces::position_normal;
    use crate::sample::lod::pool::tests::{check_held, held_visible, moved};
    use crate::sample::{PoolChange, SampleSite};
    use crate::surface::tests::torus_sampler;

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
    fn cuts_are_runs_of_about_equal_measure() {
        // Leaves of measure 1, 1, 1, 5, 1, 1, 1, 1, 1, 1 (cumulative from 0).
        let measure = [1.0, 1.0, 1.0, 5.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0];
        let cumulative: Vec<f64> = std::iter::once(0.0)
            .chain(measure.iter().scan(0.0, |c, m| {
                *c += m;
                Some(*c)
            }))
            .collect();
        let runs = cuts(&cumulative, 0..10, 4);
        assert_eq!(runs, vec![0..3, 3..4, 4..7, 7..10]);
        // Within a range, and never an empty run: three leaves give three runs.
        assert_eq!(cuts(&cumulative, 2..5, 8), vec![2..3, 3..4, 4..5]);
        assert_eq!(cuts(&cumulative, 4..10, 2), vec![4..7, 7..10]);
        assert_eq!(cuts(&cumulative, 5..6, 8), vec![5..6]);
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
            let change = split.update(&s, &v, base);
            whole.update(&s, &v, base);
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
            for (parent, children) in &split.groups {
                let p = *parent as usize;
                for c in children.start as usize..children.end as usize {
                    assert!(split.multipliers[c] <= split.multipliers[p]);
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
                let change = pool.update(&s, &v, base);
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
        assert_eq!(capped.groups.len(), 2);
        assert!(capped.bins() > roots + SPLIT_WAYS);
        assert!(unlimited.groups.len() > 10, "{}", unlimited.groups.len());
        // The splits made are the unlimited pool's first.
        assert_eq!(capped.groups[..], unlimited.groups[..2]);
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
                    pool.update(&s, &close_view(&s, distance, false), BASE);
                }
                pool
            })
        };
        let (one, three) = (run(1), run(3));
        assert!(one.bins() > one.roots);
        assert_eq!(one.groups, three.groups);
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
            probe.update(&s, &v, base);
            probe.len()
        });
        // Room for either view, not for both.
        let room = needed[0].max(needed[1]) * 5 / 4;
        assert!(room < needed[0] + needed[1], "{needed:?}");
        let mut pool = LodPool::new(&s, 4, 0, room);
        pool.update(&s, &near, base);
        let split = pool.bins();
        assert!(split > pool.roots);
        assert_eq!(pool.update(&s, &side, base), PoolChange::Rebuilt);
        assert!(pool.complete(&side, base));
        // The splits of the first view are gone: those of the second alone are left.
        let mut fresh = LodPool::new(&s, 4, 0, usize::MAX / 4);
        fresh.update(&s, &side, base);
        assert_eq!(pool.groups, fresh.groups);
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
        bent.update(&s, &v, base);
        assert!(bent.bins() > bent.roots, "no split");
        // The first ranks each child holds, placed on the stretched torus.
        let mut checked = 0;
        for (_, children) in &bent.groups {
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
