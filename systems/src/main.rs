//! The `strata` command-line tool; see `strata --help`.

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let cli = strata_systems::cli::Cli::parse();
    match strata_systems::cli::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", strata_systems::cli::one_line(&e));
            ExitCode::FAILURE
        }
    }
}
