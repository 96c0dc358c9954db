//! Dropping a MagicaVoxel model into the world in front of the player (V), as one undoable edit: the model's
//! colours join the world palette, and an `Edit::Restore` writes the box it lands in with the model's solid
//! voxels laid over what was there (air in the model leaves the world as it was).

use super::hud::StatusLine;
use super::interaction::{Target, place_position};
use super::player::Player;
use crate::colour::srgb_to_linear;
use crate::world::events::{ApplyEdits, EditRequest};
use crate::world::import::vox::VoxFile;
use crate::world::{Edit, Material, VoxelWorld};
use bevy::prelude::*;
use std::sync::Arc;

/// The model V drops: voxels in world axes (y up) with their linear albedo.
#[derive(Resource, Clone, Debug)]
pub struct ModelToPlace {
    pub name: String,
    pub size: IVec3,
    pub voxels: Vec<(IVec3, [f32; 3])>,
}

impl ModelToPlace {
    /// The first model of a `.vox` file, z-up turned y-up.
    pub fn from_vox(name: &str, file: &VoxFile) -> Option<Self> {
        let model = file.models.first()?;
        let voxels = model
            .voxels
            .iter()
            .filter(|v| v[3] > 0)
            .map(|v| {
                let [r, g, b, _] = file.palette[v[3] as usize - 1];
                (
                    IVec3::new(v[0] as i32, v[2] as i32, v[1] as i32),
                    [srgb_to_linear(r), srgb_to_linear(g), srgb_to_linear(b)],
                )
            })
            .collect();
        let [sx, sy, sz] = model.size;
        Some(ModelToPlace { name: name.to_string(), size: IVec3::new(sx as i32, sz as i32, sy as i32), voxels })
    }
}

/// Asks to drop the model in front of the player.
#[derive(Message, Clone, Copy, Debug)]
pub struct PlaceModel;

pub struct ModelPlugin;

impl Plugin for ModelPlugin {
    fn build(&self, app: &mut App) {
        app.add_message::<PlaceModel>().add_systems(Update, place_model.before(ApplyEdits));
    }
}

/// V drops the model. Needs a window.
pub fn model_key(keys: Res<ButtonInput<KeyCode>>, mut actions: MessageWriter<PlaceModel>) {
    if keys.just_pressed(KeyCode::KeyV) {
        actions.write(PlaceModel);
    }
}

/// Drops the model with its bottom centre on the cell in front of the targeted face (or 12 voxels ahead).
fn place_model(
    mut requests: MessageReader<PlaceModel>,
    model: Option<Res<ModelToPlace>>,
    target: Res<Target>,
    camera: Query<&Transform, With<Player>>,
    mut world: ResMut<VoxelWorld>,
    mut edits: MessageWriter<EditRequest>,
    mut status: ResMut<StatusLine>,
) {
    for _ in requests.read() {
        let Some(model) = model.as_deref() else {
            status.show("no model to place: start with --model PATH.vox".into());
            continue;
        };
        let anchor = match (target.0, camera.single()) {
            (Some(hit), _) => place_position(&hit),
            (None, Ok(t)) => (t.translation + *t.forward() * 12.0).floor().as_ivec3(),
            (None, Err(_)) => continue,
        };
        let min = anchor - IVec3::new(model.size.x / 2, 0, model.size.z / 2);
        let max = min + model.size - IVec3::ONE;
        if !world.grid.contains(min) || !world.grid.contains(max) {
            status.show(format!(
                "{} ({}x{}x{}) does not fit there",
                model.name, model.size.x, model.size.y, model.size.z
            ));
            continue;
        }
        // One material per distinct colour, reused across drops.
        let mut voxels = world.grid.read_box(min, max + IVec3::ONE);
        for (p, albedo) in &model.voxels {
            let name = format!("model-{:.3}-{:.3}-{:.3}", albedo[0], albedo[1], albedo[2]);
            let id = match world.palette.id_of(&name) {
                Some(id) => id,
                None if world.palette.id_count() < crate::world::palette::MAX_MATERIALS => {
                    world.palette.push(Material::solid(&name, *albedo))
                }
                None => continue,
            };
            let e = model.size;
            voxels[(p.x + e.x * (p.y + e.y * p.z)) as usize] = id;
        }
        edits.write(EditRequest::player(Edit::Restore { min, max, voxels: Arc::from(voxels) }));
        status.show(format!("placed {} at {} {} {}", model.name, min.x, min.y, min.z));
    }
}
