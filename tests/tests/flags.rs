//! Every documented flag of the commands that need no GPU, run once on a small scene,
//! each with an effect asserted (a file that appears, a value in the JSON, samples
//! that change or stay the same), so that a flag cannot silently stop working; and a
//! check, through clap's own description of the commands, that no flag is missing
//! from the table (with `render`'s and `view`'s, which are in `flags_render`).

use std::collections::BTreeSet;
use std::path::Path;

use clap::{CommandFactory, Parser};
use strata_systems::cli::{Cli, one_line, run};

/// A small curved scene (a sphere, 1280 faces, 200 samples) and a flat one.
const SCENE: &str = "(mesh: Shape(Sphere(radius: 1.0, resolution: 8)), field: Constant(direction: (1.0, 0.3, 0.2), anisotropy: 2.0, density: 1.0), sampling: (count: 200, seed: 1))";
const FLAT: &str = "(mesh: Shape(Plane(size: 1.0, resolution: 8)), field: Constant(direction: (1.0, 0.0, 0.0), anisotropy: 2.0, density: 1.0), sampling: (count: 200, seed: 1))";

/// Runs `strata args...` (`{dir}` stands for `dir`), panicking with the error line.
fn strata(dir: &Path, args: &[&str]) {
    let folder = dir.to_str().expect("utf-8 temp path");
    let argv =
        std::iter::once("strata".to_owned()).chain(args.iter().map(|a| a.replace("{dir}", folder)));
    let result = Cli::try_parse_from(argv)
        .map_err(anyhow::Error::from)
        .and_then(run);
    if let Err(e) = result {
        panic!("{args:?}: {}", one_line(&e));
    }
}

fn bytes(dir: &Path, name: &str) -> Vec<u8> {
    std::fs::read(dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn json(dir: &Path, name: &str) -> serde_json::Value {
    serde_json::from_slice(&bytes(dir, name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// One row: the flags it covers (`command --flag`), and a run that asserts their
/// effect in a folder holding `scene.ron`, `flat.ron` and `quad.obj`.
struct Row {
    covers: &'static [&'static str],
    check: fn(&Path),
}

const ROWS: &[Row] = &[
    Row {
        covers: &["sample --out", "sample -o", "sample --count", "sample -n"],
        check: |d| {
            strata(
                d,
                &["sample", "{dir}/scene.ron", "-n", "70", "-o", "{dir}/a.csv"],
            );
            let text = String::from_utf8(bytes(d, "a.csv")).expect("utf-8");
            assert_eq!(text.lines().count(), 71);
        },
    },
    Row {
        covers: &["sample --seed", "sample --order"],
        check: |d| {
            strata(d, &["sample", "{dir}/scene.ron", "-o", "{dir}/s1.ply"]);
            strata(
                d,
                &[
                    "sample",
                    "{dir}/scene.ron",
                    "-o",
                    "{dir}/s2.ply",
                    "--seed",
                    "2",
                ],
            );
            strata(
                d,
                &[
                    "sample",
                    "{dir}/scene.ron",
                    "-o",
                    "{dir}/s3.ply",
                    "--order",
                    "progressive",
                ],
            );
            assert!(bytes(d, "s1.ply") != bytes(d, "s2.ply"));
            assert!(bytes(d, "s1.ply") != bytes(d, "s3.ply"));
        },
    },
    Row {
        covers: &["sample --threads"],
        check: |d| {
            strata(d, &["sample", "{dir}/scene.ron", "-o", "{dir}/t0.ply"]);
            strata(
                d,
                &[
                    "sample",
                    "{dir}/scene.ron",
                    "-o",
                    "{dir}/t1.ply",
                    "--threads",
                    "1",
                ],
            );
            assert!(bytes(d, "t0.ply") == bytes(d, "t1.ply"));
        },
    },
    Row {
        covers: &["sample --ignore-space-check"],
        check: |d| {
            // A request that fits is written the same with the flag; that the flag lets
            // one past the free-space check is tested with the real binary in
            // systems/tests/space.rs (the run must be stopped once it writes).
            strata(
                d,
                &[
                    "sample",
                    "{dir}/scene.ron",
                    "-o",
                    "{dir}/i.ply",
                    "--ignore-space-check",
                ],
            );
            strata(d, &["sample", "{dir}/scene.ron", "-o", "{dir}/plain.ply"]);
            assert!(bytes(d, "i.ply").len() > 200 * 64);
            assert_eq!(bytes(d, "i.ply"), bytes(d, "plain.ply"));
        },
    },
    Row {
        covers: &["sample --no-out"],
        check: |d| {
            strata(d, &["sample", "{dir}/flat.ron", "--no-out"]);
            assert!(!d.join("flat.samples.ply").exists());
            strata(d, &["sample", "{dir}/flat.ron"]);
            assert!(d.join("flat.samples.ply").exists());
        },
    },
    Row {
        covers: &[
            "sample --field",
            "sample --anisotropy",
            "scene --field",
            "scene --anisotropy",
        ],
        check: |d| {
            strata(d, &["sample", "{dir}/quad.obj", "-o", "{dir}/q1.ply"]);
            strata(
                d,
                &[
                    "sample",
                    "{dir}/quad.obj",
                    "-o",
                    "{dir}/q2.ply",
                    "--field",
                    "direction:1,1,0",
                    "--anisotropy",
                    "3",
                ],
            );
            assert!(bytes(d, "q1.ply") != bytes(d, "q2.ply"));
        },
    },
    Row {
        covers: &["sample --density-from", "scene --density-from"],
        check: |d| {
            let field = "strata-field 1\n1 1 1 0 0\n1 1 1 0 0\n9 9 1 0 0\n9 9 1 0 0\n";
            std::fs::write(d.join("q.field"), field).expect("write");
            strata(
                d,
                &[
                    "sample",
                    "{dir}/quad.obj",
                    "-o",
                    "{dir}/q3.ply",
                    "--density-from",
                    "{dir}/q.field",
                ],
            );
            let s = strata_engine::io::read_samples_ply(&d.join("q3.ply")).expect("samples");
            let upper = s.iter().filter(|s| s.position[1] > 0.5).count();
            assert!(upper > s.len() * 6 / 10, "{upper} of {}", s.len());
        },
    },
    Row {
        covers: &[
            "segment --out",
            "segment -o",
            "segment --report",
            "segment --atlas",
            "segment --seed",
        ],
        check: |d| {
            strata(
                d,
                &[
                    "segment",
                    "{dir}/scene.ron",
                    "-o",
                    "{dir}/g.ply",
                    "--report",
                    "{dir}/g1.json",
                    "--atlas",
                    "{dir}/g.svg",
                ],
            );
            strata(
                d,
                &[
                    "segment",
                    "{dir}/scene.ron",
                    "--report",
                    "{dir}/g2.json",
                    "--seed",
                    "99",
                ],
            );
            assert!(bytes(d, "g.ply").starts_with(b"ply"));
            assert!(
                bytes(d, "g.svg").starts_with(b"<svg") || bytes(d, "g.svg").starts_with(b"<?xml")
            );
            assert!(json(d, "g1.json")["segments"] != json(d, "g2.json")["segments"]);
        },
    },
    Row {
        covers: &["field --out", "field -o", "field --report"],
        check: |d| {
            strata(
                d,
                &[
                    "field",
                    "{dir}/scene.ron",
                    "-o",
                    "{dir}/f.ply",
                    "--report",
                    "{dir}/f.json",
                ],
            );
            assert!(bytes(d, "f.ply").starts_with(b"ply"));
            assert!(json(d, "f.json").is_object());
        },
    },
    Row {
        covers: &[
            "bench --json",
            "bench --count",
            "bench -n",
            "bench --repeat",
            "bench --sites",
            "bench --ignore-memory-check",
        ],
        check: |d| {
            strata(
                d,
                &[
                    "bench",
                    "{dir}/scene.ron",
                    "--json",
                    "{dir}/b1.json",
                    "-n",
                    "123",
                    "--repeat",
                    "3",
                ],
            );
            strata(
                d,
                &[
                    "bench",
                    "{dir}/scene.ron",
                    "--json",
                    "{dir}/b2.json",
                    "--sites",
                    "--ignore-memory-check",
                    "--repeat",
                    "1",
                ],
            );
            let (b1, b2) = (json(d, "b1.json"), json(d, "b2.json"));
            assert_eq!(
                (b1["count"].as_u64(), b1["repeat"].as_u64()),
                (Some(123), Some(3))
            );
            assert_eq!(
                (b1["mode"].as_str(), b2["mode"].as_str()),
                (Some("samples"), Some("sites"))
            );
        },
    },
    Row {
        covers: &["bench --gpu"],
        check: |d| {
            let folder = d.to_str().expect("utf-8 temp path");
            let argv = [
                "strata",
                "bench",
                "{dir}/scene.ron",
                "-n",
                "77",
                "--repeat",
                "1",
            ];
            let argv = argv.iter().map(|a| a.replace("{dir}", folder)).chain([
                "--gpu".to_owned(),
                "--json".to_owned(),
                format!("{folder}/g.json"),
            ]);
            let result = Cli::try_parse_from(argv)
                .map_err(anyhow::Error::from)
                .and_then(run);
            let required = std::env::var("STRATA_REQUIRE_GPU").as_deref() == Ok("1");
            match result {
                Err(e) if !required && one_line(&e).contains("adapter") => {
                    eprintln!("no GPU adapter: bench --gpu not checked ({})", one_line(&e));
                }
                Err(e) => panic!("bench --gpu: {}", one_line(&e)),
                Ok(()) => {
                    let gpu = &json(d, "g.json")["gpu"];
                    assert_eq!(gpu["count"].as_u64(), Some(77), "{gpu}");
                    assert_eq!(gpu["segments_differ"].as_u64(), Some(0), "{gpu}");
                    assert!(gpu["deviation"].as_f64().is_some_and(|x| x < 1e-5), "{gpu}");
                    assert!(gpu["adapter"].as_str().is_some_and(|a| !a.is_empty()));
                }
            }
        },
    },
    Row {
        covers: &["watch --out", "watch -o", "watch --updates"],
        check: |d| {
            strata(
                d,
                &[
                    "watch",
                    "{dir}/scene.ron",
                    "-o",
                    "{dir}/w.ply",
                    "--updates",
                    "1",
                ],
            );
            assert_eq!(
                strata_engine::io::read_samples_ply(&d.join("w.ply"))
                    .expect("samples")
                    .len(),
                200
            );
        },
    },
    Row {
        covers: &[
            "analyze --out",
            "analyze -o",
            "analyze --count",
            "analyze -n",
            "analyze --runs",
            "analyze --no-plots",
            "analyze --ignore-memory-check",
        ],
        check: |d| {
            strata(
                d,
                &[
                    "analyze",
                    "{dir}/scene.ron",
                    "-o",
                    "{dir}/an",
                    "-n",
                    "64",
                    "--runs",
                    "2",
                    "--no-plots",
                    "--ignore-memory-check",
                ],
            );
            let summary = json(d, "an/summary.json");
            assert_eq!(
                (
                    summary["samples"].as_u64(),
                    summary["realizations"].as_u64()
                ),
                (Some(64), Some(2))
            );
            let pngs = std::fs::read_dir(d.join("an"))
                .expect("dir")
                .filter(|e| {
                    e.as_ref()
                        .is_ok_and(|e| e.path().extension().is_some_and(|x| x == "png"))
                })
                .count();
            assert_eq!(pngs, 0);
        },
    },
    Row {
        covers: &[
            "analyze --seed",
            "analyze --epsilon",
            "analyze --alignment",
            "analyze --field",
            "analyze --anisotropy",
            "analyze --density-from",
        ],
        check: |d| {
            strata(
                d,
                &[
                    "analyze",
                    "{dir}/flat.ron",
                    "-o",
                    "{dir}/a1",
                    "-n",
                    "64",
                    "--runs",
                    "1",
                    "--no-plots",
                ],
            );
            strata(
                d,
                &[
                    "analyze",
                    "{dir}/flat.ron",
                    "-o",
                    "{dir}/a2",
                    "-n",
                    "64",
                    "--runs",
                    "1",
                    "--no-plots",
                    "--seed",
                    "9",
                    "--epsilon",
                    "5",
                    "--alignment",
                ],
            );
            assert!(json(d, "a1/dda.json")["rapsd"] != json(d, "a2/dda.json")["rapsd"]);
            assert_eq!(
                json(d, "a2/dda.json")["options"]["epsilon"].as_f64(),
                Some(5.0)
            );
            assert!(d.join("a2/alignment.json").exists() && !d.join("a1/alignment.json").exists());
            // The mesh flags, as `sample`'s (one loader serves both).
            strata(
                d,
                &[
                    "analyze",
                    "{dir}/quad.obj",
                    "-o",
                    "{dir}/a3",
                    "-n",
                    "64",
                    "--runs",
                    "1",
                    "--no-plots",
                    "--field",
                    "direction:1,0,0",
                    "--anisotropy",
                    "2",
                ],
            );
            strata(
                d,
                &[
                    "analyze",
                    "{dir}/quad.obj",
                    "-o",
                    "{dir}/a4",
                    "-n",
                    "64",
                    "--runs",
                    "1",
                    "--no-plots",
                    "--density-from",
                    "{dir}/q.field",
                ],
            );
            assert!(json(d, "a3/dda.json")["rapsd"] != json(d, "a4/dda.json")["rapsd"]);
        },
    },
    Row {
        covers: &[
            "field --field",
            "field --anisotropy",
            "field --density-from",
        ],
        check: |d| {
            strata(d, &["field", "{dir}/quad.obj", "-o", "{dir}/fa.ply"]);
            strata(
                d,
                &[
                    "field",
                    "{dir}/quad.obj",
                    "-o",
                    "{dir}/fb.ply",
                    "--field",
                    "direction:1,1,0",
                    "--anisotropy",
                    "3",
                ],
            );
            strata(
                d,
                &[
                    "field",
                    "{dir}/quad.obj",
                    "-o",
                    "{dir}/fc.ply",
                    "--density-from",
                    "{dir}/q.field",
                ],
            );
            assert!(
                bytes(d, "fa.ply") != bytes(d, "fb.ply")
                    && bytes(d, "fa.ply") != bytes(d, "fc.ply")
            );
        },
    },
    Row {
        covers: &[
            "segment --field",
            "segment --anisotropy",
            "segment --density-from",
            "bench --field",
            "bench --anisotropy",
            "bench --density-from",
        ],
        check: |d| {
            // Uniform density is isotropic: normal-cone charts; the others align segments
            // to a field.
            let segments = |name: &str| json(d, name)["segment_count"].clone();
            strata(
                d,
                &["segment", "{dir}/sphere.ply", "--report", "{dir}/m1.json"],
            );
            strata(
                d,
                &[
                    "segment",
                    "{dir}/sphere.ply",
                    "--report",
                    "{dir}/m2.json",
                    "--field",
                    "smooth",
                    "--anisotropy",
                    "3",
                ],
            );
            strata(
                d,
                &[
                    "segment",
                    "{dir}/sphere.ply",
                    "--report",
                    "{dir}/m3.json",
                    "--density-from",
                    "{dir}/sphere.field",
                ],
            );
            assert!(
                json(d, "m1.json")["charts"] != json(d, "m2.json")["charts"],
                "{:?}",
                segments("m2.json")
            );
            assert!(json(d, "m1.json")["charts"] != json(d, "m3.json")["charts"]);
            let bench = |name: &str, flags: &[&str]| {
                let out = format!("{{dir}}/{name}");
                let mut args = vec![
                    "bench",
                    "{dir}/sphere.ply",
                    "-n",
                    "50",
                    "--repeat",
                    "1",
                    "--json",
                    &out,
                ];
                args.extend_from_slice(flags);
                strata(d, &args);
                let report = json(d, name);
                (report["segments"].clone(), report["bytes"].clone())
            };
            let plain = bench("n1.json", &[]);
            assert!(
                plain
                    != bench(
                        "n2.json",
                        &["--anisotropy", "2", "--field", "direction:1,0,0"]
                    )
            );
            assert!(plain != bench("n3.json", &["--density-from", "{dir}/sphere.field"]));
        },
    },
];

#[test]
fn every_flag_has_an_effect() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    std::fs::write(d.join("scene.ron"), SCENE).expect("write");
    std::fs::write(d.join("flat.ron"), FLAT).expect("write");
    std::fs::write(
        d.join("quad.obj"),
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n",
    )
    .expect("write");
    std::fs::write(
        d.join("q.field"),
        "strata-field 1\n1 1 1 0 0\n1 1 1 0 0\n9 9 1 0 0\n9 9 1 0 0\n",
    )
    .expect("write");
    let sphere = strata_engine::mesh::shapes::sphere(1.0, 3).expect("sphere");
    strata_engine::io::write_mesh_ply(&d.join("sphere.ply"), &sphere, None).expect("write");
    let mut field = String::from("strata-field 1\n");
    for p in sphere.positions() {
        let v = if p.y > 0.0 { 4.0 } else { 1.0 };
        field.push_str(&format!("{v} {v} 1 0 0\n"));
    }
    std::fs::write(d.join("sphere.field"), field).expect("write");
    for row in ROWS {
        (row.check)(d);
    }
}

#[test]
fn the_flag_table_covers_every_flag() {
    let covered: BTreeSet<&str> = ROWS
        .iter()
        .flat_map(|r| r.covers.iter().copied())
        .chain(crate::flags_render::COVERED.iter().copied())
        .collect();
    let mut missing = Vec::new();
    for command in Cli::command().get_subcommands() {
        let name = command.get_name();
        for arg in command.get_arguments() {
            let Some(long) = arg.get_long() else { continue };
            if matches!(long, "help" | "version") {
                continue;
            }
            let flag = format!("{name} --{long}");
            if !covered.contains(flag.as_str()) {
                missing.push(flag);
            }
        }
    }
    assert!(missing.is_empty(), "flags with no row: {missing:?}");
}
