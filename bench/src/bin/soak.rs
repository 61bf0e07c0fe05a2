//! Soak runs (issue 22): resident memory of `strata watch`'s loop through 1 000 saves of a
//! scene in a temporary folder, and of the ECS engine through 10 000 frames, each
//! measured after a warm-up and at the end (see `strata_bench::soak` for what each
//! iteration does and checks).
//!
//! `cargo run --release -p strata-bench --bin soak [-- --quick]`: prints a Markdown
//! table and the resident-set trend, and exits non-zero if either run's resident set
//! grew by more than [`LIMIT_PERCENT`] after its warm-up: the peak of the last quarter
//! of the run against the peak of the first quarter after the warm-up, each over
//! several cycles (`SoakReport::trend_growth_percent`). `--quick`: 208 saves and
//! 2 000 frames. Linux only (`/proc/self/status`).
//!
//! Both runs repeat their states (the watch soak's scene every 36 saves, the ECS
//! soak's field and count every 1 000 frames), and the baseline and the end are read in
//! the same state: growth is then what the run kept, not where in the cycle it stopped.
//! glibc's `MALLOC_*` variables, if set, are printed: they change what stays resident.

use strata_bench::soak::{EDIT_PERIOD, SoakReport, ecs_soak, markdown_table, watch_soak};

/// Largest resident-set growth after the warm-up that passes, in percent.
const LIMIT_PERCENT: f64 = 5.0;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut quick = false;
    for arg in std::env::args().skip(1) {
        match arg.as_str() {
            "--quick" => quick = true,
            _ => return Err(format!("unknown argument {arg} (usage: soak [--quick])").into()),
        }
    }
    // (saves, warm-up): the warm-up sees every scene of the cycle at least twice, and
    // the saves after it are whole cycles (900 = 25 x 36, 108 = 3 x 36).
    let (edits, edit_warm_up) = if quick { (208, 100) } else { (1000, 100) };
    let (frames, frame_warm_up) = if quick { (2000, 1000) } else { (10_000, 1000) };
    let period = 1000;
    // glibc's tunables change what the resident set keeps (bench README, "Soak").
    let malloc: Vec<String> = std::env::vars()
        .filter(|(k, _)| k.starts_with("MALLOC_"))
        .map(|(k, v)| format!("{k}={v}"))
        .collect();
    println!(
        "malloc: {}",
        if malloc.is_empty() {
            "glibc defaults".to_owned()
        } else {
            malloc.join(" ")
        }
    );
    assert_eq!((edits - edit_warm_up) % EDIT_PERIOD, 0);
    assert_eq!((frames - frame_warm_up) % period, 0);
    println!("watch soak: {edits} saves, baseline after {edit_warm_up}");
    let watch = watch_soak(edits, edit_warm_up)?;
    println!(
        "  {} invalid saves reported, {} stray errors; {:.1} ms per save (debounce included), engine updates {:.1} ms per save",
        watch.errors_reported,
        watch.stray_errors,
        1e3 * watch.elapsed.as_secs_f64() / edits as f64,
        1e3 * watch.update_time.as_secs_f64() / edits as f64
    );
    println!(
        "ECS soak: {frames} frames, baseline after {frame_warm_up}, a field edit (and its undo) every {period}"
    );
    let ecs = ecs_soak(frames, frame_warm_up, period)?;
    println!(
        "  {:.3} ms per frame, of which engine updates {:.3} ms",
        1e3 * ecs.elapsed.as_secs_f64() / frames as f64,
        1e3 * ecs.update_time.as_secs_f64() / frames as f64
    );
    let reports = [watch, ecs];
    println!();
    print!("{}", markdown_table(&reports));
    println!();
    for r in &reports {
        print_trend(r);
    }
    // The criterion is the trend (last quarter's peak against the first's): a
    // point-to-point comparison catches glibc's allocator in one of its states at
    // either end (the watch soak moves between about 21.5 and 24.8 MiB throughout).
    let failed: Vec<String> = reports
        .iter()
        .filter(|r| r.trend_growth_percent() > LIMIT_PERCENT)
        .map(|r| format!("{}: {:+.2}%", r.name, r.trend_growth_percent()))
        .collect();
    if !failed.is_empty() {
        return Err(format!(
            "resident set grew more than {LIMIT_PERCENT}% from the first quarter after the \
             warm-up to the last (peaks): {}; to see the heap's trend alone, run with \
             MALLOC_MMAP_THRESHOLD_=131072 MALLOC_ARENA_MAX=1 (bench README, \"Soak\")",
            failed.join(", ")
        )
        .into());
    }
    println!(
        "growth under {LIMIT_PERCENT}% after the warm-up (last quarter's peak against the first's): ok"
    );
    Ok(())
}

/// One line: the resident set after every tenth of the run.
fn print_trend(r: &SoakReport) {
    let points: Vec<String> = r
        .trend
        .iter()
        .map(|(i, kib)| format!("{i}: {:.1}", *kib as f64 / 1024.0))
        .collect();
    println!("{} RSS (MiB) by {}: {}", r.name, r.unit, points.join(", "));
}
