//! A full scan of a world for `check-world`: counts of bricks, voxels, emitters and lights.
//!
//! Light rules (DESIGN.md "Light pool"): a homogeneous emissive brick with at least one air voxel around it is one
//! brick light; any other emissive voxel with an air neighbour is a voxel light; enclosed emitters are not lights.

use super::VoxelWorld;
use super::grid::{AIR, BrickCell};
use bevy::math::IVec3;

/// What `glowbrick check-world` prints.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct WorldSummary {
    pub size: [u32; 3],
    pub bricks_total: u64,
    pub bricks_homogeneous: u64,
    pub bricks_pooled: u64,
    pub voxels: u64,
    pub emitters: u64,
    pub voxel_lights: u64,
    pub brick_lights: u64,
    pub materials: usize,
    pub views: Vec<String>,
}

const NEIGHBOURS: [IVec3; 6] = [IVec3::X, IVec3::NEG_X, IVec3::Y, IVec3::NEG_Y, IVec3::Z, IVec3::NEG_Z];

impl VoxelWorld {
    /// Scans the whole world (cost follows occupied bricks).
    pub fn summary(&self) -> WorldSummary {
        let grid = &self.grid;
        let dims = grid.brick_dims();
        let mut s = WorldSummary {
            size: grid.size().to_array(),
            bricks_total: dims.x as u64 * dims.y as u64 * dims.z as u64,
            materials: self.palette.materials.len(),
            views: self.views.iter().map(|v| v.name.clone()).collect(),
            ..Default::default()
        };
        for (index, &raw) in grid.top_cells().iter().enumerate() {
            match BrickCell::decode(raw) {
                BrickCell::Empty => {}
                BrickCell::Homogeneous(_) => s.bricks_homogeneous += 1,
                BrickCell::Pooled(_) => s.bricks_pooled += 1,
            }
            if let BrickCell::Homogeneous(m) = BrickCell::decode(raw) {
                let brick = grid.brick_coord(index as u32);
                if self.palette.is_emissive(m) && self.brick_light_is_exposed(brick) {
                    s.brick_lights += 1;
                }
            }
        }
        grid.for_each_solid(|p, m| {
            s.voxels += 1;
            if !self.palette.is_emissive(m) {
                return;
            }
            s.emitters += 1;
            let in_brick_light = matches!(grid.cell(p >> 3_i32), BrickCell::Homogeneous(_));
            if !in_brick_light && NEIGHBOURS.iter().any(|&n| grid.get(p + n) == AIR) {
                s.voxel_lights += 1;
            }
        });
        s
    }

    /// Whether any voxel just outside homogeneous brick `brick` is air (inside the world or beyond it).
    fn brick_light_is_exposed(&self, brick: IVec3) -> bool {
        let lo = brick * 8;
        let hi = lo + IVec3::splat(7);
        for axis in 0..3 {
            for plane in [lo[axis] - 1, hi[axis] + 1] {
                let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
                for i in lo[u]..=hi[u] {
                    for j in lo[v]..=hi[v] {
                        let mut p = IVec3::ZERO;
                        p[axis] = plane;
                        p[u] = i;
                        p[v] = j;
                        if self.grid.get(p) == AIR {
                            return true;
                        }
                    }
                }
            }
        }
        false
    }
}

impl std::fmt::Display for WorldSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let [x, y, z] = self.size;
        writeln!(f, "size: {x}x{y}x{z}")?;
        writeln!(
            f,
            "bricks: {} (homogeneous={} pooled={} empty={})",
            self.bricks_total,
            self.bricks_homogeneous,
            self.bricks_pooled,
            self.bricks_total - self.bricks_homogeneous - self.bricks_pooled
        )?;
        writeln!(f, "voxels: {}", self.voxels)?;
        writeln!(f, "emitters: {}", self.emitters)?;
        writeln!(
            f,
            "lights: {} voxel={} brick={}",
            self.voxel_lights + self.brick_lights,
            self.voxel_lights,
            self.brick_lights
        )?;
        writeln!(f, "materials: {}", self.materials)?;
        write!(f, "views: {}", if self.views.is_empty() { "(none)".to_string() } else { self.views.join(", ") })
    }
}
