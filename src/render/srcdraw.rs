//! Light sources smaller than a pixel, drawn by the area they cover.
//!
//! A pixel's value is one sample of the radiance it sees, so a luminaire narrower than a
//! pixel either falls between the samples (and vanishes from the picture) or is hit by one
//! (and fills its pixel with its full radiance). rpict draws such sources by coverage: a
//! pixel holds `(1 − c)·B + c·L`, with `c` the fraction of the pixel the source's projection
//! covers, `L` the source's radiance toward the view point and `B` the pixel's own sample,
//! or 0 when that sample landed on the source (measured: a 0.55-pixel square lamp of
//! radiance 100 on a background of 2 gives four pixels of 9.53 when it sits on their
//! common corner, two of 17.06 on an edge, one of 30.69 on the sample point; rpict 6.0a,
//! `-ps 1 -pj 0`). So the picture keeps each small source's light, wherever it falls.
//!
//! Tessera does the same for every source whose image is at most [`SMALL_PX`] pixels across
//! in its narrower direction: a local source's outline (a polygon's vertices, a ring's or
//! sphere's circle, else the hull of its bounding box), a distant source's disc. Each pixel
//! the outline touches is clipped against it; a primary ray toward the covered part's
//! centroid gives `L` where it reaches the source (an occluded part is left as sampled).
//! Every choice depends on the pixel alone (its sample point, its own random numbers), so
//! tiles and threads draw the same pixels.

use glam::DVec3;

use super::picture::FrameSetup;
use super::ray::Ray;
use super::sampler::Sampler;
use super::trace::Tracer;
use crate::color::Color;
use crate::geometry::SurfaceRef;
use crate::material::emitter::EmitterKind;

/// A source at most this many pixels across (in its narrower direction) is drawn.
pub const SMALL_PX: f64 = 2.0;

/// Most pixels one source's outline box may hold (a long thin source seen along its length
/// stops here).
const MAX_PIXELS: f64 = 4096.0;

/// Points on a circular outline.
const CIRCLE: usize = 24;

/// The random stream of a pixel's source rays (apart from its sample's).
const SALT: u32 = 0x5D_7A_11;

/// A source to draw: its index and its outline in pixels (x right, y down from the top).
#[derive(Clone, Debug)]
pub struct Drawn {
    /// Index into the light set's sources.
    pub src: usize,
    /// The outline, a simple polygon in pixel coordinates.
    pub outline: Vec<[f64; 2]>,
}

/// The sources of a frame to draw by coverage.
pub fn frame_sources(tr: &Tracer, fs: &FrameSetup) -> Vec<Drawn> {
    let mut out = Vec::new();
    if fs.irradiance {
        return out;
    }
    let (xres, yres) = (fs.xres as f64, fs.yres as f64);
    let vp = fs.view.view.vp;
    for (i, s) in tr.lights.sources.iter().enumerate() {
        if s.relay.is_some() || matches!(s.emitter.kind, EmitterKind::Illum { .. }) {
            continue;
        }
        let world = if let Some(o) = s.obj {
            let Some(obj) = tr.scene.objects.get(o) else {
                continue;
            };
            outline_of(tr.scene.objects.shape(obj), vp - tr.scene.origin)
                .into_iter()
                .map(|p| p + tr.scene.origin)
                .collect::<Vec<_>>()
        } else if let Some(d) = s.distant.and_then(|k| tr.scene.distant.get(k)) {
            let src = &d.source;
            if !(src.angle_deg > 0.0 && src.angle_deg < 90.0) {
                continue;
            }
            let r = (0.5 * src.angle_deg).to_radians().tan();
            circle(vp + src.dir, src.dir, r)
        } else {
            continue;
        };
        let mut pts = Vec::with_capacity(world.len());
        for p in &world {
            let Some((x, y, _)) = fs.view.locate(*p) else {
                pts.clear();
                break;
            };
            pts.push([x * xres, (1.0 - y) * yres]);
        }
        if pts.len() < 3 {
            continue;
        }
        if s.obj
            .is_some_and(|o| !is_outline_exact(tr.scene.objects.surface(o)))
        {
            pts = hull(pts);
        }
        let (lo, hi) = bounds(&pts);
        let (w, h) = (hi[0] - lo[0], hi[1] - lo[1]);
        if !(w.is_finite() && h.is_finite()) || w.min(h) > SMALL_PX || w * h > MAX_PIXELS {
            continue;
        }
        if hi[0] <= 0.0 || hi[1] <= 0.0 || lo[0] >= xres || lo[1] >= yres {
            continue;
        }
        out.push(Drawn {
            src: i,
            outline: pts,
        });
    }
    out
}

/// Whether [`outline_of`] is the surface's own outline (else the hull of its box).
fn is_outline_exact(s: SurfaceRef) -> bool {
    matches!(
        s,
        SurfaceRef::Polygon(_) | SurfaceRef::Ring(_) | SurfaceRef::Sphere(_)
    )
}

/// Points outlining a surface seen from `eye` (relative frame): a polygon's vertices, a
/// ring's outer circle, a sphere's silhouette circle, else its bounding box's corners.
fn outline_of(s: SurfaceRef, eye: DVec3) -> Vec<DVec3> {
    match s {
        SurfaceRef::Polygon(p) => p.verts().collect(),
        SurfaceRef::Ring(r) => circle(r.center, r.normal, r.r1.abs().max(r.r0.abs())),
        SurfaceRef::Sphere(sp) => {
            circle(sp.center, (sp.center - eye).normalize_or_zero(), sp.radius)
        }
        SurfaceRef::Cone(_) => {
            let (lo, hi) = s.bounds();
            box_corners(lo, hi).to_vec()
        }
    }
}

/// The eight corners of the box `[lo, hi]`.
pub fn box_corners(lo: DVec3, hi: DVec3) -> [DVec3; 8] {
    std::array::from_fn(|k| {
        DVec3::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        )
    })
}

/// [`CIRCLE`] points on the circle of radius `r` about `c` perpendicular to `n`.
fn circle(c: DVec3, n: DVec3, r: f64) -> Vec<DVec3> {
    let u = crate::geometry::any_perpendicular(n);
    let v = n.normalize_or_zero().cross(u);
    (0..CIRCLE)
        .map(|k| {
            let a = std::f64::consts::TAU * k as f64 / CIRCLE as f64;
            c + (u * a.cos() + v * a.sin()) * r
        })
        .collect()
}

fn bounds(pts: &[[f64; 2]]) -> ([f64; 2], [f64; 2]) {
    pts.iter().fold(
        ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
        |(lo, hi), p| {
            (
                [lo[0].min(p[0]), lo[1].min(p[1])],
                [hi[0].max(p[0]), hi[1].max(p[1])],
            )
        },
    )
}

/// Convex hull (Andrew's monotone chain), counter-clockwise.
fn hull(mut pts: Vec<[f64; 2]>) -> Vec<[f64; 2]> {
    pts.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    pts.dedup();
    if pts.len() < 3 {
        return pts;
    }
    let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    // The lower chain left to right, then the upper chain right to left; each drops its
    // last point, the first of the other.
    let mut h: Vec<[f64; 2]> = Vec::with_capacity(2 * pts.len());
    for &p in &pts {
        while h.len() >= 2 && cross(h[h.len() - 2], h[h.len() - 1], p) <= 0.0 {
            h.pop();
        }
        h.push(p);
    }
    h.pop();
    let lower = h.len();
    for &p in pts.iter().rev() {
        while h.len() >= lower + 2 && cross(h[h.len() - 2], h[h.len() - 1], p) <= 0.0 {
            h.pop();
        }
        h.push(p);
    }
    h.pop();
    h
}

/// The part of polygon `poly` inside the axis-aligned square `[x, x+1] × [y, y+1]`
/// (Sutherland–Hodgman: exact for a convex clip window, any simple subject).
fn clip_to_pixel(poly: &[[f64; 2]], x: f64, y: f64) -> Vec<[f64; 2]> {
    let mut cur = poly.to_vec();
    // (axis, bound, keep the side above the bound)
    for (axis, bound, above) in [
        (0, x, true),
        (0, x + 1.0, false),
        (1, y, true),
        (1, y + 1.0, false),
    ] {
        if cur.is_empty() {
            break;
        }
        let inside = |p: &[f64; 2]| {
            if above {
                p[axis] >= bound
            } else {
                p[axis] <= bound
            }
        };
        let mut next = Vec::with_capacity(cur.len() + 2);
        for i in 0..cur.len() {
            let a = cur[i];
            let b = cur[(i + 1) % cur.len()];
            let (ia, ib) = (inside(&a), inside(&b));
            if ia {
                next.push(a);
            }
            if ia != ib {
                let t = (bound - a[axis]) / (b[axis] - a[axis]);
                next.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
            }
        }
        cur = next;
    }
    cur
}

/// Area (absolute) and centroid of a polygon.
fn area_centroid(p: &[[f64; 2]]) -> (f64, [f64; 2]) {
    let (mut a, mut cx, mut cy) = (0.0, 0.0, 0.0);
    for i in 0..p.len() {
        let (q, r) = (p[i], p[(i + 1) % p.len()]);
        let c = q[0] * r[1] - r[0] * q[1];
        a += c;
        cx += (q[0] + r[0]) * c;
        cy += (q[1] + r[1]) * c;
    }
    if a.abs() < 1e-300 {
        let n = p.len().max(1) as f64;
        let m = p.iter().fold([0.0; 2], |s, q| [s[0] + q[0], s[1] + q[1]]);
        return (0.0, [m[0] / n, m[1] / n]);
    }
    (0.5 * a.abs(), [cx / (3.0 * a), cy / (3.0 * a)])
}

/// Even–odd point-in-polygon test.
fn contains(poly: &[[f64; 2]], p: [f64; 2]) -> bool {
    let mut inside = false;
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        if (a[1] > p[1]) != (b[1] > p[1]) {
            let x = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
            if p[0] < x {
                inside = !inside;
            }
        }
    }
    inside
}

/// Draw `sources` into the pixels of region `[x0, x1) × [y0, y1)` (`out`, row by row from
/// the top, `x1 − x0` wide).
pub fn draw(
    tr: &Tracer,
    fs: &FrameSetup,
    sources: &[Drawn],
    (x0, y0, x1, y1): (usize, usize, usize, usize),
    out: &mut [[f32; 3]],
    rays: &mut u64,
) {
    let w = x1.saturating_sub(x0);
    for d in sources {
        let (lo, hi) = bounds(&d.outline);
        let px0 = (lo[0].floor().max(0.0) as usize).max(x0);
        let py0 = (lo[1].floor().max(0.0) as usize).max(y0);
        let px1 = ((hi[0].ceil().max(0.0)) as usize).min(x1);
        let py1 = ((hi[1].ceil().max(0.0)) as usize).min(y1);
        let src = &tr.lights.sources[d.src];
        for py in py0..py1 {
            for px in px0..px1 {
                let part = clip_to_pixel(&d.outline, px as f64, py as f64);
                if part.len() < 3 {
                    continue;
                }
                let (c, at) = area_centroid(&part);
                if c.is_nan() || c <= 1e-9 {
                    continue;
                }
                let c = c.min(1.0);
                // The source's radiance where it covers this pixel, if nothing hides it.
                let (x, y) = (at[0] / fs.xres as f64, 1.0 - at[1] / fs.yres as f64);
                let Some((org, dir, tmax)) = fs.view.ray(x, y) else {
                    continue;
                };
                let ray = Ray::primary(org - tr.scene.origin, dir, tmax);
                let reaches = match (tr.intersect(&ray), src.obj) {
                    (Some(h), Some(o)) => h.is_top() && h.obj == o,
                    (None, None) => true,
                    _ => false,
                };
                if !reaches {
                    continue;
                }
                let mut rng = Sampler::for_pixel(fs.frame, px as u32, py as u32, SALT);
                let l = crate::color::sanitize(tr.trace(&ray, &mut rng));
                *rays += rng.rays;
                // Where the pixel's own sample landed, in pixels from the top left.
                let (_, sx, sy) = super::picture::sample_point(fs, px, py);
                let sample = [sx * fs.xres as f64, (1.0 - sy) * fs.yres as f64];
                let Some(pix) = out.get_mut((py - y0) * w + (px - x0)) else {
                    continue;
                };
                let b = if contains(&d.outline, sample) {
                    Color::ZERO
                } else {
                    Color::new(pix[0] as f64, pix[1] as f64, pix[2] as f64)
                };
                let v = b * (1.0 - c) + l * c;
                *pix = [v.x as f32, v.y as f32, v.z as f32];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coverage_of_a_square_over_pixels() {
        // A 0.5-pixel square on the corner of four pixels: a quarter each.
        let sq = vec![[0.75, 0.75], [1.25, 0.75], [1.25, 1.25], [0.75, 1.25]];
        let mut total = 0.0;
        for (x, y) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
            let (a, _) = area_centroid(&clip_to_pixel(&sq, x, y));
            assert!((a - 0.0625).abs() < 1e-12, "{a}");
            total += a;
        }
        assert!((total - 0.25).abs() < 1e-12);
        assert!(clip_to_pixel(&sq, 3.0, 3.0).len() < 3);
        assert!(contains(&sq, [1.0, 1.0]) && !contains(&sq, [0.5, 0.5]));
        let h = hull(vec![
            [0.0, 0.0],
            [1.0, 0.0],
            [0.5, 0.5],
            [1.0, 1.0],
            [0.0, 1.0],
        ]);
        assert_eq!(h.len(), 4);
        assert!((area_centroid(&h).0 - 1.0).abs() < 1e-12);
    }
}
