//! Fuzz-style tests on stable Rust (issue 22): seeded random mutations of valid inputs
//! for every reader of user files, each case run under `catch_unwind`.
//!
//! Covers the OBJ reader (its parallel path too, on 3 MB files), the PLY mesh reader
//! (ASCII, binary little- and big-endian), the sample PLY reader, RON scene files
//! (`SceneConfig::from_ron` and `validate` only: a mutated scene is never built, its
//! preprocessing may legitimately take long) and field files (`parse_field_file`). A
//! mutated mesh that parses is checked and, below `FIELD_MAX_FACES` faces, gets a
//! constant and a curvature field built on it. Every case must end in `Ok` or a typed
//! error (mesh and scene errors naming the file) within `SLOW_CASE`; huge declared
//! counts must fail fast and, on Unix, within 4 GiB of address space.
//!
//! Mutations (`mutate`), one to three per case: bit flips, interesting bytes, inserted
//! and deleted runs, a duplicated line, a truncation, a number replaced by an extreme
//! one or a small integer, a word replaced by a keyword of the format, a 4-byte word
//! replaced by an extreme integer or float. Case `c` draws everything from
//! `Rng::new(run seed, c)`, so it reproduces alone. `STRATA_FUZZ_SCALE=100` runs 100
//! times the cases (the same first ones); unoptimised builds run a tenth.
//!
//! A failing case (panic, broken invariant, slower than `SLOW_CASE`) is saved to
//! `tests/data/fuzz/<run>-<case>.bin` and reported with its seed input and mutations.
//! Reproduce with `cargo test --release -p strata-tests --test integration fuzz`; fix
//! the reader, then keep the file, renamed `<kind>-<what it tests>.bin`, as a
//! regression input: `pinned_inputs_end_in_ok_or_a_typed_error` reads every file there
//! with the reader its name starts with (`obj`, `ply`, `samples`, `ron`, `field`).

use std::fmt::Write as _;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

use clap::Parser;
use glam::DVec3;
use strata_engine::field::{FieldSpec, format_field_file, parse_field_file};
use strata_engine::fixtures::oblique;
use strata_engine::io;
use strata_engine::mesh::{MeshError, TriMesh, shapes};
use strata_engine::rng::Rng;
use strata_engine::sample::Sample;
use strata_systems::config::SceneConfig;
use strata_tests::{config_files, corpus_dir};

/// Meshes with fewer faces than this that survive a mutation get fields built on them.
const FIELD_MAX_FACES: usize = 2_000;
/// A case slower than this is a failure (inputs are a few kilobytes, or 3 MB for the
/// OBJ reader's parallel path).
const SLOW_CASE: Duration = Duration::from_secs(2);
/// Failing inputs saved per run (the first ones; the rest are only reported).
const MAX_SAVED: usize = 5;
/// Bytes that mean something to one of the formats.
const INTERESTING: &[u8] = b"\x00\xff-.e9\n #/)(";
/// Numbers at the edges of what the readers' number types hold (space-separated).
const EXTREME_NUMBERS: &str = "1e309 1e308 -1e-308 5e-324 -0 nan inf 18446744073709551616 \
                               4294967296 -1 0";
/// 4-byte words for binary bodies: 0, -1, `i32::MIN`, `i32::MAX`, and the `f32` bits of
/// infinity, NaN and 2^32.
#[rustfmt::skip]
const EXTREME_WORDS: [u32; 7] = [0, !0, 1 << 31, !0 >> 1, 0x7f80_0000, 0x7fc0_0000, 0x4f80_0000];

/// Which reader a case goes to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Obj,
    Ply,
    Samples,
    Ron,
    Field,
    Args,
}

impl Kind {
    /// The kind whose name (as `Debug` writes it, in lower case) `name` starts with,
    /// up to its first `-`: how pinned files say which reader they are for.
    fn from_file_name(name: &str) -> Option<Kind> {
        let prefix = name.split('-').next()?;
        [
            Kind::Obj,
            Kind::Ply,
            Kind::Samples,
            Kind::Ron,
            Kind::Field,
            Kind::Args,
        ]
        .into_iter()
        .find(|k| format!("{k:?}").to_lowercase() == prefix)
    }

    /// Words of the format, swapped in for a word of the input by `mutate`.
    fn words(self) -> Vec<&'static str> {
        let words = match self {
            Kind::Obj => "v vt vn f l o g usemtl -1/-1 1//1 1/1/1/1",
            Kind::Ply | Kind::Samples => {
                "element property list uchar int uint double float vertex face tristrips \
                 vertex_indices end_header ascii binary_big_endian binary_little_endian \
                 comment x nx index"
            }
            Kind::Ron => {
                "Shape File Plane Sphere Torus Genus2 Constant Planar Warp Curvature Designed \
                 Smoothest Direction Vertex Point Some None () [] {} \"\" true mesh field \
                 sampling count seed"
            }
            Kind::Field => "t strata-field 1 # \u{feff}",
            Kind::Args => {
                "sample segment field bench render view watch analyze scene -n -o --out \
                 --seed --count --threads --order progressive --field smooth curvature \
                 uniform direction:1,0,0 --anisotropy --density-from --no-out --report \
                 --width --height --lod --style strokes --brush -- - = 0 -1"
            }
        };
        words.split_ascii_whitespace().collect()
    }

    /// Reads `bytes` with this kind's reader: `Ok(true)` if they parse, `Ok(false)` for a
    /// typed error, `Err` for a broken invariant (a panic is caught by the caller).
    fn check(self, bytes: &[u8]) -> Result<bool, String> {
        match self {
            Kind::Obj => check_mesh(io::parse_obj(bytes, Path::new("fuzz.obj")), "fuzz.obj"),
            Kind::Ply => check_mesh(io::parse_ply(bytes, Path::new("fuzz.ply")), "fuzz.ply"),
            Kind::Samples => match io::parse_samples_ply(bytes, Path::new("fuzz.ply")) {
                Ok(_) => Ok(true),
                Err(e) => names_file(&e, "fuzz.ply"),
            },
            Kind::Ron => check_scene(bytes),
            Kind::Field => check_field_file(bytes),
            Kind::Args => check_args(bytes),
        }
    }
}

/// `Ok(false)` if the message of `e` names `file`.
fn names_file(e: &impl std::fmt::Display, file: &str) -> Result<bool, String> {
    let message = e.to_string();
    if message.contains(file) {
        Ok(false)
    } else {
        Err(format!("the error does not name the file: {message}"))
    }
}

/// A parsed mesh must be valid and take fields; an error must name the file.
fn check_mesh(result: Result<TriMesh, MeshError>, file: &str) -> Result<bool, String> {
    let mesh = match result {
        Ok(mesh) => mesh,
        Err(e) => return names_file(&e, file),
    };
    let n = mesh.vertex_count();
    if mesh.face_count() == 0 || !mesh.positions().iter().all(|p| p.is_finite()) {
        return Err("a mesh without faces or with a non-finite position".to_owned());
    }
    if mesh.triangles().iter().flatten().any(|&v| v as usize >= n) {
        return Err("a triangle index out of range".to_owned());
    }
    if mesh.face_count() < FIELD_MAX_FACES {
        for spec in [constant_field(), FieldSpec::default_curvature()] {
            // Either outcome is fine (a mutated mesh may be too degenerate for a field);
            // a field that builds must have one finite tensor per vertex.
            if let Ok(field) = spec.build(&mesh)
                && (field.tensors().len() != n || !field.tensors().iter().all(|t| t.is_finite()))
            {
                return Err(format!(
                    "{spec:?} built a field that is not one finite tensor per vertex"
                ));
            }
        }
    }
    Ok(true)
}

/// A scene that parses must still validate (`from_ron` validates before resolving its
/// paths); an error must name the file.
fn check_scene(bytes: &[u8]) -> Result<bool, String> {
    let text = String::from_utf8_lossy(bytes);
    match SceneConfig::from_ron(&text, Path::new("configs/fuzz.ron")) {
        Ok(scene) => {
            scene
                .validate()
                .map_err(|e| format!("from_ron passed a scene validate fails: {e}"))?;
            // A designed field that parses is built on a small mesh: a field or an error.
            // On a pool of its own, so that other tests' work on the global pool does not
            // hold it past `SLOW_CASE`.
            if matches!(scene.field, FieldSpec::Designed(_))
                && scene.field.files().is_empty()
                && let Ok(field) = own_pool().install(|| scene.field.build(&field_meshes()[1]))
                && !field.tensors().iter().all(|t| t.is_finite())
            {
                return Err("a designed field with a non-finite tensor".to_owned());
            }
            Ok(true)
        }
        Err(e) => names_file(&e, "fuzz.ron"),
    }
}

/// A command line (the bytes split at white space) parses or gives clap's error, and
/// one that parses as a mesh's `--field` flags gives a field or a one-line error.
fn check_args(bytes: &[u8]) -> Result<bool, String> {
    let text = String::from_utf8_lossy(bytes);
    let argv = std::iter::once("strata").chain(text.split_whitespace());
    match strata_systems::cli::Cli::try_parse_from(argv) {
        Ok(cli) => {
            if let strata_systems::cli::Command::Scene(args) = &cli.command
                && let Err(e) = args.input.field_spec()
                && strata_systems::cli::one_line(&e).contains('\n')
            {
                return Err(format!("a mesh flag's error spans lines: {e}"));
            }
            Ok(true)
        }
        Err(e) if e.to_string().is_empty() => Err("clap gave an empty error".to_owned()),
        Err(_) => Ok(false),
    }
}

/// A one-thread pool for the fields that scene cases build.
fn own_pool() -> &'static rayon::ThreadPool {
    static POOL: OnceLock<rayon::ThreadPool> = OnceLock::new();
    POOL.get_or_init(|| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .expect("a one-thread pool")
    })
}

/// A field file on each of the field meshes: a field that parses has one tensor per
/// vertex.
fn check_field_file(bytes: &[u8]) -> Result<bool, String> {
    let text = String::from_utf8_lossy(bytes);
    let mut parsed = false;
    for mesh in field_meshes() {
        if let Ok(field) = parse_field_file(&text, Path::new("fuzz.field"), mesh) {
            if field.tensors().len() != mesh.vertex_count() {
                return Err("a field with the wrong number of tensors".to_owned());
            }
            parsed = true;
        }
    }
    Ok(parsed)
}

/// A constant anisotropic field.
fn constant_field() -> FieldSpec {
    oblique(3.0)
}

/// The meshes field files are read on (built once): a plane, a sphere and a tetrahedron.
fn field_meshes() -> &'static [TriMesh] {
    static MESHES: OnceLock<Vec<TriMesh>> = OnceLock::new();
    MESHES.get_or_init(|| {
        let tetrahedron = TriMesh::new(
            vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z],
            vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
        );
        vec![
            shapes::plane(1.0, 3).expect("plane"),
            shapes::sphere(1.0, 1).expect("sphere"),
            tetrahedron.expect("tetrahedron"),
        ]
    })
}

// ---------------------------------------------------------------------------------
// Mutations

/// A uniform index in `0..n` (`n > 0`).
fn below(rng: &mut Rng, n: usize) -> usize {
    rng.below(n as u64) as usize
}

/// Applies one random mutation to `bytes`; its name and position, for the report.
fn mutate(rng: &mut Rng, bytes: &mut Vec<u8>, words: &[&str]) -> String {
    if bytes.is_empty() {
        bytes.push(INTERESTING[below(rng, INTERESTING.len())]);
        return "insert into empty".to_owned();
    }
    let len = bytes.len();
    let at = below(rng, len);
    match below(rng, 9) {
        0 => {
            bytes[at] ^= 1 << below(rng, 8);
            format!("flip@{at}")
        }
        1 => {
            bytes[at] = INTERESTING[below(rng, INTERESTING.len())];
            format!("interesting@{at}")
        }
        2 => {
            let run = (0..1 + below(rng, 16)).map(|_| INTERESTING[below(rng, INTERESTING.len())]);
            let run: Vec<u8> = run.collect();
            bytes.splice(at..at, run);
            format!("insert@{at}")
        }
        3 => {
            let end = (at + 1 + below(rng, 16)).min(len);
            bytes.drain(at..end);
            format!("delete@{at}..{end}")
        }
        4 => {
            let (start, end) = span(bytes, at, |b| b != b'\n');
            let end = (end + 1).min(len); // with its line break
            let line = bytes[start..end].to_vec();
            bytes.splice(end..end, line);
            format!("duplicate-line@{start}")
        }
        5 => {
            bytes.truncate(at);
            format!("truncate@{at}")
        }
        6 => {
            let tokens = number_tokens(bytes);
            if tokens.is_empty() {
                return "no-number".to_owned();
            }
            let (start, end) = tokens[below(rng, tokens.len())];
            // Extreme numbers, or small integers (other vertex indices, counts).
            let extreme: Vec<&str> = EXTREME_NUMBERS.split_ascii_whitespace().collect();
            let number = match below(rng, 3) {
                0 => below(rng, 12).to_string(),
                _ => extreme[below(rng, extreme.len())].to_owned(),
            };
            bytes.splice(start..end, number.bytes());
            format!("number@{start}={number}")
        }
        7 => {
            // The word (letters, digits, `_`) around `at`, or nothing between two.
            let (start, end) = span(bytes, at, |b| b.is_ascii_alphanumeric() || b == b'_');
            let word = words[below(rng, words.len())];
            bytes.splice(start..end, word.bytes());
            format!("word@{start}={word}")
        }
        _ => {
            let word = EXTREME_WORDS[below(rng, EXTREME_WORDS.len())];
            let at = at.min(len.saturating_sub(4));
            let end = (at + 4).min(len);
            let le = word.to_le_bytes();
            bytes[at..end].copy_from_slice(&le[..end - at]);
            format!("u32@{at}={word:#x}")
        }
    }
}

/// The run of bytes around `at` (from `at` on) that are all `inside`.
fn span(bytes: &[u8], at: usize, inside: impl Fn(u8) -> bool) -> (usize, usize) {
    let start = bytes[..at]
        .iter()
        .rposition(|&b| !inside(b))
        .map_or(0, |i| i + 1);
    let end = bytes[at..]
        .iter()
        .position(|&b| !inside(b))
        .map_or(bytes.len(), |i| at + i);
    (start, end)
}

/// Byte ranges of the number-like tokens of `bytes`: runs of `0-9 . e E + -` with a
/// digit in them.
fn number_tokens(bytes: &[u8]) -> Vec<(usize, usize)> {
    let is_number = |b: u8| b.is_ascii_digit() || b"+-.eE".contains(&b);
    let mut tokens = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        if !is_number(bytes[i]) {
            i += 1;
            continue;
        }
        let (start, end) = span(bytes, i, is_number);
        let in_word = start > 0 && bytes[start - 1].is_ascii_alphanumeric()
            || bytes.get(end).is_some_and(u8::is_ascii_alphabetic);
        if !in_word && bytes[start..end].iter().any(u8::is_ascii_digit) {
            tokens.push((start, end));
        }
        i = end;
    }
    tokens
}

// ---------------------------------------------------------------------------------
// The harness

/// A named valid input that cases start from.
struct Seed {
    name: String,
    bytes: Vec<u8>,
}

impl Seed {
    /// The input `bytes`, called `name` in reports.
    fn new(name: impl Into<String>, bytes: impl Into<Vec<u8>>) -> Self {
        Self {
            name: name.into(),
            bytes: bytes.into(),
        }
    }

    /// A file of the project (`tests/data/meshes` or `configs`).
    fn file(path: &Path) -> Self {
        let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        Self::new(path.display().to_string(), bytes)
    }
}

/// Runs `bytes` through `kind`'s reader, turning a panic into an `Err` with its message.
fn run_case(kind: Kind, bytes: &[u8]) -> Result<bool, String> {
    match catch_unwind(AssertUnwindSafe(|| kind.check(bytes))) {
        Ok(result) => result,
        Err(payload) => {
            let text = payload.downcast_ref::<String>().map(String::as_str);
            let message = text.or_else(|| payload.downcast_ref::<&str>().copied());
            Err(format!("panicked: {}", message.unwrap_or("(no message)")))
        }
    }
}

/// Where failing inputs are saved and pinned regression inputs live.
fn fuzz_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/fuzz")
}

/// `cases` mutated inputs from `seeds` through `kind`'s reader; the run `label` names
/// saved files and `seed` keys the random numbers. Fails listing the failing cases.
fn fuzz(label: &str, kind: Kind, seed: u64, seeds: &[Seed], cases: u64) {
    assert!(!seeds.is_empty(), "{label}: no seed inputs");
    for s in seeds {
        assert_eq!(run_case(kind, &s.bytes), Ok(true), "seed {}", s.name);
    }
    // `STRATA_FUZZ_SCALE` times the cases; a tenth in unoptimised builds.
    let scale = std::env::var("STRATA_FUZZ_SCALE").map_or(1, |v| v.parse().unwrap_or(1));
    let cases = (cases * scale / if cfg!(debug_assertions) { 10 } else { 1 }).max(1);
    let words = kind.words();
    let start = Instant::now();
    let mut outcomes = [0u64; 2];
    let mut failures = Vec::new();
    for case in 0..cases {
        let mut rng = Rng::new(seed, case);
        let input = &seeds[below(&mut rng, seeds.len())];
        let mut bytes = input.bytes.clone();
        let ops: Vec<String> = (0..1 + rng.below(3))
            .map(|_| mutate(&mut rng, &mut bytes, &words))
            .collect();
        let began = Instant::now();
        let problem = match (run_case(kind, &bytes), began.elapsed()) {
            (Ok(_), took) if took > SLOW_CASE => format!("took {took:?}"),
            (Ok(parsed), _) => {
                outcomes[usize::from(parsed)] += 1;
                continue;
            }
            (Err(what), _) => what,
        };
        let saved = if failures.len() < MAX_SAVED {
            let path = fuzz_dir().join(format!("{label}-{case}.bin"));
            match std::fs::create_dir_all(fuzz_dir()).and_then(|()| std::fs::write(&path, &bytes)) {
                Ok(()) => format!("saved to {}", path.display()),
                Err(e) => format!("could not be saved to {}: {e}", path.display()),
            }
        } else {
            "not saved (enough saved already)".to_owned()
        };
        failures.push(format!(
            "{label} case {case} (from {}, mutations {ops:?}): {problem}\n    input {saved}",
            input.name
        ));
    }
    println!(
        "fuzz {label}: {cases} cases ({} parse, {} typed errors) in {:.2?}",
        outcomes[1],
        outcomes[0],
        start.elapsed()
    );
    assert!(
        failures.is_empty(),
        "{} of {cases} {label} cases failed (up to 20 listed):\n{}\nReproduce: cargo test \
         --release -p strata-tests --test integration fuzz. Fix the reader, then pin each \
         saved input as tests/data/fuzz/{}-<what it tests>.bin (read by \
         fuzz::pinned_inputs_end_in_ok_or_a_typed_error) and delete the others.",
        failures.len(),
        failures[..failures.len().min(20)].join("\n"),
        format!("{kind:?}").to_lowercase()
    );
    // The damage is neither always fatal nor always harmless (given enough cases).
    let mixed = outcomes.iter().all(|&n| n > 0);
    assert!(mixed || cases < 50, "{label}: {outcomes:?}");
}

// ---------------------------------------------------------------------------------
// Seed inputs

/// `mesh` as OBJ text: positions, and faces with texture and normal indices (one `vt`
/// and one `vn` per vertex), positive or negative (relative).
fn obj_text(mesh: &TriMesh, relative: bool) -> String {
    let mut out = String::from("# generated\no shape\n");
    for p in mesh.positions() {
        let [x, y, z] = p.to_array();
        let _ = writeln!(out, "v {x} {y} {z}\nvt {x} {y}\nvn 0 0 1");
    }
    let n = mesh.vertex_count() as i64;
    for t in mesh.triangles() {
        out.push('f');
        for &v in t {
            let i = i64::from(v) + if relative { -n } else { 1 };
            let _ = write!(out, " {i}/{i}/{i}");
        }
        out.push('\n');
    }
    out
}

/// `mesh` as big-endian PLY with `double` coordinates and `uint` indices (the writer
/// writes little-endian `float` and `int`).
fn big_endian_ply(mesh: &TriMesh) -> Vec<u8> {
    let (v, f) = (mesh.vertex_count(), mesh.face_count());
    let mut out = format!(
        "ply\nformat binary_big_endian 1.0\nelement vertex {v}\nproperty double x\n\
         property double y\nproperty double z\nelement face {f}\n\
         property list uchar uint vertex_indices\nend_header\n"
    )
    .into_bytes();
    for c in mesh.positions().iter().flat_map(|p| p.to_array()) {
        out.extend(c.to_be_bytes());
    }
    for t in mesh.triangles() {
        out.push(3);
        t.iter().for_each(|i| out.extend(i.to_be_bytes()));
    }
    out
}

/// Files of `tests/data/meshes`.
fn corpus_seeds(names: &str) -> Vec<Seed> {
    names
        .split_ascii_whitespace()
        .map(|name| Seed::file(&corpus_dir().join(name)))
        .collect()
}

fn obj_seeds() -> Vec<Seed> {
    let mut seeds = corpus_seeds("cube.obj tetrahedron.obj open-disk.obj two-components.obj");
    let sphere = shapes::sphere(1.0, 2).expect("shape");
    seeds.push(Seed::new("sphere(1, 2), v/vt/vn", obj_text(&sphere, false)));
    let plane = shapes::plane(1.0, 3).expect("shape");
    seeds.push(Seed::new("plane(1, 3), relative", obj_text(&plane, true)));
    seeds
}

fn ply_seeds(binary: bool) -> Vec<Seed> {
    let sphere = shapes::sphere(1.0, 1).expect("shape");
    let plane = shapes::plane(1.0, 2).expect("shape");
    if !binary {
        return corpus_seeds("tetrahedron-ascii.ply extras-ascii.ply strips.ply");
    }
    let mut little = Vec::new();
    io::write_mesh_ply_to(&mut little, &sphere, None).expect("write");
    let colours: Vec<[u8; 3]> = (0..plane.face_count()).map(|f| [f as u8, 7, 200]).collect();
    let mut coloured = Vec::new();
    io::write_mesh_ply_to(&mut coloured, &plane, Some(&colours)).expect("write");
    vec![
        Seed::new("sphere(1, 1) binary little-endian", little),
        Seed::new("plane(1, 2) with colours", coloured),
        Seed::new("sphere(1, 1) big-endian", big_endian_ply(&sphere)),
    ]
}

fn samples_seeds() -> Vec<Seed> {
    let samples: Vec<Sample> = (0..12u32)
        .map(|i| {
            let t = i as f32 * 0.37;
            Sample {
                position: [t.sin(), t.cos(), t * 0.1],
                major_axis: [t.cos(), -t.sin(), 0.0],
                face: i * 7,
                index: i,
                spacing: [0.01 + t, 0.02],
                ..Sample::default()
            }
        })
        .collect();
    let mut binary = Vec::new();
    io::write_samples_ply_to(&mut binary, &samples).expect("write");
    let mut ascii = String::from(
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
         property float z\nproperty list uchar int extra\nproperty uint face\nend_header\n",
    );
    for (i, s) in samples.iter().take(4).enumerate() {
        let [x, y, z] = s.position;
        let _ = writeln!(ascii, "{x} {y} {z} 2 -1 {i} {}", s.face);
    }
    vec![Seed::new("12 binary", binary), Seed::new("4 ascii", ascii)]
}

fn ron_seeds() -> Vec<Seed> {
    let mut seeds: Vec<Seed> = config_files().iter().map(|path| Seed::file(path)).collect();
    // Designed fields with every kind of guidance, constraint and source.
    seeds.push(Seed::new(
        "designed with constraints",
        "(mesh: Shape(Sphere(radius: 1.0, resolution: 2)), field: Designed(guidance: \
         Direction((0.0, 1.0, 0.5)), weight: 2.0, smoothness: 0.5, constraints: [(at: \
         Vertex(3), direction: (1.0, 0.0, 0.0)), (at: Point(0.0, 1.0, 0.0), direction: \
         (0.0, 0.0, 1.0))], anisotropy: Curvature(min: 1.0, max: 4.0), density: \
         Curvature(floor: 0.5)))",
    ));
    seeds.push(Seed::new(
        "designed smoothest",
        "(mesh: Shape(Torus(major_radius: 1.0, minor_radius: 0.4, resolution: 2)), field: \
         Designed(guidance: Smoothest, anisotropy: Constant(2.0), cancel_distance: 0.5))",
    ));
    seeds
}

fn args_seeds() -> Vec<Seed> {
    [
        "sample configs/default.ron -n 100 --seed 3 -o out.ply --order progressive",
        "sample mesh.obj --field direction:1,0,0 --anisotropy 3 --no-out",
        "scene mesh.ply --field curvature --density-from d.field",
        "render s.ron -o r.png --width 64 --height 48 --lod --lod-max 2 --frames 2",
        "analyze s.ron -o out -n 64 --runs 2 --epsilon 5 --no-plots",
        "segment s.ron -o seg.ply --report r.json --atlas a.svg --seed 4",
    ]
    .into_iter()
    .map(|line| Seed::new(line, line))
    .collect()
}

fn field_seeds() -> Vec<Seed> {
    let meshes = field_meshes();
    let on_plane = constant_field().build(&meshes[0]).expect("constant field");
    let on_sphere = FieldSpec::default_curvature()
        .build(&meshes[1])
        .expect("curvature");
    let tetrahedron = "\u{feff}# eigenvalues and a direction\nstrata-field 1\n\n4.0 0.25 1 0 0\n\
                       1 1 0 1 0 # isotropic\n2.5e-1 4 0 0 1\nt 1 0 0 1 0 1\n";
    vec![
        Seed::new("constant on plane(1, 3)", format_field_file(&on_plane)),
        Seed::new("curvature on sphere(1, 1)", format_field_file(&on_sphere)),
        Seed::new("frames on the tetrahedron", tetrahedron),
    ]
}

// ---------------------------------------------------------------------------------
// Tests

#[test]
fn fuzz_obj_meshes() {
    fuzz("obj", Kind::Obj, 1, &obj_seeds(), 20_000);
}

#[test]
fn fuzz_ply_meshes() {
    fuzz("ply-ascii", Kind::Ply, 2, &ply_seeds(false), 10_000);
    fuzz("ply-binary", Kind::Ply, 3, &ply_seeds(true), 10_000);
}

/// Files of 2 MiB and more take the OBJ reader's parallel path (`obj_chunks`), which
/// hands anything unusual to the sequential one.
#[test]
fn fuzz_large_obj_parallel_path() {
    let sphere = shapes::sphere(1.0, 40).expect("shape");
    let seeds = [false, true].map(|relative| {
        let name = format!("sphere(1, 40), relative indices {relative}");
        Seed::new(name, obj_text(&sphere, relative))
    });
    assert!(seeds.iter().all(|s| s.bytes.len() > 2 << 20));
    fuzz("obj-large", Kind::Obj, 7, &seeds, 60);
}

#[test]
fn fuzz_samples_ply() {
    fuzz("samples", Kind::Samples, 4, &samples_seeds(), 10_000);
}

#[test]
fn fuzz_scene_ron() {
    fuzz("ron", Kind::Ron, 5, &ron_seeds(), 20_000);
}

#[test]
fn fuzz_command_lines() {
    fuzz("args", Kind::Args, 8, &args_seeds(), 5_000);
}

#[test]
fn fuzz_field_files() {
    fuzz("field", Kind::Field, 6, &field_seeds(), 10_000);
}

/// PLY element declarations (`XYZ` stands for float `x y z` properties, `FACE` for a
/// `vertex_indices` list) that declare far more than any body here holds.
const HUGE_PLY_ELEMENTS: [&str; 7] = [
    "element vertex 4000000000\nXYZ",
    "element vertex 18446744073709551615\nXYZelement face 1\nFACE",
    "element vertex 3\nXYZelement face 4294967296\nFACE",
    "element vertex 3\nXYZelement tristrips 4000000000\nproperty list int int vertex_indices\n",
    "element vertex 3\nXYZelement face 1\nproperty list uint int vertex_indices\n",
    "element junk 4000000000\nproperty list uint double a\nelement vertex 3\nXYZ",
    "element vertex 4000000000\nXYZproperty list uint float normal\nproperty uint face\n",
];

/// Every `HUGE_PLY_ELEMENTS` header in each encoding, with a short body (three vertices,
/// then a list length of `u32::MAX`), through the mesh and the sample reader; an OBJ
/// index past `u64`; a scene asking for `u64::MAX` samples. Each must end in a typed
/// error (the scene may parse) within a second.
#[test]
fn huge_declared_counts_fail_fast() {
    const XYZ: &str = "property float x\nproperty float y\nproperty float z\n";
    const FACE: &str = "property list uchar int vertex_indices\n";
    // (what, reader, bytes, whether the input may parse)
    let mut cases: Vec<(String, Kind, Vec<u8>, bool)> = Vec::new();
    for elements in HUGE_PLY_ELEMENTS {
        let elements = elements.replace("XYZ", XYZ).replace("FACE", FACE);
        for format in ["ascii", "binary_little_endian", "binary_big_endian"] {
            let mut bytes =
                format!("ply\nformat {format} 1.0\n{elements}end_header\n").into_bytes();
            if format == "ascii" {
                bytes.extend(b"0 0 0\n1 0 0\n0 1 0\n4294967295 0 1\n");
            } else {
                let big = format == "binary_big_endian";
                let word = |w: u32| [w.to_le_bytes(), w.to_be_bytes()][usize::from(big)];
                (0..9).for_each(|i| bytes.extend(word(f32::to_bits(i as f32))));
                bytes.extend([word(u32::MAX), word(0), word(1)].concat());
            }
            let name = format!("{format} `{}`", elements.replace('\n', "; "));
            // The sample reader reads no faces: three vertices are a valid sample file.
            let samples_parse = elements.starts_with("element vertex 3\n");
            cases.push((name.clone(), Kind::Ply, bytes.clone(), false));
            cases.push((name, Kind::Samples, bytes, samples_parse));
        }
    }
    let obj = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4294967296\nf 1 2 18446744073709551616\n";
    cases.push(("OBJ index past u32".into(), Kind::Obj, obj.to_vec(), false));
    let scene = "(mesh: Shape(Sphere(radius: 1.0, resolution: 4294967295)), \
                 sampling: (count: 18446744073709551615))";
    cases.push(("u64::MAX samples".into(), Kind::Ron, scene.into(), true));
    for (name, kind, bytes, may_parse) in cases {
        let start = Instant::now();
        match run_case(kind, &bytes) {
            Ok(parsed) => assert!(may_parse || !parsed, "{kind:?} {name}: parsed"),
            Err(what) => panic!("{kind:?} {name}: {what}"),
        }
        let took = start.elapsed();
        assert!(took.as_secs_f64() < 1.0, "{kind:?} {name}: took {took:?}");
    }
}

/// Runs `huge_declared_counts_fail_fast` again in a child process limited to 4 GiB of
/// address space: a reader that reserved memory for a declared count would abort it.
#[cfg(unix)]
#[test]
fn huge_declared_counts_fit_in_4_gib() {
    let exe = std::env::current_exe().expect("test binary");
    let output = std::process::Command::new("sh")
        .arg("-c")
        .arg("ulimit -v 4194304 && exec \"$0\" \"$@\"")
        .arg(&exe)
        .args(["fuzz::huge_declared_counts_fail_fast", "--exact"])
        .env("RAYON_NUM_THREADS", "2")
        .output()
        .expect("run the test binary under `sh`");
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(
        output.status.success() && stdout.contains("1 passed"),
        "{:?}\n{stdout}\n{}",
        output.status,
        String::from_utf8_lossy(&output.stderr)
    );
}

/// Every pinned input (`tests/data/fuzz/<kind>-*.bin`, inputs that once crashed a
/// reader) ends in `Ok` or a typed error.
#[test]
fn pinned_inputs_end_in_ok_or_a_typed_error() {
    assert_eq!(Kind::from_file_name("ply-ascii-17.bin"), Some(Kind::Ply));
    let Ok(entries) = std::fs::read_dir(fuzz_dir()) else {
        return; // nothing pinned yet
    };
    let mut paths: Vec<PathBuf> = entries.filter_map(|e| e.ok().map(|e| e.path())).collect();
    paths.sort();
    let mut failures = Vec::new();
    for path in &paths {
        let name = path.file_name().unwrap_or_default().to_string_lossy();
        let Some(kind) = Kind::from_file_name(&name) else {
            failures.push(format!("{name}: starts with no kind (obj, ply, ...)"));
            continue;
        };
        let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        if let Err(what) = run_case(kind, &bytes) {
            failures.push(format!("{name}: {what}"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
