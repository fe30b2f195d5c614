//! Built-in `genrev`: a surface of revolution about the z axis.
//!
//! `genrev mat name 'z(t)' 'r(t)' nseg [-e expr] [-f file] [-s]`: points at t = i/nseg
//! (nseg rounded). Segment i is `name.i`: a `cylinder` (z up) or `tube` (z down) when only
//! z changes (|Δr| ≤ 1e-9), a `ring` at z when only r changes (axis +z if r shrinks, else
//! −z), else a `cone` (z up) or `cup` (z down); nothing when neither changes. `-s` puts a
//! `texfunc Phong` (rev.cal) before each surface, which then takes `Phong` as its
//! modifier: its arguments interpolate the normals of the neighbouring segments (see
//! [`RevArgs::generate`]), as genrev 6.0a prints them.

use super::funcs::{CalDef, Funcs};
use super::{count, g12, value, ArgError, GenContext};
use crate::scene::primitive::Primitive;

/// Below this, a coordinate does not change along a segment.
const TINY: f64 = 1e-9;

/// Parsed genrev arguments.
#[derive(Clone, Debug, PartialEq)]
pub struct RevArgs {
    pub material: String,
    pub name: String,
    pub z: String,
    pub r: String,
    pub nseg: usize,
    pub defs: Vec<CalDef>,
    pub smooth: bool,
}

const USAGE: &str = "usage: genrev material name z(t) r(t) nseg [-e expr] [-f file] [-s]";

/// Parse the arguments after the word `genrev`.
pub fn parse_genrev_args(args: &[String]) -> Result<RevArgs, ArgError> {
    const P: &str = "genrev";
    if args.len() < 5 {
        return Err(ArgError::Bad(format!("genrev: too few arguments; {USAGE}")));
    }
    let mut a = RevArgs {
        material: args[0].clone(),
        name: args[1].clone(),
        z: args[2].clone(),
        r: args[3].clone(),
        nseg: count(P, "nseg", &args[4])?,
        defs: Vec::new(),
        smooth: false,
    };
    let mut i = 5;
    while i < args.len() {
        match args[i].as_str() {
            "-e" => a.defs.push(CalDef::Expr(value(P, args, i)?.to_string())),
            "-f" => a.defs.push(CalDef::File(value(P, args, i)?.to_string())),
            "-s" => {
                a.smooth = true;
                i += 1;
                continue;
            }
            w => return Err(ArgError::Bad(format!("genrev: bad option '{w}'; {USAGE}"))),
        }
        i += 2;
    }
    Ok(a)
}

impl RevArgs {
    /// The primitives, as real genrev prints them.
    pub fn generate(&self, cx: &GenContext) -> Result<Vec<Primitive>, ArgError> {
        let f = Funcs::compile(
            "genrev",
            &self.defs,
            &[("z", "t", &self.z), ("r", "t", &self.r)],
            cx.raypath,
        )?;
        let n = self.nseg;
        let mut pts = Vec::with_capacity(n + 1);
        for i in 0..=n {
            let t = i as f64 / n as f64;
            pts.push((f.call(0, &[t])?, f.call(1, &[t])?));
        }
        // Each segment's unit normal (nz, nr), pointing outward when z increases.
        let normals: Vec<(f64, f64)> = pts
            .windows(2)
            .map(|w| {
                let (z0, r0) = w[0];
                let (z1, r1) = w[1];
                let len = ((r0 - r1).powi(2) + (z1 - z0).powi(2)).sqrt();
                if len > 0.0 {
                    ((r0 - r1) / len, (z1 - z0) / len)
                } else {
                    (0.0, 0.0)
                }
            })
            .collect();
        let loc = cx.loc;
        let mut out = Vec::new();
        for i in 1..=n {
            let (z0, r0) = pts[i - 1];
            let (z1, r1) = pts[i];
            let dz = (z1 - z0).abs() > TINY;
            let dr = (r1 - r0).abs() > TINY;
            let (ptype, rargs) = match (dz, dr) {
                (false, false) => continue,
                (true, false) => (
                    if z1 > z0 { "cylinder" } else { "tube" },
                    vec![0.0, 0.0, g12(z0), 0.0, 0.0, g12(z1), g12(r0)],
                ),
                (false, true) => (
                    "ring",
                    vec![
                        0.0,
                        0.0,
                        g12(z0),
                        0.0,
                        0.0,
                        if r1 < r0 { 1.0 } else { -1.0 },
                        g12(r0),
                        g12(r1),
                    ],
                ),
                (true, true) => (
                    if z1 > z0 { "cone" } else { "cup" },
                    vec![0.0, 0.0, g12(z0), 0.0, 0.0, g12(z1), g12(r0), g12(r1)],
                ),
            };
            let mut modifier = self.material.as_str();
            if self.smooth {
                let prev = if i > 1 { normals[i - 2] } else { (0.0, 0.0) };
                let next = if i < n { normals[i] } else { (0.0, 0.0) };
                let own = normals[i - 1];
                let (a1, a2) = if dz {
                    let a1 = (next.0 - prev.0) / (z1 - z0);
                    (g12(a1), g12(prev.0 - a1 * z0))
                } else {
                    (0.0, own.0)
                };
                let (a3, a4) = if dr {
                    let a3 = (next.1 - prev.1) / (r1 - r0);
                    (g12(a3), g12(prev.1 - a3 * r0))
                } else {
                    (0.0, own.1)
                };
                out.push(Primitive {
                    modifier: self.material.clone(),
                    ptype: "texfunc".into(),
                    name: "Phong".into(),
                    sargs: ["rev_dx", "rev_dy", "rev_dz", "rev.cal"]
                        .map(String::from)
                        .to_vec(),
                    iargs: Vec::new(),
                    rargs: vec![a1, a2, a3, a4],
                    loc: loc.clone(),
                });
                modifier = "Phong";
            }
            out.push(super::prim(
                modifier,
                ptype,
                format!("{}.{i}", self.name),
                rargs,
                loc,
            ));
            cx.check_made("genrev", out.len())?;
        }
        Ok(out)
    }
}

/// Parse and generate in one step.
pub fn genrev(args: &[String], cx: &GenContext) -> Result<Vec<Primitive>, ArgError> {
    parse_genrev_args(args)?.generate(cx)
}
