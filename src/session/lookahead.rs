//! Moving-direction accuracy (`-axm`): whether a region of a frame is still seen some frames
//! later (docs/animation.md).

use super::{Region, Session};
use crate::render::ray::Ray;
use crate::view::ViewFrame;

/// Sample points per side of a region.
const GRID: usize = 4;

impl Session {
    /// The share of the surface points seen through a `GRID`×`GRID` grid over region `r` of a
    /// frame (view `now` at `res`) that are also seen from the view `later`: inside its
    /// picture, in front of it and not hidden by anything nearer. Points on the background
    /// (nothing hit) are left out; 1 when every point is background.
    pub fn share_still_seen(
        &self,
        now: &ViewFrame,
        res: (usize, usize),
        r: Region,
        later: &ViewFrame,
    ) -> f64 {
        let tracer = self.tracer();
        let origin = self.scene.origin;
        let (w, h) = ((r.x1 - r.x0) as f64, (r.y1 - r.y0) as f64);
        let (mut hits, mut seen) = (0usize, 0usize);
        for j in 0..GRID {
            for i in 0..GRID {
                let px = r.x0 as f64 + (i as f64 + 0.5) * w / GRID as f64;
                let py = r.y0 as f64 + (j as f64 + 0.5) * h / GRID as f64;
                // Regions count rows from the top, views from the bottom.
                let Some((org, dir, tmax)) = now.ray(px / res.0 as f64, 1.0 - py / res.1 as f64)
                else {
                    continue;
                };
                let Some(hit) = tracer.intersect(&Ray::primary(org - origin, dir, tmax)) else {
                    continue;
                };
                hits += 1;
                let p = hit.point + origin;
                let Some((x, y, d)) = later.locate(p) else {
                    continue;
                };
                if !((0.0..=1.0).contains(&x) && (0.0..=1.0).contains(&y) && d > 0.0) {
                    continue;
                }
                let Some((lorg, ldir, _)) = later.ray(x, y) else {
                    continue;
                };
                let back = Ray::primary(lorg - origin, ldir, f64::INFINITY);
                let hidden = tracer
                    .intersect(&back)
                    .is_some_and(|b| b.t < (p - lorg).length() * (1.0 - 1e-6) - self.scene.eps);
                if !hidden {
                    seen += 1;
                }
            }
        }
        if hits == 0 {
            1.0
        } else {
            seen as f64 / hits as f64
        }
    }
}
