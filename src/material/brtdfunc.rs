//! `BRTDfunc`: the general function material (radiance-formats.md §2.3).
//!
//! ```text
//! mod BRTDfunc id
//! 10+ rrefl grefl brefl rtrns gtrns btrns rbrtd gbrtd bbrtd ff [xf]
//! 0
//! 9+ rfdif gfdif bfdif rbdif gbdif bbdif rtdif gtdif btdif A10..
//! ```
//! `rrefl..` (expressions) are the mirror reflection, `rtrns..` the straight-through
//! transmission (both traced as one ray each, not coloured by patterns); `rbrtd..` are
//! functions `f(lx, ly, lz, ω)` of the light direction, a directional diffuse part added
//! for light sources only (`0`: none); the reals are the diffuse reflectance of the front
//! and of the back and the diffuse transmittance, each × pattern colour. Measured against
//! rpict with rtrace: per light sample `rdiff·(n·l)·ω/π` (front side), `tdiff·|n·l|·ω/π`
//! (through), plus `brtd(l)·|n·l|·ω` on either side; indirect light `rdiff` about the
//! ray-facing normal and `tdiff` about the other; shadow rays keep `(rtrns, gtrns,
//! btrns)`. The functions see `Nx Ny Nz Rdot` of the unturned surface and `NxP NyP NzP
//! RdotP` turned toward the ray; `CrP CgP CbP` are the pattern colour.

use super::brdf::{brdf_vars, light_args};
use super::{reflect, MaterialLookup};
use crate::cal::{Evaluation, ExprId, FuncRef};
use crate::color::{bright, Color};
use crate::modifier::func::{compile, finite, function, load_context, FuncCall};
use crate::render::ray::{Ray, RayKind};
use crate::render::sampler::Sampler;
use crate::render::shading::ShadingPoint;
use crate::render::trace::Tracer;
use crate::scene::primitive::Primitive;
use crate::FTINY;
use glam::DVec3;
use std::f64::consts::PI;
use std::sync::Arc;

/// A `BRTDfunc` material.
#[derive(Clone, Debug)]
pub struct BrtdFunc {
    refl: [ExprId; 3],
    trans: [ExprId; 3],
    /// The directional functions (None for `0`).
    brtd: [Option<FuncRef>; 3],
    /// Diffuse reflectance of the front side.
    pub front: Color,
    /// Diffuse reflectance of the back side.
    pub back: Color,
    /// Diffuse transmittance.
    pub tdiff: Color,
    call: Arc<FuncCall>,
}

impl BrtdFunc {
    /// Parse a `BRTDfunc` primitive.
    pub fn parse(p: &Primitive, lookup: &dyn MaterialLookup) -> Result<BrtdFunc, String> {
        let (s, r) = (&p.sargs, &p.rargs);
        if s.len() < 10 || r.len() < 9 || !p.iargs.is_empty() {
            return Err(format!(
                "bad # arguments: {} string and {} real arguments, at least 10 and 9 needed",
                s.len(),
                r.len()
            ));
        }
        if let Some(v) = r.iter().find(|v| !v.is_finite()) {
            return Err(format!("non-finite real argument {v}"));
        }
        let funcs = lookup.files().functions();
        let (refl, trans, brtd) = funcs.with(|b| {
            let ctx = load_context(b, &s[9])?;
            let mut e = [None; 6];
            for (ei, t) in e.iter_mut().zip(&s[..6]) {
                *ei = Some(compile(b, p, t, ctx)?);
            }
            let e = e.map(|x| x.expect("compiled"));
            let mut f = [None; 3];
            for (fi, name) in f.iter_mut().zip(&s[6..9]) {
                if name != "0" {
                    *fi = Some(function(b, name, ctx)?);
                }
            }
            Ok(([e[0], e[1], e[2]], [e[3], e[4], e[5]], f))
        })?;
        let call = FuncCall::new(funcs.shared(), p, 10)?;
        let c = |i: usize| DVec3::new(r[i], r[i + 1], r[i + 2]);
        Ok(BrtdFunc {
            refl,
            trans,
            brtd,
            front: c(0),
            back: c(3),
            tdiff: c(6),
            call: Arc::new(call),
        })
    }

    /// The BRDF variables at `sp` (normal turned toward the ray).
    fn vars(&self, sp: &ShadingPoint) -> (DVec3, f64, [f64; 7]) {
        let mut n = sp.normal;
        let mut pdot = -sp.dir.dot(n);
        if sp.hit.back {
            n = -n;
            pdot = -pdot;
        }
        (n, pdot, brdf_vars(&self.call, sp, n, pdot, sp.pcol))
    }

    /// Three expressions' values, None on a computation error.
    fn colour(&self, sp: &ShadingPoint, vars: [f64; 7], e: &[ExprId; 3]) -> Option<Color> {
        self.call.eval(sp, Some(vars), |ev: &mut Evaluation| {
            let mut c = [0.0; 3];
            for (ci, x) in c.iter_mut().zip(e) {
                *ci = finite(ev.eval(*x)?)?;
            }
            Ok(DVec3::from_array(c))
        })
    }

    /// Shade a hit: the mirror and straight-through rays, direct light, ambient.
    pub fn shade(&self, tr: &Tracer, ray: &Ray, sp: &ShadingPoint, rng: &mut Sampler) -> Color {
        let hit = &sp.hit;
        let (n, pdot, vars) = self.vars(sp);
        let rdiff = if hit.back { self.back } else { self.front } * sp.pcol;
        let tdiff = self.tdiff * sp.pcol;
        let hasrefl = bright(rdiff) > FTINY;
        let hastrans = bright(tdiff) > FTINY;
        let mut result = Color::ZERO;
        // Straight through (bent by a texture for rays that are not ambient samples).
        if let Some(tc) = self.colour(sp, vars, &self.trans) {
            let mut dir = ray.dir;
            if sp.is_perturbed() && ray.kind != RayKind::Ambient {
                let pert = if hit.back { -sp.pert } else { sp.pert };
                let d = (ray.dir - 0.75 * pert).normalize_or_zero();
                if d != DVec3::ZERO && d.is_finite() {
                    dir = d;
                }
            }
            if let Some(r) = tr.spawn(ray, hit, dir, RayKind::Transmitted, tc) {
                result += tc * tr.trace(&r, rng);
            }
        }
        // Mirror reflection.
        if let Some(rc) = self.colour(sp, vars, &self.refl) {
            let dir = reflect(ray.dir, n);
            if pdot > 0.0 {
                if let Some(r) = tr.spawn(ray, hit, dir, RayKind::Reflected, rc) {
                    result += rc * tr.trace(&r, rng);
                }
            }
        }
        let directional = self.brtd.iter().any(Option::is_some);
        if hasrefl || hastrans || directional {
            let coef = |l: DVec3, omega: f64| -> Color {
                let ldot = n.dot(l);
                if ldot.abs() <= FTINY {
                    return Color::ZERO;
                }
                let cosw = ldot.abs() * omega;
                let mut c = Color::ZERO;
                if ldot > 0.0 && hasrefl {
                    c += rdiff * (cosw / PI);
                }
                if ldot < 0.0 && hastrans {
                    c += tdiff * (cosw / PI);
                }
                if directional {
                    let a = light_args(&self.call, sp, l, omega);
                    let f = self.call.eval(sp, Some(vars), |ev| {
                        let mut f = [0.0; 3];
                        for (fi, g) in f.iter_mut().zip(&self.brtd) {
                            if let Some(g) = g {
                                *fi = finite(ev.call(*g, &a)?)?;
                            }
                        }
                        Ok(DVec3::from_array(f))
                    });
                    if let Some(f) = f {
                        c += f * cosw;
                    }
                }
                c
            };
            let amb = if hasrefl { rdiff } else { Color::ZERO }
                + if hastrans { tdiff } else { Color::ZERO };
            let known = result + tr.constant_ambient(amb);
            result += tr.direct(ray, hit, (n, known), &coef, rng);
        }
        let other = bright(result);
        if hasrefl {
            result += tr.ambient(ray, hit, rdiff, n, other, rng);
        }
        if hastrans {
            result += tr.ambient(ray, hit, tdiff, -n, other, rng);
        }
        result
    }

    /// What a shadow ray keeps crossing the surface: the straight-through transmission.
    pub fn shadow_transmission(&self, sp: &ShadingPoint) -> Color {
        let (_, _, vars) = self.vars(sp);
        self.colour(sp, vars, &self.trans)
            .map(|c| c.max(Color::ZERO))
            .unwrap_or(Color::ZERO)
    }
}
