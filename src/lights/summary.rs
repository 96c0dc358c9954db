//! A full scan of a world for `check-world`: counts of bricks, voxels, emitters and lights. It lives with the
//! light pool (the layer above the world) because its light counts are the pool's own.

use super::LightPool;
use crate::world::VoxelWorld;
use crate::world::grid::BrickCell;

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

impl VoxelWorld {
    /// Scans the whole world (cost follows occupied bricks). Light counts come from a full light-pool scan, so
    /// they follow exactly the pool's rules.
    pub fn summary(&self) -> WorldSummary {
        let grid = &self.grid;
        let dims = grid.brick_dims();
        let (voxel_lights, brick_lights) = LightPool::from_world(self).counts();
        let mut s = WorldSummary {
            size: grid.size().to_array(),
            bricks_total: dims.x as u64 * dims.y as u64 * dims.z as u64,
            materials: self.palette.materials.len(),
            views: self.views.iter().map(|v| v.name.clone()).collect(),
            voxel_lights: voxel_lights as u64,
            brick_lights: brick_lights as u64,
            ..Default::default()
        };
        for &raw in grid.top_cells() {
            match BrickCell::decode(raw) {
                BrickCell::Empty => {}
                BrickCell::Homogeneous(_) => s.bricks_homogeneous += 1,
                BrickCell::Pooled(_) => s.bricks_pooled += 1,
            }
        }
        grid.for_each_solid(|_, m| {
            s.voxels += 1;
            s.emitters += self.palette.is_emissive(m) as u64;
        });
        s
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
