//! A pool of progressive sample sites that grows where a view asks for more.
//!
//! A renderer that thresholds progressive ranks against a view's multiplier
//! ([`view`](super::view)) needs every rank `k < N lod(p_k)` at hand. The pool holds the
//! sites of ranks `0..P` (a prefix of the sequence, computed once: the rank of entry
//! `k < P` is `k`) and, beyond them, an extension of higher ranks drawn only where the
//! multiplier asks for them. The surface is cut into bins, about [`BINS`](super::BINS) runs of
//! consecutive cells of equal measure (a bin never spans two segments;
//! [`bins`](super::bins)). For each bin an upper bound of the multiplier, from a sphere
//! around the parts of the faces inside its cells and a cone around their normals
//! ([`bounds`](super::bounds), evaluated for all bins in one branch-free loop, and
//! skipped when only the base count changed), gives the rank it needs,
//! `ceil(N bound)`, and the ranks it lacks are enumerated in that bin alone
//! ([`Sampler::progressive_ranks_in_leaves`]) and placed there
//! ([`entries`](super::entries)), so an update costs in proportion to the bins plus the
//! new ranks. Bin `b` holds every rank below its [`reach`](LodPool::reach) that falls
//! in it.
//!
//! **Draw-ahead.** A moving camera raises the needed rank of thousands of bins by a
//! few ranks each per frame, and a rank drawn alone in its bin costs two to three
//! times one drawn among others (its cells are cold). A bin that lacks ranks is
//! therefore filled past its need, to `need (1 + a (1 + j))` with `a` the draw-ahead
//! fraction ([`DRAW_AHEAD`](super::DRAW_AHEAD), [`LodPool::with_draw_ahead`]) and `j` in `[0, 1)` drawn
//! per bin and per fill (so that bins filled in one frame run dry in different ones,
//! and stay apart): it is refilled every few frames, in batches. This changes which
//! ranks the pool holds, never which are visible: a renderer thresholds by rank.
//!
//! **Splits.** Close to the surface a bin is wider than its distance to the eye and its
//! bound far above the multiplier over most of it, so a bin that asks for many ranks
//! and whose bound is loose is split into finer bins, each with its own bound and
//! cover ([`split`](super::split)).
//!
//! **Point budget.** A [`Budget::Shown`] sets each frame's base count to the one under
//! which the view shows about that many samples ([`estimate`](super::estimate)).
//!
//! Entries are only ever appended, so a GPU copy of the pool is extended by streaming
//! the new tail ([`PoolChange::Appended`]). When the extension would outgrow its budget
//! and holds ranks the view no longer needs, even with its draw-ahead, it is rebuilt
//! for the current view ([`PoolChange::Rebuilt`]); when the current view alone needs
//! more than the budget, bins are served in order, without draw-ahead, until it is
//! spent and the rest keep the ranks they have ([`LodPool::complete`] says whether
//! every visible rank is held).
//!
//! Which ranks are visible, and where each lies, depend only on the seed, the view and
//! the ranks held, never on the path that led there: the pool's order of entries
//! differs with the path, the samples do not.
//!
//! **Placement.** By default the pool places every entry it lists on the CPU
//! ([`Placement::Cpu`]). A pool built with [`Placement::Elsewhere`]
//! ([`LodPool::new_with`]) lists the same ranks in the same order, with the same
//! bins, reaches and changes, and places none: whoever draws the samples places them
//! from the ranks and the seed (a GPU's progressive pass), and a frame's CPU cost is
//! the bins' bookkeeping plus the ranks' enumeration. Nothing the pool decides needs
//! its entries' positions (needs come from the bins' bounds, the point budget from
//! its own probes), so both modes decide alike.

use std::borrow::Cow;
use std::ops::Range;

use glam::DVec3;
use rayon::prelude::*;

use super::bins::Bins;
use super::entries::{Entries, Placement, PoolChange};
use super::estimate::{CLOSE_ROOM, IN_VIEW, MeanMultiplier, ShownEstimate};
use super::key::SamplerKey;
use super::split::SPLIT_ROOM;
use super::view::{LodError, ViewLod, check_deformation, fade};
use crate::mesh::TriMesh;
use crate::sample::{SampleSite, Sampler};

/// The base count a frame of [`LodPool::update`] thresholds with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Budget {
    /// This base count: the samples of the whole surface at multiplier 1.
    Base(f64),
    /// A point budget: the base count under which the view shows about `shown`
    /// samples ([`LodPool::base_for_shown`]), rounded to `f32` (what a GPU's uniform
    /// holds, so that the CPU's and the GPU's thresholds pick the same ranks); the
    /// base count `fallback` when nothing is in view.
    Shown {
        /// Samples the view should show.
        shown: u32,
        /// The base count of a view of nothing.
        fallback: f64,
    },
}

impl Budget {
    /// `base`, or with a point budget of `shown` samples the budget's base count (and
    /// `base` for a view of nothing).
    pub fn new(base: f64, shown: Option<u32>) -> Self {
        match shown {
            None => Self::Base(base),
            Some(shown) => Self::Shown {
                shown,
                fallback: base,
            },
        }
    }
}

/// What one [`LodPool::update`] did.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameUpdate {
    /// The entries that changed.
    pub change: PoolChange,
    /// The base count the frame thresholds with (a renderer draws with it).
    pub base: f64,
}

/// Progressive sample sites for one sampler and seed: a prefix of the sequence plus
/// ranks drawn per segment where views need them. See the module docs.
///
/// A frame is one call, [`update`](Self::update), with the sampler the pool was built
/// from (another sampler is refused: [`LodError::OtherSampler`]), the view and the
/// [`Budget`]; it returns what changed and the base count to threshold with.
///
/// ```
/// # use std::sync::Arc;
/// # use strata_engine::field::FieldSpec;
/// # use strata_engine::surface::{Preprocessed, SurfaceOptions};
/// use strata_engine::sample::lod::{Budget, LodPool, ViewLod};
///
/// # let mesh = Arc::new(strata_engine::mesh::shapes::sphere(1.0, 12).expect("sphere"));
/// # let field = FieldSpec::Constant { direction: [1.0, 0.0, 0.0], anisotropy: 2.0, density: 1.0 }
/// #     .build(&mesh).expect("field");
/// # let sampler = Preprocessed::build(mesh, Arc::new(field), &SurfaceOptions::default())
/// #     .expect("preprocessed").sampler;
/// // Ranks 0..10,000 of seed 7's sequence, room for 40,000 more.
/// let mut pool = LodPool::new(&sampler, 7, 10_000, 40_000);
/// let eye = glam::DVec3::new(0.0, 0.5, 3.0);
/// let proj = glam::dcamera::rh::proj::directx::perspective(0.8, 1.0, 0.01, 100.0);
/// let look = glam::dcamera::rh::view::look_at_mat4(eye, glam::DVec3::ZERO, glam::DVec3::Y);
/// let view = ViewLod {
///     clip_from_world: proj * look,
///     eye,
///     focal_pixels: 600.0,
///     reference: 2000.0,
///     max: 4.0,
///     cull_back_faces: true,
/// };
/// // Every frame: about 5,000 samples shown, whatever the distance.
/// let frame = pool.update(&sampler, &view, Budget::new(10_000.0, Some(5_000)))?;
/// assert!(pool.complete(&view, frame.base));
/// # Ok::<(), strata_engine::sample::lod::LodError>(())
/// ```
///
/// A clone keeps the original's room for more entries, its memory committed (as
/// [`new`](Self::new) commits it), so that it updates as the original would.
#[derive(Clone, Debug)]
pub struct LodPool {
    /// The sites and ranks held.
    entries: Entries,
    /// The bins, their bounds, needs and reaches.
    bins: Bins,
    /// The point budget's estimator, on the current geometry.
    estimate: ShownEstimate,
    /// The sampler the pool was built from.
    sampler: SamplerKey,
    /// The bins a refinement of the estimate draws in (kept, so that refinements stop
    /// allocating).
    live: Vec<u32>,
}

impl LodPool {
    /// The pool of `sampler`'s progressive sequence for `seed` holding ranks
    /// `0..prefix`, with room for `budget` more ranks drawn per segment, drawing ahead
    /// by [`DRAW_AHEAD`](super::DRAW_AHEAD). Memory: 20 bytes per entry. Room for `min(budget, prefix)`
    /// more entries is reserved and committed up front (written once, so that
    /// appending into it takes no page fault), and the pool grows geometrically
    /// beyond, so that updates soon stop allocating.
    pub fn new(sampler: &Sampler, seed: u64, prefix: u32, budget: usize) -> Self {
        Self::new_with(sampler, seed, (prefix, budget), Placement::Cpu)
    }

    /// [`new`](Self::new) (ranks `0..prefix`, room for `budget` more) with the entries
    /// placed by `placement`: with [`Placement::Elsewhere`] the pool lists the ranks
    /// that [`new`](Self::new)'s would, update by update, and computes no site
    /// ([`sites`](Self::sites) is empty; 4 bytes per entry instead of 20).
    pub fn new_with(
        sampler: &Sampler,
        seed: u64,
        (prefix, budget): (u32, usize),
        placement: Placement,
    ) -> Self {
        let entries = Entries::new(sampler, seed, (prefix, budget), placement);
        Self {
            entries,
            bins: Bins::new(sampler, seed, prefix),
            estimate: ShownEstimate::new(sampler, seed),
            sampler: SamplerKey::new(sampler),
            live: Vec::new(),
        }
    }

    /// Whether `sampler` is the one the pool was built from (or a clone of it: the same
    /// mesh, field and curves, shared): the only sampler whose sequence the pool's
    /// entries and bins are of.
    pub fn drawn_from(&self, sampler: &Sampler) -> bool {
        self.sampler.matches(sampler)
    }

    /// [`drawn_from`](Self::drawn_from), as an error.
    fn check(&self, sampler: &Sampler) -> Result<(), LodError> {
        if self.drawn_from(sampler) {
            Ok(())
        } else {
            Err(LodError::OtherSampler)
        }
    }

    /// One frame: brings the pool up to `view` under `budget`, and says what changed
    /// and which base count the frame thresholds with. Draws the ranks the view needs
    /// and the pool lacks (and, in bins that lack some, the draw-ahead); cost in
    /// proportion to the bins plus the ranks drawn (a view equal to the last update's,
    /// with only the base count changed, reuses its bounds), plus the point budget's
    /// estimate ([`mean_multiplier`](Self::mean_multiplier)) with [`Budget::Shown`];
    /// no allocation while the extension stays within its budget.
    ///
    /// Errors: [`LodError::OtherSampler`], and nothing changed, when `sampler` is not
    /// the one the pool was built from.
    pub fn update(
        &mut self,
        sampler: &Sampler,
        view: &ViewLod,
        budget: Budget,
    ) -> Result<FrameUpdate, LodError> {
        self.check(sampler)?;
        let base = match budget {
            Budget::Base(base) => base,
            Budget::Shown { shown, fallback } => self
                .shown_base(sampler, view, f64::from(shown))
                .map_or(fallback, |b| f64::from(b as f32)),
        };
        let change = self.draw(sampler, view, base);
        Ok(FrameUpdate { change, base })
    }

    /// Draws what `view` with base count `base` needs: see [`update`](Self::update).
    fn draw(&mut self, sampler: &Sampler, view: &ViewLod, base: f64) -> PoolChange {
        let start = self.entries.len();
        self.entries.begin();
        self.bins.survey(view, base);
        self.split(sampler, base);
        if self.entries.extend(sampler, &mut self.bins) {
            return self.entries.finish(sampler, &self.bins, start);
        }
        // The budget ran out. Rebuild if the extension holds ranks the view does not
        // need, even drawing ahead; otherwise keep what is there.
        let prefix = self.entries.prefix();
        let entries = &self.entries;
        if !self
            .bins
            .holds_past(prefix, |need| entries.ahead_limit(need))
        {
            return self.entries.finish(sampler, &self.bins, start);
        }
        self.entries.truncate_to_prefix();
        self.bins.reset(prefix);
        self.bins.survey(view, base);
        self.split(sampler, base);
        self.entries.extend(sampler, &mut self.bins);
        self.entries.finish(sampler, &self.bins, prefix as usize);
        PoolChange::Rebuilt
    }

    /// Splits the bins that ask for many ranks under the bounded view with base count
    /// `base`, on the current geometry.
    fn split(&mut self, sampler: &Sampler, base: f64) {
        let (geometry, deformed) = self.estimate.vertices(sampler);
        let seed = self.entries.seed();
        self.bins
            .split_for(sampler, seed, base, (geometry, !deformed));
    }

    /// Bounds the bins on `mesh`, a deformation of the sampler's mesh (the same
    /// vertices and triangles, moved): a deforming mesh keeps its samples (sites are
    /// face and barycentric coordinates) and the pool keeps serving every visible rank
    /// of views of the deformed surface. The bins are bounded around their triangles'
    /// corners, a quick bound (an eighth of the time of the tight one [`new`](Self::new)
    /// makes, so that it can follow a mesh deforming every frame; about 15% more ranks
    /// drawn for a view). Cost O(faces); an error, and nothing changed, when `mesh` has
    /// other vertices or triangles, or `sampler` is not the pool's.
    pub fn set_geometry(&mut self, sampler: &Sampler, mesh: &TriMesh) -> Result<(), LodError> {
        self.check(sampler)?;
        check_deformation(sampler.mesh(), mesh)?;
        self.bins
            .set_geometry(sampler, (mesh.positions(), mesh.vertex_normals()));
        self.estimate.move_to(mesh);
        Ok(())
    }

    /// The same pool drawing ahead by `fraction` (see the module docs; 0: a bin is
    /// filled to its need exactly). Panics unless `fraction` is in `[0, 1]`.
    pub fn with_draw_ahead(mut self, fraction: f64) -> Self {
        assert!(
            (0.0..=1.0).contains(&fraction),
            "draw-ahead fraction {fraction} out of [0, 1]"
        );
        self.entries.set_draw_ahead(fraction);
        self
    }

    /// The draw-ahead fraction.
    pub fn draw_ahead(&self) -> f64 {
        self.entries.draw_ahead()
    }

    /// The same pool, splitting bins for close views or not (the default: it does,
    /// up to [`SPLIT_ROOM`] times the roots). Without splits a view close to the
    /// surface draws several times the ranks it shows; with them the bins' bounds cost
    /// up to [`SPLIT_ROOM`] times as much.
    pub fn with_splitting(self, splitting: bool) -> Self {
        let roots = self.bins.roots();
        self.with_max_bins(if splitting { roots * SPLIT_ROOM } else { roots })
    }

    /// The same pool, its bins splitting until there are `max_bins` of them, the
    /// roots included (default [`SPLIT_ROOM`] times the roots; at most the roots, no
    /// bin splits). More bins hold fewer entries in views close to the surface, and
    /// each costs its bound in every view's update and estimate. Splits already made
    /// stay until the pool is rebuilt, whatever the new limit.
    pub fn with_max_bins(mut self, max_bins: usize) -> Self {
        self.bins.set_max_bins(max_bins);
        self
    }

    /// Whether bins split for close views: the limit on the bins leaves room past the
    /// roots.
    pub fn splitting(&self) -> bool {
        self.bins.max_bins() > self.bins.roots()
    }

    /// The most bins splits may make, the roots included
    /// ([`with_max_bins`](Self::with_max_bins)).
    pub fn max_bins(&self) -> usize {
        self.bins.max_bins()
    }

    /// The seed of the sequence.
    pub fn seed(&self) -> u64 {
        self.entries.seed()
    }

    /// Ranks `0..prefix` are the first `prefix` entries.
    pub fn prefix(&self) -> u32 {
        self.entries.prefix()
    }

    /// Every entry's site with [`Placement::Cpu`]; empty with
    /// [`Placement::Elsewhere`] (the entries' ranks and [`seed`](Self::seed) say
    /// where they lie: [`Sampler::progressive_sites_of`]).
    pub fn sites(&self) -> &[SampleSite] {
        self.entries.sites()
    }

    /// Where the entries are placed ([`new_with`](Self::new_with)).
    pub fn placement(&self) -> Placement {
        self.entries.placement()
    }

    /// Every entry's rank (entry `k < prefix` has rank `k`).
    pub fn ranks(&self) -> &[u32] {
        self.entries.ranks()
    }

    /// Entries held.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether the pool holds no entry.
    pub fn is_empty(&self) -> bool {
        self.entries.len() == 0
    }

    /// The number of bins: about [`BINS`](super::BINS) roots, and the children of the bins split
    /// for close views ([`SPLIT_WAYS`](super::SPLIT_WAYS) each), which only grow in number until the
    /// pool is rebuilt.
    pub fn bins(&self) -> usize {
        self.bins.len()
    }

    /// Bin `bin`'s segment (an index into [`Sampler::segments`]) and cells (leaves of
    /// the segment's curve).
    pub fn bin(&self, bin: usize) -> (usize, Range<usize>) {
        self.bins.bin(bin)
    }

    /// The rank below which bin `bin` holds every rank that falls in it (for a split
    /// bin, its reach when it was split: its children reach further).
    pub fn reach(&self, bin: usize) -> u32 {
        self.bins.reach(bin)
    }

    /// An upper bound of `view`'s multiplier over bin `bin`, from a sphere around the
    /// parts of the faces inside its cells and a cone around their normals (around
    /// the faces' corners after [`set_geometry`](Self::set_geometry)): 0 when the sphere lies
    /// outside the frustum or (back faces culled) every normal faces away; `view.max`
    /// when the sphere reaches the eye's plane.
    pub fn bound(&self, bin: usize, view: &ViewLod) -> f64 {
        self.bins.bound(bin, view)
    }

    /// Whether every rank visible under `view` with base count `base` is held.
    pub fn complete(&self, view: &ViewLod, base: f64) -> bool {
        self.bins.complete(view, base)
    }

    /// Room for the ranks a pool draws beyond its prefix (the `budget` of
    /// [`new`](Self::new)) for views whose multiplier is at most `max`: with base count
    /// `base`, `base x max` (a view at the clamp everywhere asks for that many); with a
    /// point budget of `shown` samples, at least [`CLOSE_ROOM`] times `shown x max`,
    /// since a close view's bins reach past what it shows: 0.012 bounding radii
    /// above the bunny, a budget of 10^5 needs 2.8 times as many entries with the
    /// bins split for the view ([`with_splitting`](Self::with_splitting)), 9.5 times without
    /// (the `lod_budget` bench). The room is used only as views ask: the pool reserves
    /// memory for its prefix and grows geometrically beyond.
    pub fn room_for(base: u32, shown: Option<u32>, max: f64) -> usize {
        let close = shown.map_or(0.0, |s| f64::from(s) * max * CLOSE_ROOM);
        // `as` saturates; half the address space is more than any pool holds.
        (((f64::from(base) * max).max(close)) as usize).min(usize::MAX / 2)
    }

    /// The base count under which `view` shows about `shown` samples (a point budget;
    /// [`ShownEstimate`]), on the pool's current geometry, at most 2^32 (the
    /// sequence's length): `None` when the estimate sees nothing in view. What
    /// [`update`](Self::update) thresholds with under [`Budget::Shown`] (there rounded
    /// to `f32`). Cost: [`mean_multiplier`](Self::mean_multiplier)'s.
    ///
    /// Errors: [`LodError::OtherSampler`] when `sampler` is not the pool's.
    pub fn base_for_shown(
        &mut self,
        sampler: &Sampler,
        view: &ViewLod,
        shown: f64,
    ) -> Result<Option<f64>, LodError> {
        self.check(sampler)?;
        Ok(self.shown_base(sampler, view, shown))
    }

    /// [`base_for_shown`](Self::base_for_shown) for the pool's sampler.
    fn shown_base(&mut self, sampler: &Sampler, view: &ViewLod, shown: f64) -> Option<f64> {
        let mean = self.estimate_mean(sampler, view).mean;
        (mean > 0.0).then(|| (shown / mean).min(4_294_967_296.0))
    }

    /// The point budget's estimate of `view`'s mean multiplier over the sequence's
    /// measure ([`ShownEstimate`]), on the pool's current geometry. Cost: a
    /// multiplier per [`PROBES`](super::PROBES); when fewer than [`IN_VIEW`] of them
    /// are in view, the bins' bounds (which the next [`update`](Self::update) for the
    /// view reuses) and the refinement's ranks, at most
    /// [`REFINE_LIMIT`](super::REFINE_LIMIT); nothing for the view of the last call.
    ///
    /// Errors: [`LodError::OtherSampler`] when `sampler` is not the pool's.
    pub fn mean_multiplier(
        &mut self,
        sampler: &Sampler,
        view: &ViewLod,
    ) -> Result<MeanMultiplier, LodError> {
        self.check(sampler)?;
        Ok(self.estimate_mean(sampler, view))
    }

    /// [`mean_multiplier`](Self::mean_multiplier) for the pool's sampler.
    fn estimate_mean(&mut self, sampler: &Sampler, view: &ViewLod) -> MeanMultiplier {
        if let Some(kept) = self.estimate.kept(view) {
            return kept;
        }
        let probes = self.estimate.probe(view);
        if probes.in_view >= IN_VIEW {
            return self.estimate.keep(view, probes);
        }
        self.bins.bound_view(view);
        // The roots: they partition the surface (split bins' children are finer
        // copies of parts of it).
        self.bins.live_roots_into(&mut self.live);
        let bins = &self.bins;
        let refined = self.estimate.refine(
            sampler,
            view,
            probes,
            &self.live,
            |b| bins.cover(b),
            bins.shares(),
        );
        self.estimate.keep(view, refined)
    }

    /// The point budget's estimator, on the pool's current geometry.
    pub fn shown_estimate(&self) -> &ShownEstimate {
        &self.estimate
    }

    /// Writes each entry's fade weight under `view` with base count `base` into `out`
    /// (0 for an entry that is not visible), computing positions and normals on the
    /// CPU as [`Sampler::record`] does: the reference a GPU cull is checked against.
    /// With [`Placement::Elsewhere`] the entries' sites are placed for it
    /// ([`Sampler::progressive_sites_of`]). Panics when `out` is not one weight per
    /// entry, or `sampler` is not the pool's ([`drawn_from`](Self::drawn_from)).
    pub fn fades_into(&self, sampler: &Sampler, view: &ViewLod, base: f64, out: &mut [f32]) {
        assert_eq!(out.len(), self.len(), "one weight per entry");
        assert!(self.drawn_from(sampler), "the pool's own sampler");
        let (seed, placed) = (self.seed(), self.sites());
        out.par_chunks_mut(4096)
            .zip(self.ranks().par_chunks(4096))
            .enumerate()
            .for_each(|(c, (dst, ranks))| {
                let sites = match placed.get(c * 4096..c * 4096 + ranks.len()) {
                    Some(sites) => Cow::Borrowed(sites),
                    None => {
                        let mut sites = vec![SampleSite::default(); ranks.len()];
                        sampler.progressive_sites_of(seed, ranks, &mut sites);
                        Cow::Owned(sites)
                    }
                };
                for ((slot, site), &rank) in dst.iter_mut().zip(sites.iter()).zip(ranks) {
                    let b = site.barycentric().map(f64::from);
                    *slot = sampler
                        .record(site.face, b, site.segment, rank, 1)
                        .map_or(0.0, |s| {
                            let p = DVec3::from(s.position.map(f64::from));
                            let n = DVec3::from(s.normal.map(f64::from));
                            fade(rank, base, view.multiplier(p, n)) as f32
                        });
                }
            });
    }

    /// The split bins and their children (for tests of the splits).
    #[cfg(test)]
    pub(super) fn groups(&self) -> &[(u32, Range<u32>)] {
        self.bins.groups()
    }

    /// The roots (for tests of the splits).
    #[cfg(test)]
    pub(super) fn roots(&self) -> usize {
        self.bins.roots()
    }

    /// The same pool, surveying its bins in separate passes over all of them (bounds,
    /// needs, the bins that lack ranks, those that ask for a split): the reference
    /// the fused survey is checked against.
    #[cfg(test)]
    pub(super) fn with_full_scans(mut self) -> Self {
        self.bins.set_full_scans(true);
        self
    }

    /// Bin `bin`'s bound under the last view bounded (for tests of the splits).
    #[cfg(test)]
    pub(super) fn bounded_multiplier(&self, bin: usize) -> f64 {
        self.bins.bounded_multiplier(bin)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixtures::along_x_2to1_on;
    use crate::fixtures::lod::{Frame, check_held, held_visible, moved, scan, view, view_at};
    use crate::fixtures::torus_sampler;
    use crate::mesh::TriMesh;
    use crate::sample::lod::DRAW_AHEAD;
    use crate::surface::{Preprocessed, SurfaceOptions};
    use std::sync::Arc;

    #[test]
    fn room_for_a_point_budget_covers_close_views() {
        assert_eq!(LodPool::room_for(1000, None, 4.0), 4000);
        // A budget below the count: the count's room still.
        assert_eq!(LodPool::room_for(100_000, Some(1000), 4.0), 400_000);
        // A budget: CLOSE_ROOM times its shown x max.
        assert_eq!(LodPool::room_for(1000, Some(1000), 4.0), 16_000);
        assert_eq!(
            LodPool::room_for(u32::MAX, Some(u32::MAX), 1e30),
            usize::MAX / 2
        );
    }

    /// A frame's base count: the given one without a budget or with nothing in view,
    /// else the budget's, rounded to `f32`.
    #[test]
    fn a_frames_base_count_follows_the_budget() {
        let s = torus_sampler();
        let mut pool = LodPool::new(&s, 3, 2_000, 10_000);
        let v = view(DVec3::new(0.0, 3.0, 3.0), 4.0);
        let mut base_of = |v: &ViewLod, shown| {
            let budget = Budget::new(2_000.0, shown);
            pool.update(&s, v, budget).expect("the pool's sampler").base
        };
        assert_eq!(base_of(&v, None), 2_000.0);
        let budget = base_of(&v, Some(5_000));
        let away = view_at(DVec3::new(0.0, 0.0, 3.0), DVec3::new(0.0, 0.0, 6.0), 4.0);
        assert_eq!(base_of(&away, Some(5_000)), 2_000.0);
        let exact = pool
            .base_for_shown(&s, &v, 5_000.0)
            .expect("the pool's sampler");
        let exact = exact.expect("in view");
        assert_eq!(budget, f64::from(exact as f32));
        assert!(budget != 2_000.0 && (budget / exact - 1.0).abs() < 1e-6);
    }

    #[test]
    fn another_sampler_is_refused_and_nothing_changes() {
        let s = torus_sampler();
        let v = view(DVec3::new(0.3, 0.1, 3.0), 10.0);
        let mut pool = LodPool::new(&s, 3, 2_000, 100_000);
        // A clone shares the mesh, field and curves: the same sampler.
        let twin = s.clone();
        assert!(pool.drawn_from(&twin));
        pool.frame(&twin, &v, 2_000.0);
        // A sampler of the same mesh and field preprocessed again has other curves.
        let other = Preprocessed::build(
            s.mesh().clone(),
            s.field().clone(),
            &SurfaceOptions::default(),
        )
        .expect("built")
        .sampler;
        assert!(!pool.drawn_from(&other));
        let (len, bins) = (pool.len(), pool.bins());
        let closer = view(DVec3::new(0.3, 0.1, 2.0), 10.0);
        for budget in [Budget::Base(2_000.0), Budget::new(2_000.0, Some(5_000))] {
            assert_eq!(
                pool.update(&other, &closer, budget),
                Err(LodError::OtherSampler)
            );
        }
        assert_eq!(
            pool.mean_multiplier(&other, &closer),
            Err(LodError::OtherSampler)
        );
        assert_eq!(
            pool.base_for_shown(&other, &closer, 1e4),
            Err(LodError::OtherSampler)
        );
        assert_eq!(
            pool.set_geometry(&other, other.mesh()),
            Err(LodError::OtherSampler)
        );
        assert_eq!((pool.len(), pool.bins()), (len, bins));
        // The pool's own sampler still extends it.
        assert!(matches!(
            pool.frame(&s, &closer, 2_000.0),
            PoolChange::Appended(_)
        ));
        // Other chains over the same curves are another sequence: refused too.
        let mut chains: Vec<Vec<u32>> = s.chains().iter().map(|c| c.to_vec()).collect();
        chains.reverse();
        if chains.len() > 1 {
            let segments = s.segments().to_vec();
            let reordered =
                Sampler::with_chains(s.mesh().clone(), s.field().clone(), segments, &chains)
                    .expect("chains");
            assert!(!pool.drawn_from(&reordered));
        }
    }

    #[test]
    fn segment_ranks_equal_a_filtered_scan() {
        let s = torus_sampler();
        assert!(s.segments().len() > 3, "{}", s.segments().len());
        let seed = 7;
        let end = 40_000u32;
        let mut sites = vec![SampleSite::default(); end as usize];
        s.progressive_sites_into(seed, 0, &mut sites);
        for (i, seg) in s.segments().iter().enumerate() {
            let scan: Vec<u32> = (0..end)
                .filter(|&k| sites[k as usize].segment == seg.segment)
                .collect();
            let mut listed = Vec::new();
            let reach = s.progressive_ranks_in_segment(seed, i, 0, end, usize::MAX, &mut listed);
            assert_eq!(reach, end);
            assert_eq!(listed, scan, "segment {i}");
            // From the middle, and cut short by a limit.
            let mut part = Vec::new();
            let reach = s.progressive_ranks_in_segment(seed, i, 1234, end, 10, &mut part);
            let expected: Vec<u32> = scan.iter().copied().filter(|&k| k >= 1234).collect();
            assert_eq!(part, expected[..10]);
            assert_eq!(reach, expected[10]);
        }
    }

    #[test]
    fn sites_of_listed_ranks_equal_the_sequence() {
        let s = torus_sampler();
        let ranks = [5u32, 99_999, 3, 70_000, 0];
        let mut out = [SampleSite::default(); 5];
        s.progressive_sites_of(4, &ranks, &mut out);
        for (site, &k) in out.iter().zip(&ranks) {
            let mut one = [SampleSite::default()];
            s.progressive_sites_into(4, k, &mut one);
            assert_eq!(*site, one[0], "rank {k}");
        }
    }

    #[test]
    fn bins_partition_every_segment_and_bound_its_samples() {
        let s = torus_sampler();
        let pool = LodPool::new(&s, 1, 0, 0);
        assert!(pool.bins() > 2 * s.segments().len(), "{} bins", pool.bins());
        let end = 20_000u32;
        let mut sites = vec![SampleSite::default(); end as usize];
        s.progressive_sites_into(1, 0, &mut sites);
        // The bins' ranks are the segments' ranks, each exactly once.
        let mut by_bin: Vec<Vec<u32>> = Vec::new();
        for b in 0..pool.bins() {
            let (segment, leaves) = pool.bin(b);
            let mut ranks = Vec::new();
            s.progressive_ranks_in_leaves(1, segment, leaves, 0, end, usize::MAX, &mut ranks);
            by_bin.push(ranks);
        }
        for (i, seg) in s.segments().iter().enumerate() {
            let mut union: Vec<u32> = (0..pool.bins())
                .filter(|&b| pool.bin(b).0 == i)
                .flat_map(|b| by_bin[b].iter().copied())
                .collect();
            union.sort_unstable();
            let scan: Vec<u32> = (0..end)
                .filter(|&k| sites[k as usize].segment == seg.segment)
                .collect();
            assert_eq!(union, scan, "segment {i}");
        }
        for (eye, cull) in [
            (DVec3::new(0.0, 0.2, 3.0), false),
            (DVec3::new(0.0, 0.2, 3.0), true),
            (DVec3::new(1.2, 0.4, 0.9), false),
            (DVec3::new(1.2, 0.4, 0.9), true),
        ] {
            let v = ViewLod {
                cull_back_faces: cull,
                ..view(eye, f64::INFINITY)
            };
            if cull {
                // Seen from outside, some bins face away entirely.
                let hidden = (0..pool.bins()).filter(|&b| pool.bound(b, &v) == 0.0);
                assert!(hidden.count() > 0, "{eye}");
            }
            let mut checked = 0;
            for (b, ranks) in by_bin.iter().enumerate() {
                for &k in ranks {
                    let site = sites[k as usize];
                    let r = s
                        .record(site.face, site.barycentric().map(f64::from), 0, k, 1)
                        .expect("record");
                    let m = v.multiplier(
                        DVec3::from(r.position.map(f64::from)),
                        DVec3::from(r.normal.map(f64::from)),
                    );
                    assert!(m <= pool.bound(b, &v) * (1.0 + 1e-9), "{eye} rank {k}");
                    checked += usize::from(m > 0.0);
                }
            }
            assert!(checked > 1000, "{checked}");
        }
    }

    #[test]
    fn the_pool_holds_every_visible_rank_of_a_moving_view() {
        let s = torus_sampler();
        let base = 20_000.0;
        let mut pool = LodPool::new(&s, 3, 20_000, 400_000);
        // Zoom in on one side of the sphere: the view asks for far more than the prefix.
        for (t, d) in [8.0, 5.0, 3.5, 2.5].into_iter().enumerate() {
            let v = view(DVec3::new(0.3, 0.1, d), 10.0);
            let before = pool.len();
            let change = pool.frame(&s, &v, base);
            assert!(pool.complete(&v, base));
            if t > 0 {
                assert_eq!(change, PoolChange::Appended(before..pool.len()), "step {t}");
            }
            let end = pool.ranks().iter().copied().max().unwrap_or(0) + 1;
            assert_eq!(
                held_visible(&pool, &s, &v, base),
                scan(&s, 3, end, &v, base)
            );
        }
        let v = view(DVec3::new(0.3, 0.1, 2.5), 10.0);
        assert_eq!(pool.frame(&s, &v, base), PoolChange::Unchanged);
    }

    #[test]
    fn a_clone_updates_as_the_original() {
        let s = torus_sampler();
        let mut pool = LodPool::new(&s, 5, 10_000, 200_000).with_draw_ahead(0.1);
        pool.frame(&s, &view(DVec3::new(0.3, 0.1, 3.0), 10.0), 10_000.0);
        let mut twin = pool.clone();
        let closer = view(DVec3::new(0.3, 0.1, 2.0), 10.0);
        assert_eq!(
            pool.frame(&s, &closer, 10_000.0),
            twin.frame(&s, &closer, 10_000.0)
        );
        assert_eq!((pool.ranks(), pool.sites()), (twin.ranks(), twin.sites()));
        assert_eq!(
            (twin.seed(), twin.prefix(), twin.draw_ahead()),
            (5, 10_000, 0.1)
        );
        assert!(twin.len() > pool.prefix() as usize);
    }

    #[test]
    fn a_still_view_keeps_its_bounds_until_the_mesh_moves() {
        let s = torus_sampler();
        let v = view(DVec3::new(0.3, 0.1, 3.0), 10.0);
        // The base count grows under a still camera: the bounds of the first update
        // serve the next, and the pool matches one built for the last count alone.
        let mut pool = LodPool::new(&s, 3, 10_000, 1_000_000);
        for base in [10_000.0, 14_000.0, 20_000.0] {
            pool.frame(&s, &v, base);
            assert!(pool.complete(&v, base));
        }
        let mut fresh = LodPool::new(&s, 3, 10_000, 1_000_000);
        fresh.frame(&s, &v, 20_000.0);
        assert_eq!(
            held_visible(&pool, &s, &v, 20_000.0),
            held_visible(&fresh, &s, &v, 20_000.0)
        );
        // Deformed under the same view: the kept bounds are dropped, and the pool
        // holds every rank visible on the stretched surface (longer along z, so it
        // needs more ranks there).
        let stretched = moved(s.mesh(), |p| DVec3::new(p.x, p.y, 2.0 * p.z));
        let mean = pool.shown_estimate().mean_multiplier(&v);
        pool.set_geometry(&s, &stretched).expect("same topology");
        // The point budget's probes moved with the surface.
        let mut probes = crate::sample::lod::ShownEstimate::new(&s, pool.seed());
        probes.set_geometry(&s, &stretched).expect("same topology");
        let stretched_mean = pool.shown_estimate().mean_multiplier(&v);
        assert_eq!(stretched_mean, probes.mean_multiplier(&v));
        assert_ne!(stretched_mean, mean);
        let wanted = pool.complete(&v, 20_000.0);
        pool.frame(&s, &v, 20_000.0);
        assert!(!wanted && pool.complete(&v, 20_000.0));
    }

    #[test]
    fn an_outgrown_budget_rebuilds_for_the_view_and_caps_in_segment_order() {
        let s = torus_sampler();
        let base = 20_000.0;
        // Two close-ups of opposite sides of the ring.
        let near = view_at(DVec3::new(1.0, 0.0, 1.2), DVec3::X, 50.0);
        let other = view_at(DVec3::new(-1.0, 0.0, 1.2), -DVec3::X, 50.0);
        let mut probe = LodPool::new(&s, 3, 20_000, usize::MAX / 2);
        probe.frame(&s, &near, base);
        let needed = probe.len() - 20_000;
        // Room for one view's ranks, not two.
        let mut pool = LodPool::new(&s, 3, 20_000, needed + needed / 4);
        assert!(matches!(
            pool.frame(&s, &near, base),
            PoolChange::Appended(_)
        ));
        assert_eq!(pool.frame(&s, &other, base), PoolChange::Rebuilt);
        assert!(pool.complete(&other, base));
        let end = pool.ranks().iter().copied().max().unwrap_or(0) + 1;
        assert_eq!(
            held_visible(&pool, &s, &other, base),
            scan(&s, 3, end, &other, base)
        );
        // A view needing more than the budget gets what fits, and no rebuild loop.
        let greedy = view_at(DVec3::new(1.0, 0.0, 0.7), DVec3::X, 1e6);
        pool.frame(&s, &greedy, base);
        assert!(!pool.complete(&greedy, base));
        assert!(pool.len() - 20_000 <= needed + needed / 4);
        assert_eq!(pool.frame(&s, &greedy, base), PoolChange::Unchanged);
    }

    #[test]
    fn parallel_and_sequential_updates_list_the_same_entries() {
        let s = torus_sampler();
        let v = view_at(DVec3::new(1.0, 0.2, 1.3), DVec3::X, 30.0);
        // A roomy budget takes the parallel path; one that the ranks exactly fill is
        // refused by its estimate and takes the sequential one.
        // Without draw-ahead: the sequential pass, which spends a budget, has none.
        let mut roomy = LodPool::new(&s, 4, 10_000, 10_000_000).with_draw_ahead(0.0);
        roomy.frame(&s, &v, 10_000.0);
        let added = roomy.len() - 10_000;
        assert!(added > 1000, "{added}");
        let mut tight = LodPool::new(&s, 4, 10_000, added);
        tight.frame(&s, &v, 10_000.0);
        assert!(tight.complete(&v, 10_000.0));
        assert_eq!(tight.ranks(), roomy.ranks());
        assert_eq!(tight.sites(), roomy.sites());
    }

    #[test]
    fn drawing_ahead_holds_more_ranks_refills_less_and_shows_the_same_samples() {
        let s = torus_sampler();
        let (seed, base) = (5, 20_000.0);
        assert_eq!(LodPool::new(&s, seed, 0, 0).draw_ahead(), DRAW_AHEAD);
        let mut exact = LodPool::new(&s, seed, 20_000, 2_000_000).with_draw_ahead(0.0);
        let mut ahead = LodPool::new(&s, seed, 20_000, 2_000_000).with_draw_ahead(0.25);
        // Bins whose reach an update raised, summed over the updates.
        let mut refills = [0, 0];
        let mut v = view(DVec3::ZERO, 10.0);
        // A dolly in small steps.
        for t in 0..8 {
            v = view(DVec3::new(0.3, 0.1, 4.0 * 0.97f64.powi(t)), 10.0);
            for (pool, count) in [&mut exact, &mut ahead].into_iter().zip(&mut refills) {
                let before: Vec<u32> = (0..pool.bins()).map(|b| pool.reach(b)).collect();
                pool.frame(&s, &v, base);
                assert!(pool.complete(&v, base), "step {t}");
                *count += (0..pool.bins())
                    .filter(|&b| pool.reach(b) > before[b])
                    .count();
            }
            assert!((0..ahead.bins()).all(|b| ahead.reach(b) >= exact.reach(b)));
            assert_eq!(
                held_visible(&ahead, &s, &v, base),
                held_visible(&exact, &s, &v, base),
                "step {t}"
            );
        }
        assert!(refills[1] * 2 < refills[0], "{refills:?}");
        assert!(ahead.len() > exact.len());
        let end = ahead.ranks().iter().copied().max().unwrap_or(0) + 1;
        assert_eq!(
            held_visible(&ahead, &s, &v, base),
            scan(&s, seed, end, &v, base)
        );
        // A superset of the exact pool's ranks.
        let held = check_held(&ahead, &s, 5);
        assert!(exact.ranks().iter().all(|k| held.binary_search(k).is_ok()));
    }

    #[test]
    fn bounds_follow_a_deformed_mesh() {
        let s = torus_sampler();
        let mut pool = LodPool::new(&s, 1, 0, 0);
        // Stretched along z and bent: the bounds of the rest mesh no longer hold.
        let bent = moved(s.mesh(), |p| {
            DVec3::new(p.x, p.y + 0.5 * p.x * p.x, 3.0 * p.z)
        });
        pool.set_geometry(&s, &bent).expect("same topology");
        let v = view(DVec3::new(0.3, 0.8, 2.5), f64::INFINITY);
        let end = 20_000u32;
        let mut sites = vec![SampleSite::default(); end as usize];
        s.progressive_sites_into(1, 0, &mut sites);
        let mut checked = 0;
        for b in 0..pool.bins() {
            let (segment, leaves) = pool.bin(b);
            let mut ranks = Vec::new();
            s.progressive_ranks_in_leaves(1, segment, leaves, 0, end, usize::MAX, &mut ranks);
            for k in ranks {
                let site = sites[k as usize];
                let w = site.barycentric().map(f64::from);
                let [i, j, l] = bent.triangles()[site.face as usize].map(|x| x as usize);
                let p = bent.positions()[i] * w[0]
                    + bent.positions()[j] * w[1]
                    + bent.positions()[l] * w[2];
                let n = (bent.vertex_normals()[i] * w[0]
                    + bent.vertex_normals()[j] * w[1]
                    + bent.vertex_normals()[l] * w[2])
                    .normalize();
                let m = v.multiplier(p, n);
                assert!(m <= pool.bound(b, &v) * (1.0 + 1e-9), "rank {k}");
                checked += usize::from(m > 0.0);
            }
        }
        assert!(checked > 1000, "{checked}");
        let other =
            TriMesh::new(vec![DVec3::ZERO, DVec3::X, DVec3::Y], vec![[0, 1, 2]]).expect("triangle");
        let e = pool.set_geometry(&s, &other).expect_err("mismatch");
        assert!(
            e.to_string().contains("must keep the sampler's vertices"),
            "{e}"
        );
    }

    #[test]
    fn each_fill_draws_its_own_factor() {
        // A factor fixed per bin keeps bins filled in one frame in step: under needs
        // that all grow at one rate they come due together again and again.
        let s = torus_sampler();
        let mut pool = LodPool::new(&s, 9, 1_000, 100_000);
        let need = 1_000_000;
        let ahead = pool.draw_ahead();
        let lo = f64::from(need) * (1.0 + ahead);
        let hi = f64::from(need) * (1.0 + 2.0 * ahead);
        let mut targets = Vec::new();
        for reach in [1_000, 1_031, 1_066, 1_100] {
            pool.bins.set_reach(0, reach);
            let t = pool.entries.ahead_of(&pool.bins, 0, need);
            assert!(
                (lo..=hi).contains(&f64::from(t)),
                "{t} outside [{lo}, {hi}]"
            );
            assert!(pool.entries.ahead_limit(need) >= t);
            targets.push(t);
        }
        targets.sort_unstable();
        targets.dedup();
        assert_eq!(targets.len(), 4, "one factor for every fill: {targets:?}");
    }

    #[test]
    fn the_pool_is_the_same_for_any_thread_count() {
        let s = torus_sampler();
        let v = view(DVec3::new(0.5, 0.0, 1.6), 100.0);
        let run = || {
            let mut pool = LodPool::new(&s, 9, 10_000, 200_000);
            pool.frame(&s, &v, 10_000.0);
            (pool.sites().to_vec(), pool.ranks().to_vec())
        };
        assert_eq!(crate::on_threads(1, run), crate::on_threads(2, run));
    }

    #[test]
    fn a_single_segment_sampler_enumerates_every_rank() {
        let mesh = Arc::new(crate::mesh::shapes::plane(1.0, 4).expect("plane"));
        let field = along_x_2to1_on(&mesh);
        let pre =
            Preprocessed::build(mesh, Arc::new(field), &SurfaceOptions::default()).expect("built");
        let s = pre.sampler;
        assert_eq!(s.segments().len(), 1);
        let mut all = Vec::new();
        s.progressive_ranks_in_segment(2, 0, 10, 300, usize::MAX, &mut all);
        assert_eq!(all, (10..300).collect::<Vec<_>>());
    }
}
