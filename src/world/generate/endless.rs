//! The endless world's generator: the same land, caves, crystals and trees as the bounded world, made one region
//! (REGION_EDGE x height x REGION_EDGE voxels) at a time, on demand, for any region of an unbounded grid. A
//! region is a function of the seed and its key alone: made in any order, on any thread, it comes out the same,
//! and regions side by side fit voxel for voxel (a tree on a border grows whole on both sides).
//!
//! Villages recur: the world is cut into village cells VILLAGE_CELL voxels wide, cell (0, 0) centred on the
//! origin (the start), and each cell has its village on the flattest spot of its middle half, found as the
//! bounded world finds its one. A village is built once per cell into the ground it stands on and kept as the
//! voxels it changed (its stamp); each region the stamp reaches takes its part.
//!
//! `window` puts regions around a point into one grid in the window's own coordinates, for `render --endless` and
//! `reference --endless`, and `Window::scroll_to` moves it over the world, writing only the regions that entered
//! (`BrickGrid::scroll_window`); `world::stream` keeps regions resident around a moving point.

use super::columns::Ground;
use super::land::{self, BLEND, Footprint, Land, VillageSite};
use super::trees::{MAX_CROWN, plant_trees_in};
use super::{Blocks, place_column, village};
use crate::world::follow::ScrollPlan;
use crate::world::format::LoadError;
use crate::world::grid::{BRICK_SIZE, BrickCell, Voxel};
use crate::world::palette::Palette;
use crate::world::region_save::EndlessSave;
use crate::world::terrain::hash_u32;
use crate::world::{CameraView, VoxelWorld};
use bevy::math::{IVec2, IVec3, UVec3, Vec3};
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

/// A region's edge in voxels (x and z; a region is the world's whole height).
pub const REGION_EDGE: i32 = 64;
/// A village cell's edge in voxels: one village in each, 0.8-2.4 km apart.
pub const VILLAGE_CELL: i32 = 1536;
/// The endless world's height when none is given: the bounded default world's.
pub const DEFAULT_HEIGHT: u32 = 192;
/// Regions across the window `render --endless` and `reference --endless` make around the camera (512 voxels).
pub const SHOT_WINDOW_REGIONS: i32 = 8;
/// Columns of height field kept past an area's edge: a tree's crown leans in from MAX_CROWN away, and a slope
/// reads one column further.
const MARGIN: i32 = MAX_CROWN + 1;
/// Columns around a plaza's centre that its village can change: the largest plaza's radius (34), its blend, and
/// room for the houses, paths, lamp posts and the swing's frame (the build rounds the area out to whole bricks).
const VILLAGE_REACH: i32 = 34 + BLEND as i32 + 14;

/// One cell's village: its plaza and the voxels building it changed, in world coordinates.
pub struct Village {
    pub site: VillageSite,
    pub stamp: Vec<(IVec3, Voxel)>,
}

/// Makes the endless world of one seed, a region at a time.
pub struct EndlessGenerator {
    seed: u32,
    height: i32,
    land: Land,
    blocks: Blocks,
    palette: Palette,
    /// Each village cell's village (None where the cell holds none), built the first time a region asks.
    villages: Mutex<HashMap<IVec2, Arc<Option<Village>>>>,
}

impl EndlessGenerator {
    /// The generator of `seed`'s world, `height` voxels high (at least 40, so villages fit; at most the bounded
    /// world's limit).
    pub fn new(seed: u32, height: u32) -> Result<Self, String> {
        if !(40..=crate::world::grid::MAX_WORLD_EDGE).contains(&height) {
            return Err(format!(
                "an endless world's height must be 40..={}, not {height}",
                crate::world::grid::MAX_WORLD_EDGE
            ));
        }
        let palette = Palette::default_blocks();
        let blocks = Blocks::of(&palette)?;
        Ok(EndlessGenerator {
            seed,
            height: height as i32,
            land: Land::new(seed, height),
            blocks,
            palette,
            villages: Mutex::new(HashMap::new()),
        })
    }

    pub fn seed(&self) -> u32 {
        self.seed
    }

    pub fn height(&self) -> u32 {
        self.height as u32
    }

    /// The palette every region is made with.
    pub fn palette(&self) -> &Palette {
        &self.palette
    }

    /// The region holding column (x, z).
    pub fn region_of(x: i32, z: i32) -> IVec2 {
        IVec2::new(x.div_euclid(REGION_EDGE), z.div_euclid(REGION_EDGE))
    }

    /// The village cell holding column (x, z).
    pub fn village_cell_of(x: i32, z: i32) -> IVec2 {
        let half = VILLAGE_CELL / 2;
        IVec2::new((x + half).div_euclid(VILLAGE_CELL), (z + half).div_euclid(VILLAGE_CELL))
    }

    /// The plaza of a village cell's village: the flattest spot of the cell's middle half.
    pub fn village_site(&self, cell: IVec2) -> Option<VillageSite> {
        let min = cell * VILLAGE_CELL - VILLAGE_CELL / 2;
        self.land.village_site_in((min.x, min.y), (VILLAGE_CELL, self.height, VILLAGE_CELL))
    }

    /// The village of a cell, built on first use.
    pub fn village(&self, cell: IVec2) -> Arc<Option<Village>> {
        if let Some(village) = self.villages.lock().unwrap_or_else(|e| e.into_inner()).get(&cell) {
            return village.clone();
        }
        // Built outside the lock: two threads may both build it, and get the same.
        let village = Arc::new(self.build_village(cell));
        self.villages.lock().unwrap_or_else(|e| e.into_inner()).entry(cell).or_insert(village).clone()
    }

    /// Region `key`: its voxels, column (0, 0) at world column key x REGION_EDGE.
    pub fn region(&self, key: IVec2) -> VoxelWorld {
        self.area(key * REGION_EDGE, IVec2::splat(REGION_EDGE))
    }

    /// Several regions at once, in parallel (rayon), in the order asked.
    pub fn regions(&self, keys: &[IVec2]) -> Vec<VoxelWorld> {
        keys.par_iter().map(|&key| self.region(key)).collect()
    }

    /// A window of the world: `regions` x `regions` regions around region `centre` in one bounded world, its
    /// column (0, 0) at world column `min`. Whatever reads it (the renderer, the reference, picking) works in the
    /// window's own coordinates, so a window a million voxels out is drawn as exactly as one at the origin.
    /// Regions with a file in `save` are read from it instead of made (one clear error for a file that is not
    /// one of this world's regions).
    pub fn window(&self, centre: IVec2, regions: i32, save: Option<&EndlessSave>) -> Result<Window, LoadError> {
        let keys = window_keys(centre, regions);
        let made: Vec<VoxelWorld> = keys
            .par_iter()
            .map(|&key| match save.map(|s| s.load_region(key, &self.palette)).transpose()?.flatten() {
                Some(saved) => Ok(saved),
                None => Ok(self.region(key)),
            })
            .collect::<Result<_, LoadError>>()?;
        let by_key: HashMap<IVec2, &VoxelWorld> = keys.iter().copied().zip(&made).collect();
        Ok(self.window_of(centre, regions, |key| by_key.get(&key).copied()).expect("every key made"))
    }

    /// The window of `window`, its regions taken from `region` (made elsewhere: `world::follow` takes them from
    /// the streamer); `None` while one of them is not there.
    pub fn window_of<'a>(
        &self,
        centre: IVec2,
        regions: i32,
        region: impl Fn(IVec2) -> Option<&'a VoxelWorld>,
    ) -> Option<Window> {
        let keys = window_keys(centre, regions);
        let sources: Vec<&VoxelWorld> = keys.iter().map(|&key| region(key)).collect::<Option<_>>()?;
        let first = centre - regions / 2;
        let edge = (regions * REGION_EDGE) as u32;
        let mut world = VoxelWorld::new(UVec3::new(edge, self.height as u32, edge), self.palette.clone());
        for (key, region) in keys.iter().zip(sources) {
            let at = (*key - first) * (REGION_EDGE / BRICK_SIZE);
            paste(&mut world, region, IVec3::new(at.x, 0, at.y));
        }
        world.grid.take_dirty();
        let min = first * REGION_EDGE;
        world.detail_origin = IVec3::new(min.x, 0, min.y);
        Some(Window { world, min })
    }

    /// A view from above the first village's plaza, in world coordinates.
    pub fn start_view(&self) -> CameraView {
        let plaza = self
            .village_site(IVec2::ZERO)
            .map_or(Vec3::ZERO, |site| Vec3::new(site.centre.0 as f32, site.ground as f32, site.centre.1 as f32) + 0.5);
        let origin = plaza + Vec3::new(-48.0, 28.0, -40.0);
        CameraView {
            name: "village".into(),
            origin: origin.into(),
            direction: (plaza - origin).normalize().into(),
            fov_deg: 60.0,
        }
    }

    /// The columns from `min` (whole bricks) `size` across: ground, caves, crystals, trees, and the part of a
    /// village that falls there. An area lies inside one village cell (a region always does).
    pub(crate) fn area(&self, min: IVec2, size: IVec2) -> VoxelWorld {
        let cell = Self::village_cell_of(min.x, min.y);
        debug_assert_eq!(
            cell,
            Self::village_cell_of(min.x + size.x - 1, min.y + size.y - 1),
            "an area in one village cell"
        );
        let village = self.village(cell);
        let site = village.as_ref().as_ref().map(|v| v.site);
        let mut world = self.ground(min, size, site.as_ref());
        if let Some(village) = village.as_ref() {
            let local = IVec3::new(min.x, 0, min.y);
            for &(p, voxel) in &village.stamp {
                if world.grid.contains(p - local) {
                    let _ = world.grid.set(p - local, voxel);
                }
            }
        }
        world.grid.take_dirty();
        world
    }

    /// The area's ground and trees, under the plaza of `site` (the cell's village, which flattens the land and
    /// keeps caves out from under it).
    fn ground(&self, min: IVec2, size: IVec2, site: Option<&VillageSite>) -> VoxelWorld {
        debug_assert!(
            min.x % BRICK_SIZE == 0 && min.y % BRICK_SIZE == 0 && size.x % BRICK_SIZE == 0 && size.y % BRICK_SIZE == 0
        );
        let footprint =
            Footprint { min: min - MARGIN, size: IVec3::new(size.x + 2 * MARGIN, self.height, size.y + 2 * MARGIN) };
        let heights: Vec<i32> = (0..footprint.size.z)
            .flat_map(|z| (0..footprint.size.x).map(move |x| (x, z)))
            .map(|(x, z)| land::column_height(&self.land, site, footprint.min.x + x, footprint.min.y + z, self.height))
            .collect();
        let ground = Ground::new(&self.land, &heights, footprint, site, self.seed, &self.blocks);
        let mut world =
            VoxelWorld::new(UVec3::new(size.x as u32, self.height as u32, size.y as u32), self.palette.clone());
        let bricks = min / BRICK_SIZE;
        for bz in 0..size.y / BRICK_SIZE {
            for bx in 0..size.x / BRICK_SIZE {
                let column = ground.brick_column(bricks.x + bx, bricks.y + bz);
                place_column(&mut world, bx, bz, column, &self.blocks);
            }
        }
        plant_trees_in(&mut world, min, &ground, self.seed, &self.blocks);
        world
    }

    /// Builds a cell's village into the ground around its plaza and keeps what it changed.
    fn build_village(&self, cell: IVec2) -> Option<Village> {
        let site = self.village_site(cell)?;
        let centre = IVec2::new(site.centre.0, site.centre.1);
        let min = (centre - VILLAGE_REACH).div_euclid(IVec2::splat(BRICK_SIZE)) * BRICK_SIZE;
        let max = (centre + VILLAGE_REACH + BRICK_SIZE).div_euclid(IVec2::splat(BRICK_SIZE)) * BRICK_SIZE;
        let mut world = self.ground(min, max - min, Some(&site));
        let size = world.grid.size().as_ivec3();
        let all = |world: &VoxelWorld| world.grid.read_box(IVec3::ZERO, size);
        let before = all(&world);
        let local = VillageSite { centre: (site.centre.0 - min.x, site.centre.1 - min.y), ..site };
        // Each cell's village is laid out by a seed of its own, so villages differ from one another.
        let seed = hash_u32(self.seed ^ hash_u32(cell.x as u32 ^ hash_u32(cell.y as u32).rotate_left(16)));
        village::build_village(&mut world, &local, seed, &self.blocks);
        let after = all(&world);
        let offset = IVec3::new(min.x, 0, min.y);
        // In read_box's order: x fastest, then y, then z.
        let stamp = (0..size.z)
            .flat_map(|z| (0..size.y).flat_map(move |y| (0..size.x).map(move |x| IVec3::new(x, y, z))))
            .zip(before.iter().zip(&after))
            .filter(|(_, (b, a))| b != a)
            .map(|(p, (_, &a))| (p + offset, a))
            .collect();
        Some(Village { site, stamp })
    }
}

/// The keys of the `regions` x `regions` regions around region `centre`, x fastest.
fn window_keys(centre: IVec2, regions: i32) -> Vec<IVec2> {
    let first = centre - regions / 2;
    (0..regions).flat_map(|z| (0..regions).map(move |x| first + IVec2::new(x, z))).collect()
}

/// A window of the endless world and where it lies.
pub struct Window {
    pub world: VoxelWorld,
    /// The world column of the window's column (0, 0).
    pub min: IVec2,
}

impl Window {
    /// The region keys whose columns the window holds now, lowest first.
    pub fn first_region(&self) -> IVec2 {
        let lo = self.world.grid.window().0;
        (self.min + IVec2::new(lo.x, lo.z)).div_euclid(IVec2::splat(REGION_EDGE))
    }

    /// Scrolls the window to the regions around region `centre` (`world::follow::ScrollPlan`): only the regions
    /// that enter are asked of `make` (in one call, to make them in parallel) and written; every other brick stays
    /// where it is. Refused, with nothing changed, where the move is not a whole step or `make` fails.
    pub fn scroll_to(
        &mut self,
        centre: IVec2,
        make: impl FnOnce(&[IVec2]) -> Result<Vec<VoxelWorld>, LoadError>,
    ) -> Result<(), LoadError> {
        let plan = ScrollPlan::new(&self.world, centre)?;
        let made = make(&plan.keys)?;
        let by_key: HashMap<IVec2, &VoxelWorld> = plan.keys.iter().copied().zip(&made).collect();
        plan.apply(&mut self.world, |key| by_key.get(&key).map(|w| &w.grid))
    }

    /// A view given in world coordinates, in the window's.
    pub fn local_view(&self, view: &CameraView) -> CameraView {
        let offset = Vec3::new(self.min.x as f32, 0.0, self.min.y as f32);
        CameraView { origin: (Vec3::from(view.origin) - offset).into(), ..view.clone() }
    }
}

/// Copies `region` into `world` with its brick (0, 0, 0) at brick `at`, brick by brick.
fn paste(world: &mut VoxelWorld, region: &VoxelWorld, at: IVec3) {
    let dims = region.grid.brick_dims().as_ivec3();
    let size = world.grid.size().as_ivec3();
    for b in (0..dims.y).flat_map(|y| (0..dims.z).flat_map(move |z| (0..dims.x).map(move |x| IVec3::new(x, y, z)))) {
        match region.grid.cell(b) {
            BrickCell::Empty => {}
            BrickCell::Homogeneous(voxel) => {
                let lo = (at + b) * BRICK_SIZE;
                let _ = world.grid.fill_box(lo, (lo + BRICK_SIZE).min(size), voxel);
            }
            BrickCell::Pooled(_) => world.grid.set_brick(at + b, &region.grid.brick_voxels(b)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn voxels(world: &VoxelWorld) -> Vec<Voxel> {
        world.grid.read_box(IVec3::ZERO, world.grid.size().as_ivec3())
    }

    /// Whether a tree stands within its crown's reach of the line x = `border` (in `world`'s columns) with leaves
    /// on the far side of it: a tree a region border cuts.
    fn tree_across(world: &VoxelWorld, border: i32, blocks: &Blocks) -> bool {
        let s = world.grid.size().as_ivec3();
        (0..s.z).any(|z| {
            (0..s.y).any(|y| {
                (border - MAX_CROWN..border).any(|x| world.grid.get(IVec3::new(x, y, z)) == blocks.wood)
                    && (border..border + MAX_CROWN)
                        .any(|x| (y..y + 5).any(|ly| world.grid.get(IVec3::new(x, ly, z)) == blocks.leaves))
            })
        })
    }

    #[test]
    fn regions_made_in_any_order_fit_the_area_they_tile_voxel_for_voxel() {
        let generator = EndlessGenerator::new(7, 64).unwrap();
        let min = IVec2::new(3, 3) * REGION_EDGE;
        let whole = generator.area(min, IVec2::splat(2 * REGION_EDGE));
        // Made in parallel and backwards, by a generator that has made nothing yet, and one by one by another.
        let keys = [IVec2::new(4, 4), IVec2::new(3, 4), IVec2::new(4, 3), IVec2::new(3, 3)];
        let parts = EndlessGenerator::new(7, 64).unwrap().regions(&keys);
        for (key, part) in keys.iter().zip(&parts) {
            assert_eq!(voxels(part), voxels(&generator.region(*key)), "region {key} made twice");
            let d = *key * REGION_EDGE - min;
            let offset = IVec3::new(d.x, 0, d.y);
            let s = part.grid.size().as_ivec3();
            for y in 0..s.y {
                for z in 0..s.z {
                    for x in 0..s.x {
                        let p = IVec3::new(x, y, z);
                        assert_eq!(part.grid.get(p), whole.grid.get(p + offset), "region {key} at {p}");
                    }
                }
            }
        }
        // Not vacuous: trees stand on the borders between the four, and caves open somewhere.
        let blocks = &generator.blocks;
        let rotated = |world: &VoxelWorld| {
            let s = world.grid.size();
            let mut turned = VoxelWorld::new(UVec3::new(s.z, s.y, s.x), world.palette.clone());
            for p in (0..s.y as i32)
                .flat_map(|y| (0..s.z as i32).flat_map(move |z| (0..s.x as i32).map(move |x| IVec3::new(x, y, z))))
            {
                let _ = turned.grid.set(IVec3::new(p.z, p.y, p.x), world.grid.get(p));
            }
            turned
        };
        let crossings = [tree_across(&whole, REGION_EDGE, blocks), tree_across(&rotated(&whole), REGION_EDGE, blocks)];
        assert!(crossings.iter().any(|&c| c), "no tree on a border in this area: pick another");
        assert!(voxels(&whole).iter().filter(|&&v| v == blocks.wood).count() > 20, "trees grow");
    }

    #[test]
    fn villages_recur_one_a_cell_and_the_first_stands_at_the_start() {
        let generator = EndlessGenerator::new(1, 96).unwrap();
        let first = generator.village_site(IVec2::ZERO).expect("a village at the start");
        let at = |site: VillageSite| IVec2::new(site.centre.0, site.centre.1);
        assert!(
            at(first).abs().max_element() <= VILLAGE_CELL / 4,
            "the first village is near the origin: {:?}",
            first.centre
        );
        for cell in [IVec2::X, IVec2::Y, -IVec2::X, -IVec2::Y, IVec2::new(5, -3)] {
            let site = generator.village_site(cell).unwrap_or_else(|| panic!("no village in cell {cell}"));
            assert_eq!(EndlessGenerator::village_cell_of(site.centre.0, site.centre.1), cell);
            if cell.abs().max_element() == 1 {
                let apart = (at(site) - at(first)).as_vec2().length();
                assert!((768.0..=2304.0).contains(&apart), "cell {cell}: {apart} voxels from the first");
            }
        }
        // The region under the first plaza holds the village: its lamps and its cobble.
        let region = generator.region(EndlessGenerator::region_of(first.centre.0, first.centre.1));
        let all = voxels(&region);
        let blocks = &generator.blocks;
        assert!(all.contains(&blocks.lamp_warm) && all.contains(&blocks.cobble), "the village is built");
        // A region far from any plaza holds none of it.
        let wild = voxels(&generator.region(EndlessGenerator::region_of(first.centre.0 + 600, first.centre.1 + 600)));
        assert!(!wild.contains(&blocks.cobble) && !wild.contains(&blocks.plaster));
    }

    #[test]
    fn far_from_the_origin_regions_are_made_as_near_it() {
        let generator = EndlessGenerator::new(3, 64).unwrap();
        let far = IVec2::new(-15_625, 15_624); // a million voxels out
        let region = generator.region(far);
        let all = voxels(&region);
        let solid = all.iter().filter(|&&v| v != 0).count();
        // Ground fills about a third of the height; the region is neither empty nor solid.
        assert!(solid > all.len() / 8 && solid < all.len() * 3 / 4, "{solid} of {}", all.len());
        assert_eq!(all, voxels(&EndlessGenerator::new(3, 64).unwrap().region(far)));
    }

    #[test]
    fn a_window_holds_its_regions_where_they_lie() {
        let generator = EndlessGenerator::new(4, 48).unwrap();
        let window = generator.window(IVec2::new(-1, 2), 3, None).unwrap();
        assert_eq!(window.min, IVec2::new(-2, 1) * REGION_EDGE);
        assert_eq!(window.world.detail_origin, IVec3::new(-128, 0, 64), "detail hashed at world coordinates");
        assert_eq!(window.world.grid.size(), UVec3::new(192, 48, 192));
        for key in [IVec2::new(-2, 1), IVec2::new(0, 3), IVec2::new(-1, 2)] {
            let region = generator.region(key);
            let d = key * REGION_EDGE - window.min;
            let s = region.grid.size().as_ivec3();
            for p in (0..s.y).flat_map(|y| (0..s.z).flat_map(move |z| (0..s.x).map(move |x| IVec3::new(x, y, z)))) {
                assert_eq!(
                    window.world.grid.get(p + IVec3::new(d.x, 0, d.y)),
                    region.grid.get(p),
                    "region {key} at {p}"
                );
            }
        }
        let view = CameraView {
            name: "far".into(),
            origin: [-100.5, 40.0, 100.25],
            direction: [1.0, 0.0, 0.0],
            fov_deg: 60.0,
        };
        assert_eq!(window.local_view(&view).origin, [27.5, 40.0, 36.25]);
    }

    #[test]
    fn a_scrolled_window_holds_what_a_window_made_there_holds() {
        let generator = EndlessGenerator::new(3, 48).unwrap();
        let mut window = generator.window(IVec2::new(5, -3), 4, None).unwrap();
        let mut asked = Vec::new();
        let make = |keys: &[IVec2]| {
            asked.extend_from_slice(keys);
            Ok(generator.regions(keys))
        };
        // Two regions along x and back along z: the storage now wraps inside the window on both axes.
        window.scroll_to(IVec2::new(7, -5), make).unwrap();
        assert_eq!(asked.len(), 4 * 4 - 2 * 2, "only the regions that entered are made");
        let fresh = generator.window(IVec2::new(7, -5), 4, None).unwrap();
        assert_eq!(window.first_region(), fresh.first_region());
        let (lo, hi) = window.world.grid.window();
        let offset = IVec3::new(window.min.x - fresh.min.x, 0, window.min.y - fresh.min.y);
        assert!(window.world.grid.read_box(lo, hi) == fresh.world.grid.read_box(lo + offset, hi + offset));
        assert_eq!(window.world.grid.pooled_bricks(), fresh.world.grid.pooled_bricks());
        // Half an occupancy region is not a step a window can take.
        assert!(window.scroll_to(IVec2::new(8, -5), |keys| Ok(generator.regions(keys))).is_err());
    }

    #[test]
    fn an_endless_world_too_low_for_a_village_is_refused() {
        assert!(EndlessGenerator::new(1, 39).err().is_some_and(|e| e.contains("40..=2048")));
        assert!(EndlessGenerator::new(1, 1 << 20).is_err());
    }
}
