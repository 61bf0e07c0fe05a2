//! The `strata` command-line tool: the clap [`Cli`], [`run`], and one file per
//! command holding its arguments and their handling (`sample`, `segment`, `field`,
//! `bench`, `watch`, `render`, `view`, `analyze`; `look` holds the camera and look options that
//! `render` and `view` share). What a command does beyond reading its arguments and
//! printing its results lives in the library: [`crate::scene`], [`crate::report`],
//! [`crate::hot_reload`], [`crate::gpu`] and [`crate::viewer`].

mod analyze;
mod bench;
mod field;
mod look;
mod render;
mod sample;
mod segment;
mod view;
mod watch;

use std::path::Path;
use strata_engine::io::SampleFormat;

use anyhow::bail;
use clap::{Parser, Subcommand};

pub use analyze::AnalyzeArgs;
pub use bench::{BenchArgs, BenchReport};
pub use field::FieldArgs;
pub use look::LookArgs;
pub use render::RenderArgs;
pub use sample::SampleArgs;
pub use segment::SegmentArgs;
pub use view::ViewArgs;
pub use watch::WatchArgs;

/// strata: anisotropic, density-controlled stratified sampling of surfaces.
#[derive(Debug, Parser)]
#[command(name = "strata", version, about)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Sample a scene and optionally write the samples (PLY or CSV).
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
    }
}

/// Writes `bytes` to `path` atomically ([`strata_engine::io::write_atomically`]).
fn write_file(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    strata_engine::io::write_atomically(path, |w| std::io::Write::write_all(w, bytes))
}

/// The samples format `path` asks for: `.ply` or `.csv` (any case).
fn output_kind(path: &Path) -> anyhow::Result<SampleFormat> {
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

/// The space the file system of `path`'s folder can still give to this user, in
/// bytes; `None` where it cannot be read.
fn available_space(path: &Path) -> Option<u64> {
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let stat = rustix::fs::statvfs(folder).ok()?;
    stat.f_bavail.checked_mul(stat.f_frsize)
}

/// Refuses an output of at least `bytes` (for `what`) that exceeds the `available`
/// space of its file system, before any work: the error says how much it needs and
/// names `--ignore-space-check`.
fn check_space(what: &str, bytes: Option<u64>, available: Option<u64>) -> anyhow::Result<()> {
    let gb = |b: u64| b as f64 / 1e9;
    match (bytes, available) {
        (None, _) => bail!("{what}: more than 2^64 bytes needed; ask for fewer"),
        (Some(b), Some(a)) if b > a => bail!(
            "{what}: at least {:.1} GB needed and {:.1} GB free there; ask for fewer, free some space, or pass --ignore-space-check to try anyway",
            gb(b),
            gb(a)
        ),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outputs_larger_than_the_free_space_are_refused() {
        assert!(check_space("x", Some(10), Some(11)).is_ok());
        assert!(check_space("x", Some(10), None).is_ok());
        let e = check_space("x.ply: 3 samples", Some(5_000_000_000), Some(2_000_000_000))
            .expect_err("too large");
        assert_eq!(
            e.to_string(),
            "x.ply: 3 samples: at least 5.0 GB needed and 2.0 GB free there; ask for fewer, free some space, or pass --ignore-space-check to try anyway"
        );
        let e = check_space("n samples", None, Some(1)).expect_err("overflow");
        assert!(e.to_string().contains("more than 2^64 bytes"), "{e}");
        let here = available_space(Path::new("out.ply"));
        assert!(here.is_some_and(|a| a > 0), "{here:?}");
        assert_eq!(
            available_space(Path::new("/nonexistent/folder/out.ply")),
            None
        );
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
