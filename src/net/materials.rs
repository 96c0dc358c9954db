//! Materials a client brings to the server's palette (a dropped model's colours). An edit names them by the ids
//! they would take after the palette the client has from the server (`EditAsk::first_new` on); the server checks
//! each one the edit uses, finds it by name or adds it, and renumbers the edit to its own ids. Every client then
//! appends the same materials in the same order (`EditDone::materials`), so palettes stay equal everywhere.

use super::protocol::{NetEdit, NetMaterial};
use crate::world::{Material, Palette, Voxel};
use std::collections::BTreeMap;

/// The brightest material a client may add: a lamp like the default palette's (strength 6-12) and then some,
/// not a sun that drowns everyone's image.
pub const MAX_STRENGTH: f32 = 64.0;
/// The longest material name a client may add, in bytes.
pub const MAX_NAME_BYTES: usize = 64;

/// Why a client's material may not join the palette.
pub fn problem(material: &Material) -> Option<String> {
    let name = &material.name;
    if name.trim().is_empty() || name.len() > MAX_NAME_BYTES || name.chars().any(char::is_control) {
        return Some(format!("a material's name must be 1-{MAX_NAME_BYTES} printable bytes"));
    }
    if let Some(problem) = material.problem() {
        return Some(problem);
    }
    (material.strength > MAX_STRENGTH)
        .then(|| format!("material '{name}': strength {} is above the server's {MAX_STRENGTH}", material.strength))
}

/// What `take_materials` did.
#[derive(Debug, PartialEq)]
pub struct Taken {
    /// The edit in the palette's ids.
    pub edit: NetEdit,
    /// The materials added to the end of the palette, in order.
    pub added: Vec<NetMaterial>,
}

/// Renumbers the new materials `edit` uses (ids from `first_new` on, `materials[id - first_new]`) to `palette`'s
/// ids, adding the ones it lacks by name: at most `allowance` of them, and never past `max_ids` ids. On an error
/// the palette is as it was. An ask without materials passes unchanged (the world checks its ids).
pub fn take_materials(
    palette: &mut Palette,
    edit: NetEdit,
    first_new: u16,
    materials: &[NetMaterial],
    allowance: usize,
    max_ids: usize,
) -> Result<Taken, String> {
    if materials.is_empty() {
        return Ok(Taken { edit, added: Vec::new() });
    }
    if first_new == 0 || first_new as usize > palette.id_count() {
        return Err(format!("new materials from id {first_new}, but the server's palette has {}", palette.id_count()));
    }
    let used = |v: Voxel| v >= first_new;
    let mut ids: BTreeMap<Voxel, Voxel> = BTreeMap::new();
    for v in voxels_of(&edit).filter(|&v| used(v)) {
        ids.insert(v, 0);
    }
    let before = palette.materials.len();
    let mut added = Vec::new();
    for (&id, server_id) in ids.iter_mut() {
        let Some(wire) = materials.get((id - first_new) as usize) else {
            palette.materials.truncate(before);
            return Err(format!("material id {id} is neither the server's nor among the {} sent", materials.len()));
        };
        let material = Material::from(wire);
        if let Some(problem) = problem(&material) {
            palette.materials.truncate(before);
            return Err(problem);
        }
        *server_id = match palette.id_of(&material.name) {
            Some(existing) => existing,
            None if added.len() < allowance && palette.id_count() < max_ids => {
                added.push(wire.clone());
                palette.push(material)
            }
            None => {
                palette.materials.truncate(before);
                return Err(format!(
                    "no room for material '{}': the server takes {allowance} more from you, {} in all",
                    material.name,
                    max_ids.saturating_sub(1)
                ));
            }
        };
    }
    let map = |v: Voxel| if used(v) { ids[&v] } else { v };
    let edit = match edit {
        NetEdit::Place { at, material } => NetEdit::Place { at, material: map(material) },
        NetEdit::FillBox { min, max, material } => NetEdit::FillBox { min, max, material: map(material) },
        NetEdit::Restore { min, max, voxels } => {
            NetEdit::Restore { min, max, voxels: voxels.into_iter().map(map).collect() }
        }
        other @ NetEdit::Break { .. } => other,
    };
    Ok(Taken { edit, added })
}

fn voxels_of(edit: &NetEdit) -> Box<dyn Iterator<Item = Voxel> + '_> {
    match edit {
        NetEdit::Place { material, .. } | NetEdit::FillBox { material, .. } => Box::new(std::iter::once(*material)),
        NetEdit::Restore { voxels, .. } => Box::new(voxels.iter().copied()),
        NetEdit::Break { .. } => Box::new(std::iter::empty()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn colour(name: &str, grey: f32) -> NetMaterial {
        NetMaterial::from(&Material::solid(name, [grey; 3]))
    }

    #[test]
    fn new_materials_are_added_once_and_the_edit_renumbered() {
        let mut palette = Palette::default_blocks();
        let server_ids = palette.id_count() as u16;
        // The client knew two fewer materials than the server has now (another player added two since).
        palette.push(Material::solid("someone else's", [0.1; 3]));
        palette.push(Material::solid("model-0.500-0.500-0.500", [0.5; 3]));
        let edit = NetEdit::Restore { min: [0; 3], max: [3, 0, 0], voxels: vec![0, 1, server_ids, server_ids + 1] };
        let sent = [colour("model-0.500-0.500-0.500", 0.5), colour("model-0.250-0.250-0.250", 0.25)];
        let taken = take_materials(&mut palette, edit, server_ids, &sent, 8, 1000).unwrap();
        // The first is the server's already (same name), the second is added at the end.
        let existing = palette.id_of("model-0.500-0.500-0.500").unwrap();
        let added = palette.id_of("model-0.250-0.250-0.250").unwrap();
        assert_eq!(added as usize, palette.id_count() - 1);
        assert_eq!(taken.added, vec![sent[1].clone()]);
        assert_eq!(taken.edit, NetEdit::Restore { min: [0; 3], max: [3, 0, 0], voxels: vec![0, 1, existing, added] });
    }

    #[test]
    fn bad_materials_and_spent_allowances_leave_the_palette_as_it_was() {
        let fresh = Palette::default_blocks();
        let first = fresh.id_count() as u16;
        let place = |material| NetEdit::Place { at: [1, 2, 3], material };
        let mut sun = colour("sun", 0.9);
        sun.emission = [1.0; 3];
        sun.strength = 1e5;
        let mut nan = colour("nan", 0.5);
        nan.albedo[1] = f32::NAN;
        let cases: [(NetEdit, Vec<NetMaterial>, usize, &str); 6] = [
            (place(first), vec![sun], 8, "strength"),
            (place(first), vec![nan], 8, "albedo"),
            (place(first), vec![colour("", 0.5)], 8, "name"),
            (place(first + 1), vec![colour("one", 0.5)], 8, "neither"),
            (place(first), vec![colour("two", 0.5)], 0, "no room"),
            (place(first), vec![colour("\u{7}bell", 0.5)], 8, "name"),
        ];
        for (edit, sent, allowance, expected) in cases {
            let mut palette = fresh.clone();
            let error = take_materials(&mut palette, edit, first, &sent, allowance, 1000).unwrap_err();
            assert!(error.contains(expected), "{error}");
            assert_eq!(palette, fresh);
        }
        // A palette at its ceiling takes nothing new.
        let mut palette = fresh.clone();
        let full = fresh.id_count();
        assert!(take_materials(&mut palette, place(first), first, &[colour("x", 0.5)], 8, full).is_err());
        // Ids beyond the palette the server has are refused before anything is read.
        assert!(take_materials(&mut palette, place(first + 9), first + 9, &[colour("x", 0.5)], 8, 1000).is_err());
        // Without materials the edit passes as it came.
        let taken = take_materials(&mut palette, place(3), 0, &[], 8, 1000).unwrap();
        assert_eq!(taken, Taken { edit: place(3), added: Vec::new() });
    }
}
