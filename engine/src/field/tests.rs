use std::path::{Path, PathBuf};

use glam::{DMat3, DVec2, DVec3};

use super::*;
use crate::mesh::{TriMesh, shapes};

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
fn eigenvalues_outside_the_supported_range_are_refused() {
    let mesh = shapes::plane(1.0, 2).expect("plane");
    let n = mesh.vertex_count();
    let [lo, hi] = super::EIGENVALUE_RANGE;
    let x = vec![DVec3::X; n];
    // The ends of the range are accepted, by both constructors.
    assert!(TensorField::from_frames(&mesh, &x, &vec![[hi, lo]; n]).is_ok());
    assert!(TensorField::new(&mesh, vec![DMat3::IDENTITY * hi; n]).is_ok());
    // Beyond them, the vertex and both eigenvalues are named (1e300 once overflowed the
    // cells' measure, 1e-300 vanished from it).
    let mut l = vec![[1.0, 1.0]; n];
    l[3] = [1e300, 1.0];
    let e = TensorField::from_frames(&mesh, &x, &l).expect_err("too large");
    assert!(
        matches!(e, FieldError::OutOfRange { vertex: 3, l1, l2 } if l1 == 1e300 && l2 == 1.0),
        "{e:?}"
    );
    assert_eq!(
        e.to_string(),
        "tensor at vertex 3 has eigenvalues 1.000e300 and 1.000e0, outside the supported range \
         [1e-100, 1e100]; densities are relative, so scale every density of the field by \
         one factor into it"
    );
    let mut t = vec![DMat3::IDENTITY; n];
    t[1] = DMat3::IDENTITY * 1e-300;
    assert!(matches!(
        TensorField::new(&mesh, t),
        Err(FieldError::OutOfRange { vertex: 1, .. })
    ));
    for density in [1e300, 1e-300] {
        let spec = FieldSpec::Constant {
            direction: [1.0, 0.0, 0.0],
            anisotropy: 2.0,
            density,
        };
        assert!(
            matches!(
                spec.build(&mesh),
                Err(FieldError::OutOfRange { vertex: 0, .. })
            ),
            "{density}"
        );
    }
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

// ---------------------------------------------------------------------------------
// Planar test functions (paper section 7.5).

/// Builds `spec` and returns the eigen-decomposition at every vertex of `mesh`.
fn vertex_eigen(spec: &FieldSpec, mesh: &TriMesh) -> Vec<Eigen2> {
    isotropic::eigens(mesh, &spec.build(mesh).expect("valid spec"))
}

fn planar(density: PlanarDensity) -> FieldSpec {
    FieldSpec::Planar {
        density,
        direction: [1.0, 0.0, 0.0],
        anisotropy: 1.0,
    }
}

fn parameter_of(result: Result<impl std::fmt::Debug, FieldError>) -> &'static str {
    match result {
        Err(FieldError::InvalidParameter { parameter, .. }) => parameter,
        other => panic!("expected InvalidParameter, got {other:?}"),
    }
}

#[test]
fn ramp_density_is_linear_between_its_ends_and_constant_beyond() {
    let ramp = PlanarDensity::Ramp {
        start: [0.0, 0.0],
        end: [2.0, 0.0],
        start_density: 1.0,
        end_density: 5.0,
    };
    ramp.validate().expect("valid");
    let cases = [
        ([0.0, 0.0], 1.0),
        ([1.0, 7.0], 3.0),
        ([0.5, -1.0], 2.0),
        ([2.0, 0.0], 5.0),
        ([-3.0, 0.0], 1.0),
        ([9.0, 1.0], 5.0),
    ];
    for (p, expect) in cases {
        assert!((ramp.eval(DVec2::from(p)) - expect).abs() < 1e-15, "{p:?}");
    }
    let mesh = shapes::plane(2.0, 4).expect("plane");
    for (e, p) in vertex_eigen(&planar(ramp), &mesh)
        .iter()
        .zip(mesh.positions())
    {
        assert!((e.density() - (1.0 + 2.0 * p.x)).abs() < 1e-12);
    }
}

#[test]
fn balzer_density_matches_its_closed_form() {
    let balzer = PlanarDensity::Balzer {
        origin: [0.0, 0.0],
        size: 4.0,
        floor: 0.001,
    };
    balzer.validate().expect("valid");
    // Centre of [0, 4]^2 is u = 0: the peak.
    assert!((balzer.eval(DVec2::new(2.0, 2.0)) - 1.001).abs() < 1e-15);
    // u = (0.5, 0.5): exp(-10) + 0.2 sin^2(pi / 2)^2.
    let expect = 0.001 + (-10.0f64).exp() + 0.2;
    assert!((balzer.eval(DVec2::new(3.0, 3.0)) - expect).abs() < 1e-15);
    // Corner u = (-1, -1): exp(-40) + 0 (sin(-pi) ~ 1e-16): about the floor.
    assert!((balzer.eval(DVec2::ZERO) - 0.001).abs() < 1e-15);
    // Positive on a wide area around its square, even where exp underflows.
    for i in -20..=20 {
        for j in -20..=20 {
            let d = balzer.eval(DVec2::new(f64::from(i), f64::from(j)));
            assert!((0.001..=1.201).contains(&d), "{i} {j}: {d}");
        }
    }
    let mesh = shapes::plane(4.0, 8).expect("plane");
    let spec = FieldSpec::Planar {
        density: balzer.clone(),
        direction: [0.0, 1.0, 0.0],
        anisotropy: 2.0,
    };
    for (e, p) in vertex_eigen(&spec, &mesh).iter().zip(mesh.positions()) {
        assert!((e.density() - balzer.eval(p.truncate())).abs() < 1e-12);
        assert!((e.anisotropy() - 2.0).abs() < 1e-9 && e.major.y.abs() > 1.0 - 1e-12);
    }
}

#[test]
fn planar_densities_reject_bad_parameters_by_name() {
    let ramp = |start: [f64; 2], end: [f64; 2], d0: f64, d1: f64| PlanarDensity::Ramp {
        start,
        end,
        start_density: d0,
        end_density: d1,
    };
    let balzer = |origin: [f64; 2], size: f64, floor: f64| PlanarDensity::Balzer {
        origin,
        size,
        floor,
    };
    let cases = [
        ("start", ramp([f64::NAN, 0.0], [1.0, 0.0], 1.0, 1.0)),
        ("end", ramp([0.0, 0.0], [0.0, f64::INFINITY], 1.0, 1.0)),
        ("end", ramp([1.0, 1.0], [1.0, 1.0], 1.0, 1.0)),
        ("start_density", ramp([0.0, 0.0], [1.0, 0.0], 0.0, 1.0)),
        ("end_density", ramp([0.0, 0.0], [1.0, 0.0], 1.0, -2.0)),
        ("origin", balzer([0.0, f64::NAN], 1.0, 0.1)),
        ("size", balzer([0.0, 0.0], 0.0, 0.1)),
        ("floor", balzer([0.0, 0.0], 1.0, 0.0)),
        ("floor", balzer([0.0, 0.0], 1.0, f64::NAN)),
        (
            "sigma",
            PlanarDensity::Gaussian {
                center: [0.0, 0.0],
                sigma: -1.0,
                peak: 1.0,
                base: 1.0,
            },
        ),
    ];
    let mesh = shapes::plane(1.0, 1).expect("plane");
    for (name, density) in cases {
        assert_eq!(parameter_of(density.validate()), name);
        assert_eq!(parameter_of(planar(density).build(&mesh)), name);
    }
}

#[test]
fn shear_metric_has_known_eigenvalues_and_unit_density() {
    let warp = PlanarWarp::Shear {
        shear: 0.5,
        shear_rate: 1.0,
    };
    let spec = FieldSpec::Warp {
        warp: warp.clone(),
        density: 3.0,
    };
    let mesh = shapes::plane(2.0, 6).expect("plane");
    for (e, p) in vertex_eigen(&spec, &mesh).iter().zip(mesh.positions()) {
        let s = 0.5 + p.y;
        // Singular values of [[1, s], [0, 1]]: (sqrt(4 + s^2) +- s) / 2.
        let root = (4.0 + s * s).sqrt();
        let (s1, s2) = (0.5 * (root + s), 0.5 * (root - s));
        assert!((e.l1 - 3.0 * s1 * s1).abs() < 1e-12 && (e.l2 - 3.0 * s2 * s2).abs() < 1e-12);
        assert!((e.density() - 3.0).abs() < 1e-12, "det J = 1");
        assert!((e.anisotropy() - s1 / s2).abs() < 1e-9);
        // Major eigenvector of J^T J = [[1, s], [s, 1 + s^2]]: (s, s1^2 - 1) normalised.
        let m = DVec3::new(s, s1 * s1 - 1.0, 0.0).normalize();
        assert!(e.major.dot(m).abs() > 1.0 - 1e-12);
    }
    // The direction turns and the anisotropy grows along y.
    let (low, high) = (DVec2::new(0.0, 0.0), DVec2::new(0.0, 2.0));
    let jl = warp.jacobian(low).expect("defined");
    let jh = warp.jacobian(high).expect("defined");
    assert_eq!(jl.col(1), DVec2::new(0.5, 1.0));
    assert_eq!(jh.col(1), DVec2::new(2.5, 1.0));
}

#[test]
fn perspective_metric_has_known_density_and_anisotropy() {
    let warp = PlanarWarp::Perspective {
        tilt: [0.0, 0.5],
        origin: [0.0, 0.0],
    };
    let spec = FieldSpec::Warp {
        warp: warp.clone(),
        density: 1.0,
    };
    let mesh = shapes::plane(4.0, 8).expect("plane");
    let eigen = vertex_eigen(&spec, &mesh);
    for (e, p) in eigen.iter().zip(mesh.positions()) {
        let w = 1.0 + 0.5 * p.y;
        assert!((e.density() - w.powi(-3)).abs() < 1e-12, "density 1 / w^3");
        if p.x == 0.0 {
            // On the line through the origin along the tilt, J = diag(1/w, 1/w^2):
            // spacing ratio w, samples closest across the tilt (along x).
            assert!((e.anisotropy() - w).abs() < 1e-9);
            if w > 1.0 {
                assert!(e.major.x.abs() > 1.0 - 1e-12);
            }
        }
    }
    // J = I at the origin; the mesh's vertex 0 is the origin.
    assert!((eigen[0].l1 - 1.0).abs() < 1e-15 && (eigen[0].l2 - 1.0).abs() < 1e-15);
    // Off the axis the direction turns: not aligned with x or y.
    let far = mesh.vertex_count() - 1; // (4, 4)
    assert!(eigen[far].major.x.abs() < 0.99 && eigen[far].major.y.abs() < 0.99);
    assert!(eigen[far].anisotropy() > 1.5);
    // A horizon across the mesh is an error naming the first vertex beyond it.
    let beyond = FieldSpec::Warp {
        warp: PlanarWarp::Perspective {
            tilt: [0.0, -0.5],
            origin: [0.0, 0.0],
        },
        density: 1.0,
    };
    match beyond.build(&mesh) {
        Err(FieldError::OutsideDomain { vertex, value, .. }) => {
            assert_eq!(mesh.positions()[vertex].y, 2.0);
            assert!(value <= 0.0);
        }
        other => panic!("expected OutsideDomain, got {other:?}"),
    }
}

#[test]
fn warps_reject_bad_parameters_by_name() {
    let mesh = shapes::plane(1.0, 1).expect("plane");
    let cases = [
        (
            "shear",
            PlanarWarp::Shear {
                shear: f64::NAN,
                shear_rate: 1.0,
            },
            1.0,
        ),
        (
            "shear_rate",
            PlanarWarp::Shear {
                shear: 0.0,
                shear_rate: f64::INFINITY,
            },
            1.0,
        ),
        (
            "tilt",
            PlanarWarp::Perspective {
                tilt: [f64::NAN, 0.0],
                origin: [0.0, 0.0],
            },
            1.0,
        ),
        (
            "origin",
            PlanarWarp::Perspective {
                tilt: [0.0, 0.0],
                origin: [0.0, f64::NEG_INFINITY],
            },
            1.0,
        ),
        (
            "density",
            PlanarWarp::Shear {
                shear: 0.0,
                shear_rate: 0.0,
            },
            0.0,
        ),
    ];
    for (name, warp, density) in cases {
        assert_eq!(
            parameter_of(FieldSpec::Warp { warp, density }.build(&mesh)),
            name
        );
    }
}

// ---------------------------------------------------------------------------------
// Field files.

fn parse(text: &str, mesh: &TriMesh) -> Result<TensorField, FieldError> {
    parse_field_file(text, Path::new("test.field"), mesh)
}

/// Two triangles over four vertices, with vertex 4 a duplicate of vertex 1 (merged)
/// and vertex 5 used by no face (dropped).
fn mesh_with_repairs() -> TriMesh {
    TriMesh::new(
        vec![
            DVec3::ZERO,
            DVec3::X,
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::Y,
            DVec3::X,
            DVec3::new(5.0, 5.0, 5.0),
        ],
        vec![[0, 1, 2], [0, 4, 2], [0, 2, 3]],
    )
    .expect("valid")
}

#[test]
fn field_file_reads_both_line_forms_with_comments() {
    let mesh = shapes::plane(1.0, 1).expect("plane"); // 4 vertices, no repairs
    let text = "# written by hand\n\
                \n\
                strata-field 1   # version 1\n\
                4 1 1 0 0\n\
                \t t 2 0 0 3 0 0\r\n\
                # the third vertex: major along y, direction not unit\n\
                9 1 0 5 0\n\
                1 1 0 0 1  # parallel to the normal: isotropic, any tangent\n";
    let field = parse(text, &mesh).expect("valid file");
    let e: Vec<Eigen2> = field
        .tensors()
        .iter()
        .map(|t| eigen_in_plane(t, DVec3::Z))
        .collect();
    assert!((e[0].l1 - 4.0).abs() < 1e-15 && (e[0].l2 - 1.0).abs() < 1e-15);
    assert!(e[0].major.x.abs() > 1.0 - 1e-15);
    assert!((e[1].l1 - 3.0).abs() < 1e-15 && (e[1].l2 - 2.0).abs() < 1e-15);
    assert!(e[1].major.y.abs() > 1.0 - 1e-15);
    assert!((e[2].l1 - 9.0).abs() < 1e-15 && e[2].major.y.abs() > 1.0 - 1e-15);
    assert!((e[3].l1 - 1.0).abs() < 1e-15 && (e[3].l2 - 1.0).abs() < 1e-15);
}

#[test]
fn field_file_maps_input_vertices_through_repairs() {
    let mesh = mesh_with_repairs();
    assert_eq!(mesh.vertex_count(), 4);
    let map = mesh.input_vertex_map();
    assert_eq!(map[4], map[1]);
    assert_eq!(map[5], crate::mesh::NONE);
    // Vertex 4 (merged into 1) and 5 (dropped) carry other values: the first wins,
    // the dropped one is only checked.
    let text = "strata-field 1\n1 1 1 0 0\n2 1 1 0 0\n3 1 1 0 0\n4 1 1 0 0\n7 1 1 0 0\n8 1 0 0 1\n";
    let field = parse(text, &mesh).expect("valid");
    let d = field.vertex_densities(&mesh);
    for (input, expect) in [(0usize, 1.0f64), (1, 2.0), (2, 3.0), (3, 4.0), (4, 2.0)] {
        assert!(
            (d[map[input] as usize] - expect.sqrt()).abs() < 1e-15,
            "input {input}"
        );
    }
}

#[test]
fn field_file_round_trips() {
    let mesh = shapes::plane(2.0, 3).expect("plane");
    let spec = FieldSpec::Warp {
        warp: PlanarWarp::Perspective {
            tilt: [0.1, 0.2],
            origin: [0.3, 0.0],
        },
        density: 2.5,
    };
    let field = spec.build(&mesh).expect("valid");
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("perspective.field");
    std::fs::write(&path, format_field_file(&field)).expect("write");
    assert_eq!(read_field_file(&path, &mesh).expect("read back"), field);
    // Through the spec, with the path made relative to a config folder.
    let mut spec = FieldSpec::File {
        path: PathBuf::from("perspective.field"),
    };
    spec.resolve_paths(dir.path());
    assert_eq!(spec.build(&mesh).expect("read back"), field);
    // Absolute paths stay as they are.
    let mut absolute = FieldSpec::File { path: path.clone() };
    absolute.resolve_paths(Path::new("elsewhere"));
    assert_eq!(absolute, FieldSpec::File { path });
}

#[test]
fn field_file_errors_name_line_and_vertex() {
    let mesh = shapes::plane(1.0, 1).expect("plane"); // 4 vertices
    let head = "# comment\nstrata-field 1\n";
    let good = "1 1 1 0 0\n";
    let body = |bad: &str| format!("{head}{good}{good}{bad}{good}");
    // (text, 1-based line of the error, fragment of the message)
    let syntax_cases = [
        ("1 1 1 0 0\n".to_owned(), 1, "header"),
        ("\n# only comments\n".to_owned(), 2, "missing the header"),
        (
            "strata-field 2\n1 1 1 0 0\n".to_owned(),
            1,
            "unsupported header",
        ),
        ("strata-field\n".to_owned(), 1, "unsupported header"),
        (body("1 1 1 0\n"), 5, "5 numbers"),
        (body("1 1 1 0 0 0\n"), 5, "found 6 value(s)"),
        (body("t 1 0 0 1 0\n"), 5, "6 numbers after `t`"),
        (body("1 1 x 0 0\n"), 5, "`x` is not a number"),
        (body("t 1 0 0 1 0 1 0 0 0 0\n"), 5, "found 10 value(s)"),
    ];
    for (text, line, fragment) in syntax_cases {
        match parse(&text, &mesh) {
            Err(FieldError::Syntax {
                line: l,
                what,
                path,
            }) => {
                assert_eq!(
                    (l, path.as_path()),
                    (line, Path::new("test.field")),
                    "{text:?}"
                );
                assert!(what.contains(fragment), "{what:?} lacks {fragment:?}");
            }
            other => panic!("{text:?}: expected Syntax, got {other:?}"),
        }
    }
    // Values: the vertex is the data line's rank (here the third vertex, index 2).
    let value_cases = [
        ("NaN 1 1 0 0\n", "non-finite"),
        ("1 inf 1 0 0\n", "non-finite"),
        ("-1 1 1 0 0\n", "l1 = -1 must be > 0"),
        ("1 0 1 0 0\n", "l2 = 0 must be > 0"),
        ("1 1 0 0 0\n", "direction"),
        ("t 1 0 0 nan 0 1\n", "non-finite"),
        ("t 1 0 0 -1 0 1\n", "not positive definite"),
        ("t 0 0 0 0 0 1\n", "not positive definite"),
        (
            "1e200 1 1 0 0\n",
            "outside the supported range [1e-100, 1e100]",
        ),
        (
            "t 1e-200 0 0 1e-200 0 1e-200\n",
            "outside the supported range",
        ),
    ];
    for (bad, fragment) in value_cases {
        let err = parse(&body(bad), &mesh).expect_err(bad);
        match &err {
            FieldError::BadValue {
                line, vertex, what, ..
            } => {
                assert_eq!((*line, *vertex), (5, 2), "{bad:?}");
                assert!(what.contains(fragment), "{what:?} lacks {fragment:?}");
            }
            other => panic!("{bad:?}: expected BadValue, got {other:?}"),
        }
        let message = err.to_string();
        assert!(message.starts_with("test.field:5: vertex 2:"), "{message}");
    }
    // Counts.
    for (text, found) in [
        (format!("{head}{good}{good}{good}"), 3),
        (format!("{head}{good}{good}{good}{good}{good}"), 5),
        (head.to_owned(), 0),
    ] {
        match parse(&text, &mesh) {
            Err(FieldError::CountMismatch {
                expected: 4,
                found: f,
            }) => assert_eq!(f, found),
            other => panic!("expected CountMismatch, got {other:?}"),
        }
    }
    // A missing file.
    let spec = FieldSpec::File {
        path: PathBuf::from("/nonexistent/strata/field.txt"),
    };
    match spec.build(&mesh) {
        Err(FieldError::Io { path, .. }) => assert!(path.ends_with("field.txt")),
        other => panic!("expected Io, got {other:?}"),
    }
}
