//! The CPU references every bench measures against, computed once and kept on disk: a reference takes minutes,
//! and a bench rerun (or another bench on the same scene) reuses it. The key holds everything the image depends on
//! (world, view, size, samples, lighting, seed, the estimator's version), so a cached image is never stale.

use crate::image_io::{LinearImage, read_image, write_image};
use crate::lights::daylight::Daylight;
use crate::reference::metrics::{Metrics, compare};
use crate::reference::{ReferenceOptions, render_reference};
use crate::world::format::world_to_string;
use crate::world::{CameraView, VoxelWorld};
use std::path::{Path, PathBuf};

/// Which light a reference integrates: emitters only (the default) or with a sun or moon and sky, and how many
/// diffuse bounces.
#[derive(Clone, Debug, Default)]
pub struct Reference {
    pub bounces: u32,
    pub daylight: Option<Daylight>,
    /// Only every n-th pixel of the bench's image in each direction (`ReferenceOptions::lattice`), or all.
    pub lattice: Option<u32>,
    /// Only the light that reaches the camera's hits by bouncing (`ReferenceOptions::indirect_only`).
    pub indirect: bool,
}

impl Reference {
    /// Direct light from the emitters (what the direct-light benches compare with).
    pub fn direct() -> Self {
        Reference::default()
    }

    /// Emitters only, with `bounces` diffuse bounces (0: direct light).
    pub fn bounces(bounces: u32) -> Self {
        Reference { bounces, ..Reference::default() }
    }
}

/// A reference lattice (`Reference::lattice`) must be at least 1 and leave at least 4 pixels each way.
pub fn check_lattice(lattice: u32, width: u32, height: u32) -> Result<(), String> {
    let most = width.min(height) / 4;
    if lattice == 0 || lattice > most {
        return Err(format!("--lattice {lattice} must be within 1..={most}"));
    }
    Ok(())
}

/// References of one image size and sample count, cached under `dir`.
#[derive(Clone, Debug)]
pub struct ReferenceCache {
    dir: PathBuf,
    width: u32,
    height: u32,
    spp: u32,
}

impl ReferenceCache {
    /// References of `width` x `height` pixels at `spp` samples per pixel, cached in `default_dir()`.
    pub fn new(width: u32, height: u32, spp: u32) -> Self {
        ReferenceCache { dir: Self::default_dir(), width, height, spp }
    }

    /// Where references are cached: `$GLOWBRICK_CACHE`, else `$CARGO_TARGET_DIR/glowbrick-reference`, else
    /// `target/glowbrick-reference` in the crate.
    pub fn default_dir() -> PathBuf {
        if let Some(dir) = std::env::var_os("GLOWBRICK_CACHE") {
            return PathBuf::from(dir);
        }
        let target = std::env::var_os("CARGO_TARGET_DIR")
            .map(PathBuf::from)
            .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("target"));
        target.join("glowbrick-reference")
    }

    /// The reference `what` of `world` seen from `view` (seed 1).
    pub fn image(&self, world: &VoxelWorld, view: &CameraView, what: &Reference) -> Result<LinearImage, String> {
        self.seeded(world, view, what, 1)
    }

    /// The noise of the reference `what` (already rendered as `image`): measured against one with another seed
    /// (also cached), the way a rendered frame is. Its MAE is the noise a bench states; its fireflies are the
    /// count a frame's are held to.
    pub fn noise(
        &self,
        world: &VoxelWorld,
        view: &CameraView,
        what: &Reference,
        image: &LinearImage,
    ) -> Result<Metrics, String> {
        compare(&self.seeded(world, view, what, 2)?, image)
    }

    /// A reference of twice the samples, the mean of two seeds' (each cached), and its own noise: MAE and relMSE
    /// between the two halved and quartered (the mean's error has half the standard deviation of each).
    pub fn two_seeds(
        &self,
        world: &VoxelWorld,
        view: &CameraView,
        what: &Reference,
    ) -> Result<(LinearImage, Metrics), String> {
        let first = self.seeded(world, view, what, 1)?;
        let second = self.seeded(world, view, what, 2)?;
        let between = compare(&first, &second)?;
        let noise = Metrics { mae: between.mae / 2.0, mse: between.mse / 4.0, relmse: between.relmse / 4.0, ..between };
        Ok((LinearImage::mean_of(&[first, second]), noise))
    }

    /// The reference `what` with the estimator's seed `seed`: read from the cache, or rendered and written there.
    fn seeded(
        &self,
        world: &VoxelWorld,
        view: &CameraView,
        what: &Reference,
        seed: u64,
    ) -> Result<LinearImage, String> {
        let step = what.lattice.unwrap_or(1);
        let path = self.dir.join(format!("{:016x}.exr", fnv1a(self.key(world, view, what, seed).as_bytes())));
        if let Ok(image) = read_image(&path)
            && (image.width, image.height) == (self.width / step, self.height / step)
        {
            return Ok(image);
        }
        let options = ReferenceOptions {
            width: self.width,
            height: self.height,
            spp: self.spp,
            bounces: what.bounces,
            seed,
            daylight: what.daylight,
            lattice: step,
            indirect_only: what.indirect,
            ..ReferenceOptions::default()
        };
        let reference = render_reference(world, view, &options)?;
        std::fs::create_dir_all(&self.dir).map_err(|e| format!("{}: {e}", self.dir.display()))?;
        write_image(&reference.image, &path)?;
        eprintln!(
            "bench: reference {} in {:.1} s ({} spp, {:.2} Mrays/s)",
            path.display(),
            reference.elapsed.as_secs_f64(),
            reference.spp,
            reference.rays_per_second() / 1e6
        );
        Ok(reference.image)
    }

    /// Everything the image depends on. The estimator's version is part of it: a cached image from another
    /// estimator is not reused. (Its layout must not change, or every cached reference is computed again.)
    fn key(&self, world: &VoxelWorld, view: &CameraView, what: &Reference, seed: u64) -> String {
        let bounces = what.bounces;
        let mut light = if bounces == 0 { "direct".to_string() } else { format!("{bounces}bounces") };
        if let Some(day) = &what.daylight {
            light += &format!("|{day:?}");
        }
        if let Some(step) = what.lattice {
            light += &format!("|lattice{step}");
        }
        if what.indirect {
            light += "|indirect";
        }
        format!(
            "{}|{:?}|{}x{}|{}spp|{light}|seed{seed}|ris{}|v{}",
            world_to_string(world),
            view,
            self.width,
            self.height,
            self.spp,
            ReferenceOptions::default().candidates,
            crate::reference::ESTIMATOR_VERSION
        )
    }
}

/// FNV-1a, stable across runs and platforms (the cache key must not change between builds).
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The file names of references cached by earlier builds stay valid.
    #[test]
    fn the_hash_is_fnv1a() {
        assert_eq!(fnv1a(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a(b"a"), 0xaf63_dc4c_8601_ec8c);
    }

    #[test]
    fn a_lattice_leaves_four_pixels_each_way() {
        assert!(check_lattice(1, 160, 90).is_ok());
        assert!(check_lattice(22, 160, 90).is_ok());
        assert_eq!(check_lattice(23, 160, 90), Err("--lattice 23 must be within 1..=22".to_string()));
        assert!(check_lattice(0, 160, 90).is_err());
    }
}
