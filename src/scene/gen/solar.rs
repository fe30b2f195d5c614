//! Sun position from a date, a time and a site, as `gensky` and `gendaylit` compute it
//! (Radiance's sun.c formulas, from the reference: a yearly sine for the declination and
//! the equation of time, or Michalsky's (1988) algorithm when a year is given), and the
//! date/time arguments of those programs.

use std::f64::consts::PI;

use super::ArgError;

/// Radians per degree.
pub const DEG: f64 = PI / 180.0;

/// Default site: latitude 0.66 rad north, longitude 2.13 rad west, meridian 120° west.
pub const DEFAULT_LAT: f64 = 0.66;
/// Default longitude (radians west).
pub const DEFAULT_LON: f64 = 2.13;
/// Default standard meridian (radians west).
pub const DEFAULT_MER: f64 = 120.0 * DEG;

/// Time zones gensky knows (name, hours west of Greenwich × 15 = degrees west); the first
/// match of a name wins.
const ZONES: [(&str, f64); 30] = [
    ("YST", 135.0),
    ("YDT", 120.0),
    ("PST", 120.0),
    ("PDT", 105.0),
    ("MST", 105.0),
    ("MDT", 90.0),
    ("CST", 90.0),
    ("CDT", 75.0),
    ("EST", 75.0),
    ("EDT", 60.0),
    ("AST", 60.0),
    ("ADT", 45.0),
    ("NST", 52.5),
    ("NDT", 37.5),
    ("GMT", 0.0),
    ("BST", -15.0),
    ("CET", -15.0),
    ("CEST", -30.0),
    ("EET", -30.0),
    ("EEST", -45.0),
    ("AST", -45.0),
    ("ADT", -60.0),
    ("GST", -60.0),
    ("GDT", -75.0),
    ("IST", -82.5),
    ("IDT", -97.5),
    ("JST", -135.0),
    ("NDT", -150.0),
    ("NZST", -180.0),
    ("NZDT", -195.0),
];

/// Day of the (non-leap) year before each month.
const MONTH_START: [u32; 12] = [0, 31, 59, 90, 120, 151, 181, 212, 243, 273, 304, 334];

/// A time of day as gensky reads it: `[+]H[.h][:MM][ZONE]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeOfDay {
    /// Hours.
    pub hour: f64,
    /// Local solar time (`+`).
    pub solar: bool,
    /// The meridian of a zone suffix (radians west).
    pub zone_meridian: Option<f64>,
}

/// Parse gensky's time argument.
pub fn parse_time(prog: &str, w: &str) -> Result<TimeOfDay, ArgError> {
    let bad = || ArgError::Bad(format!("{prog}: bad time format: {w}"));
    let (solar, rest) = match w.strip_prefix('+') {
        Some(r) => (true, r),
        None => (false, w),
    };
    let digits = |s: &str| s.bytes().take_while(u8::is_ascii_digit).count();
    let mut i = digits(rest);
    if rest[i..].starts_with('.') {
        i += 1 + digits(&rest[i + 1..]);
    }
    let hpart = &rest[..i];
    if hpart.is_empty() || hpart == "." {
        return Err(bad());
    }
    let mut hour: f64 = hpart.parse().map_err(|_| bad())?;
    let mut tail = &rest[i..];
    if let Some(t) = tail.strip_prefix(':') {
        if hpart.contains('.') {
            return Err(bad());
        }
        let n = digits(t);
        if n > 0 {
            hour += t[..n].parse::<f64>().map_err(|_| bad())? / 60.0;
        }
        tail = &t[n..];
    }
    let zone_meridian = if tail.is_empty() {
        None
    } else {
        if solar || !tail.bytes().all(|c| c.is_ascii_alphabetic()) {
            return Err(bad());
        }
        let z = ZONES
            .iter()
            .find(|(n, _)| n.eq_ignore_ascii_case(tail))
            .ok_or_else(|| ArgError::Bad(format!("{prog}: unknown time zone: {tail}")))?;
        Some(z.1 * DEG)
    };
    Ok(TimeOfDay {
        hour,
        solar,
        zone_meridian,
    })
}

/// Month (1..12) and day (1..31) arguments.
pub fn parse_date(prog: &str, month: &str, day: &str) -> Result<(u32, u32), ArgError> {
    let int = |what: &str, w: &str| -> Result<u32, ArgError> {
        w.parse::<u32>()
            .map_err(|_| ArgError::Bad(format!("{prog}: bad {what} '{w}'")))
    };
    let m = int("month", month)?;
    if !(1..=12).contains(&m) {
        return Err(ArgError::Bad(format!("{prog}: bad month '{month}'")));
    }
    let d = int("day", day)?;
    if !(1..=31).contains(&d) {
        return Err(ArgError::Bad(format!("{prog}: bad day '{day}'")));
    }
    Ok((m, d))
}

/// Day of the year (non-leap), 1 for January 1.
pub fn julian_day(month: u32, day: u32) -> u32 {
    MONTH_START[(month - 1) as usize] + day
}

/// A site: latitude (north), longitude and standard meridian (west), radians.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Site {
    pub lat: f64,
    pub lon: f64,
    pub mer: f64,
}

impl Default for Site {
    fn default() -> Self {
        Site {
            lat: DEFAULT_LAT,
            lon: DEFAULT_LON,
            mer: DEFAULT_MER,
        }
    }
}

/// The sun seen from a site at a date and time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SunPosition {
    /// Local solar time (hours).
    pub solar_time: f64,
    /// Altitude and azimuth (radians; azimuth west of south).
    pub alt: f64,
    pub az: f64,
    /// Declination (radians).
    pub dec: f64,
}

/// Declination (radians) on day `jd` of the year.
pub fn declination(jd: f64) -> f64 {
    0.4093 * (2.0 * PI * (jd - 81.0) / 365.0).sin()
}

/// Local solar time from standard time.
pub fn solar_time(jd: f64, hour: f64, site: &Site) -> f64 {
    hour + 0.170 * (4.0 * PI * (jd - 80.0) / 373.0).sin()
        - 0.129 * (2.0 * PI * (jd - 8.0) / 355.0).sin()
        + 12.0 * (site.mer - site.lon) / PI
}

/// Altitude and azimuth from the declination and the solar time.
pub fn alt_az(lat: f64, dec: f64, st: f64) -> (f64, f64) {
    let h = PI * st / 12.0;
    let alt = (lat.sin() * dec.sin() - lat.cos() * dec.cos() * h.cos()).asin();
    let az = -(dec.cos() * h.sin()).atan2(-lat.cos() * dec.sin() - lat.sin() * dec.cos() * h.cos());
    (alt, az)
}

/// The sun at `month`/`day`, `hour` (solar time if `solar`), with the default model or
/// Michalsky's when `year` is given.
pub fn sun_position(
    month: u32,
    day: u32,
    hour: f64,
    solar: bool,
    year: Option<i64>,
    site: &Site,
) -> SunPosition {
    let jd = julian_day(month, day) as f64;
    let (dec, st) = match year {
        None => {
            let st = if solar {
                hour
            } else {
                solar_time(jd, hour, site)
            };
            (declination(jd), st)
        }
        Some(y) => {
            let leap = (month > 2 && y % 4 == 0) as i64 as f64;
            let n = jd
                + leap
                + 365.0 * (y - 1949) as f64
                + ((y - 1949) / 4) as f64
                + (hour + 12.0 * site.mer / PI) / 24.0
                - 18628.5;
            let l = (280.460 + 0.9856474 * n).rem_euclid(360.0) * DEG;
            let g = (357.528 + 0.9856003 * n).rem_euclid(360.0) * DEG;
            let lambda = l + 1.915 * DEG * g.sin() + 0.020 * DEG * (2.0 * g).sin();
            let eps = (23.439 - 4e-7 * n) * DEG;
            let dec = (eps.sin() * lambda.sin()).asin();
            let st = if solar {
                hour
            } else {
                let ra = (lambda.sin() * eps.cos()).atan2(lambda.cos());
                let gmst = 6.697375 + 0.0657098242 * n + 24.0 * (n - n.floor()) + 12.0;
                (gmst - 12.0 * site.lon / PI - 12.0 * ra / PI + 12.0).rem_euclid(24.0)
            };
            (dec, st)
        }
    };
    let (alt, az) = alt_az(site.lat, dec, st);
    SunPosition {
        solar_time: st,
        alt,
        az,
        dec,
    }
}

/// Direction toward the sun (x east, y north, z up).
pub fn sun_direction(alt: f64, az: f64) -> [f64; 3] {
    [-az.sin() * alt.cos(), -az.cos() * alt.cos(), alt.sin()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reference_positions() {
        let s = sun_position(3, 21, 12.0, false, None, &Site::default());
        let d = sun_direction(s.alt, s.az);
        assert!((d[0] - 0.067850).abs() < 5e-7 && (d[2] - 0.783832).abs() < 5e-7);
        let s = sun_position(3, 21, 12.0, false, Some(2020), &Site::default());
        assert!((s.solar_time - 11.75).abs() < 0.005, "{s:?}");
        assert!((s.alt / DEG - 52.7).abs() < 0.05, "{s:?}");
    }

    #[test]
    fn times() {
        assert_eq!(parse_time("g", "12:30").unwrap().hour, 12.5);
        assert_eq!(parse_time("g", "12:").unwrap().hour, 12.0);
        assert!(parse_time("g", "+12:30").unwrap().solar);
        assert_eq!(
            parse_time("g", "12:30est").unwrap().zone_meridian,
            Some(75.0 * DEG)
        );
        for bad in [
            "12.5:30", "+12PST", "12:30.5", "-3", "", "+", "12:30XYZ", "1e1",
        ] {
            assert!(parse_time("g", bad).is_err(), "{bad}");
        }
    }
}
