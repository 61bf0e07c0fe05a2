//! The `strata` command-line tool: the clap [`Cli`], [`run`], and one file per
//! command holding its arguments and their handling (`sample`, `segment`, `field`,
//! `bench`, `watch`, `render`, `view`, `analyze`; `look` holds the camera and look
//! options that `render` and `view` share, `lod` their level-of-detail options,
//! `style` their `--style` and `--brush`).
//! What a command does beyond reading its arguments and printing its results lives in
//! the library: [`crate::scene`], [`crate::report`], [`crate::hot_reload`],
//! [`crate::gpu`] and [`crate::viewer`].

/// Prints a status line (what was written, timings): on stdout, or on stderr when an
/// output of this run is the process's standard output (`--out /dev/stdout`), so that
/// the data written there stays whole.
macro_rules! say {
    ($($arg:tt)*) => {
        if $crate::cli::status_on_stderr() {
            eprintln!($($arg)*);
        } else {
            println!($($arg)*);
        }
    };
}

mod analyze;
mod bench;
mod field;
mod input;
pub mod interrupt;
mod lod;
mod look;
mod render;
mod sample;
mod segment;
mod style;
mod view;
mod watch;

use std::path::Path;
use strata_engine::io::SampleFormat;

use anyhow::bail;
use clap::{Parser, Subcommand};

pub use analyze::AnalyzeArgs;
pub use bench::{BenchArgs, BenchReport};
pub use field::FieldArgs;
pub use input::{FieldChoice, MeshFieldArgs, SceneArgs, scene_ron};
pub use lod::LodArgs;
pub use look::LookArgs;
pub use render::RenderArgs;
pub use sample::SampleArgs;
pub use segment::SegmentArgs;
pub use style::StyleArgs;
pub use view::{ViewArgs, view_options};
pub use watch::WatchArgs;

/// strata: anisotropic, density-controlled stratified sampling of surfaces.
///
/// Every command takes a scene file (RON) or a mesh (OBJ or PLY) with uniform density;
/// `strata scene <mesh>` writes the scene a mesh and its flags stand for.
#[derive(Debug, Parser)]
#[command(name = "strata", version)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Sample a scene or a mesh and write the samples (PLY or CSV; beside the input by
    /// default).
    Sample(SampleArgs),
    /// Segment a scene's mesh along its field; write the mesh coloured by segment.
    Segment(SegmentArgs),
    /// Build a scene's field and find its singularities; write the field as a PLY mesh.
    Field(FieldArgs),
    /// Preprocess a scene once, resample it several times, and report timings and memory.
    Bench(BenchArgs),
    /// Sample a scene and draw it as field-aligned splats into a PNG, without a window.
    Render(RenderArgs),
    /// Open a window that resamples and draws the scene every frame (orbit camera).
    View(ViewArgs),
    /// Watch a scene file: recompute what each change invalidates, print per stage what
    /// reran, rewrite the samples file atomically after each change.
    Watch(WatchArgs),
    /// Measure samples: discrepancy, spectra, differential domain analysis (JSON + PNG).
    Analyze(AnalyzeArgs),
    /// Print the scene file (RON) that a mesh and its `--field` flags stand for.
    Scene(SceneArgs),
}

impl Command {
    /// Whether the command opens a GPU (`render`, `view`).
    pub fn opens_gpu(&self) -> bool {
        matches!(self, Self::Render(_) | Self::View(_))
    }

    /// Whether the command writes a sample file whose size grows with the count
    /// (`sample`), and so stops cleanly on Ctrl-C ([`interrupt`]).
    pub fn writes_samples(&self) -> bool {
        matches!(self, Self::Sample(_))
    }
}

/// Whether `error` comes from writing to a closed pipe (a reader that stopped early).
pub fn is_broken_pipe(error: &anyhow::Error) -> bool {
    error.chain().any(|cause| {
        cause
            .downcast_ref::<std::io::Error>()
            .is_some_and(|e| e.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// Gives the GPU drivers a private runtime folder when `XDG_RUNTIME_DIR` is unset or
/// not a folder (containers, CI), so that Mesa does not print its complaint about it:
/// runs this program again with `XDG_RUNTIME_DIR` set to `<temp>/strata-runtime-<uid>`
/// (mode 0700). Returns only if that is not needed or not possible.
pub fn ensure_runtime_dir() {
    use std::os::unix::fs::PermissionsExt;
    use std::os::unix::process::CommandExt;
    const VAR: &str = "XDG_RUNTIME_DIR";
    if std::env::var_os(VAR).is_some_and(|d| Path::new(&d).is_dir()) {
        return;
    }
    let uid = rustix::process::getuid().as_raw();
    let dir = std::env::temp_dir().join(format!("strata-runtime-{uid}"));
    let made = std::fs::create_dir_all(&dir)
        .and_then(|()| std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o700)));
    let Ok(exe) = std::env::current_exe() else {
        return;
    };
    if made.is_ok() {
        // `exec` returns only on failure; then this process goes on as it is.
        let _ = std::process::Command::new(exe)
            .args(std::env::args_os().skip(1))
            .env(VAR, &dir)
            .exec();
    }
}

/// An error and its causes in one line, joined by `": "`, leaving out causes whose
/// text the line already holds (our error messages often quote their source).
pub fn one_line(error: &anyhow::Error) -> String {
    let mut line = error.to_string();
    for cause in error.chain().skip(1) {
        let text = cause.to_string();
        if !line.contains(&text) {
            line.push_str(": ");
            line.push_str(&text);
        }
    }
    line
}

/// Runs a parsed command line.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Sample(args) => sample::run(&args),
        Command::Segment(args) => segment::run(&args),
        Command::Field(args) => field::run(&args),
        Command::Bench(args) => bench::run(&args),
        Command::Render(args) => render::run(&args),
        Command::View(args) => view::run(&args),
        Command::Watch(args) => watch::run(&args),
        Command::Analyze(args) => analyze::run(&args),
        Command::Scene(args) => input::run_scene(&args),
    }
}

/// Set when an output of this run is the process's standard output (see `say!`).
static STATUS_ON_STDERR: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Whether status lines go to stderr: an output of this run is the process's standard
/// output.
pub fn status_on_stderr() -> bool {
    STATUS_ON_STDERR.load(std::sync::atomic::Ordering::Relaxed)
}

/// Whether `path` is the file, device or pipe that this process's standard output is
/// (`/dev/stdout`, `/proc/self/fd/1`, or the pipe's own name).
fn is_own_stdout(path: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    let (Ok(meta), Ok(out)) = (
        std::fs::metadata(path),
        rustix::fs::fstat(std::io::stdout()),
    ) else {
        return false;
    };
    meta.dev() == out.st_dev && meta.ino() == out.st_ino
}

/// Writes `bytes` to `path` atomically ([`strata_engine::io::write_atomically`]).
fn write_file(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    strata_engine::io::write_atomically(path, |w| std::io::Write::write_all(w, bytes))
}

/// The samples format `path` asks for: `.ply` or `.csv` (any case); binary PLY for a
/// device, pipe or standard output (`/dev/stdout`) whose name has neither.
fn output_kind(path: &Path) -> anyhow::Result<SampleFormat> {
    let ext = path.extension().and_then(|e| e.to_str());
    if is_stream(path) && !ext.is_some_and(|e| matches!(e, "ply" | "csv")) {
        return Ok(SampleFormat::Ply);
    }
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("ply") => Ok(SampleFormat::Ply),
        Some("csv") => Ok(SampleFormat::Csv),
        _ => bail!("{}: output must end in .ply or .csv", path.display()),
    }
}

/// Whether `path` exists and is neither a regular file nor a folder (a device such as
/// `/dev/stdout` on a pipe or terminal, a named pipe), or is this process's standard
/// output (`/dev/stdout` redirected to a file): written whatever its name.
fn is_stream(path: &Path) -> bool {
    std::fs::metadata(path).is_ok_and(|m| !m.is_file() && !m.is_dir()) || is_own_stdout(path)
}

/// Checks an output file before any work: `flag` names the option in messages; its
/// name must end in one of `extensions` (any case; none to accept any), it must not be
/// a folder, and its folder must exist and be writable. A device or pipe that exists
/// (`/dev/null`, `/dev/stdout`, a named pipe) is written as it is, whatever its name;
/// when it is this process's standard output, status lines go to stderr.
fn check_output(path: &Path, flag: &str, extensions: &[&str]) -> anyhow::Result<()> {
    if is_stream(path) {
        if is_own_stdout(path) {
            STATUS_ON_STDERR.store(true, std::sync::atomic::Ordering::Relaxed);
        }
        return Ok(());
    }
    let shown = path.display();
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    if !extensions.is_empty() && !extensions.iter().any(|e| e.eq_ignore_ascii_case(ext)) {
        let names: Vec<String> = extensions.iter().map(|e| format!(".{e}")).collect();
        bail!(
            "{shown}: {flag} writes {}; name the file so",
            names.join(" or ")
        );
    }
    if path.is_dir() {
        bail!("{shown}: {flag} names a folder; give a file name");
    }
    check_folder(path, flag)
}

/// Checks that the folder `path` would be written into exists and is writable.
fn check_folder(path: &Path, flag: &str) -> anyhow::Result<()> {
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if folder.exists() && !folder.is_dir() {
        bail!(
            "{}: {flag}: {} is a file, not a folder",
            path.display(),
            folder.display()
        );
    }
    if !folder.is_dir() {
        bail!(
            "{}: {flag}: the folder {} does not exist",
            path.display(),
            folder.display()
        );
    }
    if rustix::fs::access(folder, rustix::fs::Access::WRITE_OK).is_err() {
        bail!(
            "{}: {flag}: the folder {} is not writable",
            path.display(),
            folder.display()
        );
    }
    Ok(())
}

/// Parses a size in pixels (`--width`, `--height`): at least 1.
fn pixels(text: &str) -> Result<u32, String> {
    match text.parse::<u32>() {
        Ok(0) => Err("must be at least 1 pixel".to_owned()),
        Ok(n) => Ok(n),
        Err(_) => Err(format!(
            "give a whole number of pixels from 1 to {}",
            u32::MAX
        )),
    }
}

/// Refuses to write any of `outputs` that is the scene file `scene` or one of the files
/// it reads (`config`'s mesh and field files): the write would destroy an input.
fn refuse_inputs_as_outputs(
    scene: &Path,
    config: &crate::config::SceneConfig,
    outputs: &[Option<&Path>],
) -> anyhow::Result<()> {
    // Paths that exist, compared canonically (links, `..`, relative paths); an output
    // that does not exist yet is no input.
    let inputs: Vec<_> = std::iter::once(scene.to_path_buf())
        .chain(config.input_files())
        .filter_map(|p| std::fs::canonicalize(p).ok())
        .collect();
    for out in outputs.iter().flatten() {
        if std::fs::canonicalize(out).is_ok_and(|c| inputs.contains(&c)) {
            bail!(
                "{}: is an input of the scene {}; writing there would destroy it, choose another output",
                out.display(),
                scene.display()
            );
        }
    }
    Ok(())
}

/// Refuses a request that does not fit (see [`crate::budget`]), in one line that
/// starts with `what` and ends naming the override `flag`, if there is one.
fn check_budget(
    what: &str,
    fits: Result<(), crate::budget::BudgetError>,
    flag: Option<&str>,
) -> anyhow::Result<()> {
    match (fits, flag) {
        (Ok(()), _) => Ok(()),
        (Err(e @ crate::budget::BudgetError::TooLarge { .. }), Some(flag)) => {
            bail!("{what}: {e}; ask for fewer, or pass {flag} to try anyway")
        }
        (Err(e), _) => bail!("{what}: {e}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn requests_that_do_not_fit_name_their_override() {
        use crate::budget::{Resource, check_fits};
        assert!(check_budget("x", check_fits(1, 64, None, Resource::Memory), None).is_ok());
        let big = || check_fits(100_000_000, 64, Some(2_000_000_000), Resource::Space);
        let e = check_budget("x.ply", big(), Some("--ignore-space-check")).expect_err("6.4 GB");
        assert_eq!(
            e.to_string(),
            "x.ply: 100000000 samples: 6.4 GB needed and 2.0 GB free there; ask for fewer, or pass --ignore-space-check to try anyway"
        );
        // No override for the index limit.
        let e = check_budget(
            "s.ron",
            check_fits(u64::MAX, 1, None, Resource::Space),
            Some("--f"),
        )
        .expect_err("2^64 - 1");
        assert!(!e.to_string().contains("--f"), "{e}");
    }

    #[test]
    fn output_kind_follows_the_extension_in_any_case() {
        assert_eq!(
            output_kind(Path::new("a/s.ply")).ok(),
            Some(SampleFormat::Ply)
        );
        assert_eq!(
            output_kind(Path::new("S.CSV")).ok(),
            Some(SampleFormat::Csv)
        );
        let e = output_kind(Path::new("s.txt")).expect_err("not a samples format");
        assert_eq!(e.to_string(), "s.txt: output must end in .ply or .csv");
        assert!(output_kind(Path::new("ply")).is_err());
    }

    #[test]
    fn one_line_joins_causes_it_does_not_already_quote() {
        let e = anyhow::anyhow!("inner")
            .context("middle: inner")
            .context("outer");
        assert_eq!(one_line(&e), "outer: middle: inner");
    }
}
