//! Light-leak ("corral") protection: a new value whose region of use crosses a wall gets
//! flags for the azimuth sectors where something rises inside its reach, and a lookup in a
//! flagged direction must see the value (docs/ambient.md).

use super::cache::CachedValue;
use super::compute::Ambient;
use glam::DVec3;
use std::f64::consts::PI;
use std::sync::atomic::Ordering;

/// Number of azimuth sectors of the light-leak ("corral") flags: one bit each in a `u32`.
pub const CORRAL_SECTORS: u32 = 32;

/// Elevation above the shading point's tangent plane of the light-leak test ray.
pub const CORRAL_ELEVATION_DEG: f64 = 20.0;

/// Smallest number of θ divisions of a new value's hemisphere for which flags are computed.
pub const CORRAL_MIN_DIVISIONS: usize = 8;

/// The flag sector of an offset `d` in the frame (u, v) (v = n × u): ⌊atan2(d·v, d·u)·16/π⌋
/// mod 32. A degenerate offset falls in sector 0.
pub fn corral_sector(u: DVec3, v: DVec3, d: DVec3) -> u32 {
    sector_of_angle(d.dot(v).atan2(d.dot(u)))
}

fn sector_of_angle(a: f64) -> u32 {
    let s = (a * (CORRAL_SECTORS as f64 / 2.0) / PI).floor();
    if s.is_finite() {
        (s as i64).rem_euclid(CORRAL_SECTORS as i64) as u32
    } else {
        0
    }
}

/// Flags of every sector that the azimuth interval `[a0, a0 + width]` (radians, width below
/// 2π) touches.
fn corral_span(a0: f64, width: f64) -> u32 {
    let sw = 2.0 * PI / CORRAL_SECTORS as f64;
    let first = sector_of_angle(a0);
    let steps = ((width / sw).ceil() as u32 + 1).min(CORRAL_SECTORS);
    let last = sector_of_angle(a0 + width);
    let mut bits = 0u32;
    for i in 0..steps {
        let s = (first + i) % CORRAL_SECTORS;
        bits |= 1 << s;
        if s == last {
            break;
        }
    }
    bits
}

/// Light-leak ("corral") flags of a new value, from its stratified hemisphere samples.
///
/// `hits[j*nphi + k]` is the hit point (relative to the value's position) of the sample in
/// cell (j, k) (θ ring j with `sin²θ ∈ [j/m, (j+1)/m)`, azimuth column k starting at
/// `φ = 2πk/nphi` in the frame (`u0`, `n × u0`)), None for a cell without a sample. The value's
/// final frame is `u` (v = n × u) with radii `rad`, interpolation accuracy (times reach) `aa`.
///
/// Flags are computed only when `m ≥ 8` and the "ceiling" — the mean height above the tangent
/// plane of the innermost ring's hits (the overhead samples) — lies beyond the smaller radius.
/// Then every cell of the outermost ring (the samples nearest the tangent plane) whose hit,
/// projected on the tangent plane, lies inside the value's region of use (the ellipse of
/// semi-axes `aa·rad`) marks the sectors its azimuth interval covers: something rises inside
/// the value's reach in that direction (a wall), and a lookup beyond it must check that the
/// value can be seen. With the ceiling beyond `rad0`, its hits in the outermost ring lie at
/// least `√(m−1)·rad0 ≥ 2.6·rad0` away, outside the ellipse (reach at most `2·aa·rad0`) for
/// any `aa` below 1.3, so a plain ceiling never sets a flag.
pub fn corral_flags(
    hits: &[Option<DVec3>],
    (m, nphi): (usize, usize),
    n: DVec3,
    (u0, u): (DVec3, DVec3),
    rad: [f64; 2],
    aa: f64,
) -> u32 {
    if m < CORRAL_MIN_DIVISIONS || nphi == 0 || hits.len() != m * nphi || aa <= 0.0 {
        return 0;
    }
    let (ra, rb) = (aa * rad[0], aa * rad[1]);
    if !(ra > 0.0 && rb > 0.0 && ra.is_finite() && rb.is_finite()) {
        return 0;
    }
    // The ceiling: mean height of the overhead (innermost ring) hits.
    let (hsum, hcnt) = hits[..nphi]
        .iter()
        .flatten()
        .fold((0.0, 0usize), |(s, c), h| (s + h.dot(n), c + 1));
    let ceiling = if hcnt > 0 { hsum / hcnt as f64 } else { 0.0 };
    if ceiling.is_nan() || ceiling <= rad[0] {
        return 0;
    }
    let v = n.cross(u);
    let v0 = n.cross(u0);
    // Azimuth of u in the (u0, v0) frame: column boundaries shift by it in the (u, v) frame.
    let alpha = u.dot(v0).atan2(u.dot(u0));
    let width = 2.0 * PI / nphi as f64;
    let mut bits = 0u32;
    for (k, h) in hits[(m - 1) * nphi..].iter().enumerate() {
        let Some(h) = h else { continue };
        let (hu, hv) = (h.dot(u) / ra, h.dot(v) / rb);
        if hu * hu + hv * hv < 1.0 {
            bits |= corral_span(k as f64 * width - alpha, width);
        }
    }
    bits
}

/// The end of the light-leak test ray from a shading point `p` (unit normal `n`) toward a
/// cached value at `pv` (unit normal `nv`): the point `Q = pv + t·nv` (t ≥ 0, the smallest)
/// seen from `p` at 20° above the tangent plane of `p`, or `pv + offset·nv` when no such
/// point exists (the value already lies that high, or the normals make it unreachable).
/// Squaring `n·(Q−p) = sin20°·|Q−p|` gives a quadratic in t; roots with `n·(Q−p) ≤ 0` are
/// the mirror solutions below the plane and are dropped.
pub fn corral_target(p: DVec3, n: DVec3, pv: DVec3, nv: DVec3, offset: f64) -> DVec3 {
    let s = CORRAL_ELEVATION_DEG.to_radians().sin();
    let a = pv - p;
    let (na, nb, ab) = (n.dot(a), n.dot(nv), a.dot(nv));
    let qa = nb * nb - s * s;
    let qb = 2.0 * (na * nb - s * s * ab);
    let qc = na * na - s * s * a.length_squared();
    let mut roots = [f64::NAN; 2];
    if qa.abs() > 1e-12 {
        let disc = qb * qb - 4.0 * qa * qc;
        if disc >= 0.0 {
            let sq = disc.sqrt();
            // Numerically stable pair of roots.
            let q = -0.5 * (qb + qb.signum() * sq);
            // q vanishes only with qb = disc = 0 (then qc = 0 too): a double root at 0.
            roots = if q != 0.0 {
                [q / qa, qc / q]
            } else {
                [0.0, 0.0]
            };
        }
    } else if qb.abs() > 1e-300 {
        roots[0] = -qc / qb;
    }
    let best = roots
        .iter()
        .copied()
        .filter(|t| t.is_finite() && *t >= 0.0 && n.dot(a + *t * nv) > 0.0)
        .fold(f64::INFINITY, f64::min);
    if best.is_finite() {
        pv + best * nv
    } else {
        pv + offset * nv
    }
}

impl Ambient {
    /// The light-leak test of a flagged value `v` seen from `p` (normal `n`), whose offset in
    /// the value's frame is (du, dv): when the flag of the offset's sector is set, a shadow
    /// ray from `p` toward the point above the value seen at 20° elevation
    /// ([`corral_target`]) must reach it; true when it is blocked (the value would leak
    /// light through a wall).
    pub(super) fn leaks(
        &self,
        v: &CachedValue,
        p: DVec3,
        n: DVec3,
        du: f64,
        dv: f64,
        occluded: &mut dyn FnMut(DVec3, DVec3, f64) -> bool,
    ) -> bool {
        if v.corral & (1u32 << sector_of_angle(dv.atan2(du))) == 0 {
            return false;
        }
        let d = p - v.pos;
        let dist = d.length();
        if dist.is_nan() || dist <= 1e-4 * v.rad[0] {
            // At the value itself: nothing can stand in between.
            return false;
        }
        let q = corral_target(p, n, v.pos, v.n, 0.05 * dist);
        let to = q - p;
        let len = to.length();
        if !(len > 0.0 && len.is_finite()) {
            return false;
        }
        self.stats.leak_tests.fetch_add(1, Ordering::Relaxed);
        // Stop just short of Q, which lies in free space above the value's surface.
        let blocked = occluded(p, to / len, len * (1.0 - 1e-3));
        if blocked {
            self.stats.leak_rejects.fetch_add(1, Ordering::Relaxed);
        }
        blocked
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ambient::compute::tests::{elevation, X, Y, Z};

    #[test]
    fn sectors_follow_atan2_in_the_value_frame() {
        let s = |x: f64, y: f64| corral_sector(X, Y, DVec3::new(x, y, 0.0));
        assert_eq!(s(1.0, 0.0), 0);
        assert_eq!(s(0.0, 1.0), 8);
        assert_eq!(s(-1.0, 0.0), 16);
        assert_eq!(s(0.0, -1.0), 24);
        assert_eq!(s(1.0, -1e-9), 31);
        let deg = |a: f64| s(a.to_radians().cos(), a.to_radians().sin());
        assert_eq!(deg(11.0), 0);
        assert_eq!(deg(12.0), 1);
        assert_eq!(deg(-11.0), 31);
        assert_eq!(deg(179.0), 15);
        // The component along the normal does not matter; a null offset is sector 0.
        assert_eq!(corral_sector(X, Y, DVec3::new(0.0, 1.0, 5.0)), 8);
        assert_eq!(corral_sector(X, Y, DVec3::ZERO), 0);
        // Another frame: u = y, v = z × y = −x.
        assert_eq!(corral_sector(Y, -X, DVec3::new(-1.0, 0.0, 0.0)), 8);
        // Spans wrap around.
        let w = 0.3;
        assert_eq!(corral_span(-0.1, w), (1 << 31) | 1 | 2);
        assert_eq!(corral_span(0.01, 0.01), 1);
        assert_eq!(corral_span(0.0, 2.0 * PI - 1e-9).count_ones(), 32);
    }

    #[test]
    fn target_is_seen_at_twenty_degrees() {
        // Coplanar: Q = pv + |pv − p|·tan20° · n.
        let q = corral_target(DVec3::ZERO, Z, X, Z, 0.01);
        assert!((q - DVec3::new(1.0, 0.0, 20f64.to_radians().tan())).length() < 1e-12);
        // Tilted normals and a value a little below or above the plane.
        let n = DVec3::new(0.1, -0.05, 1.0).normalize();
        for (pv, nv) in [
            (
                DVec3::new(0.7, 0.4, -0.05),
                DVec3::new(-0.15, 0.1, 1.0).normalize(),
            ),
            (
                DVec3::new(-0.3, 0.9, 0.1),
                DVec3::new(0.2, 0.2, 1.0).normalize(),
            ),
            (DVec3::new(0.2, -0.5, 0.0), n),
        ] {
            let p = DVec3::new(0.05, 0.02, 0.0);
            let q = corral_target(p, n, pv, nv, 0.01);
            let t = (q - pv).dot(nv);
            assert!(
                t >= 0.0 && (q - pv - t * nv).length() < 1e-12,
                "{q} off the line"
            );
            let e = elevation(p, n, q);
            assert!((e - 20.0).abs() < 1e-9, "elevation {e}");
        }
        // A value already seen at 45°: no point of its normal line is at 20°; the fallback.
        let pv = DVec3::new(1.0, 0.0, 1.0);
        let q = corral_target(DVec3::ZERO, Z, pv, Z, 0.01);
        assert!((q - (pv + 0.01 * Z)).length() < 1e-12);
        // Degenerate input stays finite.
        let q = corral_target(DVec3::ZERO, Z, DVec3::ZERO, Z, 0.01);
        assert!(q.is_finite());
    }

    /// Hit points of cell-centre directions in a room: a wall x = `wall` (if any), a
    /// ceiling z = `ceil`, nothing else within 1000.
    fn hemisphere(
        m: usize,
        nphi: usize,
        u0: DVec3,
        wall: Option<f64>,
        ceil: f64,
    ) -> Vec<Option<DVec3>> {
        let v0 = Z.cross(u0);
        let mut out = Vec::new();
        for j in 0..m {
            for k in 0..nphi {
                let s2 = (j as f64 + 0.5) / m as f64;
                let (st, ct) = (s2.sqrt(), (1.0 - s2).sqrt());
                let phi = 2.0 * PI * (k as f64 + 0.5) / nphi as f64;
                let d = Z * ct + (u0 * phi.cos() + v0 * phi.sin()) * st;
                let mut t: f64 = 1000.0;
                if d.z > 0.0 {
                    t = t.min(ceil / d.z);
                }
                if let Some(w) = wall {
                    if d.x > 0.0 {
                        t = t.min(w / d.x);
                    }
                }
                out.push(Some(d * t));
            }
        }
        out
    }

    #[test]
    fn flags_mark_the_wall_side_only() {
        let (m, nphi) = (10, 31);
        let u0 = DVec3::new(0.6, 0.8, 0.0);
        // The value's final frame: u at 30° from x.
        let u = DVec3::new(30f64.to_radians().cos(), 30f64.to_radians().sin(), 0.0);
        let v = Z.cross(u);
        let rad = [1.0, 1.5];
        let aa = 0.5;
        let hits = hemisphere(m, nphi, u0, Some(0.3), 3.0);
        let bits = corral_flags(&hits, (m, nphi), Z, (u0, u), rad, aa);
        let at = |deg: f64| {
            let d = X * deg.to_radians().cos() + Y * deg.to_radians().sin();
            bits & (1 << corral_sector(u, v, d)) != 0
        };
        assert!(at(0.0) && at(30.0) && at(-30.0), "{bits:032b}");
        assert!(
            !at(180.0) && !at(90.0) && !at(-90.0) && !at(120.0),
            "{bits:032b}"
        );
        // The flagged sectors form one run around +x.
        let runs = (0..32)
            .filter(|&i| bits & (1 << i) != 0 && bits & (1 << ((i + 31) % 32)) == 0)
            .count();
        assert_eq!(runs, 1, "{bits:032b}");
        // No wall, a low ceiling, a coarse grid or a wall beyond the reach: no flags.
        let open = hemisphere(m, nphi, u0, None, 3.0);
        assert_eq!(corral_flags(&open, (m, nphi), Z, (u0, u), rad, aa), 0);
        let low = hemisphere(m, nphi, u0, Some(0.3), 0.8);
        assert_eq!(corral_flags(&low, (m, nphi), Z, (u0, u), rad, aa), 0);
        let (mc, nc) = (7, 22);
        let coarse = hemisphere(mc, nc, u0, Some(0.3), 3.0);
        assert_eq!(corral_flags(&coarse, (mc, nc), Z, (u0, u), rad, aa), 0);
        let far = hemisphere(m, nphi, u0, Some(0.9), 3.0);
        assert_eq!(corral_flags(&far, (m, nphi), Z, (u0, u), rad, aa), 0);
        // A ceiling far above a large value never flags by itself.
        let big = [2.9, 5.8];
        assert_eq!(corral_flags(&open, (m, nphi), Z, (u0, u), big, 1.0), 0);
        // Missing samples count for nothing.
        let mut holes = hits.clone();
        for h in holes[(m - 1) * nphi..].iter_mut() {
            *h = None;
        }
        assert_eq!(corral_flags(&holes, (m, nphi), Z, (u0, u), rad, aa), 0);
    }
}
