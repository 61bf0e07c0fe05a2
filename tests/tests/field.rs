//! `strata field` end to end, as a user runs it (in process, like the other CLI tests):
//! a designed field on a built-in sphere, its singularities, the PLY and the JSON.

use clap::Parser;
use strata_systems::cli::{Cli, one_line, run};
use strata_systems::config::SceneConfig;
use strata_systems::report::field::{FIELD_VERTEX_PROPERTIES, FieldReport};

fn strata(args: &[&str]) -> anyhow::Result<()> {
    let mut argv = vec!["strata"];
    argv.extend_from_slice(args);
    run(Cli::try_parse_from(argv)?)
}

const SPHERE: &str =
    "(mesh: Shape(Sphere(radius: 1.0, resolution: 8)), field: Designed(guidance: Smoothest))";

/// The smoothest line field on a sphere has singularities whose indices sum to 2, the
/// sphere's Euler characteristic; the PLY reads back as the same mesh with the field's
/// properties, and the JSON holds the singularities with their face barycentres.
#[test]
fn field_command_reports_a_designed_sphere_field() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = dir.path().join("sphere.ron");
    std::fs::write(&scene, SPHERE).expect("write scene");
    let ply = dir.path().join("field.ply");
    let json = dir.path().join("field.json");
    let path = |p: &std::path::Path| p.to_str().expect("utf-8").to_owned();
    strata(&[
        "field",
        &path(&scene),
        "--out",
        &path(&ply),
        "--report",
        &path(&json),
    ])
    .expect("strata field");

    // The JSON report.
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).expect("json")).expect("parses");
    let mesh = strata_engine::mesh::shapes::sphere(1.0, 8).expect("sphere");
    assert_eq!(report["faces"], mesh.face_count());
    assert_eq!(report["vertices"], mesh.vertex_count());
    assert_eq!(report["euler_characteristic"], 2);
    assert_eq!(report["boundary_loops"], 0);
    assert_eq!(report["index_sum"], 2.0);
    assert!(report["field_s"].as_f64().is_some_and(|t| t >= 0.0));
    let singularities = report["singularities"].as_array().expect("list");
    assert!(!singularities.is_empty());
    let mut sum = 0.0;
    for s in singularities {
        let index = s["index"].as_f64().expect("index");
        assert!(index == 0.5 || index == -0.5, "{s}");
        sum += index;
        let p: Vec<f64> = s["position"]
            .as_array()
            .expect("position")
            .iter()
            .map(|x| x.as_f64().expect("number"))
            .collect();
        let r = p.iter().map(|x| x * x).sum::<f64>().sqrt();
        assert!(p.len() == 3 && r > 0.9 && r < 1.0, "{s}");
        assert!(
            s["face"]
                .as_u64()
                .is_some_and(|f| f < mesh.face_count() as u64)
        );
    }
    assert_eq!(sum, 2.0);

    // The line the command prints is the report's summary: index sum 2, checked.
    let config = SceneConfig::load(&scene).expect("scene");
    let field = config.field.build(&mesh).expect("field");
    let found = strata_engine::segment::detect_singularities(&mesh, &field);
    let line = FieldReport::new(&mesh, &field, &found, 1.05, 0.0).summary();
    assert!(
        line.contains("index sum 2 = Euler characteristic (Poincare-Hopf holds)"),
        "{line}"
    );
    assert_eq!(found.len(), singularities.len());

    // The PLY: a mesh reader sees the sphere; the header names the field's properties.
    let back = strata_engine::io::load_ply(&ply).expect("PLY parses");
    assert_eq!(back.vertex_count(), mesh.vertex_count());
    assert_eq!(back.face_count(), mesh.face_count());
    let bytes = std::fs::read(&ply).expect("read PLY");
    let end = bytes
        .windows(11)
        .position(|w| w == b"end_header\n")
        .expect("header");
    let header = std::str::from_utf8(&bytes[..end]).expect("ASCII");
    assert!(header.starts_with("ply\nformat binary_little_endian 1.0\n"));
    for name in FIELD_VERTEX_PROPERTIES {
        assert!(
            header.contains(&format!("property float {name}\n")),
            "{name}"
        );
    }
    assert!(header.contains("property float singularity\n"));
    assert_eq!(
        bytes.len() - end - 11,
        mesh.vertex_count() * 44 + mesh.face_count() * 17
    );
}

#[test]
fn field_command_errors_are_one_line() {
    let dir = tempfile::tempdir().expect("tempdir");
    let bad = dir.path().join("bad.ron");
    std::fs::write(
        &bad,
        "(\n  mesh: Shape(Sphere()),\n  field: Designed(guidance: Smoothes),\n)",
    )
    .expect("write");
    let e = strata(&["field", bad.to_str().expect("utf-8")]).expect_err("bad guidance");
    let line = one_line(&e);
    assert!(
        line.contains("bad.ron:3:") && line.contains("Smoothes") && !line.contains('\n'),
        "{line}"
    );

    let missing = dir.path().join("missing.ron");
    std::fs::write(&missing, "(mesh: File(\"nowhere.obj\"))").expect("write");
    let e = strata(&["field", missing.to_str().expect("utf-8")]).expect_err("missing mesh");
    let line = one_line(&e);
    assert!(
        line.contains("missing.ron") && line.contains("nowhere.obj") && !line.contains('\n'),
        "{line}"
    );

    let good = dir.path().join("good.ron");
    std::fs::write(&good, SPHERE).expect("write");
    let out = dir.path().join("no-such-folder/field.ply");
    let e = strata(&[
        "field",
        good.to_str().expect("utf-8"),
        "--out",
        out.to_str().expect("utf-8"),
    ])
    .expect_err("unwritable output");
    let line = one_line(&e);
    assert!(
        line.starts_with(&format!(
            "{}: --out (a PLY mesh): the folder ",
            out.display()
        )) && line.ends_with("no-such-folder does not exist")
            && !line.contains('\n'),
        "{line}"
    );
}
