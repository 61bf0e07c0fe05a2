//! The `strata` command-line tool; see `strata --help`.

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let cli = strata_systems::cli::Cli::parse();
    // `render` draws its frames on the main thread: it joins rayon's global pool, so
    // that parallel work it starts (a level-of-detail update) begins on it at once
    // instead of waiting for a sleeping worker to wake (1-2 ms on a 2-core machine;
    // bench/README.md). Not for `view` and `watch`: their engine samples on bevy's
    // threads, whose parallel work would then find one worker fewer while the main
    // thread waits outside rayon (a 10^6-sample resampling took twice as long).
    if matches!(cli.command, strata_systems::cli::Command::Render(_)) {
        // Fails only if a global pool exists already; then that one serves.
        let _ = rayon::ThreadPoolBuilder::new()
            .use_current_thread()
            .build_global();
    }
    match strata_systems::cli::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", strata_systems::cli::one_line(&e));
            ExitCode::FAILURE
        }
    }
}
