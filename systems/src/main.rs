//! The `strata` command-line tool; see `strata --help`.

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let cli = strata_systems::cli::Cli::parse();
    // The main thread (the frame thread of `view` and `render`) joins rayon's global
    // pool: parallel work it starts (a level-of-detail update, a resampling) begins
    // on it at once, instead of waiting for a sleeping worker to wake (1-2 ms on a
    // 2-core machine; bench/README.md). Background preprocessing has a pool of its
    // own, so the frame never picks up its work. If a pool exists already, keep it.
    let _ = rayon::ThreadPoolBuilder::new()
        .use_current_thread()
        .build_global();
    match strata_systems::cli::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", strata_systems::cli::one_line(&e));
            ExitCode::FAILURE
        }
    }
}
