//! The denoiser bench's reaction section (`glowbrick bench --denoise`, and alone with `--reaction`): a lamp
//! switched off and on again in a still view, the light it lit frame by frame against the values the renderer
//! settles to, raw and denoised, at night and by day.

use super::denoise::{ACCUMULATED_FRAMES, DenoiseConfig, SETTLE_FRAMES, renderer};
use crate::headless::HeadlessRenderer;
use crate::image_io::LinearImage;
use crate::settings::RenderSettings;
use crate::world::events::EditRequest;
use crate::world::recipe::load_scene;
use crate::world::{CameraView, Edit, VoxelWorld};
use bevy::math::IVec3;
use std::time::Instant;

/// Frames a reaction is followed for after the edit.
const REACTION_FRAMES: usize = 16;

/// A lamp switched off, then on again, in a still view: the mean over the pixels it lights, frame by frame after
/// each edit, and the values the same renderer's frames settle to after each.
pub(crate) struct Reaction {
    /// "night" or "day".
    when: &'static str,
    denoise: &'static str,
    pixels: usize,
    lit: f64,
    unlit: f64,
    off: Vec<f64>,
    on: Vec<f64>,
    /// Wall time of the frame after the edit (the GI cache's restart), mean of the two edits, and of a settled
    /// frame.
    restart_ms: f64,
    frame_ms: f64,
}

impl Reaction {
    /// The first frame after the edit from which every later followed frame is within 10% of `target`.
    fn frames_to(trajectory: &[f64], target: f64) -> Option<usize> {
        let within = |v: &f64| (v - target).abs() <= 0.1 * target.max(1e-12);
        match trajectory.iter().rposition(|v| !within(v)) {
            None => Some(1),
            Some(i) if i + 1 < trajectory.len() => Some(i + 2),
            Some(_) => None,
        }
    }
    fn off_frames(&self) -> Option<usize> {
        Self::frames_to(&self.off, self.unlit)
    }
    fn on_frames(&self) -> Option<usize> {
        Self::frames_to(&self.on, self.lit)
    }
}

/// The test room at one time of day, its lamp (a column of two voxels) and the pixels that lamp lights: where it
/// more than doubles the light of two fresh renderers, with and without it, settled and accumulated. Shared by
/// the raw and the denoised run, so both measure the same pixels.
struct LampScene {
    world: VoxelWorld,
    view: CameraView,
    time: &'static str,
    lamp: u16,
    affected: Vec<usize>,
}

const LAMP_MIN: IVec3 = IVec3::new(24, 1, 24);
const LAMP_MAX: IVec3 = IVec3::new(24, 2, 24);

impl LampScene {
    fn new(config: &DenoiseConfig, time: &'static str) -> Result<Self, String> {
        let world = load_scene("test-room").map_err(|e| e.to_string())?;
        let view = world.view(Some("inside")).cloned().ok_or("test-room: no view 'inside'")?;
        let lamp = world.palette.id_of("lamp").ok_or("test-room: no lamp")?;
        let mut dark = world.clone();
        dark.apply(Self::edit(0)).map_err(|e| e.to_string())?;
        let size = (config.width, config.height);
        let accumulated = |w: &VoxelWorld| -> Result<LinearImage, String> {
            let mut r = renderer(w, &view, size, &[time], &config.settings)?;
            r.render(SETTLE_FRAMES)?;
            r.app_mut().world_mut().resource_mut::<RenderSettings>().accumulate = true;
            r.render(ACCUMULATED_FRAMES)
        };
        let (lit, unlit) = (accumulated(&world)?, accumulated(&dark)?);
        let affected = (0..lit.pixels.len()).filter(|&i| lit.pixels[i][1] > 2.0 * unlit.pixels[i][1] + 0.005).collect();
        Ok(LampScene { world, view, time, lamp, affected })
    }

    /// The lamp's voxels set to `material` (0: switched off).
    fn edit(material: u16) -> Edit {
        Edit::FillBox { min: LAMP_MIN, max: LAMP_MAX, material }
    }

    fn mean(&self, image: &LinearImage) -> f64 {
        self.affected.iter().map(|&i| image.pixels[i][1] as f64).sum::<f64>() / self.affected.len().max(1) as f64
    }
}

/// The lamp switched off, then on again, with the denoiser `denoise` ("denoise=on|off").
fn reaction(
    config: &DenoiseConfig,
    scene: &LampScene,
    when: &'static str,
    denoise: &'static str,
) -> Result<Reaction, String> {
    // Each realisation (seed) follows the same edits; their trajectories and targets are averaged: one
    // realisation's dark room swings by 10-15% over tens of frames with the GI cache's slow noise.
    let seeds = config.seeds.max(1);
    let (mut off, mut on) = (vec![0.0; REACTION_FRAMES], vec![0.0; REACTION_FRAMES]);
    let (mut unlit, mut lit, mut restart_ms, mut frame_ms) = (0.0, 0.0, 0.0, 0.0);
    for seed in 0..seeds {
        let run = follow_edits(config, scene, denoise, seed)?;
        for i in 0..REACTION_FRAMES {
            off[i] += run.off[i] / seeds as f64;
            on[i] += run.on[i] / seeds as f64;
        }
        unlit += run.unlit / seeds as f64;
        lit += run.lit / seeds as f64;
        restart_ms += run.restart_ms / seeds as f64;
        frame_ms += run.frame_ms / seeds as f64;
    }
    Ok(Reaction { when, denoise, pixels: scene.affected.len(), lit, unlit, off, on, restart_ms, frame_ms })
}

/// One realisation of `reaction`: trajectories, targets and wall times.
struct Followed {
    off: Vec<f64>,
    on: Vec<f64>,
    unlit: f64,
    lit: f64,
    restart_ms: f64,
    frame_ms: f64,
}

fn follow_edits(
    config: &DenoiseConfig,
    scene: &LampScene,
    denoise: &'static str,
    seed: u32,
) -> Result<Followed, String> {
    let seed = format!("seed={seed}");
    let mut r = renderer(
        &scene.world,
        &scene.view,
        (config.width, config.height),
        &[scene.time, denoise, &seed],
        &config.settings,
    )?;
    r.render(SETTLE_FRAMES)?;
    // The means of the frames after an edit, and the first one's wall time (the cache's restart).
    let follow = |r: &mut HeadlessRenderer, edit: Edit| -> Result<(Vec<f64>, f64), String> {
        r.app_mut().world_mut().write_message(EditRequest::player(edit));
        let start = Instant::now();
        let first = scene.mean(&r.render_next()?);
        let ms = start.elapsed().as_secs_f64() * 1000.0;
        let rest: Result<Vec<f64>, String> =
            (1..REACTION_FRAMES).map(|_| r.render_next().map(|image| scene.mean(&image))).collect();
        Ok((std::iter::once(first).chain(rest?).collect(), ms))
    };
    // Each target is what this renderer's frames settle to after the edit (the mean of its frames
    // SETTLE_FRAMES to 2 x SETTLE_FRAMES after it), with their mean wall time: the filter's own bias is in the
    // tables above, not in how fast it reacts.
    let settled = |r: &mut HeadlessRenderer| -> Result<(f64, f64), String> {
        r.render(SETTLE_FRAMES - REACTION_FRAMES as u32)?;
        let start = Instant::now();
        let frames: Result<Vec<f64>, String> =
            (0..SETTLE_FRAMES).map(|_| r.render_next().map(|i| scene.mean(&i))).collect();
        let ms = start.elapsed().as_secs_f64() * 1000.0 / SETTLE_FRAMES as f64;
        Ok((frames?.iter().sum::<f64>() / SETTLE_FRAMES as f64, ms))
    };
    let (off, off_ms) = follow(&mut r, LampScene::edit(0))?;
    let (unlit, _) = settled(&mut r)?;
    let (on, on_ms) = follow(&mut r, LampScene::edit(scene.lamp))?;
    let (lit, frame_ms) = settled(&mut r)?;
    Ok(Followed { off, on, unlit, lit, restart_ms: (off_ms + on_ms) / 2.0, frame_ms })
}

pub(crate) fn reaction_markdown(reactions: &[Reaction], seeds: u32) -> String {
    let frames = |f: Option<usize>| f.map_or(format!("more than {REACTION_FRAMES}"), |f| f.to_string());
    let mut text = format!(
        "\n## Reaction\n\nThe test room, the game's frame: its lamp switched off after {SETTLE_FRAMES} frames, then \
         on again after {SETTLE_FRAMES} more; the mean over the pixels it lights (where it more than doubles the \
         light), frame by frame after the edit, as a share of the value the same renderer's frames settle to (the \
         mean of frames {SETTLE_FRAMES} to {} after the edit), both averaged over {seeds} seed(s) (independent \
         realisations: one realisation's dark room swings by 10-15% over tens of frames). At night the lamp is nearly all the light: unlit, \
         the room is the moon's faint bounce light. Restart: the wall time of the frame after the edit (the GI \
         cache starts over: its update runs {} times, each entry's direct light takes {} samples) against a \
         settled frame's.\n\n| time | denoiser | pixels | unlit | lit | lit / unlit | frames to within 10%, off | \
         on | restart ms | frame ms |\n|---|---|---|---|---|---|---|---|---|---|\n",
        2 * SETTLE_FRAMES,
        crate::render::gi::RESTART_ITERATIONS,
        crate::render::gpu_types::GI_RESTART_DIRECT_SAMPLES
    );
    for r in reactions {
        text += &format!(
            "| {} | {} | {} | {:.6} | {:.5} | {:.0} | **{}** | **{}** | {:.1} | {:.1} |\n",
            r.when,
            r.denoise,
            r.pixels,
            r.unlit,
            r.lit,
            r.lit / r.unlit.max(1e-12),
            frames(r.off_frames()),
            frames(r.on_frames()),
            r.restart_ms,
            r.frame_ms
        );
    }
    text += "\n| time | denoiser | frame after the edit |";
    let shown = [0usize, 1, 2, 3, 4, 5, 7, 11, 15];
    for &i in &shown {
        text += &format!(" {} |", i + 1);
    }
    text += "\n|---|---|---|";
    text += &"---|".repeat(shown.len());
    for r in reactions {
        for (name, trajectory, target) in [("switched off", &r.off, r.unlit), ("switched on", &r.on, r.lit)] {
            text += &format!("\n| {} | {} | {name} |", r.when, r.denoise);
            for &i in &shown {
                text += &format!(" {:.0}% |", 100.0 * trajectory[i] / target.max(1e-12));
            }
        }
    }
    text + "\n"
}

/// The reaction at night and by day, raw and denoised.
pub(crate) fn reactions(config: &DenoiseConfig) -> Result<Vec<Reaction>, String> {
    let mut all = Vec::new();
    for (when, time) in [("night", "time=0"), ("day", "time=10")] {
        let scene = LampScene::new(config, time)?;
        for denoise in ["denoise=off", "denoise=on"] {
            all.push(reaction(config, &scene, when, denoise)?);
        }
    }
    Ok(all)
}
