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
    /// Nanoseconds spent computing new values (including their child rays).
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
    ab: u32,
    aa: f64,
    ad: f64,
    minarad: f64,
    maxarad: f64,
    max_dist: f64,
    av: Color,
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
            minarad,
            maxarad,
            max_dist: 10.0 * size + 1000.0,
            av: Color::new(params.av[0], params.av[1], params.av[2]),
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
            Outcome::Fallback => refl * self.av,
        }
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
            let f = 1.0
                + v.gpos[0] * du
                + v.gpos[1] * dv
                + v.gdir[0] * rot.dot(v.u)
                + v.gdir[1] * rot.dot(vv);
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
        let u = any_perpendicular(n);
        let v = n.cross(u);
        let mut lval = vec![Color::ZERO; m * nphi];
        let mut dist = vec![self.max_dist; m * nphi];
        let mut sum = Color::ZERO;
        let mut rsum = 0.0;
        let mut traced = 0u64;
        for j in 0..m {
            for k in 0..nphi {
                let (r1, r2) = rng.next2();
                let s2 = (j as f64 + r1) / m as f64;
                let st = s2.sqrt();
                let ct = (1.0 - s2).max(0.0).sqrt();
                let phi = 2.0 * PI * (k as f64 + r2) / nphi as f64;
                let dir = n * ct + (u * phi.cos() + v * phi.sin()) * st;
                let Some(mut r) = tr.spawn(ray, hit, dir, RayKind::Ambient, Color::splat(AVGREFL))
                else {
                    continue;
                };
                r.amb_level = lvl + 1;
                traced += 1;
                let (c, t) = tr.trace_dist(&r, rng);
                let idx = j * nphi + k;
                lval[idx] = c;
                dist[idx] = t.clamp(FTINY, self.max_dist);
                sum += c;
                rsum += 1.0 / dist[idx];
            }
        }
        self.stats.sample_rays.fetch_add(traced, Ordering::Relaxed);
        if traced == 0 {
            return None;
        }
        let count = (m * nphi) as f64;
        let val = sum / count;
        let b = bright(val);
        // Gradients (Ward & Heckbert 1992) of the brightness, relative to the value.
        let (gpos, gdir) = if b > FTINY && m > 1 && nphi > 1 {
            let lb: Vec<f64> = lval.iter().map(|c| bright(*c)).collect();
            gradients(&lb, &dist, m, nphi, u, v)
        } else {
            (DVec3::ZERO, DVec3::ZERO)
        };
        let scale = if b > FTINY { 1.0 / b } else { 0.0 };
        let gp = [gpos.dot(u) * scale, gpos.dot(v) * scale];
        let gd = [gdir.dot(u) * scale, gdir.dot(v) * scale];
        // Radius: harmonic mean distance, limited as Radiance does.
        let mut rad = count / rsum.max(FTINY);
        let glen = (gp[0] * gp[0] + gp[1] * gp[1]).sqrt();
        if glen * rad > 1.0 {
            rad = 1.0 / glen;
        }
        rad = rad.max(self.minarad) / wt.sqrt();
        rad = rad.min(self.maxarad);
        // Cap the gradient so that it changes the value by at most 100% within the radius.
        let gscale = if glen * rad > 1.0 {
            1.0 / (glen * rad)
        } else {
            1.0
        };
        let lvl_idx = (lvl as usize).min(7);
        self.stats.new_values[lvl_idx].fetch_add(1, Ordering::Relaxed);
        self.stats
            .amb_nanos
            .fetch_add(start.elapsed().as_nanos() as u64, Ordering::Relaxed);
        Some(CachedValue {
            id: self.cache.next_id(),
            pos: hit.point,
            n,
            u,
            lvl,
            weight: wt,
            rad: [rad, rad],
            gpos: [gp[0] * gscale, gp[1] * gscale],
            gdir: gd,
            val,
        })
    }
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
