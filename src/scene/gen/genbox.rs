//! Built-in `genbox`: `genbox mat name xs ys zs [-i] [-b bevel | -r round]`.
//!
//! Output matches real genbox 6.0a primitive for primitive (names, vertex order, normals):
//! - plain: six polygons `name.1540 .4620 .2310 .3267 .5137 .6457`, where each digit is a
//!   box corner `c` at (c&1 ? xs : 0, c&2 ? ys : 0, c&4 ? zs : 0), in vertex order;
//! - `-i`: the same names with every corner `c` replaced by `7 - c` (normals point inward);
//! - `-b bev`: 6 inset faces, 12 edge bevels and 8 corner triangles whose names spell their
//!   vertices as letters: `c`+corner lies on a y face, `k`+corner on an x face, `M`+corner on
//!   a z face, each pulled in by `bev` along the two other axes;
//! - `-r rad`: the 6 inset faces of `-b`, 12 cylinders `name.st`… and 8 spheres `name.s`…
//!   (`s`+corner = corner pulled in by `rad` on all three axes). As in real genbox, `-b`
//!   and `-r` share one size (the last value given) and the box is rounded if `-r` appears.
//!
//! Real genbox's `-r` with `-i` (a tessellated rounded interior), `-n`, `-s` and `-o` are not
//! built in: [`parse_genbox_args`] reports them as unsupported so the reader can run the
//! real program when commands are allowed.

use glam::DVec3;

use crate::scene::primitive::{Location, Primitive};

/// How box edges are finished.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BoxStyle {
    /// Sharp edges.
    Plain,
    /// Bevelled edges of the given size.
    Bevel(f64),
    /// Rounded edges of the given radius.
    Round(f64),
}

/// Parsed genbox arguments.
#[derive(Clone, Debug, PartialEq)]
pub struct GenboxArgs {
    /// Modifier of every primitive.
    pub material: String,
    /// Base name.
    pub name: String,
    /// Box size along x, y, z.
    pub size: DVec3,
    /// Normals inward (`-i`).
    pub inward: bool,
    /// Edge style.
    pub style: BoxStyle,
}

pub use super::ArgError;

fn num(what: &str, w: &str) -> Result<f64, ArgError> {
    if !crate::scene::lexer::is_real(w) {
        return Err(ArgError::Bad(format!(
            "genbox: {what} '{w}' is not a number"
        )));
    }
    w.parse::<f64>()
        .map_err(|_| ArgError::Bad(format!("genbox: {what} '{w}' is not a number")))
}

/// Parse the arguments after the word `genbox`.
pub fn parse_genbox_args(args: &[String]) -> Result<GenboxArgs, ArgError> {
    const USAGE: &str = "usage: genbox material name xsize ysize zsize [-i] [-b bevel | -r round]";
    if args.len() < 5 {
        return Err(ArgError::Bad(format!("genbox: too few arguments; {USAGE}")));
    }
    let size = DVec3::new(
        num("xsize", &args[2])?,
        num("ysize", &args[3])?,
        num("zsize", &args[4])?,
    );
    if size.min_element() <= 0.0 {
        return Err(ArgError::Bad("genbox: sizes must be positive".to_string()));
    }
    let mut inward = false;
    // Like real genbox: one size shared by -b and -r (the last value given wins), and
    // rounded if -r appears at all.
    let mut amount = None;
    let mut round = false;
    let mut i = 5;
    while i < args.len() {
        match args[i].as_str() {
            "-i" => inward = true,
            "-b" | "-r" => {
                let v = args.get(i + 1).ok_or_else(|| {
                    ArgError::Bad(format!("genbox: missing value for {}", args[i]))
                })?;
                let v = num(&format!("value for {}", args[i]), v)?;
                if v <= 0.0 || 2.0 * v >= size.min_element() {
                    return Err(ArgError::Bad(format!(
                        "genbox: {} {v} must be positive and less than half the smallest size",
                        args[i]
                    )));
                }
                amount = Some(v);
                round |= args[i] == "-r";
                i += 1;
            }
            "-n" | "-s" | "-o" => {
                return Err(ArgError::Unsupported(format!(
                    "genbox option {} is not built in",
                    args[i]
                )))
            }
            other => {
                return Err(ArgError::Bad(format!(
                    "genbox: bad option '{other}'; {USAGE}"
                )))
            }
        }
        i += 1;
    }
    let style = match (amount, round) {
        (Some(r), true) => BoxStyle::Round(r),
        (Some(b), false) => BoxStyle::Bevel(b),
        (None, _) => BoxStyle::Plain,
    };
    if inward && matches!(style, BoxStyle::Round(_)) {
        return Err(ArgError::Unsupported(
            "genbox -r with -i (tessellated rounded interior) is not built in".to_string(),
        ));
    }
    Ok(GenboxArgs {
        material: args[0].clone(),
        name: args[1].clone(),
        size,
        inward,
        style,
    })
}

const PLAIN_FACES: [&str; 6] = ["1540", "4620", "2310", "3267", "5137", "6457"];
const BEVEL_FACES: [&str; 26] = [
    "dhgc", "oqmk", "OPNM", "feij", "plnr", "SQRT", "NdcM", "kmOM", "cgok", "QSqo", "TjiS", "emqi",
    "efPO", "jrnf", "lNPn", "prTR", "hdlp", "QghR", "Mck", "dNl", "Ome", "ogQ", "Siq", "pRh",
    "fnP", "Trj",
];
const ROUND_CYLINDERS: [&str; 12] = [
    "st", "sw", "su", "vt", "vu", "vz", "xt", "xw", "xz", "yu", "yw", "yz",
];

impl GenboxArgs {
    fn corner(&self, c: u8, inset: DVec3) -> DVec3 {
        let c = if self.inward { 7 - c } else { c };
        let pick = |bit: u8, size: f64, d: f64| if c & bit != 0 { size - d } else { d };
        DVec3::new(
            pick(1, self.size.x, inset.x),
            pick(2, self.size.y, inset.y),
            pick(4, self.size.z, inset.z),
        )
    }

    /// Vertex named by a letter (see module docs).
    fn letter(&self, ch: char, d: f64) -> DVec3 {
        let (c, inset) = match ch {
            'c'..='j' => (ch as u8 - b'c', DVec3::new(d, 0.0, d)),
            'k'..='r' => (ch as u8 - b'k', DVec3::new(0.0, d, d)),
            'M'..='T' => (ch as u8 - b'M', DVec3::new(d, d, 0.0)),
            _ => (ch as u8 - b's', DVec3::splat(d)),
        };
        self.corner(c, inset)
    }

    fn prim(&self, ptype: &str, suffix: &str, rargs: Vec<f64>, loc: &Location) -> Primitive {
        Primitive {
            modifier: self.material.clone(),
            ptype: ptype.to_string(),
            name: format!("{}.{}", self.name, suffix),
            sargs: Vec::new(),
            iargs: Vec::new(),
            rargs,
            loc: loc.clone(),
        }
    }

    /// Generate the primitives, all located at `loc`.
    pub fn generate(&self, loc: &Location) -> Vec<Primitive> {
        let flat = |pts: &[DVec3]| pts.iter().flat_map(|p| [p.x, p.y, p.z]).collect::<Vec<_>>();
        match self.style {
            BoxStyle::Plain => PLAIN_FACES
                .iter()
                .map(|f| {
                    let pts: Vec<DVec3> = f
                        .bytes()
                        .map(|b| self.corner(b - b'0', DVec3::ZERO))
                        .collect();
                    self.prim("polygon", f, flat(&pts), loc)
                })
                .collect(),
            BoxStyle::Bevel(d) => BEVEL_FACES
                .iter()
                .map(|f| {
                    let pts: Vec<DVec3> = f.chars().map(|ch| self.letter(ch, d)).collect();
                    self.prim("polygon", f, flat(&pts), loc)
                })
                .collect(),
            BoxStyle::Round(d) => {
                let mut out: Vec<Primitive> = BEVEL_FACES[..6]
                    .iter()
                    .map(|f| {
                        let pts: Vec<DVec3> = f.chars().map(|ch| self.letter(ch, d)).collect();
                        self.prim("polygon", f, flat(&pts), loc)
                    })
                    .collect();
                for c in ROUND_CYLINDERS {
                    let pts: Vec<DVec3> = c.chars().map(|ch| self.letter(ch, d)).collect();
                    let mut r = flat(&pts);
                    r.push(d);
                    out.push(self.prim("cylinder", c, r, loc));
                }
                for k in 0..8u8 {
                    let ch = (b's' + k) as char;
                    let p = self.letter(ch, d);
                    out.push(self.prim("sphere", &ch.to_string(), vec![p.x, p.y, p.z, d], loc));
                }
                out
            }
        }
    }
}

/// Convenience: parse and generate in one step.
pub fn genbox(args: &[String], loc: &Location) -> Result<Vec<Primitive>, ArgError> {
    Ok(parse_genbox_args(args)?.generate(loc))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn a(s: &str) -> Vec<String> {
        s.split_whitespace().map(String::from).collect()
    }

    #[test]
    fn plain_box_matches_known_output() {
        let loc = Location::new("t", 1);
        let p = genbox(&a("m b 1 2 3"), &loc).unwrap();
        assert_eq!(p.len(), 6);
        assert_eq!(p[0].name, "b.1540");
        assert_eq!(
            p[0].rargs,
            vec![1., 0., 0., 1., 0., 3., 0., 0., 3., 0., 0., 0.]
        );
        let p = genbox(&a("m b 10 5 8 -i"), &loc).unwrap();
        assert_eq!(
            p[0].rargs,
            vec![0., 5., 8., 0., 5., 0., 10., 5., 0., 10., 5., 8.]
        );
    }

    #[test]
    fn bevel_and_round_counts() {
        let loc = Location::new("t", 1);
        let p = genbox(&a("m b 1 2 3 -b .1"), &loc).unwrap();
        assert_eq!(p.len(), 26);
        assert_eq!(p[25].name, "b.Trj");
        let p = genbox(&a("m b 1 2 3 -b .2 -r .1"), &loc).unwrap();
        assert_eq!(p.len(), 26);
        assert_eq!(p[6].ptype, "cylinder");
        assert_eq!(p[25].rargs, vec![0.9, 1.9, 2.9, 0.1]);
        let p = genbox(&a("m b 1 2 3 -r .1 -b .2"), &loc).unwrap();
        assert_eq!(p[25].rargs, vec![0.8, 1.8, 2.8, 0.2]);
    }

    #[test]
    fn arg_errors() {
        assert!(matches!(
            parse_genbox_args(&a("m b 1 2")),
            Err(ArgError::Bad(_))
        ));
        assert!(matches!(
            parse_genbox_args(&a("m b 1 2 x")),
            Err(ArgError::Bad(_))
        ));
        assert!(matches!(
            parse_genbox_args(&a("m b 1 2 3 -r")),
            Err(ArgError::Bad(_))
        ));
        assert!(matches!(
            parse_genbox_args(&a("m b 1 2 3 -z")),
            Err(ArgError::Bad(_))
        ));
        assert!(matches!(
            parse_genbox_args(&a("m b 1 2 3 -b .6")),
            Err(ArgError::Bad(_))
        ));
        assert!(matches!(
            parse_genbox_args(&a("m b 1 2 3 -r .1 -i")),
            Err(ArgError::Unsupported(_))
        ));
    }
}
