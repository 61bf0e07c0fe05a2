//! Charts for isotropic fields (issue 18; the paper's section 3 leaves isotropic
//! regions to "previous methods").
//!
//! An isotropic tensor has no preferred direction, so a segment of isotropic faces
//! needs no alignment: any disc whose parameterization is bijective with moderate
//! stretch will do, and the cells carry the exact density measure, so the chart's area
//! distortion does not bias the samples. The largest such discs are those whose
//! normals stay within a cone: this module grows them by variational shape
//! approximation with normal proxies (Cohen-Steiner, Alliez and Desbrun 2004, the
//! `L^{2,1}` metric), started from a greedy cover with cones of half-angle
//! `max_normal_angle`:
//!
//! 1. greedy cover: faces in index order; an unassigned face seeds a chart that grows
//!    breadth-first through faces whose normal is within `max_normal_angle` of the
//!    seed's; the cover's chart count depends on the surface's normal variation,
//!    not on its resolution;
//! 2. [`LLOYD_ITERATIONS`] rounds of Lloyd relaxation: each chart's proxy is its
//!    area-weighted mean normal, its seed the face closest to it; every seed then
//!    floods at once, faces taken in increasing distance from the proxy normal of the
//!    chart reaching them (a priority flood, so each chart stays connected); charts
//!    under 1/[`SMALL_CHART_SHARE`] of the mean chart area give up their seed (the
//!    slivers the greedy cover leaves between caps).
//!
//! The charts are connected but need not be discs (a chart may ring a protrusion);
//! the parameterization's splitting handles those, as it handles overlaps.
//!
//! Cost: O(F) for the cover and for each Lloyd round (a bucket queue); deterministic
//! (no threads; the flood's order depends only on the input).

use std::collections::VecDeque;

use glam::DVec3;

use super::{Segmentation, segmentation_from_labels};
use crate::mesh::{NONE, TriMesh};

/// Default half-angle (radians) of the normal cones of the greedy cover: 60 degrees.
/// Measured on the isotropic bunny (69k faces), charts after splitting and their
/// face-weighted mean stretch: 40 degrees 124 and 1.010, 50 degrees 67 and 1.015, 60
/// degrees 48 and 1.019, 70 degrees 34 and 1.021. 60 keeps under the issue's 64 charts
/// with room, and the stretch barely grows past it.
pub const CHART_NORMAL_ANGLE: f64 = 60.0 * std::f64::consts::PI / 180.0;

/// Rounds of Lloyd relaxation after the greedy cover.
pub const LLOYD_ITERATIONS: usize = 4;

/// A chart smaller than the mean chart area over this gives up its seed in the Lloyd
/// rounds (unless it is the only chart of its connected component).
pub const SMALL_CHART_SHARE: f64 = 8.0;

/// Per face, its chart: the greedy cover relaxed by Lloyd rounds (see the module
/// docs). Charts are numbered from 0 by their lowest face; every face has one.
///
/// `max_normal_angle` (radians) is the half-angle of the greedy cover's cones; a
/// non-finite or non-positive value is read as [`CHART_NORMAL_ANGLE`].
pub fn chart_labels(mesh: &TriMesh, max_normal_angle: f64) -> Vec<u32> {
    let angle = if max_normal_angle.is_finite() && max_normal_angle > 0.0 {
        max_normal_angle.min(std::f64::consts::PI)
    } else {
        CHART_NORMAL_ANGLE
    };
    let normals = mesh.face_normals();
    let mut labels = greedy_cover(mesh, angle.cos());
    for _ in 0..LLOYD_ITERATIONS {
        let seeds = relaxed_seeds(mesh, &labels);
        labels = flood(mesh, normals, &seeds);
    }
    labels
}

/// The isotropic charts of `mesh` as a [`Segmentation`] (no singularities, no cut
/// edges): [`chart_labels`] split into connected parts, numbered by lowest face.
///
/// ```
/// use strata_engine::{mesh::shapes, segment::isotropic_charts};
/// let mesh = shapes::sphere(1.0, 4)?;
/// let seg = isotropic_charts(&mesh, 50f64.to_radians());
/// // A sphere needs a handful of caps, not hundreds of segments.
/// assert!((4..=20).contains(&seg.segments.len()));
/// assert!(seg.face_segment.iter().all(|&s| (s as usize) < seg.segments.len()));
/// # Ok::<(), strata_engine::mesh::MeshError>(())
/// ```
pub fn isotropic_charts(mesh: &TriMesh, max_normal_angle: f64) -> Segmentation {
    segmentation_from_labels(mesh, &chart_labels(mesh, max_normal_angle))
}

/// Greedy cover: each unassigned face (in index order) seeds a chart that grows
/// breadth-first through unassigned faces whose normal has a dot product of at least
/// `min_dot` with the seed's.
fn greedy_cover(mesh: &TriMesh, min_dot: f64) -> Vec<u32> {
    let normals = mesh.face_normals();
    let neighbors = mesh.face_neighbors();
    let mut labels = vec![NONE; mesh.face_count()];
    let mut queue = VecDeque::new();
    let mut next = 0u32;
    for start in 0..mesh.face_count() {
        if labels[start] != NONE {
            continue;
        }
        let axis = normals[start];
        labels[start] = next;
        queue.push_back(start as u32);
        while let Some(f) = queue.pop_front() {
            for &g in &neighbors[f as usize] {
                if g != NONE
                    && labels[g as usize] == NONE
                    && normals[g as usize].dot(axis) >= min_dot
                {
                    labels[g as usize] = next;
                    queue.push_back(g);
                }
            }
        }
        next += 1;
    }
    labels
}

/// A chart's seed for the next flood: its proxy normal and its face nearest that.
#[derive(Clone, Copy, Debug)]
struct Seed {
    face: u32,
    proxy: DVec3,
}

/// The next round's seeds: per chart its area-weighted mean normal and the face whose
/// normal is nearest it (lowest index on ties), skipping charts under
/// 1/[`SMALL_CHART_SHARE`] of the mean chart area unless the chart is its connected
/// component's largest.
fn relaxed_seeds(mesh: &TriMesh, labels: &[u32]) -> Vec<Seed> {
    let normals = mesh.face_normals();
    let areas = mesh.face_areas();
    let components = mesh.face_components();
    let charts = labels.iter().map(|&l| l as usize + 1).max().unwrap_or(0);
    let mut sum = vec![DVec3::ZERO; charts];
    let mut area = vec![0.0f64; charts];
    let mut component = vec![0u32; charts];
    for (f, &l) in labels.iter().enumerate() {
        sum[l as usize] += areas[f] * normals[f];
        area[l as usize] += areas[f];
        component[l as usize] = components[f];
    }
    let proxy: Vec<DVec3> = sum
        .iter()
        .zip(&labels_first_normal(labels, normals, charts))
        .map(|(s, first)| s.try_normalize().unwrap_or(*first))
        .collect();
    // The largest chart of each component keeps its seed whatever its size, so every
    // component is flooded.
    let mut largest = vec![usize::MAX; mesh.component_count()];
    for c in 0..charts {
        let k = component[c] as usize;
        if largest[k] == usize::MAX || area[c] > area[largest[k]] {
            largest[k] = c;
        }
    }
    let mean = area.iter().sum::<f64>() / charts.max(1) as f64;
    let mut best = vec![(f64::INFINITY, NONE); charts];
    for (f, &l) in labels.iter().enumerate() {
        let d = (normals[f] - proxy[l as usize]).length_squared();
        if d < best[l as usize].0 {
            best[l as usize] = (d, f as u32);
        }
    }
    (0..charts)
        .filter(|&c| area[c] * SMALL_CHART_SHARE >= mean || largest[component[c] as usize] == c)
        .filter(|&c| best[c].1 != NONE)
        .map(|c| Seed {
            face: best[c].1,
            proxy: proxy[c],
        })
        .collect()
}

/// Per chart, the normal of its lowest face (the proxy of a chart whose normals
/// cancel out).
fn labels_first_normal(labels: &[u32], normals: &[DVec3], charts: usize) -> Vec<DVec3> {
    let mut first = vec![None; charts];
    for (f, &l) in labels.iter().enumerate() {
        first[l as usize].get_or_insert(normals[f]);
    }
    first.into_iter().map(|n| n.unwrap_or(DVec3::Z)).collect()
}

/// Buckets of the flood's priority queue over `|n - proxy|^2` in [0, 4]: 1/1024 of
/// squared normal distance each, which is 1.8 degrees from the proxy at first and
/// 0.03 degrees at 60 degrees from it.
const FLOOD_BUCKETS: usize = 4096;

/// Priority flood from every seed at once: a face goes to the chart that reaches it
/// with the smallest `|n - proxy|^2`, faces taken in increasing order of that error
/// (bucketed into [`FLOOD_BUCKETS`], first in first out within a bucket, and never
/// below the bucket being emptied, as in a watershed). Deterministic: the order depends
/// only on the input. Charts are renumbered by lowest face.
///
/// A bucket queue instead of a binary heap: O(F + buckets) instead of O(F log F); on
/// the 1.1M-face bunny the whole chart step went from 0.99 s to 0.47 s.
fn flood(mesh: &TriMesh, normals: &[DVec3], seeds: &[Seed]) -> Vec<u32> {
    let neighbors = mesh.face_neighbors();
    let mut labels = vec![NONE; mesh.face_count()];
    let bucket = |f: u32, c: u32| {
        let d = (normals[f as usize] - seeds[c as usize].proxy).length_squared();
        // NaN (a degenerate normal) goes last.
        if d.is_nan() {
            FLOOD_BUCKETS - 1
        } else {
            ((d * (FLOOD_BUCKETS as f64 / 4.0)) as usize).min(FLOOD_BUCKETS - 1)
        }
    };
    // The lowest bucket a face was queued in: a later entry in the same or a higher
    // bucket would pop after it, so it is not queued.
    let mut queued = vec![usize::MAX; mesh.face_count()];
    let mut buckets: Vec<Vec<(u32, u32)>> = vec![Vec::new(); FLOOD_BUCKETS];
    for (c, s) in seeds.iter().enumerate() {
        let b = bucket(s.face, c as u32);
        if b < queued[s.face as usize] {
            queued[s.face as usize] = b;
            buckets[b].push((s.face, c as u32));
        }
    }
    for current in 0..FLOOD_BUCKETS {
        // Entries pushed into the current bucket while it is emptied are appended and
        // taken in turn (first in, first out).
        let mut i = 0;
        while i < buckets[current].len() {
            let (f, c) = buckets[current][i];
            i += 1;
            if labels[f as usize] != NONE {
                continue;
            }
            labels[f as usize] = c;
            for &g in &neighbors[f as usize] {
                if g == NONE || labels[g as usize] != NONE {
                    continue;
                }
                let b = bucket(g, c).max(current);
                if b < queued[g as usize] {
                    queued[g as usize] = b;
                    buckets[b].push((g, c));
                }
            }
        }
        buckets[current] = Vec::new();
    }
    // Every component keeps a seed (relaxed_seeds), so every face is reached; should
    // one not be, it gets a chart of its own reach rather than none.
    let mut next = seeds.len() as u32;
    for start in 0..labels.len() {
        if labels[start] != NONE {
            continue;
        }
        labels[start] = next;
        let mut queue = VecDeque::from([start as u32]);
        while let Some(f) = queue.pop_front() {
            for &g in &neighbors[f as usize] {
                if g != NONE && labels[g as usize] == NONE {
                    labels[g as usize] = next;
                    queue.push_back(g);
                }
            }
        }
        next += 1;
    }
    renumber_by_lowest_face(&mut labels);
    labels
}

/// Renumbers labels from 0 in order of each label's lowest face.
fn renumber_by_lowest_face(labels: &mut [u32]) {
    let count = labels
        .iter()
        .filter(|&&l| l != NONE)
        .map(|&l| l as usize + 1)
        .max()
        .unwrap_or(0);
    let mut map = vec![NONE; count];
    let mut next = 0u32;
    for l in labels.iter_mut() {
        if *l == NONE {
            continue;
        }
        let m = &mut map[*l as usize];
        if *m == NONE {
            *m = next;
            next += 1;
        }
        *l = *m;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{connected_parts, loop_subdivide, shapes};

    const ANGLE: f64 = CHART_NORMAL_ANGLE;

    /// Every face has a chart, charts are numbered 0..K by lowest face, and each
    /// chart is one connected part.
    fn check_labels(mesh: &TriMesh, labels: &[u32]) -> usize {
        assert_eq!(labels.len(), mesh.face_count());
        let charts = labels.iter().max().map_or(0, |&m| m as usize + 1);
        let mut seen = 0u32;
        for &l in labels {
            assert!(l <= seen, "labels numbered by lowest face");
            seen = seen.max(l + 1);
        }
        let parts = connected_parts(mesh, labels, &vec![false; mesh.edge_count()]);
        let part_count = parts.iter().max().map_or(0, |&m| m as usize + 1);
        assert_eq!(part_count, charts, "every chart is connected");
        charts
    }

    #[test]
    fn greedy_charts_stay_in_their_cone() {
        let mesh = shapes::sphere(1.0, 12).expect("sphere");
        let min_dot = ANGLE.cos();
        let labels = greedy_cover(&mesh, min_dot);
        check_labels(&mesh, &labels);
        // A chart's seed is its lowest face (faces are visited in index order).
        let normals = mesh.face_normals();
        let mut seed = vec![NONE; mesh.face_count()];
        for (f, &l) in labels.iter().enumerate() {
            if seed[l as usize] == NONE {
                seed[l as usize] = f as u32;
            }
            let axis = normals[seed[l as usize] as usize];
            assert!(normals[f].dot(axis) >= min_dot - 1e-12, "face {f}");
        }
    }

    #[test]
    fn a_flat_mesh_is_one_chart() {
        let mesh = shapes::plane(1.0, 16).expect("plane");
        let labels = chart_labels(&mesh, ANGLE);
        assert_eq!(check_labels(&mesh, &labels), 1);
    }

    #[test]
    fn sphere_charts_are_few_compact_and_independent_of_resolution() {
        // A cap of half-angle 60 degrees holds a quarter of the sphere: a handful of
        // charts, as many at 4x the faces, each near its proxy normal.
        let counts: Vec<usize> = [8, 16]
            .into_iter()
            .map(|res| {
                let mesh = shapes::sphere(1.0, res).expect("sphere");
                let labels = chart_labels(&mesh, ANGLE);
                let charts = check_labels(&mesh, &labels);
                // Lloyd's proxies: the mean normal; after relaxation no face is further
                // than 90 degrees from its chart's.
                let normals = mesh.face_normals();
                let areas = mesh.face_areas();
                let mut sum = vec![DVec3::ZERO; charts];
                for (f, &l) in labels.iter().enumerate() {
                    sum[l as usize] += areas[f] * normals[f];
                }
                for (f, &l) in labels.iter().enumerate() {
                    let proxy = sum[l as usize].normalize();
                    assert!(normals[f].dot(proxy) > 0.0, "res {res}: face {f}");
                }
                charts
            })
            .collect();
        assert!(counts.iter().all(|&c| (4..=16).contains(&c)), "{counts:?}");
        let ratio = counts[1] as f64 / counts[0] as f64;
        assert!((1.0 / 1.3..=1.3).contains(&ratio), "{counts:?}");
    }

    #[test]
    fn subdivision_keeps_the_chart_count() {
        // Loop subdivision smooths and refines the torus: the charts follow its shape,
        // not its faces.
        let mesh = shapes::torus(1.0, 0.4, 24).expect("torus");
        let fine = loop_subdivide(&mesh).expect("subdivide");
        let coarse_count = check_labels(&mesh, &chart_labels(&mesh, ANGLE));
        let fine_count = check_labels(&fine, &chart_labels(&fine, ANGLE));
        let ratio = fine_count as f64 / coarse_count as f64;
        assert!(
            (1.0 / 1.3..=1.3).contains(&ratio),
            "{coarse_count} -> {fine_count}"
        );
        // A torus needs more than one chart (it is not a disc) but few.
        assert!((2..=40).contains(&coarse_count), "{coarse_count}");
    }

    #[test]
    fn every_component_gets_charts_and_reruns_are_identical() {
        // Two spheres of very different sizes in one mesh: the small one is its own
        // component and keeps a chart even though it is far under the mean area.
        let big = shapes::sphere(1.0, 10).expect("sphere");
        let small = shapes::sphere(0.01, 4).expect("sphere");
        let offset = big.vertex_count() as u32;
        let mut positions = big.positions().to_vec();
        positions.extend(
            small
                .positions()
                .iter()
                .map(|p| *p + DVec3::new(5.0, 0.0, 0.0)),
        );
        let mut triangles = big.triangles().to_vec();
        triangles.extend(small.triangles().iter().map(|t| t.map(|v| v + offset)));
        let mesh = TriMesh::new(positions, triangles).expect("mesh");
        let labels = chart_labels(&mesh, ANGLE);
        check_labels(&mesh, &labels);
        let components = mesh.face_components();
        let first_small = big.face_count();
        assert_ne!(components[0], components[first_small], "two components");
        assert!(
            labels[..first_small]
                .iter()
                .all(|l| !labels[first_small..].contains(l)),
            "no chart spans both components"
        );
        assert_eq!(chart_labels(&mesh, ANGLE), labels);
        // The small sphere is under 1/SMALL_CHART_SHARE of the mean chart area, yet its
        // largest chart keeps a seed in the relaxation itself (not through the flood's
        // last-resort fill).
        let seeds = relaxed_seeds(&mesh, &labels);
        let in_small = |s: &Seed| s.face as usize >= first_small;
        assert_eq!(seeds.iter().filter(|s| in_small(s)).count(), 1);
        let small_area: f64 = mesh.face_areas()[first_small..].iter().sum();
        let mean = mesh.area() / (labels.iter().max().map_or(0, |&m| m + 1) as f64);
        assert!(
            small_area * SMALL_CHART_SHARE < mean,
            "{small_area} vs {mean}"
        );
    }

    #[test]
    fn bad_angles_fall_back_to_the_default() {
        let mesh = shapes::sphere(1.0, 8).expect("sphere");
        let want = chart_labels(&mesh, CHART_NORMAL_ANGLE);
        assert_eq!(chart_labels(&mesh, f64::NAN), want);
        assert_eq!(chart_labels(&mesh, -1.0), want);
        // A smaller cone makes more charts.
        let narrow = chart_labels(&mesh, 0.3);
        let count = |l: &[u32]| l.iter().max().map_or(0, |&m| m + 1);
        assert!(
            count(&narrow) > count(&want),
            "{} vs {}",
            count(&narrow),
            count(&want)
        );
    }
}
