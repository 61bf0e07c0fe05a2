//! Validity of a parameterized segment (section 5.2) and its angle statistics (section
//! 7.3.1).
//!
//! Flipped triangles and boundary self-intersections are decided with the exact
//! predicates of [`super::predicates`]. A locally injective map of a disc (no flipped
//! triangle) is globally injective when its boundary is a simple curve, so an overlap
//! shows as boundary edges that meet away from shared endpoints. Candidate pairs come
//! from a uniform grid over the boundary's bounding box with about one cell per edge.
//! Cost: O(F) for flips and angles, O(B + pairs) for the boundary (O(B) when the
//! boundary is spread evenly; edges piled into a few cells degrade towards O(B^2)).

use crate::fast_map::{FastMap, fast_map};
use std::cmp::Ordering;
use std::collections::hash_map::Entry;

use glam::{DVec2, DVec3};

use crate::mesh::{NONE, TriMesh};

use super::comb::Frames;
use super::patch::Patch;
use super::predicates::{orient2d, segments_intersect, segments_overlap_from};
use super::solve::hat_gradients;
use super::{ParamOptions, ParamReport};

/// Copies of one mesh vertex closer than this (relative to the uv bounding-box
/// diagonal) are treated as one point: the seam between them is closed, not open.
const SEAM_TOLERANCE: f64 = 1e-9;

/// Cells per side of the candidate grid, at most.
const MAX_GRID_SIDE: usize = 2048;

/// Number of triangles whose signed area in `uv` is zero or negative (exact).
pub fn count_flipped(uv: &[DVec2], triangles: &[[u32; 3]]) -> usize {
    triangles
        .iter()
        .filter(|t| {
            orient2d(uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]) != Ordering::Greater
        })
        .count()
}

/// Boundary edges of a triangle mesh: directed sides `[a, b]` (in the triangles'
/// orientation) whose reverse `[b, a]` is no triangle's side, in order of appearance.
pub fn boundary_edges(triangles: &[[u32; 3]]) -> Vec<[u32; 2]> {
    let mut sides: FastMap<(u32, u32), u32> = fast_map(3 * triangles.len());
    for t in triangles {
        for k in 0..3 {
            *sides.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
        }
    }
    let mut out = Vec::new();
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if !sides.contains_key(&(b, a)) {
                out.push([a, b]);
            }
        }
    }
    out
}

/// Whether two boundary edges (local vertex pairs) overlap other than at a shared
/// endpoint: a shared endpoint only counts if the edges fold back onto each other; two
/// edges joining the same two vertices coincide.
fn pair_overlaps(uv: &[DVec2], [a, b]: [u32; 2], [c, d]: [u32; 2]) -> bool {
    let p = |v: u32| uv[v as usize];
    if (a == c && b == d) || (a == d && b == c) {
        true
    } else if a == c {
        segments_overlap_from(p(a), p(b), p(d))
    } else if a == d {
        segments_overlap_from(p(a), p(b), p(c))
    } else if b == c {
        segments_overlap_from(p(b), p(a), p(d))
    } else if b == d {
        segments_overlap_from(p(b), p(a), p(c))
    } else {
        segments_intersect(p(a), p(b), p(c), p(d))
    }
}

/// Whether the polygon edges `edges` (pairs of indices into `uv`) meet anywhere other
/// than at shared endpoints (index equality), decided exactly: crossings, touchings,
/// collinear overlaps, and distinct vertices at the same point all count. Edges whose
/// two ends are the same index are ignored. Applied to
/// [`boundary_edges`] of a parameter mesh without flipped triangles, `true` means the
/// mesh overlaps itself.
///
/// ```
/// use glam::DVec2;
/// use strata_engine::param::boundary_overlaps;
/// // A bow tie: the closed polygon 0-1-2-3 crosses itself.
/// let uv = [DVec2::new(0.0, 0.0), DVec2::new(1.0, 1.0), DVec2::new(1.0, 0.0), DVec2::new(0.0, 1.0)];
/// assert!(boundary_overlaps(&uv, &[[0, 1], [1, 2], [2, 3], [3, 0]]));
/// assert!(!boundary_overlaps(&uv, &[[0, 2], [2, 1], [1, 3], [3, 0]]));
/// ```
pub fn boundary_overlaps(uv: &[DVec2], edges: &[[u32; 2]]) -> bool {
    !boundary_crossings(uv, edges, 1).is_empty()
}

/// The pairs of `edges` that meet other than at shared endpoints (as
/// [`boundary_overlaps`] decides), at most `limit` of them, each pair once in the
/// order the grid finds them.
pub(crate) fn boundary_crossings(
    uv: &[DVec2],
    edges: &[[u32; 2]],
    limit: usize,
) -> Vec<[[u32; 2]; 2]> {
    let mut found = Vec::new();
    let edges: Vec<[u32; 2]> = edges.iter().copied().filter(|[a, b]| a != b).collect();
    if edges.len() < 2 || limit == 0 {
        return found;
    }
    let (lo, hi) = edges.iter().flatten().fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(lo, hi), &v| (lo.min(uv[v as usize]), hi.max(uv[v as usize])),
    );
    let size = hi - lo;
    let (nx, ny) = grid_dims(size, edges.len());
    // Monotone in the coordinate, so edges whose boxes overlap share a cell.
    let cell = |x: f64, lo: f64, size: f64, n: usize| -> usize {
        if size > 0.0 {
            (((x - lo) / size * n as f64) as usize).min(n - 1)
        } else {
            0
        }
    };
    let ranges: Vec<[usize; 4]> = edges
        .iter()
        .map(|[a, b]| {
            let (p, q) = (uv[*a as usize], uv[*b as usize]);
            [
                cell(p.x.min(q.x), lo.x, size.x, nx),
                cell(p.x.max(q.x), lo.x, size.x, nx),
                cell(p.y.min(q.y), lo.y, size.y, ny),
                cell(p.y.max(q.y), lo.y, size.y, ny),
            ]
        })
        .collect();
    // Bucket edges per cell (CSR).
    let mut offsets = vec![0usize; nx * ny + 1];
    for r in &ranges {
        for y in r[2]..=r[3] {
            for x in r[0]..=r[1] {
                offsets[y * nx + x + 1] += 1;
            }
        }
    }
    for i in 0..nx * ny {
        offsets[i + 1] += offsets[i];
    }
    let mut fill = offsets.clone();
    let mut bucket = vec![0u32; offsets[nx * ny]];
    for (i, r) in ranges.iter().enumerate() {
        for y in r[2]..=r[3] {
            for x in r[0]..=r[1] {
                bucket[fill[y * nx + x]] = i as u32;
                fill[y * nx + x] += 1;
            }
        }
    }
    for y in 0..ny {
        for x in 0..nx {
            let c = y * nx + x;
            let list = &bucket[offsets[c]..offsets[c + 1]];
            for (s, &i) in list.iter().enumerate() {
                for &j in &list[s + 1..] {
                    let (ri, rj) = (ranges[i as usize], ranges[j as usize]);
                    // Test each pair once: in the first cell the two boxes share.
                    if ri[0].max(rj[0]) != x || ri[2].max(rj[2]) != y {
                        continue;
                    }
                    if pair_overlaps(uv, edges[i as usize], edges[j as usize]) {
                        found.push([edges[i as usize], edges[j as usize]]);
                        if found.len() == limit {
                            return found;
                        }
                    }
                }
            }
        }
    }
    found
}

/// Grid of about `count` square-ish cells over a box of `size`.
fn grid_dims(size: DVec2, count: usize) -> (usize, usize) {
    let side = |extent: f64, h: f64| ((extent / h).ceil() as usize).clamp(1, MAX_GRID_SIDE);
    let count = count as f64;
    if size.x > 0.0 && size.y > 0.0 {
        let h = (size.x * size.y / count).sqrt();
        (side(size.x, h), side(size.y, h))
    } else if size.x > 0.0 {
        (side(size.x, size.x / count), 1)
    } else if size.y > 0.0 {
        (1, side(size.y, size.y / count))
    } else {
        (1, 1)
    }
}

/// [`boundary_overlaps`] after closing seams: copies of one mesh vertex within
/// [`SEAM_TOLERANCE`] of each other become one vertex, and boundary edges that then
/// run both ways between the same two vertices (the two sides of a closed seam) are
/// glued, i.e. dropped.
fn overlaps_with_closed_seams(uv: &[DVec2], edges: &[[u32; 2]], local_to_mesh: &[u32]) -> bool {
    boundary_overlaps(uv, &with_closed_seams(uv, edges, local_to_mesh))
}

/// The boundary edges left after closing seams (see [`overlaps_with_closed_seams`]),
/// in the welded vertices' numbering (each welded vertex is one of its copies).
pub(crate) fn with_closed_seams(
    uv: &[DVec2],
    edges: &[[u32; 2]],
    local_to_mesh: &[u32],
) -> Vec<[u32; 2]> {
    let (lo, hi) = uv.iter().fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    let tolerance = SEAM_TOLERANCE * (hi - lo).length();
    let mut order: Vec<u32> = (0..uv.len() as u32).collect();
    order.sort_unstable_by_key(|&v| (local_to_mesh[v as usize], v));
    let mut canonical: Vec<u32> = (0..uv.len() as u32).collect();
    for group in order.chunk_by(|a, b| local_to_mesh[*a as usize] == local_to_mesh[*b as usize]) {
        for (k, &v) in group.iter().enumerate() {
            if let Some(&root) = group[..k].iter().find(|&&w| {
                canonical[w as usize] == w && uv[w as usize].distance(uv[v as usize]) <= tolerance
            }) {
                canonical[v as usize] = root;
            }
        }
    }
    let welded: Vec<[u32; 2]> = edges
        .iter()
        .map(|e| e.map(|v| canonical[v as usize]))
        .collect();
    let mut count: FastMap<(u32, u32), usize> = fast_map(0);
    for [a, b] in &welded {
        *count.entry((*a, *b)).or_insert(0) += 1;
    }
    // Per direction, how many edges survive gluing against the reverse direction.
    let mut quota: FastMap<(u32, u32), usize> = fast_map(count.len());
    for (&(a, b), &n) in &count {
        let reverse = count.get(&(b, a)).copied().unwrap_or(0);
        quota.insert((a, b), n - n.min(reverse));
    }
    let mut kept = Vec::with_capacity(welded.len());
    for e in welded {
        if let Entry::Occupied(mut q) = quota.entry((e[0], e[1]))
            && *q.get() > 0
        {
            *q.get_mut() -= 1;
            kept.push(e);
        }
    }
    kept
}

/// The boundary edges of a patch (local vertex pairs, in the triangles' orientation).
pub(crate) fn patch_boundary(patch: &Patch) -> Vec<[u32; 2]> {
    patch
        .triangles
        .iter()
        .zip(&patch.neighbors)
        .flat_map(|(t, nb)| {
            (0..3)
                .filter(|&k| nb[k].0 == NONE)
                .map(move |k| [t[k], t[(k + 1) % 3]])
        })
        .collect()
}

/// Computes the report of a solved segment.
pub(crate) fn report(
    mesh: &TriMesh,
    patch: &Patch,
    frames: &Frames,
    uv: &[DVec2],
    options: &ParamOptions,
) -> ParamReport {
    let flipped = count_flipped(uv, &patch.triangles);
    let edges = patch_boundary(patch);
    let overlaps = overlaps_with_closed_seams(uv, &edges, &patch.local_to_mesh);
    let (mut weighted, mut total_area, mut max_angle) = (0.0, 0.0, 0.0f64);
    let mut stretch_sum = 0.0;
    for (i, (&f, t)) in patch.faces.iter().zip(&patch.triangles).enumerate() {
        let area = mesh.face_areas()[f as usize];
        let grads = hat_gradients(
            mesh.face_positions(f),
            mesh.face_normals()[f as usize],
            area,
        );
        let (gu, gv) = (0..3).fold((glam::DVec3::ZERO, glam::DVec3::ZERO), |(gu, gv), k| {
            let p = uv[t[k] as usize];
            (gu + grads[k] * p.x, gv + grads[k] * p.y)
        });
        let m1 = frames.m1[i];
        let image = DVec2::new(gu.dot(m1), gv.dot(m1));
        if area > 0.0 {
            let m2 = mesh.face_normals()[f as usize].cross(m1);
            let [s1, s2] = frames.sqrt_l[i];
            stretch_sum += area * stretch(gu, gv, m1, m2, s1, s2);
        }
        let angle = if image == DVec2::ZERO {
            90.0
        } else {
            image.y.abs().atan2(image.x.abs()).to_degrees()
        };
        weighted += area * angle;
        total_area += area;
        max_angle = max_angle.max(angle);
    }
    let mean_angle = weighted / total_area;
    let mean_stretch = stretch_sum / total_area;
    let aligned = if frames.isotropic_fallback {
        mean_stretch <= options.max_stretch
    } else {
        mean_angle.to_radians() < options.gamma
    };
    ParamReport {
        flipped,
        overlaps,
        mean_angle_deg: mean_angle,
        max_angle_deg: max_angle,
        valid: flipped == 0 && !overlaps && aligned,
        isotropic_fallback: frames.isotropic_fallback,
        inconsistent_combing: frames.inconsistent,
        mean_anisotropy: frames.mean_anisotropy,
        mean_stretch,
        relaxed_vertices: 0,
    }
}

/// Largest per-face stretch counted, so that one degenerate triangle cannot make a
/// segment's mean infinite (it is flipped anyway, which the report counts).
const MAX_FACE_STRETCH: f64 = 1e3;

/// Stretch of one face: the ratio of the singular values of the map from the field's
/// metric to `uv`, `J T^-1`, where `J` has rows `gu` and `gv` (the gradients of `u`
/// and `v`) and `T` is the target, `diag(s1, s2)` in the frame `(m1, m2)`. 1 when the
/// strata are as the field asks (squares in its metric), `k` when they are `k` times
/// longer one way than the other. Capped at [`MAX_FACE_STRETCH`].
pub(crate) fn stretch(gu: DVec3, gv: DVec3, m1: DVec3, m2: DVec3, s1: f64, s2: f64) -> f64 {
    let (a, b) = (gu.dot(m1) / s1, gu.dot(m2) / s2);
    let (c, d) = (gv.dot(m1) / s1, gv.dot(m2) / s2);
    let frobenius = a * a + b * b + c * c + d * d;
    let det = (a * d - b * c).abs();
    // The singular values' ratio r solves r + 1/r = frobenius / det.
    let q = frobenius / det;
    let r = 0.5 * (q + (q * q - 4.0).max(0.0).sqrt());
    if r.is_finite() {
        r.min(MAX_FACE_STRETCH)
    } else {
        MAX_FACE_STRETCH
    }
}
