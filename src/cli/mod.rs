//! The `glowbrick` command line (README "Command line"): the clap types and one module per command. `main.rs`
//! only parses and calls `run`. Flags that conflict or mean nothing together are refused by clap (exit code 2);
//! a command that fails returns its one-line message (exit code 1).

pub mod args;
pub mod bench;
pub mod bot;
pub mod check_world;
pub mod compare;
pub mod generate;
pub mod play;
pub mod reference;
pub mod render;
pub mod serve;
pub mod stress;

use clap::{Parser, Subcommand};
use std::path::Path;

#[derive(Parser)]
#[command(name = "glowbrick", version, about = "A voxel sandbox lit by Voxel ReSTIR and a per-face GI cache")]
#[command(args_conflicts_with_subcommands = true)]
pub struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    /// Without a subcommand, glowbrick plays.
    #[command(flatten)]
    play: play::PlayArgs,
}

#[derive(Subcommand)]
enum Command {
    /// Play: open a window on a world (the default command).
    Play(play::PlayArgs),
    /// Render a world headless (no window) to a PNG (tonemapped) or EXR (linear) image.
    Render(render::RenderArgs),
    /// Render the CPU ground truth (direct light, or with --bounces diffuse bounces) to a linear EXR.
    Reference(reference::ReferenceArgs),
    /// Compare two images: prints mae, mse, relmse and bias of A against the reference B.
    Compare(compare::CompareArgs),
    /// Measure run time against error for scenes x settings; writes results.csv, report.md, plot.svg (convergence curves) and image strips.
    Bench(bench::BenchArgs),
    /// Soak the renderer: random edits, lights and camera jumps every frame, extreme settings; report non-finite
    /// values, reservoir ranges and drift (exit code 1 when any check fails).
    Stress(stress::StressArgs),
    /// Validate a world file or scene recipe and print a summary (exit code 1 on error).
    CheckWorld(check_world::CheckWorldArgs),
    /// Host a world for others to build in together: a server with no window (players join with `play --connect`).
    Serve(serve::ServeArgs),
    /// Generate the game's world for a seed and size, print what it holds and how long it took; --out saves it.
    Generate(generate::GenerateArgs),
    /// A headless player for load tests: joins a server, flies and builds for --seconds, then prints its world's
    /// state hash (no window, no GPU).
    Bot(bot::BotArgs),
}

/// Runs the parsed command; the error is one line for stderr.
pub fn run(cli: Cli) -> Result<(), String> {
    match cli.command.unwrap_or(Command::Play(cli.play)) {
        Command::Play(args) => args.run(),
        Command::Render(args) => args.run(),
        Command::Reference(args) => args.run(),
        Command::Compare(args) => args.run(),
        Command::Bench(args) => args.run(),
        Command::Stress(args) => args.run(),
        Command::CheckWorld(args) => args.run(),
        Command::Generate(args) => args.run(),
        Command::Serve(args) => args.run(),
        Command::Bot(args) => args.run(),
    }
}

/// Runs GPU work, turning a panic inside the renderer (Bevy panics when no adapter exists) into one error.
fn on_gpu<T>(work: impl FnOnce() -> Result<T, String>) -> Result<T, String> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(work)).unwrap_or_else(|panic| {
        let reason = panic
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| panic.downcast_ref::<&str>().copied())
            .unwrap_or("unknown panic");
        Err(format!(
            "the renderer stopped: {reason} (no GPU? on Debian `apt-get install mesa-vulkan-drivers` gives software Vulkan)"
        ))
    })
}

/// Refuses, before any work is done, an output path whose extension is not one of `allowed`, that is a
/// folder, or whose folder does not exist (so a long render never ends in an error, or half a file).
fn check_output(path: &Path, allowed: &[&str]) -> Result<(), String> {
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).unwrap_or_default();
    if !allowed.contains(&ext.as_str()) {
        let list: Vec<String> = allowed.iter().map(|e| format!(".{e}")).collect();
        return Err(format!("{}: output must end in {}", path.display(), list.join(" or ")));
    }
    if path.is_dir() {
        return Err(format!("{}: is a folder, not a file to write", path.display()));
    }
    let folder = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    if !folder.is_dir() {
        return Err(format!("{}: the folder {} does not exist", path.display(), folder.display()));
    }
    Ok(())
}
