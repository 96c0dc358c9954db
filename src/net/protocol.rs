//! What client and server say to each other. Every message is plain data (postcard on the wire); nothing a client
//! sends names a file, a setting of the server or another player.

use crate::world::objects::SavedObject;
use crate::world::{Edit, Material, Voxel};
use bevy::math::IVec3;
use bevy::prelude::*;
use bevy_replicon::prelude::*;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// An edit as it travels: `world::Edit` with plain arrays.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum NetEdit {
    Place { at: [i32; 3], material: Voxel },
    Break { at: [i32; 3] },
    FillBox { min: [i32; 3], max: [i32; 3], material: Voxel },
    Restore { min: [i32; 3], max: [i32; 3], voxels: Vec<Voxel> },
}

impl From<&Edit> for NetEdit {
    fn from(edit: &Edit) -> Self {
        match edit {
            Edit::Place { at, material } => NetEdit::Place { at: at.to_array(), material: *material },
            Edit::Break { at } => NetEdit::Break { at: at.to_array() },
            Edit::FillBox { min, max, material } => {
                NetEdit::FillBox { min: min.to_array(), max: max.to_array(), material: *material }
            }
            Edit::Restore { min, max, voxels } => {
                NetEdit::Restore { min: min.to_array(), max: max.to_array(), voxels: voxels.to_vec() }
            }
        }
    }
}

impl From<&NetEdit> for Edit {
    fn from(edit: &NetEdit) -> Self {
        let v = IVec3::from_array;
        match edit {
            NetEdit::Place { at, material } => Edit::Place { at: v(*at), material: *material },
            NetEdit::Break { at } => Edit::Break { at: v(*at) },
            NetEdit::FillBox { min, max, material } => {
                Edit::FillBox { min: v(*min), max: v(*max), material: *material }
            }
            NetEdit::Restore { min, max, voxels } => {
                Edit::Restore { min: v(*min), max: v(*max), voxels: Arc::from(voxels.as_slice()) }
            }
        }
    }
}

/// A material as it travels (`world::Material` skips zero fields in files, which postcard cannot read back).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NetMaterial {
    pub name: String,
    pub albedo: [f32; 3],
    pub emission: [f32; 3],
    pub strength: f32,
    pub variation: f32,
}

impl From<&Material> for NetMaterial {
    fn from(m: &Material) -> Self {
        NetMaterial {
            name: m.name.clone(),
            albedo: m.albedo,
            emission: m.emission,
            strength: m.strength,
            variation: m.variation,
        }
    }
}

impl From<&NetMaterial> for Material {
    fn from(m: &NetMaterial) -> Self {
        Material {
            name: m.name.clone(),
            albedo: m.albedo,
            emission: m.emission,
            strength: m.strength,
            variation: m.variation,
        }
    }
}

// --- client to server ---

/// The first thing a client says: who it is.
#[derive(Message, Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Hello {
    pub name: String,
}

/// Asks the server to apply an edit. `undoable` edits come back marked so the sender's undo records them.
///
/// An edit may use materials the server's palette lacks (a dropped model's colours): they travel in `materials`,
/// and the edit names them by the ids they would take after the palette the sender has from the server, from
/// `first_new` on. The server adds them (or finds them by name) and renumbers the edit.
#[derive(Message, Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EditAsk {
    pub edit: NetEdit,
    pub undoable: bool,
    pub first_new: u16,
    pub materials: Vec<NetMaterial>,
}

impl EditAsk {
    /// An edit of materials the server already has.
    pub fn plain(edit: NetEdit, undoable: bool) -> Self {
        EditAsk { edit, undoable, first_new: 0, materials: Vec::new() }
    }
}

/// Asks the server to undo (or redo) the sender's latest edit. The server keeps each player's stacks by name, so
/// they outlast a reconnect.
#[derive(Message, Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct HistoryAsk {
    pub redo: bool,
}

/// Asks the server to spawn a moving object (a built-in model; its `age` is ignored: it starts now).
#[derive(Message, Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SpawnAsk {
    pub object: SavedObject,
}

/// Asks the server to set the time of day (hours, 0-24).
#[derive(Message, Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClockAsk {
    pub hours: f32,
}

/// Where the sender's camera is (voxels) and which way it looks (yaw, radians).
#[derive(Message, Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    pub position: [f32; 3],
    pub yaw: f32,
}

/// Asks for region `key` (a world key) of the endless world: the sender holds it from now until it lets it go,
/// and hears every edit that touches it meanwhile. `ticket` comes back with the reply.
#[derive(Message, Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RegionAsk {
    pub key: [i32; 2],
    pub ticket: u32,
}

/// The sender no longer holds region `key`, asked for with `ticket` (each message kind has its own channel, so a
/// later ask for the same region may overtake this: the ticket tells them apart).
#[derive(Message, Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RegionLetGo {
    pub key: [i32; 2],
    pub ticket: u32,
}

// --- server to client ---

/// The receiver joined an endless world: it makes every region nobody changed itself, from `seed` and `height`,
/// and asks the server for the rest (`RegionAsk`). Its edits and poses travel in world coordinates. `player` is
/// the receiver's id; `seq` the number of the last edit.
#[derive(Message, Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct EndlessWelcome {
    pub seed: u32,
    pub height: u32,
    pub seq: u64,
    pub player: u64,
    pub hours: f32,
}

/// Region `key` as it was after edit `seq`, for ask `ticket`. `count` 0: nobody has changed it, the receiver
/// makes it from the seed; else piece `index` of `count` of the deflated region file.
#[derive(Message, Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RegionPiece {
    pub key: [i32; 2],
    pub ticket: u32,
    pub seq: u64,
    pub index: u32,
    pub count: u32,
    pub bytes: Vec<u8>,
}

/// One piece of the world as it was after edit `seq` (a deflated RON world file, cut in pieces). `player` is the
/// receiver's id, so it can tell its own edits among the broadcasts.
#[derive(Message, Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct WorldPiece {
    pub seq: u64,
    /// The server's object clock (seconds) when the world was copied: its objects' ages are as of then.
    pub clock: f64,
    pub player: u64,
    pub index: u32,
    pub count: u32,
    pub bytes: Vec<u8>,
}

/// A change the server made, number `seq` (1, 2, 3, ... with no gaps), asked for by player `by`. `materials`
/// join the end of the palette first, in order (every client's palette is the server's).
#[derive(Message, Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EditDone {
    pub seq: u64,
    pub by: u64,
    pub undoable: bool,
    pub materials: Vec<NetMaterial>,
    pub change: Change,
}

/// What an `EditDone` changed. Spawns travel in the edits' one numbered order, so a client joining with a world
/// as of edit `seq` gets every object spawned after it exactly once.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Change {
    Edit(NetEdit),
    /// A moving object, at age 0 when the server's object clock read `born` (seconds).
    Spawn {
        object: SavedObject,
        born: f64,
    },
}

/// The server's object clock (seconds), a few times a second: moving objects' phases follow it, not the
/// client's frame rate.
#[derive(Message, Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ServerTime {
    pub seconds: f64,
}

/// Why the server refused the receiver's request.
#[derive(Message, Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Refused {
    pub reason: String,
}

/// A line from the server's operator (`say`), or why the receiver is being disconnected (kick, ban).
#[derive(Message, Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Notice {
    pub text: String,
    /// The server disconnects the receiver after this (kicked, banned).
    pub farewell: bool,
}

/// Where the receiver was when it last left this server (a player of its name, within the last minutes): it
/// returns there.
#[derive(Message, Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct WelcomeBack {
    pub pose: Pose,
}

/// The time of day, after a player changed it.
#[derive(Message, Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClockNow {
    pub hours: f32,
}

/// One player as the others see it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlayerInfo {
    pub id: u64,
    pub name: String,
    pub pose: Option<Pose>,
}

/// Everyone playing, a few times a second.
#[derive(Message, Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Players {
    pub players: Vec<PlayerInfo>,
}

/// Registers every message on both sides, in one order (replicon checks that client and server agree).
pub fn register_messages(app: &mut App) {
    app.add_client_message::<Hello>(Channel::Ordered)
        .add_client_message::<EditAsk>(Channel::Ordered)
        .add_client_message::<ClockAsk>(Channel::Ordered)
        .add_client_message::<Pose>(Channel::Unreliable)
        .add_client_message::<SpawnAsk>(Channel::Ordered)
        .add_client_message::<HistoryAsk>(Channel::Ordered)
        .add_client_message::<RegionAsk>(Channel::Ordered)
        .add_client_message::<RegionLetGo>(Channel::Ordered)
        .add_server_message::<WorldPiece>(Channel::Ordered)
        .add_server_message::<EditDone>(Channel::Ordered)
        .add_server_message::<Refused>(Channel::Ordered)
        .add_server_message::<ClockNow>(Channel::Ordered)
        .add_server_message::<Players>(Channel::Ordered)
        .add_server_message::<Notice>(Channel::Ordered)
        .add_server_message::<WelcomeBack>(Channel::Ordered)
        .add_server_message::<EndlessWelcome>(Channel::Ordered)
        .add_server_message::<RegionPiece>(Channel::Ordered)
        .add_server_message::<ServerTime>(Channel::Unreliable);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edits_survive_the_trip() {
        let edits = [
            Edit::Place { at: IVec3::new(1, -2, 3), material: 7 },
            Edit::Break { at: IVec3::new(4, 5, 6) },
            Edit::FillBox { min: IVec3::ZERO, max: IVec3::splat(9), material: 2 },
            Edit::Restore { min: IVec3::ONE, max: IVec3::new(2, 1, 1), voxels: Arc::from([3u16, 0].as_slice()) },
        ];
        for edit in edits {
            let mut buffer = [0u8; 256];
            let bytes = bevy_replicon::postcard::to_slice(&NetEdit::from(&edit), &mut buffer).unwrap();
            let back: NetEdit = bevy_replicon::postcard::from_bytes(bytes).unwrap();
            assert_eq!(Edit::from(&back), edit);
        }
    }
}
