//! Noise streams: a `ChaCha8Rng` read a block ahead ([`NoiseStream`]),
//! the reader every per-period noise source of a flight draws through —
//! the sensors' four sources ([`crate::sensors`]), the Dryden turbulence
//! ([`crate::environment::wind`]) and the drag noise
//! ([`crate::environment`]). It serves the generator's own words in their
//! order, so a source draws the same bits through it as from the
//! generator itself; it only costs fewer instructions per draw.

use core::convert::Infallible;
use rand::{Rng, TryRng};
use rand_chacha::ChaCha8Rng;

use crate::gauss::standard_normal;

/// Words of a [`NoiseStream`]'s block: one ChaCha block refill (4 × 16
/// 32-bit words), 256 bytes.
const BLOCK_WORDS: usize = 64;

/// A noise source's generator read a block ahead: the 32-bit words of its
/// `ChaCha8Rng` in their order, 64 at a time (one ChaCha refill, 256 bytes). A `u64` is two
/// consecutive words, low word first, and bytes are the words
/// little-endian, a started word consumed whole: exactly how the
/// `ChaCha8Rng` itself serves them, so every draw (`u32`, `u64`, bytes, and
/// any distribution sampled from them, e.g. [`NoiseStream::normal`]) has
/// the bits it has on the generator itself. The words are the generator's
/// own sequence whatever the mix of calls; only the generator's position is
/// ahead of the draws (by up to one block), which nothing else reads: the
/// stream owns it. Reading the block is cheaper per draw than the
/// generator's own buffer (no index kept inside the buffer, one load per
/// `u64`).
#[derive(Clone, Debug)]
pub struct NoiseStream {
    rng: ChaCha8Rng,
    /// The words read ahead, little-endian bytes.
    block: [u8; 4 * BLOCK_WORDS],
    /// The next unread word of `block` (`BLOCK_WORDS`: all read).
    next: usize,
}

impl NoiseStream {
    /// The stream of `rng`'s words from its current position on.
    pub fn new(rng: ChaCha8Rng) -> Self {
        Self { rng, block: [0; 4 * BLOCK_WORDS], next: BLOCK_WORDS }
    }

    /// Read the generator's next [`BLOCK_WORDS`] words.
    #[inline(never)]
    fn refill(&mut self) {
        self.rng.fill_bytes(&mut self.block);
        self.next = 0;
    }

    /// The next word.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn word(&mut self) -> u32 {
        if self.next >= BLOCK_WORDS {
            self.refill();
        }
        let i = 4 * self.next;
        self.next += 1;
        u32::from_le_bytes([self.block[i], self.block[i + 1], self.block[i + 2], self.block[i + 3]])
    }

    /// The next two words as a `u64`, the first one low.
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn word_pair(&mut self) -> u64 {
        // `next < BLOCK_WORDS - 1` (not `next + 1 < BLOCK_WORDS`, which may
        // wrap): the compiler then sees `i + 8 <= 256` and drops the bounds
        // check of the slice.
        if self.next < BLOCK_WORDS - 1 {
            let i = 4 * self.next;
            self.next += 2;
            let mut bytes = [0u8; 8];
            bytes.copy_from_slice(&self.block[i..i + 8]);
            u64::from_le_bytes(bytes)
        } else {
            self.word_pair_across()
        }
    }

    /// [`NoiseStream::word_pair`] at the end of the block (once per block,
    /// out of line so that the common case inlines small).
    #[inline(never)]
    fn word_pair_across(&mut self) -> u64 {
        let lo = self.word();
        let hi = self.word();
        (u64::from(hi) << 32) | u64::from(lo)
    }

    /// One standard normal draw `z ~ N(0, 1)`: [`standard_normal`]
    /// (`rand_distr::StandardNormal`'s ziggurat on `libm`'s `exp` and `ln`) on this stream.
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn normal(&mut self) -> f64 {
        standard_normal(self)
    }
}

impl TryRng for NoiseStream {
    type Error = Infallible;

    #[cfg_attr(not(debug_assertions), inline(always))]
    fn try_next_u32(&mut self) -> Result<u32, Infallible> {
        Ok(self.word())
    }

    #[cfg_attr(not(debug_assertions), inline(always))]
    fn try_next_u64(&mut self) -> Result<u64, Infallible> {
        Ok(self.word_pair())
    }

    fn try_fill_bytes(&mut self, dst: &mut [u8]) -> Result<(), Infallible> {
        let mut chunks = dst.chunks_exact_mut(4);
        for chunk in chunks.by_ref() {
            chunk.copy_from_slice(&self.word().to_le_bytes());
        }
        let rest = chunks.into_remainder();
        if !rest.is_empty() {
            let n = rest.len();
            rest.copy_from_slice(&self.word().to_le_bytes()[..n]);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::rng::chacha_stream as generator;

    /// The stream serves the generator's own words, whatever the mix of
    /// `u32`, `u64` and byte reads and wherever they fall against the
    /// block boundaries, and so the generator's own normal draws.
    #[test]
    fn noise_stream_serves_the_generators_own_sequence() {
        let mut reference = generator(7, 23);
        let mut stream = NoiseStream::new(generator(7, 23));
        // A pattern that straddles block boundaries at odd and even words.
        for round in 0..400u32 {
            match round % 7 {
                0 | 3 => assert_eq!(stream.next_u32(), reference.next_u32(), "u32 at round {round}"),
                1 | 4 | 6 => assert_eq!(stream.next_u64(), reference.next_u64(), "u64 at round {round}"),
                2 => {
                    let n = 1 + (round as usize * 5) % 23;
                    let (mut a, mut b) = ([0u8; 23], [0u8; 23]);
                    stream.fill_bytes(&mut a[..n]);
                    reference.fill_bytes(&mut b[..n]);
                    assert_eq!(a[..n], b[..n], "{n} bytes at round {round}");
                }
                _ => {
                    let z = standard_normal(&mut reference);
                    assert_eq!(stream.normal().to_bits(), z.to_bits(), "normal at round {round}");
                }
            }
        }
        // Normal draws alone, as the sensors and the wind take them.
        let mut reference = generator(11, 20);
        let mut stream = NoiseStream::new(generator(11, 20));
        for i in 0..5000 {
            let z = standard_normal(&mut reference);
            assert_eq!(stream.normal().to_bits(), z.to_bits(), "draw {i}");
        }
    }
}
