//! Playing the endless world (`glowbrick play --endless`): the window follows the player (`world::follow`), the
//! light pool follows the window (`lights::window`), and F5 and F9 save and load the regions the player changed
//! (`world::region_save`) with where the player stands and the time of day.
//!
//! Everything in game works in the window's coordinates: its column (0, 0) is a fixed world column for the
//! whole session, so positions stay small numbers near wherever the player started.

use super::hud::StatusLine;
use super::player::Player;
use super::save_load::{SaveAction, player_view};
use crate::dynamic::DynamicObject;
use crate::dynamic::saved::saved_objects;
use crate::lights::LightPool;
use crate::lights::window::{LIGHT_BUDGET, WindowLights};
use crate::world::events::{ApplyEdits, EditApplied};
use crate::world::follow::{STREAM_RADIUS, WINDOW_REGIONS, WRITE_BUDGET, WindowFollower};
use crate::world::generate::endless::{EndlessGenerator, REGION_EDGE};
use crate::world::objects::SavedObject;
use crate::world::region_save::EndlessSave;
use crate::world::stream::MakeRegion;
use crate::world::{CameraView, VoxelWorld};
use bevy::prelude::*;
use std::sync::{Arc, Mutex};

/// The endless world being played: its follower, the lighting of regions a scroll brought in, and its save.
#[derive(Resource)]
pub struct EndlessPlay {
    /// In a mutex only because the streamer's channel may not be shared between threads; one system uses it.
    follower: Mutex<WindowFollower>,
    lights: WindowLights,
    save: EndlessSave,
    workers: usize,
}

impl EndlessPlay {
    /// Opens the endless world of `save` around where its player last stood (else above the first village),
    /// its regions made by `workers` threads, saved ones read from the folder. Returns the world with the
    /// player's view (window coordinates) as its first view, and its saved time of day.
    pub fn open(save: EndlessSave, workers: usize) -> Result<(EndlessPlay, VoxelWorld), String> {
        let generator = Arc::new(EndlessGenerator::new(save.seed, save.height)?);
        // Where the player stands, as a region key and an offset from its corner: exact however far out.
        let (key, offset, view) = match &save.player {
            Some((key, view)) => (*key, Vec3::from(view.origin), view.clone()),
            None => {
                let view = generator.start_view();
                let [x, _, z] = view.origin;
                let key = EndlessGenerator::region_of(x.floor() as i32, z.floor() as i32);
                let corner = Vec3::new((key.x * REGION_EDGE) as f32, 0.0, (key.y * REGION_EDGE) as f32);
                (key, Vec3::from(view.origin) - corner, view)
            }
        };
        let offset_regions = (Vec2::new(offset.x, offset.z) / REGION_EDGE as f32).floor().as_ivec2();
        let centre = key + offset_regions;
        let make = region_maker(generator.clone(), save.clone());
        let (follower, window) =
            WindowFollower::start_with(generator, make, centre, WINDOW_REGIONS, STREAM_RADIUS, workers);
        let corner = (key * REGION_EDGE - window.min).as_vec2();
        let origin = Vec3::new(corner.x, 0.0, corner.y) + offset;
        let mut world = window.world;
        world.views = vec![CameraView { origin: origin.into(), ..view }];
        world.time_of_day = save.time_of_day;
        // A save that has a player has its objects, none or some; a new world gets the default ones.
        // In i64: a crafted save may put an object and the player at the two ends of the world.
        let region_corner = |key: IVec2| (key.as_i64vec2() * REGION_EDGE as i64 - window.min.as_i64vec2()).as_vec2();
        world.objects = save.player.is_some().then(|| {
            save.objects
                .iter()
                .map(|(key, object)| {
                    let corner = region_corner(*key);
                    let (x, y, z) = object.anchor;
                    SavedObject { anchor: (x + corner.x, y, z + corner.y), ..object.clone() }
                })
                .collect()
        });
        let play = EndlessPlay { follower: Mutex::new(follower), lights: WindowLights::default(), save, workers };
        Ok((play, world))
    }

    /// The save folder.
    pub fn folder(&self) -> &std::path::Path {
        &self.save.folder
    }

    /// The world column of the window's coordinates' column (0, 0).
    pub fn window_min(&self) -> IVec2 {
        self.follower.lock().unwrap_or_else(|e| e.into_inner()).min()
    }

    /// Boxes a finished scroll brought in that are still to be lit.
    pub fn lights_waiting(&self) -> usize {
        self.lights.waiting()
    }

    fn follower(&mut self) -> &mut WindowFollower {
        self.follower.get_mut().unwrap_or_else(|e| e.into_inner())
    }
}

/// Makes a region from the save folder where it holds one, else from the generator. A saved region that cannot
/// be read is reported and the generator's is played instead; its file is left as it is (an F5 after an edit
/// there writes over it, keeping it as `.bak`).
fn region_maker(generator: Arc<EndlessGenerator>, save: EndlessSave) -> MakeRegion {
    Arc::new(move |key| match save.load_region(key, generator.palette()) {
        Ok(Some(region)) => region,
        Ok(None) => generator.region(key),
        Err(e) => {
            warn!("{e}; playing the generator's region {key} instead");
            generator.region(key)
        }
    })
}

pub struct EndlessPlugin;

impl Plugin for EndlessPlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(Startup, say_where_saves_go.run_if(resource_exists::<EndlessPlay>)).add_systems(
            Update,
            (note_edits, follow_player, save_or_load_regions)
                .chain()
                .after(ApplyEdits)
                .run_if(resource_exists::<EndlessPlay>)
                .run_if(resource_exists::<VoxelWorld>),
        );
    }
}

/// Tells the player which world this is and where F5 writes.
fn say_where_saves_go(play: Res<EndlessPlay>, mut status: ResMut<StatusLine>) {
    status.show(format!(
        "the endless world of seed {}: F5 saves the regions you change into {}",
        play.save.seed,
        play.save.folder.display()
    ));
}

/// Which regions the player's edits changed.
fn note_edits(mut edits: MessageReader<EditApplied>, mut play: ResMut<EndlessPlay>, world: Res<VoxelWorld>) {
    for edit in edits.read().filter(|e| e.changed > 0) {
        play.follower().note_edit(&world, edit.min, edit.max);
    }
}

/// Streams and scrolls after the player, and lights what a scroll brought in, within the tick's budgets.
fn follow_player(
    mut play: ResMut<EndlessPlay>,
    mut world: ResMut<VoxelWorld>,
    mut pool: ResMut<LightPool>,
    camera: Query<&Transform, With<Player>>,
) {
    let Ok(transform) = camera.single() else { return };
    let play = &mut *play;
    // Only a tick that wrote something tells the systems watching the world that it changed.
    let followed = play.follower().follow(world.bypass_change_detection(), transform.translation, WRITE_BUDGET);
    let wrote = followed.began.is_some() || followed.regions_written > 0 || followed.finished.is_some();
    play.lights.followed(&mut pool, &world, &followed);
    if play.lights.waiting() > 0 {
        play.lights.update(&mut pool, &world, LIGHT_BUDGET);
    }
    if let Some(plan) = &followed.finished {
        let lo = IVec2::new(plan.lo.x, plan.lo.z) + play.window_min();
        info!("the window moved: it starts at world column {lo}, {} regions came in", plan.keys.len());
    }
    if wrote {
        world.set_changed();
    }
}

/// F5 writes the regions changed since the last save, where the player stands and the time of day; F9 reopens
/// the save (the player's unsaved changes are dropped, as F9 drops them in a bounded world).
#[allow(clippy::too_many_arguments)]
fn save_or_load_regions(
    mut actions: MessageReader<SaveAction>,
    mut play: ResMut<EndlessPlay>,
    mut world: ResMut<VoxelWorld>,
    mut camera: Query<(&mut Transform, &mut Player, &Projection)>,
    mut settings: Option<ResMut<crate::settings::RenderSettings>>,
    mut status: ResMut<StatusLine>,
    mut commands: Commands,
    objects: Query<(Entity, &DynamicObject)>,
) {
    for action in actions.read() {
        match action {
            SaveAction::Save => {
                let start = std::time::Instant::now();
                let hours = settings.as_ref().map(|s| s.time);
                let view = camera.single().ok().map(|(transform, _, projection)| {
                    let fov = match projection {
                        Projection::Perspective(p) => p.fov.to_degrees(),
                        _ => 60.0,
                    };
                    player_view(transform, fov)
                });
                let live = saved_objects(objects.iter().map(|(_, o)| o));
                match save_regions(&mut play, &world, view, hours, &live) {
                    Ok((count, bytes)) => status.show(format!(
                        "saved {} ({count} changed region{}, {:.2} MB, in {:.2} s)",
                        play.save.folder.display(),
                        if count == 1 { "" } else { "s" },
                        bytes as f64 / 1e6,
                        start.elapsed().as_secs_f64()
                    )),
                    Err(e) => status.show(format!("could not save {}: {e}", play.save.folder.display())),
                }
            }
            SaveAction::Load => {
                let start = std::time::Instant::now();
                let reopened = EndlessSave::open(&play.save.folder)
                    .map_err(|e| e.to_string())
                    .and_then(|save| EndlessPlay::open(save, play.workers));
                match reopened {
                    Ok((reopened, loaded)) => {
                        if let (Some(view), Ok((mut transform, mut player, _))) =
                            (loaded.view(None), camera.single_mut())
                        {
                            *transform = crate::world::view_transform(view);
                            *player = Player { walking: player.walking, ..Player::looking(view) };
                        }
                        if let (Some(settings), Some(hours)) = (settings.as_mut(), loaded.time_of_day) {
                            settings.time = hours;
                        }
                        // A save never written with F5 has no objects of its own: the live ones stay.
                        if let Some(saved) = loaded.objects.clone() {
                            objects.iter().for_each(|(entity, _)| commands.entity(entity).despawn());
                            commands.queue(move |app_world: &mut World| {
                                super::objects::spawn_saved_or_report(app_world, &saved)
                            });
                        }
                        *play = reopened;
                        *world = loaded;
                        status.show(format!(
                            "loaded {} in {:.2} s",
                            play.save.folder.display(),
                            start.elapsed().as_secs_f64()
                        ));
                    }
                    Err(e) => status.show(format!("load failed, world unchanged: {e}")),
                }
            }
        }
    }
}

/// The player's view as the loader accepts it: its height within the reach a save allows.
fn fit_player(view: CameraView) -> CameraView {
    let [x, y, z] = view.origin;
    let reach = crate::world::region_save::PLAYER_REACH;
    CameraView { origin: [x, y.clamp(-reach, reach), z], ..view }
}

/// Whether the loader accepts `object` (anchored from a region's corner) in a world `height` voxels high.
fn object_fits(object: &SavedObject, height: u32) -> bool {
    crate::world::region_save::check_object(object, height).is_ok()
}

/// Writes every region changed since the last save and `world.ron` (the player's `view` and the moving `objects`,
/// window coordinates, and the time); returns how many regions and the bytes of their files.
pub fn save_regions(
    play: &mut EndlessPlay,
    world: &VoxelWorld,
    view: Option<CameraView>,
    hours: Option<f32>,
    objects: &[SavedObject],
) -> Result<(usize, u64), String> {
    let follower = play.follower();
    let changed = follower.changed_regions(world);
    let mut bytes = 0;
    for (key, region) in &changed {
        play.save.save_region(*key, region)?;
        bytes += std::fs::metadata(play.save.region_path(*key)).map_or(0, |m| m.len());
    }
    let keys: Vec<IVec2> = changed.iter().map(|(key, _)| *key).collect();
    let follower = play.follower();
    follower.saved(&keys);
    // A region key and an offset from its corner: exact however far out.
    let (min, region_at) = (follower.min(), |p: Vec3| follower.region_at(p));
    let from_corner = |p: Vec3| {
        let key = region_at(p);
        let corner = (key * REGION_EDGE - min).as_vec2();
        (key, p - Vec3::new(corner.x, 0.0, corner.y))
    };
    let player = view.map(|view| {
        let (key, offset) = from_corner(Vec3::from(view.origin));
        (key, CameraView { origin: offset.into(), ..view })
    });
    let objects: Vec<(IVec2, SavedObject)> = objects
        .iter()
        .map(|object| {
            let (key, offset) = from_corner(Vec3::from(object.anchor));
            (key, SavedObject { anchor: offset.into(), ..object.clone() })
        })
        .collect();
    play.save.player = player.map(|(key, view)| (key, fit_player(view))).or(play.save.player.take());
    // The loader refuses an object it could not have made (flown far above the world, say): leave it out.
    let height = play.save.height;
    play.save.objects = objects.into_iter().filter(|(_, object)| object_fits(object, height)).collect();
    play.save.time_of_day = hours.or(play.save.time_of_day);
    play.save.write_world_file()?;
    Ok((changed.len(), bytes))
}
