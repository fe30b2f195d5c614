//! The rendering parameters: every option that changes the light transport (`-d*`, `-s*`,
//! `-l*`, `-a*` but `-af`, `-i`, `-u`, `-bv`, `-m*`, and Tessera's ambient settings
//! `--amb-*`). Kept in job manifests and hashed (in part) into the ambient fingerprint.

use super::schedule::{AccuracySchedule, MotionAccuracy, TimeBudget};
use super::words::{
    arg, bool_option, f1, f3, i1, nonneg3, nonneg_i32, parse_f64, range, split_words, OptError,
};
use crate::ambient::settings::AmbientSettings;

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
    /// `-ax start end step` / `-axg start end ratio`: `-aa` varying with the frame.
    #[serde(default)]
    pub ax: Option<AccuracySchedule>,
    /// `-axm relax ahead`: relaxed `-aa` where the view moves away (batch jobs).
    #[serde(default)]
    pub axm: Option<MotionAccuracy>,
    /// `-axt seconds start end`: `-aa` chosen per frame to keep frame cost near a budget.
    #[serde(default)]
    pub axt: Option<TimeBudget>,
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
            i: false,
            u: false,
            bv: true,
            me: [0.0; 3],
            ma: [0.0; 3],
            mg: 0.0,
            ms: 0.0,
            amb: AmbientSettings::default(),
            ax: None,
            axm: None,
            axt: None,
        }
    }
}

impl RenderParams {
    /// `-aa` of the frame at `position` in its animation (0 = first): the `-ax` schedule's,
    /// or None when accuracy does not vary.
    pub fn frame_accuracy(&self, position: u32) -> Option<f64> {
        self.ax.map(|s| s.accuracy(position))
    }

    /// Why these settings cannot be rendered, if they ask for something Tessera refuses
    /// rather than ignores: a participating medium (`-me` above zero; rpict would render
    /// one). Parsing accepts them all (`-defaults` prints them as rpict does).
    pub fn refused(&self) -> Option<String> {
        self.me.iter().any(|&c| c > 0.0).then(|| {
            "option -me is not supported: a participating medium (mist) is not implemented; \
             rpict would render one. Remove -me or give -me 0 0 0"
                .to_string()
        })
    }

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
            "-ax" | "-axg" => {
                let v = f3(words)?;
                let s = AccuracySchedule::new(v[0], v[1], v[2], o == "-axg").map_err(|e| {
                    OptError::BadValue {
                        option: o.to_string(),
                        reason: e,
                    }
                })?;
                // A repeated option replaces the earlier one (rpict's rule), but -ax and
                // -axg are two schedules: both given is a mistake, not an override.
                if self.ax.is_some_and(|a| a.geometric != s.geometric) {
                    return Err(OptError::BadValue {
                        option: o.to_string(),
                        reason: "-ax and -axg both set the accuracy schedule: give one of them"
                            .into(),
                    });
                }
                self.ax = Some(s);
                4
            }
            "-axm" => {
                let relax = f1(words)?;
                let ahead = parse_f64(o, arg(words, 2, "2 numbers")?, 2)?;
                let m = MotionAccuracy::new(relax, ahead).map_err(|e| OptError::BadValue {
                    option: o.to_string(),
                    reason: e,
                })?;
                self.axm = Some(m);
                3
            }
            "-axt" => {
                let v = f3(words)?;
                let b = TimeBudget::new(v[0], v[1], v[2]).map_err(|e| OptError::BadValue {
                    option: o.to_string(),
                    reason: e,
                })?;
                self.axt = Some(b);
                4
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
        if let Some(ax) = &self.ax {
            let w = ax.to_words();
            push(&w[0], &w[1..]);
        }
        if let Some(m) = &self.axm {
            let w = m.to_words();
            push(&w[0], &w[1..]);
        }
        if let Some(b) = &self.axt {
            let w = b.to_words();
            push(&w[0], &w[1..]);
        }
        push("-ar", &i(self.ar));
        push("-ad", &i(self.ad));
        push("-as", &i(self.as_));
        for n in &self.ae {
            push("-ae", std::slice::from_ref(n));
        }
        for n in &self.ai {
            push("-ai", std::slice::from_ref(n));
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

#[cfg(test)]
mod tests {
    use super::*;

    fn words(s: &str) -> Vec<String> {
        s.split_whitespace().map(String::from).collect()
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
}
