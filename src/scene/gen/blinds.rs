//! Built-in `genblinds`: venetian blinds.
//!
//! `genblinds mat name depth width height nslats angle [-r|+r rcurv]`. Slat n (1..nslats)
//! starts at height·(n − ½)/nslats on the z axis and runs along y for `width`; a flat slat
//! is one polygon `name.n.0` tilted `angle` degrees up from +x. A curved slat spans an arc
//! of θ = 2 asin(depth/2R), cut into trunc(θ/3° + 0.99999) strips `name.n.k` of chord
//! 2R sin(θ/2·strips), chained from the axis: strip k is tilted angle − θ/2 + (k + ½)·θ/strips
//! with `-r` (the tilt grows along the slat) and angle + θ/2 − (k + ½)·θ/strips with `+r`,
//! as genblinds 6.0a prints them.

use super::{g12, num, prim, ArgError, GenContext};
use crate::scene::primitive::{Location, Primitive};

use super::solar::DEG;

/// Parsed genblinds arguments.
#[derive(Clone, Debug, PartialEq)]
pub struct BlindsArgs {
    pub material: String,
    pub name: String,
    pub depth: f64,
    pub width: f64,
    pub height: f64,
    pub nslats: usize,
    /// Tilt (radians).
    pub angle: f64,
    /// Curvature radius: positive for `-r`, negative for `+r`, None for flat slats.
    pub curve: Option<f64>,
}

const USAGE: &str = "usage: genblinds material name depth width height nslats angle [-r|+r rcurv]";

/// Parse the arguments after the word `genblinds`.
pub fn parse_genblinds_args(args: &[String]) -> Result<BlindsArgs, ArgError> {
    const P: &str = "genblinds";
    let bad = |s: String| ArgError::Bad(format!("genblinds: {s}"));
    if args.len() != 7 && args.len() != 9 {
        return Err(bad(format!("wrong number of arguments; {USAGE}")));
    }
    let nslats = num(P, "nslats", &args[5])?;
    if !(1.0..=1e6).contains(&nslats) {
        return Err(bad(format!("bad slat count '{}'", args[5])));
    }
    let mut a = BlindsArgs {
        material: args[0].clone(),
        name: args[1].clone(),
        depth: num(P, "depth", &args[2])?,
        width: num(P, "width", &args[3])?,
        height: num(P, "height", &args[4])?,
        nslats: nslats as usize,
        angle: num(P, "angle", &args[6])? * DEG,
        curve: None,
    };
    if args.len() == 9 {
        let r = num(P, "curvature radius", &args[8])?;
        a.curve = Some(match args[7].as_str() {
            "-r" => r,
            "+r" => -r,
            w => return Err(bad(format!("bad option '{w}'; {USAGE}"))),
        });
        if r == 0.0 || a.depth.abs() > 2.0 * r.abs() {
            return Err(bad(
                "the curvature radius must be at least half the depth".to_string()
            ));
        }
    }
    Ok(a)
}

impl BlindsArgs {
    /// The strips of one slat: (tilt of each strip, chord length).
    fn strips(&self) -> (Vec<f64>, f64) {
        match self.curve {
            None => (vec![self.angle], self.depth),
            Some(r) => {
                let theta = 2.0 * (self.depth / (2.0 * r.abs())).asin();
                let n = ((theta / (3.0 * DEG)) + 0.99999).trunc().max(1.0) as usize;
                let step = theta / n as f64;
                let chord = 2.0 * r.abs() * (0.5 * step).sin();
                let tilts = (0..n)
                    .map(|k| {
                        let off = -0.5 * theta + (k as f64 + 0.5) * step;
                        if r > 0.0 {
                            self.angle + off
                        } else {
                            self.angle - off
                        }
                    })
                    .collect();
                (tilts, chord)
            }
        }
    }

    /// The primitives, as real genblinds prints them.
    pub fn generate(&self, loc: &Location) -> Vec<Primitive> {
        let (tilts, chord) = self.strips();
        let mut out = Vec::new();
        for n in 1..=self.nslats {
            let z0 = self.height * (n as f64 - 0.5) / self.nslats as f64;
            let (mut x, mut z) = (0.0, z0);
            for (k, t) in tilts.iter().enumerate() {
                let (x1, z1) = (x + chord * t.cos(), z + chord * t.sin());
                let pts = [
                    (x, 0.0, z),
                    (x, self.width, z),
                    (x1, self.width, z1),
                    (x1, 0.0, z1),
                ];
                let r = pts
                    .iter()
                    .flat_map(|&(a, b, c)| [g12(a), g12(b), g12(c)])
                    .collect();
                out.push(prim(
                    &self.material,
                    "polygon",
                    format!("{}.{n}.{k}", self.name),
                    r,
                    loc,
                ));
                (x, z) = (x1, z1);
            }
        }
        out
    }
}

/// Parse and generate in one step.
pub fn genblinds(args: &[String], cx: &GenContext) -> Result<Vec<Primitive>, ArgError> {
    Ok(parse_genblinds_args(args)?.generate(cx.loc))
}
