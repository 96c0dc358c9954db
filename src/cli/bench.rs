//! `glowbrick bench`: run time against error, in one of seven modes. Each mode's flags are refused in the other
//! modes by clap, as a conflict or as a missing `--thesis`/`--gi`, so no flag is ever silently ignored. Conflicts
//! are listed flag by flag, not by group: clap names every member of a group in its error, given or not.

use super::args::parse_camera;
use super::on_gpu;
use crate::bench::daylight::{DaylightConfig, run_daylight_bench};
use crate::bench::denoise::{DenoiseConfig, DenoiseSection, check_scenes, run_denoise_bench};
use crate::bench::frame::{CASES, FrameCase, FrameConfig, run_frame_bench};
use crate::bench::gi::{GiConfig, run_gi_bench};
use crate::bench::gi_indirect::{IndirectConfig, run_indirect_bench};
use crate::bench::net::{NetBenchConfig, run_net_bench};
use crate::bench::rays::{CASES as RAYS_CASES, RaysCase, RaysConfig, run_rays_bench};
use crate::bench::reference_cache::check_lattice;
use crate::bench::sweep::{ALL_SCENES, QUICK_SCENES, SweepConfig, run_bench};
use crate::bench::thesis::{ThesisOptions, run_thesis_bench};
use crate::bench::travel::{TravelConfig, run_travel_bench};
use crate::settings::RenderSettings;
use crate::world::CameraView;
use clap::{ArgGroup, Args};
use std::path::{Path, PathBuf};

/// The flags `--spp` is refused with: the sweep's own
/// (its reference's samples are fixed) and the frame profile (no reference).
const SPP_REFUSED: [&str; 7] = ["quick", "settings", "camera", "frame", "rays", "net", "travel"];
const MODES: [&str; 8] = ["thesis", "gi", "daylight", "denoise", "frame", "rays", "net", "travel"];

#[derive(Args)]
#[command(group(ArgGroup::new("mode").args(MODES)))]
pub struct BenchArgs {
    /// Comma-separated scene names (default: all thesis-like scenes, or a small set with --quick). With
    /// --denoise: only these of its one-frame scenes (window-room, cornell, letters, apartments); with --upscale,
    /// of the frame profile's labels.
    #[arg(long, value_delimiter = ',', conflicts_with_all = ["thesis", "daylight", "motion", "reaction", "cost", "net"])]
    scenes: Vec<String>,
    /// A small, fast run (96x64, few frames, 256-spp references) for CI. With --frame: the test suite's run
    /// (48x32, four scenes, counters held to the frame's ray budget; fails over it).
    #[arg(long, conflicts_with_all = ["thesis", "gi", "daylight", "denoise"])]
    quick: bool,
    /// The thesis protocol instead: its .vx scenes and views, 32 frames, M = 32, area and point, the cornell
    /// box with brick lights on and off; writes thesis.md beside the thesis' Table 3.
    #[arg(long)]
    thesis: bool,
    /// The GI cache bench instead: K, the static cache, the filter and bounces against a 32-bounce reference,
    /// the cost of edits, memory; writes gi.md.
    #[arg(long)]
    gi: bool,
    /// The game's lighting bench instead: lighting=full with the GI cache at noon, dusk and night against a
    /// reference with the same sun, sky and lamps and 32 bounces, and the cost of the sun and sky at 10^3 and
    /// 10^5 lamps; writes daylight.md.
    #[arg(long)]
    daylight: bool,
    /// The denoiser bench instead: one frame raw and denoised against the reference on four scenes, the bias it
    /// adds, flicker, reaction to a lamp switched off and on, cost at 320x180 and 1280x720; writes denoise.md.
    #[arg(long)]
    denoise: bool,
    /// The frame profile instead: the game's frame (and emitters only) pass by pass, GPU ms per pass and the ray,
    /// step and GI counters, on six scenes at 320x180 and 1280x720 (or --sizes; --scenes picks cases by label);
    /// writes frame.md and frame.csv.
    #[arg(long)]
    frame: bool,
    /// The CPU traversal bench instead: rays per second, steps and loads per ray of primary, shadow, diffuse and
    /// sky rays, the occupancy traversal against the plain DDA on the same rays, on six scenes (--scenes picks by
    /// label; --quick: 64x36 camera rays); writes rays.md and rays.csv. No GPU.
    #[arg(long)]
    rays: bool,
    /// The server bench instead: one server and 16, then 64 headless clients on loopback editing at a steady rate
    /// (--quick: 4 clients, 2 s); the time to join, the server's tick, edits per second, bytes per edit, the time
    /// from an edit to another client; writes net.md and net.csv. No GPU.
    #[arg(long)]
    net: bool,
    /// The endless world's streaming bench instead: a 10 km straight flight at the game's top flying speed in
    /// real time (--quick: 320 voxels), the regions around the player made on worker threads; regions a second,
    /// the main thread's longest wait, ticks where the view was not yet made, resident memory; writes travel.md.
    /// No GPU.
    #[arg(long)]
    travel: bool,
    /// With --denoise: only its section on ghosting under motion (a camera path and a sliding block, every
    /// frame against its own reference); writes denoise-motion.md.
    #[arg(long, requires = "denoise")]
    motion: bool,
    /// With --denoise: only its section on reaction (a lamp switched off and on again, the light it lit frame by
    /// frame against the converged values); writes denoise-reaction.md.
    #[arg(long, requires = "denoise", conflicts_with = "motion")]
    reaction: bool,
    /// With --denoise: only its first section (one frame raw and denoised against the reference on four scenes,
    /// the bias the filter adds, flicker); writes denoise-frame.md.
    #[arg(long, requires = "denoise", conflicts_with_all = ["motion", "reaction"])]
    one_frame: bool,
    /// With --denoise: only its cost section (the cornell box's frame with and without the filter at 320x180 and
    /// 1280x720, or at --sizes; GPU ms per pass); writes denoise-cost.md.
    #[arg(long, requires = "denoise", conflicts_with_all = ["motion", "reaction", "one_frame"])]
    cost: bool,
    /// With --denoise: only the upscaler's table (the game's denoised frame at render scales 1, 0.75, 0.5, 0.33
    /// and 0.25 against the reference on the frame profile's six scenes, --scenes picks by label; relMSE, FLIP,
    /// bias, GPU ms and the equal-time view); writes upscale-frame.md.
    #[arg(long, requires = "denoise", conflicts_with_all = ["motion", "reaction", "one_frame", "cost"])]
    upscale: bool,
    /// With --denoise: average its one-frame and reaction measures over this many independent realisations
    /// (the `seed` setting 0, 1, ..): one realisation's GI cache carries a slow noise of its own (a room's mean
    /// moves by a percent or two between seeds, more at night), which this averages. With --gi --indirect:
    /// average every figure of each row over them.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=16), conflicts_with = "motion")]
    seeds: u32,
    /// With --denoise or --frame: a setting on top of the game's frame for every measure (repeatable), e.g.
    /// `gi_qmc=off`; with --thesis, on top of the protocol's, e.g. `denoise=on`.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// With --denoise: the image size of its one-frame and reaction measures (WxH, default 160x90), e.g. a game's
    /// 320x180 (the references' cost grows with the pixels).
    #[arg(long, value_parser = parse_size, requires = "denoise")]
    size: Option<(u32, u32)>,
    /// With --gi: only its section at game sizes (320x180 and 1280x720: frame with and without the cache, GPU
    /// ms per pass, the table's load); writes gi-scale.md.
    #[arg(long, requires = "gi")]
    game_sizes: bool,
    /// With --gi: only the cache's light alone (`debug=indirect` against the path tracer's indirect light) with
    /// the entries' light reservoirs off and on, and on with guided rays, on scenes of many small lights; writes
    /// gi-indirect.md. With
    /// --scenes, only the scenes whose label holds one of them (e.g. village,cornell).
    #[arg(long, requires = "gi", conflicts_with = "game_sizes")]
    indirect: bool,
    /// With --game-sizes, --denoise --cost or --frame: only these sizes (WxH, comma-separated; default
    /// 320x180,1280x720), e.g. a GPU's 1920x1080.
    #[arg(long, value_delimiter = ',', value_parser = parse_size)]
    sizes: Vec<(u32, u32)>,
    /// With --thesis: image size as a fraction of the thesis' 1600x1024.
    #[arg(long, default_value_t = 0.2, requires = "thesis", conflicts_with_all = ["gi", "daylight", "denoise", "scenes", "quick", "settings", "camera"])]
    scale: f32,
    /// With --thesis or --denoise: integrate the reference only at every n-th pixel in each direction and
    /// measure the error there (an unbiased estimate of the whole image's error at 1/n^2 of the reference's
    /// cost), e.g. the thesis' full size with `--scale 1 --lattice 5`, or the denoiser's one frame at a game's
    /// size with `--one-frame --size 1280x720 --lattice 4`.
    #[arg(long, default_value_t = 1, conflicts_with_all = ["gi", "daylight", "motion", "reaction", "cost"])]
    lattice: u32,
    /// With --thesis: only the views whose label contains one of these, e.g. `letters` (default: all four).
    #[arg(long, value_delimiter = ',', requires = "thesis")]
    views: Vec<String>,
    /// With --thesis: area samples only (the point-sample columns read n/a): half the GPU time, for the
    /// thesis' full size on a slow adapter.
    #[arg(long, requires = "thesis")]
    area_only: bool,
    /// With --thesis, --gi, --daylight or --denoise: samples per pixel of the CPU reference.
    #[arg(long, default_value_t = 1024, requires = "mode", conflicts_with_all = SPP_REFUSED)]
    spp: u32,
    /// Comma-separated bench settings to run (default: all), e.g. restir,nee-power.
    #[arg(long, value_delimiter = ',', conflicts_with_all = MODES)]
    settings: Vec<String>,
    /// A camera for every scene instead of its first view: OX,OY,OZ,DX,DY,DZ[,FOV_DEG] (voxel units, y up).
    #[arg(long, value_parser = parse_camera, allow_hyphen_values = true, conflicts_with_all = MODES)]
    camera: Option<CameraView>,
    #[arg(long)]
    out: PathBuf,
}

/// What a bench run measures, with only the options that mode reads.
enum BenchMode {
    /// Scenes x bench settings (the default): results.csv, report.md, plot.svg, image strips.
    Settings { scenes: Vec<String>, quick: bool, only: Vec<String>, camera: Option<CameraView> },
    /// The thesis protocol: thesis.md.
    Thesis(ThesisOptions),
    /// The GI cache bench: gi.md.
    Gi { spp: u32, game_sizes: bool, sizes: Vec<(u32, u32)> },
    /// The GI cache's light alone: gi-indirect.md.
    GiIndirect { spp: u32, scenes: Vec<String>, seeds: u32 },
    /// The game's lighting at three times of day: daylight.md.
    Daylight { spp: u32 },
    /// The denoiser: denoise.md (or one section alone).
    Denoise {
        spp: u32,
        section: Option<DenoiseSection>,
        seeds: u32,
        size: (u32, u32),
        set: Vec<String>,
        lattice: u32,
        scenes: Vec<String>,
        sizes: Vec<(u32, u32)>,
    },
    /// The frame profile: frame.md, frame.csv.
    Frame { quick: bool, sizes: Vec<(u32, u32)>, scenes: Vec<String>, set: Vec<String> },
    /// The CPU traversal: rays.md, rays.csv.
    Rays { quick: bool, scenes: Vec<String> },
    /// The server: net.md, net.csv.
    Net { quick: bool },
    /// The endless world streamed around a flight: travel.md.
    Travel { quick: bool },
}

impl BenchArgs {
    pub fn run(self) -> Result<(), String> {
        let out = self.out.clone();
        if out.exists() && !out.is_dir() {
            return Err(format!("{}: --out names a folder for the report, and this is a file", out.display()));
        }
        if self.lattice != 1 && !(self.thesis || self.denoise) {
            return Err("--lattice needs --thesis or --denoise".into());
        }
        if !(self.set.is_empty() || self.thesis || self.denoise || self.frame) {
            return Err("--set needs --thesis, --denoise or --frame".into());
        }
        if self.gi && !self.indirect && !self.scenes.is_empty() {
            return Err("--scenes with --gi needs --indirect".into());
        }
        // clap's `requires` names one flag; --sizes has three homes.
        if self.seeds > 1 && !(self.denoise || (self.gi && self.indirect)) {
            return Err("--seeds needs --denoise or --gi --indirect".into());
        }
        if !(self.sizes.is_empty() || self.game_sizes || self.frame || (self.denoise && self.cost)) {
            return Err("--sizes needs --gi --game-sizes, --denoise --cost or --frame".into());
        }
        match self.mode() {
            BenchMode::Settings { scenes, quick, only, camera } => run_settings(scenes, quick, only, camera, &out),
            BenchMode::Thesis(options) => on_gpu(|| run_thesis_bench(&options, &out)).map(|text| println!("{text}")),
            BenchMode::Gi { spp, game_sizes, sizes } => {
                let config = GiConfig { game_sizes_only: game_sizes, sizes, ..GiConfig::new(spp) };
                on_gpu(|| run_gi_bench(&config, &out)).map(|text| println!("{text}"))
            }
            BenchMode::GiIndirect { spp, scenes, seeds } => {
                let config = IndirectConfig { width: 160, height: 90, reference_spp: spp, only: scenes, seeds };
                on_gpu(|| run_indirect_bench(&config, &out)).map(|text| println!("{text}"))
            }
            BenchMode::Daylight { spp } => {
                let config = DaylightConfig::new(spp);
                on_gpu(|| run_daylight_bench(&config, &out)).map(|text| println!("{text}"))
            }
            BenchMode::Denoise { spp, section, seeds, size: (width, height), set, lattice, scenes, sizes } => {
                check_lattice(lattice, width, height)?;
                check_scenes(&scenes, section)?;
                let config = DenoiseConfig {
                    section,
                    seeds,
                    settings: set,
                    lattice,
                    scenes,
                    cost_sizes: sizes,
                    ..DenoiseConfig::new(width, height, spp)
                };
                on_gpu(|| run_denoise_bench(&config, &out)).map(|text| println!("{text}"))
            }
            BenchMode::Frame { quick, sizes, scenes, set } => {
                let mut config = if quick { FrameConfig::quick() } else { FrameConfig::full(sizes.clone()) };
                if quick && !sizes.is_empty() {
                    config.sizes = sizes;
                }
                config.cases = pick_cases(config.cases, &scenes)?;
                RenderSettings::game().with_pairs(&set)?;
                config.extra = set;
                on_gpu(|| run_frame_bench(&config, quick, &out))
            }
            BenchMode::Travel { quick } => {
                let config = if quick { TravelConfig::quick() } else { TravelConfig::full() };
                run_travel_bench(&config, &out).map(|text| println!("{text}"))
            }
            BenchMode::Net { quick } => {
                let config = if quick { NetBenchConfig::quick() } else { NetBenchConfig::full() };
                run_net_bench(&config, &out).map(|text| println!("{text}"))
            }
            BenchMode::Rays { quick, scenes } => {
                let config = if quick { RaysConfig::quick() } else { RaysConfig::full() };
                let cases = pick_rays_cases(&scenes)?;
                let rows = run_rays_bench(&cases, &config, &out)?;
                println!("wrote {} rows to {}/rays.md, rays.csv", rows.len(), out.display());
                Ok(())
            }
        }
    }

    /// The mode the flags pick; clap has already refused `--thesis` with `--gi` and every flag of another mode.
    fn mode(self) -> BenchMode {
        if self.thesis {
            BenchMode::Thesis(ThesisOptions {
                scale: self.scale,
                spp: self.spp,
                lattice: self.lattice,
                views: self.views,
                area_only: self.area_only,
                settings: self.set,
            })
        } else if self.gi && self.indirect {
            BenchMode::GiIndirect { spp: self.spp, scenes: self.scenes.clone(), seeds: self.seeds }
        } else if self.gi {
            BenchMode::Gi { spp: self.spp, game_sizes: self.game_sizes, sizes: self.sizes.clone() }
        } else if self.daylight {
            BenchMode::Daylight { spp: self.spp }
        } else if self.denoise {
            let section = if self.motion {
                Some(DenoiseSection::Motion)
            } else if self.reaction {
                Some(DenoiseSection::Reaction)
            } else if self.one_frame {
                Some(DenoiseSection::Frame)
            } else if self.cost {
                Some(DenoiseSection::Cost)
            } else if self.upscale {
                Some(DenoiseSection::Upscale)
            } else {
                None
            };
            BenchMode::Denoise {
                spp: self.spp,
                section,
                seeds: self.seeds,
                size: self.size.unwrap_or((160, 90)),
                set: self.set,
                lattice: self.lattice,
                scenes: self.scenes,
                sizes: self.sizes,
            }
        } else if self.frame {
            BenchMode::Frame { quick: self.quick, sizes: self.sizes, scenes: self.scenes, set: self.set }
        } else if self.rays {
            BenchMode::Rays { quick: self.quick, scenes: self.scenes }
        } else if self.travel {
            BenchMode::Travel { quick: self.quick }
        } else if self.net {
            BenchMode::Net { quick: self.quick }
        } else {
            BenchMode::Settings { scenes: self.scenes, quick: self.quick, only: self.settings, camera: self.camera }
        }
    }
}

fn run_settings(
    scenes: Vec<String>,
    quick: bool,
    only: Vec<String>,
    camera: Option<CameraView>,
    out: &Path,
) -> Result<(), String> {
    let defaults = if quick { QUICK_SCENES } else { ALL_SCENES };
    let scenes = if scenes.is_empty() { defaults.iter().map(|s| s.to_string()).collect() } else { scenes };
    let mut config = if quick { SweepConfig::quick() } else { SweepConfig::full() };
    config.camera = camera;
    config.only = only;
    let rows = on_gpu(|| run_bench(&scenes, &config, out))?;
    println!("wrote {} rows to {}/results.csv, report.md, plot.svg, strip-*.png", rows.len(), out.display());
    Ok(())
}

/// The frame profile's cases named by `--scenes` (all of `cases` when none is named).
fn pick_cases(cases: Vec<FrameCase>, names: &[String]) -> Result<Vec<FrameCase>, String> {
    if let Some(unknown) = names.iter().find(|n| !CASES.iter().any(|c| c.label == n.as_str())) {
        let valid: Vec<&str> = CASES.iter().map(|c| c.label).collect();
        return Err(format!("--frame has no scene '{unknown}' (valid: {})", valid.join(", ")));
    }
    if names.is_empty() {
        return Ok(cases);
    }
    Ok(CASES.into_iter().filter(|c| names.iter().any(|n| n == c.label)).collect())
}

/// The ray bench's cases named by `--scenes` (all when none is named).
fn pick_rays_cases(names: &[String]) -> Result<Vec<RaysCase>, String> {
    if let Some(unknown) = names.iter().find(|n| !RAYS_CASES.iter().any(|c| c.label == n.as_str())) {
        let valid: Vec<&str> = RAYS_CASES.iter().map(|c| c.label).collect();
        return Err(format!("--rays has no scene '{unknown}' (valid: {})", valid.join(", ")));
    }
    Ok(RAYS_CASES.into_iter().filter(|c| names.is_empty() || names.iter().any(|n| n == c.label)).collect())
}

/// `WxH`, both at least 1.
fn parse_size(text: &str) -> Result<(u32, u32), String> {
    let parsed = text.split_once('x').and_then(|(w, h)| Some((w.parse::<u32>().ok()?, h.parse::<u32>().ok()?)));
    match parsed {
        Some((w, h)) if w > 0 && h > 0 => Ok((w, h)),
        _ => Err(format!("'{text}' is not a size WxH such as 320x180")),
    }
}
