//! Soak (issue 22), bounded for CI: `strata watch`'s loop through 144 saves of a scene
//! in a temporary folder and the ECS engine through 2 000 frames keep their resident
//! set, open files, threads and entities flat after a warm-up. The full runs (1 000
//! saves, 10 000 frames) are `cargo run --release -p strata-bench --bin soak`; both use
//! the drivers in `strata_bench::soak`, which also check every save and frame.
//!
//! The resident set is the process's, and other tests run beside these in the same
//! process: each soak runs alone in a child process of this test binary (the test runs
//! itself again with an exact filter).

use std::process::Command;

use strata_bench::soak::{EDIT_CYCLE, EDIT_PERIOD, SoakReport, ecs_soak, markdown_table};

/// Set in the child process that runs one soak alone; its value is the test's name.
const CHILD: &str = "STRATA_SOAK_CHILD";

/// Saves before the baseline and after it: two cycles of scenes each, so that the
/// warm-up has applied every scene twice and the end is read with the baseline's scene.
const WARM_UP_EDITS: usize = 2 * EDIT_PERIOD;
const EDITS: usize = WARM_UP_EDITS + 2 * EDIT_PERIOD;

/// Frames per period of the ECS soak (a field edit and its undo, every count once), the
/// warm-up and the run: whole periods, for the same reason.
const PERIOD: usize = 1000;
const WARM_UP_FRAMES: usize = PERIOD;
const FRAMES: usize = 2 * PERIOD;

/// The resident-set growth allowed after the warm-up: 5% of the baseline (the issue's
/// bound) or 2 MiB, whichever is larger. The baselines are 14-18 MiB, where 5% is 0.7-0.9
/// MiB: about what the allocator alone moves the resident set between two reads in the
/// same state (up to 0.75 MiB with the settings below; pages are kept or returned
/// whole, and a transient peak stays resident until the heap top is trimmed). The live
/// heap does not grow (heaptrack over the bench's 1 000 saves: its floor moved by
/// 2.4 KiB), so 2 MiB separates noise from a leak: a leaked copy of the samples
/// (320 KiB) per save exceeds it within 7 of the 72 saves measured, and a 40 KiB leak
/// per save failed this test (+3.4 MiB) when tried.
fn allowed_growth_kib(baseline_kib: u64) -> u64 {
    (baseline_kib / 20).max(2048)
}

/// Runs `soak` alone in a child process and checks its report there; `test` is this
/// test's path in the binary.
fn in_child(test: &str, soak: impl FnOnce() -> SoakReport) {
    if std::env::var(CHILD).as_deref() == Ok(test) {
        let report = soak();
        println!("{}", markdown_table(std::slice::from_ref(&report)));
        check(&report);
        return;
    }
    if strata_bench::soak::resident_kib().is_none() {
        eprintln!("skipped: no VmRSS in /proc/self/status");
        return;
    }
    let exe = std::env::current_exe().expect("the test binary");
    let out = Command::new(exe)
        .args([test, "--exact", "--test-threads=1", "--nocapture"])
        .env(CHILD, test)
        // With glibc's defaults the resident set creeps (+5-8% over 900 saves) while
        // the live heap is flat: after the first large block is freed, its dynamic
        // mmap threshold rises and later large buffers (samples, fields, segment
        // data) come from per-thread arenas, where freed pages stay resident. A fixed
        // threshold and one arena make the resident set follow the live heap, which
        // is what a leak moves (bench README, "Soak").
        .env("MALLOC_MMAP_THRESHOLD_", "131072")
        .env("MALLOC_ARENA_MAX", "1")
        // And each reading counts live pages only (see `strata_bench::soak::TRIM_ENV`).
        .env(strata_bench::soak::TRIM_ENV, "1")
        .output()
        .expect("run the soak in a child process");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stdout}\n{stderr}");
    assert!(
        stdout.contains("1 passed"),
        "the child ran no test: {stdout}"
    );
    println!("{stdout}");
}

/// What must hold after the warm-up, whatever the soak. The resident set is judged by
/// [`SoakReport::kept_growth_kib`]: the lower of the end point's growth and the growth
/// of the lowest reading of the run's last quarter. The ECS soak reads its baseline
/// and its end with no build in flight; before it did, it failed twice by reading a
/// rebuild's buffers (13,856 -> 17,080 KiB with readings back at the baseline in
/// between; once more with the whole last quarter 2.4 MiB up while the last edit's
/// build ran). Memory the run keeps raises both measures: the 40 KiB-per-save leak
/// that failed this test (+3.4 MiB at the end) stands about 2.5 MiB over the
/// baseline where the last quarter starts.
fn check(r: &SoakReport) {
    let allowed = allowed_growth_kib(r.warm.rss_kib);
    assert!(
        r.kept_growth_kib() <= allowed as i64,
        "{}: resident set {} -> {} KiB (lowest of the last quarter {:+} KiB), more than \
         {allowed} KiB; by {}: {:?}",
        r.name,
        r.warm.rss_kib,
        r.end.rss_kib,
        r.floor_growth_kib(),
        r.unit,
        r.trend
    );
    assert_eq!(r.end.fds, r.warm.fds, "{}: open files", r.name);
    assert_eq!(r.end.threads, r.warm.threads, "{}: threads", r.name);
    assert_eq!(r.end.entities, r.warm.entities, "{}: entities", r.name);
}

#[test]
fn watch_loop_memory_stays_flat_through_saves() {
    in_child("soak::watch_loop_memory_stays_flat_through_saves", || {
        let r = strata_bench::soak::watch_soak(EDITS, WARM_UP_EDITS).expect("watch soak");
        assert_eq!(r.errors_reported, EDITS / EDIT_CYCLE.len(), "invalid saves");
        assert_eq!(r.stray_errors, 0, "errors for good saves");
        r
    });
}

#[test]
fn ecs_memory_stays_flat_through_frames() {
    in_child("soak::ecs_memory_stays_flat_through_frames", || {
        ecs_soak(FRAMES, WARM_UP_FRAMES, PERIOD).expect("ECS soak")
    });
}
