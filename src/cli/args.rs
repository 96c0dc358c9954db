//! Argument groups that several commands share: a world, a camera view of it, render settings, and the parsers
//! of `--camera` and `--size`.

use crate::settings::{RenderSettings, help_text, valid_pairs};
use crate::world::generate::endless::{DEFAULT_HEIGHT, EndlessGenerator, SHOT_WINDOW_REGIONS};
use crate::world::region_save::EndlessSave;
use crate::world::source::WorldSource;
use crate::world::{CameraView, VoxelWorld};
use bevy::math::UVec3;
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Default)]
pub struct WorldArgs {
    /// A world file (.ron) or scene recipe.
    #[arg(long, conflicts_with = "scene")]
    pub world: Option<PathBuf>,
    /// A bundled scene: assets/scenes/NAME.ron.
    #[arg(long)]
    pub scene: Option<String>,
}

impl WorldArgs {
    pub fn source(&self) -> Option<WorldSource> {
        match (&self.world, &self.scene) {
            (Some(path), _) => Some(WorldSource::Path(path.clone())),
            (None, Some(name)) => Some(WorldSource::Scene(name.clone())),
            (None, None) => None,
        }
    }
}

/// The generated world's size when none is given: 1024 x 192 x 1024 voxels.
pub const DEFAULT_SIZE: &str = "1024,192,1024";

/// The world the game or a server opens: a world file or scene, or else the generator's (`--new`, which is also
/// the default).
#[derive(Args)]
pub struct GameWorldArgs {
    #[command(flatten)]
    pub world: WorldArgs,
    /// Generate a new world (with --seed and --size) instead of opening one.
    #[arg(long, conflicts_with_all = ["world", "scene"])]
    pub new: bool,
    /// Seed of the generated world.
    #[arg(long, default_value_t = 1, conflicts_with_all = ["world", "scene"])]
    pub seed: u32,
    /// Size of the generated world in voxels, X,Y,Z (default 1024,192,1024).
    #[arg(long, value_parser = parse_size, conflicts_with_all = ["world", "scene"])]
    pub size: Option<UVec3>,
}

impl GameWorldArgs {
    /// Without --world or --scene the generator's world, --new or not (clap refuses --new with either).
    pub fn source(&self) -> WorldSource {
        let size = self.size.unwrap_or_else(|| parse_size(DEFAULT_SIZE).expect("the default size parses"));
        self.world.source().unwrap_or(WorldSource::Generated { seed: self.seed, size })
    }

    /// Whether nothing names a bounded world: no --world, --scene, --new or --size.
    pub fn names_no_bounded_world(&self) -> bool {
        self.world.source().is_none() && !self.new && self.size.is_none()
    }

    /// The save path when none is given: `saves/<name of --world>.ron`, or `saves/<fallback>.ron`.
    pub fn default_save(&self, fallback: &str) -> PathBuf {
        let name = self.world.world.as_ref().and_then(|p| p.file_stem()).map(|s| s.to_string_lossy().into_owned());
        PathBuf::from("saves").join(format!("{}.ron", name.as_deref().unwrap_or(fallback)))
    }
}

/// A world, a camera view of it and an image size: what `render` and `reference` both take.
#[derive(Args)]
pub struct ShotArgs {
    #[command(flatten)]
    pub world: WorldArgs,
    /// A named camera view of the world (default: its first view, or an overview).
    #[arg(long, conflicts_with = "camera")]
    pub view: Option<String>,
    /// A camera in voxel units, y up: OX,OY,OZ,DX,DY,DZ[,FOV_DEG] (vertical field of view, default 60).
    #[arg(long, value_parser = parse_camera, allow_hyphen_values = true)]
    pub camera: Option<CameraView>,
    #[arg(long, default_value_t = 320)]
    pub width: u32,
    #[arg(long, default_value_t = 180)]
    pub height: u32,
    /// The endless world of this seed instead of a file: a window of it 512 voxels across (192 high) made around
    /// the camera, which is given in world coordinates (default: above the first village).
    #[arg(long, value_name = "SEED", conflicts_with_all = ["world", "scene", "view"])]
    pub endless: Option<u32>,
    /// With --endless: an endless world's save folder (`world.ron`, `regions/r.X.Z.ron`) whose regions replace
    /// the generator's where it holds them.
    #[arg(long, value_name = "DIR", requires = "endless")]
    pub saves: Option<PathBuf>,
}

impl ShotArgs {
    /// Loads the world of `--world`/`--scene` and its camera: `--camera`, the view named `--view`, or the
    /// world's first view, or an overview.
    pub fn world_and_view(&self, command: &str) -> Result<(VoxelWorld, CameraView), String> {
        if let Some(seed) = self.endless {
            return endless_window(seed, self.camera.as_ref(), self.saves.as_deref());
        }
        let source = self.world.source().ok_or_else(|| format!("{command} needs --world PATH or --scene NAME"))?;
        let world = source.load().map_err(|e| e.to_string())?;
        if let Some(camera) = &self.camera {
            return Ok((world, camera.clone()));
        }
        pick_view(world, self.view.as_deref())
    }
}

/// How far from the origin (x and z) `--endless` takes a camera: 2^24 voxels.
const ENDLESS_CAMERA_REACH: f32 = 16_777_216.0;

/// The endless world's window around `camera` (world coordinates), and the camera in the window's.
fn endless_window(
    seed: u32,
    camera: Option<&CameraView>,
    saves: Option<&std::path::Path>,
) -> Result<(VoxelWorld, CameraView), String> {
    let save = saves.map(|folder| EndlessSave::open(folder).map_err(|e| e.to_string())).transpose()?;
    let height = save.as_ref().map_or(DEFAULT_HEIGHT, |s| s.height);
    if let Some(save) = save.as_ref().filter(|s| s.seed != seed) {
        return Err(format!("{} holds the endless world of seed {}, not {seed}", save.folder.display(), save.seed));
    }
    let generator = EndlessGenerator::new(seed, height)?;
    let camera = camera.cloned().unwrap_or_else(|| generator.start_view());
    let [x, _, z] = camera.origin;
    // Past 2^24 an f32 no longer holds every whole voxel, and region keys would near i32's end.
    if x.abs().max(z.abs()) > ENDLESS_CAMERA_REACH {
        return Err(format!(
            "the endless world's camera must stand within {ENDLESS_CAMERA_REACH} voxels of the origin on x and z, not at ({x}, {z})"
        ));
    }
    let centre = EndlessGenerator::region_of(x.floor() as i32, z.floor() as i32);
    let window = generator.window(centre, SHOT_WINDOW_REGIONS, save.as_ref()).map_err(|e| e.to_string())?;
    let view = window.local_view(&camera);
    Ok((window.world, view))
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

#[derive(Args, Default)]
pub struct SettingArgs {
    /// A render setting KEY=VALUE (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE", help = format!("A render setting KEY=VALUE (repeatable): {}", valid_pairs()), long_help = format!("A render setting KEY=VALUE (repeatable).\n\n{}", help_text()))]
    pub pairs: Vec<String>,
    /// A RON file of settings, e.g. {"lighting": "restir", "candidates": 16}; `--set` pairs apply after it.
    #[arg(long, value_name = "FILE.ron")]
    pub config: Option<PathBuf>,
}

impl SettingArgs {
    pub fn settings(&self) -> Result<RenderSettings, String> {
        self.settings_over(RenderSettings::default())
    }

    /// The settings for rendering `world`: its saved time of day, then the file and the pairs.
    pub fn settings_for(&self, world: &VoxelWorld) -> Result<RenderSettings, String> {
        self.settings_over(RenderSettings::default().with_world_time(world))
    }

    /// The settings file and pairs applied over `base`.
    pub fn settings_over(&self, base: RenderSettings) -> Result<RenderSettings, String> {
        let mut settings = base;
        if let Some(path) = &self.config {
            let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
            settings = settings.with_ron(&text, &path.display().to_string())?;
        }
        settings.with_pairs(&self.pairs)
    }
}

/// `--camera OX,OY,OZ,DX,DY,DZ[,FOV_DEG]`, refused when the view has a problem (zero direction, odd fov).
pub fn parse_camera(text: &str) -> Result<CameraView, String> {
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

/// `--size X,Y,Z` of a generated world, each edge within what the grid can hold.
pub fn parse_size(text: &str) -> Result<UVec3, String> {
    let parts: Vec<&str> = text.split(',').collect();
    let [x, y, z] = parts.as_slice() else { return Err(format!("'{text}' is not X,Y,Z")) };
    let parse = |s: &str| s.trim().parse::<u32>().map_err(|_| format!("'{s}' is not a whole number"));
    let size = UVec3::new(parse(x)?, parse(y)?, parse(z)?);
    let max = crate::world::grid::MAX_WORLD_EDGE;
    if size.cmplt(UVec3::splat(8)).any() || size.cmpgt(UVec3::splat(max)).any() {
        return Err(format!("size {text} must be within 8..={max} on each axis"));
    }
    Ok(size)
}
