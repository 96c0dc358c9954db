//! The ground, one brick column (8 x 8 voxel columns, the world's whole height) at a time so columns generate in
//! parallel: stone, soil and the surface layer up to the height field, caves carved by 3-D noise, and glowing
//! crystals on deep cave floors.
//!
//! Caves are two kinds: tunnels where two noise fields are both near zero (the intersection of two surfaces, a
//! winding tube that may break through the surface) and caverns where a third, slower field is high, only deep
//! down. The noise is sampled on a lattice every 4 voxels and interpolated, 64 times fewer noise evaluations than
//! per voxel for walls just as smooth at this scale.

use super::Blocks;
use super::land::{Footprint, Land, Surface, VillageSite, surface_of};
use crate::world::grid::{AIR, BRICK_SIZE, BRICK_VOXELS, Voxel, local_index};
use crate::world::terrain::hash_u32;
use bevy::math::{IVec2, IVec3};
use noise::{Fbm, MultiFractal, NoiseFn, Perlin};

/// One generated brick: all one voxel, or 512 voxels.
pub enum GeneratedBrick {
    Uniform(Voxel),
    Mixed(Box<[Voxel; BRICK_VOXELS]>),
}

/// Lattice spacing of the cave noise in voxels.
const LATTICE: i32 = 4;
/// Tunnels: both fields within this of zero (squared sum); about 4-5 voxels of radius.
const TUNNEL: f32 = 0.008;
/// Caverns: the cavern field above this.
const CAVERN: f32 = 0.42;
/// Voxels of soil between the surface voxel and the rock.
const SOIL_DEPTH: i32 = 3;
/// Crystals grow only this far below the surface, so they light caves and not hillsides.
const CRYSTAL_DEPTH: i32 = 10;
/// Chance per thousand that a deep cave floor voxel grows a crystal.
const CRYSTAL_PER_MILLE: u32 = 7;

/// What every brick column reads: the height field, the noises and the block ids.
pub struct Ground<'a> {
    pub land: &'a Land,
    pub heights: &'a [i32],
    /// The columns `heights` holds and the world's height.
    pub footprint: Footprint,
    pub site: Option<&'a VillageSite>,
    pub seed: u32,
    pub blocks: &'a Blocks,
    tunnel_a: Fbm<Perlin>,
    tunnel_b: Fbm<Perlin>,
    cavern: Fbm<Perlin>,
}

impl<'a> Ground<'a> {
    pub fn new(
        land: &'a Land,
        heights: &'a [i32],
        footprint: Footprint,
        site: Option<&'a VillageSite>,
        seed: u32,
        blocks: &'a Blocks,
    ) -> Self {
        let fbm = |offset: u32, frequency: f64| {
            Fbm::<Perlin>::new(seed.wrapping_add(offset)).set_octaves(2).set_frequency(frequency)
        };
        Ground {
            land,
            heights,
            footprint,
            site,
            seed,
            blocks,
            tunnel_a: fbm(21, 0.011),
            tunnel_b: fbm(22, 0.011),
            cavern: fbm(23, 0.007),
        }
    }

    pub fn height(&self, x: i32, z: i32) -> i32 {
        self.heights[self.footprint.index(x, z)]
    }

    /// What the surface voxel of column (x, z) is made of, before caves.
    pub fn surface(&self, x: i32, z: i32) -> Surface {
        surface_of(self.land, self.heights, self.footprint, x, z)
    }

    /// Whether a cave takes voxel (x, y, z) of a column whose ground is at `h`: the same answer `brick_column`
    /// gives there (the cave lattice lies on whole multiples of its spacing), for one voxel.
    pub fn carved(&self, x: i32, y: i32, z: i32, h: i32) -> bool {
        let (x0, z0) = (x.div_euclid(BRICK_SIZE) * BRICK_SIZE, z.div_euclid(BRICK_SIZE) * BRICK_SIZE);
        self.may_carve(x, y, z) && CaveLattice::sample(self, x0, z0, y + 1).is_cave(x - x0, y, z - z0, h - y)
    }

    /// Whether caves may open at (x, y, z): not under the village's plaza and houses, never in the bottom layers.
    fn may_carve(&self, x: i32, y: i32, z: i32) -> bool {
        if y < 3 {
            return false;
        }
        match self.site {
            Some(site) => {
                let d2 = (x - site.centre.0).pow(2) + (z - site.centre.1).pow(2);
                let keep = site.radius + super::land::BLEND;
                d2 as f32 > keep * keep || y < site.ground - 12
            }
            None => true,
        }
    }

    /// The voxels of brick column (bx, bz), bottom brick first.
    pub fn brick_column(&self, bx: i32, bz: i32) -> Vec<GeneratedBrick> {
        let (x0, z0) = (bx * BRICK_SIZE, bz * BRICK_SIZE);
        let size = self.footprint.size;
        let end = self.footprint.min + IVec2::new(size.x, size.z);
        let bricks_high = (size.y + BRICK_SIZE - 1) / BRICK_SIZE;
        let column_height = bricks_high * BRICK_SIZE;
        let (w, d) = ((end.x - x0).min(BRICK_SIZE), (end.y - z0).min(BRICK_SIZE));
        // Columns indexed [y][z][x] over the brick column's full 8 x 8 footprint.
        let mut voxels = vec![AIR; (column_height * BRICK_SIZE * BRICK_SIZE) as usize];
        let at = |x: i32, y: i32, z: i32| ((y * BRICK_SIZE + z) * BRICK_SIZE + x) as usize;
        let top = (0..d).flat_map(|z| (0..w).map(move |x| (x, z))).map(|(x, z)| self.height(x0 + x, z0 + z)).max();
        let caves = CaveLattice::sample(self, x0, z0, top.unwrap_or(0) + 1);
        for lz in 0..d {
            for lx in 0..w {
                let (x, z) = (x0 + lx, z0 + lz);
                let h = self.height(x, z);
                let surface = match self.surface(x, z) {
                    Surface::Grass => self.blocks.grass,
                    Surface::Sand => self.blocks.sand,
                    Surface::Stone => self.blocks.stone,
                    Surface::Snow => self.blocks.snow,
                };
                let soil = if surface == self.blocks.sand { self.blocks.sand } else { self.blocks.dirt };
                for y in 0..=h {
                    let material = if y == h {
                        surface
                    } else if y > h - SOIL_DEPTH {
                        soil
                    } else {
                        self.blocks.stone
                    };
                    let carved = self.may_carve(x, y, z) && caves.is_cave(lx, y, lz, h - y);
                    voxels[at(lx, y, lz)] = if carved { AIR } else { material };
                }
                self.grow_crystals(&mut voxels, x, z, h, |y| at(lx, y, lz));
            }
        }
        (0..bricks_high)
            .map(|by| {
                let mut brick = [AIR; BRICK_VOXELS];
                for lz in 0..BRICK_SIZE {
                    for ly in 0..BRICK_SIZE {
                        for lx in 0..BRICK_SIZE {
                            brick[local_index(IVec3::new(lx, ly, lz))] = voxels[at(lx, by * BRICK_SIZE + ly, lz)];
                        }
                    }
                }
                let first = brick[0];
                if brick.iter().all(|&v| v == first) {
                    GeneratedBrick::Uniform(first)
                } else {
                    GeneratedBrick::Mixed(Box::new(brick))
                }
            })
            .collect()
    }

    /// Crystals on the floors of deep caves: 1-3 voxels tall, cyan or violet, picked by a hash of the position.
    fn grow_crystals(&self, voxels: &mut [Voxel], x: i32, z: i32, h: i32, at: impl Fn(i32) -> usize) {
        for y in 4..h - CRYSTAL_DEPTH {
            if voxels[at(y)] != AIR || voxels[at(y - 1)] == AIR {
                continue;
            }
            let hash = hash_u32(self.seed ^ hash_u32(x as u32 ^ hash_u32(y as u32 ^ hash_u32(z as u32))));
            if hash % 1000 >= CRYSTAL_PER_MILLE {
                continue;
            }
            let crystal = if hash & 0x1000 == 0 { self.blocks.crystal_cyan } else { self.blocks.crystal_violet };
            let tall = 1 + (hash >> 16) as i32 % 3;
            for dy in 0..tall {
                if voxels[at(y + dy)] != AIR {
                    break;
                }
                voxels[at(y + dy)] = crystal;
            }
        }
    }
}

/// The cave noises sampled on a 4-voxel lattice over one brick column, interpolated per voxel.
struct CaveLattice {
    /// Lattice points per axis: x and z over the brick column (3), y up to the highest ground.
    ny: usize,
    tunnel_a: Vec<f32>,
    tunnel_b: Vec<f32>,
    cavern: Vec<f32>,
}

const NXZ: usize = (BRICK_SIZE / LATTICE + 1) as usize;

impl CaveLattice {
    fn sample(ground: &Ground, x0: i32, z0: i32, top: i32) -> Self {
        let ny = (top / LATTICE + 2) as usize;
        let count = NXZ * NXZ * ny;
        let (mut tunnel_a, mut tunnel_b, mut cavern) =
            (Vec::with_capacity(count), Vec::with_capacity(count), Vec::with_capacity(count));
        for iy in 0..ny {
            for iz in 0..NXZ {
                for ix in 0..NXZ {
                    let p = [
                        (x0 + ix as i32 * LATTICE) as f64,
                        (iy as i32 * LATTICE) as f64 * 1.6, // squashed vertically: tunnels run more level
                        (z0 + iz as i32 * LATTICE) as f64,
                    ];
                    tunnel_a.push(ground.tunnel_a.get(p) as f32);
                    tunnel_b.push(ground.tunnel_b.get(p) as f32);
                    cavern.push(ground.cavern.get(p) as f32);
                }
            }
        }
        CaveLattice { ny, tunnel_a, tunnel_b, cavern }
    }

    fn lerp_at(&self, field: &[f32], lx: i32, y: i32, lz: i32) -> f32 {
        let (fx, fy, fz) = (lx as f32 / LATTICE as f32, y as f32 / LATTICE as f32, lz as f32 / LATTICE as f32);
        let (ix, iy, iz) = (fx as usize, (fy as usize).min(self.ny - 2), fz as usize);
        let (ix, iz) = (ix.min(NXZ - 2), iz.min(NXZ - 2));
        let (tx, ty, tz) = (fx - ix as f32, fy - iy as f32, fz - iz as f32);
        let v = |x: usize, y: usize, z: usize| field[(y * NXZ + z) * NXZ + x];
        let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
        let plane = |y: usize| {
            lerp(lerp(v(ix, y, iz), v(ix + 1, y, iz), tx), lerp(v(ix, y, iz + 1), v(ix + 1, y, iz + 1), tx), tz)
        };
        lerp(plane(iy), plane(iy + 1), ty)
    }

    /// Whether voxel (lx, y, lz) of the brick column is cave, `depth` voxels below its column's surface.
    fn is_cave(&self, lx: i32, y: i32, lz: i32, depth: i32) -> bool {
        let a = self.lerp_at(&self.tunnel_a, lx, y, lz);
        let b = self.lerp_at(&self.tunnel_b, lx, y, lz);
        if a * a + b * b < TUNNEL {
            return true;
        }
        // Caverns only deep down, their threshold rising towards the surface so they never break through.
        depth > 14 && self.lerp_at(&self.cavern, lx, y, lz) > CAVERN + 0.01 * (30 - depth).max(0) as f32
    }
}
