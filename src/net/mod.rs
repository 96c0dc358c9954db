//! Building together: a dedicated server (`glowbrick serve`) that owns the world and clients (`glowbrick play
//! --connect`) that send their edits to it and apply everyone's edits in the server's one order.
//!
//! Built on bevy_replicon's messages over renet's UDP transport (netcode's connect tokens when the server has a
//! secret). Only messages travel, no replicated components: the world is far too large to replicate entity by
//! entity, and edits are small, so the protocol is the world file once and then numbered edits
//! (`protocol`). Every client applies the same edits in the same order to the same world, so its brick grid and
//! light pool end up identical to the server's (`state_hash` checks it).

pub mod client;
pub mod console;
pub mod endless_client;
pub mod endless_server;
pub mod materials;
pub mod protocol;
pub mod server;
pub mod snapshot;
pub mod state_hash;
pub mod transport;

use crate::lights::plugin::LightsPlugin;
use crate::world::VoxelWorld;
use crate::world::events::WorldEditPlugin;
use bevy::prelude::*;
use bevy::state::app::StatesPlugin;
use bevy_replicon::prelude::*;
use bevy_replicon_renet::RepliconRenetPlugins;

/// Replicon over renet and the protocol's messages: what both ends of a connection add.
pub struct NetworkingPlugin;

impl Plugin for NetworkingPlugin {
    fn build(&self, app: &mut App) {
        app.add_plugins((RepliconPlugins.set(ServerPlugin::new(PostUpdate)), RepliconRenetPlugins));
        protocol::register_messages(app);
    }
}

/// A server without window or GPU: the world, its edit path and light pool, and the server's rules. Call
/// `transport::listen` on it, then `update` it (`glowbrick serve` does, 60 times a second).
pub fn server_app(mut world: VoxelWorld, rules: server::ServerRules) -> App {
    resolve_object_models(&mut world);
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, StatesPlugin, NetworkingPlugin))
        .insert_resource(world)
        .insert_resource(rules)
        .add_plugins((WorldEditPlugin, LightsPlugin, server::NetServerPlugin));
    app.finish();
    app.cleanup();
    app
}

/// A server of the endless world `world` without window or GPU: no world file and no light pool, only the
/// regions it must hold (`endless_server`). Call `transport::listen` on it, then `update` it.
pub fn endless_server_app(world: endless_server::EndlessWorld, rules: server::ServerRules, hours: f32) -> App {
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, StatesPlugin, NetworkingPlugin))
        .insert_resource(rules)
        .add_plugins((server::NetServerPlugin, endless_server::EndlessServerPlugin))
        .insert_resource(world)
        .insert_resource(server::WorldClock(hours));
    app.finish();
    app.cleanup();
    app
}

/// Adds the materials the world's objects' models need to its palette before anyone joins: a client resolving
/// them itself would grow its palette where the server's did not, and the next material the server adds would
/// take a different id there. A model that cannot be resolved is left to each client's warning.
fn resolve_object_models(world: &mut VoxelWorld) {
    let models: Vec<String> = world.objects.iter().flatten().map(|o| o.model.clone()).collect();
    for model in models {
        if let Err(e) = crate::dynamic::model_for_palette(&model, &mut world.palette) {
            eprintln!("object model '{model}' cannot be resolved: {e}");
        }
    }
}

/// A client without window or GPU (tests, the bench): it receives the world (or, joining an endless server, makes
/// its window) and keeps its grid and light pool in step with the server's; `extra` adds plugins of the layers above (the game's undo). Call `transport::dial` on
/// it.
pub fn headless_client_app<M>(name: &str, extra: impl bevy::app::Plugins<M>) -> App {
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, StatesPlugin, NetworkingPlugin))
        .insert_resource(client::NetClient::named(name))
        .add_plugins((WorldEditPlugin, LightsPlugin, client::NetClientPlugin, endless_client::EndlessClientPlugin))
        .add_plugins(extra);
    app.finish();
    app.cleanup();
    app
}
