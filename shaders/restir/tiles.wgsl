// Voxel ReSTIR's light tiles (RTXDI's presampling): once a frame, LIGHT_TILES x LIGHT_TILE_SIZE lights drawn by the
// power pick (or uniformly, pick=uniform), each stored with a copy of its slot and its pick probability. The
// initial pass then draws each candidate of a 4x4 pixel block from one tile: one load from a few kilobytes the
// block's lanes share, where the pick itself is two or three dependent loads anywhere in the alias table and the
// pool. Each tile light is a draw from the power pick, so a candidate taken from a uniformly chosen place of a
// tile is one too: its pdf is the pick's, and the estimate stays unbiased (the candidates of a block are
// correlated within a frame; frames draw new tiles).

#import glowbrick::frame::frame
#import glowbrick::lights::{power_pick_on, lights, scene, pick_light}
#import glowbrick::random::{Rng, pcg, rng_next, rng_next_u32}
#import glowbrick::restir::common::{TileLight, light_tiles}
#import glowbrick::constants::{LIGHT_TILES, LIGHT_TILE_SIZE}

@compute @workgroup_size(64, 1, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= LIGHT_TILES * LIGHT_TILE_SIZE || scene.light_count == 0u {
        return;
    }
    var rng = Rng(pcg(i ^ pcg(frame.frame * 0x9E3779B9u + 0x7F4A7C15u)));
    let picked = pick_light(scene.light_count, power_pick_on(), rng_next_u32(&rng), rng_next(&rng));
    light_tiles[i] = TileLight(lights[picked.slot], picked.slot, picked.pdf);
}
