//! End to end: scene files through the CLI to sample files, as a user runs them.

use clap::Parser;
use strata_engine::io::read_samples_ply;
use strata_systems::cli::{Cli, one_line, run};
use strata_systems::config::{MeshSource, SceneConfig};
use strata_systems::scene::Scene;
use strata_tests::config_files;

fn strata(args: &[&str]) -> anyhow::Result<()> {
    let mut argv = vec!["strata"];
    argv.extend_from_slice(args);
    run(Cli::try_parse_from(argv)?)
}

#[test]
fn every_bundled_config_samples_exactly_its_count() {
    let files = config_files();
    assert!(
        files.len() >= 4,
        "configs/ holds the bundled scenes: {files:?}"
    );
    for path in files {
        let config = SceneConfig::load(&path).unwrap_or_else(|e| panic!("{e}"));
        if let MeshSource::File(mesh) = &config.mesh
            && !mesh.exists()
        {
            eprintln!("skipping {}: {} is absent", path.display(), mesh.display());
            continue;
        }
        let scene = Scene::build(&config).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let n = config.sampling.count as usize;
        let samples = scene.sampler.sample(n, config.sampling.seed);
        assert_eq!(samples.len(), n, "{}", path.display());
        let (lo, hi) = scene.mesh.bounds();
        for s in &samples {
            for k in 0..3 {
                let x = s.position[k] as f64;
                assert!(
                    x >= lo[k] - 1e-6 && x <= hi[k] + 1e-6,
                    "{}: {s:?}",
                    path.display()
                );
            }
        }
    }
}

/// Issues 5 and 17: an isotropic, a 3:1 anisotropic, a curvature-driven and a designed
/// ("smooth") scene for every shared mesh and every built-in shape, named
/// `<mesh>-<field>.ron`.
#[test]
fn every_mesh_has_its_three_bundled_scenes() {
    let files = config_files();
    let names: Vec<String> = files
        .iter()
        .filter_map(|p| p.file_name()?.to_str().map(str::to_owned))
        .collect();
    let built_ins = ["plane", "sphere", "cylinder", "torus", "genus2"];
    let mut missing = Vec::new();
    for mesh in strata_tests::SHARED_MESHES.iter().chain(&built_ins) {
        for field in ["isotropic", "anisotropic", "curvature", "smooth"] {
            let name = format!("{mesh}-{field}.ron");
            if !names.contains(&name) {
                missing.push(name);
            }
        }
    }
    assert!(missing.is_empty(), "configs/ lacks {missing:?}");
}

#[test]
fn cli_writes_ply_and_csv_that_read_back() {
    let dir = tempfile::tempdir().expect("tempdir");
    let config = config_files()
        .into_iter()
        .find(|p| p.ends_with("plane-anisotropic.ron"));
    let config = config.expect("plane-anisotropic.ron is bundled");
    let config = config.to_str().expect("utf-8 path");
    let ply = dir.path().join("s.ply");
    strata(&[
        "sample",
        config,
        "--count",
        "150001",
        "--seed",
        "3",
        "--out",
        ply.to_str().expect("utf-8"),
    ])
    .expect("sample to PLY");
    let samples = read_samples_ply(&ply).expect("read back");
    assert_eq!(samples.len(), 150_001);
    assert!(
        samples
            .iter()
            .enumerate()
            .all(|(i, s)| s.index as usize == i)
    );
    // Same scene, count and seed: the same samples, though the command draws and
    // writes them in blocks of 65,536 (issue 22: bounded memory for any count).
    let scene = Scene::build(&SceneConfig::load(std::path::Path::new(config)).expect("config"))
        .expect("scene");
    assert!(scene.sampler.sample(150_001, 3) == samples);
    let csv = dir.path().join("s.csv");
    strata(&[
        "sample",
        config,
        "-n",
        "10",
        "-o",
        csv.to_str().expect("utf-8"),
    ])
    .expect("sample to CSV");
    let text = std::fs::read_to_string(&csv).expect("csv");
    let mut lines = text.lines();
    assert!(lines.next().expect("header").starts_with("x,y,z,"));
    assert_eq!(lines.count(), 10);
    let mut names: Vec<_> = std::fs::read_dir(dir.path())
        .expect("dir")
        .map(|e| e.expect("entry").file_name())
        .collect();
    names.sort();
    assert_eq!(
        names,
        ["s.csv", "s.ply"],
        "atomic writes leave no temporary file"
    );
}

/// `strata sample --threads N` runs on a pool of N workers beside the process's global
/// pool (which the binary builds at start-up), and writes the same bytes for any N;
/// counts outside 1..=MAX_THREADS are refused with the range.
#[test]
fn cli_sample_threads_gives_the_same_file_for_any_count() {
    let dir = tempfile::tempdir().expect("tempdir");
    let config = config_files()
        .into_iter()
        .find(|p| p.ends_with("default.ron"))
        .expect("default.ron is bundled");
    let config = config.to_str().expect("utf-8 path");
    // The global pool exists already, as in the binary.
    let _ = rayon::ThreadPoolBuilder::new().build_global();
    let mut files = Vec::new();
    for threads in ["1", "2", "3"] {
        let out = dir.path().join(format!("t{threads}.ply"));
        strata(&[
            "sample",
            config,
            "-n",
            "70001",
            "--threads",
            threads,
            "-o",
            out.to_str().expect("utf-8"),
        ])
        .unwrap_or_else(|e| panic!("--threads {threads}: {}", one_line(&e)));
        files.push(std::fs::read(&out).expect("written"));
    }
    assert!(files[0] == files[1] && files[1] == files[2]);
    for bad in ["0", "1025", "100000000"] {
        let e =
            strata(&["sample", config, "-n", "10", "--threads", bad]).expect_err("out of range");
        let message = one_line(&e);
        assert!(
            message.contains(&format!("invalid value '{bad}' for '--threads <THREADS>'"))
                && message.contains("give a count from 1 to 1024"),
            "{message}"
        );
    }
}

#[test]
fn cli_progressive_order_nests_its_prefixes() {
    // `--order progressive`: the samples of 500 are the first 500 of 800, bit for bit
    // in place (spacing follows the count), and equal the engine's progressive ranks.
    let dir = tempfile::tempdir().expect("tempdir");
    let config = config_files()
        .into_iter()
        .find(|p| p.ends_with("sphere-anisotropic.ron"))
        .expect("sphere-anisotropic.ron is bundled");
    let config = config.to_str().expect("utf-8 path");
    let mut sets = Vec::new();
    for n in ["500", "800"] {
        let ply = dir.path().join(format!("p{n}.ply"));
        strata(&[
            "sample",
            config,
            "-n",
            n,
            "--seed",
            "4",
            "--order",
            "progressive",
            "-o",
            ply.to_str().expect("utf-8"),
        ])
        .expect("progressive sample");
        sets.push(read_samples_ply(&ply).expect("read back"));
    }
    let place =
        |s: &strata_engine::sample::Sample| (s.position, s.face, s.segment, s.bary, s.index);
    assert_eq!(sets[0].len(), 500);
    for (a, b) in sets[0].iter().zip(&sets[1]) {
        assert_eq!(place(a), place(b));
    }
    let scene = Scene::build(&SceneConfig::load(std::path::Path::new(config)).expect("config"))
        .expect("scene");
    let mut ranks = vec![strata_engine::sample::Sample::default(); 300];
    scene.sampler.progressive_into(4, 500, &mut ranks);
    for (a, b) in ranks.iter().zip(&sets[1][500..]) {
        assert_eq!(place(a), place(b));
    }
    // The stratified order moves samples when the count changes.
    let stratified = scene.sampler.sample(800, 4);
    assert!(
        stratified
            .iter()
            .zip(&sets[1])
            .any(|(a, b)| place(a) != place(b))
    );
}

#[test]
fn cli_errors_are_one_line_with_file_and_position() {
    let dir = tempfile::tempdir().expect("tempdir");
    let bad = dir.path().join("bad.ron");
    std::fs::write(
        &bad,
        "(\n  mesh: Shape(Plane(size: 1.0)),\n  sampling: (count: \"x\"),\n)",
    )
    .expect("write");
    let e = strata(&["sample", bad.to_str().expect("utf-8")]).expect_err("bad config");
    let line = one_line(&e);
    assert!(
        line.contains("bad.ron:3:") && !line.contains('\n'),
        "{line}"
    );

    let missing = dir.path().join("mesh.ron");
    std::fs::write(&missing, "(mesh: File(\"nowhere.obj\"))").expect("write");
    let e = strata(&["sample", missing.to_str().expect("utf-8")]).expect_err("missing mesh");
    let line = one_line(&e);
    assert!(
        line.contains("nowhere.obj") && line.matches("No such file").count() == 1,
        "{line}"
    );

    let curved = dir.path().join("sphere.ron");
    std::fs::write(&curved, "(mesh: Shape(Sphere(radius: 1.0, resolution: 4)))").expect("write");
    strata(&["sample", curved.to_str().expect("utf-8"), "-n", "100"])
        .expect("curved meshes sample");
    let bad_param = dir.path().join("gamma.ron");
    std::fs::write(&bad_param, "(mesh: Shape(Sphere()), param: (gamma: -1.0))").expect("write");
    let e = strata(&["sample", bad_param.to_str().expect("utf-8")]).expect_err("negative gamma");
    assert!(one_line(&e).contains("gamma"), "{}", one_line(&e));

    let good = config_files()
        .into_iter()
        .find(|p| p.ends_with("default.ron"))
        .expect("default.ron");
    let e = strata(&["sample", good.to_str().expect("utf-8"), "--out", "x.txt"])
        .expect_err("bad extension");
    assert!(one_line(&e).contains(".ply or .csv"));
}

#[test]
fn cli_bench_reports_timings_and_memory_as_json() {
    let dir = tempfile::tempdir().expect("tempdir");
    let config = config_files()
        .into_iter()
        .find(|p| p.ends_with("plane-gaussian.ron"))
        .expect("bundled");
    let json = dir.path().join("bench.json");
    // `strata bench` on the plane with `extra` arguments; its JSON.
    let bench = |extra: &[&str]| -> serde_json::Value {
        let mut args = vec![
            "bench",
            config.to_str().expect("utf-8"),
            "-n",
            "5000",
            "--repeat",
            "3",
            "--json",
            json.to_str().expect("utf-8"),
        ];
        args.extend_from_slice(extra);
        strata(&args).expect("bench");
        serde_json::from_str(&std::fs::read_to_string(&json).expect("json")).expect("parse")
    };
    let v = bench(&[]);
    for key in [
        "faces",
        "segments",
        "preprocess_s",
        "stages",
        "count",
        "sample_median_s",
        "bytes",
    ] {
        assert!(v.get(key).is_some(), "missing {key}: {v}");
    }
    assert_eq!(v["count"], 5000);
    assert_eq!(v["faces"], 8192);
    assert!(v["sample_median_s"].as_f64().expect("number") > 0.0);
    assert!(v["bytes"].as_u64().expect("number") > 0);
    assert_eq!(v["mode"], "samples");
    let v = bench(&["--sites"]);
    assert_eq!(v["mode"], "sites");
    assert_eq!(v["count"], 5000);
    assert!(v["sample_median_s"].as_f64().expect("number") > 0.0);
    assert!(strata(&["bench", config.to_str().expect("utf-8"), "--repeat", "0"]).is_err());
}

/// Issue 22: counts beyond what a request can index are refused before preprocessing,
/// in one line, instead of a panic or an abort; counts that fit are drawn and written a
/// block at a time, so memory does not limit them (see `cli_writes_ply_and_csv_...`).
#[test]
fn counts_beyond_a_request_are_refused_before_preprocessing() {
    let config = config_files()
        .into_iter()
        .find(|p| p.ends_with("sphere-anisotropic.ron"))
        .expect("sphere-anisotropic.ron is bundled");
    let config = config.to_str().expect("utf-8 path");
    for n in ["18446744073709551615", "4294967297"] {
        let e = strata(&["sample", config, "-n", n]).expect_err("too many");
        let line = one_line(&e);
        assert!(
            line.contains("at most 2^32 = 4294967296 samples per request") && line.contains(n),
            "{line}"
        );
        assert!(!line.contains('\n'));
    }
    // Commands that hold every sample in memory refuse what it cannot hold, before
    // preprocessing; bench names its override. 2^32 samples need 275 GB.
    if strata_systems::budget::available_memory().is_some_and(|m| m < 64 << 32) {
        let n = "4294967296";
        let e = strata(&["bench", config, "-n", n]).expect_err("bench");
        let line = one_line(&e);
        assert!(
            line.contains("of memory available") && line.contains("--ignore-memory-check"),
            "{line}"
        );
        let e = strata(&["analyze", config, "-n", n]).expect_err("analyze");
        let line = one_line(&e);
        assert!(
            line.contains("of memory available") && line.contains("--ignore-memory-check"),
            "{line}"
        );
    }
    let e = strata(&[
        "bench",
        config,
        "-n",
        "18446744073709551615",
        "--ignore-memory-check",
    ])
    .expect_err("beyond indices, whatever the override");
    assert!(one_line(&e).contains("sample indices are 32-bit"), "{e}");
}

/// Issue 22: a scene saved with a UTF-8 byte-order mark loads like one without.
#[test]
fn scene_files_may_start_with_a_byte_order_mark() {
    let text = "(mesh: Shape(Sphere(radius: 1.0, resolution: 3)), \
         field: Constant(direction: (1.0, 0.0, 0.0), anisotropy: 2.0, density: 1.0))";
    let plain = SceneConfig::from_ron(text, std::path::Path::new("a.ron")).expect("plain");
    let marked = SceneConfig::from_ron(&format!("\u{feff}{text}"), std::path::Path::new("b.ron"))
        .expect("with a byte-order mark");
    assert_eq!(format!("{plain:?}"), format!("{marked:?}"));
}

/// Issue 22: `strata segment --out x.obj` wrote PLY bytes under an OBJ name; it is
/// refused before any work, and nothing is written.
#[test]
fn segment_refuses_an_output_that_is_not_ply() {
    let config = config_files()
        .into_iter()
        .find(|p| p.ends_with("sphere-anisotropic.ron"))
        .expect("sphere-anisotropic.ron is bundled");
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("segments.obj");
    let e = strata(&[
        "segment",
        config.to_str().expect("utf-8"),
        "--out",
        out.to_str().expect("utf-8"),
    ])
    .expect_err("not a PLY name");
    assert!(one_line(&e).ends_with("--out writes a binary PLY mesh; name it .ply"));
    assert!(!out.exists());
}

/// Issue 22: an output path that is one of the scene's inputs (its mesh, the scene
/// file itself) is refused, and the input is left as it was.
#[test]
fn outputs_never_overwrite_the_scene_inputs() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mesh = dir.path().join("tri.obj");
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0.2\nf 1 2 3\nf 2 4 3\n";
    std::fs::write(&mesh, obj).expect("mesh");
    let scene = dir.path().join("scene.ron");
    std::fs::write(
        &scene,
        "(mesh: File(\"tri.obj\"), field: Constant(direction: (1.0, 0.0, 0.0), anisotropy: 2.0, density: 1.0), sampling: (count: 50))",
    )
    .expect("scene");
    let scene_text = std::fs::read_to_string(&scene).expect("read");
    // The mesh by another spelling of its path, and the scene file itself.
    let aliased = dir.path().join(".").join("tri.obj");
    for (command, flag, out) in [
        ("sample", "--out", aliased.clone()),
        ("segment", "--report", scene.clone()),
        ("field", "--out", mesh.clone()),
    ] {
        let e = strata(&[
            command,
            scene.to_str().expect("utf-8"),
            flag,
            out.to_str().expect("utf-8"),
        ])
        .expect_err("an input as output");
        assert!(
            one_line(&e).contains("is an input of the scene"),
            "{command}: {}",
            one_line(&e)
        );
    }
    assert_eq!(std::fs::read_to_string(&mesh).expect("mesh"), obj);
    assert_eq!(std::fs::read_to_string(&scene).expect("scene"), scene_text);
}

/// Issue 22: `strata analyze` given a mesh PLY says that it is not a sample file.
#[test]
fn analyze_samples_a_mesh_ply_as_a_mesh() {
    let config = config_files()
        .into_iter()
        .find(|p| p.ends_with("sphere-anisotropic.ron"))
        .expect("sphere-anisotropic.ron is bundled");
    let dir = tempfile::tempdir().expect("tempdir");
    let mesh = dir.path().join("segments.ply");
    strata(&[
        "segment",
        config.to_str().expect("utf-8"),
        "--out",
        mesh.to_str().expect("utf-8"),
    ])
    .expect("segment writes a mesh PLY");
    let out = dir.path().join("analysis");
    strata(&[
        "analyze",
        mesh.to_str().expect("utf-8"),
        "--out",
        out.to_str().expect("utf-8"),
    ])
    .expect("a mesh PLY is sampled as a mesh");
    // Sampled with uniform density: the summary counts the default realizations.
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).expect("summary"))
            .expect("json");
    assert_eq!(summary["realizations"].as_u64(), Some(4));
}
