//! `glowbrick bot`: a headless player for load tests and soaks. No window and no GPU: it joins a server over UDP
//! as `play --connect` does (dialing again if the connection is lost), flies a circle around the middle of the
//! world and builds there (blocks, lamps, breaks) at `--edits-per-second`, for `--seconds`. Then it stops
//! building, waits until no edit has arrived for `QUIET_SECONDS`, and prints its world's state hash, which must be
//! the server's (`serve` prints its own when it stops).

use super::play::resolve;
use crate::net::client::{Join, NetClient};
use crate::net::endless_client::EndlessClient;
use crate::net::protocol::Pose;
use crate::net::state_hash::state_line;
use crate::net::{headless_client_app, transport};
use crate::world::events::EditRequest;
use crate::world::{Edit, VoxelWorld};
use bevy::math::{IVec3, Vec3};
use clap::Args;
use std::time::{Duration, Instant};

#[derive(Args)]
pub struct BotArgs {
    /// The server, HOST[:PORT].
    #[arg(long)]
    connect: String,
    /// The server's secret, if it has one.
    #[arg(long)]
    secret: Option<String>,
    /// The bot's name (default: bot-<process id>).
    #[arg(long)]
    name: Option<String>,
    /// Seconds of building after the world arrived.
    #[arg(long, default_value_t = 60.0)]
    seconds: f64,
    /// Edits a second while building (the server allows 30 by default).
    #[arg(long, default_value_t = 4.0)]
    edits_per_second: f64,
    /// Seconds to wait for the world to arrive before giving up.
    #[arg(long, default_value_t = 120.0)]
    join_timeout: f64,
}

/// The client's updates a second (a game's frame rate at the low end).
const BOT_HZ: f64 = 30.0;
/// Stopped building, the bot waits until no edit has arrived for this long before it reports its state.
const QUIET_SECONDS: f64 = 2.0;

impl BotArgs {
    pub fn run(self) -> Result<(), String> {
        if !(self.seconds.is_finite() && (0.0..=86_400.0).contains(&self.seconds)) {
            return Err(format!("--seconds {} must be within 0..86400", self.seconds));
        }
        if !(self.edits_per_second.is_finite() && (0.0..=1000.0).contains(&self.edits_per_second)) {
            return Err(format!("--edits-per-second {} must be within 0..1000", self.edits_per_second));
        }
        let name = self.name.clone().unwrap_or_else(|| format!("bot-{}", std::process::id()));
        let server = resolve(&self.connect)?;
        let mut app = headless_client_app(&name, ());
        app.insert_resource(Join { server, secret: self.secret.clone(), name: name.clone(), view: None });
        transport::dial(&mut app, server, self.secret.as_deref(), transport::fresh_client_id())?;
        let tick = Duration::from_secs_f64(1.0 / BOT_HZ);
        let started = Instant::now();
        let mut rng = (std::process::id() as u64) << 1 | 1;
        let mut building: Option<Instant> = None;
        let mut edits = 0u64;
        let mut last_seq = (0u64, Instant::now());
        loop {
            let frame = Instant::now();
            app.update();
            let client = app.world().resource::<NetClient>();
            if let Some(why) = client.sent_away.clone().or_else(|| client.error.clone()) {
                return Err(format!("{name}: the server sent it away: {why}"));
            }
            if !client.loaded {
                if building.is_none() && started.elapsed().as_secs_f64() > self.join_timeout {
                    return Err(format!("{name}: no world from {server} after {} s", self.join_timeout));
                }
            } else {
                let endless = app.world().contains_resource::<EndlessClient>();
                // The endless world's server takes neither a colour of one's own nor moving objects yet.
                if building.is_none() && !endless {
                    bring_colour_and_lantern(&mut app, &name);
                }
                let since = *building.get_or_insert_with(Instant::now);
                let seconds = since.elapsed().as_secs_f64();
                if seconds < self.seconds {
                    while (edits as f64) < seconds * self.edits_per_second {
                        edits += 1;
                        let edit = bot_edit(app.world().resource::<VoxelWorld>(), seconds, &mut rng);
                        app.world_mut().write_message(EditRequest::player(edit));
                    }
                    let pose = circle_pose(app.world().resource::<VoxelWorld>(), seconds);
                    match app.world_mut().get_resource_mut::<EndlessClient>() {
                        // Its window follows the bot, and tells the server where it is in world coordinates.
                        Some(mut endless) => {
                            endless.at = pose.position.into();
                            endless.yaw = pose.yaw;
                        }
                        None => {
                            app.world_mut().write_message(pose);
                        }
                    }
                } else {
                    let seq = app.world().resource::<NetClient>().seq;
                    if seq != last_seq.0 {
                        last_seq = (seq, Instant::now());
                    } else if last_seq.1.elapsed().as_secs_f64() > QUIET_SECONDS {
                        break;
                    }
                }
            }
            std::thread::sleep(tick.saturating_sub(frame.elapsed()));
        }
        let objects = {
            let mut live = app.world_mut().query::<&crate::dynamic::DynamicObject>();
            crate::dynamic::saved::saved_objects(live.iter(app.world()))
        };
        let world = app.world().resource::<VoxelWorld>();
        let seq = app.world().resource::<NetClient>().seq;
        let state = state_line(seq, world, app.world().resource::<crate::lights::LightPool>(), &objects);
        println!("{name}: asked for {edits} edits; {state}");
        Ok(())
    }
}

/// What a player brings to a server once: a block of a colour of its own (a dropped model's) and a lantern,
/// both at the start of its circle. The server adds the colour to everyone's palette and the lantern to
/// everyone's objects (or refuses them when it holds its most).
fn bring_colour_and_lantern(app: &mut bevy::app::App, name: &str) {
    let start = Vec3::from(circle_pose(app.world().resource::<VoxelWorld>(), 0.0).position);
    let hue = (name.bytes().fold(0u32, |h, b| h.wrapping_mul(31).wrapping_add(b as u32)) % 1000) as f32 / 1000.0;
    let colour = crate::world::Material::solid(&format!("colour of {name}"), [hue, 1.0 - hue, 0.5]);
    let id = app.world_mut().resource_mut::<VoxelWorld>().palette.push(colour);
    let size = app.world().resource::<VoxelWorld>().grid.size().as_ivec3();
    let at = (start.as_ivec3() + IVec3::new(0, -3, 0)).clamp(IVec3::ZERO, size - 1);
    app.world_mut().write_message(EditRequest::player(Edit::Place { at, material: id }));
    let motion = crate::dynamic::Motion::Drift { radius: 3.0, period: 8.0 };
    let object = crate::world::objects::SavedObject::new("lantern", &motion, start, 0.0);
    app.world_mut().write_message(crate::net::protocol::SpawnAsk { object });
}

/// Where the bot flies: a circle of a quarter of the world's width around its middle, above its middle height.
fn circle_pose(world: &VoxelWorld, seconds: f64) -> Pose {
    let size = world.grid.size().as_vec3();
    let angle = (seconds * 0.2) as f32;
    let centre = Vec3::new(size.x * 0.5, size.y * 0.6, size.z * 0.5);
    let at = centre + Vec3::new(angle.cos(), 0.0, angle.sin()) * size.x.min(size.z) * 0.25;
    Pose { position: at.to_array(), yaw: angle }
}

/// An edit within a few voxels of the bot's circle: mostly blocks of the world's materials, some breaks.
fn bot_edit(world: &VoxelWorld, seconds: f64, rng: &mut u64) -> Edit {
    let mut next = |n: u64| {
        *rng ^= *rng << 13;
        *rng ^= *rng >> 7;
        *rng ^= *rng << 17;
        *rng % n.max(1)
    };
    let size = world.grid.size().as_ivec3();
    let near = Vec3::from(circle_pose(world, seconds).position).as_ivec3();
    let jitter = IVec3::new(next(9) as i32 - 4, next(9) as i32 - 4, next(9) as i32 - 4);
    let at = (near + jitter).clamp(IVec3::ZERO, size - 1);
    match next(4) {
        0 => Edit::Break { at },
        _ => Edit::Place { at, material: 1 + next(world.palette.id_count() as u64 - 1) as u16 },
    }
}
