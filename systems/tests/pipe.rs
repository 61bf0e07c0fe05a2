//! The `strata` binary run as a shell runs it: a reader that closes standard output
//! early (`strata field scene.ron | head -c1`) ends every command quietly, with the
//! status a shell gives a process stopped by a closed pipe and nothing on standard
//! error (no panic); an output that is a device or a named pipe (`-o /dev/stdout`, a
//! FIFO) is written in place and gets the data alone; and `render` run with no
//! `XDG_RUNTIME_DIR` sets up its own, so the driver prints nothing about it.

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

/// A scene of `count` samples on a small sphere, in `dir`.
fn sphere_scene(dir: &std::path::Path, count: u32) -> String {
    let scene = dir.join("scene.ron");
    std::fs::write(
        &scene,
        format!(
            "(mesh: Shape(Sphere(radius: 1.0, resolution: 4)), sampling: (count: {count}, seed: 1))"
        ),
    )
    .expect("write scene");
    scene.to_str().expect("utf-8").to_owned()
}

#[test]
fn samples_written_to_standard_output_come_alone_and_whole() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = sphere_scene(dir.path(), 300);
    let out = Command::new(env!("CARGO_BIN_EXE_strata"))
        .args(["sample", &scene, "-o", "/dev/stdout"])
        .output()
        .expect("run strata");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    // The status lines went to stderr; stdout holds the PLY file and nothing else:
    // the same bytes as a regular file gets.
    assert!(
        err.contains("sampled 300 points") && err.contains("wrote /dev/stdout"),
        "{err}"
    );
    let file = dir.path().join("s.ply");
    let made = Command::new(env!("CARGO_BIN_EXE_strata"))
        .args(["sample", &scene, "-o", file.to_str().expect("utf-8")])
        .output()
        .expect("run strata");
    assert!(made.status.success());
    assert!(String::from_utf8_lossy(&made.stdout).contains("sampled 300 points"));
    assert!(
        out.stdout == std::fs::read(&file).expect("read"),
        "stdout is not the PLY file"
    );
    assert_eq!(
        strata_engine::io::read_samples_ply(&file)
            .expect("samples")
            .len(),
        300
    );
    // `-o /dev/stdout > file`: standard output is a regular file, which gets the same.
    let redirected = dir.path().join("redirected.ply");
    let target = std::fs::File::create(&redirected).expect("create");
    let status = Command::new(env!("CARGO_BIN_EXE_strata"))
        .args(["sample", &scene, "-o", "/dev/stdout"])
        .stdout(target)
        .stderr(Stdio::null())
        .status()
        .expect("run strata");
    assert!(status.success());
    assert!(std::fs::read(&redirected).expect("read") == std::fs::read(&file).expect("read"));
}

#[test]
fn a_reader_that_stops_early_on_standard_output_ends_it_quietly() {
    // `strata sample scene.ron -o /dev/stdout | head -c 4`
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = sphere_scene(dir.path(), 200_000);
    let mut child = Command::new(env!("CARGO_BIN_EXE_strata"))
        .args(["sample", &scene, "-o", "/dev/stdout"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn strata");
    let mut head = [0u8; 4];
    let mut stdout = child.stdout.take().expect("stdout");
    stdout.read_exact(&mut head).expect("read 4 bytes");
    drop(stdout);
    assert_eq!(&head, b"ply\n");
    let mut err = String::new();
    child
        .stderr
        .take()
        .expect("stderr")
        .read_to_string(&mut err)
        .expect("read stderr");
    assert_eq!(child.wait().expect("wait").code(), Some(141), "{err}");
    assert!(!err.contains("panicked") && !err.contains("error"), "{err}");
}

#[test]
fn a_named_pipe_is_written_in_place_whatever_its_name() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = sphere_scene(dir.path(), 100);
    for (command, head) in [("sample", "ply"), ("field", "ply")] {
        let fifo = dir.path().join(format!("{command}-pipe"));
        let made = Command::new("mkfifo").arg(&fifo).status().expect("mkfifo");
        assert!(made.success());
        let reader = {
            let fifo = fifo.clone();
            std::thread::spawn(move || std::fs::read(&fifo).expect("read the pipe"))
        };
        let out = Command::new(env!("CARGO_BIN_EXE_strata"))
            .args([command, &scene, "-o", fifo.to_str().expect("utf-8")])
            .output()
            .expect("run strata");
        assert!(
            out.status.success(),
            "{command}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let bytes = reader.join().expect("reader");
        assert!(bytes.starts_with(head.as_bytes()), "{command}");
        assert!(bytes.len() > 1000, "{command}: {} bytes", bytes.len());
        use std::os::unix::fs::FileTypeExt;
        assert!(
            std::fs::metadata(&fifo)
                .expect("meta")
                .file_type()
                .is_fifo()
        );
    }
}

#[test]
fn render_without_a_runtime_folder_prints_no_driver_complaint() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = sphere_scene(dir.path(), 200);
    let png = dir.path().join("r.png");
    let out = Command::new(env!("CARGO_BIN_EXE_strata"))
        .args(["render", &scene, "-o", png.to_str().expect("utf-8")])
        .args(["--width", "32", "--height", "24"])
        .env_remove("XDG_RUNTIME_DIR")
        .env("TMPDIR", dir.path())
        .output()
        .expect("run strata");
    let err = String::from_utf8_lossy(&out.stderr);
    if !out.status.success() && err.contains("adapter") {
        assert!(
            std::env::var("STRATA_REQUIRE_GPU").as_deref() != Ok("1"),
            "STRATA_REQUIRE_GPU=1 but render found no adapter: {err}"
        );
        use std::io::Write;
        let _ = writeln!(std::io::stderr(), "skipping: no GPU adapter: {err}");
        return;
    }
    assert!(out.status.success(), "{err}");
    assert!(!err.contains("XDG_RUNTIME_DIR"), "{err}");
    // The folder it made for the driver: private to the user.
    use std::os::unix::fs::PermissionsExt;
    let uid = std::fs::metadata("/proc/self").map(|m| std::os::unix::fs::MetadataExt::uid(&m));
    let made = dir
        .path()
        .join(format!("strata-runtime-{}", uid.expect("uid")));
    let mode = std::fs::metadata(&made)
        .expect("runtime folder")
        .permissions()
        .mode();
    assert_eq!(mode & 0o777, 0o700);
    assert!(png.exists());
}
