//! `glowbrick play`: open a window on a world (the default command).

use super::args::{GameWorldArgs, SettingArgs};
use crate::game::endless::EndlessPlay;
use crate::game::models::ModelToPlace;
use crate::settings::RenderSettings;
use crate::world::follow::stream_workers;
use crate::world::generate::endless::DEFAULT_HEIGHT;
use crate::world::import::vox::parse_vox;
use crate::world::region_save::EndlessSave;
use clap::Args;
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct PlayArgs {
    #[command(flatten)]
    world: GameWorldArgs,
    /// Start at this named view of the world (a generated world has village, house, cave and overview; with
    /// --connect, a view of the server's world).
    #[arg(long)]
    view: Option<String>,
    /// A MagicaVoxel model (.vox) that V drops in front of the player.
    #[arg(long)]
    model: Option<PathBuf>,
    /// Join a server (`glowbrick serve`) at HOST:PORT instead of opening a world here.
    #[arg(long, value_name = "HOST:PORT", conflicts_with_all = ["world", "scene", "new", "seed", "size", "model"])]
    connect: Option<String>,
    /// Your name on the server.
    #[arg(long, requires = "connect")]
    name: Option<String>,
    /// The server's secret, when it has one.
    #[arg(long, requires = "connect")]
    secret: Option<String>,
    /// Play the endless world of --seed (the default when no --world, --scene, --new or --size is given): its
    /// window follows you wherever you go. F5 saves the regions you changed into the save folder, F9 and the
    /// next start bring them back.
    #[arg(long, conflicts_with_all = ["world", "scene", "new", "size", "connect", "view"])]
    endless: bool,
    /// Where F5 saves and F9 loads (default: saves/<name of --world>.ron, or saves/world.ron; with --endless the
    /// folder saves/endless-<seed>).
    #[arg(long)]
    save: Option<PathBuf>,
    #[command(flatten)]
    settings: SettingArgs,
}

impl PlayArgs {
    pub fn run(self) -> Result<(), String> {
        // The game lights with the GI cache and denoises unless told otherwise (`--set gi=off denoise=off`, G
        // and N in game).
        let fallback = if self.connect.is_some() { "joined" } else { "world" };
        let save = self.save.clone().unwrap_or_else(|| self.world.default_save(fallback));
        // What the player set in game last time (F4), beside the saves; `--config` and `--set` go over it.
        let base =
            crate::game::settings_file::load_over(RenderSettings::game(), &crate::game::settings_file::beside(&save))?;
        // Refused before the world loads; the world's saved time of day goes under the pairs.
        self.settings.settings_over(base.clone())?;
        let source = self.world.source();
        if let Some(address) = &self.connect {
            let join = crate::net::client::Join {
                server: resolve(address)?,
                secret: self.secret.clone(),
                name: self.name.clone().unwrap_or_else(default_name),
                view: self.view.clone(),
            };
            let settings = self.settings.settings_over(base)?;
            can_open_a_window()?;
            crate::game::run_game(crate::net::client::waiting_world(), settings, save, None, Some(join), None);
            return Ok(());
        }
        let model = self.model.as_deref().map(load_model).transpose()?;
        if self.endless || (self.world.names_no_bounded_world() && self.view.is_none()) {
            if self.model.is_some() {
                return Err("--model places a model's own colours, which the endless world's region files do not \
                            hold yet: open a bounded world for it (--new, --world or --scene)"
                    .into());
            }
            let seed = self.world.seed;
            let folder = self.save.clone().unwrap_or_else(|| PathBuf::from(format!("saves/endless-{seed}")));
            let save = EndlessSave::open_or_create(&folder, seed, DEFAULT_HEIGHT)?;
            let gpu = can_open_a_window()?;
            let (play, world) = EndlessPlay::open(save, stream_workers())?;
            let settings = self.settings.settings_over(base.with_world_time(&world))?;
            crate::render::scene::world::fits_gpu(&world, gpu.max_binding)?;
            // The settings file sits beside the folder, where every other world keeps it.
            crate::game::run_game(world, settings, folder, model, None, Some(play));
            return Ok(());
        }
        let mut world = source.load().map_err(|e| e.to_string())?;
        if let Some(name) = &self.view {
            // The game starts at the first view: move the named one to the front.
            let Some(at) = world.views.iter().position(|v| &v.name == name) else {
                let names: Vec<&str> = world.views.iter().map(|v| v.name.as_str()).collect();
                return Err(format!("no view '{name}' in this world (its views: {})", names.join(", ")));
            };
            let view = world.views.remove(at);
            world.views.insert(0, view);
        }
        let settings = self.settings.settings_over(base.with_world_time(&world))?;
        let gpu = can_open_a_window()?;
        crate::render::scene::world::fits_gpu(&world, gpu.max_binding)?;
        crate::game::run_game(world, settings, save, model, None, None);
        Ok(())
    }
}

/// The game needs an X11 display and a GPU adapter (software Vulkan will do); without either, say so and what
/// to do, instead of the window system's or the renderer's panic.
fn can_open_a_window() -> Result<crate::render::adapter::Adapter, String> {
    if cfg!(all(unix, not(target_os = "macos"))) && std::env::var_os("DISPLAY").is_none_or(|d| d.is_empty()) {
        return Err("no display: DISPLAY is not set, and the game's window needs X11 (a desktop session, XWayland or \
                    `ssh -X`); `glowbrick render` works without one"
            .into());
    }
    crate::render::adapter::probe_adapter().map_err(|why| {
        format!(
            "no GPU adapter ({why}): install a Vulkan driver (Debian/Ubuntu: `apt-get install mesa-vulkan-drivers` \
             gives software Vulkan)"
        )
    })
}

/// HOST:PORT (a name or an address; the port defaults to the server's) as one socket address.
pub(super) fn resolve(address: &str) -> Result<std::net::SocketAddr, String> {
    use std::net::ToSocketAddrs;
    let with_port = if address.rsplit_once(':').is_some_and(|(_, p)| p.parse::<u16>().is_ok()) {
        address.to_string()
    } else {
        format!("{address}:{}", crate::net::transport::DEFAULT_PORT)
    };
    with_port
        .to_socket_addrs()
        .map_err(|e| format!("cannot find server '{address}': {e}"))?
        .next()
        .ok_or_else(|| format!("cannot find server '{address}': no address"))
}

/// The player's name when `--name` is not given: the user's login name, or "player".
fn default_name() -> String {
    std::env::var("USER").ok().and_then(|n| crate::net::server::clean_name(&n)).unwrap_or_else(|| "player".into())
}

/// The `--model` file as a model V can place.
fn load_model(path: &Path) -> Result<ModelToPlace, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
    let file = parse_vox(&bytes).map_err(|e| format!("{}: {e}", path.display()))?;
    let name = path.file_stem().map_or("model".into(), |s| s.to_string_lossy().into_owned());
    ModelToPlace::from_vox(&name, &file).ok_or_else(|| format!("{}: no model", path.display()))
}
