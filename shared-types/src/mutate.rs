//! Seeded mutation of byte inputs, for the robustness tests and `hubtrack fuzz`: every input a
//! stage reads from outside (recordings, MAVLink bytes, configuration, images) is mutated from a
//! valid seed and fed back, and must give a result or a clear error, never a panic.
//!
//! Deterministic (a seed gives the same mutants on every machine), so a failing mutant is
//! reproduced from its seed alone, and no dependency beyond the standard library.

/// SplitMix64: small, fast, good enough to pick mutations.
#[derive(Debug, Clone)]
pub struct Rng(u64);

impl Rng {
    /// A generator for `seed`.
    pub fn new(seed: u64) -> Rng {
        Rng(seed)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `0..n` (0 when `n` is 0).
    pub fn below(&mut self, n: usize) -> usize {
        if n == 0 {
            0
        } else {
            (self.next_u64() % n as u64) as usize
        }
    }
}

/// Values that break length and count fields: zero, one, signed and unsigned extremes, and
/// sizes just past common power-of-two boundaries.
const INTERESTING: [u64; 12] = [
    0,
    1,
    0x7F,
    0xFF,
    0x7FFF,
    0xFFFF,
    0x7FFF_FFFF,
    0xFFFF_FFFF,
    0x1_0000_0000,
    0xC000_0000,
    0x7FFF_FFFF_FFFF_FFFF,
    u64::MAX,
];

/// Applies 1 to 8 random mutations to `data`: bit flips, random bytes, "interesting" integers
/// (1, 2, 4 or 8 bytes, little-endian) written over the data, cuts, duplicated and deleted
/// ranges. The result is at most `max_len` bytes.
pub fn mutate(rng: &mut Rng, data: &mut Vec<u8>, max_len: usize) {
    let rounds = 1 + rng.below(8);
    for _ in 0..rounds {
        let len = data.len();
        match rng.below(7) {
            0 if len > 0 => {
                let i = rng.below(len);
                data[i] ^= 1 << rng.below(8);
            }
            1 if len > 0 => {
                let i = rng.below(len);
                data[i] = rng.next_u64() as u8;
            }
            2 if len > 0 => {
                let v = INTERESTING[rng.below(INTERESTING.len())];
                let width = 1 << rng.below(4);
                let i = rng.below(len);
                let bytes = v.to_le_bytes();
                for (k, b) in bytes.iter().take(width).enumerate() {
                    if let Some(d) = data.get_mut(i + k) {
                        *d = *b;
                    }
                }
            }
            3 => data.truncate(rng.below(len + 1)),
            4 if len > 0 => {
                let a = rng.below(len);
                let n = rng.below((len - a).min(256) + 1);
                let at = rng.below(len + 1);
                let piece: Vec<u8> = data[a..a + n].to_vec();
                data.splice(at..at, piece);
            }
            5 if len > 0 => {
                let a = rng.below(len);
                let n = rng.below((len - a).min(256) + 1);
                data.drain(a..a + n);
            }
            _ => {
                let at = rng.below(len + 1);
                let n = rng.below(16);
                let bytes: Vec<u8> = (0..n).map(|_| rng.next_u64() as u8).collect();
                data.splice(at..at, bytes);
            }
        }
        data.truncate(max_len);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mutants_are_deterministic_bounded_and_different() {
        let seed: Vec<u8> = (0..200u8).collect();
        let run = |s| {
            let mut rng = Rng::new(s);
            (0..100)
                .map(|_| {
                    let mut d = seed.clone();
                    mutate(&mut rng, &mut d, 300);
                    d
                })
                .collect::<Vec<_>>()
        };
        let a = run(7);
        assert_eq!(a, run(7));
        assert_ne!(a, run(8));
        assert!(a.iter().all(|d| d.len() <= 300));
        assert!(a.iter().filter(|d| **d != seed).count() > 90);
    }
}
