//! One compute pass of the voxel renderer, as a row of a technique's table: its name, shader, entry point and
//! dispatch shape. The techniques declare their passes here; `frame` lists them in order and dispatches them.

/// Edge of a per-pixel pass's square workgroup (`@workgroup_size(8, 8)` in every per-pixel shader).
pub const PIXEL_WORKGROUP_EDGE: u32 = 8;

/// Threads of a one-dimensional pass's workgroup (`@workgroup_size(64)`: the light tiles and the GI passes).
pub const LINEAR_WORKGROUP: u32 = 64;

/// One compute pass of the voxel renderer.
#[derive(Clone, Copy, Debug)]
pub struct VoxelPass {
    /// The name its GPU time is recorded under (`render/<name>/elapsed_gpu`).
    pub name: &'static str,
    /// Its shader, a path under `shaders/`.
    pub shader: &'static str,
    pub entry_point: &'static str,
    pub dispatch: Dispatch,
}

/// How a pass is dispatched, which also says which bind group 1 it gets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Dispatch {
    /// One thread per render pixel of the view (the lighting passes' pixels, `FramePlan::render_size`), in
    /// `PIXEL_WORKGROUP_EDGE`-square workgroups; group 1 is the view.
    Pixels,
    /// One thread per output pixel of the view (the primary pass, the upscaler), as `Pixels`.
    OutputPixels,
    /// One thread per light of the view's light tiles (`restir::TILE_THREADS`), `LINEAR_WORKGROUP` per
    /// workgroup; group 1 is the view.
    LightTiles,
    /// One thread per slot of both GI tables, `LINEAR_WORKGROUP` per workgroup; no view.
    Slots,
    /// One thread per entry the GI compaction pass listed: the dispatch size is read from the GI work buffer at
    /// this byte offset; no view.
    Listed(u64),
}

impl Dispatch {
    /// Whether the pass runs once per camera (and binds the view as group 1).
    pub fn per_view(self) -> bool {
        matches!(self, Dispatch::Pixels | Dispatch::OutputPixels | Dispatch::LightTiles)
    }
}
