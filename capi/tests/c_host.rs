//! The C examples (`examples/c/`) compiled with the system C compiler (`cc`) against
//! `include/strata.h` and the shared library this build made, then run: the bad-input
//! checks pass, and the host's samples hash to the engine's for the same mesh, field
//! and seed (bit for bit), with its build, sampling and level-of-detail lines present.
//! Skipped, with a note, when no C compiler is found.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Arc;

use strata_engine::mesh::shapes;
use strata_engine::sample::Sample;
use strata_engine::surface::{Preprocessed, SurfaceOptions};

/// The folder holding the `libstrata.so` that cargo built with this test binary: the
/// binary's own (`target/<profile>/deps`).
fn library_dir() -> PathBuf {
    let exe = std::env::current_exe().expect("the test binary's path");
    exe.parent().expect("target/<profile>/deps").to_path_buf()
}

/// Compiles `examples/c/<name>.c` into the test's temporary folder; `None` without a
/// C compiler.
fn compile(name: &str, out_dir: &Path) -> Option<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let lib = library_dir();
    assert!(
        lib.join("libstrata.so").exists() || lib.join("libstrata.dylib").exists(),
        "the shared library is built beside the tests in {}",
        lib.display()
    );
    let exe = out_dir.join(name);
    let status = Command::new("cc")
        .arg("-std=c11")
        .arg("-D_POSIX_C_SOURCE=199309L")
        .args(["-O2", "-Wall", "-Wextra", "-Werror", "-I"])
        .arg(root.join("capi/include"))
        .arg(root.join(format!("examples/c/{name}.c")))
        .arg("-L")
        .arg(&lib)
        .arg(format!("-Wl,-rpath,{}", lib.display()))
        .args(["-lstrata", "-lm", "-o"])
        .arg(&exe)
        .status();
    match status {
        Ok(s) if s.success() => Some(exe),
        Ok(s) => panic!("cc failed on examples/c/{name}.c: {s}"),
        Err(e) => {
            eprintln!("note: no C compiler (cc: {e}); the C examples are not checked");
            None
        }
    }
}

fn run(exe: &Path, args: &[&str]) -> String {
    let out = Command::new(exe).args(args).output().expect("runs");
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{} {args:?} failed: {}\n{stdout}\n{}",
        exe.display(),
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}

fn line<'a>(output: &'a str, key: &str) -> &'a str {
    output
        .lines()
        .find_map(|l| l.strip_prefix(key))
        .unwrap_or_else(|| panic!("no `{key}` line in:\n{output}"))
}

/// FNV-1a over the bytes of `samples`, as the host computes it.
fn fnv1a(samples: &[Sample]) -> u64 {
    bytemuck_bytes(samples)
        .iter()
        .fold(0xcbf2_9ce4_8422_2325, |h, &b| {
            (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
        })
}

/// The little-endian bytes of the records, field by field (the host hashes its
/// in-memory records on a little-endian machine).
fn bytemuck_bytes(samples: &[Sample]) -> Vec<u8> {
    let mut bytes = Vec::with_capacity(samples.len() * 64);
    for s in samples {
        let words = [
            s.position[0].to_bits(),
            s.position[1].to_bits(),
            s.position[2].to_bits(),
            s.face,
            s.normal[0].to_bits(),
            s.normal[1].to_bits(),
            s.normal[2].to_bits(),
            s.segment,
            s.major_axis[0].to_bits(),
            s.major_axis[1].to_bits(),
            s.major_axis[2].to_bits(),
            s.index,
            s.bary[0].to_bits(),
            s.bary[1].to_bits(),
            s.spacing[0].to_bits(),
            s.spacing[1].to_bits(),
        ];
        for w in words {
            bytes.extend_from_slice(&w.to_le_bytes());
        }
    }
    bytes
}

#[test]
fn the_c_examples_build_run_and_match_the_engine() {
    let dir = std::env::temp_dir().join(format!("strata-c-host-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a temporary folder");
    let Some(errors) = compile("errors", &dir) else {
        return;
    };
    let out = run(&errors, &[]);
    assert!(!out.contains("FAILED"), "{out}");
    let passed: usize = line(&out, "errors: ")
        .split_whitespace()
        .next()
        .and_then(|n| n.parse().ok())
        .expect("a count");
    assert!(passed >= 40, "{out}");

    let host = compile("host", &dir).expect("cc worked for errors.c");
    // No mesh path: the built-in torus, whose samples the engine draws here too.
    let out = run(&host, &[]);
    assert!(line(&out, "mesh: ").starts_with("built-in torus"), "{out}");
    let mesh = Arc::new(shapes::torus(1.0, 0.4, 48).expect("torus"));
    let spec = strata_engine::field::FieldSpec::Constant {
        direction: [1.0, 0.0, 0.0],
        anisotropy: 2.0,
        density: 1.0,
    };
    let field = Arc::new(spec.build(&mesh).expect("field"));
    let sampler = Preprocessed::build(mesh, field, &SurfaceOptions::default())
        .expect("build")
        .sampler;
    let mut samples = vec![Sample::default(); 10_000];
    sampler.sample_into(11, &mut samples);
    assert_eq!(
        line(&out, "hash: "),
        format!("{:016x}", fnv1a(&samples)),
        "{out}"
    );
    assert!(line(&out, "build: ").contains("longest frame"), "{out}");
    assert!(line(&out, "sampling: ").starts_with("30 frames"), "{out}");
    let lod = line(&out, "lod: ");
    assert!(
        lod.starts_with("40 frames") && !lod.contains("streamed 0 "),
        "{out}"
    );
    assert!(out.ends_with("done\n"), "{out}");
    std::fs::remove_dir_all(&dir).ok();
}
