//! Issue 22's hostile-input corpus: every bad request and file the issue lists, run as
//! a user runs them (the real `strata` commands in process, the real loaders), each
//! ending in its one-line error that names the file, the position where there is one,
//! and the problem; or in the warning or result the issue asks for. Nothing panics,
//! aborts or allocates without bound.
//!
//! The issue's cases about state over time have their own tests: `strata watch` with
//! its output folder gone (`hot_reload::strata_watch_survives_a_missing_output_folder`),
//! an edit to a count memory cannot hold (`hot_reload::counts_beyond_memory_...`), two
//! writers of one file (`io::atomic`'s `concurrent_writes_to_one_folder_do_not_collide`),
//! and one count of isotropic-fallback segments (`surface::check`).

use std::path::Path;

use clap::Parser;
use strata_systems::budget::{available_memory, available_space};
use strata_systems::cli::{Cli, one_line, run};

/// A two-triangle unit square.
pub(crate) const QUAD: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n";

/// A scene over `mesh` (a `mesh:` value) with `rest` (more options) and 100 samples.
pub(crate) fn scene(mesh: &str, rest: &str) -> String {
    format!(
        "(\n    mesh: {mesh},\n    field: Constant(direction: (1.0, 0.0, 0.0), anisotropy: 2.0, density: 1.0),\n    sampling: (count: 100, seed: 1),\n{rest})\n"
    )
}

pub(crate) const SPHERE: &str = "Shape(Sphere(radius: 1.0, resolution: 4))";

/// One hostile input: files written into a fresh folder, a command line (`{dir}`
/// stands for the folder), and what must come out.
pub(crate) struct Case {
    name: &'static str,
    files: Vec<(&'static str, String)>,
    args: &'static [&'static str],
    /// `None`: the command succeeds. `Some(fragments)`: it fails with one line that
    /// holds every fragment.
    error: Option<&'static [&'static str]>,
}

pub(crate) fn case(
    name: &'static str,
    files: Vec<(&'static str, String)>,
    args: &'static [&'static str],
    error: Option<&'static [&'static str]>,
) -> Case {
    Case {
        name,
        files,
        args,
        error,
    }
}

pub(crate) fn check(c: &Case) {
    let dir = tempfile::tempdir().expect("tempdir");
    for (name, text) in &c.files {
        std::fs::write(dir.path().join(name), text).expect("write input");
    }
    let folder = dir.path().to_str().expect("utf-8 temp path");
    let mut argv = vec!["strata".to_owned()];
    argv.extend(c.args.iter().map(|a| a.replace("{dir}", folder)));
    let result = Cli::try_parse_from(&argv)
        .map_err(anyhow::Error::from)
        .and_then(run);
    match (result, c.error) {
        (Ok(()), None) => {}
        (Err(e), Some(fragments)) => {
            let line = one_line(&e);
            assert!(!line.contains('\n'), "{}: {line}", c.name);
            for f in fragments {
                assert!(line.contains(f), "{}: {line:?} lacks {f:?}", c.name);
            }
        }
        (Ok(()), Some(_)) => panic!("{}: accepted", c.name),
        (Err(e), None) => panic!("{}: {}", c.name, one_line(&e)),
    }
}

#[test]
fn every_hostile_request_of_issue_22_ends_in_its_clear_error() {
    let sphere = || vec![("scene.ron", scene(SPHERE, ""))];
    let mut cases = vec![
        // Crashes and unbounded memory.
        case(
            "count 2^64 - 1 on the command line (a capacity-overflow panic)",
            sphere(),
            &["sample", "{dir}/scene.ron", "-n", "18446744073709551615"],
            Some(&["scene.ron: ", "at most 2^32", "sample indices are 32-bit"]),
        ),
        case(
            "count 2^64 - 1 in the scene",
            vec![(
                "scene.ron",
                scene(SPHERE, "").replace("count: 100", "count: 18446744073709551615"),
            )],
            &["sample", "{dir}/scene.ron"],
            Some(&["scene.ron:4:", "sampling option `count`", "32-bit"]),
        ),
        case(
            "count 2^32 + 1 (an abort)",
            sphere(),
            &["sample", "{dir}/scene.ron", "--count", "4294967297"],
            Some(&["at most 2^32 = 4294967296 samples"]),
        ),
        case(
            "max_cell_share 1e-9 (grew past 8 GB)",
            vec![(
                "scene.ron",
                scene(SPHERE, "    curve: (max_cell_share: 1e-9),\n"),
            )],
            &["sample", "{dir}/scene.ron"],
            Some(&[
                "scene.ron:5:13:",
                "`max_cell_share` = 1e-9",
                "2.0e9 cells",
                "50.0 GB",
            ]),
        ),
        // Broken input accepted silently.
        case(
            "--out naming the scene's own mesh",
            vec![
                ("quad.obj", QUAD.to_owned()),
                ("scene.ron", scene("File(\"quad.obj\")", "")),
            ],
            &["sample", "{dir}/scene.ron", "--out", "{dir}/quad.obj"],
            Some(&["quad.obj: is an input of the scene"]),
        ),
        case(
            "segment --out x.obj (PLY bytes under an OBJ name)",
            sphere(),
            &["segment", "{dir}/scene.ron", "--out", "{dir}/x.obj"],
            Some(&["x.obj", "name it .ply"]),
        ),
        // Unclear errors.
        case(
            "an index beyond u64 (was \"non-integer\")",
            vec![
                ("q.obj", format!("{QUAD}f 1 2 99999999999999999999\n")),
                ("scene.ron", scene("File(\"q.obj\")", "")),
            ],
            &["sample", "{dir}/scene.ron"],
            Some(&["q.obj:7:", "out of range"]),
        ),
        case(
            "count: 2000.5 (was \"Expected comma\")",
            vec![(
                "scene.ron",
                scene(SPHERE, "").replace("count: 100", "count: 2000.5"),
            )],
            &["sample", "{dir}/scene.ron"],
            Some(&[
                "scene.ron:4:",
                "`count`: expected an integer, found `2000.5`",
            ]),
        ),
        case(
            "field: 3.0 (suggested r#3.0)",
            vec![("scene.ron", "(mesh: Shape(Plane()), field: 3.0)".to_owned())],
            &["sample", "{dir}/scene.ron"],
            Some(&[
                "scene.ron:1:",
                "`field`: expected one of `Constant`",
                "found `3.0`",
            ]),
        ),
        case(
            "a scene saved with a byte-order mark",
            vec![("scene.ron", format!("\u{feff}{}", scene(SPHERE, "")))],
            &["sample", "{dir}/scene.ron"],
            None,
        ),
        case(
            "coordinates near 1e300 (failed in a Cholesky factorization)",
            vec![
                ("far.obj", QUAD.replace("v 1 1 0", "v 1 1 1e300")),
                ("scene.ron", scene("File(\"far.obj\")", "")),
            ],
            &["sample", "{dir}/scene.ron"],
            Some(&["far.obj: vertex 2", "beyond the supported coordinate range"]),
        ),
        case(
            "density 1e300 (an isotropic-fallback message)",
            vec![(
                "scene.ron",
                scene(SPHERE, "").replace("density: 1.0", "density: 1e300"),
            )],
            &["sample", "{dir}/scene.ron"],
            Some(&[
                "scene.ron: field: ",
                "outside the supported range",
                "relative",
            ]),
        ),
        case(
            "density 1e-300",
            vec![(
                "scene.ron",
                scene(SPHERE, "").replace("density: 1.0", "density: 1e-300"),
            )],
            &["sample", "{dir}/scene.ron"],
            Some(&["outside the supported range [1e-100, 1e100]"]),
        ),
        case(
            "a curvature field on a 1000 x 1e-6 needle (a non-finite tensor)",
            vec![
                (
                    "needle.obj",
                    "v 0 0 0\nv 1000 0 0\nv 1000 1e-6 0\nv 0 1e-6 0\nf 1 2 3\nf 1 3 4\n".to_owned(),
                ),
                (
                    "scene.ron",
                    "(mesh: File(\"needle.obj\"), field: Curvature(), sampling: (count: 100))"
                        .to_owned(),
                ),
            ],
            &["sample", "{dir}/scene.ron", "--out", "{dir}/needle.ply"],
            None,
        ),
    ];
    // Sizes that depend on the machine: refused wherever they do not fit (2^32
    // samples are 275 GB on disk; 10^9 are 64 GB in memory).
    if available_space(&std::env::temp_dir().join("o.ply")).is_some_and(|free| free < 64 << 32) {
        cases.push(case(
            "2^32 samples to a file larger than the free space",
            sphere(),
            &[
                "sample",
                "{dir}/scene.ron",
                "-n",
                "4294967296",
                "--out",
                "{dir}/o.ply",
            ],
            Some(&[
                "o.ply: 4294967296 samples: ",
                "free there",
                "--ignore-space-check",
            ]),
        ));
    }
    if available_memory().is_some_and(|m| m < 64_000_000_000) {
        cases.push(case(
            "10^9 samples held in memory (an abort)",
            sphere(),
            &["bench", "{dir}/scene.ron", "-n", "1000000000"],
            Some(&[
                "1000000000 samples: 64.0 GB needed",
                "--ignore-memory-check",
            ]),
        ));
    }
    for c in &cases {
        check(c);
    }
    assert!(cases.len() >= 15);
}

/// The OBJ cases that load with a warning rather than an error: a file cut short in a
/// face line, and faces of one or two corners, are counted and their lines named.
#[test]
fn short_faces_and_cut_files_load_with_a_warning_that_names_the_lines() {
    let dir = tempfile::tempdir().expect("tempdir");
    for (text, count, lines) in [
        // Cut short in the middle of a face line (`f 1` of `f 1 3 4`).
        ("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1", 1, "6"),
        (&format!("{QUAD}f 3\nf 2 4\n"), 2, "7, 8"),
    ] {
        let path = dir.path().join("short.obj");
        std::fs::write(&path, text).expect("write");
        let mesh = strata_engine::io::load(Path::new(&path)).expect("loads");
        let warnings: Vec<String> = mesh.warnings().iter().map(|w| w.to_string()).collect();
        let want = format!("skipped {count} faces of one or two corners");
        assert!(
            warnings
                .iter()
                .any(|w| w.contains(&want) && w.contains(&format!("on lines {lines}"))),
            "{warnings:?}"
        );
    }
}
