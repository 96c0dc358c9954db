//! The height field: plains, hills and mountains blended by a slow "ruggedness" noise, flattened into a plaza
//! where the village stands, and the surface material each column gets (grass, sand in hollows, bare stone on
//! steep slopes, snow on peaks).

use bevy::math::{IVec2, IVec3};
use noise::{Fbm, MultiFractal, NoiseFn, Perlin, RidgedMulti};
use rayon::prelude::*;

/// Where the village stands: a round plaza flattened to one height.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VillageSite {
    pub centre: (i32, i32),
    /// The plaza's surface voxel height.
    pub ground: i32,
    /// Radius of the flat area in voxels; the terrain blends back to its own height over `BLEND` more.
    pub radius: f32,
}

/// Voxels over which the plaza blends back into the terrain.
pub const BLEND: f32 = 16.0;

/// What a column's surface voxel is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Surface {
    Grass,
    Sand,
    Stone,
    Snow,
}

/// The noises of a seed and the world's vertical scale.
pub struct Land {
    ruggedness: Fbm<Perlin>,
    plains: Fbm<Perlin>,
    hills: Fbm<Perlin>,
    mountains: RidgedMulti<Perlin>,
    forest: Fbm<Perlin>,
    height: f32,
}

fn smoothstep(lo: f32, hi: f32, x: f32) -> f32 {
    let t = ((x - lo) / (hi - lo)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

impl Land {
    pub fn new(seed: u32, height: u32) -> Self {
        let fbm = |offset: u32, octaves: usize, frequency: f64| {
            Fbm::<Perlin>::new(seed.wrapping_add(offset)).set_octaves(octaves).set_frequency(frequency)
        };
        Land {
            ruggedness: fbm(11, 3, 0.0025),
            plains: fbm(12, 3, 0.010),
            hills: fbm(13, 4, 0.007),
            mountains: RidgedMulti::<Perlin>::new(seed.wrapping_add(14)).set_octaves(5).set_frequency(0.0045),
            forest: fbm(15, 2, 0.006),
            height: height as f32,
        }
    }

    /// Mean ground height: a third of the world's height leaves room for caves below and peaks above.
    pub fn base(&self) -> f32 {
        self.height * 0.3
    }

    /// 0 on plains, 1 where mountains rise.
    pub fn mountain_weight(&self, x: i32, z: i32) -> f32 {
        let r = self.ruggedness.get([x as f64, z as f64]) as f32;
        smoothstep(0.15, 0.45, r)
    }

    /// The untouched terrain height at (x, z), before the village flattens it.
    pub fn natural_height(&self, x: i32, z: i32) -> f32 {
        let p = [x as f64, z as f64];
        let rugged = self.ruggedness.get(p) as f32;
        let hills_w = smoothstep(-0.25, 0.1, rugged);
        let mountain_w = smoothstep(0.15, 0.45, rugged);
        let y = self.height;
        let plains = self.plains.get(p) as f32 * y * 0.03;
        let mut h = self.base() + plains;
        if hills_w > 0.0 {
            h += hills_w * self.hills.get(p) as f32 * y * 0.12;
        }
        if mountain_w > 0.0 {
            // Ridged noise is in about [-1, 1] with sharp crests near 1: lift it to [0, 1] and sharpen the crests.
            let ridge = ((self.mountains.get(p) as f32 + 1.0) * 0.5).clamp(0.0, 1.0);
            h += mountain_w * ridge * ridge * y * 0.5;
        }
        h
    }

    /// How wooded (x, z) is: the chance that a tree grows on a candidate spot.
    pub fn tree_density(&self, x: i32, z: i32) -> f32 {
        let f = self.forest.get([x as f64, z as f64]) as f32;
        let woods = 0.08 + 0.55 * smoothstep(-0.1, 0.35, f);
        woods * (1.0 - 0.8 * self.mountain_weight(x, z))
    }

    /// Height above which peaks are snow.
    pub fn snow_line(&self) -> i32 {
        (self.base() + self.height * 0.3) as i32
    }

    /// The lowest ground, where hollows are sand.
    pub fn sand_line(&self) -> i32 {
        (self.base() - self.height * 0.035) as i32
    }

    /// A plaza for the village: the flattest of a grid of candidate spots in the middle half of the world, away from
    /// mountains. `None` for worlds too small to hold one.
    pub fn village_site(&self, size: (i32, i32, i32)) -> Option<VillageSite> {
        self.village_site_in((0, 0), size)
    }

    /// The same for the columns from `min` (x, z) on, `size` (x, height, z): one village cell of the endless world.
    pub fn village_site_in(&self, min: (i32, i32), size: (i32, i32, i32)) -> Option<VillageSite> {
        let (sx, sy, sz) = size;
        let (mx, mz) = min;
        let radius = (sx.min(sz) as f32 / 6.0).min(34.0);
        if radius < 16.0 || sy < 40 {
            return None;
        }
        let candidates: Vec<(i32, i32)> =
            (0..7).flat_map(|i| (0..7).map(move |j| (mx + sx / 4 + i * sx / 12, mz + sz / 4 + j * sz / 12))).collect();
        let score = |&(cx, cz): &(i32, i32)| {
            let r = radius as i32;
            let samples: Vec<f32> = (-r..=r)
                .step_by(4)
                .flat_map(|dx| (-r..=r).step_by(4).map(move |dz| (dx, dz)))
                .map(|(dx, dz)| self.natural_height(cx + dx, cz + dz))
                .collect();
            let mean = samples.iter().sum::<f32>() / samples.len() as f32;
            let variance = samples.iter().map(|h| (h - mean) * (h - mean)).sum::<f32>() / samples.len() as f32;
            // Prefer flat ground near the middle (the start view) and close to the mean height.
            let off_centre = ((cx - mx - sx / 2).pow(2) + (cz - mz - sz / 2).pow(2)) as f32 / (sx * sz) as f32;
            (variance + 40.0 * off_centre + (mean - self.base()).abs(), mean)
        };
        let scored: Vec<((f32, f32), (i32, i32))> = candidates.par_iter().map(|c| (score(c), *c)).collect();
        let ((_, mean), centre) = scored.into_iter().min_by(|a, b| a.0.0.total_cmp(&b.0.0))?;
        let ground = (mean.round() as i32).clamp(2, sy - 24);
        Some(VillageSite { centre, ground, radius })
    }
}

/// The terrain height at (x, z) with the village's plaza flattened in, clamped to the world.
pub fn column_height(land: &Land, site: Option<&VillageSite>, x: i32, z: i32, world_height: i32) -> i32 {
    let mut h = land.natural_height(x, z);
    if let Some(site) = site {
        let d = (((x - site.centre.0).pow(2) + (z - site.centre.1).pow(2)) as f32).sqrt();
        let w = 1.0 - smoothstep(site.radius, site.radius + BLEND, d);
        h += (site.ground as f32 - h) * w;
    }
    // A voxel of air above the highest ground; a world one or two voxels high is all ground.
    let top = (world_height - 2).max(0);
    (h.round() as i32).clamp(top.min(1), top)
}

/// Every column's height, row by row in parallel: `heights[z * sx + x]`.
pub fn height_field(land: &Land, site: Option<&VillageSite>, sx: i32, sy: i32, sz: i32) -> Vec<i32> {
    let mut heights = vec![0; (sx * sz) as usize];
    heights.par_chunks_mut(sx as usize).enumerate().for_each(|(z, row)| {
        for (x, h) in row.iter_mut().enumerate() {
            *h = column_height(land, site, x as i32, z as i32, sy);
        }
    });
    heights
}

/// The columns a height field holds: x and z from `min`, `size.x` by `size.z` of them (`heights[z * size.x + x]`,
/// relative to `min`), under a world `size.y` high. A bounded world's starts at 0 and covers it; an endless world's
/// region's reaches a few columns past the region, for its slopes and the trees that lean in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Footprint {
    pub min: IVec2,
    pub size: IVec3,
}

impl Footprint {
    /// The index of column (x, z) in the height field, clamped to the footprint's edge.
    pub fn index(&self, x: i32, z: i32) -> usize {
        let (lx, lz) = ((x - self.min.x).clamp(0, self.size.x - 1), (z - self.min.y).clamp(0, self.size.z - 1));
        (lz * self.size.x + lx) as usize
    }
}

/// The surface material of column (x, z): bare stone where the ground is steep, snow above the snow line, sand in
/// hollows, grass elsewhere.
pub fn surface_of(land: &Land, heights: &[i32], footprint: Footprint, x: i32, z: i32) -> Surface {
    let at = |x: i32, z: i32| heights[footprint.index(x, z)];
    let h = at(x, z);
    let slope = (at(x + 1, z) - at(x - 1, z)).abs() + (at(x, z + 1) - at(x, z - 1)).abs();
    if h > land.snow_line() {
        if slope > 6 { Surface::Stone } else { Surface::Snow }
    } else if slope > 5 {
        Surface::Stone
    } else if h < land.sand_line() {
        Surface::Sand
    } else {
        Surface::Grass
    }
}
