//! The lights near a shading point, for the CPU reference's candidates. Lights drawn by power from the whole pool
//! almost never include the few that dominate a point among 10^5 lamps on a floor (each lamp beside it outshines
//! the thousands far away), so two references of such a scene differed everywhere (MAE 0.3-0.5 between seeds).
//! Half the candidates are drawn uniformly from the lights whose corner lies in the 3 x 3 x 3 cells around the
//! point instead, and every candidate is weighed by the mixture's density (the power pick's plus the nearby
//! pick's), which keeps the estimator unbiased: the power pick still reaches every light.

use crate::lights::alias::column_of;
use crate::lights::{AliasTable, LightPool};
use crate::world::cell_map::CellMap;
use bevy::math::{IVec3, Vec3};

/// Cell edge in voxels: the nearby set spans 3 cells (12 voxels) around the point's cell.
const CELL: i32 = 4;

/// The lights by cell, and each light's chance of being drawn by power.
#[derive(Default)]
pub struct NearbyLights {
    cells: CellMap<Vec<u32>>,
    /// By light slot.
    power_pdf: Vec<f32>,
}

/// The lights around one point: the cells' lists, and how many they hold.
pub struct Neighbourhood<'a> {
    centre: IVec3,
    lists: [&'a [u32]; 27],
    count: u32,
}

impl NearbyLights {
    pub fn of(pool: &LightPool, alias: &AliasTable) -> NearbyLights {
        let mut cells: CellMap<Vec<u32>> = CellMap::default();
        for (slot, light) in pool.lights() {
            cells.entry(cell_of(light.min.as_vec3())).or_default().push(slot);
        }
        let mut power_pdf = vec![0.0; pool.slot_count() as usize];
        for entry in &alias.entries {
            if let Some(pdf) = power_pdf.get_mut(entry.slot as usize) {
                *pdf = entry.pdf;
            }
        }
        NearbyLights { cells, power_pdf }
    }

    /// The lights whose corner lies in the 27 cells around `p`.
    pub fn around(&self, p: Vec3) -> Neighbourhood<'_> {
        let centre = cell_of(p);
        let mut lists: [&[u32]; 27] = [&[]; 27];
        let mut count = 0;
        let mut next = 0;
        for z in -1..=1 {
            for y in -1..=1 {
                for x in -1..=1 {
                    if let Some(list) = self.cells.get(&(centre + IVec3::new(x, y, z))) {
                        count += list.len() as u32;
                        lists[next] = list.as_slice();
                        next += 1;
                    }
                }
            }
        }
        Neighbourhood { centre, lists, count }
    }

    /// The chance the power pick draws `slot`.
    pub fn power_pdf(&self, slot: u32) -> f32 {
        self.power_pdf.get(slot as usize).copied().unwrap_or(0.0)
    }
}

impl Neighbourhood<'_> {
    /// No light near: every candidate is drawn by power.
    pub const EMPTY: Neighbourhood<'static> = Neighbourhood { centre: IVec3::ZERO, lists: [&[]; 27], count: 0 };

    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// A light drawn uniformly from the neighbourhood by a uniform 32-bit number.
    pub fn pick(&self, r: u32) -> Option<u32> {
        let mut index = column_of(r, self.count) as usize;
        for list in self.lists.iter() {
            if index < list.len() {
                return Some(list[index]);
            }
            index -= list.len();
        }
        None
    }

    /// The chance `pick` draws the light with corner `min` (0 outside the neighbourhood).
    pub fn pdf(&self, min: IVec3) -> f32 {
        let offset = min.div_euclid(IVec3::splat(CELL)) - self.centre;
        if self.count == 0 || offset.abs().max_element() > 1 { 0.0 } else { 1.0 / self.count as f32 }
    }
}

fn cell_of(p: Vec3) -> IVec3 {
    p.floor().as_ivec3().div_euclid(IVec3::splat(CELL))
}
