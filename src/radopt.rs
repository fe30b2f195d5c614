//! Radiance's option language: `@file` and `$VAR` expansion, the rendering parameters shared
//! by tpict and later tools (`-ab 2 -i+ ...`), and rpict's (tpict's) full command line.
//!
//! Parsing rules follow rpict: booleans toggle when bare and accept `+ 1 y Y t T` / `- 0 n N
//! f F` suffixes; numbers must be finite; options come first, scene files last.

use std::path::Path;

use crate::ambient::settings::AmbientSettings;
use crate::view::{fmt_g6, read_view_file, View};

/// Errors from option parsing, view validation and view files.
#[derive(Debug, thiserror::Error)]
pub enum OptError {
    /// An option's argument is not a valid number.
    #[error("option {option}: expected {expected}, got '{got}'")]
    BadNumber {
        /// The option, e.g. `-vp`.
        option: String,
        /// What was expected, e.g. `3 numbers`.
        expected: String,
        /// The offending word.
        got: String,
    },
    /// An option is missing some of its arguments.
    #[error(
        "option {option}: expected {expected}, got only {got} before the end of the arguments"
    )]
    MissingArgument {
        /// The option.
        option: String,
        /// What was expected.
        expected: String,
        /// How many arguments were found.
        got: usize,
    },
    /// A value that parses but is out of range or otherwise wrong.
    #[error("option {option}: {reason}")]
    BadValue {
        /// The option.
        option: String,
        /// Why the value is rejected.
        reason: String,
    },
    /// An option nobody knows.
    #[error("unknown option {0}")]
    Unknown(String),
    /// A Radiance option that tpict does not implement.
    #[error("option {option} is not supported: {reason}")]
    Unsupported {
        /// The option.
        option: String,
        /// Why, or what to do instead.
        reason: String,
    },
    /// Options and scene files out of order.
    #[error(
        "option {option} after scene file '{scene}': options must come before the scene files"
    )]
    OptionAfterScene {
        /// The misplaced option.
        option: String,
        /// The scene file before it.
        scene: String,
    },
    /// A view that `setview` rejects.
    #[error("invalid view: {0}")]
    InvalidView(String),
    /// A problem at a line of a file.
    #[error("{path}:{line}: {reason}")]
    File {
        /// File name.
        path: String,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// A view file without any view line.
    #[error("{0}: no view found")]
    NoView(String),
    /// A file that cannot be read.
    #[error("cannot read {path}: {reason}")]
    Io {
        /// File name.
        path: String,
        /// The system's reason.
        reason: String,
    },
    /// `@file` or `$VAR` expansion failure.
    #[error("argument expansion: {0}")]
    Expand(String),
}

/// Parse a finite floating-point argument of `option` (which takes `n` numbers).
pub fn parse_f64(option: &str, word: &str, n: usize) -> Result<f64, OptError> {
    match word.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && !word.trim().is_empty() => Ok(v),
        _ => Err(OptError::BadNumber {
            option: option.to_string(),
            expected: if n == 1 {
                "a number".to_string()
            } else {
                format!("{n} numbers")
            },
            got: word.to_string(),
        }),
    }
}

fn parse_int<T: std::str::FromStr>(option: &str, word: &str) -> Result<T, OptError> {
    word.trim().parse::<T>().map_err(|_| OptError::BadNumber {
        option: option.to_string(),
        expected: "an integer".to_string(),
        got: word.to_string(),
    })
}

fn arg<'a>(words: &'a [String], i: usize, expected: &str) -> Result<&'a String, OptError> {
    words.get(i).ok_or_else(|| OptError::MissingArgument {
        option: words[0].clone(),
        expected: expected.to_string(),
        got: i - 1,
    })
}

fn f1(words: &[String]) -> Result<f64, OptError> {
    parse_f64(&words[0], arg(words, 1, "a number")?, 1)
}

fn f3(words: &[String]) -> Result<[f64; 3], OptError> {
    let mut out = [0.0; 3];
    for (k, o) in out.iter_mut().enumerate() {
        *o = parse_f64(&words[0], arg(words, k + 1, "3 numbers")?, 3)?;
    }
    Ok(out)
}

fn i1<T: std::str::FromStr>(words: &[String]) -> Result<T, OptError> {
    parse_int(&words[0], arg(words, 1, "an integer")?)
}

fn range(option: &str, v: f64, lo: f64, hi: f64) -> Result<f64, OptError> {
    if v < lo || v > hi {
        let what = if hi == f64::INFINITY {
            format!("value {v} must be at least {lo}")
        } else {
            format!("value {v} out of range {lo}..{hi}")
        };
        return Err(OptError::BadValue {
            option: option.to_string(),
            reason: what,
        });
    }
    Ok(v)
}

/// Boolean option: `word` is `-name` (toggle) or `-name` plus one of `+ 1 y Y t T` (true) or
/// `- 0 n N f F` (false). Returns `None` if `word` is not this option.
pub fn bool_option(word: &str, name: &str, current: bool) -> Option<bool> {
    let rest = word.strip_prefix('-')?.strip_prefix(name)?;
    match rest {
        "" => Some(!current),
        "+" | "1" | "y" | "Y" | "t" | "T" => Some(true),
        "-" | "0" | "n" | "N" | "f" | "F" => Some(false),
        _ => None,
    }
}

/// Split text into words like Radiance's option files: whitespace separates words, double or
/// single quotes group (and are removed), `#` at the start of a word comments out the rest of
/// the line.
pub fn split_words(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut chars = text.chars().peekable();
    loop {
        while chars.peek().is_some_and(|c| c.is_whitespace()) {
            chars.next();
        }
        let Some(&c) = chars.peek() else { break };
        if c == '#' {
            for c in chars.by_ref() {
                if c == '\n' {
                    break;
                }
            }
            continue;
        }
        let mut w = String::new();
        while let Some(&c) = chars.peek() {
            if c.is_whitespace() {
                break;
            }
            chars.next();
            if c == '"' || c == '\'' {
                for q in chars.by_ref() {
                    if q == c {
                        break;
                    }
                    w.push(q);
                }
            } else {
                w.push(c);
            }
        }
        out.push(w);
    }
    out
}

/// Maximum nesting of `@file` inclusions.
const MAX_EXPAND_DEPTH: usize = 32;

/// Expand `@file` (the words of a file; quotes and `#` comments handled like Radiance's
/// option files; nested `@` allowed up to a depth limit; error naming the file if it is
/// missing) and `$VAR` words (the variable's value split into words; error if unset).
pub fn expand_args(args: &[String]) -> Result<Vec<String>, OptError> {
    let mut out = Vec::with_capacity(args.len());
    expand_into(args, 0, &mut out)?;
    Ok(out)
}

fn expand_into(args: &[String], depth: usize, out: &mut Vec<String>) -> Result<(), OptError> {
    if depth > MAX_EXPAND_DEPTH {
        return Err(OptError::Expand(format!(
            "@file nesting deeper than {MAX_EXPAND_DEPTH} (recursive inclusion?)"
        )));
    }
    for a in args {
        if let Some(file) = a.strip_prefix('@').filter(|f| !f.is_empty()) {
            let text = std::fs::read(file).map_err(|e| OptError::Io {
                path: file.to_string(),
                reason: e.to_string(),
            })?;
            let words = split_words(&String::from_utf8_lossy(&text));
            expand_into(&words, depth + 1, out)?;
        } else if let Some(var) = a.strip_prefix('$').filter(|v| !v.is_empty()) {
            match std::env::var(var) {
                Ok(val) => expand_into(&split_words(&val), depth + 1, out)?,
                Err(_) => {
                    return Err(OptError::Expand(format!(
                        "environment variable '{var}' is not set"
                    )))
                }
            }
        } else {
            out.push(a.clone());
        }
    }
    Ok(())
}

/// Rendering parameters shared by tpict, tpiece, ... (names like Radiance's; defaults are
/// rpict's, see `rpict -defaults`).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RenderParams {
    /// `-dt` direct threshold.
    pub dt: f64,
    /// `-dc` direct certainty.
    pub dc: f64,
    /// `-dj` direct jitter.
    pub dj: f64,
    /// `-ds` direct (source) subdivision size.
    pub ds: f64,
    /// `-dr` direct relays (virtual source depth).
    pub dr: i32,
    /// `-dp` direct pretest density.
    pub dp: f64,
    /// `-dv` direct (light source) visibility.
    pub dv: bool,
    /// `-ss` specular sampling.
    pub ss: f64,
    /// `-st` specular threshold.
    pub st: f64,
    /// `-lr` limit reflection (negative: Russian roulette).
    pub lr: i32,
    /// `-lw` limit weight.
    pub lw: f64,
    /// `-av` ambient value.
    pub av: [f64; 3],
    /// `-aw` ambient value weight.
    pub aw: i32,
    /// `-ab` ambient bounces.
    pub ab: i32,
    /// `-aa` ambient accuracy.
    pub aa: f64,
    /// `-ar` ambient resolution.
    pub ar: i32,
    /// `-ad` ambient divisions.
    pub ad: i32,
    /// `-as` ambient super-samples.
    pub as_: i32,
    /// `-ae`/`-aE`: modifiers excluded from the ambient calculation.
    pub ae: Vec<String>,
    /// `-ai`/`-aI`: the only modifiers included in the ambient calculation.
    pub ai: Vec<String>,
    /// `-af` ambient file.
    pub af: Option<String>,
    /// `-i` irradiance calculation.
    pub i: bool,
    /// `-u` uncorrelated (true) or correlated quasi-Monte Carlo (false) sampling.
    pub u: bool,
    /// `-bv` back face visibility.
    pub bv: bool,
    /// `-me` mist extinction coefficient.
    pub me: [f64; 3],
    /// `-ma` mist scattering albedo.
    pub ma: [f64; 3],
    /// `-mg` mist scattering eccentricity.
    pub mg: f64,
    /// `-ms` mist sampling distance.
    pub ms: f64,
    /// Tessera's own settings of the ambient calculation (`--amb-share-max`, ...).
    #[serde(default)]
    pub amb: AmbientSettings,
}

impl Default for RenderParams {
    /// rpict's defaults.
    fn default() -> Self {
        RenderParams {
            dt: 0.05,
            dc: 0.5,
            dj: 0.0,
            ds: 0.25,
            dr: 1,
            dp: 512.0,
            dv: true,
            ss: 1.0,
            st: 0.15,
            lr: 7,
            lw: 1e-4,
            av: [0.0; 3],
            aw: 0,
            ab: 0,
            aa: 0.2,
            ar: 64,
            ad: 512,
            as_: 128,
            ae: Vec::new(),
            ai: Vec::new(),
            af: None,
            i: false,
            u: false,
            bv: true,
            me: [0.0; 3],
            ma: [0.0; 3],
            mg: 0.0,
            ms: 0.0,
            amb: AmbientSettings::default(),
        }
    }
}

fn nonneg_i32(option: &str, v: i32) -> Result<i32, OptError> {
    if v < 0 {
        return Err(OptError::BadValue {
            option: option.to_string(),
            reason: format!("value {v} must not be negative"),
        });
    }
    Ok(v)
}

fn nonneg3(option: &str, v: [f64; 3]) -> Result<[f64; 3], OptError> {
    for c in v {
        range(option, c, 0.0, f64::INFINITY)?;
    }
    Ok(v)
}

impl RenderParams {
    /// Try to apply one rendering option at `words[0]`. Returns `Ok(Some(n_words_consumed))`
    /// if it was a rendering option, `Ok(None)` if not, and an error for bad values, photon
    /// map / spectral options (not supported) or mixing `-ae` and `-ai`.
    pub fn apply_option(&mut self, words: &[String]) -> Result<Option<usize>, OptError> {
        let Some(w) = words.first() else {
            return Ok(None);
        };
        let o = w.as_str();
        let inf = f64::INFINITY;
        if let Some(n) = self
            .amb
            .apply_option(words)
            .map_err(|e| OptError::BadValue {
                option: o.to_string(),
                reason: e.strip_prefix(&format!("{o}: ")).unwrap_or(&e).to_string(),
            })?
        {
            return Ok(Some(n));
        }
        if let Some(b) = bool_option(o, "i", self.i) {
            self.i = b;
            return Ok(Some(1));
        }
        if let Some(b) = bool_option(o, "u", self.u) {
            self.u = b;
            return Ok(Some(1));
        }
        if let Some(b) = bool_option(o, "bv", self.bv) {
            self.bv = b;
            return Ok(Some(1));
        }
        if let Some(b) = bool_option(o, "dv", self.dv) {
            self.dv = b;
            return Ok(Some(1));
        }
        let n = match o {
            "-dt" => {
                self.dt = range(o, f1(words)?, 0.0, inf)?;
                2
            }
            "-dc" => {
                self.dc = range(o, f1(words)?, 0.0, 1.0)?;
                2
            }
            "-dj" => {
                self.dj = range(o, f1(words)?, 0.0, 1.0)?;
                2
            }
            "-ds" => {
                self.ds = range(o, f1(words)?, 0.0, inf)?;
                2
            }
            "-dr" => {
                self.dr = nonneg_i32(o, i1(words)?)?;
                2
            }
            "-dp" => {
                self.dp = range(o, f1(words)?, 0.0, inf)?;
                2
            }
            "-ss" => {
                self.ss = range(o, f1(words)?, 0.0, inf)?;
                2
            }
            "-st" => {
                self.st = range(o, f1(words)?, 0.0, inf)?;
                2
            }
            "-lr" => {
                self.lr = i1(words)?;
                2
            }
            "-lw" => {
                self.lw = range(o, f1(words)?, 0.0, inf)?;
                2
            }
            "-av" => {
                self.av = f3(words)?;
                4
            }
            "-aw" => {
                self.aw = nonneg_i32(o, i1(words)?)?;
                2
            }
            "-ab" => {
                self.ab = i1(words)?;
                2
            }
            "-aa" => {
                self.aa = range(o, f1(words)?, 0.0, inf)?;
                2
            }
            "-ar" => {
                self.ar = nonneg_i32(o, i1(words)?)?;
                2
            }
            "-ad" => {
                self.ad = nonneg_i32(o, i1(words)?)?;
                2
            }
            "-as" => {
                self.as_ = nonneg_i32(o, i1(words)?)?;
                2
            }
            "-ae" | "-ai" | "-aE" | "-aI" => {
                let a = arg(words, 1, "a name")?.clone();
                let include = o == "-ai" || o == "-aI";
                let names = if o == "-aE" || o == "-aI" {
                    let text = std::fs::read(&a).map_err(|e| OptError::Io {
                        path: a.clone(),
                        reason: e.to_string(),
                    })?;
                    split_words(&String::from_utf8_lossy(&text))
                } else {
                    vec![a]
                };
                let (mine, other) = if include {
                    (&mut self.ai, &self.ae)
                } else {
                    (&mut self.ae, &self.ai)
                };
                if !other.is_empty() {
                    return Err(OptError::BadValue {
                        option: o.to_string(),
                        reason: "cannot mix ambient exclude (-ae/-aE) and include (-ai/-aI) lists"
                            .into(),
                    });
                }
                mine.extend(names);
                2
            }
            "-af" => {
                self.af = Some(arg(words, 1, "a file name")?.clone());
                2
            }
            "-me" => {
                self.me = nonneg3(o, f3(words)?)?;
                4
            }
            "-ma" => {
                self.ma = nonneg3(o, f3(words)?)?;
                4
            }
            "-mg" => {
                self.mg = range(o, f1(words)?, -1.0, 1.0)?;
                2
            }
            "-ms" => {
                self.ms = range(o, f1(words)?, 0.0, inf)?;
                2
            }
            "-am" | "-ap" | "-apc" | "-apd" | "-api" | "-apo" | "-apD" | "-apP" | "-apm"
            | "-apr" | "-ape" => {
                return Err(OptError::Unsupported {
                    option: o.to_string(),
                    reason: "photon mapping is not implemented".into(),
                })
            }
            "-cs" | "-cw" => {
                return Err(OptError::Unsupported {
                    option: o.to_string(),
                    reason: "hyperspectral rendering is not implemented (RGB only)".into(),
                })
            }
            _ => return Ok(None),
        };
        Ok(Some(n))
    }

    /// The parameters as exact option words (shortest round-trip number forms).
    pub fn to_words(&self) -> Vec<String> {
        let mut w: Vec<String> = Vec::new();
        let mut push = |name: &str, vals: &[String]| {
            w.push(name.to_string());
            w.extend(vals.iter().cloned());
        };
        let f = |v: f64| vec![format!("{v}")];
        let i = |v: i32| vec![format!("{v}")];
        let v3 = |v: [f64; 3]| v.iter().map(|c| format!("{c}")).collect::<Vec<_>>();
        let b = |v: bool| if v { "+" } else { "-" };
        push(&format!("-i{}", b(self.i)), &[]);
        push(&format!("-u{}", b(self.u)), &[]);
        push(&format!("-bv{}", b(self.bv)), &[]);
        push("-dt", &f(self.dt));
        push("-dc", &f(self.dc));
        push("-dj", &f(self.dj));
        push("-ds", &f(self.ds));
        push("-dr", &i(self.dr));
        push("-dp", &f(self.dp));
        push(&format!("-dv{}", b(self.dv)), &[]);
        push("-ss", &f(self.ss));
        push("-st", &f(self.st));
        push("-av", &v3(self.av));
        push("-aw", &i(self.aw));
        push("-ab", &i(self.ab));
        push("-aa", &f(self.aa));
        push("-ar", &i(self.ar));
        push("-ad", &i(self.ad));
        push("-as", &i(self.as_));
        for n in &self.ae {
            push("-ae", std::slice::from_ref(n));
        }
        for n in &self.ai {
            push("-ai", std::slice::from_ref(n));
        }
        if let Some(af) = &self.af {
            push("-af", std::slice::from_ref(af));
        }
        push("-me", &v3(self.me));
        push("-ma", &v3(self.ma));
        push("-mg", &f(self.mg));
        push("-ms", &f(self.ms));
        push("-lr", &i(self.lr));
        push("-lw", &f(self.lw));
        // Tessera's ambient settings where they differ from the defaults.
        let defaults = AmbientSettings::default().to_words();
        for (pair, default) in self.amb.to_words().chunks(2).zip(defaults.chunks(2)) {
            if pair != default {
                w.extend(pair.iter().cloned());
            }
        }
        w
    }
}

/// Everything rpict's (and tpict's) command line can say.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RpictOptions {
    /// The view (`-v*`, `-vf`).
    pub view: View,
    /// Rendering parameters.
    pub params: RenderParams,
    /// `-x` maximum horizontal resolution.
    pub x: usize,
    /// `-y` maximum vertical resolution.
    pub y: usize,
    /// `-pa` pixel aspect (0: keep x, y and compute it).
    pub pa: f64,
    /// `-pj` pixel jitter.
    pub pj: f64,
    /// `-pm` pixel motion (stored; motion blur is up to the renderer).
    pub pm: f64,
    /// `-pd` depth-of-field aperture diameter.
    pub pd: f64,
    /// `-ps` pixel sample spacing (1..16).
    pub ps: usize,
    /// `-pt` pixel threshold.
    pub pt: f64,
    /// `-t` seconds between progress reports (0: none).
    pub report_interval: f64,
    /// `-w` warnings.
    pub warnings: bool,
    /// `-n N` threads (None: default, resolved by the caller).
    pub threads: Option<usize>,
    /// `-o` output file (pattern with `%d` for `-S`).
    pub output: Option<String>,
    /// `-S n` read views from stdin, frames numbered from n.
    pub sequence_start: Option<u32>,
    /// `-e file` error file.
    pub error_file: Option<String>,
    /// `--allow-commands`: allow `!command` lines in scene files.
    pub allow_commands: bool,
    /// `--stats FILE`: write render statistics.
    pub stats_file: Option<String>,
    /// `--amb-log FILE`: Tessera's append-only ambient log (shared between processes).
    pub amb_log: Option<String>,
    /// `--amb-flush N`: append new ambient values to the log every N values.
    pub amb_flush: usize,
    /// `--amb-force`: use an ambient log whose fingerprint does not match.
    pub amb_force: bool,
    /// Fill the ambient cache in an overture pass before the picture's own pass (default;
    /// `--no-overture` turns it off). See [`RpictOptions::overture_step`]. Manifests written
    /// before the option existed read as on.
    #[serde(default = "default_true")]
    pub overture: bool,
    /// Scene files (after the options); `-` is stdin. Empty input means `["-"]`.
    pub scene_files: Vec<String>,
}

fn default_true() -> bool {
    true
}

impl RpictOptions {
    /// Pixel step of the overture pass ([`crate::render::FrameSetup::overture`]): the `-ps`
    /// spacing when the ambient values are cached (`-ab > 0`, `-aa > 0`, `-ad > 0`) and the
    /// overture is on, else 0 (no overture).
    pub fn overture_step(&self) -> usize {
        let p = &self.params;
        if self.overture && crate::ambient::settings::caches(p.ab, p.ad, p.aa) {
            self.ps.max(1)
        } else {
            0
        }
    }
}

impl Default for RpictOptions {
    /// rpict's defaults with no scene file.
    fn default() -> Self {
        RpictOptions {
            view: View::default(),
            params: RenderParams::default(),
            x: 512,
            y: 512,
            pa: 1.0,
            pj: 0.67,
            pm: 0.0,
            pd: 0.0,
            ps: 4,
            pt: 0.05,
            report_interval: 0.0,
            warnings: true,
            threads: None,
            output: None,
            sequence_start: None,
            error_file: None,
            allow_commands: false,
            stats_file: None,
            amb_log: None,
            amb_flush: 128,
            amb_force: false,
            overture: true,
            scene_files: Vec::new(),
        }
    }
}

/// What a tpict command line asks for.
#[derive(Clone, Debug, PartialEq)]
pub enum Command {
    /// Render with these options.
    Render(Box<RpictOptions>),
    /// `-defaults`/`-help`: print [`defaults_text`] of the options given before it.
    PrintDefaults(Box<RpictOptions>),
    /// `-version`.
    PrintVersion,
}

fn unsupported(option: &str, reason: &str) -> OptError {
    OptError::Unsupported {
        option: option.to_string(),
        reason: reason.to_string(),
    }
}

/// Apply one rpict option at `words[0]` (not a scene file). Returns the words consumed, or a
/// finished command for `-defaults`/`-version`.
fn apply_rpict_option(
    o: &mut RpictOptions,
    words: &[String],
) -> Result<Result<usize, Command>, OptError> {
    let w = words[0].as_str();
    if let Some(n) = o.view.apply_option(words)? {
        return Ok(Ok(n));
    }
    if let Some(n) = o.params.apply_option(words)? {
        return Ok(Ok(n));
    }
    if let Some(b) = bool_option(w, "w", o.warnings) {
        o.warnings = b;
        return Ok(Ok(1));
    }
    let inf = f64::INFINITY;
    let n = match w {
        "-version" => return Ok(Err(Command::PrintVersion)),
        "-defaults" | "-help" => return Ok(Err(Command::PrintDefaults(Box::new(o.clone())))),
        "-vf" => {
            let f = arg(words, 1, "a view file name")?;
            o.view = read_view_file(Path::new(f), &o.view)?;
            2
        }
        "-x" | "-y" => {
            let v: usize = i1(words)?;
            if v == 0 {
                return Err(OptError::BadValue {
                    option: w.into(),
                    reason: "resolution must be at least 1".into(),
                });
            }
            if w == "-x" {
                o.x = v
            } else {
                o.y = v
            }
            2
        }
        "-pa" => {
            o.pa = range(w, f1(words)?, 0.0, inf)?;
            2
        }
        "-pj" => {
            o.pj = range(w, f1(words)?, 0.0, 1.0)?;
            2
        }
        "-pm" => {
            o.pm = range(w, f1(words)?, 0.0, inf)?;
            2
        }
        "-pd" => {
            o.pd = range(w, f1(words)?, 0.0, inf)?;
            2
        }
        "-ps" => {
            let v: usize = i1(words)?;
            range(w, v as f64, 1.0, 16.0)?;
            o.ps = v;
            2
        }
        "-pt" => {
            o.pt = range(w, f1(words)?, 0.0, inf)?;
            2
        }
        "-pRGB" => 1,
        "-pXYZ" | "-pc" => {
            return Err(unsupported(w, "only RGB output (-pRGB) is implemented"));
        }
        "-t" => {
            o.report_interval = range(w, f1(words)?, 0.0, inf)?;
            2
        }
        "-n" => {
            let v: usize = i1(words)?;
            if v == 0 {
                return Err(OptError::BadValue {
                    option: w.into(),
                    reason: "thread count must be at least 1".into(),
                });
            }
            o.threads = Some(v);
            2
        }
        "-o" => {
            o.output = Some(arg(words, 1, "a file name")?.clone());
            2
        }
        "-S" => {
            o.sequence_start = Some(i1(words)?);
            2
        }
        "-e" => {
            let a = arg(words, 1, "a file name")?;
            if a.contains('=') || a.contains(':') {
                return Err(unsupported(
                    w,
                    &format!("'{a}' is a function-file expression; only -e errfile is supported"),
                ));
            }
            o.error_file = Some(a.clone());
            2
        }
        "--allow-commands" => {
            o.allow_commands = true;
            1
        }
        "--stats" => {
            o.stats_file = Some(arg(words, 1, "a file name")?.clone());
            2
        }
        "--amb-log" => {
            o.amb_log = Some(arg(words, 1, "a file name")?.clone());
            2
        }
        "--amb-flush" => {
            let v = arg(words, 1, "a count")?;
            o.amb_flush = match v.parse::<usize>() {
                Ok(n) if n > 0 => n,
                _ => {
                    return Err(OptError::BadValue {
                        option: w.to_string(),
                        reason: format!("expected a positive count, got '{v}'"),
                    })
                }
            };
            2
        }
        "--amb-force" => {
            o.amb_force = true;
            1
        }
        "--no-overture" => {
            o.overture = false;
            1
        }
        "-z" => return Err(unsupported(w, "depth buffer output is not implemented")),
        "-P" | "-PP" => {
            return Err(unsupported(
                w,
                "persistent server mode is not implemented; use -n for threads",
            ))
        }
        "-r" | "-ro" => {
            return Err(unsupported(w, "picture recovery is not implemented"));
        }
        "-f" => {
            return Err(unsupported(w, "function files are not supported"));
        }
        "-features" => {
            return Err(unsupported(w, "feature queries are not implemented"));
        }
        _ => return Err(OptError::Unknown(w.to_string())),
    };
    Ok(Ok(n))
}

/// Parse tpict's arguments (without argv[0]): expands `@file`/`$VAR`, applies `-vf` files
/// in order (later view options override, like rpict), validates numbers and ranges,
/// rejects unknown options (the error names the option) and unsupported ones with a reason.
/// Options come first, then scene files (`-` is stdin; none given means stdin).
/// `-defaults`/`-help` and `-version` end parsing at once, like rpict.
pub fn parse_rpict_args(args: &[String]) -> Result<Command, OptError> {
    let words = expand_args(args)?;
    let mut o = RpictOptions::default();
    let mut i = 0;
    while i < words.len() {
        let w = &words[i];
        let is_option = w.len() > 1 && w.starts_with('-');
        if !is_option {
            o.scene_files.push(w.clone());
            i += 1;
            continue;
        }
        if let Some(scene) = o.scene_files.first() {
            return Err(OptError::OptionAfterScene {
                option: w.clone(),
                scene: scene.clone(),
            });
        }
        match apply_rpict_option(&mut o, &words[i..])? {
            Ok(n) => i += n,
            Err(cmd) => return Ok(cmd),
        }
    }
    if o.scene_files.is_empty() {
        o.scene_files.push("-".to_string());
    }
    if o.sequence_start.is_some() && o.scene_files.iter().any(|s| s == "-") {
        return Err(OptError::BadValue {
            option: "-S".into(),
            reason: "views are read from stdin, so the scene cannot come from stdin".into(),
        });
    }
    o.view.frame()?;
    Ok(Command::Render(Box::new(o)))
}

/// Format like C's `%.{prec}e` (two-digit exponent at least).
fn fmt_e(v: f64, prec: usize) -> String {
    let s = format!("{:.*e}", prec, v);
    match s.split_once('e') {
        Some((m, e)) => {
            let e: i32 = e.parse().unwrap_or(0);
            let sign = if e < 0 { '-' } else { '+' };
            format!("{m}e{sign}{:02}", e.abs())
        }
        None => s,
    }
}

/// The text of `-defaults`, in rpict's layout, reflecting the given options (so
/// `tpict -ab 2 -defaults` shows `-ab 2`).
pub fn defaults_text(opts: &RpictOptions) -> String {
    let v = &opts.view;
    let p = &opts.params;
    let mut s = String::new();
    let mut line = |text: String, tabs: usize, comment: &str| {
        s.push_str(&text);
        for _ in 0..tabs {
            s.push('\t');
        }
        s.push_str("# ");
        s.push_str(comment);
        s.push('\n');
    };
    let f = |x: f64| format!("{x:.6}");
    let v3 = |a: [f64; 3]| format!("{:.6} {:.6} {:.6}", a[0], a[1], a[2]);
    let int = |name: &str, x: i64| format!("{name} {x:<9}");
    let onoff = |b: bool| if b { "on" } else { "off" };
    let pm = |b: bool| if b { '+' } else { '-' };
    line(
        format!("-vt{}", v.vtype.letter()),
        4,
        &format!("view type {}", v.vtype.name()),
    );
    line(format!("-vp {}", v3(v.vp.to_array())), 1, "view point");
    line(format!("-vd {}", v3(v.vd.to_array())), 1, "view direction");
    line(format!("-vu {}", v3(v.vu.to_array())), 1, "view up");
    line(format!("-vh {}", f(v.vh)), 3, "view horizontal size");
    line(format!("-vv {}", f(v.vv)), 3, "view vertical size");
    line(format!("-vo {}", f(v.vo)), 3, "view fore clipping plane");
    line(format!("-va {}", f(v.va)), 3, "view aft clipping plane");
    line(format!("-vs {}", f(v.vs)), 3, "view shift");
    line(format!("-vl {}", f(v.vl)), 3, "view lift");
    line(format!("-x  {:<9}", opts.x), 3, "x resolution");
    line(format!("-y  {:<9}", opts.y), 3, "y resolution");
    line("-pRGB".into(), 4, "standard RGB color output");
    line(format!("-pa {}", f(opts.pa)), 3, "pixel aspect ratio");
    line(format!("-pj {}", f(opts.pj)), 3, "pixel jitter");
    line(format!("-pm {}", f(opts.pm)), 3, "pixel motion");
    line(format!("-pd {}", f(opts.pd)), 3, "pixel depth-of-field");
    line(format!("-ps {:<9}", opts.ps), 3, "pixel sample");
    line(format!("-pt {}", f(opts.pt)), 3, "pixel threshold");
    let t = if opts.report_interval.fract() == 0.0 {
        format!("{}", opts.report_interval as i64)
    } else {
        fmt_g6(opts.report_interval)
    };
    line(format!("-t  {t:<9}"), 3, "time between reports");
    line(
        format!("-w{}", pm(opts.warnings)),
        4,
        &format!("warning messages {}", onoff(opts.warnings)),
    );
    line(
        format!("-i{}", pm(p.i)),
        4,
        &format!("irradiance calculation {}", onoff(p.i)),
    );
    line(
        format!("-u{}", pm(p.u)),
        4,
        if p.u {
            "uncorrelated Monte Carlo sampling"
        } else {
            "correlated quasi-Monte Carlo sampling"
        },
    );
    line(
        format!("-bv{}", pm(p.bv)),
        4,
        &format!("back face visibility {}", onoff(p.bv)),
    );
    line(format!("-dt {}", f(p.dt)), 3, "direct threshold");
    line(format!("-dc {}", f(p.dc)), 3, "direct certainty");
    line(format!("-dj {}", f(p.dj)), 3, "direct jitter");
    line(format!("-ds {}", f(p.ds)), 3, "direct sampling");
    line(int("-dr", p.dr as i64), 3, "direct relays");
    line(int("-dp", p.dp as i64), 3, "direct pretest density");
    line(
        format!("-dv{}", pm(p.dv)),
        4,
        &format!("direct visibility {}", onoff(p.dv)),
    );
    line(format!("-ss {}", f(p.ss)), 3, "specular sampling");
    line(format!("-st {}", f(p.st)), 3, "specular threshold");
    line(format!("-av {}", v3(p.av)), 1, "ambient value");
    line(int("-aw", p.aw as i64), 3, "ambient value weight");
    line(int("-ab", p.ab as i64), 3, "ambient bounces");
    line(format!("-aa {}", f(p.aa)), 3, "ambient accuracy");
    line(int("-ar", p.ar as i64), 3, "ambient resolution");
    line(int("-ad", p.ad as i64), 3, "ambient divisions");
    line(int("-as", p.as_ as i64), 3, "ambient super-samples");
    line(
        format!(
            "-me {} {} {}",
            fmt_e(p.me[0], 2),
            fmt_e(p.me[1], 2),
            fmt_e(p.me[2], 2)
        ),
        1,
        "mist extinction coefficient",
    );
    line(format!("-ma {}", v3(p.ma)), 1, "mist scattering albedo");
    line(
        format!("-mg {}", f(p.mg)),
        3,
        "mist scattering eccentricity",
    );
    line(format!("-ms {}", f(p.ms)), 3, "mist sampling distance");
    line(
        int("-lr", p.lr as i64),
        3,
        if p.lr <= 0 {
            "limit reflection (Russian roulette)"
        } else {
            "limit reflection"
        },
    );
    line(format!("-lw {}", fmt_e(p.lw, 2)), 3, "limit weight");
    line("-am 0.0".into(), 4, "max photon search radius");
    s
}

/// Options as command-line words that [`parse_rpict_args`] parses back to the same value
/// (for picture headers and manifests; scene files excluded).
pub fn to_args(opts: &RpictOptions) -> Vec<String> {
    let mut w = opts.view.to_words();
    let s = |v: &dyn std::fmt::Display| v.to_string();
    w.extend([
        "-x".into(),
        s(&opts.x),
        "-y".into(),
        s(&opts.y),
        "-pa".into(),
        s(&opts.pa),
        "-pj".into(),
        s(&opts.pj),
        "-pm".into(),
        s(&opts.pm),
        "-pd".into(),
        s(&opts.pd),
        "-ps".into(),
        s(&opts.ps),
        "-pt".into(),
        s(&opts.pt),
        "-t".into(),
        s(&opts.report_interval),
        if opts.warnings { "-w+" } else { "-w-" }.into(),
    ]);
    w.extend(opts.params.to_words());
    if let Some(n) = opts.threads {
        w.extend(["-n".into(), n.to_string()]);
    }
    if let Some(o) = &opts.output {
        w.extend(["-o".into(), o.clone()]);
    }
    if let Some(n) = opts.sequence_start {
        w.extend(["-S".into(), n.to_string()]);
    }
    if let Some(e) = &opts.error_file {
        w.extend(["-e".into(), e.clone()]);
    }
    if opts.allow_commands {
        w.push("--allow-commands".into());
    }
    if let Some(f) = &opts.stats_file {
        w.extend(["--stats".into(), f.clone()]);
    }
    if let Some(f) = &opts.amb_log {
        w.extend(["--amb-log".into(), f.clone()]);
    }
    if opts.amb_flush != 128 {
        w.extend(["--amb-flush".into(), opts.amb_flush.to_string()]);
    }
    if opts.amb_force {
        w.push("--amb-force".into());
    }
    if !opts.overture {
        w.push("--no-overture".into());
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;

    fn words(s: &str) -> Vec<String> {
        s.split_whitespace().map(String::from).collect()
    }

    #[test]
    fn booleans() {
        assert_eq!(bool_option("-i", "i", false), Some(true));
        assert_eq!(bool_option("-i", "i", true), Some(false));
        assert_eq!(bool_option("-iT", "i", false), Some(true));
        assert_eq!(bool_option("-bvf", "bv", true), Some(false));
        assert_eq!(bool_option("-ix", "i", false), None);
        assert_eq!(bool_option("-ab", "i", false), None);
    }

    #[test]
    fn c_exponent_format() {
        assert_eq!(fmt_e(0.0, 2), "0.00e+00");
        assert_eq!(fmt_e(1e-4, 2), "1.00e-04");
        assert_eq!(fmt_e(123.0, 2), "1.23e+02");
    }

    #[test]
    fn split_words_quotes_comments() {
        assert_eq!(
            split_words("-ab 2 # bounces\n\"a b\" 'c d'e\n#x y\n-i"),
            vec!["-ab", "2", "a b", "c de", "-i"]
        );
    }

    #[test]
    fn params_parse() {
        let mut p = RenderParams::default();
        assert_eq!(p.apply_option(&words("-av 1 2 3")).unwrap(), Some(4));
        assert_eq!(p.av, [1.0, 2.0, 3.0]);
        assert_eq!(p.apply_option(&words("-x 3")).unwrap(), None);
        assert!(p.apply_option(&words("-ab 1.5")).is_err());
        assert!(p.apply_option(&words("-av 1 2")).is_err());
        p.apply_option(&words("-ae foo")).unwrap();
        let e = p.apply_option(&words("-ai bar")).unwrap_err();
        assert!(e.to_string().contains("cannot mix"), "{e}");
    }

    #[test]
    fn overture_runs_only_for_cached_ambient_and_can_be_turned_off() {
        let parse = |a: &str| match parse_rpict_args(&words(a)).unwrap() {
            Command::Render(o) => *o,
            c => panic!("{c:?}"),
        };
        assert_eq!(parse("-ab 1 s.rad").overture_step(), 4);
        assert_eq!(parse("-ab 1 -ps 1 s.rad").overture_step(), 1);
        assert_eq!(parse("-ab 1 -ps 8 s.rad").overture_step(), 8);
        // No cache: nothing to fill.
        assert_eq!(parse("-ab 0 s.rad").overture_step(), 0);
        assert_eq!(parse("-ab 1 -aa 0 s.rad").overture_step(), 0);
        assert_eq!(parse("-ab 1 -aa 1e-7 s.rad").overture_step(), 0);
        assert_eq!(parse("-ab 1 -ad 0 s.rad").overture_step(), 0);
        let off = parse("-ab 1 --no-overture s.rad");
        assert_eq!(off.overture_step(), 0);
        // The option survives the round trip through words (job manifests, `-defaults`).
        let w = to_args(&off);
        assert!(w.contains(&"--no-overture".to_string()), "{w:?}");
        // A manifest written before the option existed reads as on.
        let mut json = serde_json::to_value(parse("-ab 1 s.rad")).unwrap();
        json.as_object_mut().unwrap().remove("overture");
        let back: RpictOptions = serde_json::from_value(json).unwrap();
        assert!(back.overture);
    }
}
