use std::time::Instant;

use glam::{DVec2, DVec3};

use super::*;
use crate::field::{FieldSpec, TensorField};
use crate::mesh::{TriMesh, shapes};
use crate::planar;

fn all_faces(mesh: &TriMesh) -> Vec<u32> {
    (0..mesh.face_count() as u32).collect()
}

fn no_cut(mesh: &TriMesh) -> Vec<bool> {
    vec![false; mesh.edge_count()]
}

fn constant(mesh: &TriMesh, direction: [f64; 3], anisotropy: f64, density: f64) -> TensorField {
    FieldSpec::Constant {
        direction,
        anisotropy,
        density,
    }
    .build(mesh)
    .expect("constant field")
}

/// Major direction at angle `rate * x` in the xy plane, `sqrt(l1 / l2) = 3`, density 1.
fn turning(mesh: &TriMesh, rate: f64) -> TensorField {
    let directions: Vec<DVec3> = mesh
        .positions()
        .iter()
        .map(|p| DVec3::new((rate * p.x).cos(), (rate * p.x).sin(), 0.0))
        .collect();
    TensorField::from_frames(
        mesh,
        &directions,
        &vec![[3.0, 1.0 / 3.0]; mesh.vertex_count()],
    )
    .expect("field from frames")
}

fn run(mesh: &TriMesh, field: &TensorField, faces: &[u32], cut: &[bool]) -> SegmentParam {
    parameterize(mesh, field, faces, cut, &ParamOptions::default()).expect("parameterize")
}

/// Index of the mesh vertex at `p`.
fn vertex_at(mesh: &TriMesh, p: DVec3) -> u32 {
    mesh.positions()
        .iter()
        .position(|q| q.distance(p) < 1e-12)
        .expect("vertex at the position") as u32
}

/// Index of the mesh edge joining `a` and `b`.
fn edge_id(mesh: &TriMesh, a: u32, b: u32) -> usize {
    let key = [a.min(b), a.max(b)];
    mesh.edges()
        .iter()
        .position(|e| *e == key)
        .expect("edge between the vertices")
}

/// Largest distance between corresponding points relative to the largest coordinate.
fn relative_error(a: &[DVec2], b: &[DVec2]) -> f64 {
    let scale = b.iter().map(|p| p.abs().max_element()).fold(0.0, f64::max);
    a.iter()
        .zip(b)
        .map(|(p, q)| p.distance(*q))
        .fold(0.0, f64::max)
        / scale
}

fn copies(p: &SegmentParam, v: u32) -> Vec<usize> {
    (0..p.local_to_mesh.len())
        .filter(|&i| p.local_to_mesh[i] == v)
        .collect()
}

#[test]
fn constant_field_on_a_plane_is_the_linear_map() {
    let mesh = shapes::plane(1.0, 12).expect("plane");
    let a = 0.4f64;
    let field = constant(&mesh, [a.cos(), a.sin(), 0.0], 3.0, 2.0);
    let p = run(&mesh, &field, &all_faces(&mesh), &no_cut(&mesh));
    assert_eq!(p.uv.len(), mesh.vertex_count(), "no cut: no split vertex");
    assert_eq!(p.uv[0], DVec2::ZERO, "local vertex 0 is pinned");

    // anisotropy 3 and density 2: l1 = 6, l2 = 2/3.
    let (s1, s2) = (6f64.sqrt(), (2.0f64 / 3.0).sqrt());
    let m1 = DVec3::new(a.cos(), a.sin(), 0.0);
    let m2 = DVec3::Z.cross(m1);
    let x0 = mesh.positions()[p.local_to_mesh[0] as usize];
    let expected: Vec<DVec2> = p
        .local_to_mesh
        .iter()
        .map(|&v| {
            let d = mesh.positions()[v as usize] - x0;
            DVec2::new(s1 * m1.dot(d), s2 * m2.dot(d))
        })
        .collect();
    let flipped: Vec<DVec2> = expected.iter().map(|q| -*q).collect();
    let err = relative_error(&p.uv, &expected).min(relative_error(&p.uv, &flipped));
    assert!(err < 1e-6, "relative error {err}");

    // The same map as the planar sampler's single linear map, after scaling.
    let map = planar::planar_map(&mesh, &field).expect("planar map");
    let planar_uv: Vec<DVec2> = p
        .local_to_mesh
        .iter()
        .map(|&v| map.to_uv(mesh.positions()[v as usize]))
        .collect();
    let (unit, scale, offset) = p.to_unit_square();
    assert!(relative_error(&unit, &planar_uv) < 1e-9);
    assert!((scale - map.scale).abs() < 1e-9 * map.scale);
    for (q, r) in unit.iter().zip(&p.uv) {
        assert!((*r * scale + offset).distance(*q) < 1e-12);
    }
    // Corner densities as in planar.rs: density * surface area / unit-square area.
    let densities = p.corner_density(&mesh, &field, &unit);
    for ((t, &f), d) in p.triangles.iter().zip(&p.faces).zip(&densities) {
        let q = t.map(|v| planar_uv[v as usize]);
        let area_uv = 0.5 * (q[1] - q[0]).perp_dot(q[2] - q[0]);
        let want = 2.0 * mesh.face_areas()[f as usize] / area_uv;
        for c in d {
            assert!((c - want).abs() < 1e-6 * want, "{c} vs {want}");
        }
    }

    let r = p.report;
    assert!(r.valid && r.flipped == 0 && !r.overlaps, "{r:?}");
    assert!(r.mean_angle_deg < 1e-6 && r.max_angle_deg < 1e-6, "{r:?}");
    assert!(!r.isotropic_fallback && r.inconsistent_combing == 0);
    assert!((r.mean_anisotropy - 3.0).abs() < 1e-9);
}

/// The 10 x 10 plane with a slit of cut edges along y = 0.5 from the boundary x = 0
/// to x = 0.5, and the mesh vertices on the slit.
fn slit_plane() -> (TriMesh, Vec<bool>, Vec<u32>) {
    let mesh = shapes::plane(1.0, 10).expect("plane");
    let slit: Vec<u32> = (0..=5)
        .map(|i| vertex_at(&mesh, DVec3::new(0.1 * i as f64, 0.5, 0.0)))
        .collect();
    let mut cut = no_cut(&mesh);
    for w in slit.windows(2) {
        cut[edge_id(&mesh, w[0], w[1])] = true;
    }
    (mesh, cut, slit)
}

/// The largest number of `uv` triangles covering one point of a fine grid over the
/// domain (a brute-force overlap measure, independent of the exact test).
fn max_cover(p: &SegmentParam) -> usize {
    let (lo, hi) = p.uv.iter().fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(lo, hi), q| (lo.min(*q), hi.max(*q)),
    );
    let steps = 300;
    let mut worst = 0;
    for a in 0..steps {
        for b in 0..steps {
            let q = lo + (hi - lo) * DVec2::new(a as f64 + 0.37, b as f64 + 0.61) / steps as f64;
            let covering = p
                .triangles
                .iter()
                .filter(|t| {
                    let v = t.map(|i| p.uv[i as usize]);
                    (0..3).all(|k| (v[(k + 1) % 3] - v[k]).perp_dot(q - v[k]) > 0.0)
                })
                .count();
            worst = worst.max(covering);
        }
    }
    worst
}

/// Major direction +x, `sqrt(l1 / l2) = 3`, density growing (`up`) or falling along x.
fn density_ramp(mesh: &TriMesh, up: bool) -> TensorField {
    let eigenvalues: Vec<[f64; 2]> = mesh
        .positions()
        .iter()
        .map(|p| {
            let k = if up { 1.0 + 2.0 * p.x } else { 3.0 - 2.0 * p.x };
            [3.0 * k, k / 3.0]
        })
        .collect();
    TensorField::from_frames(mesh, &vec![DVec3::X; mesh.vertex_count()], &eigenvalues)
        .expect("field from frames")
}

#[test]
fn a_slit_opens_or_overlaps_and_the_report_says_which() {
    let (mesh, cut, slit) = slit_plane();
    let cases = [
        // Constant: both sides map onto each other (a closed seam, not an overlap).
        (
            "constant",
            constant(&mesh, [1.0, 0.3, 0.0], 3.0, 1.0),
            false,
        ),
        // Density growing along the slit: its sides move apart.
        ("ramp up", density_ramp(&mesh, true), false),
        // Falling density, or a turning field: the sides slide over each other.
        ("ramp down", density_ramp(&mesh, false), true),
        ("turning", turning(&mesh, 1.0), true),
    ];
    for (name, field, overlapping) in cases {
        let p = run(&mesh, &field, &all_faces(&mesh), &cut);
        // Every slit vertex but the tip has two copies, one per side.
        assert_eq!(p.uv.len(), mesh.vertex_count() + 5, "{name}");
        for &v in &slit[..5] {
            assert_eq!(copies(&p, v).len(), 2, "{name}");
        }
        assert_eq!(copies(&p, slit[5]).len(), 1, "{name}");
        // Each side of the slit has its own boundary edges.
        assert_eq!(p.boundary_edges().len(), 40 + 10, "{name}");
        let r = p.report;
        assert_eq!(r.flipped, 0, "{name}: {r:?}");
        assert_eq!(r.overlaps, overlapping, "{name}: {r:?}");
        assert_eq!(r.valid, !overlapping, "{name}: {r:?}");
        assert_eq!(max_cover(&p) > 1, overlapping, "{name}");
        let c = copies(&p, slit[2]);
        let gap = p.uv[c[0]].distance(p.uv[c[1]]);
        if name == "constant" {
            assert!(gap < 1e-12, "{name}: {gap}");
        } else {
            assert!(gap > 1e-3, "{name}: {gap}");
        }
    }
}

#[test]
fn a_cylinder_cut_along_its_axis_unrolls() {
    let n = 32;
    let mesh = shapes::cylinder(1.0, 2.0, n).expect("cylinder");
    let rows = mesh.vertex_count() as u32 / n - 1;
    // Vertex 0 of every ring zig-zags up one side (rings are staggered by half a step).
    let mut cut = no_cut(&mesh);
    for j in 0..rows {
        cut[edge_id(&mesh, j * n, (j + 1) * n)] = true;
    }
    let field = constant(&mesh, [0.0, 0.0, 1.0], 3.0, 2.0);
    let p = run(&mesh, &field, &all_faces(&mesh), &cut);
    assert_eq!(p.uv.len(), mesh.vertex_count() + rows as usize + 1);
    let r = p.report;
    assert!(r.valid && r.flipped == 0 && !r.overlaps, "{r:?}");
    assert!(r.mean_angle_deg < 0.5, "{r:?}");
    assert_eq!(r.inconsistent_combing, 0);
    // The unrolled rectangle: sqrt(l1) x height along u, sqrt(l2) x perimeter along v
    // (a little more: the cut zig-zags by half a step).
    let (lo, hi) = p.uv.iter().fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(lo, hi), q| (lo.min(*q), hi.max(*q)),
    );
    let perimeter = 2.0 * n as f64 * (std::f64::consts::PI / n as f64).sin();
    let extent = hi - lo;
    assert!(
        (extent.x / (6f64.sqrt() * 2.0) - 1.0).abs() < 0.01,
        "{extent}"
    );
    let around = extent.y / ((2.0f64 / 3.0).sqrt() * perimeter);
    assert!((1.0..1.03).contains(&around), "{extent}");
}

#[test]
fn isotropic_fields_use_the_fallback_frame() {
    // A hemisphere.
    let sphere = shapes::sphere(1.0, 8).expect("sphere");
    let cap: Vec<u32> = (0..sphere.face_count() as u32)
        .filter(|&f| sphere.face_positions(f).iter().map(|p| p.z).sum::<f64>() > 0.0)
        .collect();
    let field = constant(&sphere, [1.0, 0.0, 0.0], 1.0, 3.0);
    let p = run(&sphere, &field, &cap, &no_cut(&sphere));
    assert!(p.uv.iter().all(|q| q.is_finite()));
    let r = p.report;
    assert!(
        r.isotropic_fallback && r.valid && r.flipped == 0 && !r.overlaps,
        "{r:?}"
    );
    assert!(r.mean_angle_deg.is_finite() && r.max_angle_deg.is_finite());
    assert_eq!(r.inconsistent_combing, 0, "{r:?}");
    // A hemisphere cannot be flattened without stretch, but the fallback frame keeps
    // it mild; a bound under what it measures makes the same map invalid.
    assert!(r.mean_stretch > 1.0 + 1e-3 && r.mean_stretch < 1.5, "{r:?}");
    let strict = ParamOptions {
        max_stretch: 1.0,
        ..ParamOptions::default()
    };
    let p_strict =
        parameterize(&sphere, &field, &cap, &no_cut(&sphere), &strict).expect("hemisphere");
    assert!(!p_strict.report.valid, "{:?}", p_strict.report);
    assert_eq!(
        p_strict.uv, p.uv,
        "the bound changes the verdict, not the map"
    );
    println!("hemisphere: {r:?}");

    // On a plane the fallback frame is constant, so the map is a similarity with
    // scale sqrt(l) = sqrt(density).
    let plane = shapes::plane(1.0, 8).expect("plane");
    let field = constant(&plane, [0.0, 0.0, 1.0], 1.0, 2.0);
    let p = run(&plane, &field, &all_faces(&plane), &no_cut(&plane));
    let r = p.report;
    assert!(
        r.isotropic_fallback && r.valid && r.mean_angle_deg < 1e-6,
        "{r:?}"
    );
    assert!((r.mean_stretch - 1.0).abs() < 1e-9, "a similarity: {r:?}");
    for t in &p.triangles {
        for k in 0..3 {
            let (a, b) = (t[k] as usize, t[(k + 1) % 3] as usize);
            let x = |v: usize| plane.positions()[p.local_to_mesh[v] as usize];
            let (d3, d2) = (x(a).distance(x(b)), p.uv[a].distance(p.uv[b]));
            assert!((d2 / d3 - 2f64.sqrt()).abs() < 1e-9, "{d2} {d3}");
        }
    }
}

#[test]
fn stretch_is_the_aspect_ratio_in_the_fields_metric() {
    use super::validity::stretch;
    let (m1, m2) = (DVec3::X, DVec3::Y);
    // The target itself (gu = s1 m1, gv = s2 m2): no stretch, whatever s1 and s2.
    assert!((stretch(3.0 * m1, 0.5 * m2, m1, m2, 3.0, 0.5) - 1.0).abs() < 1e-12);
    // Twice the target along m1 only: 2; a rotation of the target: 1.
    assert!((stretch(6.0 * m1, 0.5 * m2, m1, m2, 3.0, 0.5) - 2.0).abs() < 1e-12);
    let (c, s) = (0.3f64.cos(), 0.3f64.sin());
    let rotated = stretch(c * m1 - s * m2, s * m1 + c * m2, m1, m2, 1.0, 1.0);
    assert!((rotated - 1.0).abs() < 1e-12, "{rotated}");
    // A shear [[1, 1], [0, 1]]: singular values golden ratio and its inverse.
    let golden = (1.0 + 5f64.sqrt()) / 2.0;
    let shear = stretch(m1 + m2, m2, m1, m2, 1.0, 1.0);
    assert!((shear - golden * golden).abs() < 1e-12, "{shear}");
    // Degenerate: capped, never infinite or NaN.
    assert_eq!(stretch(m1, m1, m1, m2, 1.0, 1.0), 1e3);
    assert_eq!(stretch(DVec3::ZERO, DVec3::ZERO, m1, m2, 1.0, 1.0), 1e3);
}

#[test]
fn a_turning_field_gives_small_nonzero_angles() {
    let mesh = shapes::plane(1.0, 32).expect("plane");
    let slow = run(
        &mesh,
        &turning(&mesh, 0.5),
        &all_faces(&mesh),
        &no_cut(&mesh),
    )
    .report;
    assert!(slow.valid && !slow.isotropic_fallback, "{slow:?}");
    assert_eq!(slow.inconsistent_combing, 0);
    assert!(
        slow.mean_angle_deg > 0.05 && slow.mean_angle_deg < 5.0,
        "{slow:?}"
    );
    assert!(slow.max_angle_deg >= slow.mean_angle_deg);
    // Turning three times faster misaligns more.
    let fast = run(
        &mesh,
        &turning(&mesh, 1.5),
        &all_faces(&mesh),
        &no_cut(&mesh),
    )
    .report;
    assert!(fast.mean_angle_deg > 2.0 * slow.mean_angle_deg, "{fast:?}");
}

#[test]
fn combing_reveals_a_singularity() {
    let mesh = shapes::plane(1.0, 16).expect("plane");
    // An index +1/2 wedge centred inside a face.
    let c = DVec3::new(0.53, 0.47, 0.0);
    let directions: Vec<DVec3> = mesh
        .positions()
        .iter()
        .map(|p| {
            let t = 0.5 * (p.y - c.y).atan2(p.x - c.x);
            DVec3::new(t.cos(), t.sin(), 0.0)
        })
        .collect();
    let field =
        TensorField::from_frames(&mesh, &directions, &vec![[4.0, 1.0]; mesh.vertex_count()])
            .expect("singular field");
    let r = run(&mesh, &field, &all_faces(&mesh), &no_cut(&mesh)).report;
    assert!(r.inconsistent_combing > 0, "{r:?}");
    assert!(!r.valid, "a singular segment cannot be aligned: {r:?}");
}

/// A band between radii 1 and 2 over the angles [0, sweep], `k` quads.
fn band(sweep: f64, k: u32) -> (Vec<DVec2>, Vec<[u32; 3]>) {
    let mut uv = Vec::new();
    for i in 0..=k {
        let a = sweep * i as f64 / k as f64;
        let d = DVec2::new(a.cos(), a.sin());
        uv.push(d);
        uv.push(d * 2.0);
    }
    let tris = (0..k)
        .flat_map(|i| {
            let (a, b, c, d) = (2 * i, 2 * i + 1, 2 * i + 3, 2 * i + 2);
            [[a, b, c], [a, c, d]]
        })
        .collect();
    (uv, tris)
}

#[test]
fn folds_and_flips_are_detected() {
    // A band winding more than once around has no flipped triangle but overlaps.
    let (uv, tris) = band(std::f64::consts::TAU + 1.0, 40);
    assert_eq!(count_flipped(&uv, &tris), 0);
    assert!(boundary_overlaps(&uv, &boundary_edges(&tris)));
    let (uv, tris) = band(std::f64::consts::TAU - 0.1, 40);
    assert_eq!(count_flipped(&uv, &tris), 0);
    assert!(!boundary_overlaps(&uv, &boundary_edges(&tris)));
    // Closing the band exactly: its two ends touch along a whole edge.
    let (mut uv, tris) = band(std::f64::consts::TAU, 40);
    let (first, last) = (uv.len() - 2, uv.len() - 1);
    uv[first] = uv[0];
    uv[last] = uv[1];
    assert!(boundary_overlaps(&uv, &boundary_edges(&tris)));

    // A solved plane with one boundary corner dragged across the domain.
    let mesh = shapes::plane(1.0, 6).expect("plane");
    let field = constant(&mesh, [1.0, 0.0, 0.0], 2.0, 1.0);
    let mut p = run(&mesh, &field, &all_faces(&mesh), &no_cut(&mesh));
    assert_eq!(count_flipped(&p.uv, &p.triangles), 0);
    assert!(!boundary_overlaps(&p.uv, &p.boundary_edges()));
    let corner = vertex_at(&mesh, DVec3::new(1.0, 1.0, 0.0)) as usize;
    let far = vertex_at(&mesh, DVec3::ZERO) as usize;
    p.uv[corner] = p.uv[far] - (p.uv[corner] - p.uv[far]) * 0.2;
    assert!(count_flipped(&p.uv, &p.triangles) >= 1);
    assert!(boundary_overlaps(&p.uv, &p.boundary_edges()));
    // A degenerate (zero-area) triangle counts as flipped.
    let uv = [DVec2::ZERO, DVec2::X, DVec2::new(2.0, 0.0)];
    assert_eq!(count_flipped(&uv, &[[0, 1, 2]]), 1);
}

#[test]
fn segments_that_are_not_discs_are_rejected() {
    let sphere = shapes::sphere(1.0, 4).expect("sphere");
    let field = constant(&sphere, [1.0, 0.0, 0.0], 2.0, 1.0);
    let options = ParamOptions::default();
    let err = parameterize(
        &sphere,
        &field,
        &all_faces(&sphere),
        &no_cut(&sphere),
        &options,
    );
    assert!(matches!(
        err,
        Err(ParamError::NotADisc {
            euler_characteristic: 2,
            boundary_loops: 0
        })
    ));

    let cylinder = shapes::cylinder(1.0, 1.0, 12).expect("cylinder");
    let field = constant(&cylinder, [0.0, 0.0, 1.0], 2.0, 1.0);
    let err = parameterize(
        &cylinder,
        &field,
        &all_faces(&cylinder),
        &no_cut(&cylinder),
        &options,
    );
    assert!(matches!(
        err,
        Err(ParamError::NotADisc {
            euler_characteristic: 0,
            boundary_loops: 2
        })
    ));

    // A slit inside the plane that does not reach its boundary makes a second loop.
    let (plane, _, _) = slit_plane();
    let field = constant(&plane, [1.0, 0.0, 0.0], 2.0, 1.0);
    let mut cut = no_cut(&plane);
    for i in 2..6 {
        let a = vertex_at(&plane, DVec3::new(0.1 * i as f64, 0.5, 0.0));
        let b = vertex_at(&plane, DVec3::new(0.1 * (i + 1) as f64, 0.5, 0.0));
        cut[edge_id(&plane, a, b)] = true;
    }
    let err = parameterize(&plane, &field, &all_faces(&plane), &cut, &options);
    assert!(matches!(
        err,
        Err(ParamError::NotADisc {
            euler_characteristic: 0,
            boundary_loops: 2
        })
    ));

    // Two faces that do not touch.
    let last = plane.face_count() as u32 - 1;
    let err = parameterize(&plane, &field, &[0, last], &no_cut(&plane), &options);
    assert!(matches!(
        err,
        Err(ParamError::Disconnected { components: 2 })
    ));
}

#[test]
fn bad_input_is_rejected() {
    let mesh = shapes::plane(1.0, 4).expect("plane");
    let field = constant(&mesh, [1.0, 0.0, 0.0], 2.0, 1.0);
    let cut = no_cut(&mesh);
    let o = ParamOptions::default();
    assert!(matches!(
        parameterize(&mesh, &field, &[], &cut, &o),
        Err(ParamError::EmptySegment)
    ));
    assert!(matches!(
        parameterize(&mesh, &field, &[0, 99], &cut, &o),
        Err(ParamError::FaceOutOfRange { face: 99, .. })
    ));
    assert!(matches!(
        parameterize(&mesh, &field, &[1, 2, 1], &cut, &o),
        Err(ParamError::DuplicateFace { face: 1 })
    ));
    assert!(matches!(
        parameterize(&mesh, &field, &[0], &cut[1..], &o),
        Err(ParamError::CutMaskLength { .. })
    ));
    for bad in [
        ParamOptions { gamma: 0.0, ..o },
        ParamOptions {
            gamma: f64::NAN,
            ..o
        },
        ParamOptions {
            isotropy_threshold: 0.9,
            ..o
        },
        ParamOptions {
            max_stretch: 0.5,
            ..o
        },
        ParamOptions {
            max_stretch: f64::NAN,
            ..o
        },
    ] {
        assert!(matches!(
            parameterize(&mesh, &field, &[0], &cut, &bad),
            Err(ParamError::InvalidOption { .. })
        ));
    }
    // A mesh wound inconsistently across one edge.
    let tris = vec![[0, 1, 2], [1, 3, 2], [2, 3, 4]];
    let mut tris_bad = tris.clone();
    tris_bad[2] = [2, 4, 3];
    let pos = vec![
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.0, 1.0, 0.0),
        DVec3::new(1.0, 1.0, 0.0),
        DVec3::new(0.5, 2.0, 0.0),
    ];
    let bad = TriMesh::new(pos, tris_bad).expect("mesh");
    let field = constant(&bad, [1.0, 0.0, 0.0], 2.0, 1.0);
    assert!(matches!(
        parameterize(&bad, &field, &[0, 1, 2], &no_cut(&bad), &o),
        Err(ParamError::InconsistentOrientation { .. })
    ));
}

#[test]
fn parameterize_all_is_deterministic_across_thread_counts() {
    let mesh = shapes::plane(1.0, 24).expect("plane");
    let field = turning(&mesh, 1.0);
    let mut segments = vec![Vec::new(); 4];
    for f in 0..mesh.face_count() as u32 {
        let c = mesh.face_positions(f).iter().sum::<DVec3>() / 3.0;
        segments[usize::from(c.x > 0.5) + 2 * usize::from(c.y > 0.5)].push(f);
    }
    segments.push(Vec::new());
    let cut = no_cut(&mesh);
    let options = ParamOptions::default();
    let run_with = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool")
            .install(|| parameterize_all(&mesh, &field, &segments, &cut, &options))
            .into_iter()
            .map(|r| r.map_err(|e| e.to_string()))
            .collect::<Vec<_>>()
    };
    let one = run_with(1);
    let two = run_with(2);
    assert_eq!(one, two);
    assert_eq!(one.len(), 5);
    assert!(
        one[..4]
            .iter()
            .all(|r| r.as_ref().is_ok_and(|p| p.report.valid))
    );
    assert!(one[4].is_err());
    // Same as one at a time.
    for (s, r) in segments.iter().zip(&one).take(4) {
        let single = parameterize(&mesh, &field, s, &cut, &options).expect("parameterize");
        assert_eq!(Ok(single), *r);
    }
}

#[test]
fn unit_square_and_corner_densities_feed_the_curve_stage() {
    use crate::curve::{CurveDomain, CurveOptions, SegmentCurve};
    let n = 24;
    let mesh = shapes::cylinder(1.0, 2.0, n).expect("cylinder");
    let rows = mesh.vertex_count() as u32 / n - 1;
    let mut cut = no_cut(&mesh);
    for j in 0..rows {
        cut[edge_id(&mesh, j * n, (j + 1) * n)] = true;
    }
    let field = constant(&mesh, [0.0, 0.0, 1.0], 3.0, 2.0);
    let p = run(&mesh, &field, &all_faces(&mesh), &cut);
    let (unit, _, _) = p.to_unit_square();
    let density = p.corner_density(&mesh, &field, &unit);
    let curve = SegmentCurve::build(
        &CurveDomain {
            uv: &unit,
            triangles: &p.triangles,
            corner_density: &density,
        },
        &CurveOptions {
            max_cell_share: 1.0 / 1024.0,
            ..CurveOptions::default()
        },
    )
    .expect("cells");
    // The cells' measure is the surface integral of the density: 2 x area.
    let want = 2.0 * mesh.area();
    assert!(
        (curve.measure() / want - 1.0).abs() < 1e-9,
        "{}",
        curve.measure()
    );
}

/// Timing of one large disc: `cargo test --release -p strata-engine large_plane_timing
/// -- --ignored --nocapture`.
#[test]
#[ignore]
fn large_plane_timing() {
    use faer::Side;
    use faer::prelude::*;
    use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};

    let mesh = shapes::plane(1.0, 200).expect("plane");
    let isotropic = constant(&mesh, [1.0, 0.0, 0.0], 1.0, 1.0);
    let t = Instant::now();
    let r = run(&mesh, &isotropic, &all_faces(&mesh), &no_cut(&mesh)).report;
    println!("isotropic fallback: total {:?} {r:?}", t.elapsed());
    let field = turning(&mesh, 1.0);
    let faces = all_faces(&mesh);
    let cut = no_cut(&mesh);
    let options = ParamOptions::default();
    let t = Instant::now();
    let p = parameterize(&mesh, &field, &faces, &cut, &options).expect("parameterize");
    let total = t.elapsed();

    let t = Instant::now();
    let patch = patch::Patch::build(&mesh, &faces, &cut).expect("patch");
    let t_patch = t.elapsed();
    let t = Instant::now();
    let frames = frames_of(&mesh, &field, &patch, &options);
    let t_frames = t.elapsed();
    let t = Instant::now();
    let (matrix, mut rhs) = solve::assemble(&mesh, &patch, &frames).expect("assembly");
    let t_assemble = t.elapsed();
    let t = Instant::now();
    let symbolic =
        SymbolicLlt::try_new(matrix.symbolic(), Side::Lower).expect("symbolic factorization");
    let t_symbolic = t.elapsed();
    let t = Instant::now();
    let llt = Llt::try_new_with_symbolic(symbolic, matrix.as_ref(), Side::Lower)
        .expect("numeric factorization");
    let t_numeric = t.elapsed();
    let t = Instant::now();
    llt.solve_in_place(rhs.as_mut());
    let t_solve = t.elapsed();
    let uv = solve::solve(&mesh, &patch, &frames).expect("solve");
    let t = Instant::now();
    let report = validity::report(&mesh, &patch, &frames, &uv, &options);
    let t_report = t.elapsed();
    assert_eq!(report, p.report);
    println!(
        "faces {} unknowns {} nnz(lower K) {}\n\
         total {total:?}: patch {t_patch:?}, frames {t_frames:?}, assembly {t_assemble:?}, \
         symbolic {t_symbolic:?}, numeric {t_numeric:?}, solve (2 rhs) {t_solve:?}, \
         validity {t_report:?}\n{report:?}",
        faces.len(),
        rhs.nrows(),
        matrix.compute_nnz(),
    );
}

/// The combed frames of `patch` for `field`.
fn frames_of(
    mesh: &TriMesh,
    field: &TensorField,
    patch: &patch::Patch,
    options: &ParamOptions,
) -> comb::Frames {
    let eigen = patch
        .faces
        .iter()
        .map(|&f| comb::face_eigen(mesh, field, f))
        .collect();
    comb::frames(mesh, eigen, patch, options).expect("frames")
}

/// The solved map of the `n` x `n` unit plane with a constant 2:1 field, its patch and
/// frames, for the repair tests.
fn plane_map(
    n: u32,
) -> (
    TriMesh,
    patch::Patch,
    comb::Frames,
    Vec<DVec2>,
    ParamOptions,
) {
    let mesh = shapes::plane(1.0, n).expect("plane");
    let field = constant(&mesh, [1.0, 0.0, 0.0], 2.0, 1.0);
    let options = ParamOptions::default();
    let faces = all_faces(&mesh);
    let patch = patch::Patch::build(&mesh, &faces, &no_cut(&mesh)).expect("patch");
    let frames = frames_of(&mesh, &field, &patch, &options);
    let uv = solve::solve(&mesh, &patch, &frames).expect("solve");
    (mesh, patch, frames, uv, options)
}

#[test]
fn defects_are_the_corners_of_flips_and_the_vertices_that_turn_more_than_once() {
    let (mesh, patch, _, mut uv, _) = plane_map(8);
    assert!(!untangle::defects(&uv, &patch.triangles).contains(&true));
    // Push the middle of the bottom edge up past the next row: its triangles flip.
    let v = vertex_at(&mesh, DVec3::new(0.5, 0.0, 0.0)) as usize;
    let above = vertex_at(&mesh, DVec3::new(0.5, 0.25, 0.0)) as usize;
    uv[v] = uv[above] + (uv[above] - uv[v]) * 0.5;
    let bad = untangle::defects(&uv, &patch.triangles);
    assert!(bad[v]);
    assert!(count_flipped(&uv, &patch.triangles) > 0);
    // Every flagged vertex is a corner of a flipped triangle or turns more than once.
    let flipped_corners: Vec<bool> = {
        let mut c = vec![false; uv.len()];
        for t in &patch.triangles {
            if count_flipped(&uv, &[*t]) == 1 {
                for &k in t {
                    c[k as usize] = true;
                }
            }
        }
        c
    };
    for (i, &b) in bad.iter().enumerate() {
        if b && !flipped_corners[i] {
            let turn: f64 = patch
                .triangles
                .iter()
                .filter(|t| t.contains(&(i as u32)))
                .map(|t| {
                    let k = t.iter().position(|&c| c as usize == i).expect("corner");
                    let (a, b) = (
                        uv[t[(k + 1) % 3] as usize] - uv[i],
                        uv[t[(k + 2) % 3] as usize] - uv[i],
                    );
                    a.perp_dot(b).atan2(a.dot(b))
                })
                .sum();
            assert!(turn > std::f64::consts::TAU, "vertex {i} turns {turn}");
        }
    }
}

#[test]
fn a_local_fold_is_relaxed_and_the_rest_of_the_map_stays() {
    let n = 16;
    let (mesh, patch, frames, solved, options) = plane_map(n);
    let mut uv = solved.clone();
    let edge = 1.0 / f64::from(n);
    let v = vertex_at(&mesh, DVec3::new(0.5, 0.0, 0.0)) as usize;
    let above = vertex_at(&mesh, DVec3::new(0.5, 2.0 * edge, 0.0)) as usize;
    uv[v] = uv[above] + (uv[above] - uv[v]) * 0.5;
    assert!(!validity::report(&mesh, &patch, &frames, &uv, &options).valid);
    let (fixed, report) =
        untangle::repair(&mesh, &patch, &frames, &uv, &options).expect("a local fold repairs");
    assert!(report.valid, "{report:?}");
    assert_eq!(report, {
        let mut r = validity::report(&mesh, &patch, &frames, &fixed, &options);
        r.relaxed_vertices = report.relaxed_vertices;
        r
    });
    assert!(report.relaxed_vertices > 0);
    // The region is the defects (within two rings of the pushed vertex) grown by a
    // ring per round: vertices farther than that (diagonal edges) keep their place.
    let reach = (untangle::ROUNDS + 3) as f64 * edge * std::f64::consts::SQRT_2;
    let centre = DVec3::new(0.5, 0.0, 0.0);
    let mut far = 0;
    for (i, (&p, &q)) in fixed.iter().zip(&uv).enumerate() {
        let at = mesh.positions()[patch.local_to_mesh[i] as usize];
        if at.distance(centre) > reach {
            far += 1;
            assert_eq!(p, q, "vertex {i} at {at} moved");
        }
    }
    assert!(far > uv.len() / 3, "{far} of {} vertices checked", uv.len());
}

#[test]
fn a_map_that_winds_over_itself_is_not_repaired() {
    let (mesh, patch, frames, _, options) = plane_map(8);
    // The plane wound onto a band through more than a full turn: a global overlap.
    let uv: Vec<DVec2> = patch
        .local_to_mesh
        .iter()
        .map(|&m| {
            let p = mesh.positions()[m as usize];
            let angle = (std::f64::consts::TAU + 1.5) * p.x;
            DVec2::new(angle.cos(), angle.sin()) * (2.0 - p.y)
        })
        .collect();
    let report = validity::report(&mesh, &patch, &frames, &uv, &options);
    assert_eq!(
        report.flipped, 0,
        "counter-clockwise: only the overlap is wrong"
    );
    assert!(report.overlaps);
    assert!(untangle::repair(&mesh, &patch, &frames, &uv, &options).is_none());
}

#[test]
fn stiffness_fills_its_pattern_as_a_dense_sum_of_the_faces_would() {
    // A plane slit from its left side to its middle: the slit's vertices are copied in
    // the patch, so the patch's sides are not the mesh's edges.
    let mesh = shapes::plane(1.0, 8).expect("plane");
    let pos = mesh.positions();
    let cut: Vec<bool> = mesh
        .edges()
        .iter()
        .map(|&[a, b]| {
            let (p, q) = (pos[a as usize], pos[b as usize]);
            (p.y - 0.5).abs() < 1e-9 && (q.y - 0.5).abs() < 1e-9 && p.x.max(q.x) <= 0.5 + 1e-9
        })
        .collect();
    assert_eq!(cut.iter().filter(|&&c| c).count(), 4);
    let field = turning(&mesh, 0.5);
    let patch = patch::Patch::build(&mesh, &all_faces(&mesh), &cut).expect("patch");
    assert_eq!(patch.local_to_mesh.len(), mesh.vertex_count() + 4);
    let frames = frames_of(&mesh, &field, &patch, &ParamOptions::default());
    let (matrix, _) = solve::assemble(&mesh, &patch, &frames).expect("assembly");
    // The reference: every face's terms summed into a dense matrix, in face order.
    let n = patch.local_to_mesh.len() - 1;
    let mut dense = vec![vec![0.0; n]; n];
    let mut coupled = vec![vec![false; n]; n];
    for (&f, t) in patch.faces.iter().zip(&patch.triangles) {
        let (normal, area) = (
            mesh.face_normals()[f as usize],
            mesh.face_areas()[f as usize],
        );
        let grads = solve::hat_gradients(mesh.face_positions(f), normal, area);
        for a in 0..3 {
            for b in 0..3 {
                if let (Some(r), Some(c)) = (
                    (t[a] as usize).checked_sub(1),
                    (t[b] as usize).checked_sub(1),
                ) && r >= c
                {
                    dense[r][c] += area * grads[a].dot(grads[b]);
                    coupled[r][c] = true;
                }
            }
        }
    }
    let symbolic = matrix.symbolic();
    let mut entries = 0;
    for c in 0..n {
        let rows = symbolic.row_idx_of_col_raw(c);
        let values = matrix.val_of_col(c);
        assert_eq!(rows[0], c, "column {c} starts at its diagonal");
        assert!(rows.windows(2).all(|w| w[0] < w[1]), "column {c}: {rows:?}");
        for (&r, &v) in rows.iter().zip(values) {
            assert!(coupled[r][c], "({r}, {c}) shares no face");
            assert_eq!(v, dense[r][c], "({r}, {c})");
        }
        entries += rows.len();
    }
    let want: usize = coupled.iter().flatten().filter(|&&c| c).count();
    assert_eq!(entries, want, "every coupled pair once");
}
