//! `glowbrick generate`: make the game's world for a seed and size without opening a window, say how long it
//! took and what it holds, and optionally save it (how large and how slow a save of that world is).

use super::args::parse_size;
use crate::game::player::TOP_FLYING_SPEED;
use crate::world::format::save_world;
use crate::world::generate::endless::{EndlessGenerator, REGION_EDGE};
use crate::world::generate::generate_world;
use crate::world::region_save::EndlessSave;
use bevy::math::{IVec2, UVec3};
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
    /// Save the world here (RON, as F5 does) and report the file's size and the time taken. With --endless: an
    /// endless world's save folder, every region made written into it.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Instead of a bounded world, make R x R regions of the endless world around its first village (each
    /// REGION_EDGE voxels across and --size's Y high) in parallel, and report how fast regions are made.
    #[arg(long, value_name = "R", value_parser = clap::value_parser!(u32).range(1..=64))]
    endless: Option<u32>,
}

/// The resident window's edge the endless world will keep filled (today's bounded world's).
const WINDOW_EDGE: i32 = 1024;

impl GenerateArgs {
    pub fn run(self) -> Result<(), String> {
        if let Some(regions) = self.endless {
            return run_endless(self.seed, self.size.y, regions as i32, self.out.as_deref());
        }
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

/// Makes `count` x `count` regions around the endless world's first village and says how fast: regions a
/// second, and the straight-line speed at which a WINDOW_EDGE-wide window's next row of regions is made in the
/// time the player takes to cross one (the row is WINDOW_EDGE / REGION_EDGE regions).
fn run_endless(seed: u32, height: u32, count: i32, out: Option<&std::path::Path>) -> Result<(), String> {
    let generator = EndlessGenerator::new(seed, height)?;
    let start = Instant::now();
    let first = generator.village_site(IVec2::ZERO);
    let village_seconds = start.elapsed().as_secs_f64();
    let centre = first.map_or(IVec2::ZERO, |site| EndlessGenerator::region_of(site.centre.0, site.centre.1));
    let keys: Vec<IVec2> =
        (0..count).flat_map(|z| (0..count).map(move |x| centre - count / 2 + IVec2::new(x, z))).collect();
    let start = Instant::now();
    let regions = generator.regions(&keys);
    let seconds = start.elapsed().as_secs_f64();
    let rate = keys.len() as f64 / seconds;
    let bricks: u64 = regions.iter().map(|r| r.grid.pooled_bricks() as u64).sum();
    let row = (WINDOW_EDGE / REGION_EDGE) as f64;
    let speed = rate / row * REGION_EDGE as f64;
    let top = TOP_FLYING_SPEED as f64;
    println!(
        "made {} regions of {REGION_EDGE}x{height}x{REGION_EDGE} (seed {seed}, the first village's at {:?}, found in \
         {village_seconds:.2} s) in {seconds:.2} s on {} threads: {rate:.1} regions/s, {:.1} ms a region, {:.0} \
         stored bricks a region",
        keys.len(),
        first.map(|site| site.centre),
        rayon::current_num_threads(),
        1000.0 / rate,
        bricks as f64 / keys.len() as f64,
    );
    println!(
        "a {WINDOW_EDGE}-wide window's next row ({row} regions) in the time a player crosses a region at {speed:.0} \
         voxels/s of straight flight along an axis (top flying speed {top}: {:.1}x)",
        speed / top
    );
    if let Some(folder) = out {
        let start = Instant::now();
        let save = EndlessSave::open_or_create(folder, seed, height)?;
        for (key, region) in keys.iter().zip(&regions) {
            save.save_region(*key, region)?;
        }
        println!("saved {} regions into {} in {:.2} s", keys.len(), folder.display(), start.elapsed().as_secs_f64());
    }
    Ok(())
}
