//! Keyframed camera paths: `tplan --path KEYFILE --path-frames N` makes an animation of N
//! frames from a few key views (docs/animation.md). Key views are read like a frames file
//! (one view line each, `rview -vp ...`, `VIEW= ...` or bare options, each on top of the
//! previous); frames are spread evenly over the path,
//! the view point on a Catmull–Rom spline through the key points (so the camera moves
//! smoothly through every key), the direction, up vector and sizes interpolated between
//! neighbouring keys.

use crate::view::{parse_view_line, View};
use anyhow::{anyhow, bail, Context, Result};
use glam::DVec3;

/// Read key views from a file of view lines (each applied on top of the previous, the
/// first on top of `base`).
pub fn read_keys(path: &str, base: &View) -> Result<Vec<View>> {
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {path}"))?;
    let mut keys = Vec::new();
    let mut cur = base.clone();
    for (i, line) in text.lines().enumerate() {
        // View lines as in view files (`rview -vp ...`, `VIEW= ...`), or bare options.
        let line = if line.trim_start().starts_with('-') {
            format!("rview {line}")
        } else {
            line.to_string()
        };
        if let Some(v) =
            parse_view_line(&line, &cur).map_err(|e| anyhow!("{path}:{}: {e}", i + 1))?
        {
            v.frame()
                .map_err(|e| anyhow!("{path}:{}: bad view: {e}", i + 1))?;
            cur = v.clone();
            keys.push(v);
        }
    }
    if keys.len() < 2 {
        bail!(
            "{path}: a path needs at least two key views (found {})",
            keys.len()
        );
    }
    Ok(keys)
}

fn catmull_rom(p0: DVec3, p1: DVec3, p2: DVec3, p3: DVec3, t: f64) -> DVec3 {
    let t2 = t * t;
    let t3 = t2 * t;
    0.5 * ((2.0 * p1)
        + (p2 - p0) * t
        + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * t2
        + (3.0 * p1 - p0 - 3.0 * p2 + p3) * t3)
}

/// The view at `s` in [0, 1] along the path through `keys`.
pub fn view_at(keys: &[View], s: f64) -> View {
    let n = keys.len();
    let x = s.clamp(0.0, 1.0) * (n - 1) as f64;
    let i = (x.floor() as usize).min(n - 2);
    let t = x - i as f64;
    let (a, b) = (&keys[i], &keys[i + 1]);
    // Frames on a key are that key exactly.
    if t < 1e-12 {
        return a.clone();
    }
    if t > 1.0 - 1e-12 {
        return b.clone();
    }
    let p0 = keys[i.saturating_sub(1)].vp;
    let p3 = keys[(i + 2).min(n - 1)].vp;
    let lerp = |x: f64, y: f64| x + (y - x) * t;
    let dir = |u: DVec3, w: DVec3| {
        let v = u.normalize_or_zero().lerp(w.normalize_or_zero(), t);
        let len = lerp(u.length(), w.length());
        if v.length_squared() > 1e-24 {
            v.normalize() * len
        } else {
            u
        }
    };
    let mut v = if t < 0.5 { a.clone() } else { b.clone() };
    v.vp = catmull_rom(p0, a.vp, b.vp, p3, t);
    v.vd = dir(a.vd, b.vd);
    v.vu = dir(a.vu, b.vu);
    v.vh = lerp(a.vh, b.vh);
    v.vv = lerp(a.vv, b.vv);
    v.vo = lerp(a.vo, b.vo);
    v.va = lerp(a.va, b.va);
    v.vs = lerp(a.vs, b.vs);
    v.vl = lerp(a.vl, b.vl);
    v
}

/// Most frames of a job (task names have five digits).
pub const MAX_FRAMES: usize = 99_999;

/// `frames` views evenly spread along the path (the first and last are the end keys).
pub fn frames(keys: &[View], frames: usize) -> Result<Vec<View>> {
    if frames < 2 {
        bail!("a path needs at least 2 frames");
    }
    // Checked before any view is made: a job holds at most this many frames.
    if frames > MAX_FRAMES {
        bail!("--path-frames {frames}: a job holds at most {MAX_FRAMES} frames");
    }
    (0..frames)
        .map(|k| {
            let v = view_at(keys, k as f64 / (frames - 1) as f64);
            v.frame()
                .map(|_| v.clone())
                .map_err(|e| anyhow!("frame {k} of the path: bad view: {e}"))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(x: f64, dx: f64) -> View {
        View {
            vp: DVec3::new(x, 0.0, 1.0),
            vd: DVec3::new(dx, 1.0, 0.0),
            ..View::default()
        }
    }

    #[test]
    fn the_path_passes_through_every_key() {
        let keys = [key(0.0, 0.0), key(1.0, 1.0), key(3.0, 0.0)];
        let v = frames(&keys, 5).unwrap();
        assert_eq!(v.len(), 5);
        assert!((v[0].vp - keys[0].vp).length() < 1e-12);
        assert!((v[2].vp - keys[1].vp).length() < 1e-12);
        assert!((v[4].vp - keys[2].vp).length() < 1e-12);
        assert!((v[2].vd.normalize() - keys[1].vd.normalize()).length() < 1e-12);
        // Between keys the camera moves on: x grows monotonically here.
        assert!(v.windows(2).all(|w| w[1].vp.x > w[0].vp.x));
        assert!(frames(&keys, 1).is_err());
    }
}
