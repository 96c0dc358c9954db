//! What the soak's memory does over time: the process's resident bytes (on software Vulkan this includes the
//! "GPU" memory) and the bytes the GPU device holds in buffers and textures (wgpu's own counters).
//!
//! A leak is growth that never comes back. The soak cycles its settings every 300 frames and some settings own
//! bigger buffers than others (the GI cache at K = 128), so single samples go up and down with the cycle; each
//! block of `BLOCK_FRAMES` (longer than a cycle) is summarised by its highest sample, and a run fails when a
//! block's high exceeds the first block after warm-up by more than `MAX_GROWTH`.

use bevy::render::renderer::RenderDevice;

/// Frames summarised by one report line.
pub const BLOCK_FRAMES: u32 = 500;
/// Blocks of warm-up (caches filling, pipelines compiling) before growth is judged.
pub const WARMUP_BLOCKS: usize = 2;
/// The most a later block may exceed the first judged block by.
pub const MAX_GROWTH: f64 = 0.05;

/// One reading.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MemorySample {
    /// Resident set size of this process.
    pub resident_bytes: u64,
    /// Device memory in buffers and textures (0 when the device does not count, e.g. without wgpu's counters).
    pub gpu_bytes: u64,
}

impl MemorySample {
    /// Reads the process and the device now.
    pub fn now(device: Option<&RenderDevice>) -> Self {
        let gpu_bytes = device.map_or(0, |d| {
            let hal = d.wgpu_device().get_internal_counters().hal;
            (hal.buffer_memory.read().max(0) + hal.texture_memory.read().max(0)) as u64
        });
        MemorySample { resident_bytes: resident_bytes().unwrap_or(0), gpu_bytes }
    }

    fn max(self, other: Self) -> Self {
        MemorySample {
            resident_bytes: self.resident_bytes.max(other.resident_bytes),
            gpu_bytes: self.gpu_bytes.max(other.gpu_bytes),
        }
    }
}

/// Resident bytes of this process (Linux: `/proc/self/statm`); `None` where the platform does not say.
pub fn resident_bytes() -> Option<u64> {
    let statm = std::fs::read_to_string("/proc/self/statm").ok()?;
    let pages: u64 = statm.split_whitespace().nth(1)?.parse().ok()?;
    Some(pages * 4096)
}

/// The highest sample of each block of frames.
#[derive(Clone, Debug, Default)]
pub struct MemoryTrack {
    /// One entry per finished block: (last frame of the block, its highest sample).
    pub blocks: Vec<(u32, MemorySample)>,
    current: Option<MemorySample>,
    /// The latest sample.
    pub last: MemorySample,
}

impl MemoryTrack {
    /// Adds frame `frame`'s sample; closes a block every `BLOCK_FRAMES` frames.
    pub fn record(&mut self, frame: u32, sample: MemorySample) {
        self.last = sample;
        let high = self.current.map_or(sample, |c| c.max(sample));
        if (frame + 1).is_multiple_of(BLOCK_FRAMES) {
            self.blocks.push((frame + 1, high));
            self.current = None;
        } else {
            self.current = Some(high);
        }
    }

    /// The first judged block (after warm-up), when the run was long enough to have one.
    pub fn baseline(&self) -> Option<MemorySample> {
        self.blocks.get(WARMUP_BLOCKS).map(|&(_, s)| s)
    }

    /// The largest growth of a later block over the baseline, (resident, gpu), as fractions.
    pub fn growth(&self) -> Option<(f64, f64)> {
        let base = self.baseline()?;
        let grow = |now: u64, then: u64| if then == 0 { 0.0 } else { now as f64 / then as f64 - 1.0 };
        let later = &self.blocks[WARMUP_BLOCKS..];
        let resident = later.iter().map(|(_, s)| grow(s.resident_bytes, base.resident_bytes)).fold(0.0, f64::max);
        let gpu = later.iter().map(|(_, s)| grow(s.gpu_bytes, base.gpu_bytes)).fold(0.0, f64::max);
        Some((resident, gpu))
    }

    /// Why memory fails the run, if it does.
    pub fn failure(&self) -> Option<String> {
        let (resident, gpu) = self.growth()?;
        (resident > MAX_GROWTH || gpu > MAX_GROWTH).then(|| {
            format!(
                "memory grew after warm-up: resident {:+.1}%, GPU {:+.1}% (limit {:.0}%)",
                100.0 * resident,
                100.0 * gpu,
                100.0 * MAX_GROWTH
            )
        })
    }
}

impl std::fmt::Display for MemoryTrack {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        const MIB: f64 = 1024.0 * 1024.0;
        writeln!(
            f,
            "  last frame: resident {:.1} MiB, GPU buffers + textures {:.1} MiB",
            self.last.resident_bytes as f64 / MIB,
            self.last.gpu_bytes as f64 / MIB
        )?;
        for (frame, s) in &self.blocks {
            writeln!(
                f,
                "  frame {frame:>6}: resident {:8.1} MiB, GPU buffers + textures {:8.1} MiB",
                s.resident_bytes as f64 / MIB,
                s.gpu_bytes as f64 / MIB
            )?;
        }
        match self.growth() {
            Some((resident, gpu)) => write!(
                f,
                "  growth after {} warm-up blocks: resident {:+.2}%, GPU {:+.2}% (limit {:.0}%)",
                WARMUP_BLOCKS,
                100.0 * resident,
                100.0 * gpu,
                100.0 * MAX_GROWTH
            ),
            None => write!(f, "  (growth is judged from block {}; the run was shorter)", WARMUP_BLOCKS + 1),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(resident: u64, gpu: u64) -> MemorySample {
        MemorySample { resident_bytes: resident, gpu_bytes: gpu }
    }

    #[test]
    fn a_block_keeps_its_highest_sample_and_growth_is_judged_after_warm_up() {
        let mut track = MemoryTrack::default();
        for frame in 0..BLOCK_FRAMES * 5 {
            // Up and down with a cycle, no trend, except a big warm-up start.
            let wobble = if frame % 300 < 30 { 50 } else { 0 };
            let warm = if frame < 100 { 500 } else { 0 };
            track.record(frame, sample(1000 + wobble + warm, 200 + wobble));
        }
        assert_eq!(track.blocks.len(), 5);
        assert_eq!(track.blocks[0].1, sample(1550, 250));
        assert_eq!(track.baseline(), Some(sample(1050, 250)));
        assert_eq!(track.growth(), Some((0.0, 0.0)));
        assert!(track.failure().is_none());
        // A leak: one more block 6% higher fails the run.
        for frame in BLOCK_FRAMES * 5..BLOCK_FRAMES * 6 {
            track.record(frame, sample(1113, 250));
        }
        let failure = track.failure().expect("growth over 5% fails");
        assert!(failure.contains("resident +6.0%"), "{failure}");
    }

    #[test]
    fn this_process_has_resident_memory() {
        if cfg!(target_os = "linux") {
            assert!(resident_bytes().unwrap() > 1 << 20);
        }
    }
}
