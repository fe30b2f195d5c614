//! The orientation vector of the anisotropic materials (`plastic2`, `metal2`, `trans2`,
//! `ashik2`): string arguments `ux uy uz ff [xf]` (radiance-formats.md §2.3).
//!
//! `ux uy uz` are expressions in the context of the function file `ff` (`.`: none),
//! evaluated in the pattern frame of the optional transform; the vector is taken back to
//! the world with the forward transform. Three numbers with `.` and no transform are kept
//! as a constant vector (no function language is loaded). The material turns the vector
//! into its tangent frame: `v = normalize(N × u)`, `u = v × N`.

use crate::cal::ExprId;
use crate::material::MaterialLookup;
use crate::modifier::func::{compile, finite, load_context, FuncCall};
use crate::render::shading::ShadingPoint;
use crate::scene::primitive::Primitive;
use crate::FTINY;
use glam::DVec3;
use std::sync::Arc;

/// An orientation vector: constant, or expressions evaluated at each hit.
#[derive(Clone, Debug)]
pub enum Orientation {
    /// Three numbers, no function file, no transform.
    Fixed(DVec3),
    /// Expressions in a function file's context, with the primitive's transform.
    Func {
        /// The primitive's call state (frame, real arguments).
        call: Arc<FuncCall>,
        /// `ux uy uz`.
        exprs: [ExprId; 3],
    },
}

impl Orientation {
    /// Parse string arguments 0..=3 (`ux uy uz ff`) and the transform after them.
    pub fn parse(p: &Primitive, lookup: &dyn MaterialLookup) -> Result<Orientation, String> {
        let s = &p.sargs;
        if s.len() < 4 {
            return Err(format!(
                "bad # arguments: {} string arguments, at least 4 needed (ux uy uz funcfile)",
                s.len()
            ));
        }
        let nums: Vec<f64> = s[..3].iter().filter_map(|w| w.parse().ok()).collect();
        if nums.len() == 3 && s[3] == "." && s.len() == 4 {
            let u = DVec3::new(nums[0], nums[1], nums[2]);
            if u.length_squared() <= FTINY * FTINY || !u.is_finite() {
                return Err("zero orientation vector".to_string());
            }
            return Ok(Orientation::Fixed(u));
        }
        let funcs = lookup.files().functions();
        let exprs = funcs.with(|b| {
            let ctx = load_context(b, &s[3])?;
            let mut e = Vec::with_capacity(3);
            for t in &s[..3] {
                e.push(compile(b, p, t, ctx)?);
            }
            Ok([e[0], e[1], e[2]])
        })?;
        let call = FuncCall::new(funcs.shared(), p, 4)?;
        Ok(Orientation::Func {
            call: Arc::new(call),
            exprs,
        })
    }

    /// The vector in world coordinates at `sp` (not normalised), or None where it cannot
    /// be computed (the material then uses an arbitrary tangent, as Radiance does).
    pub fn world(&self, sp: &ShadingPoint) -> Option<DVec3> {
        match self {
            Orientation::Fixed(u) => Some(*u),
            Orientation::Func { call, exprs } => {
                let v = call.eval(sp, None, |ev| {
                    let mut c = [0.0; 3];
                    for (ci, e) in c.iter_mut().zip(exprs) {
                        *ci = finite(ev.eval(*e)?)?;
                    }
                    Ok(DVec3::from_array(c))
                })?;
                let w = call.frame().vector_to_world(sp, v);
                w.is_finite().then_some(w)
            }
        }
    }

    /// The tangent frame `(u, v)` about the unit normal `n` at `sp` (`v = normalize(n ×
    /// u)`, `u = v × n`), or None where the vector is parallel to `n` or not computable.
    pub fn frame(&self, sp: &ShadingPoint, n: DVec3) -> Option<(DVec3, DVec3)> {
        let u = self.world(sp)?;
        let u = (u - u.dot(n) * n).normalize_or_zero();
        (u != DVec3::ZERO).then(|| (u, n.cross(u)))
    }
}
