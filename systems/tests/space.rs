//! Large sample files, with the real binary: `strata sample --ignore-space-check` (a
//! request whose file cannot fit in its folder's free space is refused before any
//! work, naming the flag; with the flag the same request starts drawing and writing,
//! and the test stops it once the file grows, long before the disk fills), and Ctrl-C
//! or SIGTERM during a write (status 130, the temporary file removed).

use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The largest count strata takes (`strata_systems::budget::MAX_COUNT`): 2^32 samples
/// of 64 bytes, 256 GiB of PLY.
const COUNT: u64 = 1 << 32;

#[test]
fn a_request_larger_than_the_free_space_is_refused_unless_the_flag_is_given() {
    let dir = tempfile::tempdir().expect("tempdir");
    let free = strata_systems::budget::available_space(&dir.path().join("x.ply"));
    match free {
        Some(bytes) if bytes < COUNT * 64 => {}
        other => {
            eprintln!("skipped: the temp folder's free space ({other:?} bytes) holds 2^32 samples");
            return;
        }
    }
    let scene = dir.path().join("scene.ron");
    std::fs::write(
        &scene,
        "(mesh: Shape(Plane(size: 1.0, resolution: 2)), sampling: (count: 10, seed: 1))",
    )
    .expect("write scene");
    let out = dir.path().join("big.ply");
    let count = COUNT.to_string();
    let args = [
        "sample",
        scene.to_str().expect("utf-8"),
        "-n",
        &count,
        "-o",
        out.to_str().expect("utf-8"),
    ];

    let refused = Command::new(env!("CARGO_BIN_EXE_strata"))
        .args(args)
        .output()
        .expect("run strata");
    let err = String::from_utf8_lossy(&refused.stderr);
    assert_eq!(refused.status.code(), Some(1), "{err}");
    assert!(err.contains("--ignore-space-check"), "{err}");
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .expect("read dir")
        .map(|e| e.expect("entry").file_name())
        .collect();
    assert_eq!(left.len(), 1, "nothing but the scene is written: {left:?}");

    let mut child = Command::new(env!("CARGO_BIN_EXE_strata"))
        .args(args)
        .arg("--ignore-space-check")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn strata");
    // The atomic writer's temporary file, `.big.ply.<random>.tmp`, grows as blocks of
    // samples are written.
    let started = Instant::now();
    let mut written = 0;
    while started.elapsed() < Duration::from_secs(60) && written < (1 << 20) {
        if let Some(status) = child.try_wait().expect("poll strata") {
            panic!("strata ended ({status}) before writing a MiB");
        }
        written = std::fs::read_dir(dir.path())
            .expect("read dir")
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().starts_with(".big.ply."))
            .filter_map(|e| e.metadata().ok())
            .map(|m| m.len())
            .sum();
        std::thread::sleep(Duration::from_millis(20));
    }
    child.kill().expect("stop strata");
    child.wait().expect("reap strata");
    assert!(
        written >= 1 << 20,
        "with the flag it writes: {written} bytes"
    );
}

/// Sizes of the atomic writer's temporary files for `name` in `dir`.
fn temporary_bytes(dir: &std::path::Path, name: &str) -> Option<u64> {
    let prefix = format!(".{name}.");
    std::fs::read_dir(dir)
        .expect("read dir")
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().starts_with(&prefix))
        .map(|e| e.metadata().map_or(0, |m| m.len()))
        .reduce(|a, b| a + b)
}

#[test]
fn an_interrupted_write_leaves_no_temporary_file() {
    for signal in ["-INT", "-TERM"] {
        let dir = tempfile::tempdir().expect("tempdir");
        let scene = dir.path().join("scene.ron");
        std::fs::write(
            &scene,
            "(mesh: Shape(Plane(size: 1.0, resolution: 2)), sampling: (count: 10, seed: 1))",
        )
        .expect("write scene");
        let out = dir.path().join("big.ply");
        std::fs::write(&out, "the old file").expect("write old output");
        let child = Command::new(env!("CARGO_BIN_EXE_strata"))
            .args(["sample", scene.to_str().expect("utf-8"), "-n", "1000000000"])
            .args(["-o", out.to_str().expect("utf-8"), "--ignore-space-check"])
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("spawn strata");
        let started = Instant::now();
        while temporary_bytes(dir.path(), "big.ply").unwrap_or(0) < 1 << 20 {
            assert!(
                started.elapsed() < Duration::from_secs(60),
                "{signal}: no write began"
            );
            std::thread::sleep(Duration::from_millis(10));
        }
        let sent = Command::new("kill")
            .args([signal, &child.id().to_string()])
            .status()
            .expect("run kill");
        assert!(sent.success());
        let ended = child.wait_with_output().expect("wait for strata");
        let err = String::from_utf8_lossy(&ended.stderr);
        assert_eq!(ended.status.code(), Some(130), "{signal}: {err}");
        assert!(err.contains("interrupted"), "{signal}: {err}");
        assert_eq!(temporary_bytes(dir.path(), "big.ply"), None, "{signal}");
        assert_eq!(
            std::fs::read_to_string(&out).expect("old output"),
            "the old file",
            "{signal}: the old output stays"
        );
    }
}
