//! Built-in `genprism`: an extruded polygon.
//!
//! `genprism mat name {N x1 y1 … xN yN | vfile} [-l lx ly lz] [-c] [-e]`: 3..1024
//! vertices (a file holds `x y` pairs), extrusion vector `l` [0 0 1] (lz = 0 is illegal).
//! Output as genprism 6.0a: `name.b` (the vertices as given, z = 0), `name.t` (in reverse
//! order, moved by `l`), then the sides `name.1..N`, side k = (v_k, v_k + l, v_k+1 + l,
//! v_k+1) (wrapping); `-e` omits the ends, `-c` the last side. `-r radius` (rounded edges)
//! is not built in; `-` (vertices on standard input) cannot be used inline.

use glam::DVec3;

use super::{g12, num, opt_num, prim, ArgError, GenContext};
use crate::scene::primitive::{Location, Primitive};

/// Most vertices genprism accepts.
pub const MAX_VERTICES: usize = 1024;

/// Parsed genprism arguments.
#[derive(Clone, Debug, PartialEq)]
pub struct PrismArgs {
    pub material: String,
    pub name: String,
    pub vertices: Vec<(f64, f64)>,
    pub extrude: DVec3,
    pub closed_last: bool,
    pub ends: bool,
}

const USAGE: &str =
    "usage: genprism material name { N x1 y1 .. xN yN | vfile } [-l lx ly lz][-c][-e]";

/// Parse the arguments after the word `genprism`.
pub fn parse_genprism_args(args: &[String]) -> Result<PrismArgs, ArgError> {
    const P: &str = "genprism";
    let bad = |s: String| ArgError::Bad(format!("genprism: {s}"));
    if args.len() < 3 {
        return Err(bad(format!("too few arguments; {USAGE}")));
    }
    let mut i;
    let mut vertices = Vec::new();
    if let Ok(n) = args[2].parse::<usize>() {
        if args.len() < 3 + 2 * n {
            return Err(bad(format!("{n} vertices need {} numbers", 2 * n)));
        }
        for k in 0..n {
            vertices.push((
                num(P, "vertex x", &args[3 + 2 * k])?,
                num(P, "vertex y", &args[4 + 2 * k])?,
            ));
        }
        i = 3 + 2 * n;
    } else if args[2] == "-" {
        return Err(bad(
            "vertices on standard input ('-') cannot be read inline".to_string(),
        ));
    } else {
        let text = std::fs::read_to_string(&args[2])
            .map_err(|e| bad(format!("cannot read vertex file '{}': {e}", args[2])))?;
        let words: Vec<&str> = text.split_whitespace().collect();
        for p in words.chunks(2) {
            if p.len() < 2 {
                break;
            }
            vertices.push((num(P, "vertex x", p[0])?, num(P, "vertex y", p[1])?));
            if vertices.len() > MAX_VERTICES {
                break;
            }
        }
        i = 3;
    }
    if vertices.len() < 3 {
        return Err(bad("not enough vertices".to_string()));
    }
    if vertices.len() > MAX_VERTICES {
        return Err(bad(format!("too many vertices (at most {MAX_VERTICES})")));
    }
    let mut a = PrismArgs {
        material: args[0].clone(),
        name: args[1].clone(),
        vertices,
        extrude: DVec3::Z,
        closed_last: true,
        ends: true,
    };
    while i < args.len() {
        match args[i].as_str() {
            "-l" => {
                if args.len() < i + 4 {
                    return Err(bad("-l needs three numbers".to_string()));
                }
                a.extrude = DVec3::new(
                    num(P, "lx", &args[i + 1])?,
                    num(P, "ly", &args[i + 2])?,
                    num(P, "lz", &args[i + 3])?,
                );
                i += 3;
            }
            "-c" => a.closed_last = false,
            "-e" => a.ends = false,
            "-r" => {
                opt_num(P, args, i)?;
                return Err(ArgError::Unsupported(
                    "genprism option -r (rounded edges) is not built in".to_string(),
                ));
            }
            w => return Err(bad(format!("bad option '{w}'; {USAGE}"))),
        }
        i += 1;
    }
    if a.extrude.z == 0.0 {
        return Err(bad("illegal extrusion vector (lz = 0)".to_string()));
    }
    Ok(a)
}

impl PrismArgs {
    /// The primitives, as real genprism prints them.
    pub fn generate(&self, loc: &Location) -> Vec<Primitive> {
        let base: Vec<DVec3> = self
            .vertices
            .iter()
            .map(|&(x, y)| DVec3::new(x, y, 0.0))
            .collect();
        let l = self.extrude;
        let flat = |pts: &[DVec3]| -> Vec<f64> {
            pts.iter()
                .flat_map(|p| [g12(p.x), g12(p.y), g12(p.z)])
                .collect()
        };
        let poly = |suffix: String, pts: &[DVec3]| {
            prim(
                &self.material,
                "polygon",
                format!("{}.{suffix}", self.name),
                flat(pts),
                loc,
            )
        };
        let mut out = Vec::new();
        if self.ends {
            out.push(poly("b".into(), &base));
            let top: Vec<DVec3> = base.iter().rev().map(|&p| p + l).collect();
            out.push(poly("t".into(), &top));
        }
        let n = base.len();
        let sides = if self.closed_last { n } else { n - 1 };
        for k in 0..sides {
            let (a, b) = (base[k], base[(k + 1) % n]);
            out.push(poly(format!("{}", k + 1), &[a, a + l, b + l, b]));
        }
        out
    }
}

/// Parse and generate in one step.
pub fn genprism(args: &[String], cx: &GenContext) -> Result<Vec<Primitive>, ArgError> {
    Ok(parse_genprism_args(args)?.generate(cx.loc))
}
