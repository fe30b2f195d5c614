//! Tessera's own settings of the ambient calculation, beside rpict's `-a*` options: each of
//! Tessera's additions to Radiance's irradiance cache (docs/ambient.md) with its switch.
//!
//! They are options like any other (`--amb-share-max 1`, `--amb-corral off`, ...), parsed
//! here from Radiance-style words so that `tpict`, view/option files and job manifests share
//! them, kept in [`crate::options::RenderParams::amb`], hashed into the ambient fingerprint
//! (two processes with different settings never share values) and written into picture
//! headers and `--stats`. Nothing else configures the calculation.

use crate::FTINY;

/// Default largest share reach ([`AmbientSettings::share_max`]).
pub const SHARE_MAX: f64 = 3.0;

/// Largest share reach accepted at all (from an option or a log record).
pub const SHARE_LIMIT: f64 = 4.0;

/// Default share of `-ad`'s divisions a cached value spends on super-sampling when `-as` is
/// 0 ([`AmbientSettings::as0_split`]).
pub const AS0_SPLIT: f64 = 0.25;

/// Largest `-as 0` split accepted.
pub const AS0_SPLIT_LIMIT: f64 = 0.9;

/// Default cell limit of the mesh a new value's Hessian is taken from: `-ad 1024` (18 × 57
/// cells) and `-ad 512` (13 × 41) are thinned to 9 × 28 evenly spaced rings and columns (see
/// [`super::hessian::subsample_grid`]); radii change by under 1% in a room, the Hessian's
/// cost falls from about a quarter of a render to a few percent (docs/ambient.md).
pub const HESSIAN_CELLS: usize = 256;

/// Fewest Hessian cells accepted (a mesh of 2 rings × 3 columns at least, with room).
pub const HESSIAN_CELLS_MIN: usize = 16;

/// Default outlier limit of a cached value's cells (see
/// [`super::sample::clamp_outliers`]).
pub const OUTLIER_LIMIT: f64 = 2.0;

/// Tessera's settings of the ambient calculation (defaults: Tessera's; docs/ambient.md says
/// which settings come closest to rpict's calculation).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct AmbientSettings {
    /// `--amb-share-max F`: largest share reach (1: Radiance's rule, every value serves out
    /// to `-aa` whatever the rest of the surface's light); 1 to [`SHARE_LIMIT`].
    pub share_max: f64,
    /// `--amb-as0-split F`: with `-as 0`, the share of the `-ad` rays a cached value spends
    /// on super-sampling (0: rpict's meaning, no super-sampling); 0 to [`AS0_SPLIT_LIMIT`].
    pub as0_split: f64,
    /// `--amb-hessian on|off`: anisotropic radii from the irradiance Hessian (off: the
    /// harmonic mean distance to the surfaces the samples hit).
    pub hessian: bool,
    /// `--amb-reach on|off`: a value serves as far as its Hessian radii leave room for, up to
    /// 2 × `-aa` (off: every value's reach is 1, as in Radiance).
    pub reach: bool,
    /// `--amb-gradients on|off`: extrapolate cached values with their gradients.
    pub gradients: bool,
    /// `--amb-gradient-radii on|off`: a value's gradient shrinks its radii as in Radiance
    /// (`rad ≤ 1/|gpos|`).
    pub gradient_radii: bool,
    /// `--amb-glow-sampling on|off`: cached values sample the scene's glows beyond their
    /// radius as light sources.
    pub glow_sampling: bool,
    /// `--amb-corral on|off`: the light-leak test (flag new values, test flagged ones at
    /// lookups).
    pub corral: bool,
    /// `--amb-shadow-reuse on|off`: reuse shadow rays of a value's sample hits within their
    /// footprints ([`crate::light::viscache`]).
    pub shadow_reuse: bool,
    /// `--amb-shadow-trust N`: agreeing shadow rays a footprint's cube must have traced
    /// before it answers without one (1 to [`crate::light::viscache::TRUST_MAX`]).
    pub shadow_trust: u16,
    /// `--amb-hessian-cells N`: cells of the mesh a value's Hessian is taken from at most
    /// (thinned evenly beyond); at least [`HESSIAN_CELLS_MIN`].
    pub hessian_cells: usize,
    /// `--amb-outlier-limit F`: a cell of a new value may bring at most F times the others'
    /// sum, loosened with the sample count (0: no limit).
    pub outlier_limit: f64,
    /// `--amb-ss-own on|off`: whether a cell's own first sample counts in how many of the
    /// super-sampling rays it gets (on: Radiance's rule, which biases values low by about
    /// 1/`-ad`; off: the spread of its neighbours only, unbiased).
    pub ss_own: bool,
}

impl Default for AmbientSettings {
    fn default() -> AmbientSettings {
        AmbientSettings {
            share_max: SHARE_MAX,
            as0_split: AS0_SPLIT,
            hessian: true,
            reach: true,
            gradients: true,
            gradient_radii: false,
            glow_sampling: true,
            corral: true,
            shadow_reuse: true,
            shadow_trust: crate::light::viscache::TRUST,
            hessian_cells: HESSIAN_CELLS,
            outlier_limit: OUTLIER_LIMIT,
            ss_own: true,
        }
    }
}

/// The option names, in the order [`AmbientSettings::to_words`] writes them.
pub const OPTION_NAMES: &[&str] = &[
    "--amb-share-max",
    "--amb-as0-split",
    "--amb-hessian",
    "--amb-reach",
    "--amb-gradients",
    "--amb-gradient-radii",
    "--amb-glow-sampling",
    "--amb-corral",
    "--amb-shadow-reuse",
    "--amb-shadow-trust",
    "--amb-hessian-cells",
    "--amb-outlier-limit",
    "--amb-ss-own",
];

fn on_off(option: &str, w: &str) -> Result<bool, String> {
    match w {
        "on" | "+" | "1" | "true" | "yes" => Ok(true),
        "off" | "-" | "0" | "false" | "no" => Ok(false),
        _ => Err(format!("{option}: expected on or off, got '{w}'")),
    }
}

fn number(option: &str, w: &str, lo: f64, hi: f64) -> Result<f64, String> {
    match w.parse::<f64>() {
        Ok(v) if v.is_finite() && (lo..=hi).contains(&v) => Ok(v),
        _ => Err(format!(
            "{option}: expected a number from {lo} to {hi}, got '{w}'"
        )),
    }
}

impl AmbientSettings {
    /// Try to apply one option at `words[0]`: `Ok(Some(words consumed))`, `Ok(None)` when it
    /// is not one of these options, or an error naming the option and the bad value.
    pub fn apply_option(&mut self, words: &[String]) -> Result<Option<usize>, String> {
        let Some(o) = words.first().map(String::as_str) else {
            return Ok(None);
        };
        if !OPTION_NAMES.contains(&o) {
            return Ok(None);
        }
        let Some(w) = words.get(1).map(String::as_str) else {
            return Err(format!("{o}: missing value"));
        };
        match o {
            "--amb-share-max" => self.share_max = number(o, w, 1.0, SHARE_LIMIT)?,
            "--amb-as0-split" => self.as0_split = number(o, w, 0.0, AS0_SPLIT_LIMIT)?,
            "--amb-hessian" => self.hessian = on_off(o, w)?,
            "--amb-reach" => self.reach = on_off(o, w)?,
            "--amb-gradients" => self.gradients = on_off(o, w)?,
            "--amb-gradient-radii" => self.gradient_radii = on_off(o, w)?,
            "--amb-glow-sampling" => self.glow_sampling = on_off(o, w)?,
            "--amb-corral" => self.corral = on_off(o, w)?,
            "--amb-shadow-reuse" => self.shadow_reuse = on_off(o, w)?,
            "--amb-shadow-trust" => {
                let max = crate::light::viscache::TRUST_MAX;
                self.shadow_trust = match w.parse::<u16>() {
                    Ok(n) if (1..=max).contains(&n) => n,
                    _ => return Err(format!("{o}: expected a count from 1 to {max}, got '{w}'")),
                }
            }
            "--amb-hessian-cells" => {
                self.hessian_cells = match w.parse::<usize>() {
                    Ok(n) if n >= HESSIAN_CELLS_MIN => n,
                    _ => {
                        return Err(format!(
                            "{o}: expected a count of at least {HESSIAN_CELLS_MIN}, got '{w}'"
                        ))
                    }
                }
            }
            "--amb-outlier-limit" => self.outlier_limit = number(o, w, 0.0, 1e6)?,
            "--amb-ss-own" => self.ss_own = on_off(o, w)?,
            _ => unreachable!("every name in OPTION_NAMES has a branch"),
        }
        Ok(Some(2))
    }

    /// Every setting as option words (shortest round-trip numbers), in [`OPTION_NAMES`]
    /// order: the text of picture headers, `--stats` and ambient stores.
    pub fn to_words(&self) -> Vec<String> {
        let b = |v: bool| if v { "on" } else { "off" }.to_string();
        let values = [
            format!("{}", self.share_max),
            format!("{}", self.as0_split),
            b(self.hessian),
            b(self.reach),
            b(self.gradients),
            b(self.gradient_radii),
            b(self.glow_sampling),
            b(self.corral),
            b(self.shadow_reuse),
            format!("{}", self.shadow_trust),
            format!("{}", self.hessian_cells),
            format!("{}", self.outlier_limit),
            b(self.ss_own),
        ];
        OPTION_NAMES
            .iter()
            .zip(values)
            .flat_map(|(n, v)| [n.to_string(), v])
            .collect()
    }

    /// [`AmbientSettings::to_words`] as one line.
    pub fn to_text(&self) -> String {
        self.to_words().join(" ")
    }
}

/// The one rule for "are ambient values cached?": with `-ab` > 0 and `-ad` > 0, `-aa` above
/// this caches values; at or below it every ambient request is a fresh Monte Carlo estimate
/// (Radiance's `ambacc <= FTINY`), and no store is read, written or shared.
pub const CACHE_MIN_AA: f64 = FTINY;

/// Whether the ambient calculation runs at all (`-ab` > 0 and `-ad` > 0); else the constant
/// `-av` serves.
pub fn computes(ab: i32, ad: i32) -> bool {
    ab > 0 && ad > 0
}

/// Whether the ambient calculation caches its values (see [`CACHE_MIN_AA`]).
pub fn caches(ab: i32, ad: i32, aa: f64) -> bool {
    computes(ab, ad) && aa > CACHE_MIN_AA
}

#[cfg(test)]
mod tests {
    use super::*;

    fn words(s: &str) -> Vec<String> {
        s.split_whitespace().map(String::from).collect()
    }

    #[test]
    fn options_round_trip_through_their_words() {
        let mut s = AmbientSettings::default();
        let w = words(
            "--amb-share-max 1.5 --amb-as0-split 0 --amb-hessian off --amb-reach off \
             --amb-gradients off --amb-gradient-radii on --amb-glow-sampling off \
             --amb-corral off --amb-shadow-reuse off --amb-shadow-trust 9 --amb-hessian-cells 64 \
             --amb-outlier-limit 0 --amb-ss-own off",
        );
        let mut i = 0;
        while i < w.len() {
            i += s.apply_option(&w[i..]).unwrap().unwrap();
        }
        assert_eq!(s.to_words(), w);
        let mut back = AmbientSettings::default();
        let w2 = s.to_words();
        let mut i = 0;
        while i < w2.len() {
            i += back.apply_option(&w2[i..]).unwrap().unwrap();
        }
        assert_eq!(back, s);
        assert_ne!(s, AmbientSettings::default());
    }

    #[test]
    fn bad_values_are_refused_with_the_option_named() {
        let mut s = AmbientSettings::default();
        for bad in [
            "--amb-share-max 0.5",
            "--amb-share-max 5",
            "--amb-share-max nan",
            "--amb-as0-split 0.95",
            "--amb-corral maybe",
            "--amb-hessian-cells 4",
            "--amb-shadow-trust 0",
            "--amb-shadow-trust 32",
            "--amb-shadow-trust 2.5",
            "--amb-outlier-limit -1",
            "--amb-reach",
        ] {
            let e = s.apply_option(&words(bad)).unwrap_err();
            assert!(e.starts_with(bad.split(' ').next().unwrap()), "{bad}: {e}");
        }
        assert_eq!(s, AmbientSettings::default());
        assert_eq!(s.apply_option(&words("-ab 2")).unwrap(), None);
    }

    #[test]
    fn one_rule_decides_caching() {
        assert!(caches(1, 512, 0.2));
        assert!(!caches(1, 512, 0.0));
        assert!(!caches(1, 512, 1e-7));
        assert!(!caches(0, 512, 0.2));
        assert!(!caches(1, 0, 0.2));
        assert!(computes(1, 512) && !computes(0, 512));
    }
}
