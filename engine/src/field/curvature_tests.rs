//! Known-answer tests of the curvature estimator and the curvature source, on small
//! meshes generated here (a UV sphere without seam duplicates, an open cylinder, a
//! torus, height-field grids).

use std::f64::consts::{PI, TAU};

use glam::{DMat3, DQuat, DVec3};

use super::*;
use crate::field::FieldSpec;
use crate::mesh::shapes;

/// UV sphere of radius `r`: `rings - 1` latitude rings of `segments` vertices plus two
/// poles, no duplicated seam, outward-facing triangles.
fn uv_sphere(r: f64, segments: u32, rings: u32) -> TriMesh {
    let mut positions = vec![DVec3::new(0.0, 0.0, r)];
    for j in 1..rings {
        let theta = PI * f64::from(j) / f64::from(rings);
        for i in 0..segments {
            let phi = TAU * f64::from(i) / f64::from(segments);
            positions.push(
                r * DVec3::new(
                    theta.sin() * phi.cos(),
                    theta.sin() * phi.sin(),
                    theta.cos(),
                ),
            );
        }
    }
    positions.push(DVec3::new(0.0, 0.0, -r));
    let south = positions.len() as u32 - 1;
    let at = |j: u32, i: u32| 1 + (j - 1) * segments + i % segments;
    let mut triangles = Vec::new();
    for i in 0..segments {
        triangles.push([0, at(1, i), at(1, i + 1)]);
        triangles.push([south, at(rings - 1, i + 1), at(rings - 1, i)]);
    }
    for j in 1..rings - 1 {
        for i in 0..segments {
            let (a, b, c, d) = (at(j, i), at(j + 1, i), at(j + 1, i + 1), at(j, i + 1));
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }
    TriMesh::new(positions, triangles).expect("valid sphere")
}

/// Open cylinder of radius `r` around the z axis, `z in [0, height]`, `segments`
/// around and `rows` quads along, outward-facing. Vertex `(i, j)` is `j * segments + i`.
fn cylinder(r: f64, height: f64, segments: u32, rows: u32) -> TriMesh {
    let mut positions = Vec::new();
    for j in 0..=rows {
        for i in 0..segments {
            let phi = TAU * f64::from(i) / f64::from(segments);
            positions.push(DVec3::new(
                r * phi.cos(),
                r * phi.sin(),
                height * f64::from(j) / f64::from(rows),
            ));
        }
    }
    let at = |i: u32, j: u32| j * segments + i % segments;
    let mut triangles = Vec::new();
    for j in 0..rows {
        for i in 0..segments {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }
    TriMesh::new(positions, triangles).expect("valid cylinder")
}

/// Torus with tube radius `r` around a circle of radius `big_r` in the xy plane;
/// vertex `(i, j)` at angles `u = 2 pi i / segments` (around z) and `v = 2 pi j / rings`
/// (around the tube) is `j * segments + i`.
fn torus(big_r: f64, r: f64, segments: u32, rings: u32) -> TriMesh {
    let mut positions = Vec::new();
    for j in 0..rings {
        let v = TAU * f64::from(j) / f64::from(rings);
        for i in 0..segments {
            let u = TAU * f64::from(i) / f64::from(segments);
            let w = big_r + r * v.cos();
            positions.push(DVec3::new(w * u.cos(), w * u.sin(), r * v.sin()));
        }
    }
    let at = |i: u32, j: u32| (j % rings) * segments + i % segments;
    let mut triangles = Vec::new();
    for j in 0..rings {
        for i in 0..segments {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }
    TriMesh::new(positions, triangles).expect("valid torus")
}

/// Height field `z = h(x, y)` on `[-half, half]^2` with `2 n` quads per side, normals
/// up; the vertex at the origin is returned too.
fn height_field(half: f64, n: u32, h: impl Fn(f64, f64) -> f64) -> (TriMesh, usize) {
    let flat = shapes::plane(2.0 * half, 2 * n).expect("plane");
    let positions = flat
        .positions()
        .iter()
        .map(|p| {
            let (x, y) = (p.x - half, p.y - half);
            DVec3::new(x, y, h(x, y))
        })
        .collect();
    let mesh = TriMesh::new(positions, flat.triangles().to_vec()).expect("valid grid");
    let centre = (n * (2 * n + 1) + n) as usize;
    assert!(mesh.positions()[centre].truncate().length() < 1e-12);
    (mesh, centre)
}

fn max_relative_error(values: impl Iterator<Item = f64>, expected: f64) -> f64 {
    values
        .map(|k| (k - expected).abs() / expected.abs())
        .fold(0.0, f64::max)
}

#[test]
fn sphere_has_equal_curvatures_one_over_r() {
    let r = 2.0;
    for (segments, rings) in [(12, 6), (24, 12), (48, 24)] {
        let mesh = uv_sphere(r, segments, rings);
        for smoothing in [0, 3] {
            let k = principal_curvatures(&mesh, smoothing);
            let e1 = max_relative_error(k.k1.iter().copied(), 1.0 / r);
            let e2 = max_relative_error(k.k2.iter().copied(), 1.0 / r);
            eprintln!(
                "sphere {segments}x{rings} smoothing {smoothing}: max rel err k1 {e1:.2e} k2 {e2:.2e}"
            );
            assert!(e1 < 1e-9 && e2 < 1e-9, "{segments}x{rings}: {e1} {e2}");
        }
    }
}

#[test]
fn cylinder_bends_around_and_is_straight_along_the_axis() {
    let r = 0.5;
    let (segments, rows) = (32, 8);
    let mesh = cylinder(r, 2.0, segments, rows);
    let k = principal_curvatures(&mesh, 0);
    let rim = |v: usize| v < segments as usize || v >= (rows * segments) as usize;
    let (mut err_k1, mut err_k2, mut err_dir, mut rim_err) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for v in 0..mesh.vertex_count() {
        let p = mesh.positions()[v];
        let around = DVec3::new(-p.y, p.x, 0.0).normalize();
        let e1 = (k.k1[v] - 1.0 / r).abs() * r;
        if rim(v) {
            rim_err = rim_err.max(e1);
            continue;
        }
        err_k1 = err_k1.max(e1);
        err_k2 = err_k2.max(k.k2[v].abs() * r);
        err_dir = err_dir.max(1.0 - k.d1[v].dot(around).abs());
    }
    eprintln!(
        "cylinder interior: rel err k1 {err_k1:.2e}, |k2| r {err_k2:.2e}, 1-|d1.around| {err_dir:.2e}; rim rel err k1 {rim_err:.2e}"
    );
    assert!(err_k1 < 1e-9 && err_k2 < 1e-9 && err_dir < 1e-12);
    assert!(rim_err < 1e-9);

    // The sampling tensor: densest around the circumference, anisotropy at its clamp.
    let field = FieldSpec::default_curvature().build(&mesh).expect("valid");
    for v in segments as usize..(rows * segments) as usize {
        let p = mesh.positions()[v];
        let e = eigen_in_plane(&field.tensors()[v], mesh.vertex_normals()[v]);
        assert!(
            (e.anisotropy() - DEFAULT_MAX_ANISOTROPY).abs() < 1e-9,
            "{}",
            e.anisotropy()
        );
        assert!(e.major.z.abs() < 1e-9 && e.major.dot(p.truncate().extend(0.0)).abs() < 1e-9);
    }
}

#[test]
fn plane_is_flat_floor_density_and_isotropic() {
    let mesh = shapes::plane(3.0, 6).expect("plane");
    let k = principal_curvatures(&mesh, 2);
    assert!(k.k1.iter().chain(&k.k2).all(|&c| c == 0.0));
    for normalization in [
        CurvatureNormalization::AreaRadius,
        CurvatureNormalization::Max,
        CurvatureNormalization::Raw,
    ] {
        let spec = FieldSpec::Curvature {
            measure: CurvatureMeasure::Mean,
            normalization,
            floor: 0.3,
            scale: 5.0,
            max_anisotropy: 8.0,
            isotropy_curvature: 0.01,
            smoothing_iterations: 1,
        };
        let field = spec.build(&mesh).expect("valid");
        for v in 0..mesh.vertex_count() {
            let e = eigen_in_plane(&field.tensors()[v], DVec3::Z);
            assert!((e.density() - 0.3).abs() < 1e-15 && (e.anisotropy() - 1.0).abs() < 1e-12);
        }
    }
}

#[test]
fn paraboloid_origin_has_curvatures_a_b_along_x_y() {
    let (a, b) = (1.0, 0.4);
    let mut last = f64::INFINITY;
    for n in [4, 8, 16, 32] {
        let (mesh, o) = height_field(0.5, n, |x, y| 0.5 * (a * x * x + b * y * y));
        let k = principal_curvatures(&mesh, 0);
        // Normals point up, the surface bends towards them: negative curvatures.
        let err = ((k.k1[o] + a).abs() / a).max((k.k2[o] + b).abs() / b);
        let dir = (1.0 - k.d1[o].x.abs()).max(1.0 - k.d2[o].y.abs());
        let smoothed = principal_curvatures(&mesh, 2);
        let err_s = ((smoothed.k1[o] + a).abs() / a).max((smoothed.k2[o] + b).abs() / b);
        eprintln!(
            "paraboloid h = {:.4}: max rel err {err:.2e} (smoothed x2: {err_s:.2e}), 1-|cos| {dir:.1e}",
            0.5 / f64::from(n)
        );
        assert!(
            err < 0.02 && err_s < 0.05 && dir < 1e-4,
            "n {n}: {err} {err_s} {dir}"
        );
        assert!(
            err <= last * 1.01,
            "error grew with resolution: {err} after {last}"
        );
        last = err;
    }
}

#[test]
fn ellipsoid_axis_point_converges() {
    // x^2/a^2 + y^2/b^2 + z^2/c^2 = 1 at (a, 0, 0): k = a / b^2 along y, a / c^2 along z.
    let (a, b, c) = (1.0, 0.7, 0.5);
    let mut last = f64::INFINITY;
    for (segments, rings) in [(16, 8), (32, 16), (64, 32), (128, 64)] {
        let sphere = uv_sphere(1.0, segments, rings);
        let mesh = TriMesh::new(
            sphere
                .positions()
                .iter()
                .map(|p| *p * DVec3::new(a, b, c))
                .collect(),
            sphere.triangles().to_vec(),
        )
        .expect("valid ellipsoid");
        let v = mesh
            .positions()
            .iter()
            .position(|p| (*p - DVec3::X * a).length() < 1e-12)
            .expect("vertex on the x axis");
        let k = principal_curvatures(&mesh, 0);
        let (kz, ky) = (a / (c * c), a / (b * b));
        let err = ((k.k1[v] - kz).abs() / kz).max((k.k2[v] - ky).abs() / ky);
        let dir = 1.0 - k.d1[v].z.abs();
        eprintln!("ellipsoid {segments}x{rings}: max rel err {err:.2e}, 1-|d1.z| {dir:.1e}");
        assert!(
            err < last && dir < 1e-2,
            "{segments}x{rings}: {err} after {last}, {dir}"
        );
        last = err;
    }
    assert!(last < 0.01);
}

#[test]
fn torus_curvatures_converge() {
    let (big_r, r) = (1.0, 0.4);
    let mut last = f64::INFINITY;
    for (segments, rings) in [(24, 12), (48, 24), (96, 48)] {
        let mesh = torus(big_r, r, segments, rings);
        let k = principal_curvatures(&mesh, 0);
        let mut err = 0.0f64;
        for j in 0..rings {
            let v = TAU * f64::from(j) / f64::from(rings);
            let tube = 1.0 / r;
            let ring = v.cos() / (big_r + r * v.cos());
            for i in 0..segments {
                let id = (j * segments + i) as usize;
                // |tube| >= |ring| everywhere on this torus (R > 2r).
                err = err
                    .max((k.k1[id] - tube).abs() / tube)
                    .max((k.k2[id] - ring).abs() / tube);
            }
        }
        eprintln!("torus {segments}x{rings}: max err / (1/r) {err:.2e}");
        assert!(err < last, "no convergence: {err} after {last}");
        last = err;
    }
    assert!(last < 0.01);
}

#[test]
fn estimate_is_invariant_under_rigid_motion() {
    let (mesh, _) = height_field(0.5, 6, |x, y| 0.8 * x * x - 0.3 * x * y + 0.2 * y * y * y);
    let q = DQuat::from_euler(glam::EulerRot::XYZ, 0.3, -1.1, 2.0);
    let shift = DVec3::new(3.0, -2.0, 0.5);
    let moved = TriMesh::new(
        mesh.positions().iter().map(|p| q * *p + shift).collect(),
        mesh.triangles().to_vec(),
    )
    .expect("valid");
    let (k, km) = (
        principal_curvatures(&mesh, 1),
        principal_curvatures(&moved, 1),
    );
    for v in 0..mesh.vertex_count() {
        assert!((k.k1[v] - km.k1[v]).abs() < 1e-9 && (k.k2[v] - km.k2[v]).abs() < 1e-9);
        if (k.k1[v].abs() - k.k2[v].abs()).abs() > 1e-6 {
            assert!((q * k.d1[v]).dot(km.d1[v]).abs() > 1.0 - 1e-9, "vertex {v}");
        }
    }
}

#[test]
fn tensors_are_tangent_and_match_principal_values() {
    let mesh = torus(1.0, 0.3, 20, 10);
    let k = principal_curvatures(&mesh, 2);
    for v in 0..mesh.vertex_count() {
        let n = mesh.vertex_normals()[v];
        let t = k.tensors[v];
        assert!((t * n).length() < 1e-12 && t.abs_diff_eq(t.transpose(), 1e-14));
        let rebuilt = outer(k.d1[v], k.d1[v]) * k.k1[v] + outer(k.d2[v], k.d2[v]) * k.k2[v];
        assert!(rebuilt.abs_diff_eq(t, 1e-12), "vertex {v}");
        assert!(k.k1[v].abs() >= k.k2[v].abs());
        assert!(k.d1[v].dot(n).abs() < 1e-12 && (k.d2[v] - n.cross(k.d1[v])).length() < 1e-15);
    }
}

#[test]
fn sampling_tensor_follows_the_documented_formulas() {
    // Sphere: isotropic, density floor + scale * c / r with c the area radius.
    let r = 3.0;
    let mesh = uv_sphere(r, 24, 12);
    let c = (mesh.area() / (4.0 * PI)).sqrt();
    for measure in [
        CurvatureMeasure::Mean,
        CurvatureMeasure::Gaussian,
        CurvatureMeasure::MaxAbs,
        CurvatureMeasure::Rms,
    ] {
        let spec = FieldSpec::Curvature {
            measure,
            normalization: CurvatureNormalization::AreaRadius,
            floor: 0.5,
            scale: 2.0,
            max_anisotropy: 4.0,
            isotropy_curvature: 0.05,
            smoothing_iterations: 0,
        };
        let field = spec.build(&mesh).expect("valid");
        for (t, n) in field.tensors().iter().zip(mesh.vertex_normals()) {
            let e = eigen_in_plane(t, *n);
            assert!(
                (e.density() - (0.5 + 2.0 * c / r)).abs() < 1e-9,
                "{measure:?}"
            );
            assert!((e.anisotropy() - 1.0).abs() < 1e-9);
        }
    }
    // Paraboloid origin, raw normalization: anisotropy (a + eps) / (b + eps), density
    // floor + scale * rms(a, b), major along x.
    let (a, b) = (1.0, 0.25);
    let (mesh, o) = height_field(0.5, 16, |x, y| 0.5 * (a * x * x + b * y * y));
    let k = principal_curvatures(&mesh, 0);
    let spec = FieldSpec::Curvature {
        measure: CurvatureMeasure::Rms,
        normalization: CurvatureNormalization::Raw,
        floor: 0.1,
        scale: 1.0,
        max_anisotropy: 10.0,
        isotropy_curvature: 0.05,
        smoothing_iterations: 0,
    };
    let e = eigen_in_plane(&spec.build(&mesh).expect("valid").tensors()[o], DVec3::Z);
    let expect_ratio = (k.k1[o].abs() + 0.05) / (k.k2[o].abs() + 0.05);
    assert!((e.anisotropy() - expect_ratio).abs() < 1e-9);
    assert!((expect_ratio - (a + 0.05) / (b + 0.05)).abs() < 0.05);
    let rms = (0.5 * (k.k1[o].powi(2) + k.k2[o].powi(2))).sqrt();
    assert!((e.density() - (0.1 + rms)).abs() < 1e-9);
    assert!(e.major.dot(k.d1[o]).abs() > 1.0 - 1e-12 && e.major.x.abs() > 1.0 - 1e-4);
    // Max normalization: the largest density is floor + scale.
    let spec = FieldSpec::Curvature {
        measure: CurvatureMeasure::MaxAbs,
        normalization: CurvatureNormalization::Max,
        floor: 0.1,
        scale: 3.0,
        max_anisotropy: 2.0,
        isotropy_curvature: 0.05,
        smoothing_iterations: 1,
    };
    let field = spec.build(&mesh).expect("valid");
    let max = field
        .vertex_densities(&mesh)
        .into_iter()
        .fold(0.0, f64::max);
    assert!((max - 3.1).abs() < 1e-9);
    assert!(field.tensors().iter().all(|t| t.is_finite()));
}

/// A curvature spec with the given numeric settings.
fn curvature_spec(
    floor: f64,
    scale: f64,
    max_anisotropy: f64,
    eps: f64,
    iterations: u32,
) -> FieldSpec {
    FieldSpec::Curvature {
        measure: CurvatureMeasure::Rms,
        normalization: CurvatureNormalization::AreaRadius,
        floor,
        scale,
        max_anisotropy,
        isotropy_curvature: eps,
        smoothing_iterations: iterations,
    }
}

#[test]
fn curvature_settings_are_validated_by_name() {
    let mesh = shapes::plane(1.0, 2).expect("plane");
    let cases = [
        ("floor", curvature_spec(0.0, 1.0, 4.0, 0.05, 2)),
        ("floor", curvature_spec(f64::NAN, 1.0, 4.0, 0.05, 2)),
        ("scale", curvature_spec(0.2, -1.0, 4.0, 0.05, 2)),
        ("scale", curvature_spec(0.2, f64::INFINITY, 4.0, 0.05, 2)),
        ("max_anisotropy", curvature_spec(0.2, 1.0, 0.9, 0.05, 2)),
        (
            "max_anisotropy",
            curvature_spec(0.2, 1.0, f64::NAN, 0.05, 2),
        ),
        ("isotropy_curvature", curvature_spec(0.2, 1.0, 4.0, 0.0, 2)),
        (
            "smoothing_iterations",
            curvature_spec(0.2, 1.0, 4.0, 0.05, 1001),
        ),
    ];
    for (name, spec) in cases {
        match spec.build(&mesh) {
            Err(FieldError::InvalidParameter { parameter, .. }) => assert_eq!(parameter, name),
            other => panic!("{name}: expected InvalidParameter, got {other:?}"),
        }
    }
    assert!(FieldSpec::default_curvature().validate().is_ok());
    assert_eq!(
        FieldSpec::default_curvature(),
        curvature_spec(0.2, 1.0, 4.0, 0.05, 2)
    );
    // Edge values are valid: no density scaling, isotropic, no smoothing.
    assert!(curvature_spec(1e-9, 0.0, 1.0, 1e-9, 0).build(&mesh).is_ok());
}

#[test]
fn voronoi_areas_sum_to_face_areas() {
    // An obtuse triangle exercises the mixed-area branch.
    let mesh = TriMesh::new(
        vec![
            DVec3::ZERO,
            DVec3::new(4.0, 0.0, 0.0),
            DVec3::new(1.0, 0.5, 0.0),
            DVec3::new(2.0, 3.0, 0.0),
        ],
        vec![[0, 1, 2], [1, 3, 2], [0, 2, 3]],
    )
    .expect("valid");
    let (corners, points) = voronoi_areas(&mesh);
    for (c, a) in corners.iter().zip(mesh.face_areas()) {
        assert!((c.iter().sum::<f64>() - a).abs() < 1e-12 && c.iter().all(|&x| x > 0.0));
    }
    assert!((points.iter().sum::<f64>() - mesh.area()).abs() < 1e-12);
}

#[test]
fn rotation_between_takes_from_to_to() {
    let cases = [
        (DVec3::Z, DVec3::X),
        (
            DVec3::new(1.0, 2.0, 3.0).normalize(),
            DVec3::new(-1.0, 0.5, 0.2).normalize(),
        ),
        (DVec3::Y, DVec3::Y),
    ];
    for (a, b) in cases {
        let r = rotation_between(a, b);
        assert!((r * a - b).length() < 1e-14);
        assert!((r * r.transpose()).abs_diff_eq(DMat3::IDENTITY, 1e-14));
        assert!((r.determinant() - 1.0).abs() < 1e-14);
    }
    assert_eq!(rotation_between(DVec3::Z, -DVec3::Z), DMat3::IDENTITY);
}

/// A strip `length` long and `width` wide along x, bent into an arc of `radius` in the
/// x-z plane (flat when `radius` is infinite), `n` quads of two triangles.
fn needle(length: f64, width: f64, radius: f64, n: u32) -> TriMesh {
    let mut p = Vec::new();
    for i in 0..=n {
        let s = length * f64::from(i) / f64::from(n);
        let (x, z) = if radius.is_finite() {
            let a = s / radius;
            (radius * a.sin(), radius * (1.0 - a.cos()))
        } else {
            (s, 0.0)
        };
        p.push(DVec3::new(x, 0.0, z));
        p.push(DVec3::new(x, width, z));
    }
    let t = (0..n)
        .flat_map(|i| [[2 * i, 2 * i + 2, 2 * i + 3], [2 * i, 2 * i + 3, 2 * i + 1]])
        .collect();
    TriMesh::new(p, t).expect("needle")
}

#[test]
fn needle_thin_strips_have_finite_curvature() {
    // 1000 x 1e-6: the Voronoi areas' obtuse test once cancelled a right angle into an
    // obtuse one and divided by zero, and the curvature field had a non-finite tensor.
    let flat = needle(1000.0, 1e-6, f64::INFINITY, 1);
    let k = principal_curvatures(&flat, 2);
    assert!(k.k1.iter().chain(&k.k2).all(|&x| x == 0.0), "{k:?}");
    assert!(FieldSpec::default_curvature().build(&flat).is_ok());
    // Bent along its length into an arc of radius 300: |k1| near 1/300 inside.
    let bent = needle(300.0, 1e-6, 300.0, 50);
    let k = principal_curvatures(&bent, 2);
    assert!(k.k1.iter().chain(&k.k2).all(|x| x.is_finite()), "{k:?}");
    for v in 20..80 {
        let ratio = k.k1[v].abs() * 300.0;
        assert!((0.5..1.5).contains(&ratio), "vertex {v}: k1 = {}", k.k1[v]);
    }
    assert!(FieldSpec::default_curvature().build(&bent).is_ok());
}
