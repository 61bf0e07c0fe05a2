//! The `strata` command-line tool; see `strata --help`.

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let cli = strata_systems::cli::Cli::parse();
    // The main thread runs `render`'s frames and `view`'s schedule: a rayon worker, so
    // that the parallel work it starts begins at once (`frame_thread`). It fails only
    // if a global pool exists already; then that one serves.
    let _ = strata_systems::frame_thread::join_rayon_pool();
    match strata_systems::cli::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", strata_systems::cli::one_line(&e));
            ExitCode::FAILURE
        }
    }
}
