//! Built-in `gendaylit`: the Perez all-weather sky (Perez, Seals & Michalsky 1993) with
//! Perez et al. (1990) luminous efficacies, from the reference (§8.2 of
//! radiance-formats.md).
//!
//! `gendaylit month day hour [-y year] INPUT [opts]` | `gendaylit -ang alt az INPUT
//! [opts]`; INPUT is `-W Edn Edh` (direct normal and diffuse horizontal irradiance),
//! `-G Edh_dir Edh`, `-L Evn Evh` (illuminances), `-E Eglob` (Erbs split) or `-P ε Δ`; the
//! last one given wins. Options `-O 0|1|2`, `-s`, `-c`, `-g refl`, `-a -o -m`, `-d dew`,
//! `-w`, and the ignored `-t -b`. Not built in (reported as unsupported): `-i` (sun
//! correction near sunrise/sunset) and the colour options `-C`, `-l`.
//!
//! Output as the real program's: `void light solar` and `solar source sun` (0.533° disk)
//! unless `-s`/`-c`, then `void brightfunc skyfunc 2 skybright perezlum.cal 0 10 diffnorm
//! ground a b c d e sx sy sz`. Dated runs before sunrise or after sunset give the "error
//! sky" (zeros, no sun).

use std::f64::consts::PI;

use super::sky::sun_primitives;
use super::solar::{self, Site, DEG};
use super::{e3, f6, num, opt_num, value, ArgError, GenContext};
use crate::scene::primitive::{Location, Primitive};

/// The measured input.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Input {
    /// Direct normal, diffuse horizontal irradiance (W/m²).
    W(f64, f64),
    /// Direct horizontal, diffuse horizontal irradiance (W/m²).
    G(f64, f64),
    /// Direct normal, diffuse horizontal illuminance (lux).
    L(f64, f64),
    /// Global horizontal irradiance (W/m²).
    E(f64),
    /// Perez sky clearness ε and brightness Δ.
    P(f64, f64),
}

/// Parsed gendaylit arguments.
#[derive(Clone, Debug, PartialEq)]
pub struct DaylitArgs {
    /// Month, day, hour (solar time?) or None for `-ang`.
    date: Option<(u32, u32, f64, bool)>,
    angles: (f64, f64),
    year: Option<i64>,
    input: Option<Input>,
    output: u8,
    with_sun: bool,
    ground_refl: f64,
    site: Site,
    /// Precipitable water (cm).
    water: f64,
}

const USAGE: &str = "usage: gendaylit month day hour [-y year] {-W|-G|-L} dir diff | -E glob | -P eps delta [options], or gendaylit -ang alt az ...";

/// `atof`: the number at the start of `w` (0 if none), as gendaylit reads its hour.
fn atof(w: &str) -> f64 {
    let b = w.as_bytes();
    let mut i = 0;
    if i < b.len() && (b[i] == b'+' || b[i] == b'-') {
        i += 1;
    }
    while i < b.len() && b[i].is_ascii_digit() {
        i += 1;
    }
    if i < b.len() && b[i] == b'.' {
        i += 1;
        while i < b.len() && b[i].is_ascii_digit() {
            i += 1;
        }
    }
    let mut end = i;
    if i < b.len() && (b[i] == b'e' || b[i] == b'E') {
        let mut j = i + 1;
        if j < b.len() && (b[j] == b'+' || b[j] == b'-') {
            j += 1;
        }
        if j < b.len() && b[j].is_ascii_digit() {
            while j < b.len() && b[j].is_ascii_digit() {
                j += 1;
            }
            end = j;
        }
    }
    w[..end].parse().unwrap_or(0.0)
}

/// Parse the arguments after the word `gendaylit`.
pub fn parse_gendaylit_args(args: &[String]) -> Result<DaylitArgs, ArgError> {
    const P: &str = "gendaylit";
    let bad = |s: String| ArgError::Bad(format!("gendaylit: {s}"));
    if args.len() < 3 {
        return Err(bad(format!("too few arguments; {USAGE}")));
    }
    let mut a = DaylitArgs {
        date: None,
        angles: (0.0, 0.0),
        year: None,
        input: None,
        output: 0,
        with_sun: true,
        ground_refl: 0.2,
        site: Site::default(),
        water: 2.0,
    };
    if args[0] == "-ang" {
        a.angles = (num(P, "altitude", &args[1])?, num(P, "azimuth", &args[2])?);
    } else {
        let (m, d) = solar::parse_date(P, &args[0], &args[1])?;
        let w = args[2].as_str();
        if !w.starts_with(|c: char| c.is_ascii_digit() || c == '+' || c == '.') {
            return Err(bad(format!("bad hour '{w}'")));
        }
        a.date = Some((m, d, atof(w.trim_start_matches('+')), w.starts_with('+')));
    }
    let mut i = 3;
    while i < args.len() {
        let w = args[i].as_str();
        let two = |i: usize| -> Result<(f64, f64), ArgError> {
            if args.len() < i + 3 {
                return Err(bad(format!("missing value for {w} (it takes two)")));
            }
            let x = num(P, &format!("first value for {w}"), &args[i + 1])?;
            let y = num(P, &format!("second value for {w}"), &args[i + 2])?;
            Ok((x, y))
        };
        match w {
            "-W" | "-G" | "-L" | "-P" => {
                let (x, y) = two(i)?;
                a.input = Some(match w {
                    "-W" => Input::W(x, y),
                    "-G" => Input::G(x, y),
                    "-L" => Input::L(x, y),
                    _ => Input::P(x, y),
                });
                i += 2;
            }
            "-E" => {
                a.input = Some(Input::E(opt_num(P, args, i)?));
                i += 1;
            }
            "-O" => {
                let v = value(P, args, i)?;
                a.output = match v {
                    "0" => 0,
                    "1" => 1,
                    "2" => 2,
                    _ => return Err(bad(format!("-O takes 0, 1 or 2, not '{v}'"))),
                };
                i += 1;
            }
            "-s" | "-c" => a.with_sun = false,
            "-w" => {}
            "-g" | "-a" | "-o" | "-m" | "-d" | "-y" | "-t" | "-b" => {
                let v = opt_num(P, args, i)?;
                match w {
                    "-g" => a.ground_refl = v,
                    "-a" => a.site.lat = v * DEG,
                    "-o" => a.site.lon = v * DEG,
                    "-m" => a.site.mer = v * DEG,
                    "-d" => a.water = (0.07 * v - 0.075).exp(),
                    "-y" => a.year = Some(v.trunc() as i64),
                    _ => {}
                }
                i += 1;
            }
            "-i" | "-C" | "-l" | "-CIE" => {
                return Err(ArgError::Unsupported(format!(
                    "gendaylit option {w} is not built in"
                )))
            }
            _ => return Err(bad(format!("unknown option: {w}; {USAGE}"))),
        }
        i += 1;
    }
    Ok(a)
}

/// Perez (1990) luminous efficacy coefficients per ε bin: diffuse (a b c d), direct (a b c d).
const EFFICACY: [([f64; 4], [f64; 4]); 8] = [
    ([97.24, -0.46, 12.00, -8.91], [57.20, -4.55, -2.98, 117.12]),
    ([107.22, 1.15, 0.59, -3.95], [98.99, -3.46, -1.21, 12.38]),
    ([104.97, 2.96, -5.53, -8.77], [109.83, -4.90, -1.71, -8.81]),
    (
        [102.39, 5.59, -13.95, -13.90],
        [110.34, -5.84, -1.99, -4.56],
    ),
    (
        [100.71, 5.94, -22.75, -23.74],
        [106.36, -3.97, -1.75, -6.16],
    ),
    (
        [106.42, 3.83, -36.15, -28.83],
        [107.19, -1.25, -1.51, -26.73],
    ),
    (
        [141.88, 1.90, -53.24, -14.03],
        [105.75, 0.77, -1.26, -34.44],
    ),
    ([152.23, 0.35, -45.27, -7.98], [101.18, 1.58, -1.10, -8.29]),
];

/// Perez (1993) coefficients per ε bin: a, b, c, d, e, each (x0, x1, x2, x3).
const PEREZ: [[[f64; 4]; 5]; 8] = [
    [
        [1.3525, -0.2576, -0.2690, -1.4366],
        [-0.7670, 0.0007, 1.2734, -0.1233],
        [2.8000, 0.6004, 1.2375, 1.000],
        [1.8734, 0.6297, 0.9738, 0.2809],
        [0.0356, -0.1246, -0.5718, 0.9938],
    ],
    [
        [-1.2219, -0.7730, 1.4148, 1.1016],
        [-0.2054, 0.0367, -3.9128, 0.9156],
        [6.9750, 0.1774, 6.4477, -0.1239],
        [-1.5798, -0.5081, -1.7812, 0.1080],
        [0.2624, 0.0672, -0.2190, -0.4285],
    ],
    [
        [-1.1000, -0.2515, 0.8952, 0.0156],
        [0.2782, -0.1812, -4.5000, 1.1766],
        [24.7219, -13.0812, -37.7000, 34.8438],
        [-5.0000, 1.5218, 3.9229, -2.6204],
        [-0.0156, 0.1597, 0.4199, -0.5562],
    ],
    [
        [-0.5484, -0.6654, -0.2672, 0.7117],
        [0.7234, -0.6219, -5.6812, 2.6297],
        [33.3389, -18.3000, -62.2500, 52.0781],
        [-3.5000, 0.0016, 1.1477, 0.1062],
        [0.4659, -0.3296, -0.0876, -0.0329],
    ],
    [
        [-0.6000, -0.3566, -2.5000, 2.3250],
        [0.2937, 0.0496, -5.6812, 1.8415],
        [21.0000, -4.7656, -21.5906, 7.2492],
        [-3.5000, -0.1554, 1.4062, 0.3988],
        [0.0032, 0.0766, -0.0656, -0.1294],
    ],
    [
        [-1.0156, -0.3670, 1.0078, 1.4051],
        [0.2875, -0.5328, -3.8500, 3.3750],
        [14.0000, -0.9999, -7.1406, 7.5469],
        [-3.4000, -0.1078, -1.0750, 1.5702],
        [-0.0672, 0.4016, 0.3017, -0.4844],
    ],
    [
        [-1.0000, 0.0211, 0.5025, -0.5119],
        [-0.3000, 0.1922, 0.7023, -1.6317],
        [19.0000, -5.0000, 1.2438, -1.9094],
        [-4.0000, 0.0250, 0.3844, 0.2656],
        [1.0468, -0.3788, -2.4517, 1.4656],
    ],
    [
        [-1.0500, 0.0289, 0.4260, 0.3590],
        [-0.3250, 0.1156, 0.7781, 0.0025],
        [31.0625, -14.5000, -46.1148, 55.3750],
        [-7.2312, 0.4050, 13.3500, 0.6234],
        [1.5000, -0.6426, 1.8564, 0.5636],
    ],
];

/// Upper bounds of the ε bins.
const EPS_BOUNDS: [f64; 7] = [1.065, 1.23, 1.5, 1.95, 2.8, 4.5, 6.2];

fn bin(eps: f64) -> usize {
    EPS_BOUNDS.iter().take_while(|&&b| eps >= b).count()
}

/// Solid angle of the 0.533° sun disk.
fn sun_solid_angle() -> f64 {
    2.0 * PI * (1.0 - (0.5 * 0.533 * DEG).cos())
}

const SOLAR_CONSTANT: f64 = 1367.0;
/// Direct normal illuminance above which the input is refused (lux).
const SOLAR_ILLUMINANCE: f64 = 127_500.0;
const KAPPA: f64 = 1.041;

/// The model's state for one sky.
struct Model {
    /// Solar zenith angle used by the model (at most 90°).
    z: f64,
    /// Eccentricity correction.
    e0: f64,
    /// Air mass.
    m: f64,
    water: f64,
}

impl Model {
    fn clearness(&self, edn: f64, edh: f64) -> f64 {
        let k = KAPPA * self.z.powi(3);
        let e = ((edh + edn) / edh + k) / (1.0 + k);
        if e.is_nan() || e < 1.0 {
            1.0
        } else if e >= 12.01 {
            12.009
        } else {
            e
        }
    }

    fn brightness(&self, edh: f64) -> f64 {
        (edh * self.m / (SOLAR_CONSTANT * self.e0)).clamp(0.01, 0.6)
    }

    /// Diffuse and direct luminous efficacies (lm/W).
    fn efficacies(&self, eps: f64, delta: f64) -> (f64, f64) {
        let (d, b) = EFFICACY[bin(eps)];
        let w = self.water;
        let diff = d[0] + d[1] * w + d[2] * self.z.cos() + d[3] * delta.ln();
        let dir = b[0] + b[1] * w + b[2] * (5.73 * self.z - 5.0).exp() + b[3] * delta;
        (diff, dir.max(0.0))
    }

    /// Perez coefficients a..e.
    fn coefficients(&self, eps: f64, delta: f64) -> [f64; 5] {
        let k = bin(eps);
        let x = &PEREZ[k];
        let z = self.z;
        let dl = if eps > 1.065 && eps < 2.8 {
            delta.max(0.2)
        } else {
            delta
        };
        let lin = |c: &[f64; 4]| c[0] + c[1] * z + dl * (c[2] + c[3] * z);
        let mut out = [lin(&x[0]), lin(&x[1]), lin(&x[2]), lin(&x[3]), lin(&x[4])];
        if k == 0 {
            out[2] = ((dl * (x[2][0] + x[2][1] * z)).powf(x[2][2])).exp() - x[2][3];
            out[3] = -(dl * (x[3][0] + x[3][1] * z)).exp() + x[3][2] + dl * x[3][3];
        }
        out
    }
}

/// Relative sky luminance at zenith angle `zeta`, `gamma` from the sun.
fn lv(c: &[f64; 5], zeta: f64, gamma: f64) -> f64 {
    (1.0 + c[0] * (c[1] / zeta.cos()).exp())
        * (1.0 + c[2] * (c[3] * gamma).exp() + c[4] * gamma.cos() * gamma.cos())
}

/// Σ lv·cos ζ · 2π/145 over the 145 normalisation points.
fn integral(c: &[f64; 5], z: f64) -> f64 {
    const RINGS: [(f64, u32); 8] = [
        (84.0, 30),
        (72.0, 30),
        (60.0, 24),
        (48.0, 24),
        (36.0, 18),
        (24.0, 12),
        (12.0, 6),
        (0.0, 1),
    ];
    let mut sum = 0.0;
    for (zd, n) in RINGS {
        let zeta = zd * DEG;
        for k in 0..n {
            let phi = 2.0 * PI * k as f64 / n as f64;
            let cg = zeta.cos() * z.cos() + zeta.sin() * z.sin() * phi.cos();
            let gamma = cg.clamp(-1.0, 1.0).acos();
            sum += lv(c, zeta, gamma) * zeta.cos();
        }
    }
    sum * 2.0 * PI / 145.0
}

/// The sky's numbers.
#[derive(Clone, Debug, PartialEq)]
pub enum DaylitSky {
    /// Sun below the horizon (dated runs): zeros.
    Error { dir: [f64; 3] },
    Sky {
        eps: f64,
        delta: f64,
        sun: Option<f64>,
        diffnorm: f64,
        ground: f64,
        coef: [f64; 5],
        dir: [f64; 3],
    },
}

impl DaylitArgs {
    /// Compute the sky.
    pub fn sky(&self) -> DaylitSky {
        let (mut alt, az, jd) = match self.date {
            Some((m, d, hour, solar)) => {
                let s = solar::sun_position(m, d, hour, solar, self.year, &self.site);
                // Before sunrise or after sunset (in solar time): the error sky.
                let half_day = (-self.site.lat.tan() * s.dec.tan()).acos() * 12.0 / PI;
                if s.solar_time < 12.0 - half_day || s.solar_time > 12.0 + half_day {
                    return DaylitSky::Error {
                        dir: solar::sun_direction(s.alt, s.az),
                    };
                }
                (s.alt, s.az, solar::julian_day(m, d) as f64)
            }
            None => (self.angles.0 * DEG, self.angles.1 * DEG, 0.0),
        };
        if alt > 87.0 * DEG {
            alt = 87.0 * DEG;
        }
        let dir = solar::sun_direction(alt, az);
        let z = (PI / 2.0 - alt).min(PI / 2.0);
        let zdeg = z / DEG;
        let da = 2.0 * PI * (jd - 1.0) / 365.0;
        let e0 = 1.00011
            + 0.034221 * da.cos()
            + 0.00128 * da.sin()
            + 0.000719 * (2.0 * da).cos()
            + 0.000077 * (2.0 * da).sin();
        let m = 1.0 / (z.cos() + 0.15 * (93.885 - zdeg).powf(-1.253));
        let model = Model {
            z,
            e0,
            m,
            water: self.water,
        };
        let sz_model = (PI / 2.0 - z).sin();
        // Irradiances (W/m²) and ε, Δ.
        let input = self.input.unwrap_or(Input::P(0.0, 0.0));
        let (edn, edh, eps, delta) = match input {
            Input::W(n, h) => (n, h, model.clearness(n, h), model.brightness(h)),
            Input::G(hdir, h) => {
                let n = hdir / sz_model;
                (n, h, model.clearness(n, h), model.brightness(h))
            }
            Input::E(g) => {
                let kt = g / (SOLAR_CONSTANT * e0 * sz_model);
                let h = if kt <= 0.22 {
                    g * (1.0 - 0.09 * kt)
                } else if kt <= 0.8 {
                    g * (0.9511 - 0.1604 * kt + 4.388 * kt * kt - 16.638 * kt.powi(3)
                        + 12.336 * kt.powi(4))
                } else {
                    0.165 * g
                };
                let n = (g - h) / sz_model;
                (n, h, model.clearness(n, h), model.brightness(h))
            }
            Input::P(eps, delta) => {
                let eps = if eps < 1.0 {
                    1.0
                } else if eps >= 12.01 {
                    12.009
                } else {
                    eps
                };
                let delta = delta.clamp(0.01, 0.6);
                let h = delta * SOLAR_CONSTANT * e0 / m;
                let k = KAPPA * z.powi(3);
                let n = (eps * (1.0 + k) - k - 1.0) * h;
                (n, h, eps, delta)
            }
            Input::L(vn, vh) => {
                // Iterate on the efficacies from a first guess.
                let (mut n, mut h) = (vn / 93.73, vh / 93.73);
                let (mut eps, mut delta) = (model.clearness(n, h), model.brightness(h));
                for _ in 0..9 {
                    let (ed, eb) = model.efficacies(eps, delta);
                    h = vh / ed;
                    n = if eb > 0.0 { vn / eb } else { 0.0 };
                    eps = model.clearness(n, h);
                    delta = model.brightness(h);
                }
                (n, h, eps, delta)
            }
        };
        let (eff_d, eff_b) = model.efficacies(eps, delta);
        let (evdh, evdn) = (edh * eff_d, edn * eff_b);
        // No light, or more direct light than the sun gives outside the atmosphere: the
        // real program prints the error sky.
        if (edn <= 0.0 && edh <= 0.0) || edn > SOLAR_CONSTANT || evdn > SOLAR_ILLUMINANCE {
            return DaylitSky::Error { dir };
        }
        let coef = model.coefficients(eps, delta);
        let i = integral(&coef, z);
        let (diffnorm, sun) = match self.output {
            0 => (evdh / i / 179.0, evdn / sun_solid_angle() / 179.0),
            1 => (edh / i, edn / sun_solid_angle()),
            _ => (evdh / i, evdn / sun_solid_angle()),
        };
        let sun = if eps <= 1.0 { 0.0 } else { sun };
        let zenith = lv(&coef, 0.0, z) * diffnorm;
        let norm = if eps <= 1.0 {
            0.777778
        } else {
            let kind = if eps >= 6.0 {
                super::sky::SkyType::Clear
            } else {
                super::sky::SkyType::Intermediate
            };
            super::sky::f2_norm(kind, alt).1
        };
        let sun_ground = if self.with_sun && eps > 1.0 {
            6.8e-5 / PI * sun * alt.sin()
        } else {
            0.0
        };
        DaylitSky::Sky {
            eps,
            delta,
            sun: self.with_sun.then_some(sun),
            diffnorm,
            ground: (zenith * norm + sun_ground) * self.ground_refl,
            coef,
            dir,
        }
    }

    /// The primitives, as real gendaylit prints them.
    pub fn generate(&self, loc: &Location) -> Vec<Primitive> {
        let skyfunc = |rargs: Vec<f64>| Primitive {
            modifier: "void".into(),
            ptype: "brightfunc".into(),
            name: "skyfunc".into(),
            sargs: vec!["skybright".into(), "perezlum.cal".into()],
            iargs: Vec::new(),
            rargs,
            loc: loc.clone(),
        };
        match self.sky() {
            DaylitSky::Error { dir } => {
                let mut r = vec![0.0; 7];
                r.extend(dir.map(f6));
                vec![skyfunc(r)]
            }
            DaylitSky::Sky {
                sun,
                diffnorm,
                ground,
                coef,
                dir,
                ..
            } => {
                let dir = dir.map(f6);
                let mut out = Vec::new();
                if let Some(l) = sun {
                    out.extend(sun_primitives(e3(l), dir, 0.533, loc));
                }
                let mut r = vec![e3(diffnorm), e3(ground)];
                r.extend(coef.map(f6));
                r.extend(dir);
                out.push(skyfunc(r));
                out
            }
        }
    }
}

/// Parse and generate in one step.
pub fn gendaylit(args: &[String], cx: &GenContext) -> Result<Vec<Primitive>, ArgError> {
    Ok(parse_gendaylit_args(args)?.generate(cx.loc))
}
