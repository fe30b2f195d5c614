//! `ashik2`: the anisotropic model of Ashikhmin & Shirley (2000), radiance-formats.md §2.3.
//!
//! ```text
//! mod ashik2 id  4+ ux uy uz ff [xf]  0  8 dr dg db sr sg sb u-power v-power
//! ```
//! Measured against rpict with rtrace (to 5 digits over light and view directions):
//! - diffuse, per light sample: `d·pcol·(n·l)·ω/π·(1 − (1 − n·l)⁵)`, not reduced by the
//!   specular part (total = diffuse + specular);
//! - specular, per light sample: the published lobe `√((nu+1)(nv+1))/(8π) ·
//!   (n·h)^((nu (h·u)² + nv (h·v)²)/(1 − (n·h)²)) / ((l·h) max(n·l, n·v)) · F(l·h)` ×
//!   `(n·l)·ω`, with Schlick's Fresnel at the view angle, `F = s + (1 − s)(1 − n·v)⁵`
//!   per channel (not `l·h` as published; the specular colour is not multiplied by the
//!   pattern colour);
//! - indirect: the diffuse colour times the ambient; the specular part is sampled with
//!   `-ss` rays drawn from the lobe's half-vector distribution, each weighted by the
//!   specular colour with Schlick's Fresnel at the view angle, `s + (1 − s)(1 − n·v)⁵`
//!   (a uniform sky reflects exactly that); when `s` is below `-st` that colour joins
//!   the ambient coefficient instead.

use super::orient::Orientation;
use super::{expect_args, reflect, MaterialLookup};
use crate::color::{bright, Color};
use crate::render::ray::{Hit, Ray, RayKind};
use crate::render::sampler::Sampler;
use crate::render::shading::ShadingPoint;
use crate::render::trace::Tracer;
use crate::scene::primitive::Primitive;
use crate::FTINY;
use glam::DVec3;
use std::f64::consts::PI;

/// An `ashik2` material.
#[derive(Clone, Debug)]
pub struct Ashik {
    orient: Orientation,
    /// Diffuse reflectance.
    pub diffuse: Color,
    /// Specular reflectance at normal incidence.
    pub specular: Color,
    /// Exponents along u and v.
    pub power: (f64, f64),
}

impl Ashik {
    /// Parse an `ashik2` primitive.
    pub fn parse(p: &Primitive, lookup: &dyn MaterialLookup) -> Result<Ashik, String> {
        let r = &p.rargs;
        expect_args("ashik2", &p.sargs, r, 4..=usize::MAX, &[8])?;
        if r[6] < 0.0 || r[7] < 0.0 {
            return Err("ashik2: negative exponent".to_string());
        }
        Ok(Ashik {
            orient: Orientation::parse(p, lookup).map_err(|m| format!("ashik2: {m}"))?,
            diffuse: DVec3::new(r[0], r[1], r[2]),
            specular: DVec3::new(r[3], r[4], r[5]),
            power: (r[6], r[7]),
        })
    }

    /// The specular BRDF times `n·l` toward `l` (view `v`, frame `(u, w)`, normal `n`,
    /// specular colour `scolor` with the Fresnel term applied).
    fn lobe(&self, (n, u, w): (DVec3, DVec3, DVec3), v: DVec3, l: DVec3, scolor: Color) -> Color {
        let ldot = n.dot(l);
        let h = (l + v).normalize_or_zero();
        let hn = h.dot(n);
        let lh = l.dot(h);
        if hn <= 0.0 || lh <= FTINY {
            return Color::ZERO;
        }
        let (nu, nv) = self.power;
        let (hu, hw) = (h.dot(u), h.dot(w));
        let s2 = 1.0 - hn * hn;
        let e = if s2 > 1e-12 {
            (nu * hu * hu + nv * hw * hw) / s2
        } else {
            0.0
        };
        let mut val =
            hn.powf(e) * ((nu + 1.0) * (nv + 1.0)).sqrt() / (8.0 * PI * lh * ldot.max(n.dot(v)));
        val *= ldot;
        if !val.is_finite() {
            return Color::ZERO;
        }
        scolor * val
    }

    /// Shade a hit.
    pub fn shade(&self, tr: &Tracer, ray: &Ray, sp: &ShadingPoint, rng: &mut Sampler) -> Color {
        let hit = &sp.hit;
        let (n, fsp) = match super::turn_to_ray(tr, ray, sp, rng) {
            Ok(front) => front,
            Err(c) => return c,
        };
        let v = -ray.dir;
        let dcolor = self.diffuse * sp.pcol;
        // Schlick's Fresnel at the view angle, for the whole specular part.
        let f5 = (1.0 - n.dot(v).clamp(0.0, 1.0)).powi(5);
        let scolor = self.specular + (Color::ONE - self.specular) * f5;
        let (u, w) = self.orient.frame(&fsp, n).unwrap_or_else(|| {
            let u = crate::geometry::any_perpendicular(n);
            (u, n.cross(u))
        });
        let rspec = bright(self.specular);
        let hasspec = rspec > FTINY;
        let rblt = hasspec && tr.params.st >= rspec - FTINY;
        let mut result = Color::ZERO;
        if hasspec && !rblt {
            result += self.sample((tr, ray, hit), (n, u, w), scolor, rng);
        }
        let coef = |l: DVec3, omega: f64| -> Color {
            let ldot = n.dot(l);
            if ldot <= 0.0 {
                return Color::ZERO;
            }
            let mut c = dcolor * (ldot * omega / PI * (1.0 - (1.0 - ldot).powi(5)));
            if hasspec {
                c += self.lobe((n, u, w), v, l, scolor) * omega;
            }
            c
        };
        result += tr.direct(ray, hit, n, &coef, rng);
        let mut acolor = dcolor;
        if rblt {
            acolor += scolor;
        }
        let other = bright(result);
        result += tr.ambient(ray, hit, acolor, n, other, rng);
        result
    }

    /// Sample the specular lobe with `-ss` rays from the half-vector distribution of
    /// Ashikhmin & Shirley (φ from `tan φ = √((nu+1)/(nv+1)) tan(πξ₁/2)` per quadrant,
    /// `cos θh = (1 − ξ₂)^(1/(nu cos²φ + nv sin²φ + 1))`), each ray weighted by the
    /// specular colour; a direction below the surface is drawn again.
    fn sample(
        &self,
        (tr, ray, hit): (&Tracer, &Ray, &Hit),
        (n, u, w): (DVec3, DVec3, DVec3),
        scolor: Color,
        rng: &mut Sampler,
    ) -> Color {
        let ss = tr.params.ss;
        let nsamp = if ss > 1.5 {
            ((ss * ray.weight).round() as usize).max(1)
        } else {
            1
        };
        let (nu, nv) = self.power;
        let ratio = ((nu + 1.0) / (nv + 1.0)).sqrt();
        let scale = 1.0 / nsamp as f64;
        let coef = scolor * scale;
        let mut sum = Color::ZERO;
        // Independent draws; one below the surface is drawn again, within a budget of
        // ten draws per ray (Radiance's rule; stratifying the draws would give every
        // azimuth stratum its full share and change the distribution the retries shape).
        let (mut taken, mut tries) = (0, 0);
        while taken < nsamp && tries < 10 * nsamp {
            tries += 1;
            let (mut r1, r2) = rng.next2();
            if (0.0..1.0).contains(&ss) {
                r1 = 0.5 + (r1 - 0.5) * ss;
            }
            // φ over the four quadrants.
            let q = (r1 * 4.0).min(3.999_999);
            let quad = q.floor();
            let x = q - quad;
            let mut phi = (ratio * (0.5 * PI * x).tan()).atan();
            phi = match quad as u32 {
                0 => phi,
                1 => PI - phi,
                2 => PI + phi,
                _ => 2.0 * PI - phi,
            };
            let (c, s) = (phi.cos(), phi.sin());
            let ex = nu * c * c + nv * s * s + 1.0;
            let cos_t = (1.0 - r2).max(0.0).powf(1.0 / ex);
            let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
            let h = (n * cos_t + u * (sin_t * c) + w * (sin_t * s)).normalize();
            let d = reflect(ray.dir, h);
            if d.dot(n) <= FTINY {
                continue;
            }
            taken += 1;
            // Each ray carries its share of the specular colour (as the Gaussian lobe's
            // samples do, `normal.rs`).
            if let Some(r) = tr.spawn(ray, hit, d, RayKind::SpecReflected, coef) {
                sum += tr.trace(&r, rng);
            }
        }
        coef * sum
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// rtrace figures: a 0.5° distant source of radiance 1000 lighting an `ashik2` plane
    /// z = 0 (`u` = x) seen from direction `v`.
    fn source_omega() -> f64 {
        2.0 * PI * (1.0 - 0.25f64.to_radians().cos())
    }

    fn mat(d: f64, s: f64, nu: f64, nv: f64) -> Ashik {
        Ashik {
            orient: Orientation::Fixed(DVec3::X),
            diffuse: Color::splat(d),
            specular: Color::splat(s),
            power: (nu, nv),
        }
    }

    fn specular(m: &Ashik, l: [f64; 3], v: [f64; 3]) -> f64 {
        let (l, v) = (DVec3::from(l).normalize(), DVec3::from(v).normalize());
        let n = DVec3::Z;
        let f5 = (1.0 - n.dot(v)).powi(5);
        let sc = m.specular + (Color::ONE - m.specular) * f5;
        (m.lobe((n, DVec3::X, DVec3::Y), v, l, sc) * source_omega() * 1000.0).x
    }

    #[test]
    fn specular_lobe_matches_rtrace() {
        let m = mat(0.0, 0.1, 10.0, 100.0);
        for (l, v, want) in [
            ([0.3, 0.0, 1.0], [0.0, 0.0, 1.0], 6.902979e-3),
            ([1.0, 0.0, 1.0], [0.0, 0.0, 1.0], 2.750580e-3),
            ([1.0, 0.0, 1.0], [0.0, 0.5, 1.0], 9.334159e-5),
            ([1.0, 0.0, 1.0], [-1.0, 0.0, 1.0], 1.143564e-2),
            ([0.2, 0.1, 1.0], [-0.1, -0.2, 1.0], 7.068806e-3),
        ] {
            let got = specular(&m, l, v);
            assert!(
                (got / want - 1.0).abs() < 1e-4,
                "{l:?} {v:?}: {got} vs {want}"
            );
        }
        // Fresnel at the view angle (not at l·h): off the mirror direction at 45°.
        let m = mat(0.0, 0.05, 400.0, 40.0);
        for (l, want) in [
            ([1.05, 0.0, 1.0], 2.152877e-2),
            ([1.1, 0.0, 1.0], 1.955042e-2),
            ([1.2, 0.0, 1.0], 1.413556e-2),
        ] {
            let got = specular(&m, l, [-1.0, 0.0, 1.0]);
            assert!((got / want - 1.0).abs() < 1e-4, "{l:?}: {got} vs {want}");
        }
    }

    #[test]
    fn diffuse_has_the_grazing_factor() {
        // d = .5 at n·l = 0.2873 (light toward (1, 0, 0.3)): rtrace 2.232539e-3.
        let ldot = DVec3::new(1.0, 0.0, 0.3).normalize().z;
        let got = 0.5 * ldot * source_omega() / PI * (1.0 - (1.0 - ldot).powi(5)) * 1000.0;
        assert!((got / 2.232539e-3 - 1.0).abs() < 1e-5, "{got}");
    }
}
