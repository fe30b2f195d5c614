//! The picture parameters: what a picture looks like without changing the light transport:
//! the view (`-v*`, `-vf`), the resolution (`-x`, `-y`), the pixel options (`-pa -pj -pm -pd
//! -ps -pt`, `-pRGB`) and the ambient overture (`--no-overture`). Kept in job manifests.

use std::path::Path;

use super::render::RenderParams;
use super::words::{arg, f1, i1, range, unsupported, OptError};
use crate::render::picture::FrameSetup;
use crate::view::{read_view_file, View, ViewFrame};

/// How a picture is made from the scene's light: view, resolution and pixel sampling.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PictureParams {
    /// The view (`-v*`, `-vf`).
    pub view: View,
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
    /// Fill the ambient cache in an overture pass before the picture's own pass (default;
    /// `--no-overture` turns it off). See [`PictureParams::overture_step`]. Manifests written
    /// before the option existed read as on.
    #[serde(default = "default_true")]
    pub overture: bool,
    /// `--same-seeds`: pixel samples are seeded by their position alone, not by the frame,
    /// so that what stays still in an animation is sampled the same way in every frame
    /// (less flicker; docs/animation.md). Off: each frame has its own samples, as rpict.
    #[serde(default)]
    pub same_seeds: bool,
}

fn default_true() -> bool {
    true
}

impl Default for PictureParams {
    /// rpict's defaults.
    fn default() -> Self {
        PictureParams {
            view: View::default(),
            x: 512,
            y: 512,
            pa: 1.0,
            pj: 0.67,
            pm: 0.0,
            pd: 0.0,
            ps: 4,
            pt: 0.05,
            overture: true,
            same_seeds: false,
        }
    }
}

impl PictureParams {
    /// Try to apply one picture option at `words[0]` (the view's own options `-v?` are
    /// applied by [`View::apply_option`] first). Returns `Ok(Some(n_words_consumed))` if it
    /// was a picture option, `Ok(None)` if not.
    pub fn apply_option(&mut self, words: &[String]) -> Result<Option<usize>, OptError> {
        let Some(w) = words.first() else {
            return Ok(None);
        };
        let w = w.as_str();
        let inf = f64::INFINITY;
        let n = match w {
            "-vf" => {
                let f = arg(words, 1, "a view file name")?;
                self.view = read_view_file(Path::new(f), &self.view)?;
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
                    self.x = v
                } else {
                    self.y = v
                }
                2
            }
            "-pa" => {
                self.pa = range(w, f1(words)?, 0.0, inf)?;
                2
            }
            "-pj" => {
                self.pj = range(w, f1(words)?, 0.0, 1.0)?;
                2
            }
            "-pm" => {
                self.pm = range(w, f1(words)?, 0.0, inf)?;
                2
            }
            "-pd" => {
                self.pd = range(w, f1(words)?, 0.0, inf)?;
                2
            }
            "-ps" => {
                let v: usize = i1(words)?;
                range(w, v as f64, 1.0, 16.0)?;
                self.ps = v;
                2
            }
            "-pt" => {
                self.pt = range(w, f1(words)?, 0.0, inf)?;
                2
            }
            "-pRGB" => 1,
            "-pXYZ" | "-pc" => {
                return Err(unsupported(w, "only RGB output (-pRGB) is implemented"));
            }
            "--no-overture" => {
                self.overture = false;
                1
            }
            "--same-seeds" => {
                self.same_seeds = true;
                1
            }
            _ => return Ok(None),
        };
        Ok(Some(n))
    }

    /// The parameters as option words (shortest round-trip number forms).
    pub fn to_words(&self) -> Vec<String> {
        let mut w = self.view.to_words();
        let s = |v: &dyn std::fmt::Display| v.to_string();
        w.extend([
            "-x".into(),
            s(&self.x),
            "-y".into(),
            s(&self.y),
            "-pa".into(),
            s(&self.pa),
            "-pj".into(),
            s(&self.pj),
            "-pm".into(),
            s(&self.pm),
            "-pd".into(),
            s(&self.pd),
            "-ps".into(),
            s(&self.ps),
            "-pt".into(),
            s(&self.pt),
        ]);
        if !self.overture {
            w.push("--no-overture".into());
        }
        if self.same_seeds {
            w.push("--same-seeds".into());
        }
        w
    }

    /// Pixel step of the overture pass ([`crate::render::FrameSetup::overture`]): the `-ps`
    /// spacing when the ambient values are cached (`-ab > 0`, `-aa > 0`, `-ad > 0`) and the
    /// overture is on, else 0 (no overture).
    pub fn overture_step(&self, p: &RenderParams) -> usize {
        if self.overture && crate::ambient::settings::caches(p.ab, p.ad, p.aa) {
            self.ps.max(1)
        } else {
            0
        }
    }

    /// The pixel loop's set-up for one frame of `xres` × `yres` pixels seen through `view`.
    pub fn frame_setup<'a>(
        &self,
        params: &RenderParams,
        view: &'a ViewFrame,
        (xres, yres): (usize, usize),
        frame: u32,
    ) -> FrameSetup<'a> {
        FrameSetup {
            view,
            xres,
            yres,
            pj: self.pj,
            ps: self.ps,
            pt: self.pt,
            frame: if self.same_seeds { 0 } else { frame },
            irradiance: params.i,
            overture: self.overture_step(params),
            aa: None,
        }
    }
}
