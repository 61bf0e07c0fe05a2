//! `strata watch`: the engine loop on a scene file. Applies every change of the scene
//! (or of the mesh and field files it names), prints what reran and how long it took
//! (and a running build's progress every half second), and rewrites the samples file
//! atomically after each change.

use std::io::Write;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use anyhow::Context;

use crate::hot_reload::StreamingEngine;

/// Arguments of `strata watch`.
#[derive(Debug, clap::Args)]
pub struct WatchArgs {
    /// Scene file (RON) to watch.
    pub config: PathBuf,
    /// Samples file (binary PLY), rewritten atomically (temporary file, then rename)
    /// after every change.
    #[arg(long, short = 'o')]
    pub out: Option<PathBuf>,
    /// Stop after this many changes applied in full, their builds included (default:
    /// run until interrupted).
    #[arg(long)]
    pub updates: Option<usize>,
}

/// Runs `strata watch`.
pub(super) fn run(args: &WatchArgs) -> anyhow::Result<()> {
    if let Some(path) = &args.out {
        super::check_output(path, "--out (binary PLY samples)", &["ply"])?;
    }
    // A scene that does not load yet is waited for; one that does must not name the
    // output among its inputs.
    if let Ok(config) = crate::config::SceneConfig::load(&args.config) {
        super::refuse_inputs_as_outputs(&args.config, &config, &[args.out.as_deref()])?;
    }
    let mut engine = StreamingEngine::watch(&args.config)
        .with_context(|| format!("watching {}", args.config.display()))?;
    eprintln!("watching {} (Ctrl-C to stop)", args.config.display());
    let mut done = 0usize;
    let mut pending = false;
    loop {
        engine.clear_stats();
        let generation = engine.sample_generation();
        let t = Instant::now();
        engine.update();
        let took = t.elapsed();
        let mut out = std::io::stdout().lock();
        for e in engine.take_errors() {
            eprintln!("error: {e} (keeping the last good state)");
        }
        let runs = &engine.stats().runs;
        if !runs.is_empty() {
            for r in runs {
                writeln!(
                    out,
                    "  {:<17} {:>8} {:>9.2} ms  {}",
                    r.stage.name(),
                    r.items,
                    r.took.as_secs_f64() * 1e3,
                    r.note
                )?;
            }
            writeln!(out, "update: {:.2} ms", took.as_secs_f64() * 1e3)?;
        }
        // A failed write (its folder gone, a full disk) is reported and retried after
        // the next change, whether or not that change moves the samples.
        if engine.sample_generation() != generation || pending {
            pending = false;
            if let Some(path) = &args.out {
                let t = Instant::now();
                match strata_engine::io::write_samples_ply(path, engine.samples()) {
                    Ok(()) => writeln!(
                        out,
                        "wrote {} samples to {} ({:.2} ms)",
                        engine.samples().len(),
                        path.display(),
                        t.elapsed().as_secs_f64() * 1e3
                    )?,
                    Err(e) => {
                        pending = true;
                        eprintln!(
                            "error: {} (the samples are kept; writing again after the next change)",
                            super::one_line(&anyhow::Error::new(e))
                        );
                    }
                }
            }
        }
        // Builds run off the loop: while one runs, its progress every half second.
        let idle = engine.is_idle();
        if let Some(progress) = engine.progress() {
            writeln!(out, "  {progress}")?;
        }
        out.flush()?;
        drop(out);
        if !runs.is_empty() && idle {
            done += 1;
            if args.updates.is_some_and(|n| done >= n) {
                return Ok(());
            }
        }
        let tick = if idle {
            Duration::from_secs(3600)
        } else {
            Duration::from_millis(500)
        };
        while !engine.wait(tick) && idle {}
    }
}
