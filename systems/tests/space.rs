//! `strata sample --ignore-space-check`, run as a user runs it: a request whose file
//! cannot fit in its folder's free space is refused before any work, naming the flag;
//! with the flag the same request starts drawing and writing (the test stops it once
//! the file grows, long before the disk fills).

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
