//! Reference samplers of a mesh under a tensor field, returning the same [`Sample`]
//! records as strata's sampler, so that every analysis applies to them.
//!
//! | sampler | method | cost |
//! | --- | --- | --- |
//! | [`mesh_uniform_random`] | independent points, probability proportional to area x density | O(F + n log F) |
//! | [`mesh_poisson_disk`] | weighted sample elimination (Yuksel, "Sample elimination for generating Poisson disk sample sets", EG 2015) from 5n random candidates, distances in local spacings | O(n log n) |
//!
//! Each sample carries the field's frame and expected spacings at its position
//! (`spacing_k = sqrt(M / n) / sqrt(l_k)` with `M` the total density measure, as in
//! strata's sampler), and a pure function of `(n, seed)`.

use std::collections::BinaryHeap;

use glam::{DVec3, Vec3};

use crate::field::TensorField;
use crate::mesh::TriMesh;
use crate::rng::Rng;
use crate::sample::Sample;

const STREAM_MESH_UNIFORM: u64 = 0xa11a_0200;

/// Per face, `area * mean corner density`, and their running sum.
fn face_measures(mesh: &TriMesh, field: &TensorField) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let density = field.vertex_densities(mesh);
    let measures: Vec<f64> = mesh
        .triangles()
        .iter()
        .zip(mesh.face_areas())
        .map(|(t, a)| a * t.iter().map(|&v| density[v as usize]).sum::<f64>() / 3.0)
        .collect();
    let mut cum = Vec::with_capacity(measures.len());
    let mut acc = 0.0;
    for m in &measures {
        acc += m;
        cum.push(acc);
    }
    (measures, cum, density)
}

/// A sample record at barycentric point `bary` of face `f`, for a set of `n` samples
/// of total measure `total`.
fn record(
    mesh: &TriMesh,
    field: &TensorField,
    f: u32,
    bary: [f64; 3],
    index: u32,
    scale: f64,
) -> Sample {
    let [a, b, c] = mesh.face_positions(f);
    let p = a * bary[0] + b * bary[1] + c * bary[2];
    let e = field.face_eigen(mesh, f, bary);
    let to = |v: DVec3| -> [f32; 3] { v.as_vec3().to_array() };
    Sample {
        position: to(p),
        face: f,
        normal: to(mesh.face_normals()[f as usize]),
        segment: 0,
        major_axis: to(e.major),
        index,
        bary: [bary[1] as f32, bary[2] as f32],
        spacing: [
            (scale / e.l1.max(f64::MIN_POSITIVE).sqrt()) as f32,
            (scale / e.l2.max(f64::MIN_POSITIVE).sqrt()) as f32,
        ],
    }
}

/// `n` independent random samples with probability density proportional to the
/// field's density (face by area x mean corner density, then a uniform point of the
/// face accepted with probability `density(point) / max corner density`).
///
/// # Example
/// ```
/// use strata_engine::{analysis::mesh_baseline, field::FieldSpec, mesh::shapes};
/// let mesh = shapes::sphere(1.0, 16)?;
/// let field = FieldSpec::Constant { direction: [1.0, 0.0, 0.0], anisotropy: 1.0, density: 1.0 }
///     .build(&mesh)?;
/// let s = mesh_baseline::mesh_uniform_random(&mesh, &field, 200, 1);
/// assert_eq!(s.len(), 200);
/// assert!(s.iter().all(|s| (glam::Vec3::from(s.position).length() - 1.0).abs() < 0.05));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn mesh_uniform_random(
    mesh: &TriMesh,
    field: &TensorField,
    n: usize,
    seed: u64,
) -> Vec<Sample> {
    let (_, cum, density) = face_measures(mesh, field);
    let total = cum.last().copied().unwrap_or(0.0);
    let scale = (total / n.max(1) as f64).sqrt();
    let mut rng = Rng::new(seed, STREAM_MESH_UNIFORM);
    let mut out = Vec::with_capacity(n);
    while out.len() < n && total > 0.0 {
        let target = rng.next_f64() * total;
        let f = cum.partition_point(|&c| c <= target).min(cum.len() - 1) as u32;
        let (r1, r2) = (rng.next_f64().sqrt(), rng.next_f64());
        let bary = [1.0 - r1, r1 * (1.0 - r2), r1 * r2];
        let t = mesh.triangles()[f as usize];
        let d: Vec<f64> = t.iter().map(|&v| density[v as usize]).collect();
        let here = d[0] * bary[0] + d[1] * bary[1] + d[2] * bary[2];
        let max = d.iter().copied().fold(0.0, f64::max);
        if rng.next_f64() * max > here {
            continue;
        }
        out.push(record(mesh, field, f, bary, out.len() as u32, scale));
    }
    out
}

/// `n` Poisson-disk samples by weighted sample elimination from `5 n` random
/// candidates ([`mesh_uniform_random`]): repeatedly remove the candidate with the
/// largest weight `sum_j (1 - d_ij / (2 r))^8` over neighbours closer than `2 r`,
/// where `d_ij` is the Euclidean distance in units of the mean expected spacing of the
/// two samples and `r = 0.537` (Yuksel's `r_max = sqrt(A / (2 sqrt(3) N))` in
/// spacings). Distances are Euclidean in space (not geodesic): fine while the spacing
/// is small against the surface's curvature radius.
///
/// # Example
/// ```
/// use strata_engine::{analysis::mesh_baseline, field::FieldSpec, mesh::shapes};
/// let mesh = shapes::plane(1.0, 8)?;
/// let field = FieldSpec::Constant { direction: [1.0, 0.0, 0.0], anisotropy: 1.0, density: 1.0 }
///     .build(&mesh)?;
/// let s = mesh_baseline::mesh_poisson_disk(&mesh, &field, 300, 1);
/// assert_eq!(s.len(), 300);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn mesh_poisson_disk(mesh: &TriMesh, field: &TensorField, n: usize, seed: u64) -> Vec<Sample> {
    let candidates = mesh_uniform_random(mesh, field, 5 * n, seed);
    if candidates.len() <= n {
        return candidates;
    }
    // Spacings for the final count n (the candidates' are for 5n).
    let grow = (5.0f64).sqrt() as f32;
    let cand: Vec<Sample> = candidates
        .into_iter()
        .map(|mut s| {
            s.spacing = s.spacing.map(|x| x * grow);
            s
        })
        .collect();
    let (neighbours, weight) = elimination_weights(&cand);
    let alive = eliminate(&neighbours, weight, n);
    cand.into_iter()
        .zip(alive)
        .filter(|(_, a)| *a)
        .enumerate()
        .map(|(k, (mut s, _))| {
            s.index = k as u32;
            s
        })
        .collect()
}

/// Yuksel's `r_max` in units of the mean expected spacing of two samples.
const R_MAX: f64 = 0.537;

/// Per candidate, its neighbours closer than `2 r` (in units of the two samples' mean
/// expected spacing) with their pair weights `(1 - d_ij / (2 r))^8`, and its weight (the
/// sum), found through a grid of cells `2 r` median spacings wide. Candidates are
/// non-empty.
fn elimination_weights(cand: &[Sample]) -> (Vec<Vec<(u32, f64)>>, Vec<f64>) {
    let pos: Vec<DVec3> = cand
        .iter()
        .map(|s| Vec3::from(s.position).as_dvec3())
        .collect();
    let iso: Vec<f64> = cand
        .iter()
        .map(|s| (s.spacing[0] as f64 * s.spacing[1] as f64).sqrt())
        .collect();
    let mut sorted = iso.clone();
    sorted.sort_by(f64::total_cmp);
    let cell = 2.0 * R_MAX * sorted[sorted.len() / 2];
    let key = |p: DVec3| -> (i64, i64, i64) {
        let q = (p / cell).floor();
        (q.x as i64, q.y as i64, q.z as i64)
    };
    let mut grid: std::collections::HashMap<(i64, i64, i64), Vec<u32>> = Default::default();
    for (i, p) in pos.iter().enumerate() {
        grid.entry(key(*p)).or_default().push(i as u32);
    }
    let max_iso = sorted[sorted.len() - 1];
    let mut neighbours: Vec<Vec<(u32, f64)>> = vec![Vec::new(); cand.len()];
    let mut weight = vec![0.0; cand.len()];
    for i in 0..cand.len() {
        let (cx, cy, cz) = key(pos[i]);
        let r = ((2.0 * R_MAX * 0.5 * (iso[i] + max_iso)) / cell).ceil() as i64;
        for gz in cz - r..=cz + r {
            for gy in cy - r..=cy + r {
                for gx in cx - r..=cx + r {
                    let Some(list) = grid.get(&(gx, gy, gz)) else {
                        continue;
                    };
                    for &j in list {
                        if j as usize == i {
                            continue;
                        }
                        let d =
                            pos[i].distance(pos[j as usize]) / (0.5 * (iso[i] + iso[j as usize]));
                        if d < 2.0 * R_MAX {
                            let w = (1.0 - d / (2.0 * R_MAX)).powi(8);
                            neighbours[i].push((j, w));
                            weight[i] += w;
                        }
                    }
                }
            }
        }
    }
    (neighbours, weight)
}

/// A candidate in the elimination's max-heap: its weight then its index (ties: the
/// higher index first).
#[derive(PartialEq)]
struct Entry(f64, u32);

impl Eq for Entry {}

impl PartialOrd for Entry {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}

impl Ord for Entry {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&o.0).then(self.1.cmp(&o.1))
    }
}

/// Which candidates survive the elimination down to `n`: the one of largest `weight`
/// is removed and its neighbours' weights lose their pair weights with it, until `n`
/// are left (a max-heap with lazy deletion).
fn eliminate(neighbours: &[Vec<(u32, f64)>], mut weight: Vec<f64>, n: usize) -> Vec<bool> {
    let mut heap: BinaryHeap<Entry> = (0..weight.len())
        .map(|i| Entry(weight[i], i as u32))
        .collect();
    let mut alive = vec![true; weight.len()];
    let mut remaining = weight.len();
    while remaining > n {
        let Some(Entry(w, i)) = heap.pop() else { break };
        let i = i as usize;
        if !alive[i] || w != weight[i] {
            continue;
        }
        alive[i] = false;
        remaining -= 1;
        for &(j, _) in &neighbours[i] {
            let j = j as usize;
            if alive[j] {
                // The pair weight is symmetric up to the spacing mean: use j's own entry.
                if let Some(&(_, wj)) = neighbours[j].iter().find(|(k, _)| *k as usize == i) {
                    weight[j] -= wj;
                    heap.push(Entry(weight[j], j as u32));
                }
            }
        }
    }
    alive
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixtures::isotropic_on;
    use crate::mesh::shapes;

    fn closest_pair(s: &[Sample]) -> f64 {
        let p: Vec<Vec3> = s.iter().map(|s| Vec3::from(s.position)).collect();
        let mut best = f32::INFINITY;
        for i in 0..p.len() {
            for j in i + 1..p.len() {
                best = best.min(p[i].distance(p[j]));
            }
        }
        best as f64
    }

    #[test]
    fn random_follows_density_and_poisson_is_spaced() {
        let mesh = shapes::plane(1.0, 8).expect("plane");
        let field = isotropic_on(&mesh);
        let n = 800;
        let r = mesh_uniform_random(&mesh, &field, n, 3);
        let p = mesh_poisson_disk(&mesh, &field, n, 3);
        assert_eq!((r.len(), p.len()), (n, n));
        let spacing = (1.0 / n as f64).sqrt();
        // Random sets have pairs ~1/100 spacing apart; Poisson disk keeps well apart.
        assert!(closest_pair(&r) < 0.1 * spacing);
        assert!(
            closest_pair(&p) > 0.45 * spacing,
            "{}",
            closest_pair(&p) / spacing
        );
        // Expected spacing recorded: sqrt(area / n) for a unit isotropic field.
        assert!((p[0].spacing[0] as f64 - spacing).abs() < 1e-3 * spacing);
        assert_eq!(r, mesh_uniform_random(&mesh, &field, n, 3));
    }
}
