//! Radiance views: the `-v*` options, view files, validation (`setview`), the pixel → ray
//! mapping (`viewray`), its inverse (`viewloc`), `normaspect` and `cropview`.
//!
//! Image coordinates are `x, y` in `[0, 1]` measured from the **lower left** of the image, as
//! in Radiance. Shift (`-vs`) and lift (`-vl`) move the image window in units of the image
//! size.

use std::path::Path;

use glam::DVec3;

use crate::options::words::{parse_f64, OptError};
use crate::FTINY;

/// A Radiance view projection (`-vt?`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum ViewType {
    /// `-vtv`: perspective.
    Perspective,
    /// `-vtl`: parallel (orthographic); sizes are in world units.
    Parallel,
    /// `-vta`: angular fisheye (equidistant), up to 360°.
    Angular,
    /// `-vth`: hemispherical fisheye (orthographic projection of the hemisphere), up to 180°.
    Hemispherical,
    /// `-vts`: planisphere (stereographic), below 360°.
    Planisphere,
    /// `-vtc`: cylindrical panorama (angular horizontally, perspective vertically).
    Cylindrical,
}

impl ViewType {
    /// The option letter Radiance uses (`v l a h s c`).
    pub fn letter(self) -> char {
        match self {
            ViewType::Perspective => 'v',
            ViewType::Parallel => 'l',
            ViewType::Angular => 'a',
            ViewType::Hemispherical => 'h',
            ViewType::Planisphere => 's',
            ViewType::Cylindrical => 'c',
        }
    }

    /// The view type for an option letter, if valid.
    pub fn from_letter(c: char) -> Option<ViewType> {
        Some(match c {
            'v' => ViewType::Perspective,
            'l' => ViewType::Parallel,
            'a' => ViewType::Angular,
            'h' => ViewType::Hemispherical,
            's' => ViewType::Planisphere,
            'c' => ViewType::Cylindrical,
            _ => return None,
        })
    }

    /// The name rpict prints in `-defaults` (`perspective`, `parallel`, ...).
    pub fn name(self) -> &'static str {
        match self {
            ViewType::Perspective => "perspective",
            ViewType::Parallel => "parallel",
            ViewType::Angular => "angular",
            ViewType::Hemispherical => "hemispherical",
            ViewType::Planisphere => "planisphere",
            ViewType::Cylindrical => "cylindrical",
        }
    }
}

/// Serialise a `DVec3` as `[x, y, z]` (glam is built without its serde feature).
mod dvec3_serde {
    use glam::DVec3;
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub fn serialize<S: Serializer>(v: &DVec3, s: S) -> Result<S::Ok, S::Error> {
        [v.x, v.y, v.z].serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<DVec3, D::Error> {
        let a = <[f64; 3]>::deserialize(d)?;
        Ok(DVec3::from_array(a))
    }
}

/// A Radiance view, exactly as the `-v*` options describe it (not yet validated).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct View {
    /// Projection type (`-vt?`).
    pub vtype: ViewType,
    /// View point (`-vp`).
    #[serde(with = "dvec3_serde")]
    pub vp: DVec3,
    /// View direction (`-vd`); its length is the focal distance used by `-pd`.
    #[serde(with = "dvec3_serde")]
    pub vd: DVec3,
    /// View up vector (`-vu`).
    #[serde(with = "dvec3_serde")]
    pub vu: DVec3,
    /// Horizontal size (`-vh`): degrees, or world units for parallel views.
    pub vh: f64,
    /// Vertical size (`-vv`): degrees, or world units for parallel views.
    pub vv: f64,
    /// Fore clipping distance (`-vo`).
    pub vo: f64,
    /// Aft clipping distance (`-va`); 0 means none.
    pub va: f64,
    /// Horizontal shift in image widths (`-vs`).
    pub vs: f64,
    /// Vertical lift in image heights (`-vl`).
    pub vl: f64,
}

impl Default for View {
    /// rpict's default view: `-vtv -vp 0 0 0 -vd 0 1 0 -vu 0 0 1 -vh 45 -vv 45 -vo 0 -va 0 -vs 0 -vl 0`.
    fn default() -> Self {
        View {
            vtype: ViewType::Perspective,
            vp: DVec3::ZERO,
            vd: DVec3::Y,
            vu: DVec3::Z,
            vh: 45.0,
            vv: 45.0,
            vo: 0.0,
            va: 0.0,
            vs: 0.0,
            vl: 0.0,
        }
    }
}

/// Format a number like C's `%.6g` (the form Radiance uses in `VIEW=` lines).
pub fn fmt_g6(v: f64) -> String {
    fmt_g(v, 6)
}

/// Format like C's `%.{prec}g`.
pub(crate) fn fmt_g(v: f64, prec: usize) -> String {
    if !v.is_finite() {
        return format!("{v}");
    }
    if v == 0.0 {
        return "0".to_string();
    }
    let prec = prec.max(1);
    // Exponent after rounding to `prec` significant digits.
    let e_str = format!("{:.*e}", prec - 1, v);
    let (mant, exp) = match e_str.split_once('e') {
        Some(p) => p,
        None => return e_str,
    };
    let exp: i32 = exp.parse().unwrap_or(0);
    if exp < -4 || exp >= prec as i32 {
        let mant = strip_zeros(mant);
        let sign = if exp < 0 { '-' } else { '+' };
        format!("{mant}e{sign}{:02}", exp.abs())
    } else {
        let decimals = (prec as i32 - 1 - exp).max(0) as usize;
        strip_zeros(&format!("{:.*}", decimals, v)).to_string()
    }
}

fn strip_zeros(s: &str) -> &str {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.')
    } else {
        s
    }
}

fn take_numbers(words: &[String], n: usize) -> Result<Vec<f64>, OptError> {
    let opt = &words[0];
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        match words.get(i + 1) {
            None => {
                return Err(OptError::MissingArgument {
                    option: opt.clone(),
                    expected: count_text(n),
                    got: i,
                })
            }
            Some(w) => out.push(parse_f64(opt, w, n)?),
        }
    }
    Ok(out)
}

fn count_text(n: usize) -> String {
    if n == 1 {
        "1 number".to_string()
    } else {
        format!("{n} numbers")
    }
}

impl View {
    /// Try to apply one view option at `words[0]` (e.g. `-vp` with 3 following numbers,
    /// `-vtv`, `-vh` ...). Returns `Ok(Some(n_words_consumed))` if it was a view option,
    /// `Ok(None)` if it is not a view option, and an error on bad or missing numbers.
    /// `-vf` is not handled here (it needs file access; see [`read_view_file`]).
    pub fn apply_option(&mut self, words: &[String]) -> Result<Option<usize>, OptError> {
        let Some(opt) = words.first() else {
            return Ok(None);
        };
        let Some(rest) = opt.strip_prefix("-v") else {
            return Ok(None);
        };
        let mut chars = rest.chars();
        let c1 = chars.next();
        if c1 == Some('t') {
            let tail: String = chars.collect();
            let mut tc = tail.chars();
            let (Some(letter), None) = (tc.next(), tc.next()) else {
                return Err(OptError::BadValue {
                    option: opt.clone(),
                    reason: "expected a view type -vtv, -vtl, -vta, -vth, -vts or -vtc".into(),
                });
            };
            return match ViewType::from_letter(letter) {
                Some(t) => {
                    self.vtype = t;
                    Ok(Some(1))
                }
                None => Err(OptError::BadValue {
                    option: opt.clone(),
                    reason: format!("unknown view type '{letter}' (expected one of v l a h s c)"),
                }),
            };
        }
        if chars.next().is_some() {
            return Ok(None);
        }
        match c1 {
            Some('p') | Some('d') | Some('u') => {
                let n = take_numbers(words, 3)?;
                let v = DVec3::new(n[0], n[1], n[2]);
                match c1 {
                    Some('p') => self.vp = v,
                    Some('d') => self.vd = v,
                    _ => self.vu = v,
                }
                Ok(Some(4))
            }
            Some(c @ ('h' | 'v' | 'o' | 'a' | 's' | 'l')) => {
                let n = take_numbers(words, 1)?[0];
                match c {
                    'h' => self.vh = n,
                    'v' => self.vv = n,
                    'o' => self.vo = n,
                    'a' => self.va = n,
                    's' => self.vs = n,
                    _ => self.vl = n,
                }
                Ok(Some(2))
            }
            _ => Ok(None),
        }
    }

    /// Parse all view options in a line of words (e.g. the text after `VIEW=`, or an
    /// `rview ...`/`rpict ...` line), skipping non-view words as Radiance does for view files.
    pub fn apply_words(&mut self, words: &[String]) -> Result<(), OptError> {
        let mut i = 0;
        while i < words.len() {
            match self.apply_option(&words[i..])? {
                Some(n) => i += n,
                None => i += 1,
            }
        }
        Ok(())
    }

    /// Radiance's text form, as in `VIEW=` lines:
    /// `-vtv -vp 1 2 3 -vd ... -vu ... -vh 45 -vv 45 -vo 0 -va 0 -vs 0 -vl 0` (numbers as `%.6g`).
    pub fn to_radiance_string(&self) -> String {
        let g = fmt_g6;
        format!(
            "-vt{} -vp {} {} {} -vd {} {} {} -vu {} {} {} -vh {} -vv {} -vo {} -va {} -vs {} -vl {}",
            self.vtype.letter(),
            g(self.vp.x),
            g(self.vp.y),
            g(self.vp.z),
            g(self.vd.x),
            g(self.vd.y),
            g(self.vd.z),
            g(self.vu.x),
            g(self.vu.y),
            g(self.vu.z),
            g(self.vh),
            g(self.vv),
            g(self.vo),
            g(self.va),
            g(self.vs),
            g(self.vl)
        )
    }

    /// The view options as exact words (shortest round-trip number forms), for command lines
    /// that must parse back to the identical view.
    pub fn to_words(&self) -> Vec<String> {
        let mut w = vec![format!("-vt{}", self.vtype.letter())];
        for (name, v) in [("-vp", self.vp), ("-vd", self.vd), ("-vu", self.vu)] {
            w.push(name.to_string());
            w.extend([v.x, v.y, v.z].iter().map(|c| format!("{c}")));
        }
        for (name, v) in [
            ("-vh", self.vh),
            ("-vv", self.vv),
            ("-vo", self.vo),
            ("-va", self.va),
            ("-vs", self.vs),
            ("-vl", self.vl),
        ] {
            w.push(name.to_string());
            w.push(format!("{v}"));
        }
        w
    }

    /// Validate and precompute (Radiance's `setview`): errors for a zero `-vd`, `-vu` parallel
    /// to `-vd`, sizes out of range for the view type, and bad clipping distances.
    pub fn frame(&self) -> Result<ViewFrame, OptError> {
        let bad = |m: &str| Err(OptError::InvalidView(m.to_string()));
        let all = [
            self.vp.x, self.vp.y, self.vp.z, self.vd.x, self.vd.y, self.vd.z, self.vu.x, self.vu.y,
            self.vu.z, self.vh, self.vv, self.vo, self.va, self.vs, self.vl,
        ];
        if all.iter().any(|v| !v.is_finite()) {
            return bad("non-finite number in view");
        }
        if self.vo < -FTINY || self.va < -FTINY || (self.va > FTINY && self.va <= self.vo) {
            return bad("illegal fore/aft clipping plane");
        }
        let vdist = self.vd.length();
        if vdist <= FTINY {
            return bad("zero view direction");
        }
        let vdir = self.vd / vdist;
        let h = vdir.cross(self.vu);
        if h.length() <= FTINY * self.vu.length().max(1.0) || self.vu.length() <= FTINY {
            return bad("view up parallel to view direction");
        }
        let hunit = h.normalize();
        let vunit = hunit.cross(vdir).normalize();
        if self.vh <= FTINY {
            return bad("illegal horizontal view size");
        }
        if self.vv <= FTINY {
            return bad("illegal vertical view size");
        }
        let rad = std::f64::consts::PI / 180.0;
        let persp = |deg: f64| 2.0 * (deg * rad / 2.0).tan();
        let (hn, vn, hmax_ok, vmax_ok) = match self.vtype {
            ViewType::Perspective => (
                persp(self.vh),
                persp(self.vv),
                self.vh < 180.0,
                self.vv < 180.0,
            ),
            ViewType::Parallel => (self.vh, self.vv, true, true),
            ViewType::Cylindrical => (
                self.vh * rad,
                persp(self.vv),
                self.vh <= 360.0,
                self.vv < 180.0,
            ),
            ViewType::Angular => (
                self.vh * rad,
                self.vv * rad,
                self.vh <= 360.0,
                self.vv <= 360.0,
            ),
            ViewType::Hemispherical => (
                2.0 * (self.vh * rad / 2.0).sin(),
                2.0 * (self.vv * rad / 2.0).sin(),
                self.vh <= 180.0,
                self.vv <= 180.0,
            ),
            ViewType::Planisphere => {
                let f = |deg: f64| {
                    let a = deg * rad / 2.0;
                    2.0 * a.sin() / (1.0 + a.cos())
                };
                (f(self.vh), f(self.vv), self.vh < 360.0, self.vv < 360.0)
            }
        };
        if !hmax_ok {
            return bad("illegal horizontal view size");
        }
        if !vmax_ok {
            return bad("illegal vertical view size");
        }
        Ok(ViewFrame {
            view: self.clone(),
            vdir,
            vdist,
            hunit,
            vunit,
            hn,
            vn,
            hvec: hunit * hn,
            vvec: vunit * vn,
            hn2: hn * hn,
            vn2: vn * vn,
        })
    }

    /// rpiece's `cropview`: the view of the sub-rectangle `[x0,x1]×[y0,y1]` (fractions of the
    /// image, from the lower left). Rays of the cropped view at `(x', y')` equal rays of this
    /// view at `(x0 + x'·(x1−x0), y0 + y'·(y1−y0))`.
    pub fn crop(&self, x0: f64, y0: f64, x1: f64, y1: f64) -> Result<View, OptError> {
        let ok = |a: f64, b: f64| {
            a.is_finite() && b.is_finite() && a >= 0.0 && b <= 1.0 && b - a > FTINY
        };
        if !ok(x0, x1) || !ok(y0, y1) {
            return Err(OptError::InvalidView(format!(
                "bad crop rectangle [{x0}, {x1}] x [{y0}, {y1}]"
            )));
        }
        // Validate the original first.
        self.frame()?;
        let dx = x1 - x0;
        let dy = y1 - y0;
        let mut v = self.clone();
        v.vs = ((x0 + x1) / 2.0 - 0.5 + self.vs) / dx;
        v.vl = ((y0 + y1) / 2.0 - 0.5 + self.vl) / dy;
        let rad = std::f64::consts::PI / 180.0;
        let persp = |deg: f64, d: f64| 2.0 * (d * (deg * rad / 2.0).tan()).atan() / rad;
        let hemi = |deg: f64, d: f64| 2.0 * (d * (deg * rad / 2.0).sin()).asin() / rad;
        let stereo = |deg: f64, d: f64| 4.0 * (d * (deg * rad / 4.0).tan()).atan() / rad;
        match self.vtype {
            ViewType::Perspective => {
                v.vh = persp(self.vh, dx);
                v.vv = persp(self.vv, dy);
            }
            ViewType::Parallel | ViewType::Angular => {
                v.vh = self.vh * dx;
                v.vv = self.vv * dy;
            }
            ViewType::Cylindrical => {
                v.vh = self.vh * dx;
                v.vv = persp(self.vv, dy);
            }
            ViewType::Hemispherical => {
                v.vh = hemi(self.vh, dx);
                v.vv = hemi(self.vv, dy);
            }
            ViewType::Planisphere => {
                v.vh = stereo(self.vh, dx);
                v.vv = stereo(self.vv, dy);
            }
        }
        Ok(v)
    }
}

/// A validated view ready for ray generation.
#[derive(Clone, Debug)]
pub struct ViewFrame {
    /// The view this frame was made from.
    pub view: View,
    /// Unit view direction.
    pub vdir: DVec3,
    /// Focal distance `|vd|`.
    pub vdist: f64,
    /// Unit right vector (`vdir × vu`, normalised).
    pub hunit: DVec3,
    /// Unit up vector in the image plane (`hunit × vdir`).
    pub vunit: DVec3,
    /// Image-plane width (before squaring): `2·tan(vh/2)`, `vh` in radians, etc. per type.
    pub hn: f64,
    /// Image-plane height (before squaring).
    pub vn: f64,
    /// `hunit · hn`.
    pub hvec: DVec3,
    /// `vunit · vn`.
    pub vvec: DVec3,
    /// `hn²`.
    pub hn2: f64,
    /// `vn²`.
    pub vn2: f64,
}

impl ViewFrame {
    /// Radiance's `viewray`: `x, y` in `[0,1]` from the LOWER-LEFT of the image (shift and
    /// lift applied). Returns (origin, unit direction, max distance from the origin: the aft
    /// clip, or `f64::INFINITY` when `-va 0`), or `None` outside a fisheye circle.
    ///
    /// Clipping follows Radiance: for perspective views the fore/aft clips are planes
    /// perpendicular to the view direction, for cylindrical views cylinders around the view
    /// axis, for fisheye types spheres, for parallel views planes.
    pub fn ray(&self, x: f64, y: f64) -> Option<(DVec3, DVec3, f64)> {
        let v = &self.view;
        let x = x + v.vs - 0.5;
        let y = y + v.vl - 0.5;
        if !x.is_finite() || !y.is_finite() {
            return None;
        }
        let aft = |len: f64| {
            if v.va > FTINY {
                (v.va - v.vo) * len
            } else {
                f64::INFINITY
            }
        };
        if v.vtype == ViewType::Parallel {
            let orig = v.vp + v.vo * self.vdir + x * self.hvec + y * self.vvec;
            return Some((orig, self.vdir, aft(1.0)));
        }
        let d = match v.vtype {
            ViewType::Perspective => self.vdir + x * self.hvec + y * self.vvec,
            ViewType::Cylindrical => {
                let a = x * self.hn;
                a.cos() * self.vdir + a.sin() * self.hunit + y * self.vvec
            }
            ViewType::Angular => {
                let u = x * self.hn;
                let w = y * self.vn;
                let r = (u * u + w * w).sqrt();
                if r > std::f64::consts::PI {
                    return None;
                }
                let s = if r <= FTINY { 1.0 } else { r.sin() / r };
                r.cos() * self.vdir + s * (u * self.hunit + w * self.vunit)
            }
            ViewType::Hemispherical => {
                let u = x * self.hn;
                let w = y * self.vn;
                let r2 = u * u + w * w;
                if r2 > 1.0 {
                    return None;
                }
                (1.0 - r2).sqrt() * self.vdir + u * self.hunit + w * self.vunit
            }
            ViewType::Planisphere => {
                let u = x * self.hn;
                let w = y * self.vn;
                let r2 = u * u + w * w;
                ((1.0 - r2) * self.vdir + 2.0 * u * self.hunit + 2.0 * w * self.vunit) / (1.0 + r2)
            }
            ViewType::Parallel => self.vdir,
        };
        let len = d.length();
        if len <= 0.0 || !len.is_finite() {
            return None;
        }
        let orig = v.vp + v.vo * d;
        Some((orig, d / len, aft(len)))
    }

    /// Inverse of [`ViewFrame::ray`] (Radiance's `viewloc`): image position (`x, y` in
    /// `[0,1]` from the lower left when inside the image) and distance from the ray origin
    /// (negative before the fore clip) of a world point, or `None` when the point cannot be
    /// seen in this view type (behind a perspective/hemispherical view, on the view axis of
    /// a cylinder, at the view point...).
    pub fn locate(&self, p: DVec3) -> Option<(f64, f64, f64)> {
        let v = &self.view;
        let disp = p - v.vp;
        let dist = disp.length();
        let fin = |x: f64, y: f64, t: f64| {
            let x = x + 0.5 - v.vs;
            let y = y + 0.5 - v.vl;
            (x.is_finite() && y.is_finite() && t.is_finite()).then_some((x, y, t))
        };
        match v.vtype {
            ViewType::Parallel => {
                let x = disp.dot(self.hvec) / self.hn2;
                let y = disp.dot(self.vvec) / self.vn2;
                fin(x, y, disp.dot(self.vdir) - v.vo)
            }
            ViewType::Perspective => {
                let dz = disp.dot(self.vdir);
                if dz <= FTINY * dist.max(1.0) {
                    return None;
                }
                let d = disp / dz;
                let x = d.dot(self.hvec) / self.hn2;
                let y = d.dot(self.vvec) / self.vn2;
                fin(x, y, dist - v.vo * d.length())
            }
            ViewType::Cylindrical => {
                let a = disp.dot(self.vdir);
                let b = disp.dot(self.hunit);
                let rh = (a * a + b * b).sqrt();
                if rh <= FTINY * dist.max(1.0) {
                    return None;
                }
                let ang = b.atan2(a);
                let d = disp / rh;
                let x = ang / self.hn;
                let y = d.dot(self.vvec) / self.vn2;
                fin(x, y, dist - v.vo * d.length())
            }
            ViewType::Angular | ViewType::Hemispherical | ViewType::Planisphere => {
                if dist <= FTINY {
                    return None;
                }
                let dir = disp / dist;
                let c = dir.dot(self.vdir).clamp(-1.0, 1.0);
                let u = dir.dot(self.hunit);
                let w = dir.dot(self.vunit);
                let (pu, pw) = match v.vtype {
                    ViewType::Angular => {
                        let s = (u * u + w * w).sqrt();
                        let theta = c.acos();
                        if s <= 1e-12 {
                            if c < 0.0 {
                                return None; // straight behind: any point on the circle
                            }
                            (0.0, 0.0)
                        } else {
                            (theta * u / s, theta * w / s)
                        }
                    }
                    ViewType::Hemispherical => {
                        if c < 0.0 {
                            return None;
                        }
                        (u, w)
                    }
                    _ => {
                        if 1.0 + c <= 1e-12 {
                            return None;
                        }
                        (u / (1.0 + c), w / (1.0 + c))
                    }
                };
                fin(pu / self.hn, pw / self.vn, dist - v.vo)
            }
        }
    }

    /// Image-plane height/width ratio (Radiance's `viewaspect`, `sqrt(vn2/hn2)`).
    pub fn aspect(&self) -> f64 {
        (self.vn2 / self.hn2).sqrt()
    }
}

/// Radiance's `normaspect`: reduce `x` or `y` (maxima) so that `y/x = aspect/pa` (rounded to
/// the nearest integer, as Radiance does; extreme aspects can round to 0). `pa <= 0` keeps
/// `x, y` and sets `pa` to the implied pixel aspect `aspect·x/y`.
pub fn normaspect(aspect: f64, pa: &mut f64, x: &mut usize, y: &mut usize) {
    if !aspect.is_finite() || aspect <= 0.0 {
        return;
    }
    let xf = *x as f64;
    let yf = *y as f64;
    if *pa <= FTINY {
        if *y > 0 {
            *pa = aspect * xf / yf;
        }
    } else if aspect * xf > *pa * yf {
        *x = (yf / aspect * *pa + 0.5) as usize;
    } else {
        *y = (xf * aspect / *pa + 0.5) as usize;
    }
}

/// Program names whose command lines count as view lines (besides `VIEW=`).
const VIEW_PROGRAMS: [&str; 7] = [
    "rpict", "rview", "rvu", "rpiece", "rxpiece", "pinterp", "tpict",
];

/// Split a line into words on whitespace.
fn line_words(s: &str) -> Vec<String> {
    s.split_whitespace().map(str::to_string).collect()
}

/// If `line` is a view line, the words holding its options.
fn view_line_words(line: &str) -> Option<Vec<String>> {
    let t = line.trim_start();
    if let Some(rest) = t.strip_prefix("VIEW=") {
        return Some(line_words(rest));
    }
    let first = t.split_whitespace().next()?;
    let base = first.rsplit('/').next().unwrap_or(first);
    if VIEW_PROGRAMS.contains(&base) {
        let words = line_words(t);
        return Some(words[1..].to_vec());
    }
    None
}

/// Parse one line as a view line (for `-S` sequences reading views from stdin): `Some(view)`
/// (the line's view options applied on top of `base`) if the line is a view line.
pub fn parse_view_line(line: &str, base: &View) -> Result<Option<View>, OptError> {
    match view_line_words(line) {
        None => Ok(None),
        Some(words) => {
            let mut v = base.clone();
            v.apply_words(&words)?;
            Ok(Some(v))
        }
    }
}

/// Read the views in a view file (`-vf`): lines starting with `VIEW=`, `rpict`, `rview`,
/// `rvu`, `rpiece`, `rxpiece`, `pinterp` or `tpict` (a leading directory is ignored).
/// Picture files work too: text lines are read until the blank line ending the header, and
/// the binary data after it is never parsed. The views are applied in order on top of
/// `base`. Errors (naming file:line) when no view line is found or numbers are bad.
pub fn read_view_file(path: &Path, base: &View) -> Result<View, OptError> {
    let data = std::fs::read(path).map_err(|e| OptError::Io {
        path: path.display().to_string(),
        reason: e.to_string(),
    })?;
    let is_picture = data.starts_with(b"#?");
    let mut view = base.clone();
    let mut found = false;
    for (i, raw) in data.split(|&b| b == b'\n').enumerate() {
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        if is_picture && raw.is_empty() {
            break; // end of the picture header
        }
        let line = String::from_utf8_lossy(raw);
        match parse_view_line(&line, &view) {
            Ok(Some(v)) => {
                view = v;
                found = true;
            }
            Ok(None) => {}
            Err(e) => {
                return Err(OptError::File {
                    path: path.display().to_string(),
                    line: i + 1,
                    reason: e.to_string(),
                })
            }
        }
    }
    if !found {
        return Err(OptError::NoView(path.display().to_string()));
    }
    Ok(view)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn g6_formats_like_c() {
        assert_eq!(fmt_g6(0.0), "0");
        assert_eq!(fmt_g6(45.0), "45");
        assert_eq!(fmt_g6(0.1), "0.1");
        assert_eq!(fmt_g6(-0.268328), "-0.268328");
        assert_eq!(fmt_g6(1234567.0), "1.23457e+06");
        assert_eq!(fmt_g6(0.0000123), "1.23e-05");
        assert_eq!(fmt_g6(123456.4), "123456");
        assert_eq!(fmt_g6(999999.7), "1e+06");
    }
}
