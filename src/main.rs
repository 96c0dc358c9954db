//! The `glowbrick` command line (DESIGN.md "Command line").

use bevy::math::UVec3;
use clap::{Args, Parser, Subcommand};
use glowbrick::game::models::ModelToPlace;
use glowbrick::headless::{HeadlessOptions, render_headless};
use glowbrick::image_io::{read_image, write_image, write_png_plain};
use glowbrick::reference::{ReferenceOptions, metrics, render_reference};
use glowbrick::settings::{RenderSettings, valid_pairs};
use glowbrick::world::import::vox::parse_vox;
use glowbrick::world::source::{WorldSource, load_path};
use glowbrick::world::{CameraView, VoxelWorld};
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
    /// Render the CPU ground truth (direct light, or with --bounces diffuse bounces) to a linear EXR.
    Reference(ReferenceArgs),
    /// Compare two images: prints mae, mse, relmse and bias of A against the reference B.
    Compare {
        image: PathBuf,
        reference: PathBuf,
        /// Also write a false-colour error image (PNG).
        #[arg(long)]
        diff: Option<PathBuf>,
    },
    /// Measure run time against error for scenes x settings; writes results.csv, report.md and plot.png.
    Bench {
        /// Comma-separated scene names (default: all thesis-like scenes, or a small set with --quick).
        #[arg(long, value_delimiter = ',')]
        scenes: Vec<String>,
        /// A small, fast run (96x64, few frames, 256-spp references) for CI.
        #[arg(long)]
        quick: bool,
        /// The thesis protocol instead: its .vx scenes and views, 32 frames, M = 32, area and point, the cornell
        /// box with brick lights on and off; writes thesis.md beside the thesis' Table 3.
        #[arg(long)]
        thesis: bool,
        /// The GI cache bench instead: K, the static cache, the filter and bounces against an 8-bounce reference,
        /// the cost of edits, memory; writes gi.md.
        #[arg(long)]
        gi: bool,
        /// With --thesis: image size as a fraction of the thesis' 1600x1024.
        #[arg(long, default_value_t = 0.2)]
        scale: f32,
        /// With --thesis or --gi: samples per pixel of the CPU reference.
        #[arg(long, default_value_t = 1024)]
        spp: u32,
        /// Comma-separated bench settings to run (default: all), e.g. restir,nee-power.
        #[arg(long, value_delimiter = ',')]
        settings: Vec<String>,
        /// A camera for every scene instead of its first view: OX,OY,OZ,DX,DY,DZ[,FOV_DEG] (voxel units, y up).
        #[arg(long, value_parser = parse_camera, allow_hyphen_values = true)]
        camera: Option<CameraView>,
        #[arg(long)]
        out: PathBuf,
    },
    /// Soak the renderer: random edits, lights and camera jumps every frame, extreme settings; report non-finite
    /// values, reservoir ranges and drift (exit code 1 when any check fails).
    Stress {
        /// A short run (240 frames at 64x48) for CI.
        #[arg(long)]
        quick: bool,
        /// Frames of the soak (default 5000, or 240 with --quick).
        #[arg(long)]
        frames: Option<u32>,
        #[arg(long, default_value = "test-room")]
        scene: String,
        #[arg(long, default_value_t = 1)]
        seed: u64,
    },
    /// Validate a world file or scene recipe and print a summary (exit code 1 on error).
    CheckWorld { path: PathBuf },
}

/// A world, a camera view of it and an image size: what `render` and `reference` both take.
#[derive(Args)]
struct ShotArgs {
    #[command(flatten)]
    world: WorldArgs,
    /// A named camera view of the world (default: its first view, or an overview).
    #[arg(long, conflicts_with = "camera")]
    view: Option<String>,
    /// A camera in voxel units, y up: OX,OY,OZ,DX,DY,DZ[,FOV_DEG] (vertical field of view, default 60).
    #[arg(long, value_parser = parse_camera, allow_hyphen_values = true)]
    camera: Option<CameraView>,
    #[arg(long, default_value_t = 320)]
    width: u32,
    #[arg(long, default_value_t = 180)]
    height: u32,
}

fn parse_camera(text: &str) -> Result<CameraView, String> {
    let numbers: Vec<f32> = text
        .split(',')
        .map(|s| s.trim().parse::<f32>().map_err(|_| format!("'{s}' is not a number")))
        .collect::<Result<_, _>>()?;
    if !(6..=7).contains(&numbers.len()) {
        return Err(format!("'{text}' is not OX,OY,OZ,DX,DY,DZ[,FOV_DEG]"));
    }
    let view = CameraView {
        name: "camera".into(),
        origin: [numbers[0], numbers[1], numbers[2]],
        direction: [numbers[3], numbers[4], numbers[5]],
        fov_deg: numbers.get(6).copied().unwrap_or(60.0),
    };
    match view.problem() {
        Some(problem) => Err(problem),
        None => Ok(view),
    }
}

#[derive(Args)]
struct ReferenceArgs {
    #[command(flatten)]
    shot: ShotArgs,
    /// Samples per pixel.
    #[arg(long, default_value_t = 256)]
    spp: u32,
    /// Diffuse bounces after the camera hit (0: direct light only).
    #[arg(long, default_value_t = 0)]
    bounces: u32,
    /// Stop after this many seconds (after a whole batch of samples).
    #[arg(long)]
    seconds: Option<f64>,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Output image (.exr keeps linear values).
    #[arg(long)]
    out: PathBuf,
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
    /// A MagicaVoxel model (.vox) that V drops in front of the player.
    #[arg(long)]
    model: Option<PathBuf>,
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
    #[arg(long = "set", value_name = "KEY=VALUE", help = format!("A render setting KEY=VALUE (repeatable): {}", valid_pairs()))]
    pairs: Vec<String>,
    /// A RON file of settings, e.g. {"lighting": "restir", "candidates": 16}; `--set` pairs apply after it.
    #[arg(long, value_name = "FILE.ron")]
    config: Option<PathBuf>,
}

impl SettingArgs {
    fn settings(&self) -> Result<RenderSettings, String> {
        self.settings_over(RenderSettings::default())
    }

    /// The settings file and pairs applied over `base`.
    fn settings_over(&self, base: RenderSettings) -> Result<RenderSettings, String> {
        let mut settings = base;
        if let Some(path) = &self.config {
            let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
            settings = settings.with_ron(&text, &path.display().to_string())?;
        }
        settings.with_pairs(&self.pairs)
    }
}

#[derive(Args)]
struct RenderArgs {
    #[command(flatten)]
    shot: ShotArgs,
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
        Command::Reference(args) => reference(args),
        Command::Compare { image, reference, diff } => compare(image, reference, diff),
        Command::Bench { thesis: true, scale, spp, out, .. } => {
            on_gpu(|| glowbrick::bench::thesis::run_thesis_bench(scale, spp, &out)).map(|text| println!("{text}"))
        }
        Command::Bench { gi: true, spp, out, .. } => {
            let config = glowbrick::bench::BenchConfig {
                width: 128,
                height: 72,
                reference_spp: spp,
                ..glowbrick::bench::BenchConfig::full()
            };
            on_gpu(|| glowbrick::bench::gi::run_gi_bench(&config, &out)).map(|text| println!("{text}"))
        }
        Command::Bench { scenes, quick, out, camera, settings, .. } => bench(scenes, quick, camera, settings, out),
        Command::Stress { quick, frames, scene, seed } => stress(quick, frames, scene, seed),
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
    // The game lights with the GI cache unless told otherwise (`--set gi=off`, or G in game).
    let mut base = RenderSettings::default();
    base.gi.enabled = true;
    let settings = args.settings.settings_over(base)?;
    let source = match args.world.source() {
        Some(source) if !args.new => source,
        Some(_) => return Err("--new generates a world; it cannot be combined with --world or --scene".into()),
        None => WorldSource::Generated { seed: args.seed, size: args.size },
    };
    let save = args.save.unwrap_or_else(|| {
        let name = args.world.world.as_ref().and_then(|p| p.file_stem()).map(|s| s.to_string_lossy().into_owned());
        PathBuf::from("saves").join(format!("{}.ron", name.as_deref().unwrap_or("world")))
    });
    let model = match &args.model {
        Some(path) => {
            let bytes = std::fs::read(path).map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
            let file = parse_vox(&bytes).map_err(|e| format!("{}: {e}", path.display()))?;
            let name = path.file_stem().map_or("model".into(), |s| s.to_string_lossy().into_owned());
            Some(ModelToPlace::from_vox(&name, &file).ok_or_else(|| format!("{}: no model", path.display()))?)
        }
        None => None,
    };
    let world = source.load().map_err(|e| e.to_string())?;
    glowbrick::game::run_game(world, settings, save, model);
    Ok(())
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

impl ShotArgs {
    /// Loads the world of `--world`/`--scene` and its camera: `--camera`, the view named `--view`, or the
    /// world's first view, or an overview.
    fn world_and_view(&self, command: &str) -> Result<(VoxelWorld, CameraView), String> {
        let source = self.world.source().ok_or_else(|| format!("{command} needs --world PATH or --scene NAME"))?;
        let world = source.load().map_err(|e| e.to_string())?;
        if let Some(camera) = &self.camera {
            return Ok((world, camera.clone()));
        }
        pick_view(world, self.view.as_deref())
    }
}

/// The view named `view`, or the world's first, or an overview.
fn pick_view(world: VoxelWorld, view: Option<&str>) -> Result<(VoxelWorld, CameraView), String> {
    let view = match view {
        Some(name) => world.view(Some(name)).cloned().ok_or_else(|| {
            let names: Vec<&str> = world.views.iter().map(|v| v.name.as_str()).collect();
            let names = if names.is_empty() { "none".to_string() } else { names.join(", ") };
            format!("no view '{name}' (this world has: {names})")
        })?,
        None => world.view(None).cloned().unwrap_or_else(|| world.overview()),
    };
    Ok((world, view))
}

/// Refuses an output path whose extension is not one of `allowed`, before any work is done.
fn check_output(path: &std::path::Path, allowed: &[&str]) -> Result<(), String> {
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).unwrap_or_default();
    if allowed.contains(&ext.as_str()) {
        return Ok(());
    }
    let list: Vec<String> = allowed.iter().map(|e| format!(".{e}")).collect();
    Err(format!("{}: output must end in {}", path.display(), list.join(" or ")))
}

fn render(args: RenderArgs) -> Result<(), String> {
    let settings = args.settings.settings()?;
    let (world, view) = args.shot.world_and_view("render")?;
    check_output(&args.out, &["png", "exr"])?;
    let options = HeadlessOptions {
        width: args.shot.width,
        height: args.shot.height,
        frames: args.frames,
        settings,
        ..Default::default()
    };
    let start = std::time::Instant::now();
    let image = on_gpu(|| render_headless(world, &view, &options))?;
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

fn reference(args: ReferenceArgs) -> Result<(), String> {
    let (world, view) = args.shot.world_and_view("reference")?;
    check_output(&args.out, &["exr", "png"])?;
    if let Some(s) = args.seconds.filter(|s| !(s.is_finite() && *s > 0.0)) {
        return Err(format!("--seconds {s} must be a positive number"));
    }
    let options = ReferenceOptions {
        width: args.shot.width,
        height: args.shot.height,
        spp: args.spp,
        bounces: args.bounces,
        seed: args.seed,
        time_budget: args.seconds.map(std::time::Duration::from_secs_f64),
    };
    let result = render_reference(&world, &view, &options)?;
    write_image(&result.image, &args.out)?;
    println!(
        "wrote {} ({}x{}, view '{}', {} spp, {} bounces, {:.1} s)",
        args.out.display(),
        args.shot.width,
        args.shot.height,
        view.name,
        result.spp,
        args.bounces,
        result.elapsed.as_secs_f64()
    );
    Ok(())
}

fn compare(image: PathBuf, reference: PathBuf, diff: Option<PathBuf>) -> Result<(), String> {
    let a = read_image(&image)?;
    let b = read_image(&reference)?;
    let m = metrics::compare(&a, &b)?;
    if let Some(path) = diff {
        check_output(&path, &["png"])?;
        // White at four times the mean absolute error: the worst pixels stand out.
        write_png_plain(&metrics::error_image(&a, &b, (4.0 * m.mae).max(1e-6) as f32), &path)?;
    }
    println!("{m}");
    Ok(())
}

fn bench(
    scenes: Vec<String>,
    quick: bool,
    camera: Option<CameraView>,
    only: Vec<String>,
    out: PathBuf,
) -> Result<(), String> {
    use glowbrick::bench::{ALL_SCENES, BenchConfig, QUICK_SCENES, run_bench};
    let defaults = if quick { QUICK_SCENES } else { ALL_SCENES };
    let scenes = if scenes.is_empty() { defaults.iter().map(|s| s.to_string()).collect() } else { scenes };
    let mut config = if quick { BenchConfig::quick() } else { BenchConfig::full() };
    config.camera = camera;
    config.only = only;
    let rows = on_gpu(|| run_bench(&scenes, &config, &out))?;
    println!("wrote {} rows to {}/results.csv, report.md, plot.png", rows.len(), out.display());
    Ok(())
}

fn stress(quick: bool, frames: Option<u32>, scene: String, seed: u64) -> Result<(), String> {
    use glowbrick::stress::{StressConfig, run_stress};
    let mut config = if quick { StressConfig::quick() } else { StressConfig::full() };
    config.frames = frames.unwrap_or(config.frames);
    if config.frames == 0 || config.frames > 1_000_000 {
        return Err(format!("--frames {} must be within 1..=1000000", config.frames));
    }
    config.scene = scene;
    config.seed = seed;
    let start = std::time::Instant::now();
    let report = on_gpu(|| run_stress(&config))?;
    println!(
        "{report}
({:.1} s)",
        start.elapsed().as_secs_f64()
    );
    match report.failure() {
        Some(why) => Err(format!("stress failed: {why}")),
        None => Ok(()),
    }
}

fn check_world(path: PathBuf) -> Result<(), String> {
    let world = load_path(&path).map_err(|e| e.to_string())?;
    println!("{}", world.summary());
    Ok(())
}
