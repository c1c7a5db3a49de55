//! The generator every random draw of ftsmc comes from: ChaCha8 keyed by a
//! 64-bit seed, on one of its 2⁶⁴ independent streams. Each noise source,
//! each sampled parameter and each run's seed has a stream of its own (the
//! stream numbers are documented where they are used), so adding a source
//! never moves the draws of another.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// `ChaCha8Rng` keyed by `seed` (rand's `SeedableRng::seed_from_u64`: the
/// seed expanded by PCG32 into the 256-bit key) on stream `stream` (ChaCha's
/// 64-bit stream number, Bernstein 2008, as `rand_chacha` lays it out), at
/// its first word.
pub fn chacha_stream(seed: u64, stream: u64) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(stream);
    rng
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::Rng;

    /// Streams of one seed differ from each other and from another seed's,
    /// and the same key gives the same words.
    #[test]
    fn streams_are_distinct_and_repeatable() {
        let words = |seed, stream| {
            let mut rng = chacha_stream(seed, stream);
            [rng.next_u64(), rng.next_u64()]
        };
        assert_eq!(words(7, 3), words(7, 3));
        assert_ne!(words(7, 3), words(7, 4));
        assert_ne!(words(7, 3), words(8, 3));
        // Stream 0 is the generator `seed_from_u64` gives.
        let mut plain = ChaCha8Rng::seed_from_u64(7);
        assert_eq!(words(7, 0), [plain.next_u64(), plain.next_u64()]);
    }
}
