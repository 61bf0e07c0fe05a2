//! `strata render --sampler auto|cpu|gpu` run as a user runs it (the binary): the GPU's
//! compute passes draw the picture the CPU's samples draw (pixels compared), the status
//! line names the sampler used and why, `auto` keeps the CPU on a software adapter,
//! and `gpu` without any adapter or with `--lod` fails in one line, no panic. Runs on
//! whatever adapter wgpu opens (lavapipe in CI); skipped without one unless
//! `STRATA_REQUIRE_GPU=1`.

use std::path::Path;
use std::process::{Command, Output};

/// Runs `strata render scene -o out --sampler choice extra...` in `d` at 160x120.
fn render(d: &Path, out: &str, choice: &str, extra: &[&str], env: &[(&str, &str)]) -> Output {
    let scene = d.join("scene.ron");
    let out = d.join(out);
    let mut command = Command::new(env!("CARGO_BIN_EXE_strata"));
    command
        .arg("render")
        .arg(&scene)
        .arg("-o")
        .arg(&out)
        .args(["--width", "160", "--height", "120", "--sampler", choice])
        .args(extra);
    for (k, v) in env {
        command.env(k, v);
    }
    command.output().expect("run strata")
}

/// A PNG's RGBA pixels.
fn pixels(path: &Path) -> Vec<[u8; 4]> {
    let file = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .expect("a PNG");
    let mut buf = vec![0; reader.output_buffer_size().expect("size")];
    let info = reader.next_frame(&mut buf).expect("a frame");
    assert_eq!(info.color_type, png::ColorType::Rgba);
    buf[..info.buffer_size()]
        .chunks_exact(4)
        .map(|p| [p[0], p[1], p[2], p[3]])
        .collect()
}

/// Pixels of `a` and `b` whose channels differ by more than 8 of 255.
fn differing(a: &[[u8; 4]], b: &[[u8; 4]]) -> usize {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .filter(|(p, q)| p.iter().zip(q.iter()).any(|(x, y)| x.abs_diff(*y) > 8))
        .count()
}

fn text(out: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn gpu_sampler_draws_the_cpu_picture_and_says_so() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    let scene = "(mesh: Shape(Sphere(radius: 1.0, resolution: 8)), field: Constant(direction: (1.0, 0.3, 0.2), anisotropy: 2.0, density: 1.0), sampling: (count: 3000, seed: 1))";
    std::fs::write(d.join("scene.ron"), scene).expect("write");
    let cpu = render(d, "cpu.png", "cpu", &[], &[]);
    let (out, err) = text(&cpu);
    if !cpu.status.success() {
        assert!(
            std::env::var("STRATA_REQUIRE_GPU").as_deref() != Ok("1")
                && err.contains("no GPU adapter"),
            "render failed: {err}"
        );
        eprintln!("skipped: {err}");
        return;
    }
    assert!(out.contains("sampler cpu (forced)"), "{out}");
    let gpu = render(d, "gpu.png", "gpu", &[], &[]);
    let (out, err) = text(&gpu);
    assert!(gpu.status.success(), "{err}");
    assert!(out.contains("sampler gpu (forced)"), "{out}");
    // Auto: the CPU on a software adapter, the GPU on a real one; the line says which.
    let auto = render(d, "auto.png", "auto", &[], &[]);
    let (out, err) = text(&auto);
    assert!(auto.status.success(), "{err}");
    let software = out.contains("Cpu, driver");
    let want = if software {
        "sampler cpu (auto: software adapter)"
    } else {
        "sampler gpu (auto: hardware adapter)"
    };
    assert!(out.contains(want), "{out}");
    // The same picture from either sampler; another seed draws another one.
    let (c, g) = (pixels(&d.join("cpu.png")), pixels(&d.join("gpu.png")));
    let other = render(d, "seed.png", "cpu", &["--seed", "2"], &[]);
    assert!(other.status.success());
    let seeded = differing(&c, &pixels(&d.join("seed.png")));
    let near = differing(&c, &g);
    eprintln!("cpu against gpu: {near} pixels differ; against another seed: {seeded}");
    assert!(
        near * 1000 <= c.len(),
        "{near} of {} pixels differ",
        c.len()
    );
    assert!(seeded > 10 * near.max(1), "{seeded} against {near}");
    if software {
        assert_eq!(differing(&c, &pixels(&d.join("auto.png"))), 0);
    }
    // Strokes drawn from the GPU's samples too.
    let strokes = render(d, "strokes.png", "gpu", &["--style", "strokes"], &[]);
    let (out, err) = text(&strokes);
    assert!(
        strokes.status.success() && out.contains("sampler gpu"),
        "{err}"
    );
    // Refused in one line: gpu with level of detail, gpu without any adapter.
    for (extra, env, says) in [
        (
            &["--lod"] as &[&str],
            &[] as &[(&str, &str)],
            "--sampler gpu does not apply with --lod",
        ),
        (
            &[],
            &[("WGPU_BACKEND", "dx12")],
            "--sampler gpu needs a GPU",
        ),
    ] {
        let refused = render(d, "no.png", "gpu", extra, env);
        let (_, err) = text(&refused);
        assert_eq!(refused.status.code(), Some(1), "{extra:?}: {err}");
        assert!(err.contains(says) && !err.contains("panicked"), "{err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
    }
}
