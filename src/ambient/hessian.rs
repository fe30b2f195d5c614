//! The irradiance Hessian of a new ambient value, which sets its anisotropic radii
//! (Schwarzhaupt, Jensen & Jarosz 2012, "Practical Hessian-Based Error Control for Irradiance
//! Caching").
//!
//! The hemisphere's hit points form a mesh seen from the shading point: two triangles per quad
//! of neighbouring cells (wrapping in φ) and one polygon closing the cap around the pole. Each
//! triangle radiates with the brightness of its farthest vertex, normalised so the mean cell
//! is 1, plus 0.01 (a black hemisphere gives the purely geometric Hessian). The irradiance of
//! that fixed mesh at a point displaced by δ = δu·U + δv·V in the tangent plane is Lambert's
//! contour integral, `F(δ) = (1/2π) Σ_triangles w_t |Σ_edges e(δ)|`, with, for an edge from
//! hit point A to C, `e(δ) = Θ · (N·X)/|X|`: X = (A−δ)×(C−δ) is the normal of the plane through
//! the point and the edge and `Θ = atan2(|X|, (A−δ)·(C−δ))` the angle the edge subtends.
//!
//! The Hessian is the exact second derivative of F at δ = 0, evaluated in one pass with
//! second-order Taylor jets ([`Jet`]): X is *linear* in δ (`X = A×C + (C−A)×δ`, the δ×δ term
//! vanishes), the dot product is quadratic (`A·C − δ·(A+C) + |δ|²`), so each edge needs one
//! `atan2`, one square root and a few dozen multiplications, and every edge is evaluated once
//! although two triangles share it. This is the quantity the paper differentiates
//! analytically, with visibility and hit points held fixed and the tangent plane unchanged by
//! a tangential displacement (every triangle stays above it).

use crate::FTINY;
use glam::DVec3;
use std::f64::consts::PI;
use std::ops::{Add, Mul, Sub};

/// A second-order Taylor jet of a function of the two tangent-plane offsets (δu, δv): its
/// value, gradient and Hessian at δ = 0. Arithmetic on jets applies the chain rule, so a
/// formula evaluated on jets yields its exact first and second derivatives.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Jet {
    /// Value.
    pub v: f64,
    /// ∂/∂δu.
    pub du: f64,
    /// ∂/∂δv.
    pub dv: f64,
    /// ∂²/∂δu².
    pub uu: f64,
    /// ∂²/∂δu∂δv.
    pub uv: f64,
    /// ∂²/∂δv².
    pub vv: f64,
}

impl Jet {
    /// A constant.
    pub fn constant(v: f64) -> Jet {
        Jet {
            v,
            ..Jet::default()
        }
    }

    /// φ(self) for a function φ with φ(v) = `f0`, φ'(v) = `f1`, φ''(v) = `f2`.
    fn chain(self, f0: f64, f1: f64, f2: f64) -> Jet {
        Jet {
            v: f0,
            du: f1 * self.du,
            dv: f1 * self.dv,
            uu: f2 * self.du * self.du + f1 * self.uu,
            uv: f2 * self.du * self.dv + f1 * self.uv,
            vv: f2 * self.dv * self.dv + f1 * self.vv,
        }
    }

    /// self × L for a function L linear in δ with value `l`, gradient (`lu`, `lv`) and no
    /// second derivatives (a cheaper [`Mul`]).
    #[inline]
    fn scale_linear(self, l: f64, lu: f64, lv: f64) -> Jet {
        Jet {
            v: self.v * l,
            du: self.du * l + self.v * lu,
            dv: self.dv * l + self.v * lv,
            uu: self.uu * l + 2.0 * self.du * lu,
            uv: self.uv * l + self.du * lv + self.dv * lu,
            vv: self.vv * l + 2.0 * self.dv * lv,
        }
    }

    /// √self (self.v > 0).
    pub fn sqrt(self) -> Jet {
        let r = self.v.sqrt();
        self.chain(r, 0.5 / r, -0.25 / (r * self.v))
    }

    /// 1/self (self.v ≠ 0).
    pub fn recip(self) -> Jet {
        let r = 1.0 / self.v;
        self.chain(r, -r * r, 2.0 * r * r * r)
    }

    /// atan2(self, x): the angle of the point (x, self).
    pub fn atan2(self, x: Jet) -> Jet {
        let y = self;
        let (x0, y0) = (x.v, y.v);
        let r2 = x0 * x0 + y0 * y0;
        let r4 = r2 * r2;
        // First and second partials of atan2(y, x).
        let (ty, tx) = (x0 / r2, -y0 / r2);
        let (tyy, txx, txy) = (
            -2.0 * x0 * y0 / r4,
            2.0 * x0 * y0 / r4,
            (y0 * y0 - x0 * x0) / r4,
        );
        let second = |yi: f64, yj: f64, xi: f64, xj: f64, yij: f64, xij: f64| {
            tyy * yi * yj + txy * (yi * xj + xi * yj) + txx * xi * xj + ty * yij + tx * xij
        };
        Jet {
            v: y0.atan2(x0),
            du: ty * y.du + tx * x.du,
            dv: ty * y.dv + tx * x.dv,
            uu: second(y.du, y.du, x.du, x.du, y.uu, x.uu),
            uv: second(y.du, y.dv, x.du, x.dv, y.uv, x.uv),
            vv: second(y.dv, y.dv, x.dv, x.dv, y.vv, x.vv),
        }
    }
}

impl Add for Jet {
    type Output = Jet;
    fn add(self, o: Jet) -> Jet {
        Jet {
            v: self.v + o.v,
            du: self.du + o.du,
            dv: self.dv + o.dv,
            uu: self.uu + o.uu,
            uv: self.uv + o.uv,
            vv: self.vv + o.vv,
        }
    }
}

impl Sub for Jet {
    type Output = Jet;
    fn sub(self, o: Jet) -> Jet {
        self + o * -1.0
    }
}

impl Mul for Jet {
    type Output = Jet;
    fn mul(self, o: Jet) -> Jet {
        Jet {
            v: self.v * o.v,
            du: self.du * o.v + self.v * o.du,
            dv: self.dv * o.v + self.v * o.dv,
            uu: self.uu * o.v + 2.0 * self.du * o.du + self.v * o.uu,
            uv: self.uv * o.v + self.du * o.dv + self.dv * o.du + self.v * o.uv,
            vv: self.vv * o.v + 2.0 * self.dv * o.dv + self.v * o.vv,
        }
    }
}

impl Mul<f64> for Jet {
    type Output = Jet;
    fn mul(self, k: f64) -> Jet {
        Jet {
            v: self.v * k,
            du: self.du * k,
            dv: self.dv * k,
            uu: self.uu * k,
            uv: self.uv * k,
            vv: self.vv * k,
        }
    }
}

/// What an edge term can be: a plain number or a jet. Triangles add their edges and take the
/// absolute value, which on a jet flips all its derivatives with its sign.
pub trait EdgeTerm:
    Copy + Default + Add<Output = Self> + Sub<Output = Self> + Mul<f64, Output = Self>
{
    /// The value (for the sign).
    fn value(self) -> f64;
}

impl EdgeTerm for f64 {
    fn value(self) -> f64 {
        self
    }
}

impl EdgeTerm for Jet {
    fn value(self) -> f64 {
        self.v
    }
}

/// The edge term `Θ·(N·X)/|X|` of the edge from `a` to `c` (hit points relative to the
/// shading point) as a jet in the point's tangent-plane offset along `u` and `v`
/// (an orthonormal frame with `n`).
pub fn edge_jet(a: DVec3, c: DVec3, n: DVec3, u: DVec3, v: DVec3) -> Jet {
    edge_jet_local(in_frame(a, n, u, v), in_frame(c, n, u, v))
}

/// `p` in the tangent frame: (p·u, p·v, p·n).
#[inline]
fn in_frame(p: DVec3, n: DVec3, u: DVec3, v: DVec3) -> DVec3 {
    DVec3::new(p.dot(u), p.dot(v), p.dot(n))
}

/// [`edge_jet`] with `a` and `c` given in the tangent frame itself (x along u, y along v,
/// z along the normal), where the frame's cross and dot products reduce to picking
/// components: with e = C − A, `X = A×C + e×δ`, `e×u = (0, e_z, −e_y)`,
/// `e×v = (−e_z, 0, e_x)`, `N·X = X_z`.
#[inline]
pub fn edge_jet_local(a: DVec3, c: DVec3) -> Jet {
    let x0 = a.cross(c);
    let e = c - a;
    let s2 = Jet {
        v: x0.length_squared(),
        du: 2.0 * (x0.y * e.z - x0.z * e.y),
        dv: 2.0 * (x0.z * e.x - x0.x * e.z),
        uu: 2.0 * (e.y * e.y + e.z * e.z),
        uv: -2.0 * e.x * e.y,
        vv: 2.0 * (e.x * e.x + e.z * e.z),
    };
    if s2.v < 1e-300 {
        return Jet::default();
    }
    // |X| and 1/|X| straight from |X|².
    let r = s2.v.sqrt();
    let ir = 1.0 / r;
    let s = s2.chain(r, 0.5 * ir, -0.25 * ir * ir * ir);
    let inv_s = s2.chain(ir, -0.5 * ir * ir * ir, 0.75 * ir * ir * ir * ir * ir);
    let d = Jet {
        v: a.dot(c),
        du: -(a.x + c.x),
        dv: -(a.y + c.y),
        uu: 2.0,
        uv: 0.0,
        vv: 2.0,
    };
    // N·X is linear in δ: (X0_z, −e_y, e_x) with no second derivatives.
    let g = inv_s.scale_linear(x0.z, -e.y, e.x);
    s.atan2(d) * g
}

/// The same edge term as a number, seen from the shading point itself.
pub fn edge_value(a: DVec3, c: DVec3, n: DVec3) -> f64 {
    let x = a.cross(c);
    let s = x.length();
    if s < 1e-150 {
        return 0.0;
    }
    s.atan2(a.dot(c)) * n.dot(x) / s
}

/// The hemisphere's mesh of hit points with its triangle weights.
pub struct Mesh<'a> {
    pts: &'a [DVec3],
    m: usize,
    nphi: usize,
    /// Weights of the two triangles of quad (j, k): (j,k)→(j,k+1)→(j+1,k+1) and
    /// (j,k)→(j+1,k+1)→(j+1,k).
    tw: Vec<[f64; 2]>,
    /// Weight of the cap around the pole (ring 0).
    cap_w: f64,
}

impl<'a> Mesh<'a> {
    /// The mesh of `pts[j*nphi + k]` (hit points relative to the shading point, m rings of
    /// nphi cells) with brightness `b`; None for a degenerate one.
    pub fn new(pts: &'a [DVec3], b: &[f64], m: usize, nphi: usize) -> Option<Mesh<'a>> {
        let nc = m * nphi;
        if m < 2 || nphi < 3 || pts.len() != nc || b.len() != nc {
            return None;
        }
        let dmin = pts.iter().map(|p| p.length()).fold(f64::INFINITY, f64::min);
        if !(dmin > 0.0 && dmin.is_finite()) {
            return None;
        }
        let bmean = b.iter().sum::<f64>() / nc as f64;
        let w = |i: usize| -> f64 {
            if bmean > FTINY {
                b[i] / bmean + 0.01
            } else {
                1.0
            }
        };
        let far = |ids: &[usize]| -> usize {
            let mut f = ids[0];
            for &i in &ids[1..] {
                if pts[i].length_squared() > pts[f].length_squared() {
                    f = i;
                }
            }
            f
        };
        let at = |j: usize, k: usize| j * nphi + (k % nphi);
        let mut tw = vec![[0.0; 2]; (m - 1) * nphi];
        for j in 0..m - 1 {
            for k in 0..nphi {
                let (p00, p01, p10, p11) = (at(j, k), at(j, k + 1), at(j + 1, k), at(j + 1, k + 1));
                tw[j * nphi + k] = [w(far(&[p00, p01, p11])), w(far(&[p00, p11, p10]))];
            }
        }
        let ring0: Vec<usize> = (0..nphi).collect();
        let cap_w = w(far(&ring0));
        Some(Mesh {
            pts,
            m,
            nphi,
            tw,
            cap_w,
        })
    }

    /// 2π × the weighted projected solid angle of the mesh, from `edge(A, C)` evaluated once
    /// per edge: along φ (j,k)→(j,k+1), along θ (j,k)→(j+1,k), diagonal (j,k)→(j+1,k+1).
    pub fn contour<T: EdgeTerm>(&self, edge: impl Fn(DVec3, DVec3) -> T) -> T {
        let (m, nphi) = (self.m, self.nphi);
        let pts = self.pts;
        let ring = |j: usize, out: &mut Vec<T>| {
            out.clear();
            out.extend((0..nphi).map(|k| edge(pts[j * nphi + k], pts[j * nphi + (k + 1) % nphi])));
        };
        let abs = |t: T| if t.value() < 0.0 { t * -1.0 } else { t };
        // Edges along φ of the current and the next ring; along θ and diagonal of the current.
        let (mut eh, mut eh_next) = (Vec::with_capacity(nphi), Vec::with_capacity(nphi));
        let (mut ev, mut ed) = (Vec::with_capacity(nphi), Vec::with_capacity(nphi));
        ring(0, &mut eh);
        let cap = eh.iter().fold(T::default(), |s, &e| s + e);
        let mut f = abs(cap) * self.cap_w;
        for j in 0..m - 1 {
            ring(j + 1, &mut eh_next);
            ev.clear();
            ed.clear();
            for k in 0..nphi {
                let p = pts[j * nphi + k];
                ev.push(edge(p, pts[(j + 1) * nphi + k]));
                ed.push(edge(p, pts[(j + 1) * nphi + (k + 1) % nphi]));
            }
            for k in 0..nphi {
                let ta = eh[k] + ev[(k + 1) % nphi] - ed[k];
                let tb = ed[k] - eh_next[k] - ev[k];
                let [wa, wb] = self.tw[j * nphi + k];
                f = f + abs(ta) * wa + abs(tb) * wb;
            }
            std::mem::swap(&mut eh, &mut eh_next);
        }
        f
    }
}

/// The 2×2 tangent-plane Hessian `[h_uu, h_uv, h_vv]` (per unit length²) of the normalised
/// irradiance of the mesh of hit points `pts[j*nphi + k]` (relative to the shading point, m
/// rings of nphi cells, brightness `b`) at the shading point with normal `n` and tangent
/// frame (`u`, `v`): exact derivatives by [`Jet`]s (see the module documentation), of the
/// mesh thinned to at most about `max_cells` cells by [`subsample_grid`] (`usize::MAX`: the
/// whole mesh). Returns None for a degenerate mesh.
pub fn hessian(
    pts: &[DVec3],
    b: &[f64],
    (m, nphi): (usize, usize),
    (n, u, v): (DVec3, DVec3, DVec3),
    max_cells: usize,
) -> Option<[f64; 3]> {
    if pts.len() != m * nphi || b.len() != m * nphi {
        return None;
    }
    let (rows, cols) = subsample_grid(m, nphi, max_cells);
    let mut local = Vec::with_capacity(rows.len() * cols.len());
    let mut lb = Vec::with_capacity(rows.len() * cols.len());
    // A kept vertex stands for its block of the grid (halfway to the kept neighbours, in
    // rings and in columns, wrapping): the block's mean brightness, and its nearest hit along
    // the vertex's own direction. Point samples alone miss what lies between them: a near
    // object's hits that no kept vertex lands on leave the radii several times too large.
    let thinned = rows.len() < m || cols.len() < nphi;
    let rlo = |i: usize| {
        if i == 0 {
            0
        } else {
            (rows[i - 1] + rows[i]) / 2 + 1
        }
    };
    let rhi = |i: usize| {
        if i + 1 == rows.len() {
            m - 1
        } else {
            (rows[i] + rows[i + 1]) / 2
        }
    };
    let nc = cols.len();
    for (ri, &j) in rows.iter().enumerate() {
        for (ci, &k) in cols.iter().enumerate() {
            let p = pts[j * nphi + k];
            if !thinned {
                local.push(in_frame(p, n, u, v));
                lb.push(b[j * nphi + k]);
                continue;
            }
            let prev = cols[(ci + nc - 1) % nc];
            let next = cols[(ci + 1) % nc];
            let back = ((k + nphi - prev) % nphi) / 2;
            let fwd = ((next + nphi - k) % nphi).saturating_sub(1) / 2;
            let mut bsum = 0.0;
            let mut cnt = 0.0;
            let mut near2 = p.length_squared();
            for jj in rlo(ri)..=rhi(ri) {
                for dk in 0..=(back + fwd) {
                    let idx = jj * nphi + (k + nphi - back + dk) % nphi;
                    bsum += b[idx];
                    cnt += 1.0;
                    near2 = near2.min(pts[idx].length_squared());
                }
            }
            let p = p.normalize_or_zero() * near2.sqrt();
            local.push(in_frame(p, n, u, v));
            lb.push(bsum / cnt);
        }
    }
    let mesh = Mesh::new(&local, &lb, rows.len(), cols.len())?;
    let f = mesh.contour(edge_jet_local) * (1.0 / (2.0 * PI));
    let h = [f.uu, f.uv, f.vv];
    h.iter().all(|x| x.is_finite()).then_some(h)
}

/// The rings and columns of an m × nphi grid kept for a mesh of at most about `max_cells`
/// cells: evenly spaced, always including the first and the last ring.
pub fn subsample_grid(m: usize, nphi: usize, max_cells: usize) -> (Vec<usize>, Vec<usize>) {
    if m * nphi <= max_cells || m < 3 {
        return ((0..m).collect(), (0..nphi).collect());
    }
    let f = ((m * nphi) as f64 / max_cells as f64).sqrt();
    let m2 = ((m as f64 / f).round() as usize).clamp(2, m);
    let n2 = ((nphi as f64 / f).round() as usize).clamp(3, nphi);
    let rows = (0..m2)
        .map(|i| ((i * (m - 1)) as f64 / (m2 - 1) as f64).round() as usize)
        .collect();
    let cols = (0..n2)
        .map(|i| ((i * nphi) as f64 / n2 as f64).round() as usize % nphi)
        .collect();
    (rows, cols)
}

/// Radii from a tangent-plane Hessian `[h_uu, h_uv, h_vv]`: eigenvalues λ give
/// `r = (4/|λ|)^¼` (Schwarzhaupt et al. 2012: the interpolation error integrated over the
/// record's disc stays under the target). Returns `(angle of the first eigenvector from u,
/// r0, r1)` with r0 (the larger |λ|) <= r1, or None when both eigenvalues vanish.
pub fn hessian_radii(h: &[f64; 3]) -> Option<(f64, f64, f64)> {
    let [a, b, c] = *h;
    let mean = 0.5 * (a + c);
    let disc = (0.25 * (a - c) * (a - c) + b * b).sqrt();
    let (l1, l2) = (mean + disc, mean - disc);
    // Angle of the eigenvector of l1: tan 2θ = 2b/(a−c).
    let th1 = 0.5 * (2.0 * b).atan2(a - c);
    let (lbig, lsmall, ang) = if l1.abs() >= l2.abs() {
        (l1, l2, th1)
    } else {
        (l2, l1, th1 + PI / 2.0)
    };
    if lbig.abs() <= 1e-12 || !lbig.is_finite() {
        return None;
    }
    let r = |l: f64| (4.0 / l.abs().max(1e-300)).powf(0.25);
    Some((ang, r(lbig), r(lsmall).min(1e30)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic pseudo-random stream in [0, 1).
    fn stream(seed: u64) -> impl FnMut() -> f64 {
        let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
        move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// The Hessian by a 7-point central second difference of the contour integral evaluated
    /// at displaced points (step `h`): an independent check of the jets.
    fn numerical(mesh: &Mesh, n: DVec3, u: DVec3, v: DVec3, h: f64) -> [f64; 3] {
        let f = |d: DVec3| mesh.contour(|a, c| edge_value(a - d, c - d, n)) / (2.0 * PI);
        let f0 = f(DVec3::ZERO);
        let (fu, fmu, fv, fmv) = (f(u * h), f(-u * h), f(v * h), f(-v * h));
        let (fuv, fmuv) = (f((u + v) * h), f(-(u + v) * h));
        let h2 = h * h;
        [
            (fu - 2.0 * f0 + fmu) / h2,
            (fuv - fu - fv + 2.0 * f0 - fmu - fmv + fmuv) / (2.0 * h2),
            (fv - 2.0 * f0 + fmv) / h2,
        ]
    }

    /// Random hemispheres of hit points (stratified like the ambient sampler, at random
    /// distances) and brightness.
    fn hemisphere(seed: u64, m: usize, nphi: usize) -> (Vec<DVec3>, Vec<f64>) {
        let mut r = stream(seed);
        let mut pts = Vec::new();
        let mut b = Vec::new();
        for j in 0..m {
            for k in 0..nphi {
                // Jitter within the middle of each cell, so that no triangle is seen edge-on
                // (where |·| has a kink that a finite difference would straddle).
                let s2 = (j as f64 + 0.3 + 0.4 * r()) / m as f64;
                let (st, ct) = (s2.sqrt(), (1.0 - s2).sqrt());
                let phi = 2.0 * PI * (k as f64 + 0.3 + 0.4 * r()) / nphi as f64;
                let dir = DVec3::new(st * phi.cos(), st * phi.sin(), ct);
                pts.push(dir * (0.5 + 3.0 * r()));
                b.push(if r() < 0.2 { 5.0 * r() } else { r() });
            }
        }
        (pts, b)
    }

    #[test]
    fn jets_match_finite_differences() {
        let (n, u, v) = (DVec3::Z, DVec3::X, DVec3::Y);
        for seed in 1..20u64 {
            let (m, nphi) = (4 + (seed as usize % 5), 13 + 3 * (seed as usize % 4));
            let (pts, b) = hemisphere(seed, m, nphi);
            let mesh = Mesh::new(&pts, &b, m, nphi).unwrap();
            let exact = hessian(&pts, &b, (m, nphi), (n, u, v), usize::MAX).unwrap();
            let dmin = pts.iter().map(|p| p.length()).fold(f64::INFINITY, f64::min);
            let approx = numerical(&mesh, n, u, v, 2e-3 * dmin);
            let scale = exact.iter().map(|x| x.abs()).fold(0.0, f64::max);
            for i in 0..3 {
                assert!(
                    (exact[i] - approx[i]).abs() <= 1e-4 * scale,
                    "seed {seed}: {exact:?} vs {approx:?}"
                );
            }
            // The value of the jet is the contour integral itself.
            let f0 = mesh.contour(|a, c| edge_value(a, c, n));
            let j0 = mesh.contour(|a, c| edge_jet(a, c, n, u, v));
            assert!((f0 - j0.v).abs() < 1e-12 * f0.abs().max(1.0));
        }
    }

    /// The hit points of a stratified hemisphere (cell centres) above the floor point `p` of
    /// the box `lo`..`hi`, relative to `p`.
    fn room(p: DVec3, lo: DVec3, hi: DVec3, m: usize, nphi: usize) -> Vec<DVec3> {
        let mut pts = Vec::new();
        for j in 0..m {
            for k in 0..nphi {
                let s2 = (j as f64 + 0.5) / m as f64;
                let phi = 2.0 * PI * (k as f64 + 0.5) / nphi as f64;
                let st = s2.sqrt();
                let d = DVec3::new(st * phi.cos(), st * phi.sin(), (1.0 - s2).sqrt());
                let t = (0..3)
                    .filter(|&i| d[i].abs() > 1e-12)
                    .map(|i| {
                        let wall = if d[i] > 0.0 { hi[i] } else { lo[i] };
                        (wall - p[i]) / d[i]
                    })
                    .fold(f64::INFINITY, f64::min);
                pts.push(d * t);
            }
        }
        pts
    }

    #[test]
    fn a_rotated_frame_gives_the_same_hessian() {
        // The same mesh expressed in a rotated world frame: the tangent-frame Hessian is a
        // property of the mesh alone.
        let (m, nphi) = (6, 19);
        let (pts, b) = hemisphere(7, m, nphi);
        let h0 = hessian(
            &pts,
            &b,
            (m, nphi),
            (DVec3::Z, DVec3::X, DVec3::Y),
            usize::MAX,
        )
        .unwrap();
        let rot = glam::DQuat::from_axis_angle(DVec3::new(0.3, -0.8, 0.5).normalize(), 1.1);
        let moved: Vec<DVec3> = pts.iter().map(|p| rot * *p).collect();
        let h1 = hessian(
            &moved,
            &b,
            (m, nphi),
            (rot * DVec3::Z, rot * DVec3::X, rot * DVec3::Y),
            usize::MAX,
        )
        .unwrap();
        let scale = h0.iter().map(|x| x.abs()).fold(0.0, f64::max);
        for i in 0..3 {
            assert!((h0[i] - h1[i]).abs() <= 1e-9 * scale, "{h0:?} vs {h1:?}");
        }
    }

    #[test]
    fn thinned_grids_keep_the_first_and_last_ring() {
        assert_eq!(
            subsample_grid(5, 16, 256),
            ((0..5).collect(), (0..16).collect())
        );
        for (m, nphi, max) in [(18, 57, 256), (13, 41, 256), (26, 82, 128), (40, 126, 300)] {
            let (rows, cols) = subsample_grid(m, nphi, max);
            assert_eq!(rows[0], 0);
            assert_eq!(*rows.last().unwrap(), m - 1);
            assert!(rows.windows(2).all(|w| w[0] < w[1]), "{rows:?}");
            assert!(cols.windows(2).all(|w| w[0] < w[1]), "{cols:?}");
            assert!(*cols.last().unwrap() < nphi);
            let cells = rows.len() * cols.len();
            assert!(
                cells <= max * 5 / 4 && cells >= max / 2,
                "{m}x{nphi} -> {cells}"
            );
        }
    }

    #[test]
    fn a_thinned_mesh_gives_nearly_the_same_radii_in_a_room() {
        // Floor points of a box room, seen through an 18 x 57 mesh (-ad 1024) and through
        // the same mesh thinned to 256 cells: the radii agree to within 5% (measured: 0.1–1%).
        let (lo, hi) = (DVec3::new(-2.0, -1.5, 0.0), DVec3::new(3.0, 2.5, 2.2));
        let (m, nphi) = (18, 57);
        let b = vec![1.0; m * nphi];
        for p in [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(2.5, 0.3, 0.0),
            DVec3::new(-1.6, 2.1, 0.0),
        ] {
            let pts = room(p, lo, hi, m, nphi);
            let (n, u, v) = (DVec3::Z, DVec3::X, DVec3::Y);
            let full = hessian_radii(&hessian(&pts, &b, (m, nphi), (n, u, v), usize::MAX).unwrap())
                .unwrap();
            let thin =
                hessian_radii(&hessian(&pts, &b, (m, nphi), (n, u, v), 256).unwrap()).unwrap();
            for (a, t) in [(full.1, thin.1), (full.2, thin.2)] {
                assert!((t / a - 1.0).abs() < 0.05, "at {p}: {full:?} vs {thin:?}");
            }
        }
    }

    #[test]
    fn jet_arithmetic_follows_the_chain_rule() {
        // g(δu, δv) = atan2(√(1 + δu² + 3δuδv), 2 + δv) / (1 + δu), checked against
        // second differences.
        let g = |x: f64, y: f64| (1.0 + x * x + 3.0 * x * y).sqrt().atan2(2.0 + y) / (1.0 + x);
        let du = Jet {
            du: 1.0,
            ..Jet::default()
        };
        let dv = Jet {
            dv: 1.0,
            ..Jet::default()
        };
        let one = Jet::constant(1.0);
        let j = (one + du * du + du * dv * 3.0)
            .sqrt()
            .atan2(Jet::constant(2.0) + dv)
            * (one + du).recip();
        let h = 1e-4;
        let num_uu = (g(h, 0.0) - 2.0 * g(0.0, 0.0) + g(-h, 0.0)) / (h * h);
        let num_vv = (g(0.0, h) - 2.0 * g(0.0, 0.0) + g(0.0, -h)) / (h * h);
        let num_uv = (g(h, h) - g(h, -h) - g(-h, h) + g(-h, -h)) / (4.0 * h * h);
        let num_u = (g(h, 0.0) - g(-h, 0.0)) / (2.0 * h);
        let num_v = (g(0.0, h) - g(0.0, -h)) / (2.0 * h);
        assert!((j.v - g(0.0, 0.0)).abs() < 1e-15);
        for (a, b) in [
            (j.du, num_u),
            (j.dv, num_v),
            (j.uu, num_uu),
            (j.uv, num_uv),
            (j.vv, num_vv),
        ] {
            assert!((a - b).abs() < 1e-6, "{j:?}: {a} vs {b}");
        }
    }

    #[test]
    fn degenerate_meshes_are_refused() {
        let (pts, b) = hemisphere(3, 4, 13);
        assert!(Mesh::new(&pts, &b, 1, 13).is_none());
        assert!(Mesh::new(&pts, &b, 4, 12).is_none());
        let mut z = pts.clone();
        z[5] = DVec3::ZERO;
        assert!(hessian(&z, &b, (4, 13), (DVec3::Z, DVec3::X, DVec3::Y), usize::MAX).is_none());
    }
}
