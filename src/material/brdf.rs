//! The BRDF-function and BRDF-data materials: `plasfunc`, `metfunc`, `transfunc`,
//! `plasdata`, `metdata`, `transdata` (radiance-formats.md §2.3).
//!
//! ```text
//! mod plasfunc  id  2+ refl ff [xf]                0  4+ r g b spec A5..
//! mod metfunc   id  2+ refl ff [xf]                0  4+ r g b spec A5..
//! mod transfunc id  2+ brtd ff [xf]                0  6+ r g b rspec trans tspec A7..
//! mod plasdata  id  3+N f dfile ff x1..xN [xf]     0  4+ r g b spec A5..
//! mod metdata   id  (as plasdata)
//! mod transdata id  3+N f dfile ff x1..xN [xf]     0  6+ r g b rspec trans tspec A7..
//! ```
//! The function `refl(lx, ly, lz, ω)` (the light direction in the pattern frame and the
//! source's solid angle) is the specular BRDF toward **light sources only**; a data
//! material calls its coordinate functions `xi(lx, ly, lz, ω)`, interpolates its data
//! file there and returns `f(value, lx, ly, lz, ω)`. The split, measured against rpict
//! with rtrace: `T = trans·(1 − rspec)`, `Ts = T·tspec`, diffuse transmission `T − Ts`,
//! diffuse reflection `1 − T − rspec`, colour = `r g b` × pattern colour. Per light
//! sample: diffuse `colour·rdiff·(n·l)·ω/π` (`tdiff` through the back); specular
//! `refl·(n·l)·ω·rspec` (× colour for metals), transmitted `colour·brtd·|n·l|·ω·Ts`. No
//! ray samples the function: the indirect light is `colour·(1 − T)` times the ambient on
//! the front and `colour·T` on the back. The surface turns toward the ray (`-bv`), and so
//! do `Nx Ny Nz Rdot` as the functions see them; `NxP NyP NzP RdotP CrP CgP CbP` are set.
//! These materials stop shadow rays.

use super::{MaterialLookup, WHITE};
use crate::cal::{EvalError, Evaluation, FuncRef};
use crate::color::{bright, Color};
use crate::modifier::data::DataArray;
use crate::modifier::func::{finite, function, load_context, FuncCall};
use crate::render::ray::Ray;
use crate::render::sampler::Sampler;
use crate::render::shading::ShadingPoint;
use crate::render::trace::Tracer;
use crate::scene::primitive::Primitive;
use crate::FTINY;
use glam::DVec3;
use std::f64::consts::PI;
use std::sync::Arc;

/// Which family a [`BrdfMat`] belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BrdfKind {
    /// `plasfunc`, `plasdata`: uncoloured specular.
    Plastic,
    /// `metfunc`, `metdata`: specular in the material's colour.
    Metal,
    /// `transfunc`, `transdata`: plus transmission.
    Trans,
}

/// Where the specular value comes from.
#[derive(Clone, Debug)]
enum Source {
    /// `refl(lx, ly, lz, ω)`.
    Func(FuncRef),
    /// `f(interp(data, x1(..), .., xN(..)), lx, ly, lz, ω)`.
    Data {
        f: FuncRef,
        data: Arc<DataArray>,
        coords: Vec<FuncRef>,
    },
}

/// A BRDF-function or BRDF-data material.
#[derive(Clone, Debug)]
pub struct BrdfMat {
    /// Family.
    pub kind: BrdfKind,
    /// Material colour.
    pub color: Color,
    /// Specular reflectance.
    pub rspec: f64,
    /// Transmitted fraction of what is not specularly reflected (`trans*` only).
    pub trans: f64,
    /// Specular fraction of the transmitted light (`trans*` only).
    pub tspec: f64,
    source: Source,
    call: Arc<FuncCall>,
}

/// The BRDF variables `NxP NyP NzP RdotP CrP CgP CbP` at `sp` (pattern frame) for the
/// ray-facing perturbed normal `n`, its cosine `pdot` with the ray, and colour `c`.
pub(crate) fn brdf_vars(
    call: &FuncCall,
    sp: &ShadingPoint,
    n: DVec3,
    pdot: f64,
    c: Color,
) -> [f64; 7] {
    let np = call.frame().direction_to_pattern(sp, n);
    [np.x, np.y, np.z, pdot.clamp(-1.0, 1.0), c.x, c.y, c.z]
}

/// The arguments `(lx, ly, lz, ω)` of a light direction `l` (world) at `sp`.
pub(crate) fn light_args(call: &FuncCall, sp: &ShadingPoint, l: DVec3, omega: f64) -> [f64; 4] {
    let lp = call.frame().direction_to_pattern(sp, l);
    [lp.x, lp.y, lp.z, omega]
}

impl BrdfMat {
    /// Parse primitive `p` of one of the six types.
    pub fn parse(p: &Primitive, lookup: &dyn MaterialLookup) -> Result<BrdfMat, String> {
        let t = p.ptype.as_str();
        let kind = match t {
            "plasfunc" | "plasdata" => BrdfKind::Plastic,
            "metfunc" | "metdata" => BrdfKind::Metal,
            "transfunc" | "transdata" => BrdfKind::Trans,
            _ => return Err(format!("{t} is not a BRDF function or data material")),
        };
        let data = t.ends_with("data");
        let nreal = if kind == BrdfKind::Trans { 6 } else { 4 };
        let (s, r) = (&p.sargs, &p.rargs);
        let bad = |need: usize| {
            format!(
                "bad # arguments: {} string and {} real arguments, at least {need} and {nreal} \
                 needed",
                s.len(),
                r.len()
            )
        };
        if r.len() < nreal || !p.iargs.is_empty() {
            return Err(bad(if data { 4 } else { 2 }));
        }
        if let Some(v) = r.iter().find(|v| !v.is_finite()) {
            return Err(format!("non-finite real argument {v}"));
        }
        if s.len() < if data { 4 } else { 2 } {
            return Err(bad(if data { 4 } else { 2 }));
        }
        let files = lookup.files();
        let funcs = files.functions();
        let (source, xf_at) = if data {
            let d = files.data(&s[1])?;
            let nd = d.dims();
            if s.len() < 3 + nd {
                return Err(format!(
                    "bad # arguments: data file {} has {nd} dimension(s), {} coordinate \
                     function(s) given",
                    s[1],
                    s.len() - 3
                ));
            }
            let (f, coords) = funcs.with(|b| {
                let ctx = load_context(b, &s[2])?;
                let f = function(b, &s[0], ctx)?;
                let coords = s[3..3 + nd]
                    .iter()
                    .map(|n| function(b, n, ctx))
                    .collect::<Result<Vec<_>, _>>()?;
                Ok((f, coords))
            })?;
            (Source::Data { f, data: d, coords }, 3 + nd)
        } else {
            let f = funcs.with(|b| {
                let ctx = load_context(b, &s[1])?;
                function(b, &s[0], ctx)
            })?;
            (Source::Func(f), 2)
        };
        let call = FuncCall::new(funcs.shared(), p, xf_at)?;
        let (trans, tspec) = if kind == BrdfKind::Trans {
            (r[4], r[5])
        } else {
            (0.0, 0.0)
        };
        Ok(BrdfMat {
            kind,
            color: DVec3::new(r[0], r[1], r[2]),
            rspec: r[3],
            trans,
            tspec,
            source,
            call: Arc::new(call),
        })
    }

    /// The specular function's value for light arguments `a`.
    fn value(&self, ev: &mut Evaluation, a: &[f64; 4]) -> Result<f64, EvalError> {
        match &self.source {
            Source::Func(f) => finite(ev.call(*f, a)?),
            Source::Data { f, data, coords } => {
                let mut x = [0.0; 6];
                for (xi, c) in x.iter_mut().zip(coords) {
                    *xi = finite(ev.call(*c, a)?)?;
                }
                let v = data.interp(&x[..coords.len()]);
                finite(ev.call(*f, &[v, a[0], a[1], a[2], a[3]])?)
            }
        }
    }

    /// Shade a hit: direct light through the function, indirect light as diffuse.
    pub fn shade(&self, tr: &Tracer, ray: &Ray, sp: &ShadingPoint, rng: &mut Sampler) -> Color {
        let hit = &sp.hit;
        // The functions see the surface turned toward the ray (Nx.., Rdot included).
        let (n, fsp) = match super::turn_to_ray(tr, ray, sp, rng) {
            Ok(front) => front,
            Err(c) => return c,
        };
        let mcolor = self.color * sp.pcol;
        let rspec = self.rspec;
        let (trans, tspec) = if self.kind == BrdfKind::Trans {
            let t = self.trans * (1.0 - rspec);
            (t, t * self.tspec)
        } else {
            (0.0, 0.0)
        };
        let tdiff = trans - tspec;
        let rdiff = 1.0 - trans - rspec;
        let pdot = n.dot(-ray.dir).max(0.001);
        let vars = brdf_vars(&self.call, &fsp, n, pdot, mcolor);
        let scolor = if self.kind == BrdfKind::Metal {
            mcolor
        } else {
            WHITE
        };
        let coef = |l: DVec3, omega: f64| -> Color {
            let ldot = n.dot(l);
            if ldot.abs() <= FTINY
                || (ldot < 0.0 && trans <= FTINY)
                || (ldot > 0.0 && trans >= 1.0 - FTINY)
            {
                return Color::ZERO;
            }
            let (diff, spec) = if ldot > 0.0 {
                (rdiff, rspec)
            } else {
                (tdiff, tspec)
            };
            let cosw = ldot.abs() * omega;
            let mut c = mcolor * (diff * cosw / PI);
            if spec <= FTINY {
                return c;
            }
            let a = light_args(&self.call, &fsp, l, omega);
            let Some(f) = self.call.eval(&fsp, Some(vars), |ev| self.value(ev, &a)) else {
                return c;
            };
            if f > FTINY {
                let sc = if ldot > 0.0 { scolor } else { mcolor };
                c += sc * (cosw * spec * f);
            }
            c
        };
        let mut result = tr.direct(ray, hit, n, &coef, rng);
        let other = bright(result);
        if trans < 1.0 - FTINY {
            result += tr.ambient(ray, hit, mcolor * (1.0 - trans), n, other, rng);
        }
        if trans > FTINY {
            result += tr.ambient(ray, hit, mcolor * trans, -n, other, rng);
        }
        result
    }
}
