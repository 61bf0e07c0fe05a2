//! The reliability of the `strata` commands on real-world input: every case a user met
//! on scans and flags ends in a sample file or in one clear line (the table below),
//! and a corpus of messy scans made in code runs every field kind through
//! `strata sample`, each ending in finite samples or a clear error.

use std::path::Path;

use clap::Parser;
use strata_engine::fixtures::messy::messy_scans;
use strata_engine::sample::Sample;
use strata_systems::cli::{Cli, one_line, run};
use strata_systems::config::SceneConfig;

use crate::hostile::{QUAD, SPHERE, case, check, scene};

/// A triangle with corners at 0 and `s` on two axes, as OBJ text.
fn triangle(s: &str) -> String {
    format!("v 0 0 0\nv {s} 0 0\nv 0 {s} 0\nf 1 2 3\n")
}

#[test]
fn every_reliability_case_ends_in_its_clear_error() {
    let with_mesh = |obj: String| vec![("m.obj", obj), ("scene.ron", scene("File(\"m.obj\")", ""))];
    let sphere = || vec![("scene.ron", scene(SPHERE, ""))];
    let sample = &["sample", "{dir}/scene.ron", "-o", "{dir}/s.ply"] as &'static [&'static str];
    let cases = vec![
        case(
            "coordinates at 1e45 (inf samples were written)",
            with_mesh(triangle("1e45")),
            sample,
            Some(&["m.obj: placed coordinates reach 1.000e45", "scale the mesh down"]),
        ),
        case(
            "coordinates at 1e39, beyond f32",
            with_mesh(triangle("1e39")),
            sample,
            Some(&["placed coordinates reach 1.000e39", "32-bit"]),
        ),
        case(
            "a mesh of extent 1e-45 (zero spacings were written)",
            with_mesh(triangle("1e-45")),
            sample,
            Some(&["m.obj: the placed mesh spans only 1.414e-45", "scale the mesh up"]),
        ),
        case(
            "a transform that places a unit mesh at 1e40",
            vec![
                ("m.obj", QUAD.to_owned()),
                ("scene.ron", scene("File(\"m.obj\")", "    transform: (scale: 1e40),\n")),
            ],
            sample,
            Some(&["placed coordinates reach 1.000e40"]),
        ),
        case(
            "a mesh whose only face has two corners",
            with_mesh("v 0 0 0\nv 1 0 0\nf 1 2\n".to_owned()),
            sample,
            Some(&["m.obj:3: no usable face", "fewer than 3 corners"]),
        ),
        case(
            "a folder as the mesh",
            vec![("scene.ron", scene("File(\".\")", ""))],
            sample,
            Some(&["is a folder, not a mesh file", ".obj or .ply"]),
        ),
        case(
            "a mesh path without an extension",
            vec![
                ("mesh", QUAD.to_owned()),
                ("scene.ron", scene("File(\"mesh\")", "")),
            ],
            sample,
            Some(&["mesh: has no extension", ".obj or .ply"]),
        ),
        case(
            "field --out with another extension",
            sphere(),
            &["field", "{dir}/scene.ron", "-o", "{dir}/f.txt"],
            Some(&["f.txt: --out (a PLY mesh) writes .ply"]),
        ),
        case(
            "field --report not JSON",
            sphere(),
            &["field", "{dir}/scene.ron", "--report", "{dir}/f.ply"],
            Some(&["f.ply: --report (JSON) writes .json"]),
        ),
        case(
            "render --out not PNG (refused before opening a GPU)",
            sphere(),
            &["render", "{dir}/scene.ron", "-o", "{dir}/r.jpg"],
            Some(&["r.jpg: --out (PNG) writes .png"]),
        ),
        case(
            "watch --out not PLY",
            sphere(),
            &["watch", "{dir}/scene.ron", "-o", "{dir}/w.csv", "--updates", "1"],
            Some(&["w.csv: --out (binary PLY samples) writes .ply"]),
        ),
        case(
            "bench --json not JSON",
            sphere(),
            &["bench", "{dir}/scene.ron", "--json", "{dir}/b.txt"],
            Some(&["b.txt: --json writes .json"]),
        ),
        case(
            "segment --atlas not SVG",
            sphere(),
            &["segment", "{dir}/scene.ron", "--atlas", "{dir}/a.png"],
            Some(&["a.png: --atlas (SVG) writes .svg"]),
        ),
        // The output is checked before the mesh is read: the broken mesh is not reached.
        case(
            "an output folder that does not exist, before any loading",
            with_mesh("v 0 0 0\nv 1 0 0\nf 1 2\n".to_owned()),
            &["sample", "{dir}/scene.ron", "-o", "{dir}/missing/s.ply"],
            Some(&["s.ply: --out: the folder ", "missing does not exist"]),
        ),
        case(
            "an output that is a folder",
            sphere(),
            &["field", "{dir}/scene.ron", "--report", "{dir}"],
            Some(&["--report (JSON) writes .json"]),
        ),
        case(
            "analyze --out naming a file",
            vec![
                ("scene.ron", scene(SPHERE, "")),
                ("taken.json", String::new()),
            ],
            &["analyze", "{dir}/scene.ron", "-o", "{dir}/taken.json"],
            Some(&["taken.json: --out names a file; give a folder"]),
        ),
        case(
            "a designed-field constraint along the vertex normal",
            vec![(
                "scene.ron",
                scene("Shape(Plane(size: 1.0, resolution: 4))", "").replace(
                    "Constant(direction: (1.0, 0.0, 0.0), anisotropy: 2.0, density: 1.0)",
                    "Designed(guidance: Smoothest, constraints: [(at: Vertex(3), direction: (0.0, 0.01, 1.0))])",
                ),
            )],
            &["field", "{dir}/scene.ron"],
            Some(&[
                "constraint 0 at vertex 3",
                "within 1 degree of the surface normal",
            ]),
        ),
    ];
    for c in &cases {
        check(c);
    }
}

/// Command-line values that clap refuses, each with its reason.
#[test]
fn bad_flag_values_say_what_they_must_be() {
    for (args, want) in [
        (
            &["render", "s.ron", "-o", "r.png", "--width", "0"][..],
            "'--width <WIDTH>': must be at least 1 pixel",
        ),
        (
            &["view", "s.ron", "--height", "0"][..],
            "'--height <HEIGHT>': must be at least 1 pixel",
        ),
        (
            &["sample", "s.ron", "--threads", "99999999999999999999999"][..],
            "'--threads <THREADS>': give a count from 1 to 1024",
        ),
        (
            &["sample", "s.ron", "--threads", "0"][..],
            "give a count from 1 to 1024",
        ),
    ] {
        let argv = std::iter::once("strata").chain(args.iter().copied());
        let e = Cli::try_parse_from(argv).expect_err(want);
        assert!(e.to_string().contains(want), "{args:?}: {e}");
    }
}

#[test]
fn help_opens_with_what_strata_does() {
    let e = Cli::try_parse_from(["strata", "--help"]).expect_err("help");
    let help = e.to_string();
    assert!(
        help.starts_with("strata: anisotropic, density-controlled stratified sampling"),
        "{help}"
    );
    assert!(!help.contains("later the ECS"), "{help}");
}

#[test]
fn vectors_in_designed_fields_take_both_spellings() {
    let parse = |guidance: &str, site: &str| {
        let text = format!(
            "(mesh: Shape(Plane()), field: Designed(guidance: {guidance}, constraints: [(at: {site}, direction: (1.0, 0.0, 0.0))]))"
        );
        SceneConfig::from_ron(&text, Path::new("d.ron"))
            .unwrap_or_else(|e| panic!("{guidance} {site}: {e}"))
            .field
    };
    let flat = parse("Direction(0.0, 1.0, 0.5)", "Point(0.5, 0.5, 0.0)");
    assert_eq!(
        flat,
        parse("Direction((0.0, 1.0, 0.5))", "Point((0.5, 0.5, 0.0))")
    );
    assert_eq!(flat, parse("Direction(0, 1, 0.5)", "Point((0.5, 0.5, 0))"));
    assert_ne!(
        flat,
        parse("Direction(0.0, 1.0, 0.25)", "Point(0.5, 0.5, 0.0)")
    );
    for bad in [
        "Direction(0.0, 1.0)",
        "Direction((0.0, 1.0, 0.0), 2.0)",
        "Direction((0.0, 1.0))",
    ] {
        let text = format!("(mesh: Shape(Plane()), field: Designed(guidance: {bad}))");
        let e = SceneConfig::from_ron(&text, Path::new("d.ron")).expect_err(bad);
        assert!(e.to_string().starts_with("d.ron:1:"), "{bad}: {e}");
    }
}

#[test]
fn samples_files_never_hold_non_finite_values() {
    let mut s = Sample {
        position: [1.0, f32::INFINITY, 0.0],
        ..Sample::default()
    };
    let mut bytes = Vec::new();
    let e = strata_engine::io::write_samples_ply_to(&mut bytes, &[s]).expect_err("inf");
    assert!(e.to_string().contains("non-finite"), "{e}");
    s.position = [0.0; 3];
    s.spacing = [f32::NAN, 1.0];
    let e = strata_engine::io::write_samples_csv_to(&mut bytes, &[s]).expect_err("nan");
    assert!(e.to_string().contains("non-finite"), "{e}");
}

/// Every field kind, on the messy-scan corpus.
const FIELDS: &[(&str, &str)] = &[
    (
        "constant",
        "Constant(direction: (1.0, 0.3, 0.2), anisotropy: 3.0, density: 1.0)",
    ),
    (
        "isotropic",
        "Constant(direction: (1.0, 0.0, 0.0), anisotropy: 1.0, density: 1.0)",
    ),
    ("curvature", "Curvature(max_anisotropy: 3.0)"),
    ("designed smoothest", "Designed(guidance: Smoothest)"),
    ("designed curvature", "Designed(guidance: Curvature())"),
    (
        "designed direction",
        "Designed(guidance: Direction(1.0, 0.0, 0.0))",
    ),
    (
        "designed with a constraint",
        "Designed(guidance: Smoothest, constraints: [(at: Vertex(0), direction: (1.0, 1.0, 0.0))])",
    ),
];

/// What a corpus case ended in: finite samples, or the error line.
fn sample_corpus_case(dir: &Path, obj: &str, field: &str) -> Result<(), String> {
    std::fs::write(dir.join("m.obj"), obj).map_err(|e| e.to_string())?;
    let text = format!("(mesh: File(\"m.obj\"), field: {field}, sampling: (count: 300, seed: 3))");
    std::fs::write(dir.join("scene.ron"), text).map_err(|e| e.to_string())?;
    let out = dir.join("s.ply");
    let _ = std::fs::remove_file(&out);
    let argv = ["strata", "sample", "", "-o", ""];
    let mut argv = argv.map(std::ffi::OsString::from);
    argv[2] = dir.join("scene.ron").into();
    argv[4] = out.clone().into();
    let cli = Cli::try_parse_from(argv).map_err(|e| e.to_string())?;
    run(cli).map_err(|e| one_line(&e))?;
    let samples = strata_engine::io::read_samples_ply(&out).map_err(|e| e.to_string())?;
    assert_eq!(samples.len(), 300);
    for s in &samples {
        let values = s.position.iter().chain(&s.spacing);
        assert!(values.clone().all(|v| v.is_finite()), "{s:?}");
    }
    Ok(())
}

#[test]
fn messy_scans_end_in_samples_or_a_clear_error_for_every_field() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mut failed = Vec::new();
    let mut runs = 0;
    for (name, obj) in messy_scans() {
        for (kind, field) in FIELDS {
            let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                sample_corpus_case(dir.path(), &obj, field)
            }));
            runs += 1;
            match outcome {
                Ok(Ok(())) => {}
                Ok(Err(line)) => {
                    assert!(!line.contains('\n'), "{name}, {kind}: {line}");
                    assert!(line.contains("scene.ron"), "{name}, {kind}: {line}");
                    failed.push(format!("{name}, {kind}: {line}"));
                }
                Err(_) => panic!("{name}, {kind}: panicked"),
            }
        }
    }
    // The combinations that end in an error (printed for the record: designed fields
    // on some messy meshes are refused by the solver with a clear error for now).
    for f in &failed {
        eprintln!("messy corpus: {f}");
    }
    assert_eq!(runs, 6 * FIELDS.len());
    // The plain fields always sample.
    assert!(failed.iter().all(|f| f.contains("designed")), "{failed:#?}");
}

/// Runs `strata args...` in process (`{dir}` stands for `dir`).
fn strata_in(dir: &Path, args: &[&str]) -> anyhow::Result<()> {
    let folder = dir.to_str().expect("utf-8 temp path");
    let argv =
        std::iter::once("strata".to_owned()).chain(args.iter().map(|a| a.replace("{dir}", folder)));
    run(Cli::try_parse_from(argv)?)
}

/// The mesh flags that `strata sample <mesh>` and `strata scene <mesh>` share, each
/// with an effect on the samples.
const MESH_FLAGS: &[&[&str]] = &[
    &[],
    &["--field", "smooth"],
    &["--field", "curvature", "--anisotropy", "2"],
    &["--field", "direction:0,1,0", "--anisotropy", "4"],
    &["--anisotropy", "2"],
    &["--density-from", "{dir}/density.field"],
];

#[test]
fn a_mesh_is_a_scene_and_strata_scene_writes_the_same_one() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    let mesh = strata_engine::mesh::shapes::sphere(1.0, 4).expect("sphere");
    strata_engine::io::write_mesh_ply(&d.join("m.ply"), &mesh, None).expect("write mesh");
    // Density 4 on the upper half, 1 below (l1 = l2 = density).
    let mut field = String::from("strata-field 1\n");
    for p in mesh.positions() {
        let v = if p.y > 0.0 { 4.0 } else { 1.0 };
        field.push_str(&format!("{v} {v} 1 0 0\n"));
    }
    std::fs::write(d.join("density.field"), field).expect("write field");
    let mut files: Vec<Vec<u8>> = Vec::new();
    for (i, flags) in MESH_FLAGS.iter().enumerate() {
        let out = format!("{{dir}}/mesh{i}.ply");
        let mut args = vec![
            "sample",
            "{dir}/m.ply",
            "-n",
            "400",
            "--seed",
            "5",
            "-o",
            &out,
        ];
        args.extend_from_slice(flags);
        strata_in(d, &args).unwrap_or_else(|e| panic!("{flags:?}: {}", one_line(&e)));
        // The scene `strata scene` prints for the same flags, run as a scene file from
        // another folder, gives the same bytes.
        let folder = d.to_str().expect("utf-8");
        let mut scene_args = vec![
            "strata".to_owned(),
            "scene".into(),
            format!("{folder}/m.ply"),
        ];
        scene_args.extend(flags.iter().map(|f| f.replace("{dir}", folder)));
        let Ok(strata_systems::cli::Cli {
            command: strata_systems::cli::Command::Scene(scene),
        }) = Cli::try_parse_from(&scene_args)
        else {
            panic!("{scene_args:?} parses as strata scene");
        };
        let config = scene.input.scene_for_mesh(&scene.mesh).expect("scene");
        let text = strata_systems::cli::scene_ron(&config).expect("ron");
        std::fs::create_dir_all(d.join("elsewhere")).expect("mkdir");
        std::fs::write(d.join("elsewhere/scene.ron"), &text).expect("write scene");
        let again = format!("{{dir}}/again{i}.ply");
        strata_in(
            d,
            &[
                "sample",
                "{dir}/elsewhere/scene.ron",
                "-n",
                "400",
                "--seed",
                "5",
                "-o",
                &again,
            ],
        )
        .unwrap_or_else(|e| panic!("{flags:?}: {}\n{text}", one_line(&e)));
        let bytes = std::fs::read(d.join(format!("mesh{i}.ply"))).expect("read");
        assert!(
            bytes == std::fs::read(d.join(format!("again{i}.ply"))).expect("read"),
            "{flags:?}: the scene's samples differ"
        );
        files.push(bytes);
    }
    // Every flag set changes the samples.
    for i in 0..files.len() {
        for j in 0..i {
            assert!(
                files[i] != files[j],
                "{:?} = {:?}",
                MESH_FLAGS[i],
                MESH_FLAGS[j]
            );
        }
    }
    let read = |i: usize| {
        strata_engine::io::read_samples_ply(&d.join(format!("mesh{i}.ply"))).expect("samples")
    };
    // Uniform: isotropic; direction:0,1,0 with --anisotropy 4: spacings 4:1.
    let median_ratio = |i: usize| {
        let mut r: Vec<f32> = read(i)
            .iter()
            .map(|s| s.spacing[0].max(s.spacing[1]) / s.spacing[0].min(s.spacing[1]))
            .collect();
        r.sort_by(f32::total_cmp);
        r[r.len() / 2]
    };
    assert!(median_ratio(0) < 1.5, "{}", median_ratio(0));
    assert!(median_ratio(3) > 3.0, "{}", median_ratio(3));
    // --density-from: four times the density above, so most samples are there.
    let above = read(5).iter().filter(|s| s.position[1] > 0.0).count();
    assert!(above > 250, "{above} of 400 above");
}

#[test]
fn mesh_flags_on_a_scene_file_are_refused_and_bad_values_named() {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(dir.path().join("scene.ron"), scene(SPHERE, "")).expect("write");
    std::fs::write(dir.path().join("q.obj"), QUAD).expect("write");
    let e = strata_in(
        dir.path(),
        &["sample", "{dir}/scene.ron", "--field", "smooth"],
    )
    .expect_err("--field with a scene");
    assert!(one_line(&e).contains("apply to a mesh input"), "{e}");
    let e = strata_in(
        dir.path(),
        &["sample", "{dir}/q.obj", "--anisotropy", "0.5"],
    )
    .expect_err("anisotropy under 1");
    assert!(
        one_line(&e).contains("--anisotropy must be a number of at least 1"),
        "{e}"
    );
    let e = strata_in(dir.path(), &["sample", "{dir}/q.obj", "--field", "wavy"])
        .expect_err("unknown field");
    assert!(
        e.to_string()
            .contains("give uniform, smooth, curvature or direction:X,Y,Z"),
        "{e}"
    );
    let e = strata_in(dir.path(), &["scene", "{dir}/scene.ron"]).expect_err("not a mesh");
    assert!(one_line(&e).contains("strata scene takes a mesh"), "{e}");
}

#[test]
fn sample_leaves_a_file_beside_its_input_unless_told_not_to() {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(dir.path().join("scene.ron"), scene(SPHERE, "")).expect("write");
    std::fs::write(dir.path().join("q.obj"), QUAD).expect("write");
    strata_in(dir.path(), &["sample", "{dir}/scene.ron", "-n", "50"]).expect("sample");
    let samples = strata_engine::io::read_samples_ply(&dir.path().join("scene.samples.ply"))
        .expect("the default output");
    assert_eq!(samples.len(), 50);
    strata_in(dir.path(), &["sample", "{dir}/q.obj", "-n", "20"]).expect("sample a mesh");
    assert!(dir.path().join("q.samples.ply").is_file());
    std::fs::remove_file(dir.path().join("q.samples.ply")).expect("rm");
    strata_in(dir.path(), &["sample", "{dir}/q.obj", "--no-out"]).expect("no output");
    assert!(!dir.path().join("q.samples.ply").exists());
}

/// Every output-path error, for every command that writes a file, as root too (CI runs
/// as root, who may write almost anywhere): `/proc/self` is a folder that no one may
/// create files in, and a path under a regular file has no folder to go to.
#[test]
fn every_output_path_error_names_the_path_and_its_reason() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    std::fs::write(
        d.join("scene.ron"),
        crate::hostile::scene(crate::hostile::SPHERE, ""),
    )
    .expect("write");
    std::fs::create_dir(d.join("taken.ply")).expect("mkdir");
    let cases: &[(&[&str], &str)] = &[
        (
            &["sample", "{dir}/scene.ron", "-o", "/proc/self/s.ply"],
            "/proc/self/s.ply: --out: the folder /proc/self is not writable",
        ),
        (
            &["field", "{dir}/scene.ron", "-o", "/proc/self/f.ply"],
            "/proc/self/f.ply: --out (a PLY mesh): the folder /proc/self is not writable",
        ),
        (
            &["field", "{dir}/scene.ron", "--report", "/proc/self/f.json"],
            "/proc/self/f.json: --report (JSON): the folder /proc/self is not writable",
        ),
        (
            &["segment", "{dir}/scene.ron", "-o", "/proc/self/g.ply"],
            "/proc/self/g.ply: --out (a PLY mesh): the folder /proc/self is not writable",
        ),
        (
            &["segment", "{dir}/scene.ron", "--atlas", "/proc/self/g.svg"],
            "/proc/self/g.svg: --atlas (SVG): the folder /proc/self is not writable",
        ),
        (
            &["bench", "{dir}/scene.ron", "--json", "/proc/self/b.json"],
            "/proc/self/b.json: --json: the folder /proc/self is not writable",
        ),
        (
            &["watch", "{dir}/scene.ron", "-o", "/proc/self/w.ply"],
            "/proc/self/w.ply: --out (binary PLY samples): the folder /proc/self is not writable",
        ),
        (
            &["render", "{dir}/scene.ron", "-o", "/proc/self/r.png"],
            "/proc/self/r.png: --out (PNG): the folder /proc/self is not writable",
        ),
        (
            &["analyze", "{dir}/scene.ron", "-o", "/proc/self/an"],
            "--out: creating the folder /proc/self/an",
        ),
        (
            &["sample", "{dir}/scene.ron", "-o", "{dir}/scene.ron/s.ply"],
            "s.ply: --out: {dir}/scene.ron is a file, not a folder",
        ),
        (
            &["sample", "{dir}/scene.ron", "-o", "{dir}/taken.ply"],
            "taken.ply: --out names a folder; give a file name",
        ),
        (
            &["sample", "{dir}/scene.ron", "-o", "{dir}/s.txt"],
            "s.txt: output must end in .ply or .csv",
        ),
        (
            &["sample", "{dir}/scene.ron", "-o", "{dir}/no/s.ply"],
            "s.ply: --out: the folder {dir}/no does not exist",
        ),
    ];
    let folder = d.to_str().expect("utf-8 temp path");
    for (args, expected) in cases {
        let e = strata_in(d, args).expect_err("refused");
        let line = one_line(&e);
        let expected = expected.replace("{dir}", folder);
        assert!(
            line.contains(&expected),
            "{args:?}: {line:?} lacks {expected:?}"
        );
        assert!(!line.contains('\n'), "{line}");
    }
    // Nothing was written into the scene's folder.
    let mut names: Vec<_> = std::fs::read_dir(d)
        .expect("dir")
        .map(|e| e.expect("entry").file_name())
        .collect();
    names.sort();
    assert_eq!(names, ["scene.ron", "taken.ply"]);
}
