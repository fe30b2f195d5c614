//! rad's last step for a job made from a `.rif` file: the rendered (supersampled) picture is
//! reduced and exposed as rad's `pfilt [-1 -e EXPOSURE] [-r .6 | -m .25] -x /m -y /m` makes
//! it, so that `tassemble` writes the picture rad would (`tassemble --raw` keeps the
//! rendered one).
//!
//! The reduction is pfilt's box filter: output pixel `j` of a row averages the input pixels
//! `i` with `⌊i·out/in⌋ = j` (columns left to right, scanlines from the top), the output
//! size `in/m` rounded to the nearest integer, as real pfilt's box filter does. rad asks
//! pfilt for a Gaussian (`-r .6`, medium quality) or its variant (`-m .25`, high) instead:
//! those spread each input pixel a little wider; the box keeps every pixel's own light (see
//! docs/rif.md for the measured difference). `EXPOSURE` multiplies the pixels and is
//! recorded in the header (`EXPOSURE=`), as pfilt does. Without `EXPOSURE` rad's pfilt sets
//! an exposure from the picture's average; that automatic exposure is not applied (the
//! picture keeps its radiances).

use crate::image::Image;
use anyhow::{bail, Result};
use serde::{Deserialize, Serialize};

/// The finishing step of a rif job's frames.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Finish {
    /// rad's supersampling factor (1, 2 or 3): the picture is reduced by it.
    pub reduce: usize,
    /// The rif's EXPOSURE as a multiplier, when it sets one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub exposure: Option<f64>,
    /// rad's pfilt options (for the record and the header).
    pub pfilt: Vec<String>,
}

/// An EXPOSURE value as pfilt reads it: `+n`/`-n` are f-stops, anything else a multiplier.
pub fn parse_exposure(s: &str) -> Result<f64> {
    let t = s.trim();
    let v = if t.starts_with('+') || t.starts_with('-') {
        let stops: f64 = t
            .parse()
            .map_err(|_| anyhow::anyhow!("EXPOSURE '{s}' is not a number"))?;
        stops.exp2()
    } else {
        t.parse()
            .map_err(|_| anyhow::anyhow!("EXPOSURE '{s}' is not a number"))?
    };
    if !(v.is_finite() && v > 0.0) {
        bail!("EXPOSURE '{s}' must give a positive, finite multiplier");
    }
    Ok(v)
}

impl Finish {
    /// The step for rad's supersampling factor and pfilt options (as `RadPlan` holds
    /// them); the options Tessera does not apply are returned as warnings.
    pub fn from_rad(reduce: usize, pfilt: &[String]) -> Result<(Finish, Vec<String>)> {
        let mut exposure = None;
        let mut warnings = Vec::new();
        let mut i = 0;
        while i < pfilt.len() {
            match pfilt[i].as_str() {
                "-1" => {}
                "-e" => {
                    let Some(v) = pfilt.get(i + 1) else {
                        bail!("pfilt's -e needs a value");
                    };
                    let e = parse_exposure(v)?;
                    exposure = Some(exposure.unwrap_or(1.0) * e);
                    i += 1;
                }
                "-r" | "-m" => {
                    i += 1;
                }
                w => warnings.push(format!(
                    "rad's pfilt option '{w}' is not applied by tassemble (only the exposure \
                     and the reduction are)"
                )),
            }
            i += 1;
        }
        let f = Finish {
            reduce,
            exposure,
            pfilt: pfilt.to_vec(),
        };
        f.validate()?;
        Ok((f, warnings))
    }

    /// Check a step read from a manifest.
    pub fn validate(&self) -> Result<()> {
        if !(1..=3).contains(&self.reduce) {
            bail!("finish.reduce must be 1, 2 or 3, not {}", self.reduce);
        }
        if let Some(e) = self.exposure {
            if !(e.is_finite() && e > 0.0) {
                bail!("finish.exposure must be positive and finite");
            }
        }
        Ok(())
    }

    /// True when the step changes the picture.
    pub fn changes(&self) -> bool {
        self.reduce > 1 || self.exposure.is_some_and(|e| e != 1.0)
    }

    /// The finished picture: reduced, exposed, its header saying so.
    pub fn apply(&self, img: &Image) -> Image {
        let m = self.reduce.max(1);
        let (w, h) = (img.width, img.height);
        let ow = ((w as f64 / m as f64 + 0.5) as usize).clamp(1, w.max(1));
        let oh = ((h as f64 / m as f64 + 0.5) as usize).clamp(1, h.max(1));
        let mut sum = vec![[0f64; 4]; ow * oh];
        for y in 0..h {
            let oy = y * oh / h;
            for x in 0..w {
                let ox = x * ow / w;
                let p = img.pixels[y * w + x];
                let s = &mut sum[oy * ow + ox];
                s[0] += p[0] as f64;
                s[1] += p[1] as f64;
                s[2] += p[2] as f64;
                s[3] += 1.0;
            }
        }
        let e = self.exposure.unwrap_or(1.0);
        let mut out = Image::new(ow, oh);
        for (o, s) in out.pixels.iter_mut().zip(&sum) {
            let n = s[3].max(1.0);
            let v = |c: f64| {
                let v = c / n * e;
                if v.is_finite() {
                    v.clamp(0.0, f32::MAX as f64) as f32
                } else {
                    0.0
                }
            };
            *o = [v(s[0]), v(s[1]), v(s[2])];
        }
        out.header = img.header.clone();
        out.header.exposure = img.header.exposure * e;
        let mut words = vec!["pfilt".to_string()];
        words.extend(self.pfilt.iter().cloned());
        if m > 1 {
            words.extend([format!("-x /{m}"), format!("-y /{m}")]);
        }
        out.header.commands.push(format!(
            "{} (applied by tassemble: box reduction{})",
            words.join(" "),
            if self.exposure.is_some() {
                ", exposure"
            } else {
                ""
            }
        ));
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exposures_read_as_pfilt_reads_them() {
        assert_eq!(parse_exposure("+1").unwrap(), 2.0);
        assert_eq!(parse_exposure("-2").unwrap(), 0.25);
        assert_eq!(parse_exposure("0.5").unwrap(), 0.5);
        assert!(parse_exposure("0").is_err());
        assert!(parse_exposure("x").is_err());
        assert!(parse_exposure("+1e9").is_err());
    }

    #[test]
    fn reduction_averages_pfilts_boxes() {
        // 7 x 5 with red = x, green = row from the top: /2 gives 4 x 3 (rounded), each
        // output pixel the mean of the inputs i with floor(i * out / in) equal to it.
        let mut img = Image::new(7, 5);
        for y in 0..5 {
            for x in 0..7 {
                img.pixels[y * 7 + x] = [x as f32, y as f32, 1.0];
            }
        }
        let (f, warn) = Finish::from_rad(2, &["-1".into(), "-e".into(), "+1".into()]).unwrap();
        assert!(warn.is_empty());
        let out = f.apply(&img);
        assert_eq!((out.width, out.height), (4, 3));
        let reds: Vec<f32> = out.pixels[..4].iter().map(|p| p[0]).collect();
        assert_eq!(reds, [1.0, 5.0, 9.0, 12.0]);
        let greens: Vec<f32> = (0..3).map(|r| out.pixels[r * 4][1]).collect();
        assert_eq!(greens, [1.0, 5.0, 8.0]);
        assert_eq!(out.header.exposure, 2.0);
        // The options tassemble does not apply are named.
        let (_, warn) = Finish::from_rad(1, &["-h".into()]).unwrap();
        assert_eq!(warn.len(), 1);
        assert!(Finish::from_rad(4, &[]).is_err());
    }
}
