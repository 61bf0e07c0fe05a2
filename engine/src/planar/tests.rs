use std::sync::Arc;

use glam::{DVec2, DVec3};

use super::*;
use crate::curve::{barycentric, clip_triangle};
use crate::field::{FieldSpec, PlanarDensity};
use crate::fixtures::{along_x, constant, isotropic, isotropic_on};
use crate::mesh::shapes;
use crate::rng::Rng;
use crate::sample::Sample;

fn build(spec: FieldSpec, resolution: u32) -> (Sampler, PlanarMap) {
    let mesh = Arc::new(shapes::plane(1.0, resolution).expect("plane"));
    let field = Arc::new(spec.build(&mesh).expect("field"));
    sampler(mesh, field, &CurveOptions::default()).expect("planar sampler")
}

fn iso() -> FieldSpec {
    isotropic()
}

fn xy(s: &Sample) -> DVec2 {
    DVec2::new(s.position[0] as f64, s.position[1] as f64)
}

#[test]
fn every_dyadic_cell_holds_its_share() {
    let (sampler, _) = build(iso(), 32);
    for n in [1000usize, 10_000, 33_333] {
        let samples = sampler.sample(n, 5);
        assert_eq!(samples.len(), n);
        for level in 1..=6u32 {
            let side = 1usize << level;
            let mut counts = vec![0i64; side * side];
            for s in &samples {
                let p = xy(s) * side as f64;
                let (i, j) = ((p.x as usize).min(side - 1), (p.y as usize).min(side - 1));
                counts[j * side + i] += 1;
            }
            let expect = n as f64 / (side * side) as f64;
            let worst = counts
                .iter()
                .map(|&c| (c as f64 - expect).abs())
                .fold(0.0, f64::max);
            assert!(worst <= 2.0, "n {n} level {level}: worst deviation {worst}");
        }
    }
}

#[test]
fn samples_are_valid_and_consistent() {
    let (sampler, _) = build(iso(), 8);
    let samples = sampler.sample(5000, 1);
    let mesh = sampler.mesh();
    for (i, s) in samples.iter().enumerate() {
        assert_eq!(s.index as usize, i);
        let b = s.barycentric();
        assert!(
            b.iter().all(|&x| (-1e-6..=1.0 + 1e-6).contains(&x)),
            "{b:?}"
        );
        let p = mesh.face_positions(s.face);
        let back = p[0] * b[0] as f64 + p[1] * b[1] as f64 + p[2] * b[2] as f64;
        assert!((back - DVec3::from(s.position.map(|x| x as f64))).length() < 1e-5);
        assert!((s.normal[2] - 1.0).abs() < 1e-6);
        // Isotropic unit density: both spacings sqrt(area / N).
        let want = (1.0f64 / 5000.0).sqrt() as f32;
        assert!((s.spacing[0] - want).abs() < 1e-5 && (s.spacing[1] - want).abs() < 1e-5);
    }
}

#[test]
fn same_seed_same_samples_whatever_the_thread_count() {
    let (sampler, _) = build(iso(), 16);
    let pool = |n| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .expect("pool")
    };
    let one = pool(1).install(|| sampler.sample(50_000, 77));
    let two = pool(2).install(|| sampler.sample(50_000, 77));
    let three = pool(3).install(|| sampler.sample(50_000, 77));
    assert!(one == two && two == three);
    let other = sampler.sample(50_000, 78);
    assert!(
        one.iter()
            .zip(&other)
            .filter(|(a, b)| a.position != b.position)
            .count()
            > 49_000
    );
}

/// Mean spacing along x and along y: for every interior sample, its 4 nearest
/// neighbours in the metric `diag(sqrt_l)` (in which samples that follow the field are
/// isotropic), and the mean world-space offset of those neighbours along each axis.
/// This is the issue's "mean nearest-neighbour spacing along the minor and major
/// directions"; because the metric picks the neighbours it is only weakly sensitive
/// to the samples themselves, so the tests pair it with box counts that are.
fn directional_spacing(points: &[DVec2], sqrt_l: (f64, f64)) -> (f64, f64) {
    const K: usize = 4;
    let (mut sum, mut count) = ([0.0; 2], 0usize);
    for (i, p) in points.iter().enumerate() {
        if p.min_element() < 0.15 || p.max_element() > 0.85 {
            continue;
        }
        let mut near: Vec<(f64, DVec2)> = points
            .iter()
            .enumerate()
            .filter(|(j, _)| *j != i)
            .map(|(_, q)| {
                let d = *q - *p;
                (DVec2::new(d.x * sqrt_l.0, d.y * sqrt_l.1).length(), d)
            })
            .collect();
        near.select_nth_unstable_by(K, |a, b| a.0.total_cmp(&b.0));
        for (_, d) in &near[..K] {
            sum[0] += d.x.abs();
            sum[1] += d.y.abs();
        }
        count += K;
    }
    (sum[0] / count as f64, sum[1] / count as f64)
}

/// Largest deviation from `N * area` of the counts in a tiling of the unit square by
/// `nx x ny` boxes.
fn worst_box_deviation(points: &[DVec2], nx: usize, ny: usize) -> f64 {
    let mut counts = vec![0f64; nx * ny];
    for p in points {
        let (i, j) = (
            ((p.x * nx as f64) as usize).min(nx - 1),
            ((p.y * ny as f64) as usize).min(ny - 1),
        );
        counts[j * nx + i] += 1.0;
    }
    let expect = points.len() as f64 / (nx * ny) as f64;
    counts
        .iter()
        .map(|c| (c - expect).abs())
        .fold(0.0, f64::max)
}

#[test]
fn four_to_one_field_gives_four_to_one_spacing() {
    let spec = along_x(4.0);
    let (sampler, map) = build(spec, 16);
    assert!((map.reference.anisotropy() - 4.0).abs() < 1e-12);
    let pts: Vec<DVec2> = sampler.sample(3000, 3).iter().map(xy).collect();
    let (major, minor) = directional_spacing(&pts, (2.0, 0.5));
    let ratio = minor / major;
    assert!(
        (ratio - 4.0).abs() <= 0.4,
        "minor/major spacing ratio {ratio}"
    );
    // Stratification follows the field: boxes that are images of dyadic parameter
    // cells (4 times longer along the minor axis y) hold N * area within 2, while
    // boxes of the same area turned by 90 degrees do not.
    let n = 10_000;
    let pts: Vec<DVec2> = sampler.sample(n, 4).iter().map(xy).collect();
    for level in 1..=5 {
        let (nx, ny) = (1usize << (level + 1), 1usize << (level - 1));
        let aligned = worst_box_deviation(&pts, nx, ny);
        assert!(
            aligned <= 2.0,
            "level {level}: aligned boxes deviate by {aligned}"
        );
        let across = worst_box_deviation(&pts, ny, nx);
        if level >= 3 {
            assert!(
                across > 2.0 * aligned.max(1.0),
                "level {level}: {across} vs {aligned}"
            );
        }
    }
}

#[test]
fn rotated_anisotropy_follows_the_direction() {
    let dir = DVec2::new(1.0, 1.0).normalize();
    let spec = constant([dir.x, dir.y, 0.0], 3.0);
    let (sampler, _) = build(spec, 16);
    let samples = sampler.sample(3000, 9);
    // Rotate so that the field's major direction is +x (about the square's centre).
    let pts: Vec<DVec2> = samples
        .iter()
        .map(|s| {
            let p = xy(s) - DVec2::splat(0.5);
            DVec2::new(p.dot(dir), dir.perp_dot(p)) + DVec2::splat(0.5)
        })
        .collect();
    let (major, minor) = directional_spacing(&pts, (3f64.sqrt(), 1.0 / 3f64.sqrt()));
    assert!(
        (minor / major - 3.0).abs() <= 0.3,
        "ratio {}",
        minor / major
    );
    for s in &samples {
        let a = DVec2::new(s.major_axis[0] as f64, s.major_axis[1] as f64);
        assert!(a.dot(dir).abs() > 1.0 - 1e-6);
    }
}

/// Exact integral of the mesh-interpolated density over each cell of a `g x g` grid.
fn region_measures(sampler: &Sampler, g: usize) -> Vec<f64> {
    let mesh = sampler.mesh();
    let dens = sampler.field().vertex_densities(mesh);
    let mut out = vec![0.0; g * g];
    for t in mesh.triangles() {
        let p = t.map(|v| mesh.positions()[v as usize].truncate());
        for j in 0..g {
            for i in 0..g {
                let lo = DVec2::new(i as f64, j as f64) / g as f64;
                let (a, c) = clip_triangle(&p, lo, 1.0 / g as f64).area_centroid();
                if a > 0.0 {
                    let b = barycentric(&p, c);
                    let d: f64 = (0..3).map(|k| b[k] * dens[t[k] as usize]).sum();
                    out[j * g + i] += a * d;
                }
            }
        }
    }
    out
}

#[test]
fn gaussian_density_is_followed_far_better_than_random() {
    let spec = FieldSpec::Planar {
        density: PlanarDensity::Gaussian {
            center: [0.5, 0.5],
            sigma: 0.15,
            peak: 8.0,
            base: 0.5,
        },
        direction: [1.0, 0.0, 0.0],
        anisotropy: 1.0,
    };
    let (sampler, _) = build(spec, 64);
    let g = 8;
    let measures = region_measures(&sampler, g);
    let total: f64 = measures.iter().sum();
    assert!((total - sampler.total_measure()).abs() < 1e-9 * total);
    let n = 20_000;
    let count = |pts: &mut dyn Iterator<Item = DVec2>| {
        let mut c = vec![0f64; g * g];
        for p in pts {
            let (i, j) = (
                ((p.x * g as f64) as usize).min(g - 1),
                ((p.y * g as f64) as usize).min(g - 1),
            );
            c[j * g + i] += 1.0;
        }
        c
    };
    let rms = |c: &[f64]| {
        let s: f64 = c
            .iter()
            .zip(&measures)
            .map(|(c, m)| (c - n as f64 * m / total).powi(2))
            .sum();
        (s / c.len() as f64).sqrt()
    };
    let ours = rms(&count(&mut sampler.sample(n, 11).iter().map(xy)));
    // Random sampling of the same (mesh-interpolated) density: faces by measure, then
    // rejection inside the face against its linear density.
    let mesh = sampler.mesh();
    let dens = sampler.field().vertex_densities(mesh);
    let face_measure: Vec<f64> = mesh
        .triangles()
        .iter()
        .zip(mesh.face_areas())
        .map(|(t, a)| a * t.iter().map(|&v| dens[v as usize]).sum::<f64>() / 3.0)
        .collect();
    let mut cum = vec![0.0];
    for m in &face_measure {
        cum.push(cum.last().copied().unwrap_or(0.0) + m);
    }
    let mut rng = Rng::new(11, 99);
    let mut random = Vec::with_capacity(n);
    while random.len() < n {
        let u = rng.next_f64() * total;
        let f = cum.partition_point(|&c| c <= u) - 1;
        let t = mesh.triangles()[f];
        let (mut u, mut v) = (rng.next_f64(), rng.next_f64());
        if u + v > 1.0 {
            (u, v) = (1.0 - u, 1.0 - v);
        }
        let d = [
            dens[t[0] as usize],
            dens[t[1] as usize],
            dens[t[2] as usize],
        ];
        let here = (1.0 - u - v) * d[0] + u * d[1] + v * d[2];
        if rng.next_f64() * d.iter().cloned().fold(0.0, f64::max) > here {
            continue;
        }
        let p = mesh.face_positions(f as u32);
        random.push((p[0] * (1.0 - u - v) + p[1] * u + p[2] * v).truncate());
    }
    let theirs = rms(&count(&mut random.into_iter()));
    println!("8x8 region counts, RMS deviation: strata {ours:.3}, random {theirs:.3}");
    assert!(ours < 1.5, "strata rms deviation {ours}");
    assert!(theirs > 5.0 * ours, "random {theirs} vs strata {ours}");
}

#[test]
fn non_planar_mesh_is_rejected_clearly() {
    let mut p = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(1.0, 1.0, 0.5)];
    let mesh = crate::mesh::TriMesh::new(p.clone(), vec![[0, 1, 3], [0, 3, 2]]).expect("mesh");
    let field = isotropic_on(&mesh);
    let err = planar_map(&mesh, &field).expect_err("not planar");
    assert!(err.to_string().contains("not planar"), "{err}");
    p[3].z = 0.0;
    let mesh = crate::mesh::TriMesh::new(p, vec![[0, 1, 3], [0, 3, 2]]).expect("mesh");
    let field = isotropic_on(&mesh);
    assert!(planar_map(&mesh, &field).is_ok());
}
