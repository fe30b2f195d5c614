//! Computing and interpolating indirect irradiance (Ward, Rubinstein & Clear 1988; gradients
//! after Ward & Heckbert 1992).
//!
//! A new value samples the hemisphere above a point with M×N cells stratified in sin²θ and φ
//! (cosine-weighted: `sin θ = √((j+ξ)/M)`, `φ = 2π(k+ξ)/N`, N ≈ πM), which is the layout for
//! which Ward & Heckbert derived the translational and rotational gradient formulas. The stored
//! value is the mean incoming radiance (irradiance/π), independent of the surface's
//! reflectance, so it serves every material. Its validity radius is the harmonic mean distance
//! to the surfaces the samples hit, clamped by `-ar` and the scene size and limited by the
//! gradient as Radiance does. Lookups apply Radiance's acceptance tests and weights.

use super::cache::{AmbientCache, CachedValue};
use crate::color::{bright, Color};
use crate::material::normal::any_perpendicular;
use crate::radopt::RenderParams;
use crate::render::ray::{Hit, Ray, RayKind};
use crate::render::sampler::Sampler;
use crate::render::trace::Tracer;
use crate::FTINY;
use glam::DVec3;
use std::collections::HashSet;
use std::f64::consts::PI;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// Radiance's average reflectance assumed for ambient rays.
pub const AVGREFL: f64 = 0.5;

/// Counters of the ambient calculation (the seed paper's T_amb among them).
#[derive(Debug, Default)]
pub struct AmbientStats {
    /// Cache lookups.
    pub lookups: AtomicU64,
    /// Lookups answered by interpolation.
    pub hits: AtomicU64,
    /// New values computed, by ambient level (index clamped to 7).
    pub new_values: [AtomicU64; 8],
    /// Nanoseconds spent computing new level-0 values (including their child rays and the
    /// deeper values made inside them, so nothing is counted twice).
    pub amb_nanos: AtomicU64,
    /// Hemisphere sample rays traced.
    pub sample_rays: AtomicU64,
}

/// The ambient calculation with its shared cache.
pub struct Ambient {
    /// The shared cache.
    pub cache: AmbientCache,
    /// Counters.
    pub stats: AmbientStats,
    /// Extrapolate cached values with their gradients (default true; tests switch it off).
    pub use_gradients: bool,
    ab: u32,
    aa: f64,
    ad: f64,
    minarad: f64,
    maxarad: f64,
    max_dist: f64,
    as_: f64,
    /// Anisotropic radii from the Hessian (default true; else the harmonic mean distance).
    pub use_hessian: bool,
    av: Color,
    /// `-aw`: weight of `-av` in the moving log-average (0: `-av` stays fixed).
    aw: f64,
    /// Σ ln(brightness) of the new values and their count, for `-aw`.
    log_sum: std::sync::Mutex<(f64, u64)>,
    exclude: HashSet<String>,
    include: Option<HashSet<String>>,
}

/// What a lookup or computation returned.
enum Outcome {
    Value(Color),
    Fallback,
}

impl Ambient {
    /// Set up from the rendering parameters and the scene's cube size; `origin_id` names this
    /// process in value ids. Returns None when `-ab 0` or `-ad 0` (constant ambient only).
    pub fn new(params: &RenderParams, scene_size: f64, origin_id: u64) -> Option<Ambient> {
        if params.ab <= 0 || params.ad <= 0 {
            return None;
        }
        let size = scene_size.max(FTINY);
        let (minarad, maxarad) = if params.ar > 0 {
            let min = size / params.ar as f64;
            (min, (64.0 * min).min(0.2 * size))
        } else {
            (size * 1e-6, 0.2 * size)
        };
        let aa = params.aa.max(0.0);
        Some(Ambient {
            cache: AmbientCache::new(minarad, aa.max(0.01), origin_id),
            stats: AmbientStats::default(),
            ab: params.ab as u32,
            aa,
            ad: params.ad as f64,
            as_: params.as_.max(0) as f64,
            use_hessian: true,
            use_gradients: true,
            minarad,
            maxarad,
            max_dist: 10.0 * size + 1000.0,
            av: Color::new(params.av[0], params.av[1], params.av[2]),
            aw: params.aw.max(0) as f64,
            log_sum: std::sync::Mutex::new((0.0, 0)),
            exclude: params.ae.iter().cloned().collect(),
            include: if params.ai.is_empty() {
                None
            } else {
                Some(params.ai.iter().cloned().collect())
            },
        })
    }

    /// Indirect light reflected with coefficient `refl` at a hit whose (ray-facing,
    /// unperturbed) normal is `n`.
    pub fn reflected(
        &self,
        tr: &Tracer,
        ray: &Ray,
        hit: &Hit,
        refl: Color,
        n: DVec3,
        rng: &mut Sampler,
    ) -> Color {
        if bright(refl) <= 0.0 {
            return Color::ZERO;
        }
        match self.value(tr, ray, hit, n, rng) {
            Outcome::Value(v) => refl * v,
            Outcome::Fallback => refl * self.fallback(),
        }
    }

    /// The ambient value used when no value is computed: `-av`, or with `-aw N` > 0 a moving
    /// log-average in which `-av` weighs N and each new value (times 1 − AVGREFL, the light
    /// left after one more reflection) weighs 1; the colour of `-av` is kept.
    pub fn fallback(&self) -> Color {
        let b0 = bright(self.av);
        if self.aw <= 0.0 || b0 <= 0.0 {
            return self.av;
        }
        let (sum, n) = self.log_sum.lock().map(|g| *g).unwrap_or((0.0, 0));
        let n = n as f64;
        let lb = (b0.ln() * self.aw + sum + n * (1.0 - AVGREFL).ln()) / (self.aw + n);
        self.av * (lb.exp() / b0)
    }

    fn excluded(&self, tr: &Tracer, hit: &Hit) -> bool {
        let m = &tr.scene.objects[hit.obj].modifier;
        match &self.include {
            Some(inc) => !inc.contains(m),
            None => self.exclude.contains(m),
        }
    }

    fn value(&self, tr: &Tracer, ray: &Ray, hit: &Hit, n: DVec3, rng: &mut Sampler) -> Outcome {
        if ray.amb_level >= self.ab || self.excluded(tr, hit) {
            return Outcome::Fallback;
        }
        if self.aa <= FTINY {
            // No cache: Monte Carlo at every bounce.
            return match self.sample(tr, ray, hit, n, rng) {
                Some(v) => Outcome::Value(v.val),
                None => Outcome::Fallback,
            };
        }
        self.stats.lookups.fetch_add(1, Ordering::Relaxed);
        if let Some(v) = self.interpolate(hit.point, n, ray.amb_level, ray.weight) {
            self.stats.hits.fetch_add(1, Ordering::Relaxed);
            return Outcome::Value(v);
        }
        match self.sample(tr, ray, hit, n, rng) {
            Some(v) => {
                self.cache.insert(v);
                Outcome::Value(v.val)
            }
            None => Outcome::Fallback,
        }
    }

    /// Weighted interpolation of the cached values valid at `p` (Radiance's acceptance
    /// tests and weights), or None when no value applies.
    pub fn interpolate(&self, p: DVec3, n: DVec3, level: u32, rweight: f64) -> Option<Color> {
        let aa = self.aa;
        let mut maxangle = 10f64.to_radians() + aa;
        if rweight < 0.6 {
            maxangle = (maxangle - PI / 2.0) * rweight.powf(0.13) + PI / 2.0;
        }
        let behind = -self.minarad * aa;
        let mut sum = Color::ZERO;
        let mut wsum = 0.0;
        self.cache.for_each_near(p, |v| {
            if v.lvl > level || (v.lvl == level && v.weight < 0.9 * rweight) {
                return;
            }
            let d = v.n.dot(n);
            if d <= 0.0 {
                return;
            }
            // Rounding can make d exceed 1 for equal normals: keep the angle term real.
            let dr2 = (2.0 - 2.0 * d).max(0.0);
            if dr2 >= maxangle * maxangle {
                return;
            }
            let dd = p - v.pos;
            let dn = dd.dot(v.n);
            if dn < behind {
                return;
            }
            let mut dt2 = (dn / v.rad[0]).powi(2);
            if dt2 >= aa * aa {
                return;
            }
            let vv = v.n.cross(v.u);
            let du = dd.dot(v.u);
            let dv = dd.dot(vv);
            dt2 += (du / v.rad[0]).powi(2) + (dv / v.rad[1]).powi(2);
            if dt2 >= aa * aa {
                return;
            }
            let rot = v.n.cross(n);
            let f = if !self.use_gradients {
                1.0
            } else {
                1.0 + v.gpos[0] * du
                    + v.gpos[1] * dv
                    + v.gdir[0] * rot.dot(v.u)
                    + v.gdir[1] * rot.dot(vv)
            };
            if f <= 0.05 {
                return;
            }
            let f = f.min(20.0);
            let w = (1.0 - dr2.sqrt() / maxangle) * (1.0 - dt2.sqrt() / aa);
            sum += v.val * (f * w);
            wsum += w;
        });
        (wsum > FTINY).then(|| sum / wsum)
    }

    /// Compute a new value at a hit by sampling the hemisphere around `n`.
    fn sample(
        &self,
        tr: &Tracer,
        ray: &Ray,
        hit: &Hit,
        n: DVec3,
        rng: &mut Sampler,
    ) -> Option<CachedValue> {
        let start = Instant::now();
        let lvl = ray.amb_level;
        let mut wt = AVGREFL.powi(lvl as i32);
        if ray.weight < 0.1 * wt {
            wt = 1.25 * ray.weight;
        }
        let total = (self.ad * wt).max(1.0);
        let m = ((total / PI).sqrt().round() as usize).max(if self.aa > FTINY { 4 } else { 1 });
        let nphi = ((PI * m as f64).round() as usize).max(1);
        let u0 = any_perpendicular(n);
        let v0 = n.cross(u0);
        let ncells = m * nphi;
        let mut cells = vec![Cell::default(); ncells];
        let mut traced = 0u64;
        // One jittered sample in cell (j, k): its value, distance and direction.
        let mut shoot = |j: usize, k: usize, rng: &mut Sampler| -> Option<(Color, f64, DVec3)> {
            let (r1, r2) = rng.next2();
            let s2 = (j as f64 + r1) / m as f64;
            let st = s2.sqrt();
            let ct = (1.0 - s2).max(0.0).sqrt();
            let phi = 2.0 * PI * (k as f64 + r2) / nphi as f64;
            let dir = n * ct + (u0 * phi.cos() + v0 * phi.sin()) * st;
            let mut r = tr.spawn(ray, hit, dir, RayKind::Ambient, Color::splat(AVGREFL))?;
            r.amb_level = lvl + 1;
            traced += 1;
            let (c, t) = tr.trace_dist(&r, rng);
            Some((c, t.clamp(FTINY, self.max_dist), dir))
        };
        for j in 0..m {
            for k in 0..nphi {
                if let Some((c, t, dir)) = shoot(j, k, rng) {
                    let cell = &mut cells[j * nphi + k];
                    cell.add(c, t);
                    cell.hit = dir * t;
                }
            }
        }
        let complete = cells.iter().all(|c| c.count > 0);
        // Super-sampling (-as): extra rays where neighbouring cells differ most.
        let extra = (self.as_ * wt).floor();
        if complete && ncells > 49 && extra >= 4.0 * m as f64 {
            let b: Vec<f64> = cells.iter().map(|c| bright(c.mean())).collect();
            let var = cell_variances(&b, m, nphi);
            let vsum: f64 = var.iter().sum();
            if vsum > 0.0 {
                // Systematic allocation: cell i gets floor(acc_i) − floor(acc_{i−1}) rays with
                // acc the running share of `extra`, so the total is exactly `extra`.
                let mut acc = rng.next2().0;
                for (idx, vi) in var.iter().enumerate() {
                    let before = acc.floor();
                    acc += extra * vi / vsum;
                    let nextra = (acc.floor() - before) as usize;
                    let (j, k) = (idx / nphi, idx % nphi);
                    for _ in 0..nextra {
                        if let Some((c, t, _)) = shoot(j, k, rng) {
                            cells[idx].add(c, t);
                        }
                    }
                }
            }
        }
        self.stats.sample_rays.fetch_add(traced, Ordering::Relaxed);
        if traced == 0 {
            return None;
        }
        let lval: Vec<Color> = cells.iter().map(|c| c.mean()).collect();
        let dist: Vec<f64> = cells.iter().map(|c| c.dist(self.max_dist)).collect();
        let count = ncells as f64;
        let val = lval.iter().fold(Color::ZERO, |a, c| a + *c) / count;
        let rsum: f64 = dist.iter().map(|d| 1.0 / d).sum();
        let b = bright(val);
        if self.aw > 0.0 && b > 0.0 && b.is_finite() {
            if let Ok(mut g) = self.log_sum.lock() {
                g.0 += b.ln();
                g.1 += 1;
            }
        }
        let lb: Vec<f64> = lval.iter().map(|c| bright(*c)).collect();
        // Gradients (Ward & Heckbert 1992) of the brightness, relative to the value.
        let (gpos, gdir) = if b > FTINY && m > 1 && nphi > 1 {
            gradients(&lb, &dist, m, nphi, u0, v0)
        } else {
            (DVec3::ZERO, DVec3::ZERO)
        };
        let scale = if b > FTINY { 1.0 / b } else { 0.0 };
        // Radii: from the Hessian when the mesh of hit points is complete, else the harmonic
        // mean distance (isotropic).
        let hess = if complete && self.use_hessian && m > 1 && nphi > 2 {
            let pts: Vec<DVec3> = cells.iter().map(|c| c.hit).collect();
            hessian(&pts, &lb, m, nphi, n, u0, v0).and_then(|h| hessian_radii(&h))
        } else {
            None
        };
        let (u, mut rad) = match hess {
            Some((ang, r0, r1)) => (u0 * ang.cos() + v0 * ang.sin(), [r0, r1]),
            None => {
                let r = count / rsum.max(FTINY);
                (u0, [r, r])
            }
        };
        let mut u = u;
        let mut v = n.cross(u);
        let mut gp = [gpos.dot(u) * scale, gpos.dot(v) * scale];
        let mut gd = [gdir.dot(u) * scale, gdir.dot(v) * scale];
        // Radiance's post-processing, in order.
        for i in 0..2 {
            if gp[i].abs() * rad[i] > 1.0 {
                rad[i] = 1.0 / gp[i].abs();
            }
        }
        if rad[0] > rad[1] {
            // Rotate the frame by 90° so that rad[0] <= rad[1]: u' = v, v' = n × v = −u.
            rad.swap(0, 1);
            gp = [gp[1], -gp[0]];
            gd = [gd[1], -gd[0]];
            let nu = v;
            v = -u;
            u = nu;
        }
        for r in rad.iter_mut() {
            *r = r.max(self.minarad) / wt.sqrt();
        }
        rad[1] = rad[1].min(2.0 * rad[0]);
        for r in rad.iter_mut() {
            *r = r.min(self.maxarad);
        }
        // Cap the gradient so that it changes the value by at most 100% within the radii.
        let glen = ((gp[0] * rad[0]).powi(2) + (gp[1] * rad[1]).powi(2)).sqrt();
        if glen > 1.0 {
            gp = [gp[0] / glen, gp[1] / glen];
        }
        let _ = v;
        let lvl_idx = (lvl as usize).min(7);
        self.stats.new_values[lvl_idx].fetch_add(1, Ordering::Relaxed);
        // Deeper values are made inside a level-0 value's sampling: counting level 0 only
        // counts each nanosecond once.
        if lvl == 0 {
            self.stats
                .amb_nanos
                .fetch_add(start.elapsed().as_nanos() as u64, Ordering::Relaxed);
        }
        Some(CachedValue {
            id: self.cache.next_id(),
            pos: hit.point,
            n,
            u,
            lvl,
            weight: wt,
            rad,
            gpos: gp,
            gdir: gd,
            val,
        })
    }
}

/// One hemisphere cell: the running sum of its samples.
#[derive(Clone, Copy, Default)]
struct Cell {
    sum: Color,
    count: u32,
    rinv: f64,
    /// First sample's hit point relative to the shading point (the mesh vertex).
    hit: DVec3,
}

impl Cell {
    fn add(&mut self, c: Color, t: f64) {
        self.sum += c;
        self.count += 1;
        self.rinv += 1.0 / t;
    }
    fn mean(&self) -> Color {
        if self.count == 0 {
            Color::ZERO
        } else {
            self.sum / self.count as f64
        }
    }
    /// Harmonic mean distance of the cell's samples.
    fn dist(&self, max: f64) -> f64 {
        if self.count == 0 {
            max
        } else {
            self.count as f64 / self.rinv
        }
    }
}

/// Per-cell variance estimate for super-sampling: the mean squared brightness difference with
/// the (up to 8) neighbouring cells, wrapping in φ, not across the pole or the horizon.
pub fn cell_variances(b: &[f64], m: usize, nphi: usize) -> Vec<f64> {
    let mut out = vec![0.0; m * nphi];
    for j in 0..m {
        for k in 0..nphi {
            let c = b[j * nphi + k];
            let mut s = 0.0;
            let mut cnt = 0usize;
            for dj in -1i64..=1 {
                let jj = j as i64 + dj;
                if jj < 0 || jj >= m as i64 {
                    continue;
                }
                for dk in -1i64..=1 {
                    if dj == 0 && dk == 0 {
                        continue;
                    }
                    let kk = (k as i64 + dk).rem_euclid(nphi as i64) as usize;
                    let d = b[jj as usize * nphi + kk] - c;
                    s += d * d;
                    cnt += 1;
                }
            }
            out[j * nphi + k] = if cnt > 0 { s / cnt as f64 } else { 0.0 };
        }
    }
    out
}

/// The 2×2 tangent-plane Hessian `[h_uu, h_uv, h_vv]` (per unit length²) of the normalised
/// irradiance at the shading point, after Schwarzhaupt, Jensen & Jarosz (2012).
///
/// `pts[j*nphi + k]` are the cells' hit points relative to the shading point, `b` their
/// brightness. As in the paper the hit points form a mesh (two triangles per quad of
/// neighbouring cells, wrapping in φ, plus one polygon closing the cap around the pole), each
/// triangle radiating with the brightness of its farthest vertex, normalised so the mean cell
/// is 1, plus 0.01 (a black hemisphere gives the purely geometric Hessian). Instead of the
/// paper's analytic derivatives of the edge form factors, this differentiates numerically:
/// the irradiance of the fixed mesh seen from a point displaced by δ in the tangent plane is
/// evaluated exactly with Lambert's contour formula (the projected solid angle of a polygon
/// from its edges alone), `F = (1/2π) Σ_edges Θ_e (n·ĉ_e)` with Θ_e the angle an edge
/// subtends and ĉ_e the unit normal of the plane through the point and the edge; the Hessian
/// is the 7-point central second difference with a step of 2% of the nearest hit distance.
/// This is the same quantity the paper differentiates analytically (visibility fixed, hit
/// points fixed, the tangent plane unchanged under tangential displacement so every triangle
/// stays above it); the step is small against every hit distance, so the truncation error is
/// O(step²) relative and the round-off (differences of order 10⁻⁴ of values near 1) is far
/// below it. Returns None for a degenerate mesh.
pub fn hessian(
    pts: &[DVec3],
    b: &[f64],
    m: usize,
    nphi: usize,
    n: DVec3,
    u: DVec3,
    v: DVec3,
) -> Option<[f64; 3]> {
    let nc = m * nphi;
    if m < 2 || nphi < 3 || pts.len() != nc || b.len() != nc {
        return None;
    }
    let dmin = pts.iter().map(|p| p.length()).fold(f64::INFINITY, f64::min);
    if !(dmin > FTINY && dmin.is_finite()) {
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
    let at = |j: usize, k: usize| j * nphi + (k % nphi);
    let far = |a: usize, c: usize, d: usize| -> usize {
        let mut f = a;
        for i in [c, d] {
            if pts[i].length_squared() > pts[f].length_squared() {
                f = i;
            }
        }
        f
    };
    // Triangle weights (by farthest vertex), computed once.
    let mut tw_a = vec![0.0; (m - 1) * nphi];
    let mut tw_b = vec![0.0; (m - 1) * nphi];
    for j in 0..m - 1 {
        for k in 0..nphi {
            let (p00, p01, p10, p11) = (at(j, k), at(j, k + 1), at(j + 1, k), at(j + 1, k + 1));
            tw_a[j * nphi + k] = w(far(p00, p01, p11));
            tw_b[j * nphi + k] = w(far(p00, p11, p10));
        }
    }
    let cap_far = (0..nphi).fold(0, |f, k| {
        if pts[k].length_squared() > pts[f].length_squared() {
            k
        } else {
            f
        }
    });
    let cap_w = w(cap_far);
    let edge = |a: DVec3, c: DVec3| -> f64 {
        let x = a.cross(c);
        let s = x.length();
        if s < 1e-300 {
            return 0.0;
        }
        s.atan2(a.dot(c)) * n.dot(x) / s
    };
    let mut dirs = vec![DVec3::ZERO; nc];
    let mut eh = vec![0.0; nc];
    let mut ev = vec![0.0; nc];
    let mut ed = vec![0.0; nc];
    let mut f_at = |d: DVec3| -> f64 {
        for (o, p) in dirs.iter_mut().zip(pts) {
            *o = (*p - d).normalize_or_zero();
        }
        for j in 0..m {
            for k in 0..nphi {
                let i = at(j, k);
                eh[i] = edge(dirs[i], dirs[at(j, k + 1)]);
                if j + 1 < m {
                    ev[i] = edge(dirs[i], dirs[at(j + 1, k)]);
                    ed[i] = edge(dirs[i], dirs[at(j + 1, k + 1)]);
                }
            }
        }
        let mut f = 0.0;
        for j in 0..m - 1 {
            for k in 0..nphi {
                let i = at(j, k);
                // (j,k) → (j,k+1) → (j+1,k+1) → back.
                let ta = eh[i] + ev[at(j, k + 1)] - ed[i];
                // (j,k) → (j+1,k+1) → (j+1,k) → back.
                let tb = ed[i] - eh[at(j + 1, k)] - ev[i];
                f += tw_a[j * nphi + k] * ta.abs() + tw_b[j * nphi + k] * tb.abs();
            }
        }
        let cap: f64 = (0..nphi).map(|k| eh[k]).sum();
        f += cap_w * cap.abs();
        f / (2.0 * PI)
    };
    let h = 0.02 * dmin;
    let f0 = f_at(DVec3::ZERO);
    let fu = f_at(u * h);
    let fmu = f_at(-u * h);
    let fv = f_at(v * h);
    let fmv = f_at(-v * h);
    let fuv = f_at((u + v) * h);
    let fmuv = f_at(-(u + v) * h);
    let h2 = h * h;
    let huu = (fu - 2.0 * f0 + fmu) / h2;
    let hvv = (fv - 2.0 * f0 + fmv) / h2;
    let huv = (fuv - fu - fv + 2.0 * f0 - fmu - fmv + fmuv) / (2.0 * h2);
    [huu, huv, hvv]
        .iter()
        .all(|x| x.is_finite())
        .then_some([huu, huv, hvv])
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

/// Translational and rotational gradients of the hemisphere integral (in the same units as
/// the mean of `l`) for cells stratified as in [`Ambient`]: `l[j*nphi + k]` and distances.
/// Formulas of Ward & Heckbert (1992), "Irradiance Gradients", divided by π because the
/// values here are mean radiance rather than irradiance.
pub fn gradients(
    l: &[f64],
    r: &[f64],
    m: usize,
    nphi: usize,
    u: DVec3,
    v: DVec3,
) -> (DVec3, DVec3) {
    let mut gt = DVec3::ZERO;
    let mut gr = DVec3::ZERO;
    let at = |j: usize, k: usize| j * nphi + k;
    for k in 0..nphi {
        let phi_c = 2.0 * PI * (k as f64 + 0.5) / nphi as f64;
        let phi_b = 2.0 * PI * k as f64 / nphi as f64;
        let uk = u * phi_c.cos() + v * phi_c.sin();
        let vk_c = u * (phi_c + PI / 2.0).cos() + v * (phi_c + PI / 2.0).sin();
        let vk_b = u * (phi_b + PI / 2.0).cos() + v * (phi_b + PI / 2.0).sin();
        let km = (k + nphi - 1) % nphi;
        // Across θ boundaries (between rings j-1 and j).
        let mut a = 0.0;
        for j in 1..m {
            let s2 = j as f64 / m as f64;
            let sin_b = s2.sqrt();
            let cos2_b = 1.0 - s2;
            let rmin = r[at(j, k)].min(r[at(j - 1, k)]);
            a += sin_b * cos2_b / rmin * (l[at(j, k)] - l[at(j - 1, k)]);
        }
        gt += uk * (2.0 * PI / nphi as f64 * a);
        // Across φ boundaries (between columns k-1 and k).
        let mut b = 0.0;
        for j in 0..m {
            let sin_lo = (j as f64 / m as f64).sqrt();
            let sin_hi = ((j + 1) as f64 / m as f64).sqrt();
            let rmin = r[at(j, k)].min(r[at(j, km)]);
            b += (sin_hi - sin_lo) / rmin * (l[at(j, k)] - l[at(j, km)]);
        }
        gt += vk_b * b;
        // Rotational: Σ_j tanθ_j L_jk along v_k.
        let mut c = 0.0;
        for j in 0..m {
            let s2 = (j as f64 + 0.5) / m as f64;
            let tan = (s2 / (1.0 - s2).max(1e-12)).sqrt();
            c += tan * l[at(j, k)];
        }
        gr += vk_c * c;
    }
    let n = (m * nphi) as f64;
    (gt / PI, gr * (PI / n) / PI)
}
