use glam::{DMat3, DVec3};

use super::*;
use crate::mesh::shapes;

#[test]
fn eigen_2x2_known_answers() {
    let (l1, l2, th) = eigen_2x2(4.0, 0.0, 1.0);
    assert_eq!((l1, l2, th), (4.0, 1.0, 0.0));
    let (l1, l2, th) = eigen_2x2(1.0, 0.0, 4.0);
    assert_eq!((l1, l2), (4.0, 1.0));
    assert!((th.abs() - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
    // Rotated by 30 degrees: R diag(3, 1) R^T.
    let a = 30f64.to_radians();
    let (c, s) = (a.cos(), a.sin());
    let m = [3.0 * c * c + s * s, 2.0 * c * s, 3.0 * s * s + c * c];
    let (l1, l2, th) = eigen_2x2(m[0], m[1], m[2]);
    assert!((l1 - 3.0).abs() < 1e-14 && (l2 - 1.0).abs() < 1e-14 && (th - a).abs() < 1e-14);
    // Isotropic: any angle is fine, eigenvalues equal.
    let (l1, l2, _) = eigen_2x2(2.0, 0.0, 2.0);
    assert_eq!((l1, l2), (2.0, 2.0));
}

#[test]
fn eigen_in_plane_reconstructs_tensor() {
    let n = DVec3::new(1.0, 2.0, 3.0).normalize();
    let (e1, e2) = tangent_frame(n);
    assert!(e1.dot(n).abs() < 1e-15 && e2.dot(n).abs() < 1e-15 && e1.cross(e2).dot(n) > 0.999);
    for k in 0..16 {
        let a = k as f64 * 0.4;
        let m1 = e1 * a.cos() + e2 * a.sin();
        let m2 = n.cross(m1);
        let t = outer(m1, m1) * 5.0 + outer(m2, m2) * 0.5;
        let e = eigen_in_plane(&t, n);
        assert!((e.l1 - 5.0).abs() < 1e-12 && (e.l2 - 0.5).abs() < 1e-12);
        assert!(e.major.dot(m1).abs() > 1.0 - 1e-12, "angle {a}");
        assert!(e.minor.dot(m2).abs() > 1.0 - 1e-12);
    }
}

#[test]
fn validation_names_the_vertex() {
    let mesh = shapes::plane(1.0, 2).expect("plane");
    let mut t = vec![DMat3::IDENTITY; mesh.vertex_count()];
    assert!(TensorField::new(&mesh, t.clone()).is_ok());
    t[4] = DMat3::from_cols_array(&[1.0, 0.5, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]);
    assert!(matches!(
        TensorField::new(&mesh, t.clone()),
        Err(FieldError::NotSymmetric { vertex: 4, .. })
    ));
    t[4] = DMat3::IDENTITY;
    t[2] = DMat3::from_diagonal(DVec3::new(1.0, f64::NAN, 1.0));
    assert!(matches!(
        TensorField::new(&mesh, t.clone()),
        Err(FieldError::NonFinite { vertex: 2 })
    ));
    // Positive only along the normal (z): zero in the tangent plane.
    t[2] = DMat3::from_diagonal(DVec3::new(0.0, 0.0, 1.0));
    let err = TensorField::new(&mesh, t.clone()).expect_err("not PD in plane");
    assert!(matches!(
        err,
        FieldError::NotPositiveDefinite { vertex: 2, .. }
    ));
    assert!(err.to_string().contains("vertex 2"));
    t[2] = DMat3::from_diagonal(DVec3::new(1.0, -1.0, 1.0));
    assert!(matches!(
        TensorField::new(&mesh, t),
        Err(FieldError::NotPositiveDefinite { vertex: 2, .. })
    ));
    assert!(matches!(
        TensorField::new(&mesh, vec![]),
        Err(FieldError::CountMismatch { .. })
    ));
}

#[test]
fn constant_spec_on_sphere_is_tangent_with_right_eigenvalues() {
    let mesh = shapes::plane(2.0, 3).expect("plane");
    let spec = FieldSpec::Constant {
        direction: [1.0, 1.0, 0.0],
        anisotropy: 3.0,
        density: 2.0,
    };
    let field = spec.build(&mesh).expect("valid");
    for f in 0..mesh.face_count() as u32 {
        let e = field.face_eigen(&mesh, f, [0.2, 0.3, 0.5]);
        assert!((e.l1 - 6.0).abs() < 1e-12 && (e.l2 - 2.0 / 3.0).abs() < 1e-12);
        assert!(e.major.dot(DVec3::new(1.0, 1.0, 0.0).normalize()).abs() > 1.0 - 1e-12);
    }
    let bad = FieldSpec::Constant {
        direction: [1.0, 0.0, 0.0],
        anisotropy: 0.5,
        density: 1.0,
    };
    assert!(matches!(
        bad.build(&mesh),
        Err(FieldError::InvalidParameter {
            parameter: "anisotropy",
            ..
        })
    ));
    let bad = FieldSpec::Constant {
        direction: [0.0, 0.0, 0.0],
        anisotropy: 1.0,
        density: 1.0,
    };
    assert!(bad.build(&mesh).is_err());
}

#[test]
fn interpolation_is_linear_and_exact_at_corners() {
    let mesh = shapes::plane(1.0, 1).expect("plane");
    let spec = FieldSpec::Planar {
        density: PlanarDensity::Gaussian {
            center: [0.0, 0.0],
            sigma: 0.3,
            peak: 5.0,
            base: 1.0,
        },
        direction: [1.0, 0.0, 0.0],
        anisotropy: 1.0,
    };
    let field = spec.build(&mesh).expect("valid");
    let d = field.vertex_densities(&mesh);
    assert!((d[0] - 6.0).abs() < 1e-12);
    let t = mesh.triangles()[0];
    let e = field.face_eigen(&mesh, 0, [1.0, 0.0, 0.0]);
    assert!((e.density() - d[t[0] as usize]).abs() < 1e-12);
    // Isotropic tensors: the midpoint is the mean of the two endpoint tensors.
    let mid = field.interpolate(&mesh, 0, [0.5, 0.5, 0.0]);
    let expect = (field.tensors()[t[0] as usize] + field.tensors()[t[1] as usize]) * 0.5;
    assert!(mid.abs_diff_eq(expect, 1e-15));
}
