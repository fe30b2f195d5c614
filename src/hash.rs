//! A fast integer mix for hash keys of cell coordinates (not input an adversary chooses).

/// One step of the multiply–rotate mix (as FxHash) used for the ambient cache's grid keys and
/// the shadow-reuse cubes.
#[inline]
pub fn fx_mix(h: u64, x: u64) -> u64 {
    (h.rotate_left(5) ^ x).wrapping_mul(0x517C_C1B7_2722_0A95)
}
