//! Interpolating cached values at a lookup: Radiance's acceptance tests (level and weight,
//! normal angle, behind-the-plane, the elliptical distance), gradient extrapolation, hat
//! weights, the light-leak test of flagged values, and Tessera's reach and share reach.

use super::cache::CachedValue;
use super::compute::{Ambient, Share};
use crate::color::{bright, Color};
use crate::FTINY;
use glam::DVec3;
use std::f64::consts::PI;

/// A value that may apply at a lookup with the share reach (see
/// [`Ambient::interpolate_share`]).
struct Candidate {
    /// Normalised distance² (in the value's radii).
    dt2: f64,
    /// Angle term² between the normals.
    dr2: f64,
    /// The value extrapolated to the lookup.
    val: Color,
    reach: f64,
    share: f64,
}

thread_local! {
    /// Per-thread buffer of [`Candidate`]s (reused between lookups).
    static CANDIDATES: std::cell::RefCell<Vec<Candidate>> = const { std::cell::RefCell::new(Vec::new()) };
}

thread_local! {
    /// The last ray weight [`widening`] was asked for, and its answer.
    static WIDENING: std::cell::Cell<(f64, f64)> = const { std::cell::Cell::new((f64::NAN, 0.0)) };
}

/// `rweight^0.13`, the widening of the angle limit for light rays: the sample rays of one
/// value, whose lookups follow one another, share a weight, so the last answer is kept
/// (a `powf` call was 0.6% of an `-ab 2` frame).
fn widening(rweight: f64) -> f64 {
    WIDENING.with(|c| {
        let (w, f) = c.get();
        if w == rweight {
            return f;
        }
        let f = rweight.powf(0.13);
        c.set((rweight, f));
        f
    })
}

/// One lookup: the point, its normal, and the limits Radiance's tests use.
struct Lookup<'o> {
    p: DVec3,
    n: DVec3,
    /// Largest angle between the normals.
    maxangle: f64,
    /// How far behind a value's tangent plane `p` may lie.
    behind: f64,
    occluded: &'o mut dyn FnMut(DVec3, DVec3, f64) -> bool,
}

/// The weighted sum of the accepted values.
#[derive(Default)]
struct Sum {
    sum: Color,
    wsum: f64,
    /// Whether a value passes Radiance's own tests (reach 1): else a new value is due, even
    /// when values of a larger reach contribute, so values stay as dense as rpict's.
    near: bool,
}

impl Sum {
    /// Add a value that passed with acceptance limit `lim` (hat weight falling to zero
    /// there); it is near (no new value due) within `near_lim`.
    fn add(&mut self, dt2: f64, dr2: f64, val: Color, maxangle: f64, lim: f64, near_lim: f64) {
        self.near |= dt2 < near_lim * near_lim;
        let w = (1.0 - dr2.sqrt() / maxangle) * (1.0 - dt2.sqrt() / lim);
        self.sum += val * w;
        self.wsum += w;
    }

    fn result(&self) -> Option<Color> {
        (self.near && self.wsum > FTINY).then(|| self.sum / self.wsum)
    }
}

impl Ambient {
    /// Weighted interpolation of the cached values valid at `p` (Radiance's acceptance
    /// tests and weights), or None when no value applies.
    ///
    /// `occluded(org, dir, dist)` answers whether an opaque surface blocks the segment from
    /// `org` along the unit `dir` within `dist`; it is asked about values whose light-leak
    /// flag is set in the direction of `p` (see [`Ambient::leaks`]). Pass `&mut |_, _, _|
    /// false` to interpolate without the test.
    pub fn interpolate(
        &self,
        p: DVec3,
        n: DVec3,
        level: u32,
        rweight: f64,
        occluded: &mut dyn FnMut(DVec3, DVec3, f64) -> bool,
    ) -> Option<Color> {
        self.interpolate_share(p, n, level, rweight, Share::NONE, occluded)
    }

    /// [`Ambient::interpolate`] at a surface that reflects the indirect light by
    /// `share.refl` and sends `share.other` (brightness) besides: each value may serve out
    /// to its share reach ([`CachedValue::share`]) as far as the indirect light's part of
    /// the surface's light allows here ([`Ambient::share_factor`]).
    pub fn interpolate_share(
        &self,
        p: DVec3,
        n: DVec3,
        level: u32,
        rweight: f64,
        share: Share,
        occluded: &mut dyn FnMut(DVec3, DVec3, f64) -> bool,
    ) -> Option<Color> {
        let aa = self.aa();
        let mut maxangle = 10f64.to_radians() + aa;
        if rweight < 0.6 {
            maxangle = (maxangle - PI / 2.0) * widening(rweight) + PI / 2.0;
        }
        let mut q = Lookup {
            p,
            n,
            maxangle,
            behind: -self.minarad * aa,
            occluded,
        };
        let usable =
            |lvl: u32, weight: f64| lvl < level || (lvl == level && weight >= 0.9 * rweight);
        // The share reach applies when the surface sends other light besides.
        if self.settings().share_max > 1.0 && share.other > 0.0 {
            return self.interpolate_shared(&mut q, usable, share);
        }
        let mut acc = Sum::default();
        // The cache hands on only values whose reach sphere (|P − P_v| <
        // aa·reach·share·max(rad), implied by the elliptical test) holds P.
        self.cache.for_each_near(p, usable, |v| {
            // This value's acceptance limit: -aa times its reach.
            let lim = aa * v.reach;
            if let Some((dt2, dr2, val)) = self.accept(v, lim, &mut q) {
                acc.add(dt2, dr2, val, maxangle, lim, aa);
            }
        });
        acc.result()
    }

    /// [`Ambient::interpolate_share`] with the share reach: first every value that may apply
    /// at its widest, then one share factor for all of them from the nearest one's light (a
    /// factor per value would favour the values that are darker than their neighbours).
    fn interpolate_shared(
        &self,
        q: &mut Lookup,
        usable: impl Fn(u32, f64) -> bool,
        share: Share,
    ) -> Option<Color> {
        let aa = self.aa();
        let mut cands = CANDIDATES.with(|c| std::mem::take(&mut *c.borrow_mut()));
        cands.clear();
        self.cache.for_each_near(q.p, usable, |v| {
            let sh = v.share.max(1.0);
            if let Some((dt2, dr2, val)) = self.accept(v, aa * v.reach * sh, q) {
                cands.push(Candidate {
                    dt2,
                    dr2,
                    val,
                    reach: v.reach,
                    share: sh,
                });
            }
        });
        let nearest = cands
            .iter()
            .min_by(|a, b| a.dt2.total_cmp(&b.dt2))
            .map(|c| bright(c.val));
        let mut acc = Sum::default();
        if let Some(b) = nearest {
            let s_here = self.share_factor(share, b);
            for c in &cands {
                let s = c.share.min(s_here);
                let lim = aa * c.reach * s;
                if c.dt2 < lim * lim {
                    acc.add(c.dt2, c.dr2, c.val, q.maxangle, lim, aa * s);
                }
            }
        }
        CANDIDATES.with(|c| *c.borrow_mut() = cands);
        acc.result()
    }

    /// Radiance's tests of value `v` at the lookup `q` with acceptance limit `lim` (its
    /// normalised distance): Some((dt², δr², extrapolated value)) when it passes.
    fn accept(&self, v: &CachedValue, lim: f64, q: &mut Lookup) -> Option<(f64, f64, Color)> {
        let (p, n) = (q.p, q.n);
        let d = v.n.dot(n);
        if d <= 0.0 {
            return None;
        }
        // Rounding can make d exceed 1 for equal normals: keep the angle term real.
        let dr2 = (2.0 - 2.0 * d).max(0.0);
        if dr2 >= q.maxangle * q.maxangle {
            return None;
        }
        let dd = p - v.pos;
        let dn = dd.dot(v.n);
        if dn < q.behind {
            return None;
        }
        let mut dt2 = (dn / v.rad[0]).powi(2);
        if dt2 >= lim * lim {
            return None;
        }
        let vv = v.n.cross(v.u);
        let du = dd.dot(v.u);
        let dv = dd.dot(vv);
        dt2 += (du / v.rad[0]).powi(2) + (dv / v.rad[1]).powi(2);
        if dt2 >= lim * lim {
            return None;
        }
        let rot = v.n.cross(n);
        let f = if !self.settings().gradients {
            1.0
        } else {
            1.0 + v.gpos[0] * du
                + v.gpos[1] * dv
                + v.gdir[0] * rot.dot(v.u)
                + v.gdir[1] * rot.dot(vv)
        };
        if f <= 0.05 {
            return None;
        }
        let f = f.min(20.0);
        if self.settings().corral && v.corral != 0 && self.leaks(v, p, n, du, dv, q.occluded) {
            return None;
        }
        Some((dt2, dr2, v.val * f))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ambient::compute::tests::{elevation, test_ambient, test_ambient_with, unit_value};
    use crate::ambient::settings::AmbientSettings;
    use crate::options::RenderParams;

    const Z: DVec3 = DVec3::Z;

    #[test]
    fn a_wider_reach_adds_weight_but_never_replaces_a_new_value() {
        let params = RenderParams {
            ab: 1,
            aa: 0.2,
            ..RenderParams::default()
        };
        let amb = Ambient::new(&params, 10.0, 1).unwrap();
        let value = |x: f64, v: f64, reach: f64| unit_value(DVec3::new(x, 0.0, 0.0), v, 0, reach);
        let mut clear = |_: DVec3, _: DVec3, _: f64| false;
        // Reach 2 at the origin: the normalised distance 0.3 is beyond aa = 0.2 but within
        // 2·aa. Alone, it does not spare a new value there.
        amb.cache.insert(value(0.0, 1.0, 2.0));
        let p = DVec3::new(0.3, 0.0, 0.0);
        assert!(amb.interpolate(p, Z, 0, 1.0, &mut clear).is_none());
        assert!(amb
            .interpolate(DVec3::new(0.1, 0.0, 0.0), Z, 0, 1.0, &mut clear)
            .is_some());
        // With a reach-1 value within aa of p, the wide value joins the average with the hat
        // weight 1 − 0.3/0.4 = 0.25 (the near value at 0.05 weighs 1 − 0.05/0.2 = 0.75).
        amb.cache.insert(value(0.35, 3.0, 1.0));
        let got = amb.interpolate(p, Z, 0, 1.0, &mut clear).unwrap();
        let want = (0.25 * 1.0 + 0.75 * 3.0) / (0.25 + 0.75);
        assert!((got.x - want).abs() < 1e-9, "{got} vs {want}");
        // Beyond 2·aa it is out of reach: only the near value counts.
        let far = DVec3::new(0.45, 0.0, 0.0);
        let got = amb.interpolate(far, Z, 0, 1.0, &mut clear).unwrap();
        assert!((got.x - 3.0).abs() < 1e-9, "{got}");
    }

    #[test]
    fn lookup_tests_flagged_values_only_in_their_sectors() {
        let amb = test_ambient();
        assert!(amb.settings().corral);
        // A value at the origin facing +z, radius 1, a wall flagged toward +x (sectors 30..1).
        let corral = (1u32 << 30) | (1 << 31) | 1 | 2;
        amb.cache.insert(unit_value(DVec3::ZERO, 1.0, corral, 1.0));
        let mut asked = Vec::new();
        let mut blocked = |o: DVec3, d: DVec3, t: f64| {
            asked.push((o, d, t));
            true
        };
        let east = DVec3::new(0.1, 0.0, 0.0);
        let west = DVec3::new(-0.1, 0.0, 0.0);
        assert!(amb.interpolate(east, Z, 0, 1.0, &mut blocked).is_none());
        assert!(amb.interpolate(west, Z, 0, 1.0, &mut blocked).is_some());
        assert_eq!(asked.len(), 1, "only the flagged direction is tested");
        let (o, d, t) = asked[0];
        assert_eq!(o, east);
        // Toward the point above the value seen at 20°, stopping just short of it.
        let q = o + d * t;
        assert!((elevation(east, Z, q) - 20.0).abs() < 1e-9);
        assert!(q.x.abs() < 1e-3 && (q.z - 0.1 * 20f64.to_radians().tan()).abs() < 1e-3);
        let mut clear = |_: DVec3, _: DVec3, _: f64| false;
        assert!(amb.interpolate(east, Z, 0, 1.0, &mut clear).is_some());
        // Switched off: never asked, never rejected.
        let amb = test_ambient_with(AmbientSettings {
            corral: false,
            ..AmbientSettings::default()
        });
        amb.cache.insert(unit_value(DVec3::ZERO, 1.0, corral, 1.0));
        let mut never = |_: DVec3, _: DVec3, _: f64| -> bool { panic!("asked") };
        assert!(amb.interpolate(east, Z, 0, 1.0, &mut never).is_some());
    }
}
