//! The `strata` command-line tool; see `strata --help`.

use std::process::ExitCode;

use clap::Parser;
use strata_systems::cli::interrupt;

/// The exit status of a command whose standard output was closed early (`| head`): the
/// status a shell gives a process ended by SIGPIPE.
const BROKEN_PIPE_STATUS: u8 = 141;

fn main() -> ExitCode {
    let cli = strata_systems::cli::Cli::parse();
    quiet_on_broken_pipe();
    if cli.command.opens_gpu() {
        strata_systems::cli::ensure_runtime_dir();
    }
    // The main thread runs `render`'s frames and `view`'s schedule: a rayon worker, so
    // that the parallel work it starts begins at once (`frame_thread`). It fails only
    // if a global pool exists already; then that one serves.
    let _ = strata_systems::frame_thread::join_rayon_pool();
    if cli.command.writes_samples() {
        interrupt::install();
    }
    match strata_systems::cli::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if strata_systems::cli::is_broken_pipe(&e) => ExitCode::from(BROKEN_PIPE_STATUS),
        Err(e) if interrupt::is_interrupted(&e) => {
            eprintln!("{}", strata_systems::cli::one_line(&e));
            ExitCode::from(interrupt::INTERRUPTED_STATUS)
        }
        Err(e) => {
            eprintln!("error: {}", strata_systems::cli::one_line(&e));
            ExitCode::FAILURE
        }
    }
}

/// A reader that stops early (`strata field scene.ron | head -1`) ends the process
/// quietly: printing to a closed standard output panics in `println!`, and this hook
/// turns that one panic into the exit a shell expects, without a message.
fn quiet_on_broken_pipe() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let text = info
            .payload()
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| info.payload().downcast_ref::<&str>().copied())
            .unwrap_or("");
        if text.starts_with("failed printing to stdout") && text.contains("Broken pipe") {
            std::process::exit(i32::from(BROKEN_PIPE_STATUS));
        }
        default(info);
    }));
}
