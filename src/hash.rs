//! A fast integer mix for hash keys of cell coordinates (not input an adversary chooses).

/// One step of the multiply–rotate mix (as FxHash) used for the ambient cache's grid keys and
/// the shadow-reuse cubes.
#[inline]
pub fn fx_mix(h: u64, x: u64) -> u64 {
    (h.rotate_left(5) ^ x).wrapping_mul(0x517C_C1B7_2722_0A95)
}

/// Uniform numbers in [0, 1) from a 64-bit linear congruential generator seeded with
/// `seed`: reproducible inputs for tests (the crate's and the integration tests'), never
/// for rendering.
pub fn test_uniform(seed: u64) -> impl FnMut() -> f64 {
    let mut s = seed;
    move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    }
}
