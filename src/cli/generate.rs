//! `glowbrick generate`: make the game's world for a seed and size without opening a window, say how long it
//! took and what it holds, and optionally save it (how large and how slow a save of that world is).

use super::args::parse_size;
use crate::world::format::save_world;
use crate::world::generate::generate_world;
use bevy::math::UVec3;
use clap::Args;
use std::path::PathBuf;
use std::time::Instant;

#[derive(Args)]
pub struct GenerateArgs {
    /// Seed of the world.
    #[arg(long, default_value_t = 1)]
    seed: u32,
    /// Size in voxels, X,Y,Z (each edge at most 2048).
    #[arg(long, default_value = super::args::DEFAULT_SIZE, value_parser = parse_size)]
    size: UVec3,
    /// Save the world here (RON, as F5 does) and report the file's size and the time taken.
    #[arg(long)]
    out: Option<PathBuf>,
}

impl GenerateArgs {
    pub fn run(self) -> Result<(), String> {
        let start = Instant::now();
        let (world, report) = generate_world(self.seed, self.size).map_err(|e| e.to_string())?;
        let seconds = start.elapsed().as_secs_f64();
        let grid = &world.grid;
        let bytes = grid.top_cells().len() * 4
            + grid.pool_capacity() as usize * 1024
            + (grid.occupancy().masks().len() + grid.voxel_masks().len()) * 8;
        println!(
            "generated {}x{}x{} (seed {}) in {seconds:.2} s on {} threads: {} trees, {} houses, {} crystal voxels",
            self.size.x,
            self.size.y,
            self.size.z,
            self.seed,
            rayon::current_num_threads(),
            report.trees,
            report.houses,
            report.crystals
        );
        println!(
            "grid memory {:.1} MB ({} stored bricks of {}), views: {}",
            bytes as f64 / 1e6,
            grid.pooled_bricks(),
            grid.top_cells().len(),
            world.views.iter().map(|v| v.name.as_str()).collect::<Vec<_>>().join(", ")
        );
        println!("{}", world.summary());
        if let Some(path) = self.out {
            let start = Instant::now();
            save_world(&world, &path).map_err(|e| format!("{}: {e}", path.display()))?;
            let size = std::fs::metadata(&path).map(|m| m.len()).unwrap_or(0);
            println!("saved {} in {:.2} s: {:.1} MB", path.display(), start.elapsed().as_secs_f64(), size as f64 / 1e6);
        }
        Ok(())
    }
}
