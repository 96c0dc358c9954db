//! How the fuzzer corrupts an input: a few random edits of a real file's bytes. Text formats get tokens that
//! stress a RON parser and our range checks (unbalanced brackets, NaN, huge and negative numbers, a 2048^3
//! size, a run longer than a brick); binary formats get little-endian words that stress size and count fields
//! (0, 1, 256, 2048, 2^31 - 1, 2^32 - 1). Either may splice in a span of another seed.

use crate::reference::sampling::Pcg;

/// Tokens inserted into text inputs.
const TOKENS: [&str; 16] = [
    "(",
    ")",
    "[",
    "]",
    ",",
    "\"",
    "99999999999",
    "-1",
    "NaN",
    "inf",
    "1e39",
    "Uniform(",
    "Runs([(600, 1)])",
    "size: (2048, 2048, 2048),",
    "//",
    "/*",
];

/// Words written over binary inputs.
const WORDS: [u32; 10] = [0, 1, 2, 255, 256, 1023, 2048, 65_536, 0x7fff_ffff, 0xffff_ffff];

/// Whether an input is text or binary, which picks the mutations.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    Text,
    Binary,
}

/// `input` with one to five random mutations; `donor` is another seed spans may be copied from.
pub fn mutate(input: &[u8], donor: &[u8], kind: Kind, rng: &mut Pcg) -> Vec<u8> {
    let mut bytes = input.to_vec();
    for _ in 0..1 + rng.next_u32() % 5 {
        let at = |rng: &mut Pcg, len: usize| rng.next_u32() as usize % (len + 1);
        match rng.next_u32() % 6 {
            // Overwrite one byte.
            0 if !bytes.is_empty() => {
                let i = rng.next_u32() as usize % bytes.len();
                bytes[i] = rng.next_u32() as u8;
            }
            // Insert a token (text) or overwrite an aligned word (binary).
            1 => match kind {
                Kind::Text => {
                    let i = at(rng, bytes.len());
                    let token = TOKENS[rng.next_u32() as usize % TOKENS.len()];
                    bytes.splice(i..i, token.bytes());
                }
                Kind::Binary if bytes.len() >= 4 => {
                    let i = (rng.next_u32() as usize % (bytes.len() / 4)) * 4;
                    let word = if rng.next_u32().is_multiple_of(4) {
                        rng.next_u32()
                    } else {
                        WORDS[rng.next_u32() as usize % WORDS.len()]
                    };
                    bytes[i..i + 4].copy_from_slice(&word.to_le_bytes());
                }
                Kind::Binary => {}
            },
            // Delete a span of up to 64 bytes.
            2 => {
                let i = at(rng, bytes.len());
                let end = (i + rng.next_u32() as usize % 65).min(bytes.len());
                bytes.drain(i..end);
            }
            // Duplicate a span of up to 256 bytes.
            3 => {
                let i = at(rng, bytes.len());
                let end = (i + rng.next_u32() as usize % 257).min(bytes.len());
                let span = bytes[i..end].to_vec();
                bytes.splice(end..end, span);
            }
            // Cut the input short.
            4 => {
                let keep = at(rng, bytes.len());
                bytes.truncate(keep);
            }
            // Splice in a span of another seed.
            _ if !donor.is_empty() => {
                let from = rng.next_u32() as usize % donor.len();
                let end = (from + 1 + rng.next_u32() as usize % 128).min(donor.len());
                let i = at(rng, bytes.len());
                bytes.splice(i..i, donor[from..end].iter().copied());
            }
            _ => {}
        }
    }
    bytes
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mutations_change_the_input_and_are_repeatable() {
        let input = b"(format: \"glowbrick-world\", size: (16, 16, 16), bricks: [])".as_slice();
        let mut changed = 0;
        for seed in 0..200 {
            let a = mutate(input, b"donor bytes", Kind::Text, &mut Pcg::new(seed, 1));
            let b = mutate(input, b"donor bytes", Kind::Text, &mut Pcg::new(seed, 1));
            assert_eq!(a, b, "the same seed gives the same input");
            changed += (a != input) as u32;
        }
        assert!(changed >= 190, "only {changed} of 200 inputs changed");
    }

    #[test]
    fn binary_mutations_write_the_interesting_words() {
        let input = vec![7u8; 64];
        let found = (0..500).any(|seed| {
            let out = mutate(&input, &[], Kind::Binary, &mut Pcg::new(seed, 2));
            out.windows(4).any(|w| w == 0xffff_ffffu32.to_le_bytes())
        });
        assert!(found, "no input got the word 0xffffffff");
    }
}
