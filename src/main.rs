//! The `glowbrick` command line (DESIGN.md "Command line").

use bevy::math::UVec3;
use clap::{Args, Parser, Subcommand};
use glowbrick::headless::{HeadlessOptions, render_headless};
use glowbrick::image_io::write_image;
use glowbrick::settings::{RenderSettings, SETTING_KEYS};
use glowbrick::world::source::{WorldSource, load_path};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(name = "glowbrick", version, about = "A voxel sandbox lit by Voxel ReSTIR and a per-face GI cache")]
#[command(args_conflicts_with_subcommands = true)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    /// Without a subcommand, glowbrick plays.
    #[command(flatten)]
    play: PlayArgs,
}

#[derive(Subcommand)]
enum Command {
    /// Play: open a window on a world (the default command).
    Play(PlayArgs),
    /// Render a world headless (no window) to a PNG (tonemapped) or EXR (linear) image.
    Render(RenderArgs),
    /// Validate a world file or scene recipe and print a summary (exit code 1 on error).
    CheckWorld { path: PathBuf },
}

#[derive(Args)]
struct PlayArgs {
    #[command(flatten)]
    world: WorldArgs,
    /// Generate a new world (with --seed and --size) instead of opening one.
    #[arg(long)]
    new: bool,
    /// Seed of the generated world.
    #[arg(long, default_value_t = 1)]
    seed: u32,
    /// Size of the generated world in voxels, X,Y,Z.
    #[arg(long, default_value = "192,64,192", value_parser = parse_size)]
    size: UVec3,
    /// Where F5 saves and F9 loads (default: saves/<name of --world>.ron, or saves/world.ron).
    #[arg(long)]
    save: Option<PathBuf>,
    #[command(flatten)]
    settings: SettingArgs,
}

#[derive(Args, Default)]
struct WorldArgs {
    /// A world file (.ron) or scene recipe.
    #[arg(long, conflicts_with = "scene")]
    world: Option<PathBuf>,
    /// A bundled scene: assets/scenes/NAME.ron.
    #[arg(long)]
    scene: Option<String>,
}

#[derive(Args, Default)]
struct SettingArgs {
    /// A render setting KEY=VALUE (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE", help = format!("A render setting KEY=VALUE (repeatable): {SETTING_KEYS}"))]
    pairs: Vec<String>,
}

#[derive(Args)]
struct RenderArgs {
    #[command(flatten)]
    world: WorldArgs,
    /// A named camera view of the world (default: its first view, or an overview).
    #[arg(long)]
    view: Option<String>,
    #[arg(long, default_value_t = 320)]
    width: u32,
    #[arg(long, default_value_t = 180)]
    height: u32,
    /// Frames to render before writing the last one.
    #[arg(long, default_value_t = 1)]
    frames: u32,
    #[command(flatten)]
    settings: SettingArgs,
    /// Output image: .png (tonemapped) or .exr (linear float).
    #[arg(long)]
    out: PathBuf,
}

fn parse_size(text: &str) -> Result<UVec3, String> {
    let parts: Vec<&str> = text.split(',').collect();
    let [x, y, z] = parts.as_slice() else { return Err(format!("'{text}' is not X,Y,Z")) };
    let parse = |s: &str| s.trim().parse::<u32>().map_err(|_| format!("'{s}' is not a whole number"));
    let size = UVec3::new(parse(x)?, parse(y)?, parse(z)?);
    let max = glowbrick::world::grid::MAX_WORLD_EDGE;
    if size.cmplt(UVec3::splat(8)).any() || size.cmpgt(UVec3::splat(max)).any() {
        return Err(format!("size {text} must be within 8..={max} on each axis"));
    }
    Ok(size)
}

impl WorldArgs {
    fn source(&self) -> Option<WorldSource> {
        match (&self.world, &self.scene) {
            (Some(path), _) => Some(WorldSource::Path(path.clone())),
            (None, Some(name)) => Some(WorldSource::Scene(name.clone())),
            (None, None) => None,
        }
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command.unwrap_or(Command::Play(cli.play)) {
        Command::Play(args) => play(args),
        Command::Render(args) => render(args),
        Command::CheckWorld { path } => check_world(path),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("error: {message}");
            ExitCode::FAILURE
        }
    }
}

fn play(args: PlayArgs) -> Result<(), String> {
    let settings = RenderSettings::default().with_pairs(&args.settings.pairs)?;
    let source = match args.world.source() {
        Some(source) if !args.new => source,
        Some(_) => return Err("--new generates a world; it cannot be combined with --world or --scene".into()),
        None => WorldSource::Generated { seed: args.seed, size: args.size },
    };
    let save = args.save.unwrap_or_else(|| {
        let name = args.world.world.as_ref().and_then(|p| p.file_stem()).map(|s| s.to_string_lossy().into_owned());
        PathBuf::from("saves").join(format!("{}.ron", name.as_deref().unwrap_or("world")))
    });
    let world = source.load().map_err(|e| e.to_string())?;
    glowbrick::game::run_game(world, settings, save);
    Ok(())
}

fn render(args: RenderArgs) -> Result<(), String> {
    let settings = RenderSettings::default().with_pairs(&args.settings.pairs)?;
    let source = args.world.source().ok_or("render needs --world PATH or --scene NAME")?;
    let world = source.load().map_err(|e| e.to_string())?;
    let view = match &args.view {
        Some(name) => world.view(Some(name)).cloned().ok_or_else(|| {
            let names: Vec<&str> = world.views.iter().map(|v| v.name.as_str()).collect();
            format!(
                "no view '{name}' (this world has: {})",
                if names.is_empty() { "none".into() } else { names.join(", ") }
            )
        })?,
        None => world.view(None).cloned().unwrap_or_else(|| world.overview()),
    };
    let ext = args.out.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    if !matches!(ext.as_deref(), Some("png") | Some("exr")) {
        return Err(format!("{}: output must end in .png or .exr", args.out.display()));
    }
    let options =
        HeadlessOptions { width: args.width, height: args.height, frames: args.frames, settings, ..Default::default() };
    let start = std::time::Instant::now();
    let image = render_headless(world, &view, &options)?;
    write_image(&image, &args.out)?;
    println!(
        "wrote {} ({}x{}, view '{}', {} frames, {:.2} s)",
        args.out.display(),
        image.width,
        image.height,
        view.name,
        args.frames,
        start.elapsed().as_secs_f64()
    );
    Ok(())
}

fn check_world(path: PathBuf) -> Result<(), String> {
    let world = load_path(&path).map_err(|e| e.to_string())?;
    println!("{}", world.summary());
    Ok(())
}
