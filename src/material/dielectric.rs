//! Transparent materials: `glass` (a thin slab, no refraction offset), `dielectric` and
//! `interface` (refracting boundaries with absorption per unit length).

use super::{expect_args, reflect};
use crate::color::Color;
use crate::render::ray::{Ray, RayKind};
use crate::render::sampler::Sampler;
use crate::render::shading::ShadingPoint;
use crate::render::trace::Tracer;
use crate::FTINY;
use glam::DVec3;

/// `glass`: transmissivity per pass at normal incidence and refractive index.
#[derive(Clone, Debug)]
pub struct Glass {
    /// Transmissivity (per unit path at normal incidence) per channel.
    pub tn: Color,
    /// Refractive index (default 1.52).
    pub n: f64,
}

/// Reflectance and transmittance of a thin slab for one polarisation, given the interface
/// reflectance `r` and the internal transmission `tau` for one pass.
#[inline]
fn slab(r: f64, tau: f64) -> (f64, f64) {
    let denom = 1.0 - r * r * tau * tau;
    let t = (1.0 - r) * (1.0 - r) * tau / denom;
    let rr = r * (1.0 + (1.0 - 2.0 * r) * tau * tau) / denom;
    (rr, t)
}

impl Glass {
    /// Parse `glass` (3 or 4 real arguments).
    pub fn parse(sargs: &[String], rargs: &[f64]) -> Result<Glass, String> {
        expect_args("glass", sargs, rargs, 0..=0, &[3, 4])?;
        let n = if rargs.len() == 4 { rargs[3] } else { 1.52 };
        if n <= 0.0 {
            return Err(format!("glass: refractive index must be positive, got {n}"));
        }
        Ok(Glass {
            tn: DVec3::new(rargs[0], rargs[1], rargs[2]),
            n,
        })
    }

    /// Reflected (uncoloured, per channel) and transmitted colours at incidence cosine `cos1`.
    pub fn coefficients(&self, cos1: f64) -> (Color, Color) {
        self.coefficients_of(self.tn, cos1)
    }

    /// [`Glass::coefficients`] for the transmissivity `tn` (the glass's, times a pattern).
    fn coefficients_of(&self, tn: Color, cos1: f64) -> (Color, Color) {
        let cos1 = cos1.clamp(1e-6, 1.0);
        let n = self.n;
        let cos2 = (1.0 - (1.0 - cos1 * cos1) / (n * n))
            .max(0.0)
            .sqrt()
            .max(1e-6);
        // Fresnel reflectance for the two polarisations.
        let re = ((cos1 - n * cos2) / (cos1 + n * cos2)).powi(2);
        let rm = ((1.0 / cos1 - n / cos2) / (1.0 / cos1 + n / cos2)).powi(2);
        let mut refl = Color::ZERO;
        let mut trans = Color::ZERO;
        for c in 0..3 {
            let tau = tn[c].max(0.0).powf(1.0 / cos2);
            let (r1, t1) = slab(re, tau);
            let (r2, t2) = slab(rm, tau);
            refl[c] = 0.5 * (r1 + r2);
            trans[c] = 0.5 * (t1 + t2);
        }
        (refl, trans)
    }

    /// Shade a hit on glass: a mirror ray and a straight-through ray.
    pub fn shade(&self, tr: &Tracer, ray: &Ray, sp: &ShadingPoint, rng: &mut Sampler) -> Color {
        let n = sp.facing_normal();
        let cos1 = -ray.dir.dot(n);
        let (refl, trans) = self.coefficients_of(self.tn * sp.pcol, cos1);
        tr.split(
            ray,
            &sp.hit,
            &[
                (ray.dir, RayKind::Transmitted, trans),
                (reflect(ray.dir, n), RayKind::Reflected, refl),
            ],
            rng,
        )
    }

    /// What a shadow ray sees through the glass.
    pub fn shadow_transmission(&self, sp: &ShadingPoint) -> Color {
        let n = sp.facing_normal();
        self.coefficients_of(self.tn * sp.pcol, -sp.dir.dot(n)).1
    }
}

/// `dielectric` (outside is vacuum) or `interface` (two media).
#[derive(Clone, Debug)]
pub struct Dielectric {
    /// Transmission per unit length inside (behind the surface normal).
    pub inside_col: Color,
    /// Refractive index inside.
    pub inside_n: f64,
    /// Transmission per unit length outside.
    pub outside_col: Color,
    /// Refractive index outside.
    pub outside_n: f64,
    /// Hartmann's dispersion constant (`dielectric` only; 0 for none).
    pub hartmann: f64,
}

/// Unpolarised Fresnel reflectance from index `n1` into `n2` at incidence cosine `ci`;
/// returns (reflectance, transmitted cosine) or None for total internal reflection.
pub fn fresnel(n1: f64, n2: f64, ci: f64) -> Option<(f64, f64)> {
    let eta = n1 / n2;
    let s2 = eta * eta * (1.0 - ci * ci);
    if s2 >= 1.0 {
        return None;
    }
    let ct = (1.0 - s2).sqrt();
    let rs = (n1 * ci - n2 * ct) / (n1 * ci + n2 * ct);
    let rp = (n2 * ci - n1 * ct) / (n2 * ci + n1 * ct);
    Some((0.5 * (rs * rs + rp * rp), ct))
}

impl Dielectric {
    /// Parse `dielectric` (5 reals) or `interface` (8 reals).
    pub fn parse(ptype: &str, sargs: &[String], rargs: &[f64]) -> Result<Dielectric, String> {
        let d = if ptype == "dielectric" {
            expect_args(ptype, sargs, rargs, 0..=0, &[5])?;
            Dielectric {
                inside_col: DVec3::new(rargs[0], rargs[1], rargs[2]),
                inside_n: rargs[3],
                outside_col: DVec3::ONE,
                outside_n: 1.0,
                hartmann: rargs[4],
            }
        } else {
            expect_args(ptype, sargs, rargs, 0..=0, &[8])?;
            Dielectric {
                inside_col: DVec3::new(rargs[0], rargs[1], rargs[2]),
                inside_n: rargs[3],
                outside_col: DVec3::new(rargs[4], rargs[5], rargs[6]),
                outside_n: rargs[7],
                hartmann: 0.0,
            }
        };
        if d.inside_n <= 0.0 || d.outside_n <= 0.0 {
            return Err(format!("{ptype}: refractive indices must be positive"));
        }
        if d.hartmann != 0.0 {
            return Err(format!(
                "{ptype}: a non-zero Hartmann dispersion constant is not supported yet"
            ));
        }
        Ok(d)
    }

    /// Shade: attenuate along the arriving ray's medium, then reflect and refract.
    pub fn shade(&self, tr: &Tracer, ray: &Ray, sp: &ShadingPoint, rng: &mut Sampler) -> Color {
        let hit = &sp.hit;
        // The arriving ray travelled `hit.t` through the medium on its own side; a pattern
        // multiplies the media's transmission.
        let (n, n1, n2, col1) = if hit.back {
            (-sp.normal, self.inside_n, self.outside_n, self.inside_col)
        } else {
            (sp.normal, self.outside_n, self.inside_n, self.outside_col)
        };
        let col1 = col1 * sp.pcol;
        let atten = Color::new(
            absorb(col1.x, hit.t),
            absorb(col1.y, hit.t),
            absorb(col1.z, hit.t),
        );
        let ci = (-ray.dir.dot(n)).clamp(0.0, 1.0);
        let (refl, refr) = match fresnel(n1, n2, ci) {
            Some((r, ct)) => {
                let eta = n1 / n2;
                let t = (ray.dir * eta + n * (eta * ci - ct)).normalize();
                (r, Some((1.0 - r, t)))
            }
            None => (1.0, None),
        };
        let mut branches = [(DVec3::ZERO, RayKind::Transmitted, Color::ZERO); 2];
        let mut count = 0;
        if let Some((tw, tdir)) = refr {
            branches[count] = (tdir, RayKind::Transmitted, atten * tw);
            count += 1;
        }
        if refl > FTINY {
            branches[count] = (reflect(ray.dir, n), RayKind::Reflected, atten * refl);
            count += 1;
        }
        tr.split(ray, hit, &branches[..count], rng)
    }
}

/// Transmission after travelling `dist` through a medium of transmission `c` per unit length.
#[inline]
pub fn absorb(c: f64, dist: f64) -> f64 {
    if c >= 1.0 - 1e-12 {
        1.0
    } else if c <= 0.0 {
        0.0
    } else {
        let od = -c.ln() * dist;
        if od > 92.0 {
            0.0
        } else {
            (-od).exp()
        }
    }
}
