//! Vose's alias method over light power: O(n) build, O(1) sampling with two uniform numbers. The thesis picked
//! candidates uniformly and named power sampling as future work (seed 000 §6.4); this is that.

/// One column of the table, as the GPU reads it (`AliasEntry` in `shaders/lib/lights.wgsl`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct AliasEntry {
    /// Keep this column's own light when `u < threshold`, else take `alias`'s.
    pub threshold: f32,
    /// Column whose light is taken otherwise.
    pub alias: u32,
    /// Light slot of this column.
    pub slot: u32,
    /// Probability of drawing this column's light: power / total (or 1 / n when all powers are zero).
    pub pdf: f32,
}

/// The table over the live lights; empty when there are none.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AliasTable {
    pub entries: Vec<AliasEntry>,
    /// Sum of the lights' power.
    pub total_power: f64,
    /// True when every power was zero (or non-finite) and the table is uniform.
    pub uniform: bool,
}

impl AliasTable {
    /// Builds the table from `(slot, power)` pairs. Non-finite or negative powers count as zero; if all are
    /// zero the table falls back to uniform picking.
    pub fn build(lights: &[(u32, f32)]) -> Self {
        let n = lights.len();
        if n == 0 {
            return AliasTable::default();
        }
        let power = |p: f32| if p.is_finite() && p > 0.0 { p as f64 } else { 0.0 };
        let total: f64 = lights.iter().map(|&(_, p)| power(p)).sum();
        let uniform = !(total > 0.0 && total.is_finite());
        // Scaled probabilities: mean 1.
        let mut scaled: Vec<f64> =
            lights.iter().map(|&(_, p)| if uniform { 1.0 } else { power(p) * n as f64 / total }).collect();
        let mut entries: Vec<AliasEntry> = lights
            .iter()
            .enumerate()
            .map(|(i, &(slot, p))| AliasEntry {
                threshold: 1.0,
                alias: i as u32,
                slot,
                pdf: if uniform { 1.0 / n as f32 } else { (power(p) / total) as f32 },
            })
            .collect();
        let (mut small, mut large): (Vec<usize>, Vec<usize>) = (0..n).partition(|&i| scaled[i] < 1.0);
        while let (Some(s), Some(&l)) = (small.pop(), large.last()) {
            entries[s].threshold = scaled[s] as f32;
            entries[s].alias = l as u32;
            scaled[l] -= 1.0 - scaled[s];
            if scaled[l] < 1.0 {
                large.pop();
                small.push(l);
            }
        }
        // Whatever is left holds probability 1 up to rounding.
        for i in small.into_iter().chain(large) {
            entries[i].threshold = 1.0;
            entries[i].alias = i as u32;
        }
        AliasTable { entries, total_power: if uniform { 0.0 } else { total }, uniform }
    }

    pub fn len(&self) -> usize {
        self.entries.len()
    }

    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Draws a column from a uniform 32-bit number and the pick from a uniform number in [0, 1); returns
    /// (slot, pdf).
    pub fn sample(&self, r_column: u32, u_pick: f32) -> Option<(u32, f32)> {
        let n = self.entries.len();
        if n == 0 {
            return None;
        }
        let column = column_of(r_column, n as u32) as usize;
        let entry = &self.entries[column];
        let chosen = if u_pick < entry.threshold { entry } else { &self.entries[entry.alias as usize] };
        Some((chosen.slot, chosen.pdf))
    }

    /// Probability the table draws each column's light: the exact distribution it encodes (for tests).
    pub fn column_probabilities(&self) -> Vec<f64> {
        let n = self.entries.len();
        let mut p = vec![0.0; n];
        for (i, e) in self.entries.iter().enumerate() {
            let t = e.threshold.clamp(0.0, 1.0) as f64;
            p[i] += t / n as f64;
            p[e.alias as usize] += (1.0 - t) / n as f64;
        }
        p
    }
}

/// The column a uniform 32-bit number picks among `n`: the high word of `r x n` (a 32x32 -> 64-bit multiply), so
/// every column gets floor or ceil of 2^32 / n codes. Not `floor(u x n)` with a float `u`: its 24 bits give
/// columns unequal shares at large n and cannot reach columns past 2^24 (docs/bench/why.md).
/// `shaders/lib/lights.wgsl` (`column_of`) computes the same.
pub fn column_of(r: u32, n: u32) -> u32 {
    ((r as u64 * n as u64) >> 32) as u32
}
