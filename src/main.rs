//! The `glowbrick` binary: parses the command line and runs it (`glowbrick::cli`). A usage error exits with
//! clap's code 2, a failed command prints its one-line error and exits with 1.

use clap::Parser;
use glowbrick::cli::{Cli, run};
use std::process::ExitCode;

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("error: {message}");
            ExitCode::FAILURE
        }
    }
}
