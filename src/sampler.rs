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
        let bits = mix64(
            self.key
                .wrapping_add((self.dim as u64).wrapping_mul(GOLDEN_GAMMA)),
        );
        self.dim += 1;
        // 24 high bits: every value is exactly representable and strictly below 1.
        (bits >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
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
        let mut word = || (self.next_1d() * 16_777_216.0) as u32 * 256;
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

#[cfg(test)]
mod tests {
    use super::*;

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
