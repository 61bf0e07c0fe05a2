//! The sampler flattened into plain tables for a data-parallel sampler (a GPU compute
//! pass) that draws the same samples as [`Sampler::sample_sites_into`], and the small
//! per-request table of its groups.
//!
//! Input: a built [`Sampler`]. Output: [`FlatSampler`] (built once per preprocessing):
//! every segment's leaves in chain order with their cumulative measures as 64-bit
//! fixed-point fractions of the total, their keys, candidate triangles, the clipped
//! pieces of boundary leaves, the domain triangles' corners and faces; and per request
//! ([`FlatSampler::request`]) the groups that receive samples with their counts, first
//! outputs, leaf ranges, random-stream keys and fixed-point extents, and the levels of
//! the continuous map per segment. Cost: O(cells + candidates) once; O(segments) per
//! request. The engine stays GPU-free: these are plain vectors.
//!
//! Fixed point: the measure before leaf `l` in chain order, over the total `T`, is
//! stored as `floor(C_l / T 2^64)`. A group's value `v` in `[0, 1)` then maps to
//! `G_lo + floor(v G_len)`, the same leaf as the sequential sampler's `v M_group` in
//! `f64` except within about `2^-52` of the group's measure of a leaf boundary.

use super::sampler::Sampler;
use super::stratified::Allocation;
use crate::curve::SegmentCurve;

/// One leaf: `[x, y, meta, first, len]` where `meta` holds the level (bits 0..5), the
/// Hilbert state (5..7), whether the leaf is full (bit 7) and the segment's slot in
/// chain order (8..32); `first`/`len` index [`FlatSampler::candidates`] for a full
/// leaf and [`FlatSampler::pieces`] for a boundary leaf.
pub type FlatLeaf = [u32; 5];

/// A clipped piece of a boundary leaf: `[triangle, corners, measure lo, measure hi,
/// x0, y0, ...]` with the triangle a global domain-triangle index, the measure as a
/// fraction of the leaf's measure in 2^62 fixed point (the pieces' exact measures sum
/// to the leaf's up to round-off), and up to 8 corners in the leaf's own unit square
/// (`f32`).
pub type FlatPiece = [u32; 20];

/// A domain triangle: its corners' `u, v` in the unit square (`f32` bits) and its mesh
/// face.
pub type FlatTriangle = [u32; 7];

/// A group that receives samples in one request: `[first output, count, first leaf,
/// leaf end, key lo, key hi, G_lo lo, G_lo hi, G_len lo, G_len hi]`.
pub type FlatGroup = [u32; 10];

/// Why a request cannot be drawn from the flat tables.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum FlatError {
    /// A boundary leaf expects more than one sample, where the sequential sampler
    /// descends through its sub-cells (not part of the flat tables).
    #[error(
        "{count} samples put more than one sample in a boundary leaf (about {limit} at most can be drawn from these cells)"
    )]
    BoundaryDescent {
        /// The request.
        count: u64,
        /// About the largest count that needs no descent (rounding of the allocation
        /// may refuse a count slightly below it).
        limit: u64,
    },
    /// The request or the tables exceed 32-bit indices.
    #[error("{what} ({value}) exceeds 32-bit indices")]
    TooLarge {
        /// What.
        what: &'static str,
        /// How many.
        value: u64,
    },
}

/// Per segment slot (chain order), what a request needs.
#[derive(Clone, Debug)]
struct Slot {
    segment_index: usize,
    leaf_lo: u32,
    leaf_hi: u32,
    /// The largest measure of a boundary leaf (as `cum[l + 1] - cum[l]`).
    max_boundary: f64,
}

/// The sampler's cells as flat tables ([module docs](self)).
#[derive(Clone, Debug, Default)]
pub struct FlatSampler {
    /// Per leaf (and one past the last), the measure before it over the total, in
    /// 64-bit fixed point.
    pub cumulative: Vec<u64>,
    /// The leaves in chain order ([`FlatLeaf`]).
    pub leaves: Vec<FlatLeaf>,
    /// Candidate triangles of full leaves (global domain-triangle indices).
    pub candidates: Vec<u32>,
    /// Clipped pieces of boundary leaves ([`FlatPiece`]).
    pub pieces: Vec<FlatPiece>,
    /// Domain triangles of every segment ([`FlatTriangle`]).
    pub triangles: Vec<FlatTriangle>,
    /// Per slot, the segment id written into samples.
    pub slot_segments: Vec<u32>,
    slots: Vec<Slot>,
}

/// One request's groups and levels ([`FlatSampler::request`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FlatRequest {
    /// The groups with at least one sample, in output order ([`FlatGroup`]).
    pub groups: Vec<FlatGroup>,
    /// Per slot, the levels of the continuous map in its full leaves.
    pub levels: Vec<u32>,
}

fn split(v: u64) -> [u32; 2] {
    [v as u32, (v >> 32) as u32]
}

fn f32_bits(x: f64) -> u32 {
    (x as f32).to_bits()
}

impl FlatSampler {
    /// Flattens `sampler`'s cells.
    pub fn new(sampler: &Sampler) -> Result<Self, FlatError> {
        let mut flat = FlatSampler::default();
        let total = sampler.chain_cumulative.last().copied().unwrap_or(0.0);
        let fixed = |c: f64| (c / total * 18_446_744_073_709_551_616.0) as u64;
        for (slot, &si) in sampler.chains.order.iter().enumerate() {
            let seg = &sampler.segments[si as usize];
            let curve = &seg.curve;
            let base = sampler.chain_cumulative[slot];
            let tri_base = flat.triangles.len() as u64;
            for t in 0..curve.triangle_count() {
                let c = curve.triangle_uv(t);
                let mut row = [0u32; 7];
                for (k, p) in c.iter().enumerate() {
                    row[2 * k] = f32_bits(p.x);
                    row[2 * k + 1] = f32_bits(p.y);
                }
                row[6] = seg.faces[t];
                flat.triangles.push(row);
            }
            let leaf_lo = flat.leaves.len() as u32;
            let mut max_boundary = 0.0f64;
            let cum = curve.cumulative();
            for (l, key) in curve.cells().iter().enumerate() {
                flat.cumulative.push(fixed(base + cum[l]));
                let meta = u32::from(key.level())
                    | u32::from(key.state().0) << 5
                    | u32::from(key.full()) << 7
                    | (slot as u32) << 8;
                let global = |t: u32| -> Result<u32, FlatError> {
                    u32::try_from(tri_base + u64::from(t)).map_err(|_| FlatError::TooLarge {
                        what: "domain triangles",
                        value: tri_base + u64::from(t),
                    })
                };
                let (first, len) = if key.full() {
                    let first = flat.candidates.len() as u32;
                    for &t in curve.leaf_triangles(l) {
                        flat.candidates.push(global(t)?);
                    }
                    (first, flat.candidates.len() as u32 - first)
                } else {
                    max_boundary = max_boundary.max(cum[l + 1] - cum[l]);
                    let first = flat.pieces.len() as u32;
                    flat.push_pieces(curve, l, global)?;
                    (first, flat.pieces.len() as u32 - first)
                };
                flat.leaves.push([key.x(), key.y(), meta, first, len]);
            }
            flat.slot_segments.push(seg.segment);
            flat.slots.push(Slot {
                segment_index: si as usize,
                leaf_lo,
                leaf_hi: flat.leaves.len() as u32,
                max_boundary,
            });
        }
        flat.cumulative.push(u64::MAX);
        if flat.leaves.len() as u64 >= 1 << 31 || flat.slots.len() >= 1 << 24 {
            return Err(FlatError::TooLarge {
                what: "leaves",
                value: flat.leaves.len() as u64,
            });
        }
        Ok(flat)
    }

    /// Appends the pieces of boundary leaf `l` of `curve`.
    fn push_pieces(
        &mut self,
        curve: &SegmentCurve,
        l: usize,
        global: impl Fn(u32) -> Result<u32, FlatError>,
    ) -> Result<(), FlatError> {
        let key = curve.cells()[l];
        let (origin, size) = (key.origin(), key.size());
        let cum = curve.cumulative();
        let node = cum[l + 1] - cum[l];
        let mut result = Ok(());
        curve.leaf_pieces(l, |t, poly, m| {
            let tri = match global(t) {
                Ok(t) => t,
                Err(e) => {
                    result = Err(e);
                    return;
                }
            };
            let mut row = [0u32; 20];
            row[0] = tri;
            let pts = poly.points();
            row[1] = pts.len().min(8) as u32;
            let share = if node > 0.0 { m / node } else { 0.0 };
            [row[2], row[3]] = split((share * 4_611_686_018_427_387_904.0) as u64);
            for (k, p) in pts.iter().take(8).enumerate() {
                let q = (*p - origin) / size;
                row[4 + 2 * k] = f32_bits(q.x);
                row[5 + 2 * k] = f32_bits(q.y);
            }
            self.pieces.push(row);
        });
        result
    }

    /// Bytes of the tables (what a GPU holds of them).
    pub fn bytes(&self) -> usize {
        self.cumulative.len() * 8
            + self.leaves.len() * 20
            + self.candidates.len() * 4
            + self.pieces.len() * 80
            + self.triangles.len() * 28
            + self.slot_segments.len() * 4
    }

    /// The groups and levels of an `n`-sample stratified request for `seed` of
    /// `sampler` (the one these tables were built from): the allocation of
    /// [`Sampler::sample_sites_into`] over segments or chains, O(segments).
    pub fn request(&self, sampler: &Sampler, n: u64, seed: u64) -> Result<FlatRequest, FlatError> {
        if n > u64::from(u32::MAX) {
            return Err(FlatError::TooLarge {
                what: "samples per request",
                value: n,
            });
        }
        let linked = sampler.uses_chains(n as usize);
        let segments = sampler.segments();
        let measure = |i: u32| segments[i as usize].curve.measure();
        // The groups as runs of slots in chain order, with their measures summed as
        // the sampler sums them.
        let groups: Vec<(u32, u32, f64)> = if linked {
            let mut at = 0u32;
            sampler
                .chains_iter()
                .map(|members| {
                    let lo = at;
                    at += members.len() as u32;
                    (lo, at, members.iter().map(|&i| measure(i)).sum())
                })
                .collect()
        } else {
            (0..segments.len() as u32)
                .map(|i| {
                    let slot = sampler.chain_slot[i as usize];
                    (slot, slot + 1, measure(i))
                })
                .collect()
        };
        let mut request = FlatRequest {
            groups: Vec::new(),
            levels: vec![0; self.slots.len()],
        };
        let mut first = 0u64;
        let mut limit = u64::MAX;
        for (i, count) in Allocation::new(n, groups.iter().map(|g| g.2)) {
            let (slot_lo, slot_hi, group_measure) = groups[i];
            let start = first;
            first += count;
            if count == 0 {
                continue;
            }
            let per_sample = count as f64 / group_measure;
            for slot in slot_lo..slot_hi {
                let s = &self.slots[slot as usize];
                let curve = &segments[s.segment_index].curve;
                if s.max_boundary * per_sample > 1.0 {
                    let scaled = (n as f64 / (s.max_boundary * per_sample)).floor() as u64;
                    limit = limit.min(scaled);
                }
                let share = curve.measure() / group_measure;
                let per_leaf = count as f64 * share / curve.cell_count() as f64;
                let levels = (per_leaf.max(1.0).log2() * 0.5).ceil() as u32 + 5;
                request.levels[slot as usize] = levels.min(u32::from(curve.options().leaf_levels));
            }
            let (lo, hi) = (
                self.slots[slot_lo as usize].leaf_lo,
                self.slots[slot_hi as usize - 1].leaf_hi,
            );
            let g_lo = self.cumulative[lo as usize];
            let g_len = self.cumulative[hi as usize].wrapping_sub(g_lo);
            let key = split(crate::rng::stream_key(seed, i as u64));
            let (g_lo, g_len) = (split(g_lo), split(g_len));
            request.groups.push([
                start as u32,
                count as u32,
                lo,
                hi,
                key[0],
                key[1],
                g_lo[0],
                g_lo[1],
                g_len[0],
                g_len[1],
            ]);
        }
        if limit != u64::MAX {
            return Err(FlatError::BoundaryDescent { count: n, limit });
        }
        Ok(request)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sample::SampleSite;

    fn torus() -> crate::surface::Preprocessed {
        let (mesh, field) = crate::fixtures::torus_case();
        crate::surface::Preprocessed::build(mesh, field, &Default::default()).expect("preprocessed")
    }

    /// The tables hold every leaf once with non-decreasing fixed-point cumulative
    /// measures, candidates and pieces in range, and a request's groups cover the
    /// outputs in order with the counts of the sequential sampler's allocation: the
    /// per-segment counts of its sites.
    #[test]
    fn tables_and_requests_follow_the_sampler() {
        let pre = torus();
        let sampler = &pre.sampler;
        let flat = FlatSampler::new(sampler).expect("flat");
        let cells: usize = sampler
            .segments()
            .iter()
            .map(|s| s.curve.cell_count())
            .sum();
        assert_eq!(flat.leaves.len(), cells);
        assert_eq!(flat.cumulative.len(), cells + 1);
        assert!(flat.cumulative.windows(2).all(|w| w[0] <= w[1]));
        assert_eq!(flat.cumulative[0], 0);
        for leaf in &flat.leaves {
            let (first, len) = (leaf[3] as usize, leaf[4] as usize);
            assert!(len > 0, "{leaf:?}");
            if leaf[2] & 128 != 0 {
                assert!(first + len <= flat.candidates.len());
            } else {
                assert!(first + len <= flat.pieces.len());
                let sum: f64 = flat.pieces[first..first + len]
                    .iter()
                    .map(|p| (u64::from(p[2]) | u64::from(p[3]) << 32) as f64 / 2f64.powi(62))
                    .sum();
                assert!((sum - 1.0).abs() < 1e-3, "pieces sum to {sum}");
            }
        }
        assert!(
            flat.candidates
                .iter()
                .all(|&t| (t as usize) < flat.triangles.len())
        );
        assert!(flat.bytes() > 0);
        for n in [1u64, 7, 5000] {
            let request = flat.request(sampler, n, 3).expect("request");
            let mut sites = vec![SampleSite::default(); n as usize];
            sampler.sample_sites_into(3, &mut sites);
            let mut next = 0u32;
            for g in &request.groups {
                assert_eq!(g[0], next, "n {n}: groups in output order");
                assert!(g[1] > 0 && g[2] < g[3] && g[3] as usize <= cells);
                next += g[1];
                // Every sample of the group lies in a segment of its leaves.
                let slots: Vec<u32> = (g[2]..g[3])
                    .map(|l| flat.slot_segments[(flat.leaves[l as usize][2] >> 8) as usize])
                    .collect();
                for s in &sites[g[0] as usize..(g[0] + g[1]) as usize] {
                    assert!(slots.contains(&s.segment), "n {n}: {s:?}");
                }
            }
            assert_eq!(u64::from(next), n);
            assert!(request.levels.iter().all(|&l| l <= 12));
        }
        assert!(matches!(
            flat.request(sampler, 1 << 33, 3),
            Err(FlatError::TooLarge { .. })
        ));
    }
}
