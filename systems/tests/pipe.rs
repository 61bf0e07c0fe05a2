//! The `strata` binary run as a shell runs it: a reader that closes standard output
//! early (`strata field scene.ron | head -c1`) ends every command quietly, with the
//! status a shell gives a process stopped by a closed pipe and nothing on standard
//! error (no panic).

use std::io::Read;
use std::process::{Command, Stdio};

/// Runs `strata args...` with its standard output closed before it prints, and returns
/// the exit status and what it wrote to standard error.
fn with_closed_stdout(args: &[&str]) -> (Option<i32>, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_strata"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn strata");
    drop(child.stdout.take());
    let mut err = String::new();
    child
        .stderr
        .take()
        .expect("stderr")
        .read_to_string(&mut err)
        .expect("read stderr");
    (child.wait().expect("wait").code(), err)
}

#[test]
fn every_command_ends_quietly_when_its_reader_stops() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = dir.path().join("scene.ron");
    std::fs::write(
        &scene,
        "(mesh: Shape(Sphere(radius: 1.0, resolution: 4)), sampling: (count: 200, seed: 1))",
    )
    .expect("write scene");
    let mesh = dir.path().join("quad.obj");
    std::fs::write(
        &mesh,
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n",
    )
    .expect("write mesh");
    let scene = scene.to_str().expect("utf-8");
    let mesh = mesh.to_str().expect("utf-8");
    let analysis = dir.path().join("analysis");
    let analysis = analysis.to_str().expect("utf-8");
    let commands: [&[&str]; 6] = [
        &["field", scene],
        &["sample", scene, "--no-out"],
        &["segment", scene],
        &["bench", scene, "--repeat", "1"],
        &[
            "analyze",
            scene,
            "-o",
            analysis,
            "--runs",
            "1",
            "--no-plots",
        ],
        &["scene", mesh],
    ];
    for args in commands {
        let (code, err) = with_closed_stdout(args);
        assert_eq!(code, Some(141), "{args:?}: {err}");
        assert!(err.is_empty(), "{args:?}: {err}");
    }
}
