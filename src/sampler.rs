//! Counter-based random numbers.
//!
//! Every random number is a pure function of `(stream id, sample index, dimension)`: a pixel or a
//! surfel id, the sample number and a running dimension counter are hashed together. Nothing
//! depends on which thread runs the work or in which order, so images are byte-identical for any
//! thread count (the lesson of pbrt-v4's `StartPixelSample`, and of the bakers users complain about).

use glam::Vec2;

/// A stateless-per-sample random stream.
#[derive(Clone, Copy, Debug)]
pub struct Sampler {
    key: u64,
    dim: u32,
}

/// SplitMix64's increment, 2^64 / φ.
pub(crate) const GOLDEN_GAMMA: u64 = 0x9e37_79b9_7f4a_7c15;

/// SplitMix64's finaliser: a bijective 64-bit mix with full avalanche.
#[inline]
pub(crate) fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

impl Sampler {
    /// The stream for sample `index` of item `stream` (pixel, surfel, ...) under `seed`.
    #[inline]
    pub fn new(seed: u64, stream: u64, index: u64) -> Self {
        let key = mix64(
            mix64(seed ^ 0x6a09_e667_f3bc_c908).wrapping_add(stream)
                ^ mix64(index.wrapping_add(GOLDEN_GAMMA)),
        );
        Sampler { key, dim: 0 }
    }

    /// Next uniform number in [0, 1).
    #[inline]
    pub fn next_1d(&mut self) -> f32 {
        // 24 high bits: every value is exactly representable and strictly below 1.
        (self.next_u32() >> 8) as f32 * (1.0 / (1u64 << 24) as f32)
    }

    /// The next dimension as 32 random bits (a permutation's seed, which [`permute`] reads
    /// whole: its top five bits choose one of its multipliers).
    #[inline]
    pub(crate) fn next_u32(&mut self) -> u32 {
        let bits = mix64(
            self.key
                .wrapping_add((self.dim as u64).wrapping_mul(GOLDEN_GAMMA)),
        );
        self.dim += 1;
        (bits >> 32) as u32
    }

    #[inline]
    /// The next two dimensions.
    pub fn next_2d(&mut self) -> Vec2 {
        let x = self.next_1d();
        Vec2::new(x, self.next_1d())
    }

    /// A scramble for [`sobol02`]: two random words (their 24 bits that [`sobol02`] keeps).
    #[inline]
    pub(crate) fn next_scramble(&mut self) -> [u32; 2] {
        let mut word = || self.next_u32() & !0xff;
        [word(), word()]
    }
}

/// Point `k` of the first two Sobol dimensions, a (0, 2)-sequence, xor-scrambled by
/// `scramble`: any 2^m consecutive points from a multiple of 2^m are stratified in every
/// elementary interval of area 2^−m, so K points integrate smooth 2D functions with error
/// O(K^−3/4) instead of Monte Carlo's K^−1/2. A random `scramble` per item keeps the estimate
/// unbiased and decorrelates items.
#[inline]
pub fn sobol02(k: u32, scramble: [u32; 2]) -> Vec2 {
    let x = k.reverse_bits();
    // Dimension 2: generator columns v_i = v_{i−1} ^ (v_{i−1} >> 1) from v_0 = 2^31.
    let (mut y, mut v, mut bits) = (0u32, 1u32 << 31, k);
    while bits != 0 {
        if bits & 1 != 0 {
            y ^= v;
        }
        bits >>= 1;
        v ^= v >> 1;
    }
    let unit = |b: u32| (b >> 8) as f32 * (1.0 / (1u32 << 24) as f32);
    Vec2::new(unit(x ^ scramble[0]), unit(y ^ scramble[1]))
}

/// Index `i` of `0..n` under a pseudo-random permutation chosen by `seed` (Kensler,
/// "Correlated Multi-Jittered Sampling", 2013: a hash that is a bijection on the next power of
/// two, walked until it falls below `n`). Handing a pixel's blocks of a sequence to its
/// camera samples in this order decorrelates the blocks from the samples' own points.
pub(crate) fn permute(mut i: u32, n: u32, seed: u32) -> u32 {
    if n <= 1 {
        return 0;
    }
    let mut w = n - 1;
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    let p = seed;
    loop {
        i ^= p;
        i = i.wrapping_mul(0xe170_893d);
        i ^= p >> 16;
        i ^= (i & w) >> 4;
        i ^= p >> 8;
        i = i.wrapping_mul(0x0929_eb3f);
        i ^= p >> 23;
        i ^= (i & w) >> 1;
        i = i.wrapping_mul(1 | p >> 27);
        i = i.wrapping_mul(0x6935_fa69);
        i ^= (i & w) >> 11;
        i = i.wrapping_mul(0x74dc_b303);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0x9e50_1cc3);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0xc860_a3df);
        i &= w;
        i ^= i >> 5;
        if i < n {
            break;
        }
    }
    (i + p % n) % n
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every n and seed gives a bijection of 0..n, and seeds give different orders.
    #[test]
    fn permute_is_a_bijection() {
        for n in 1..=70u32 {
            for seed in [0u32, 1, 0xdead_beef, 0x8000_0000, u32::MAX] {
                let mut seen = vec![false; n as usize];
                for i in 0..n {
                    let j = permute(i, n, seed) as usize;
                    assert!(!seen[j], "n {n} seed {seed}: {j} twice");
                    seen[j] = true;
                }
            }
        }
        let order = |seed| (0..64).map(|i| permute(i, 64, seed)).collect::<Vec<_>>();
        assert_ne!(order(1), order(2));
        assert_ne!(order(1), (0..64).collect::<Vec<_>>());
    }

    #[test]
    fn words_reach_every_bit() {
        // A permutation's seed is read whole: its top five bits pick a multiplier, which a
        // seed of 24 bits (a uniform number scaled by 2^24) never reached.
        let mut sampler = Sampler::new(7, 3, 1);
        let mut tops = [false; 32];
        for _ in 0..2000 {
            tops[(sampler.next_u32() >> 27) as usize] = true;
        }
        assert!(tops.iter().all(|&t| t));
        // A uniform number is the same draw's 24 high bits.
        let (mut a, mut b) = (Sampler::new(1, 2, 3), Sampler::new(1, 2, 3));
        for _ in 0..100 {
            let word = a.next_u32();
            assert_eq!(b.next_1d(), (word >> 8) as f32 / 16_777_216.0);
        }
    }

    #[test]
    fn sobol_points_are_stratified() {
        // 256 points: each of the 16 × 16 cells, and each 256 × 1 and 1 × 256 strip, holds one.
        for scramble in [[0, 0], [0x1234_5678, 0x9abc_def0]] {
            for (cols, rows) in [(16, 16), (256, 1), (1, 256), (32, 8)] {
                let mut seen = vec![0; 256];
                for k in 0..256 {
                    let p = sobol02(k, scramble);
                    let c = (p.x * cols as f32) as usize + cols * (p.y * rows as f32) as usize;
                    seen[c] += 1;
                }
                assert!(seen.iter().all(|&n| n == 1), "{cols}x{rows}");
            }
        }
    }

    #[test]
    fn uniform_mean_and_range() {
        let mut sum = 0.0_f64;
        let n = 100_000;
        for i in 0..n {
            let mut s = Sampler::new(7, i, 3);
            let x = s.next_1d();
            assert!((0.0..1.0).contains(&x));
            sum += x as f64;
        }
        // Standard error of the mean of U(0,1) is 1/sqrt(12 n) = 9.1e-4; allow 5 of them.
        assert!((sum / n as f64 - 0.5).abs() < 5.0 * 9.2e-4);
    }
}
