//! `tgrid`: sensor points on a work plane, one ray record per point for `ttrace -I` or
//! `tplan --points`: a square lattice of the given spacing over a rectangle or a polygon
//! outline (a room's plan), at a height, kept a distance from the outline, facing a normal.

use anyhow::{bail, Result};
use clap::Parser;

/// `tgrid`: work-plane sensor points.
#[derive(Parser, Debug)]
#[command(
    name = "tgrid",
    version,
    about = "Sensor points on a work plane (x y z nx ny nz per line) for ttrace -I or tplan --points"
)]
pub struct GridArgs {
    /// The outline in plan: x,y corners in order (at least three),
    /// e.g. "0,0 6,0 6,5 0,5".
    #[arg(
        verbatim_doc_comment,
        long,
        value_name = "\"X,Y X,Y ...\"",
        conflicts_with = "rect",
        required_unless_present = "rect"
    )]
    polygon: Option<String>,
    /// A rectangle in plan: X0 Y0 X1 Y1.
    #[arg(long, num_args = 4, value_names = ["X0", "Y0", "X1", "Y1"], allow_negative_numbers = true, verbatim_doc_comment)]
    rect: Option<Vec<f64>>,
    /// Distance between neighbouring points.
    #[arg(long, default_value_t = 0.5, verbatim_doc_comment)]
    spacing: f64,
    /// Height of the work plane (z).
    #[arg(
        long,
        default_value_t = 0.8,
        allow_negative_numbers = true,
        verbatim_doc_comment
    )]
    height: f64,
    /// Least distance from a point to the outline (default: half the
    /// spacing).
    #[arg(long, verbatim_doc_comment)]
    offset: Option<f64>,
    /// The sensors' normal (the direction of each
    /// record).
    #[arg(long, num_args = 3, value_names = ["NX", "NY", "NZ"], allow_negative_numbers = true, default_values_t = [0.0, 0.0, 1.0], verbatim_doc_comment)]
    normal: Vec<f64>,
}

/// Most points one grid may hold.
pub const MAX_POINTS: usize = 50_000_000;

/// The outline's corners.
fn outline(a: &GridArgs) -> Result<Vec<(f64, f64)>> {
    let pts: Vec<(f64, f64)> = match (&a.polygon, &a.rect) {
        (Some(p), _) => p
            .split_whitespace()
            .map(|w| {
                let (x, y) = w
                    .split_once(',')
                    .ok_or_else(|| anyhow::anyhow!("--polygon: '{w}' is not x,y"))?;
                let (x, y): (f64, f64) = (
                    x.trim()
                        .parse()
                        .map_err(|_| anyhow::anyhow!("--polygon: '{x}' is not a number"))?,
                    y.trim()
                        .parse()
                        .map_err(|_| anyhow::anyhow!("--polygon: '{y}' is not a number"))?,
                );
                Ok((x, y))
            })
            .collect::<Result<_>>()?,
        (None, Some(r)) => vec![(r[0], r[1]), (r[2], r[1]), (r[2], r[3]), (r[0], r[3])],
        (None, None) => bail!("give --polygon or --rect"),
    };
    if pts.len() < 3 {
        bail!("the outline needs at least three corners");
    }
    if pts.iter().any(|(x, y)| !(x.is_finite() && y.is_finite())) {
        bail!("the outline's coordinates must be finite");
    }
    Ok(pts)
}

/// Even-odd point-in-polygon test.
fn inside(p: (f64, f64), poly: &[(f64, f64)]) -> bool {
    let mut c = false;
    let n = poly.len();
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + n - 1) % n]);
        if (a.1 > p.1) != (b.1 > p.1) {
            let x = a.0 + (p.1 - a.1) * (b.0 - a.0) / (b.1 - a.1);
            if p.0 < x {
                c = !c;
            }
        }
    }
    c
}

/// Distance from `p` to the segment `a`–`b`.
fn seg_dist(p: (f64, f64), a: (f64, f64), b: (f64, f64)) -> f64 {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let l2 = dx * dx + dy * dy;
    let t = if l2 > 0.0 {
        (((p.0 - a.0) * dx + (p.1 - a.1) * dy) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (x, y) = (a.0 + t * dx - p.0, a.1 + t * dy - p.1);
    (x * x + y * y).sqrt()
}

/// The grid's points (x, y) in plan: a lattice of `spacing` from the outline's lower-left
/// corner plus half a spacing, the points inside the outline and at least `offset` from it.
pub fn points(poly: &[(f64, f64)], spacing: f64, offset: f64) -> Result<Vec<(f64, f64)>> {
    if !(spacing.is_finite() && spacing > 0.0) {
        bail!("--spacing must be positive");
    }
    if !(offset.is_finite() && offset >= 0.0) {
        bail!("--offset must be zero or positive");
    }
    let (x0, x1) = poly
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p.0), b.max(p.0)));
    let (y0, y1) = poly
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p.1), b.max(p.1)));
    let (nx, ny) = (((x1 - x0) / spacing).ceil(), ((y1 - y0) / spacing).ceil());
    if nx * ny > MAX_POINTS as f64 {
        bail!("{nx} x {ny} lattice points: more than {MAX_POINTS}; use a larger --spacing");
    }
    let n = poly.len();
    let mut out = Vec::new();
    for i in 0..nx as usize {
        for j in 0..ny as usize {
            let p = (
                x0 + spacing * (i as f64 + 0.5),
                y0 + spacing * (j as f64 + 0.5),
            );
            if !inside(p, poly) {
                continue;
            }
            let d = (0..n)
                .map(|k| seg_dist(p, poly[k], poly[(k + 1) % n]))
                .fold(f64::INFINITY, f64::min);
            if d + 1e-9 * spacing >= offset {
                out.push(p);
            }
        }
    }
    Ok(out)
}

/// Run `tgrid`: the records on standard output.
pub fn tgrid(a: GridArgs) -> Result<i32> {
    let poly = outline(&a)?;
    let offset = a.offset.unwrap_or(a.spacing / 2.0);
    let pts = points(&poly, a.spacing, offset)?;
    let n = &a.normal;
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if !(len.is_finite() && len > 0.0 && a.height.is_finite()) {
        bail!("--normal must be a non-zero vector and --height finite");
    }
    if pts.is_empty() {
        bail!("no point of the lattice lies inside the outline at that offset");
    }
    let mut s = String::new();
    for (x, y) in pts {
        s.push_str(&format!(
            "{x} {y} {} {} {} {}\n",
            a.height,
            n[0] / len,
            n[1] / len,
            n[2] / len
        ));
    }
    let mut out = std::io::stdout().lock();
    std::io::Write::write_all(&mut out, s.as_bytes())?;
    Ok(0)
}

/// Entry point of `tgrid`.
pub fn tgrid_main() -> i32 {
    match tgrid(GridArgs::parse()) {
        Ok(c) => c,
        Err(e) => {
            eprintln!(
                "{}",
                crate::runinfo::printable(&format!("tgrid: error: {e:#}"))
            );
            1
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lattices_fill_outlines() {
        let room = [(0.0, 0.0), (6.0, 0.0), (6.0, 5.0), (0.0, 5.0)];
        let p = points(&room, 0.5, 0.25).unwrap();
        assert_eq!(p.len(), 12 * 10);
        assert_eq!(p[0], (0.25, 0.25));
        // An offset of one spacing drops the outer ring.
        assert_eq!(points(&room, 0.5, 0.5).unwrap().len(), 10 * 8);
        // An L-shaped plan: the cut-out corner holds no point.
        let l = [
            (0.0, 0.0),
            (4.0, 0.0),
            (4.0, 2.0),
            (2.0, 2.0),
            (2.0, 4.0),
            (0.0, 4.0),
        ];
        let p = points(&l, 1.0, 0.5).unwrap();
        assert_eq!(p.len(), 12);
        assert!(p.iter().all(|&(x, y)| !(x > 2.0 && y > 2.0)));
        assert!(points(&room, 0.0, 0.0).is_err());
        assert!(points(&room, 1e-4, 0.0).is_err());
    }
}
