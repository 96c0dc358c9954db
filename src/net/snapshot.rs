//! The world a joining client receives: the RON world file (the same encoding and validation as a save),
//! deflated and cut into pieces the transport's channel takes without filling its buffers. A client puts the
//! pieces back together with limits on their count and size, so a hostile server cannot exhaust its memory.

use crate::world::VoxelWorld;
use crate::world::format::{MAX_FILE_BYTES, parse_world, text_from_bytes, world_to_string};
use flate2::Compression;
use flate2::read::DeflateDecoder;
use flate2::write::DeflateEncoder;
use std::io::{Read, Write};

/// Bytes per piece: well under renet's per-message fragment limit.
pub const PIECE_BYTES: usize = 32 * 1024;
/// Most pieces a world may take (a 512 MiB world file deflates far below this many).
pub const MAX_PIECES: u32 = 16 * 1024;

/// The world as deflated RON pieces.
pub fn encode(world: &VoxelWorld) -> Vec<Vec<u8>> {
    let text = world_to_string(world);
    let mut encoder = DeflateEncoder::new(Vec::new(), Compression::fast());
    // Writing into a Vec cannot fail.
    encoder.write_all(text.as_bytes()).expect("deflate into memory");
    let bytes = encoder.finish().expect("deflate into memory");
    bytes.chunks(PIECE_BYTES).map(<[u8]>::to_vec).collect()
}

/// Pieces of one world arriving in order.
#[derive(Debug, Default)]
pub struct Assembly {
    count: u32,
    received: u32,
    bytes: Vec<u8>,
}

impl Assembly {
    /// Adds piece `index` of `count`; returns the world once the last piece is in, or why the pieces are bad.
    pub fn add(&mut self, index: u32, count: u32, piece: &[u8]) -> Result<Option<VoxelWorld>, String> {
        if count == 0 || count > MAX_PIECES || piece.len() > PIECE_BYTES {
            return Err(format!("world piece {index} of {count} ({} bytes) is out of bounds", piece.len()));
        }
        if index == 0 {
            *self = Assembly { count, received: 0, bytes: Vec::new() };
        }
        if index != self.received || count != self.count {
            return Err(format!("world piece {index} of {count} arrived out of order (expected {})", self.received));
        }
        self.bytes.extend_from_slice(piece);
        self.received += 1;
        if self.received < self.count {
            return Ok(None);
        }
        decode(&std::mem::take(&mut self.bytes)).map(Some)
    }

    /// Fraction of the pieces received.
    pub fn progress(&self) -> f32 {
        if self.count == 0 { 0.0 } else { self.received as f32 / self.count as f32 }
    }
}

/// Inflates (at most a world file's size limit) and parses a world.
pub fn decode(deflated: &[u8]) -> Result<VoxelWorld, String> {
    let mut text = Vec::new();
    DeflateDecoder::new(deflated)
        .take(MAX_FILE_BYTES + 1)
        .read_to_end(&mut text)
        .map_err(|e| format!("the server's world does not inflate: {e}"))?;
    if text.len() as u64 > MAX_FILE_BYTES {
        return Err(format!("the server's world inflates beyond {MAX_FILE_BYTES} bytes"));
    }
    let text = text_from_bytes(text, "the server's world").map_err(|e| e.to_string())?;
    parse_world(&text, "the server's world").map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::source::WorldSource;

    #[test]
    fn a_world_comes_back_whole_from_its_pieces() {
        let world = WorldSource::Scene("cornell".into()).load().unwrap();
        let pieces = encode(&world);
        let mut assembly = Assembly::default();
        let mut done = None;
        for (i, piece) in pieces.iter().enumerate() {
            done = assembly.add(i as u32, pieces.len() as u32, piece).unwrap();
        }
        let back = done.expect("the last piece completes the world");
        assert_eq!(back.grid.size(), world.grid.size());
        let mut voxels = 0;
        world.grid.for_each_solid(|p, v| {
            assert_eq!(back.grid.get(p), v);
            voxels += 1;
        });
        assert!(voxels > 1000);
    }

    #[test]
    fn bad_pieces_are_refused() {
        let mut assembly = Assembly::default();
        assert!(assembly.add(1, 3, &[1, 2, 3]).is_err(), "a piece before the first");
        assert!(assembly.add(0, MAX_PIECES + 1, &[]).is_err(), "too many pieces");
        assert!(assembly.add(0, 1, &vec![0; PIECE_BYTES + 1]).is_err(), "a piece too large");
        assert!(assembly.add(0, 1, b"not deflate").is_err(), "bytes that do not inflate to a world");
        // A deflate bomb: a tiny stream that inflates to zeros far beyond any world file is stopped at the limit
        // without holding it all (the parse then refuses the text).
        let mut encoder = DeflateEncoder::new(Vec::new(), Compression::best());
        encoder.write_all(&vec![b' '; 8 << 20]).unwrap();
        let bomb = encoder.finish().unwrap();
        assert!(bomb.len() < PIECE_BYTES);
        assert!(Assembly::default().add(0, 1, &bomb).is_err());
    }
}
