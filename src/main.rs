//! The `glowbrick` binary: parses the command line and runs it (`glowbrick::cli`). A usage error prints one
//! line and exits with clap's code 2, a failed command prints its one-line error and exits with 1.

use clap::Parser;
use glowbrick::cli::{Cli, run};
use std::process::ExitCode;

/// Counts each thread's heap bytes, so `glowbrick stress --fuzz` can bound what one hostile input allocates.
#[global_allocator]
static ALLOCATOR: glowbrick::alloc_watch::WatchingAllocator = glowbrick::alloc_watch::WatchingAllocator;

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        // --help and --version.
        Err(e) if !e.use_stderr() => {
            let _ = e.print();
            return ExitCode::SUCCESS;
        }
        // A usage error in one line (clap's message up to its first blank line; the rest is usage text and
        // tips), exit code 2 as clap's own.
        Err(e) => {
            let text = e.render().to_string();
            let message: Vec<&str> =
                text.lines().map(str::trim).skip_while(|l| l.is_empty()).take_while(|l| !l.is_empty()).collect();
            eprintln!(
                "{} (`glowbrick help` lists the commands, `glowbrick COMMAND --help` their options)",
                message.join(" ")
            );
            return ExitCode::from(2);
        }
    };
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("error: {message}");
            ExitCode::FAILURE
        }
    }
}
