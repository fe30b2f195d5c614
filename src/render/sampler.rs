//! Deterministic random numbers: every choice for a pixel is seeded by the pixel position and
//! frame alone, so pictures do not depend on thread count or tiling.

/// A small, fast generator (SplitMix64 seeding a xoshiro256++ state) with a ray counter.
#[derive(Clone, Debug)]
pub struct Sampler {
    s: [u64; 4],
    /// Rays traced with this sampler (statistics).
    pub rays: u64,
}

#[inline]
fn splitmix(x: &mut u64) -> u64 {
    *x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *x;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

impl Sampler {
    /// A sampler for pixel sample (x, y) of `frame`; `salt` separates independent streams.
    pub fn for_pixel(frame: u32, x: u32, y: u32, salt: u32) -> Sampler {
        let mut seed = ((frame as u64) << 32 | salt as u64)
            ^ ((x as u64) << 40 | y as u64).wrapping_mul(0xD6E8_FEB8_6659_FD93);
        let s = [
            splitmix(&mut seed),
            splitmix(&mut seed),
            splitmix(&mut seed),
            splitmix(&mut seed),
        ];
        Sampler { s, rays: 0 }
    }

    /// Next 64 random bits.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        let result = (self.s[0].wrapping_add(self.s[3]))
            .rotate_left(23)
            .wrapping_add(self.s[0]);
        let t = self.s[1] << 17;
        self.s[2] ^= self.s[0];
        self.s[3] ^= self.s[1];
        self.s[1] ^= self.s[2];
        self.s[0] ^= self.s[3];
        self.s[2] ^= t;
        self.s[3] = self.s[3].rotate_left(45);
        result
    }

    /// Uniform in [0, 1).
    #[inline]
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Two uniforms in [0, 1).
    #[inline]
    pub fn next2(&mut self) -> (f64, f64) {
        (self.uniform(), self.uniform())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn deterministic_and_uniform() {
        let mut a = Sampler::for_pixel(0, 10, 20, 0);
        let mut b = Sampler::for_pixel(0, 10, 20, 0);
        let mut c = Sampler::for_pixel(0, 11, 20, 0);
        let va: Vec<f64> = (0..100).map(|_| a.uniform()).collect();
        let vb: Vec<f64> = (0..100).map(|_| b.uniform()).collect();
        let vc: Vec<f64> = (0..100).map(|_| c.uniform()).collect();
        assert_eq!(va, vb);
        assert_ne!(va, vc);
        let mut s = Sampler::for_pixel(1, 2, 3, 4);
        let n = 100_000;
        let mean: f64 = (0..n).map(|_| s.uniform()).sum::<f64>() / n as f64;
        assert!((mean - 0.5).abs() < 0.01, "mean {mean}");
        let mut s = Sampler::for_pixel(1, 2, 3, 4);
        assert!((0..n).map(|_| s.uniform()).all(|v| (0.0..1.0).contains(&v)));
    }
}
