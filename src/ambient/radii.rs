//! A new value's shape: its frame and anisotropic radii (from the Hessian, else the harmonic
//! mean distance), its gradients relative to its light, Radiance's limits on the radii, and
//! Tessera's interpolation reach.

use super::cache::REACH_MAX;
use super::compute::Ambient;
use super::hemisphere::gradients;
use super::hessian::{hessian, hessian_radii};
use super::sample::Hemisphere;
use crate::color::{bright, Color};
use crate::FTINY;
use glam::DVec3;

/// A new value's shape: its frame, radii, gradients and interpolation reach.
pub(super) struct Shape {
    pub(super) u: DVec3,
    pub(super) rad: [f64; 2],
    pub(super) gpos: [f64; 2],
    pub(super) gdir: [f64; 2],
    pub(super) reach: f64,
}

impl Ambient {
    /// A value's frame, radii, gradients and reach from its cells' brightness `lb` and its
    /// light `val`.
    pub(super) fn shape(
        &self,
        h: &Hemisphere,
        lb: &[f64],
        val: Color,
        wt: f64,
        complete: bool,
    ) -> Shape {
        let (cached, m, nphi, n, u0, v0) = (h.cached, h.m, h.nphi, h.n, h.u0, h.v0);
        let dist: Vec<f64> = h.cells.iter().map(|c| c.dist(self.max_dist)).collect();
        let count = h.cells.len() as f64;
        let rsum: f64 = dist.iter().map(|d| 1.0 / d).sum();
        let b = bright(val);
        // Gradients (Ward & Heckbert 1992) of the brightness, relative to the value.
        // Gradients, radii and light-leak flags serve interpolation only: an uncached
        // estimate (-aa 0) is used once and needs none of them.
        let (gpos, gdir) = if cached && b > FTINY && m > 1 && nphi > 1 {
            gradients(lb, &dist, m, nphi, u0, v0)
        } else {
            (DVec3::ZERO, DVec3::ZERO)
        };
        let scale = if b > FTINY { 1.0 / b } else { 0.0 };
        // Radii: from the Hessian when the mesh of hit points is complete, else the harmonic
        // mean distance (isotropic).
        let hess = if cached && complete && self.settings().hessian && m > 1 && nphi > 2 {
            let pts: Vec<DVec3> = h.cells.iter().map(|c| c.hit).collect();
            hessian(
                &pts,
                lb,
                (m, nphi),
                (n, u0, v0),
                self.settings().hessian_cells,
            )
            .and_then(|h| hessian_radii(&h))
        } else {
            None
        };
        let (u, rad) = match hess {
            Some((ang, r0, r1)) => (u0 * ang.cos() + v0 * ang.sin(), [r0, r1]),
            None => {
                let r = count / rsum.max(FTINY);
                (u0, [r, r])
            }
        };
        let v = n.cross(u);
        let gp = [gpos.dot(u) * scale, gpos.dot(v) * scale];
        let gd = [gdir.dot(u) * scale, gdir.dot(v) * scale];
        // The Hessian's own radii (r0 ≤ r1, as `hessian_radii` returns them), kept for the
        // reach.
        let hess_rad = hess.is_some().then_some(rad);
        let mut shape = Shape {
            u,
            rad,
            gpos: gp,
            gdir: gd,
            reach: 1.0,
        };
        self.limit_radii(&mut shape, n, wt, hess_rad.is_none());
        // The room the Hessian leaves beyond the radii used: where `-ar`'s largest radius or
        // the 1:2 aspect limit shrank them, interpolating farther stays within the Hessian's
        // error target, and averages more values' noise.
        let reach = match hess_rad {
            Some(hr) if self.settings().reach => {
                let s = wt.sqrt();
                (hr[0] / s / shape.rad[0])
                    .min(hr[1] / s / shape.rad[1])
                    .clamp(1.0, REACH_MAX)
            }
            _ => 1.0,
        };
        shape.reach = if reach.is_finite() { reach } else { 1.0 };
        shape
    }

    /// Radiance's post-processing of a new value's radii, in order, except that the
    /// gradient does not shrink Hessian radii (`rad_i ≤ 1/|gpos_i|`) unless
    /// `--amb-gradient-radii on`: the Hessian already sets them from the light's variation,
    /// and a noisy gradient (a bright patch caught by a few cells) would shrink them for
    /// noise. The gradient is still capped to the radii. Radii from the mean distance
    /// (`mean_distance`, no Hessian) keep the limit.
    fn limit_radii(&self, s: &mut Shape, n: DVec3, wt: f64, mean_distance: bool) {
        let mut u = s.u;
        let (rad, gp, gd) = (&mut s.rad, &mut s.gpos, &mut s.gdir);
        if self.settings().gradient_radii || mean_distance {
            for i in 0..2 {
                if gp[i].abs() * rad[i] > 1.0 {
                    rad[i] = 1.0 / gp[i].abs();
                }
            }
        }
        if rad[0] > rad[1] {
            // Rotate the frame by 90° so that rad[0] <= rad[1]: u' = v, v' = n × v = −u.
            rad.swap(0, 1);
            *gp = [gp[1], -gp[0]];
            *gd = [gd[1], -gd[0]];
            u = n.cross(u);
        }
        for r in rad.iter_mut() {
            *r = r.max(self.minarad) / wt.sqrt();
        }
        rad[1] = rad[1].min(2.0 * rad[0]);
        for r in rad.iter_mut() {
            *r = r.min(self.maxarad);
        }
        // Cap the gradient so that it changes the value by at most 100% within the radii.
        let glen = ((gp[0] * rad[0]).powi(2) + (gp[1] * rad[1]).powi(2)).sqrt();
        if glen > 1.0 {
            *gp = [gp[0] / glen, gp[1] / glen];
        }
        s.u = u;
    }
}
