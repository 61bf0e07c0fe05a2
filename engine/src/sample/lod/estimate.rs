//! A point budget for level of detail: the base count under which a view
//! shows about a given number of samples.
//!
//! With base count `N`, rank `k` is visible when `k < N lod(p_k)`
//! ([`view`](super::view)). The sequence spreads every run of ranks over the surface by
//! one measure `rho` (the curves' measure, stratified at every prefix), so the visible
//! count is, up to that stratification's error, `N E_rho[lod]`: linear in `N`. The
//! base count that shows `S` samples is then `S / E_rho[lod]`.
//!
//! The mean multiplier is estimated as the mean over the sequence's first `M` ranks:
//! one rank in each `1 / M` of the measure when `M` is a power of two.
//!
//! - **The probes.** The first [`PROBES`] ranks: their positions and normals are kept,
//!   so a view costs one multiplier each, computed a block at a time without branches
//!   (`ViewLod::multipliers_into`): 27-28 us for the 4096 on the test machine (150 one
//!   at a time), with the probes out of cache as they are between frames (the `lod`
//!   bench). On the bunny's `lod` bench paths this is within 1% of the count.
//! - **Refinement in view.** A close view sees a small part of the surface, and few
//!   probes: on the bunny, 2.7 times the budget shown 0.03 bounding radii from the
//!   surface, and the base count jumping by up to 1.5 times between frames of a smooth
//!   dolly as probes cross the frame's edge (the `lod_budget` bench). While fewer than
//!   [`IN_VIEW`] of the ranks averaged are in view, `M` doubles: the new ranks `M..2M`
//!   are enumerated only in the bins of a pool ([`LodPool`](super::LodPool)) whose bound of the
//!   multiplier is above 0 (elsewhere every multiplier is 0), placed, and their
//!   multipliers added.
//!   The ranks evaluated are about `IN_VIEW` times the measure of those bins over the
//!   measure in view, at most [`REFINE_LIMIT`] per view (where that limit stops the
//!   doubling, how far it got depends on the bins' bounds too: the looser bounds of a
//!   deformed mesh reach it sooner).
//! - **Kept sites.** Placing a rank drawn a few per bin costs 150-250 ns (cold cells);
//!   the sites a refinement evaluated are kept per bin for the next one, so a camera
//!   that moves a little reads most of them back and places only the ranks new to it.
//!
//! The estimate depends on the view alone (and the seed and geometry), never on the
//! path of the camera or on the ranks a pool holds; fixed chunks of bins summed in
//! order make it the same for any thread count. The last view's estimate is kept, so a
//! still camera costs nothing.
//!
//! A renderer with a point budget (as point-cloud renderers bound the points they draw)
//! sets the base count of every frame this way, so that the shown count stays at its
//! budget while the camera moves: a dolly in then refines near the camera and thins
//! elsewhere instead of showing ever more samples.

use std::ops::Range;

use glam::DVec3;
use rayon::prelude::*;

use super::view::{LodError, ViewLod, check_deformation};
use crate::curve::LeafScratch;
use crate::mesh::TriMesh;
use crate::sample::faces::{Geometry, position_normal};
use crate::sample::progressive::RankCover;
use crate::sample::{SampleSite, Sampler};

/// Probes of the mean multiplier: the first this many ranks of the sequence. On the
/// bunny's `lod` bench paths, 4096 estimate the shown count within 1% (1024: within
/// 4.5%, 16384: within 0.3%).
pub const PROBES: usize = 4096;

/// Probes whose multipliers are computed together, on the stack.
const PROBE_BLOCK: usize = 512;

/// Ranks in view (multiplier above 0) the estimate refines to: on the bunny the probes
/// in view number 1100-1700 while all of it is in view, so those views keep the
/// probes' estimate.
pub const IN_VIEW: usize = 1024;

/// The most ranks the refinement of one view evaluates beyond the probes (placing them
/// all takes about 5-8 ms of one core; reached only when the view shows a small part of
/// its bins).
pub const REFINE_LIMIT: usize = 1 << 15;

/// Bins per task of a refinement.
const REFINE_CHUNK: usize = 16;

/// With a point budget, the pool's room for ranks beyond its prefix is this many times
/// the budget's `shown x max` (see [`LodPool::room_for`](super::LodPool::room_for)).
pub const CLOSE_ROOM: f64 = 4.0;

/// A view's estimate of the mean multiplier `E_rho[lod]` (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeanMultiplier {
    /// The mean multiplier over the first [`ranks`](Self::ranks) ranks.
    pub mean: f64,
    /// The ranks averaged: [`PROBES`] times a power of two.
    pub ranks: u64,
    /// Of them, those in view (multiplier above 0).
    pub in_view: usize,
    /// Ranks evaluated for this view beyond the probes.
    pub evaluated: usize,
    /// Of them, those whose sites were placed for this view (the others were kept from
    /// the last refinement): the only field that depends on what came before.
    pub placed: usize,
}

/// The estimator of a point budget: see the module docs.
#[derive(Clone, Debug)]
pub struct ShownEstimate {
    /// The probes' sites (ranks `0..PROBES`).
    sites: Vec<SampleSite>,
    /// Their positions and unit normals on the current geometry, as columns (x, y, z
    /// of the positions, then of the normals) for the view's batch multipliers.
    points: [Vec<f64>; 6],
    /// The current geometry when it is a deformation of the sampler's mesh: vertex
    /// positions, vertex normals and face normals.
    deformed: Option<[Vec<DVec3>; 3]>,
    /// The last view estimated, and its estimate: a camera that has not moved costs
    /// nothing.
    last: Option<(ViewLod, MeanMultiplier)>,
    /// Per chunk of [`REFINE_CHUNK`] bins, a refinement's lists (kept, so that
    /// refinements stop allocating).
    lists: Vec<ProbeList>,
    /// The sites the last refinement evaluated.
    cache: SiteCache,
}

/// One chunk's part of a refinement.
#[derive(Clone, Debug, Default)]
struct ProbeList {
    ranks: Vec<u32>,
    sites: Vec<SampleSite>,
    /// The sum of the chunk's multipliers at the current doubling, in order.
    sum: f64,
    /// Ranks in view at the current doubling.
    in_view: usize,
    /// Ranks evaluated at the current doubling.
    evaluated: usize,
    /// Ranks whose sites were placed at the current doubling.
    placed: usize,
    /// The ranks and sites placed over the refinement, for the cache.
    fresh: Vec<(u32, SampleSite)>,
    /// Runs of `fresh`: (the bin's position in the chunk, end).
    runs: Vec<(u8, u32)>,
}

impl ProbeList {
    /// One doubling of a refinement over this chunk's bins `bins`: the multipliers of
    /// their ranks in `from..to`, summed in rank order per bin, read from the sites
    /// `cached` of the last refinement where it holds them, else listed in the bin's
    /// dyadic cover (`cover` of `sampler`) and placed (kept in `fresh` for the next).
    fn double<'a, 'c>(
        &mut self,
        bins: &[u32],
        (from, to): (u32, u32),
        cached: &SiteCache,
        (sampler, cover): (&'a Sampler, &(impl Fn(usize) -> &'c RankCover + Sync)),
        evaluate: &impl Fn(&SampleSite) -> f64,
        scratch: &mut LeafScratch<'a>,
    ) {
        let (mut s, mut seen, mut count, mut drawn) = (0.0, 0, 0, 0);
        for (i, &b) in bins.iter().enumerate() {
            // Every rank of the bin in [PROBES, `reach`) is in the cache, in order; the
            // others in [from, to) are placed. Either way the multipliers are summed in
            // rank order.
            let (slot, reach) = match cached.slots[b as usize].clone() {
                Some(slot) => (slot, cached.end),
                None => (0..0, 0),
            };
            let kept = &cached.entries[slot.start as usize..slot.end as usize];
            let lo = kept.partition_point(|e| e.0 < from);
            let hi = kept.partition_point(|e| e.0 < to);
            for (_, site) in &kept[lo..hi] {
                let m = evaluate(site);
                s += m;
                seen += usize::from(m > 0.0);
            }
            count += hi - lo;
            let start = from.max(reach);
            if start >= to {
                continue;
            }
            let cover = cover(b as usize);
            self.ranks.clear();
            sampler.progressive_ranks_in_cover(cover, start, to, usize::MAX, &mut self.ranks);
            self.sites.resize(self.ranks.len(), SampleSite::default());
            sampler.progressive_cover_sites_with(cover, &self.ranks, &mut self.sites, scratch);
            for (&rank, site) in self.ranks.iter().zip(&self.sites) {
                let m = evaluate(site);
                s += m;
                seen += usize::from(m > 0.0);
                self.fresh.push((rank, *site));
            }
            count += self.ranks.len();
            drawn += self.ranks.len();
            self.runs.push((i as u8, self.fresh.len() as u32));
        }
        (self.sum, self.in_view) = (s, seen);
        (self.evaluated, self.placed) = (count, drawn);
    }
}

/// The sites of the last refinement, per bin, so that the next one (a camera that moved
/// a little: about the same bins and ranks) reads them instead of placing them again,
/// at a small part of the cost. Sites do not move with the view or the geometry; only
/// the time depends on the cache, never the estimate.
#[derive(Clone, Debug, Default)]
struct SiteCache {
    /// Per bin of the pool in the last refinement, its ranks from [`PROBES`] to `end`:
    /// a range of `entries`, in rank order.
    slots: Vec<Option<Range<u32>>>,
    /// The end of the ranks the last refinement averaged.
    end: u32,
    /// The entries: rank and site.
    entries: Vec<(u32, SampleSite)>,
    /// The next refinement's entries while they are gathered.
    spare: Vec<(u32, SampleSite)>,
    /// The next refinement's range per bin of its `live`, while they are gathered.
    built: Vec<Range<u32>>,
}

impl ShownEstimate {
    /// The estimator of `sampler`'s progressive sequence for `seed`, on the sampler's
    /// mesh. Cost: [`PROBES`] progressive sites.
    pub fn new(sampler: &Sampler, seed: u64) -> Self {
        let mut sites = vec![SampleSite::default(); PROBES];
        sampler.progressive_sites_into(seed, 0, &mut sites);
        let mut points = Default::default();
        Self::place(&sites, sampler.mesh(), &mut points);
        Self {
            sites,
            points,
            deformed: None,
            last: None,
            lists: Vec::new(),
            cache: SiteCache::default(),
        }
    }

    /// Writes the positions and normals of `sites` on `mesh` into `columns` (their
    /// memory reused: a deforming mesh moves the probes every frame).
    fn place(sites: &[SampleSite], mesh: &TriMesh, columns: &mut [Vec<f64>; 6]) {
        columns.iter_mut().for_each(Vec::clear);
        for s in sites {
            let (p, n) = position_normal(mesh, s.face, s.barycentric().map(f64::from));
            for (c, x) in columns
                .iter_mut()
                .zip(p.to_array().into_iter().chain(n.to_array()))
            {
                c.push(x);
            }
        }
    }

    /// Moves the probes onto `mesh`, a deformation of the sampler's mesh (the same
    /// vertices and triangles): an error, and nothing changed, when it has others.
    pub fn set_geometry(&mut self, sampler: &Sampler, mesh: &TriMesh) -> Result<(), LodError> {
        check_deformation(sampler.mesh(), mesh)?;
        self.move_to(mesh);
        Ok(())
    }

    /// [`set_geometry`](Self::set_geometry) for a caller that checked `mesh` already.
    /// Keeps a copy of its vertices and face normals for the refinement (what
    /// [`Sampler::record`] reads of a mesh besides its triangles).
    pub(crate) fn move_to(&mut self, mesh: &TriMesh) {
        Self::place(&self.sites, mesh, &mut self.points);
        let copy = |from: &[DVec3], to: &mut Vec<DVec3>| {
            to.clear();
            to.extend_from_slice(from);
        };
        let deformed = self.deformed.get_or_insert_with(Default::default);
        copy(mesh.positions(), &mut deformed[0]);
        copy(mesh.vertex_normals(), &mut deformed[1]);
        copy(mesh.face_normals(), &mut deformed[2]);
        self.last = None;
    }

    /// The current geometry, `deformed` (the field of that name, taken alone so that
    /// the estimator's other fields stay free to borrow) or the sampler's mesh's.
    fn geometry<'a>(deformed: &'a Option<[Vec<DVec3>; 3]>, sampler: &'a Sampler) -> Geometry<'a> {
        let mesh = sampler.mesh();
        let [positions, vertex_normals, face_normals] = match deformed {
            Some([p, v, f]) => [&p[..], v, f],
            None => [mesh.positions(), mesh.vertex_normals(), mesh.face_normals()],
        };
        Geometry {
            positions,
            vertex_normals,
            face_normals,
        }
    }

    /// The vertex positions and normals of the current geometry: the sampler's mesh's,
    /// or the deformation's given to [`set_geometry`](Self::set_geometry); and whether
    /// it is a deformation.
    pub(crate) fn vertices<'a>(
        &'a self,
        sampler: &'a Sampler,
    ) -> ((&'a [DVec3], &'a [DVec3]), bool) {
        let g = Self::geometry(&self.deformed, sampler);
        ((g.positions, g.vertex_normals), self.deformed.is_some())
    }

    /// The mean of `view`'s multiplier over the [`PROBES`] alone (no refinement).
    pub fn mean_multiplier(&self, view: &ViewLod) -> f64 {
        self.probe(view).mean
    }

    /// The probes' estimate of `view` alone (no refinement; what
    /// [`LodPool::mean_multiplier`](super::LodPool::mean_multiplier) refines).
    pub fn probe(&self, view: &ViewLod) -> MeanMultiplier {
        // One thread, summed in order: the same sum whatever the thread count, and
        // faster than waking rayon's workers for 4096 multipliers. The multipliers are
        // computed a block at a time without branches, on the stack.
        let (mut sum, mut in_view) = (0.0, 0);
        let [px, py, pz, nx, ny, nz] = self.points.each_ref().map(Vec::as_slice);
        let mut block = [0.0; PROBE_BLOCK];
        for start in (0..px.len()).step_by(PROBE_BLOCK) {
            let end = (start + PROBE_BLOCK).min(px.len());
            let out = &mut block[..end - start];
            let (p, n) = ([px, py, pz], [nx, ny, nz]);
            view.multipliers_into(p.map(|c| &c[start..end]), n.map(|c| &c[start..end]), out);
            for &m in out.iter() {
                sum += m;
                in_view += usize::from(m > 0.0);
            }
        }
        MeanMultiplier {
            mean: sum / PROBES as f64,
            ranks: PROBES as u64,
            in_view,
            evaluated: 0,
            placed: 0,
        }
    }

    /// The estimate kept for `view`, if it is the last view estimated.
    pub(crate) fn kept(&self, view: &ViewLod) -> Option<MeanMultiplier> {
        self.last.filter(|(last, _)| last == view).map(|(_, e)| e)
    }

    /// Keeps `estimate` as `view`'s, and returns it.
    pub(crate) fn keep(&mut self, view: &ViewLod, estimate: MeanMultiplier) -> MeanMultiplier {
        self.last = Some((*view, estimate));
        estimate
    }

    /// Refines the probes' estimate `probes` of `view`: doubles the ranks averaged while
    /// fewer than [`IN_VIEW`] are in view, the next doubling fits [`REFINE_LIMIT`] and
    /// the ranks stay within `2^31`. The new ranks are drawn in the bins `live` only
    /// (every bin where a multiplier may be above 0), whose dyadic covers `cover` gives
    /// and whose shares of the measure are `shares`.
    pub(crate) fn refine<'c>(
        &mut self,
        sampler: &Sampler,
        view: &ViewLod,
        probes: MeanMultiplier,
        live: &[u32],
        cover: impl Fn(usize) -> &'c RankCover + Sync,
        shares: &[f64],
    ) -> MeanMultiplier {
        let share: f64 = live.iter().map(|&b| shares[b as usize]).sum();
        let chunks = live.len().div_ceil(REFINE_CHUNK);
        if self.lists.len() < chunks {
            self.lists.resize_with(chunks, Default::default);
        }
        let cache = &mut self.cache;
        cache.slots.resize(shares.len(), None);
        let mesh = sampler.mesh();
        let geometry = Self::geometry(&self.deformed, sampler);
        let evaluate = |site: &SampleSite| {
            let tri = mesh.triangles()[site.face as usize];
            let (p, n) =
                geometry.position_normal(tri, site.face, site.barycentric().map(f64::from));
            view.multiplier(p, n)
        };
        for list in &mut self.lists[..chunks] {
            list.fresh.clear();
            list.runs.clear();
        }
        let mut sum = probes.mean * PROBES as f64;
        let (mut ranks, mut in_view) = (probes.ranks, probes.in_view);
        let (mut evaluated, mut placed) = (0, 0);
        // `share * ranks` is the number of new ranks expected in the bins.
        while in_view < IN_VIEW
            && !live.is_empty()
            && ranks < 1 << 31
            && evaluated as f64 + share * ranks as f64 <= REFINE_LIMIT as f64
        {
            let (from, to) = (ranks as u32, 2 * ranks as u32);
            let cached = &*cache;
            self.lists[..chunks]
                .par_iter_mut()
                .zip(live.par_chunks(REFINE_CHUNK))
                .for_each_init(LeafScratch::default, |scratch, (list, bins)| {
                    list.double(
                        bins,
                        (from, to),
                        cached,
                        (sampler, &cover),
                        &evaluate,
                        scratch,
                    );
                });
            for list in &self.lists[..chunks] {
                sum += list.sum;
                in_view += list.in_view;
                evaluated += list.evaluated;
                placed += list.placed;
            }
            ranks *= 2;
        }
        Self::keep_sites(cache, &self.lists[..chunks], live, ranks as u32);
        MeanMultiplier {
            mean: sum / ranks as f64,
            ranks,
            in_view,
            evaluated,
            placed,
        }
    }

    /// Keeps in `cache` the sites of the ranks below `end` of every bin of `live`: those
    /// it held and those the chunks' `lists` placed; the other bins' are dropped.
    fn keep_sites(cache: &mut SiteCache, lists: &[ProbeList], live: &[u32], end: u32) {
        let SiteCache {
            slots,
            end: kept_end,
            entries,
            spare,
            built,
        } = cache;
        spare.clear();
        built.clear();
        for (list, bins) in lists.iter().zip(live.chunks(REFINE_CHUNK)) {
            for (i, &b) in bins.iter().enumerate() {
                let start = spare.len() as u32;
                let slot = slots[b as usize].clone().unwrap_or(0..0);
                let kept = &entries[slot.start as usize..slot.end as usize];
                spare.extend(kept.iter().take_while(|e| e.0 < end));
                let mut from = 0;
                for &(bin, to) in &list.runs {
                    if usize::from(bin) == i {
                        spare.extend_from_slice(&list.fresh[from as usize..to as usize]);
                    }
                    from = to;
                }
                built.push(start..spare.len() as u32);
            }
        }
        slots.fill(None);
        for (&b, range) in live.iter().zip(built.iter()) {
            slots[b as usize] = Some(range.clone());
        }
        *kept_end = end;
        std::mem::swap(entries, spare);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixtures::lod::{close_view, culled_view as view, multipliers};
    use crate::fixtures::torus_sampler;

    #[test]
    fn the_probes_mean_is_the_sum_of_their_multipliers_in_rank_order() {
        let s = torus_sampler();
        let estimate = ShownEstimate::new(&s, 7);
        // Far (all of the torus in view, half turned away) and close (a little of it).
        for v in [
            view(DVec3::new(0.4, 3.0, 2.5), DVec3::ZERO),
            close_view(&s, 0.3),
        ] {
            let lods = multipliers(&s, 7, PROBES as u32, &v);
            let probed = estimate.probe(&v);
            let sum = lods.iter().fold(0.0, |sum, m| sum + m);
            assert_eq!(probed.mean.to_bits(), (sum / PROBES as f64).to_bits());
            assert_eq!(probed.in_view, lods.iter().filter(|&&m| m > 0.0).count());
            assert!(probed.in_view > 0 && probed.in_view < PROBES);
        }
    }
}
