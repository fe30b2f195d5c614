//! The function patterns, texture and mixture: `brightfunc`, `colorfunc`, `texfunc` and
//! `mixfunc` (radiance-formats.md §2.3).
//!
//! ```text
//! mod brightfunc id  2+ refl ff [xf]       0  n A1..An   pattern colour ×= refl
//! mod colorfunc  id  4+ r g b ff [xf]      0  n A1..An   pattern colour ×= (r, g, b)
//! mod texfunc    id  4+ dx dy dz ff [xf]   0  n A1..An   perturbation += (dx, dy, dz)
//! void mixfunc   id  4+ fore back c ff [xf] 0 n A1..An   foreground share c
//! ```
//! Expressions are compiled in the context of the function file `ff` (`.`: none) and
//! evaluated in the pattern frame ([`super::frame`]); a texture's vector is taken back to
//! the world frame.

use super::func::{compile, finite, load_context, FuncCall, PureExprs};
use super::{MixCoefficient, ModifierKind, ModifierLookup, Pattern, Texture};
use crate::cal::ExprId;
use crate::color::Color;
use crate::render::shading::ShadingPoint;
use crate::scene::primitive::Primitive;
use glam::DVec3;

/// Compile the first `n` string arguments of `p` as expressions in the context of its
/// function file (string argument `n + skip`), after `skip` leading names.
fn expressions(
    p: &Primitive,
    l: &dyn ModifierLookup,
    skip: usize,
    n: usize,
) -> Result<(Vec<ExprId>, FuncCall), String> {
    if p.sargs.len() < skip + n + 1 {
        return Err(format!(
            "bad # arguments for {} \"{}\": {} string arguments, at least {} needed",
            p.ptype,
            p.name,
            p.sargs.len(),
            skip + n + 1
        ));
    }
    let funcs = l.files().functions();
    let exprs = funcs.with(|b| {
        let ctx = load_context(b, &p.sargs[skip + n])?;
        p.sargs[skip..skip + n]
            .iter()
            .map(|t| compile(b, p, t, ctx))
            .collect::<Result<Vec<_>, _>>()
    })?;
    let call = FuncCall::new(funcs.shared(), p, skip + n + 1)?;
    Ok((exprs, call))
}

/// `brightfunc` and `colorfunc`.
#[derive(Debug)]
struct FuncPattern {
    call: FuncCall,
    /// One expression (grey) or three (r, g, b).
    exprs: Vec<ExprId>,
    pure: PureExprs,
}

impl Pattern for FuncPattern {
    fn colour(&self, sp: &ShadingPoint) -> Option<Color> {
        let c = values(&self.call, &self.exprs, &self.pure, sp)?;
        Some(if self.exprs.len() == 1 {
            Color::splat(c[0])
        } else {
            Color::new(c[0], c[1], c[2])
        })
    }

    fn reads(&self) -> Option<u32> {
        self.pure.reads(&self.call, &self.exprs)
    }
}

/// The values of `exprs` (one to three) at `sp`: by their pure form where it gives them,
/// else by the machine (the same values; errors only from the machine).
fn values(
    call: &FuncCall,
    exprs: &[ExprId],
    pure: &PureExprs,
    sp: &ShadingPoint,
) -> Option<[f64; 3]> {
    if let Some(c) = pure.values(call, exprs, sp) {
        return Some(c);
    }
    call.eval(sp, None, |ev| {
        let mut c = [0.0; 3];
        for (ci, e) in c.iter_mut().zip(exprs) {
            *ci = finite(ev.eval(*e)?)?;
        }
        Ok(c)
    })
}

/// `texfunc`.
#[derive(Debug)]
struct FuncTexture {
    call: FuncCall,
    exprs: Vec<ExprId>,
    pure: PureExprs,
}

impl Texture for FuncTexture {
    fn perturbation(&self, sp: &ShadingPoint) -> Option<DVec3> {
        let v = values(&self.call, &self.exprs, &self.pure, sp)?;
        Some(self.call.frame().vector_to_world(sp, DVec3::from_array(v)))
    }
}

/// `mixfunc`'s coefficient.
#[derive(Debug)]
struct FuncMix {
    call: FuncCall,
    coef: ExprId,
    pure: PureExprs,
}

impl MixCoefficient for FuncMix {
    fn coefficient(&self, sp: &ShadingPoint) -> Option<f64> {
        values(&self.call, &[self.coef], &self.pure, sp).map(|c| c[0])
    }
}

/// Parser of `brightfunc`.
pub fn parse_brightfunc(p: &Primitive, l: &dyn ModifierLookup) -> Result<ModifierKind, String> {
    let (exprs, call) = expressions(p, l, 0, 1)?;
    Ok(ModifierKind::Pattern(Box::new(FuncPattern {
        call,
        exprs,
        pure: PureExprs::default(),
    })))
}

/// Parser of `colorfunc`.
pub fn parse_colorfunc(p: &Primitive, l: &dyn ModifierLookup) -> Result<ModifierKind, String> {
    let (exprs, call) = expressions(p, l, 0, 3)?;
    Ok(ModifierKind::Pattern(Box::new(FuncPattern {
        call,
        exprs,
        pure: PureExprs::default(),
    })))
}

/// Parser of `texfunc`.
pub fn parse_texfunc(p: &Primitive, l: &dyn ModifierLookup) -> Result<ModifierKind, String> {
    let (exprs, call) = expressions(p, l, 0, 3)?;
    Ok(ModifierKind::Texture(Box::new(FuncTexture {
        call,
        exprs,
        pure: PureExprs::default(),
    })))
}

/// Parser of `mixfunc`.
pub fn parse_mixfunc(p: &Primitive, l: &dyn ModifierLookup) -> Result<ModifierKind, String> {
    let (exprs, call) = expressions(p, l, 2, 1)?;
    Ok(ModifierKind::Mixture {
        coef: Box::new(FuncMix {
            call,
            coef: exprs[0],
            pure: PureExprs::default(),
        }),
        foreground: l.modref(&p.sargs[0])?,
        background: l.modref(&p.sargs[1])?,
    })
}
