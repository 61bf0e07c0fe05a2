//! A pool of progressive sample sites that grows where a view asks for more (issue 19).
//!
//! A renderer that thresholds progressive ranks against a view's multiplier
//! ([`lod`](super::lod)) needs every rank `k < N lod(p_k)` at hand. The pool holds the
//! sites of ranks `0..P` (a prefix of the sequence, computed once: the rank of entry
//! `k < P` is `k`) and, beyond them, an extension of higher ranks drawn only where the
//! multiplier asks for them. The surface is cut into bins, about [`BINS`] runs of
//! consecutive cells of equal measure (a bin never spans two segments). For each bin
//! an upper bound of the multiplier, from a sphere around the faces its cells overlap
//! and a cone around their normals, gives the rank it needs, `ceil(N bound)`, and the
//! ranks it lacks are enumerated in that bin alone
//! ([`Sampler::progressive_ranks_in_leaves`]), so an update costs in proportion to the
//! bins plus the new ranks. Bin `b` holds every rank below `reach[b]` that falls in it.
//!
//! Entries are only ever appended, so a GPU copy of the pool is extended by streaming
//! the new tail ([`PoolChange::Appended`]). When the extension would outgrow its budget
//! and holds ranks the view no longer needs, it is rebuilt for the current view
//! ([`PoolChange::Rebuilt`]); when the current view alone needs more than the budget,
//! bins are served in order until it is spent and the rest keep the ranks
//! they have ([`LodPool::complete`] says whether every visible rank is held).
//!
//! Which ranks are visible, and where each lies, depend only on the seed, the view and
//! the ranks held, never on the path that led there: the pool's order of entries
//! differs with the path, the samples do not.

use std::ops::Range;

use glam::{DVec3, DVec4, Vec4Swizzles};
use rayon::prelude::*;

use super::lod::{LodError, ViewLod, fade};
use super::progressive::RankCover;
use super::{SampleSite, Sampler};
use crate::mesh::TriMesh;

/// The pool cuts the surface into about this many bins, each with its own bound of a
/// view's multiplier: finer bins bound more tightly (fewer ranks drawn that no view
/// shows) and cost more per update (one bound per bin).
pub const BINS: usize = 16384;

/// What an [`LodPool::update`] changed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum PoolChange {
    /// Nothing: the pool already held every rank the view needs (or the budget is
    /// spent on ranks the view still needs).
    Unchanged,
    /// Entries in this range were appended; the entries before it are as they were.
    Appended(Range<usize>),
    /// The extension was rebuilt: entries from [`LodPool::prefix`] on changed.
    Rebuilt,
}

/// Progressive sample sites for one sampler and seed: a prefix of the sequence plus
/// ranks drawn per segment where views need them. See the module docs.
#[derive(Clone, Debug)]
pub struct LodPool {
    seed: u64,
    prefix: u32,
    budget: usize,
    sites: Vec<SampleSite>,
    ranks: Vec<u32>,
    /// The bins, in segment order and cell order within a segment.
    bins: Vec<Bin>,
    /// Per bin: every rank below it that falls in the bin is held.
    reach: Vec<u32>,
    /// The ranks listed by an update, as runs of one bin: (bin, end entry).
    runs: Vec<(u32, u32)>,
    /// Per chunk of [`BIN_CHUNK`] bins, the lists of a parallel update (kept, so that
    /// updates stop allocating).
    lists: Vec<BinList>,
}

/// Bins per task of a parallel update.
const BIN_CHUNK: usize = 64;

/// Ranks a bin may list beyond its share of a rank range (an estimate's slack: the
/// cover's end intervals).
const COVER_SLACK: f64 = 24.0;

/// One chunk's part of a parallel update.
#[derive(Clone, Debug, Default)]
struct BinList {
    /// Each bin's needed rank.
    needs: Vec<u32>,
    /// The ranks listed, bin after bin.
    ranks: Vec<u32>,
    /// (bin, ranks listed) per bin that listed some.
    runs: Vec<(u32, u32)>,
    /// Each bin's reach after listing.
    reach: Vec<u32>,
}

/// A run of consecutive cells of one segment's curve, with a bound of its region.
#[derive(Clone, Debug)]
struct Bin {
    /// Index into `Sampler::segments`.
    segment: u32,
    /// Leaves of the segment's curve.
    leaves: Range<u32>,
    /// The bin's share of the total measure (of the sequence's values).
    share: f64,
    bound: RegionBound,
    /// The dyadic intervals over the bin's values.
    cover: RankCover,
}

/// A sphere holding some faces and a cone holding their vertex normals (hence every
/// normal interpolated on them), for an upper bound of a view's multiplier there.
#[derive(Clone, Copy, Debug)]
struct RegionBound {
    centre: DVec3,
    radius: f64,
    /// Unit axis of the normal cone.
    axis: DVec3,
    /// Half-angle of the normal cone in radians (pi: no bound).
    spread: f64,
    /// Its cosine and sine.
    spread_cos: f64,
    spread_sin: f64,
}

/// A view made ready to bound many regions: its frustum planes with unit normals
/// (world space), the depth's row and its gradient's length.
struct Frustum<'a> {
    view: &'a ViewLod,
    planes: [DVec4; 6],
    depth: DVec4,
    depth_slope: f64,
}

impl<'a> Frustum<'a> {
    fn new(view: &'a ViewLod) -> Self {
        let m = view.clip_from_world;
        let [x, y, z, w] = [m.row(0), m.row(1), m.row(2), m.row(3)];
        // The planes w - x >= 0, w + x >= 0, ..., z >= 0, scaled to unit normals (a
        // degenerate plane keeps its scale: it culls nothing).
        let planes = [w - x, w + x, w - y, w + y, z, w - z].map(|p| {
            let len = p.xyz().length();
            if len > 0.0 { p / len } else { p }
        });
        Self {
            view,
            planes,
            depth: w,
            depth_slope: w.xyz().length(),
        }
    }
}

impl RegionBound {
    /// The bound of the faces whose corners (vertex indices) `corners` lists.
    fn new<I: Iterator<Item = usize>>(
        mesh: &crate::mesh::TriMesh,
        corners: impl Fn() -> I,
    ) -> Self {
        let (lo, hi) = corners().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), v| (lo.min(mesh.positions()[v]), hi.max(mesh.positions()[v])),
        );
        let centre = 0.5 * (lo + hi);
        let radius = corners()
            .map(|v| mesh.positions()[v].distance(centre))
            .fold(0.0, f64::max);
        let normals = mesh.vertex_normals();
        let axis = corners()
            .map(|v| normals[v])
            .sum::<DVec3>()
            .normalize_or_zero();
        // The smallest cosine to the axis; a cone of half-angle under 90 degrees is
        // convex, so it holds every normalised blend of its corner normals too.
        let least = corners()
            .map(|v| normals[v].dot(axis))
            .fold(1.0f64, f64::min);
        let spread = if axis != DVec3::ZERO && least > 1e-3 {
            // A little slack for the f32 normals a renderer interpolates.
            least.clamp(-1.0, 1.0).acos() + 1e-4
        } else {
            std::f64::consts::PI
        };
        Self {
            centre,
            radius,
            axis,
            spread,
            spread_cos: spread.cos(),
            spread_sin: spread.sin(),
        }
    }

    /// An upper bound of the multiplier of `frustum`'s view over the region: 0 when
    /// its sphere lies outside the frustum or (back faces culled) every normal faces
    /// away; the view's clamp when the sphere reaches the eye's plane.
    fn multiplier(&self, frustum: &Frustum) -> f64 {
        let view = frustum.view;
        let (c, r) = (self.centre, self.radius);
        let at = DVec4::new(c.x, c.y, c.z, 1.0);
        if frustum.planes.iter().any(|p| p.dot(at) < -r) {
            return 0.0;
        }
        let nearest = frustum.depth.dot(at) - r * frustum.depth_slope;
        if !(nearest > 0.0) {
            return view.max;
        }
        let farthest = view.eye.distance(c) + r;
        let area = view.focal_pixels * view.focal_pixels * self.cos_bound(view) * farthest
            / (nearest * nearest * nearest);
        (area / view.reference).min(view.max)
    }

    /// An upper bound of `|cos theta|` (or of `cos theta` when back faces are
    /// culled, 0 when every normal faces away) over the region. Normals lie within
    /// `spread` of the axis and directions to the eye within `seen` of the centre's
    /// (at angle `off` from the axis), so a normal meets a direction to the eye at an
    /// angle of at least `off - spread - seen` (front) and at most `off + spread +
    /// seen` (its cosine's least value; the back's bound). Cosines of sums, without
    /// trigonometric calls.
    fn cos_bound(&self, view: &ViewLod) -> f64 {
        let to_eye = view.eye - self.centre;
        let d = to_eye.length();
        if !(self.spread < std::f64::consts::FRAC_PI_2) || !(d > self.radius) {
            return 1.0;
        }
        let (seen_sin, off_cos) = (self.radius / d, self.axis.dot(to_eye / d).clamp(-1.0, 1.0));
        let seen_cos = (1.0 - seen_sin * seen_sin).max(0.0).sqrt();
        let off_sin = (1.0 - off_cos * off_cos).max(0.0).sqrt();
        // theta = spread + seen, in [0, pi).
        let theta_cos = self.spread_cos * seen_cos - self.spread_sin * seen_sin;
        let theta_sin = self.spread_sin * seen_cos + self.spread_cos * seen_sin;
        // cos(off - theta) when off > theta, else 1.
        let front = if off_cos >= theta_cos {
            1.0
        } else {
            off_cos * theta_cos + off_sin * theta_sin
        };
        if view.cull_back_faces {
            return front.max(0.0);
        }
        // The back: cos(pi - off - theta) = -cos(off + theta), 1 when off + theta >= pi.
        let sum_cos = off_cos * theta_cos - off_sin * theta_sin;
        let back = if -off_cos >= theta_cos { 1.0 } else { -sum_cos };
        front.max(back).max(0.0)
    }
}

/// The bound of the faces that cells `leaves` of segment `segment` overlap, with the
/// positions and normals of `mesh` (the sampler's mesh, or a deformation of it).
fn bin_bound(
    sampler: &Sampler,
    mesh: &TriMesh,
    segment: usize,
    leaves: Range<usize>,
) -> RegionBound {
    let seg = &sampler.segments()[segment];
    RegionBound::new(mesh, || {
        leaves
            .clone()
            .flat_map(|l| seg.curve.leaf_triangles(l))
            .flat_map(|&t| mesh.triangles()[seg.faces[t as usize] as usize])
            .map(|v| v as usize)
    })
}

impl LodPool {
    /// Bounds the bins on `mesh`, a deformation of the sampler's mesh (the same
    /// vertices and triangles, moved): a deforming mesh keeps its samples (sites are
    /// face and barycentric coordinates) and the pool keeps serving every visible rank
    /// of views of the deformed surface. Cost O(faces); an error, and nothing changed,
    /// when `mesh` has other vertices or triangles.
    pub fn set_geometry(&mut self, sampler: &Sampler, mesh: &TriMesh) -> Result<(), LodError> {
        let rest = sampler.mesh();
        if mesh.vertex_count() != rest.vertex_count() || mesh.triangles() != rest.triangles() {
            return Err(LodError::Mismatch {
                vertices: mesh.vertex_count(),
                faces: mesh.face_count(),
                expected_vertices: rest.vertex_count(),
                expected_faces: rest.face_count(),
            });
        }
        self.bins.par_iter_mut().for_each(|bin| {
            let leaves = bin.leaves.start as usize..bin.leaves.end as usize;
            bin.bound = bin_bound(sampler, mesh, bin.segment as usize, leaves);
        });
        Ok(())
    }

    /// The pool of `sampler`'s progressive sequence for `seed` holding ranks
    /// `0..prefix`, with room for `budget` more ranks drawn per segment. Memory:
    /// 20 bytes per entry. Room for `min(budget, prefix)` more entries is reserved up
    /// front, and the pool grows geometrically beyond, so that updates soon stop
    /// allocating.
    pub fn new(sampler: &Sampler, seed: u64, prefix: u32, budget: usize) -> Self {
        let capacity = prefix as usize + budget.min(prefix as usize);
        let mut sites = Vec::with_capacity(capacity);
        sites.resize(prefix as usize, SampleSite::default());
        sampler.progressive_sites_into(seed, 0, &mut sites);
        let mut ranks = Vec::with_capacity(capacity);
        ranks.extend(0..prefix);
        let bins: Vec<Bin> = sampler
            .segments()
            .par_iter()
            .enumerate()
            .flat_map_iter(|(i, seg)| {
                let target = sampler.total_measure() / BINS as f64;
                let cumulative = seg.curve.cumulative();
                let cells = seg.curve.cell_count();
                let mut runs = Vec::new();
                let mut start = 0;
                for leaf in 0..cells {
                    if cumulative[leaf + 1] - cumulative[start] >= target || leaf + 1 == cells {
                        runs.push(start..leaf + 1);
                        start = leaf + 1;
                    }
                }
                runs.into_iter().map(move |leaves| {
                    let bound = bin_bound(sampler, sampler.mesh(), i, leaves.clone());
                    Bin {
                        segment: i as u32,
                        share: (cumulative[leaves.end] - cumulative[leaves.start])
                            / sampler.total_measure(),
                        leaves: leaves.start as u32..leaves.end as u32,
                        bound,
                        cover: sampler.progressive_cover(seed, i, leaves),
                    }
                })
            })
            .collect();
        Self {
            seed,
            prefix,
            budget,
            sites,
            ranks,
            reach: vec![prefix; bins.len()],
            bins,
            runs: Vec::new(),
            lists: Vec::new(),
        }
    }

    /// The seed of the sequence.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// Ranks `0..prefix` are the first `prefix` entries.
    pub fn prefix(&self) -> u32 {
        self.prefix
    }

    /// Every entry's site.
    pub fn sites(&self) -> &[SampleSite] {
        &self.sites
    }

    /// Every entry's rank (entry `k < prefix` has rank `k`).
    pub fn ranks(&self) -> &[u32] {
        &self.ranks
    }

    /// Entries held.
    pub fn len(&self) -> usize {
        self.sites.len()
    }

    /// Whether the pool holds no entry.
    pub fn is_empty(&self) -> bool {
        self.sites.is_empty()
    }

    /// The number of bins.
    pub fn bins(&self) -> usize {
        self.bins.len()
    }

    /// Bin `bin`'s segment (an index into [`Sampler::segments`]) and cells (leaves of
    /// the segment's curve).
    pub fn bin(&self, bin: usize) -> (usize, Range<usize>) {
        let b = &self.bins[bin];
        (
            b.segment as usize,
            b.leaves.start as usize..b.leaves.end as usize,
        )
    }

    /// An upper bound of `view`'s multiplier over bin `bin`, from a sphere around the
    /// faces its cells overlap and a cone around their normals: 0 when the sphere lies
    /// outside the frustum or (back faces culled) every normal faces away; `view.max`
    /// when the sphere reaches the eye's plane.
    pub fn bound(&self, bin: usize, view: &ViewLod) -> f64 {
        self.bins[bin].bound.multiplier(&Frustum::new(view))
    }

    /// The rank bin `bin` needs under `frustum` with base count `base`.
    fn need(&self, bin: usize, frustum: &Frustum, base: f64) -> u32 {
        let bound = self.bins[bin].bound.multiplier(frustum);
        (base * bound).ceil().min(f64::from(u32::MAX)) as u32
    }

    /// Whether every rank visible under `view` with base count `base` is held.
    pub fn complete(&self, view: &ViewLod, base: f64) -> bool {
        let frustum = Frustum::new(view);
        (0..self.reach.len()).all(|s| self.reach[s] >= self.need(s, &frustum, base))
    }

    /// Draws the ranks `view` with base count `base` needs and the pool lacks. Cost in
    /// proportion to the segments plus the ranks drawn; no allocation while the
    /// extension stays within its budget.
    pub fn update(&mut self, sampler: &Sampler, view: &ViewLod, base: f64) -> PoolChange {
        let start = self.sites.len();
        self.runs.clear();
        if self.extend(sampler, view, base) {
            return self.finish(sampler, start);
        }
        // The budget ran out. Rebuild if the extension holds ranks the view does not
        // need; otherwise keep what is there.
        let frustum = Frustum::new(view);
        let stale = (0..self.reach.len())
            .any(|s| self.reach[s] > self.prefix.max(self.need(s, &frustum, base)));
        if !stale {
            return self.finish(sampler, start);
        }
        self.sites.truncate(self.prefix as usize);
        self.ranks.truncate(self.prefix as usize);
        self.reach.fill(self.prefix);
        self.runs.clear();
        self.extend(sampler, view, base);
        self.finish(sampler, self.prefix as usize);
        PoolChange::Rebuilt
    }

    /// Lists the missing ranks of every bin in order; false when the budget ran out
    /// first.
    fn extend(&mut self, sampler: &Sampler, view: &ViewLod, base: f64) -> bool {
        if self.extend_parallel(sampler, view, base) {
            return true;
        }
        let frustum = Frustum::new(view);
        for s in 0..self.reach.len() {
            let need = self.need(s, &frustum, base);
            if need <= self.reach[s] {
                continue;
            }
            let listed = self.ranks.len();
            let room = self.budget - (listed - self.prefix as usize);
            self.reach[s] = sampler.progressive_ranks_in_cover(
                &self.bins[s].cover,
                self.reach[s],
                need,
                room,
                &mut self.ranks,
            );
            if self.ranks.len() > listed {
                self.runs.push((s as u32, self.ranks.len() as u32));
            }
            if self.reach[s] < need {
                return false;
            }
        }
        true
    }

    /// [`extend`](Self::extend) over fixed chunks of bins in parallel, when the ranks
    /// expected fit the budget twice over: each chunk lists into its own reused list,
    /// and the lists are appended in chunk order, so the result is the sequential one.
    /// False (nothing changed) when they might not fit.
    fn extend_parallel(&mut self, sampler: &Sampler, view: &ViewLod, base: f64) -> bool {
        let room = self.budget - (self.ranks.len() - self.prefix as usize);
        let chunks = self.bins.len().div_ceil(BIN_CHUNK);
        let mut lists = std::mem::take(&mut self.lists);
        lists.resize_with(chunks, Default::default);
        let this = &*self;
        let (bins, reach) = (&this.bins, &this.reach);
        let frustum = Frustum::new(view);
        // The ranks a bin lacks, and how many of them it should hold.
        let expected: f64 = lists
            .par_iter_mut()
            .enumerate()
            .map(|(c, list)| {
                list.needs.clear();
                let mut expected = 0.0;
                for s in c * BIN_CHUNK..((c + 1) * BIN_CHUNK).min(bins.len()) {
                    let need = this.need(s, &frustum, base);
                    list.needs.push(need);
                    if need > reach[s] {
                        expected += f64::from(need - reach[s]) * bins[s].share + COVER_SLACK;
                    }
                }
                expected
            })
            .sum();
        if expected * 2.0 > room as f64 {
            self.lists = lists;
            return false;
        }
        let total: usize = lists
            .par_iter_mut()
            .enumerate()
            .map(|(c, list)| {
                list.ranks.clear();
                list.runs.clear();
                list.reach.clear();
                for (i, s) in (c * BIN_CHUNK..((c + 1) * BIN_CHUNK).min(bins.len())).enumerate() {
                    let need = list.needs[i];
                    let before = list.ranks.len();
                    let now = if need > reach[s] {
                        sampler.progressive_ranks_in_cover(
                            &bins[s].cover,
                            reach[s],
                            need,
                            usize::MAX,
                            &mut list.ranks,
                        )
                    } else {
                        reach[s]
                    };
                    list.reach.push(now);
                    if list.ranks.len() > before {
                        list.runs
                            .push((s as u32, (list.ranks.len() - before) as u32));
                    }
                }
                list.ranks.len()
            })
            .sum();
        if total > room {
            // Far more than expected: let the sequential pass spend the budget.
            self.lists = lists;
            return false;
        }
        for (c, list) in lists.iter().enumerate() {
            let first = c * BIN_CHUNK;
            self.reach[first..first + list.reach.len()].copy_from_slice(&list.reach);
            let mut end = self.ranks.len() as u32;
            for &(bin, count) in &list.runs {
                end += count;
                self.runs.push((bin, end));
            }
            self.ranks.extend_from_slice(&list.ranks);
        }
        self.lists = lists;
        true
    }

    /// Computes the sites of the ranks listed from entry `start` on.
    fn finish(&mut self, sampler: &Sampler, start: usize) -> PoolChange {
        let end = self.ranks.len();
        if end == start {
            return PoolChange::Unchanged;
        }
        self.sites.resize(end, SampleSite::default());
        let (runs, bins, ranks) = (&self.runs, &self.bins, &self.ranks);
        // Fixed chunks of entries, each split at the bins' runs: a bin's cells are
        // searched alone, and the work split does not depend on the thread count.
        self.sites[start..]
            .par_chunks_mut(1024)
            .enumerate()
            .for_each(|(c, dst)| {
                let (first, last) = (start + c * 1024, start + c * 1024 + dst.len());
                let mut run = runs.partition_point(|&(_, end)| end as usize <= first);
                let mut at = first;
                while at < last {
                    let (bin, end) = runs[run];
                    let stop = (end as usize).min(last);
                    sampler.progressive_cover_sites_of(
                        &bins[bin as usize].cover,
                        &ranks[at..stop],
                        &mut dst[at - first..stop - first],
                    );
                    at = stop;
                    run += 1;
                }
            });
        PoolChange::Appended(start..end)
    }

    /// Writes each entry's fade weight under `view` with base count `base` into `out`
    /// (0 for an entry that is not visible), computing positions and normals on the
    /// CPU as [`Sampler::record`] does: the reference a GPU cull is checked against.
    /// Panics when `out` is not one weight per entry.
    pub fn fades_into(&self, sampler: &Sampler, view: &ViewLod, base: f64, out: &mut [f32]) {
        assert_eq!(out.len(), self.len(), "one weight per entry");
        out.par_chunks_mut(4096)
            .zip(self.sites.par_chunks(4096))
            .zip(self.ranks.par_chunks(4096))
            .for_each(|((dst, sites), ranks)| {
                for ((slot, site), &rank) in dst.iter_mut().zip(sites).zip(ranks) {
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
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::FieldSpec;
    use crate::mesh::TriMesh;
    use crate::surface::{Preprocessed, SurfaceOptions};
    use std::sync::Arc;

    /// The torus fixture of `surface` (1 by 0.4, a 3:1 field), preprocessed.
    fn torus_sampler() -> Sampler {
        let (mesh, field) = crate::surface::tests::torus_case();
        Preprocessed::build(mesh, field, &SurfaceOptions::default())
            .expect("preprocessed")
            .sampler
    }

    fn view(eye: DVec3, max: f64) -> ViewLod {
        view_at(eye, DVec3::ZERO, max)
    }

    fn view_at(eye: DVec3, target: DVec3, max: f64) -> ViewLod {
        let fov = 50f64.to_radians();
        let proj = glam::camera::rh::proj::directx::perspective(fov as f32, 1.0, 0.01, 100.0);
        let look =
            glam::camera::rh::view::look_at_mat4(eye.as_vec3(), target.as_vec3(), glam::Vec3::Y);
        ViewLod {
            clip_from_world: (proj * look).as_dmat4(),
            eye,
            focal_pixels: 500.0 / (2.0 * (fov / 2.0).tan()),
            reference: 5000.0,
            max,
            cull_back_faces: false,
        }
    }

    /// The visible ranks and their sites, by a scan of the whole sequence up to `end`.
    fn scan(s: &Sampler, seed: u64, end: u32, v: &ViewLod, base: f64) -> Vec<(u32, SampleSite)> {
        let mut sites = vec![SampleSite::default(); end as usize];
        s.progressive_sites_into(seed, 0, &mut sites);
        (0..end)
            .zip(sites)
            .filter(|&(k, site)| {
                let r = s
                    .record(site.face, site.barycentric().map(f64::from), 0, k, 1)
                    .expect("record");
                let p = DVec3::from(r.position.map(f64::from));
                let n = DVec3::from(r.normal.map(f64::from));
                fade(k, base, v.multiplier(p, n)) > 0.0
            })
            .collect()
    }

    fn held_visible(pool: &LodPool, s: &Sampler, v: &ViewLod, base: f64) -> Vec<(u32, SampleSite)> {
        let mut fades = vec![0.0; pool.len()];
        pool.fades_into(s, v, base, &mut fades);
        let mut shown: Vec<(u32, SampleSite)> = (0..pool.len())
            .filter(|&i| fades[i] > 0.0)
            .map(|i| (pool.ranks()[i], pool.sites()[i]))
            .collect();
        shown.sort_by_key(|e| e.0);
        shown
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
            let change = pool.update(&s, &v, base);
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
        assert_eq!(pool.update(&s, &v, base), PoolChange::Unchanged);
    }

    #[test]
    fn an_outgrown_budget_rebuilds_for_the_view_and_caps_in_segment_order() {
        let s = torus_sampler();
        let base = 20_000.0;
        // Two close-ups of opposite sides of the ring.
        let near = view_at(DVec3::new(1.0, 0.0, 1.2), DVec3::X, 50.0);
        let other = view_at(DVec3::new(-1.0, 0.0, 1.2), -DVec3::X, 50.0);
        let mut probe = LodPool::new(&s, 3, 20_000, usize::MAX / 2);
        probe.update(&s, &near, base);
        let needed = probe.len() - 20_000;
        // Room for one view's ranks, not two.
        let mut pool = LodPool::new(&s, 3, 20_000, needed + needed / 4);
        assert!(matches!(
            pool.update(&s, &near, base),
            PoolChange::Appended(_)
        ));
        assert_eq!(pool.update(&s, &other, base), PoolChange::Rebuilt);
        assert!(pool.complete(&other, base));
        let end = pool.ranks().iter().copied().max().unwrap_or(0) + 1;
        assert_eq!(
            held_visible(&pool, &s, &other, base),
            scan(&s, 3, end, &other, base)
        );
        // A view needing more than the budget gets what fits, and no rebuild loop.
        let greedy = view_at(DVec3::new(1.0, 0.0, 0.7), DVec3::X, 1e6);
        pool.update(&s, &greedy, base);
        assert!(!pool.complete(&greedy, base));
        assert!(pool.len() - 20_000 <= needed + needed / 4);
        assert_eq!(pool.update(&s, &greedy, base), PoolChange::Unchanged);
    }

    #[test]
    fn parallel_and_sequential_updates_list_the_same_entries() {
        let s = torus_sampler();
        let v = view_at(DVec3::new(1.0, 0.2, 1.3), DVec3::X, 30.0);
        // A roomy budget takes the parallel path; one that the ranks exactly fill is
        // refused by its estimate and takes the sequential one.
        let mut roomy = LodPool::new(&s, 4, 10_000, 10_000_000);
        roomy.update(&s, &v, 10_000.0);
        let added = roomy.len() - 10_000;
        assert!(added > 1000, "{added}");
        let mut tight = LodPool::new(&s, 4, 10_000, added);
        tight.update(&s, &v, 10_000.0);
        assert!(tight.complete(&v, 10_000.0));
        assert_eq!(tight.ranks(), roomy.ranks());
        assert_eq!(tight.sites(), roomy.sites());
    }

    #[test]
    fn bounds_follow_a_deformed_mesh() {
        let s = torus_sampler();
        let mut pool = LodPool::new(&s, 1, 0, 0);
        let rest = s.mesh();
        // Stretched along z and bent: the bounds of the rest mesh no longer hold.
        let moved: Vec<DVec3> = rest
            .positions()
            .iter()
            .map(|p| DVec3::new(p.x, p.y + 0.5 * p.x * p.x, 3.0 * p.z))
            .collect();
        let bent = TriMesh::new(moved, rest.triangles().to_vec()).expect("mesh");
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
    fn the_pool_is_the_same_for_any_thread_count() {
        let s = torus_sampler();
        let v = view(DVec3::new(0.5, 0.0, 1.6), 100.0);
        let run = || {
            let mut pool = LodPool::new(&s, 9, 10_000, 200_000);
            pool.update(&s, &v, 10_000.0);
            (pool.sites().to_vec(), pool.ranks().to_vec())
        };
        assert_eq!(crate::on_threads(1, run), crate::on_threads(2, run));
    }

    #[test]
    fn a_single_segment_sampler_enumerates_every_rank() {
        let mesh = Arc::new(crate::mesh::shapes::plane(1.0, 4).expect("plane"));
        let field = FieldSpec::Constant {
            direction: [1.0, 0.0, 0.0],
            anisotropy: 2.0,
            density: 1.0,
        }
        .build(&mesh)
        .expect("field");
        let pre =
            Preprocessed::build(mesh, Arc::new(field), &SurfaceOptions::default()).expect("built");
        let s = pre.sampler;
        assert_eq!(s.segments().len(), 1);
        let mut all = Vec::new();
        s.progressive_ranks_in_segment(2, 0, 10, 300, usize::MAX, &mut all);
        assert_eq!(all, (10..300).collect::<Vec<_>>());
    }
}
