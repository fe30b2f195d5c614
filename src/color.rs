//! RGB colour (radiance values) in Radiance's standard primaries.

use glam::DVec3;

/// An RGB triple of radiance or reflectance, in Radiance's standard RGB primaries.
pub type Color = DVec3;

/// Radiance's brightness weights for its standard RGB primaries (`bright()`).
pub const LUMINANCE_WEIGHTS: [f64; 3] = [0.265074126, 0.670114631, 0.064811243];

/// Brightness (relative luminance) of a colour, as Radiance's `bright()`.
#[inline]
pub fn bright(c: Color) -> f64 {
    LUMINANCE_WEIGHTS[0] * c.x + LUMINANCE_WEIGHTS[1] * c.y + LUMINANCE_WEIGHTS[2] * c.z
}

/// Replace any non-finite or negative component with zero.
#[inline]
pub fn sanitize(c: Color) -> Color {
    let f = |v: f64| if v.is_finite() && v > 0.0 { v } else { 0.0 };
    Color::new(f(c.x), f(c.y), f(c.z))
}
