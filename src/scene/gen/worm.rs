//! Built-in `genworm`: a worm of spheres joined by cones or cylinders along a curve.
//!
//! `genworm mat name 'x(t)' 'y(t)' 'z(t)' 'r(t)' nseg [-e expr] [-f file]`: sphere
//! `name.s0` at t = 0, then for i = 1..nseg a `cylinder name.c<i>` from point i−1 to
//! point i (radius r_i) when the radius does not change (|Δr| ≤ 1e-6), else a `cone`
//! tangent to both spheres, then sphere `name.s<i>`, as genworm 6.0a.

use glam::DVec3;

use super::funcs::{CalDef, Funcs};
use super::{count, g12, prim, value, ArgError, GenContext};
use crate::scene::primitive::Primitive;

const FTINY: f64 = 1e-6;

/// Parsed genworm arguments.
#[derive(Clone, Debug, PartialEq)]
pub struct WormArgs {
    pub material: String,
    pub name: String,
    pub funcs: [String; 4],
    pub nseg: usize,
    pub defs: Vec<CalDef>,
}

const USAGE: &str = "usage: genworm material name x(t) y(t) z(t) r(t) nseg [-e expr] [-f file]";

/// Parse the arguments after the word `genworm`.
pub fn parse_genworm_args(args: &[String]) -> Result<WormArgs, ArgError> {
    const P: &str = "genworm";
    if args.len() < 7 {
        return Err(ArgError::Bad(format!(
            "genworm: too few arguments; {USAGE}"
        )));
    }
    let mut a = WormArgs {
        material: args[0].clone(),
        name: args[1].clone(),
        funcs: [
            args[2].clone(),
            args[3].clone(),
            args[4].clone(),
            args[5].clone(),
        ],
        nseg: count(P, "nseg", &args[6])?,
        defs: Vec::new(),
    };
    let mut i = 7;
    while i < args.len() {
        match args[i].as_str() {
            "-e" => a.defs.push(CalDef::Expr(value(P, args, i)?.to_string())),
            "-f" => a.defs.push(CalDef::File(value(P, args, i)?.to_string())),
            w => return Err(ArgError::Bad(format!("genworm: bad option '{w}'; {USAGE}"))),
        }
        i += 2;
    }
    Ok(a)
}

impl WormArgs {
    /// The primitives, as real genworm prints them.
    pub fn generate(&self, cx: &GenContext) -> Result<Vec<Primitive>, ArgError> {
        // A sphere per joint at least: refuse before evaluating anything.
        cx.check_made("genworm", self.nseg.saturating_add(1))?;
        let f = Funcs::compile(
            "genworm",
            &self.defs,
            &[
                ("x", "t", &self.funcs[0]),
                ("y", "t", &self.funcs[1]),
                ("z", "t", &self.funcs[2]),
                ("r", "t", &self.funcs[3]),
            ],
            cx.raypath,
        )?;
        let at = |t: f64| -> Result<(DVec3, f64), ArgError> {
            Ok((
                DVec3::new(f.call(0, &[t])?, f.call(1, &[t])?, f.call(2, &[t])?),
                f.call(3, &[t])?,
            ))
        };
        let v = |p: DVec3| [g12(p.x), g12(p.y), g12(p.z)];
        let sphere = |i: usize, p: DVec3, r: f64| {
            let mut a = v(p).to_vec();
            a.push(g12(r));
            prim(
                &self.material,
                "sphere",
                format!("{}.s{i}", self.name),
                a,
                cx.loc,
            )
        };
        let (mut p0, mut r0) = at(0.0)?;
        let mut out = vec![sphere(0, p0, r0)];
        for i in 1..=self.nseg {
            let (p1, r1) = at(i as f64 / self.nseg as f64)?;
            let name = format!("{}.c{i}", self.name);
            if (r1 - r0).abs() <= FTINY {
                let mut a = v(p0).to_vec();
                a.extend(v(p1));
                a.push(g12(r1));
                out.push(prim(&self.material, "cylinder", name, a, cx.loc));
            } else {
                let d = p1 - p0;
                let f = (r0 - r1) / d.length_squared();
                let k = (1.0 - (r0 - r1) * f).max(0.0).sqrt();
                let mut a = v(p0 + f * r0 * d).to_vec();
                a.extend(v(p1 + f * r1 * d));
                a.push(g12(k * r0));
                a.push(g12(k * r1));
                out.push(prim(&self.material, "cone", name, a, cx.loc));
            }
            out.push(sphere(i, p1, r1));
            cx.check_made("genworm", out.len())?;
            (p0, r0) = (p1, r1);
        }
        Ok(out)
    }
}

/// Parse and generate in one step.
pub fn genworm(args: &[String], cx: &GenContext) -> Result<Vec<Primitive>, ArgError> {
    parse_genworm_args(args)?.generate(cx)
}
