//! A fast hash for the crate's own small keys (grid cells, a tile's pixels and layers).
//!
//! The standard library's SipHash resists keys chosen by an adversary; none of these maps
//! holds such keys, and SipHash was a third of the surfel sampling's time and about 2 % of a
//! final render's (`render::sparse`, perf). Each word is folded in by a rotate, an xor and a
//! multiply; `finish` folds the product's high half down, since the table's bucket index is
//! taken from the low bits. The hash is the same in every run (no random seed), which changes
//! nothing here: no map's iteration order reaches an output.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// A [`HashMap`] with [`FastHasher`].
pub type FastHashMap<K, V> = HashMap<K, V, BuildHasherDefault<FastHasher>>;

/// A multiplicative hash of whole words (see the module docs).
#[derive(Clone, Copy, Debug, Default)]
pub struct FastHasher(u64);

impl Hasher for FastHasher {
    fn finish(&self) -> u64 {
        self.0 ^ (self.0 >> 32)
    }

    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }

    fn write_u8(&mut self, i: u8) {
        self.write_u64(u64::from(i));
    }

    fn write_u16(&mut self, i: u16) {
        self.write_u64(u64::from(i));
    }

    fn write_u32(&mut self, i: u32) {
        self.write_u64(u64::from(i));
    }

    fn write_i32(&mut self, i: i32) {
        self.write_u64(u64::from(i as u32));
    }

    fn write_usize(&mut self, i: usize) {
        self.write_u64(i as u64);
    }

    fn write_isize(&mut self, i: isize) {
        self.write_u64(i as u64);
    }

    fn write_u64(&mut self, i: u64) {
        self.0 = (self.0.rotate_left(5) ^ i).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every field of a key counts, and the low bits the table indexes by spread: over a 64 ×
    /// 64 tile's pixels, two chains and five quarters (40 960 keys), the hashes are all
    /// distinct, and the busiest of the 4 096 buckets of their 12 low bits holds at most 30
    /// (10 on average; a uniform hash's busiest holds about 24, the Poisson maximum over 4 096
    /// buckets, and one that ignored the chain or the quarter would repeat hashes).
    #[test]
    fn keys_hash_apart_and_spread_over_the_low_bits() {
        let mut hashes = Vec::new();
        let mut buckets = vec![0u32; 4096];
        for pixel in 0..4096u32 {
            for chain in [0u64, 0x9e37_79b9_7f4a_7c15] {
                for quarter in [None, Some(0u8), Some(1), Some(2), Some(3)] {
                    let mut h = FastHasher::default();
                    std::hash::Hash::hash(&(pixel, chain, quarter), &mut h);
                    hashes.push(h.finish());
                    buckets[(h.finish() & 4095) as usize] += 1;
                }
            }
        }
        let keys = hashes.len();
        hashes.sort_unstable();
        hashes.dedup();
        assert_eq!(hashes.len(), keys);
        let busiest = buckets.iter().max().copied().unwrap_or(0);
        assert!(busiest <= 30, "{busiest} keys in one bucket");
    }
}
