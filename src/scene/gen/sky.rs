//! Built-in `gensky`: CIE clear, intermediate, overcast and uniform skies with an optional
//! sun, from a date, time and site or from a solar altitude and azimuth.
//!
//! `gensky month day [+]hour[:min][ZONE] [opts]` | `gensky -ang alt az [opts]`, options
//! `+s -s +i -i -c -u -t turb -b zen -B Ediff -r sun -R Edir -g refl -a lat -o lon -m mer
//! -y year` (every option of gensky 6.0a; `-defaults` prints settings, not a scene, and is
//! refused). Output, as the real program's: `void light solar` and `solar source sun`
//! when the sky has a sun above the horizon, then `void brightfunc skyfunc 2 skybr
//! skybright.cal 0 7 type zenith ground F2 sx sy sz` (`3 type zenith ground` for overcast
//! and uniform skies), numbers rounded as printed (`%.3e` radiances, `%f` directions).
//! The brightness models are the reference's (§8.1 of radiance-formats.md).

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

use super::solar::{self, Site, DEG};
use super::{e3, f6, num, opt_num, ArgError, GenContext};
use crate::scene::primitive::{Location, Primitive};

/// Sky types, numbered as skybright.cal's first real argument.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SkyType {
    Clear = 1,
    Overcast = 2,
    Uniform = 3,
    Intermediate = 4,
}

/// A given brightness: a radiance, or an irradiance it is derived from.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Given {
    Radiance(f64),
    Irradiance(f64),
}

/// Luminous efficacy gensky divides zenith luminances by (lm/W), times 1/1000.
const SKY_EFFICACY: f64 = 203.0;

/// Where the sun is, for gensky.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SunSpec {
    /// Date and time at a site.
    Dated {
        month: u32,
        day: u32,
        time: solar::TimeOfDay,
    },
    /// `-ang alt az` (degrees).
    Angles { alt: f64, az: f64 },
}

/// Parsed gensky arguments.
#[derive(Clone, Debug, PartialEq)]
pub struct SkyArgs {
    pub sun: SunSpec,
    pub sky: SkyType,
    pub with_sun: bool,
    turbidity: f64,
    zenith: Option<Given>,
    solar: Option<Given>,
    pub ground_refl: f64,
    pub site: Site,
    pub year: Option<i64>,
}

const USAGE: &str =
    "usage: gensky month day hour [options] | gensky -ang altitude azimuth [options]";

/// Parse the arguments after the word `gensky`.
pub fn parse_gensky_args(args: &[String]) -> Result<SkyArgs, ArgError> {
    const P: &str = "gensky";
    let bad = |s: String| ArgError::Bad(format!("gensky: {s}"));
    if args.first().map(String::as_str) == Some("-defaults") {
        return Err(bad(
            "-defaults prints gensky's settings, not a scene".to_string()
        ));
    }
    if args.len() < 3 {
        return Err(bad(format!("too few arguments; {USAGE}")));
    }
    let sun = if args[0] == "-ang" {
        SunSpec::Angles {
            alt: num(P, "altitude", &args[1])?,
            az: num(P, "azimuth", &args[2])?,
        }
    } else {
        let (month, day) = solar::parse_date(P, &args[0], &args[1])?;
        SunSpec::Dated {
            month,
            day,
            time: solar::parse_time(P, &args[2])?,
        }
    };
    let mut a = SkyArgs {
        sun,
        sky: SkyType::Clear,
        with_sun: true,
        turbidity: 2.45,
        zenith: None,
        solar: None,
        ground_refl: 0.2,
        site: Site::default(),
        year: None,
    };
    let mut i = 3;
    while i < args.len() {
        let w = args[i].as_str();
        let b = w.as_bytes();
        if b.len() != 2 || (b[0] != b'-' && b[0] != b'+') {
            return Err(bad(format!("bad option '{w}'; {USAGE}")));
        }
        let plus = b[0] == b'+';
        match b[1] {
            b's' | b'i' | b'c' | b'u' => {
                a.sky = match b[1] {
                    b's' => SkyType::Clear,
                    b'i' => SkyType::Intermediate,
                    b'c' => SkyType::Overcast,
                    _ => SkyType::Uniform,
                };
                a.with_sun = plus;
            }
            b't' | b'b' | b'B' | b'r' | b'R' | b'g' | b'a' | b'o' | b'm' | b'y' if !plus => {
                let v = opt_num(P, args, i)?;
                match b[1] {
                    b't' => a.turbidity = v,
                    b'b' => a.zenith = Some(Given::Radiance(v)),
                    b'B' => a.zenith = Some(Given::Irradiance(v)),
                    b'r' => a.solar = Some(Given::Radiance(v)),
                    b'R' => a.solar = Some(Given::Irradiance(v)),
                    b'g' => a.ground_refl = v,
                    b'a' => a.site.lat = v * DEG,
                    b'o' => a.site.lon = v * DEG,
                    b'm' => a.site.mer = v * DEG,
                    _ => a.year = Some(v.trunc() as i64),
                }
                i += 1;
            }
            _ => return Err(bad(format!("unknown option: {w}; {USAGE}"))),
        }
        i += 1;
    }
    if let SunSpec::Dated { time, .. } = &a.sun {
        if let Some(m) = time.zone_meridian {
            a.site.mer = m;
        }
    }
    Ok(a)
}

/// The sun's altitude and azimuth (radians) for a date/time or angles.
pub fn sun_alt_az(sun: &SunSpec, site: &Site, year: Option<i64>) -> (f64, f64, Option<f64>) {
    match *sun {
        SunSpec::Angles { alt, az } => (alt * DEG, az * DEG, None),
        SunSpec::Dated { month, day, time } => {
            let s = solar::sun_position(month, day, time.hour, time.solar, year, site);
            (s.alt, s.az, Some(s.solar_time))
        }
    }
}

/// Polynomial fits of the normalisation (clear, intermediate).
const NORM_CLEAR: [f64; 5] = [2.766521, 0.547665, -0.369832, 0.009237, 0.059229];
const NORM_INTER: [f64; 5] = [3.5556, -2.7152, -1.3081, 1.0660, 0.60227];

/// The F2 factor (0 for overcast and uniform skies) and the normalisation (the ratio of
/// horizontal diffuse illuminance to π × zenith luminance) of a sky at solar altitude
/// `alt`.
pub fn f2_norm(sky: SkyType, alt: f64) -> (f64, f64) {
    let sz = alt.sin();
    let poly = |c: &[f64; 5], x: f64| c.iter().rev().fold(0.0, |acc, k| acc * x + k);
    let x = (alt - FRAC_PI_4) / FRAC_PI_4;
    let zen_angle = FRAC_PI_2 - alt;
    match sky {
        SkyType::Uniform => (0.0, 1.0),
        SkyType::Overcast => (0.0, 0.777778),
        SkyType::Clear => {
            let f2 = 0.274 * (0.91 + 10.0 * (-3.0 * zen_angle).exp() + 0.45 * sz * sz);
            (f2, poly(&NORM_CLEAR, x) / f2 / PI)
        }
        SkyType::Intermediate => {
            let f2 = (2.739 + 0.9891 * (0.3119 + 2.6 * alt).sin())
                * (-zen_angle * (0.4441 + 1.48 * alt)).exp();
            (f2, poly(&NORM_INTER, x) / f2 / PI)
        }
    }
}

/// What a sky evaluates to (before rounding).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SkyValues {
    pub zenith: f64,
    pub ground: f64,
    /// Clear/intermediate F2 factor (skybright.cal's A4).
    pub f2: f64,
    /// Sun radiance when a sun is emitted.
    pub sun: Option<f64>,
    pub dir: [f64; 3],
}

impl SkyArgs {
    /// Compute the sky.
    pub fn values(&self) -> SkyValues {
        let (mut alt, az, _) = sun_alt_az(&self.sun, &self.site, self.year);
        let cie = matches!(self.sky, SkyType::Clear | SkyType::Intermediate);
        if cie && alt > 87.0 * DEG {
            alt = 87.0 * DEG;
        }
        let sz = alt.sin();
        let (f2, norm) = f2_norm(self.sky, alt);
        let zenith = match self.zenith {
            Some(Given::Radiance(z)) => z,
            Some(Given::Irradiance(e)) => e / (PI * norm),
            None => {
                let over = 8.6 * sz + 0.123;
                let clear = (1.376 * self.turbidity - 1.81) * alt.tan() + 0.38;
                let z = match self.sky {
                    SkyType::Overcast | SkyType::Uniform => over,
                    SkyType::Clear => clear,
                    SkyType::Intermediate => 0.5 * (over + clear),
                };
                z.max(0.0) * 1000.0 / SKY_EFFICACY
            }
        };
        // The sun's radiance counts in the ground's brightness whenever the sky is clear or
        // intermediate with the sun above the horizon, even when the sun itself is not
        // emitted (`-s`, `-i`), as in real gensky.
        let sun_l = if cie && alt > 0.0 {
            let l = match self.solar {
                Some(Given::Radiance(l)) => l,
                Some(Given::Irradiance(e)) => e / (5.98e-5 * sz),
                None => {
                    let l = 1.5e9 / 208.0 * (1.147 - 0.147 / sz.max(0.16));
                    if self.sky == SkyType::Intermediate {
                        l * 0.15
                    } else {
                        l
                    }
                }
            };
            (l > 0.0).then_some(l)
        } else {
            None
        };
        let sun = sun_l.filter(|_| self.with_sun);
        let sun_ground = sun_l.map_or(0.0, |l| 6e-5 / PI * l * sz);
        SkyValues {
            zenith,
            ground: (zenith * norm + sun_ground) * self.ground_refl,
            f2,
            sun,
            dir: solar::sun_direction(alt, az),
        }
    }

    /// The primitives, as real gensky prints them.
    pub fn generate(&self, loc: &Location) -> Vec<Primitive> {
        let v = self.values();
        let dir = v.dir.map(f6);
        let mut out = Vec::new();
        if let Some(l) = v.sun {
            out.extend(sun_primitives(e3(l), dir, 0.5, loc));
        }
        let mut rargs = vec![self.sky as i32 as f64, e3(v.zenith), e3(v.ground)];
        if matches!(self.sky, SkyType::Clear | SkyType::Intermediate) {
            rargs.push(e3(v.f2));
            rargs.extend(dir);
        }
        out.push(Primitive {
            modifier: "void".into(),
            ptype: "brightfunc".into(),
            name: "skyfunc".into(),
            sargs: vec!["skybr".into(), "skybright.cal".into()],
            iargs: Vec::new(),
            rargs,
            loc: loc.clone(),
        });
        out
    }
}

/// `void light solar 0 0 3 L L L` and `solar source sun 0 0 4 dx dy dz size`.
pub(crate) fn sun_primitives(l: f64, dir: [f64; 3], size: f64, loc: &Location) -> [Primitive; 2] {
    [
        super::prim("void", "light", "solar".into(), vec![l; 3], loc),
        super::prim(
            "solar",
            "source",
            "sun".into(),
            vec![dir[0], dir[1], dir[2], size],
            loc,
        ),
    ]
}

/// Parse and generate in one step.
pub fn gensky(args: &[String], cx: &GenContext) -> Result<Vec<Primitive>, ArgError> {
    Ok(parse_gensky_args(args)?.generate(cx.loc))
}
