//! `glowbrick stress`: the checks a player's trust rests on, each a command anyone can run (README "Stress").
//!
//! - `soak`: the renderer for thousands of frames of edits, lamps, camera jumps and extreme settings; non-finite
//!   values, drift against the CPU reference, and memory growth (`memory`).
//! - `fuzz`: a million corrupted inputs through every loader; one error line or a valid world, never a panic,
//!   a hang or a huge allocation.
//! - `kills`: a saving process killed at a hundred moments; no save lost, no temporary left behind.

pub mod fuzz;
pub mod kills;
pub mod memory;
pub mod soak;

pub use soak::{StressConfig, StressReport, run_stress};
