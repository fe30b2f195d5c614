//! A new value: the hemisphere above a point sampled with M×N cells stratified in sin²θ and
//! φ (cosine-weighted: `sin θ = √((j+ξ)/M)`, `φ = 2π(k+ξ)/N`, N ≈ πM), super-sampled where
//! neighbouring cells differ (`-as`), the glows beyond their radius sampled as sources; then
//! its light, gradients, radii, reach, share reach and light-leak flags.

use super::cache::CachedValue;
use super::compute::{Ambient, Share, AVGREFL};
use super::corral::{corral_flags, CORRAL_MIN_DIVISIONS};
use super::hemisphere::{
    clamp_outliers, outlier_limit, super_sample_shares, super_sample_shares_unbiased, Cell,
};
use crate::color::{bright, sanitize, Color};
use crate::geometry::any_perpendicular;
use crate::material::MatId;
use crate::render::ray::{Hit, Ray, RayKind, SamplePath, MAX_ANTIMATTER};
use crate::render::sampler::Sampler;
use crate::render::trace::Tracer;
use glam::DVec3;
use std::f64::consts::PI;
use std::sync::atomic::Ordering;

/// The hemisphere of a new value being sampled: its frame, its cells and what its sample
/// rays carry.
pub(super) struct Hemisphere<'t, 'a> {
    pub(super) tr: &'t Tracer<'a>,
    pub(super) ray: &'t Ray,
    pub(super) hit: &'t Hit,
    /// The normal and the frame's first tangent (`v0 = n × u0`).
    pub(super) n: DVec3,
    pub(super) u0: DVec3,
    pub(super) v0: DVec3,
    /// Rings in sin²θ and columns in φ.
    pub(super) m: usize,
    pub(super) nphi: usize,
    /// The coefficient each sample ray carries.
    pub(super) coef: f64,
    /// A sample ray's footprint radius per unit distance (0: no shadow reuse).
    pub(super) spread: f64,
    pub(super) cached: bool,
    /// Glows beyond their radius are sampled explicitly, hidden from the sample rays.
    pub(super) glows: bool,
    pub(super) max_dist: f64,
    /// Sample rays traced.
    pub(super) traced: u64,
    pub(super) cells: Vec<Cell>,
}

impl Hemisphere<'_, '_> {
    /// One jittered sample in cell (j, k): its value, distance and direction.
    fn shoot(
        &mut self,
        j: usize,
        k: usize,
        (r1, r2): (f64, f64),
        rng: &mut Sampler,
    ) -> Option<(Color, f64, DVec3)> {
        let (m, nphi, n) = (self.m, self.nphi, self.n);
        let s2 = (j as f64 + r1) / m as f64;
        let st = s2.sqrt();
        let ct = (1.0 - s2).max(0.0).sqrt();
        let phi = 2.0 * PI * (k as f64 + r2) / nphi as f64;
        let dir = n * ct + (self.u0 * phi.cos() + self.v0 * phi.sin()) * st;
        let tr = self.tr;
        let mut r = tr.spawn(
            self.ray,
            self.hit,
            dir,
            RayKind::Ambient,
            Color::splat(self.coef),
        )?;
        r.amb_level = self.ray.amb_level + 1;
        r.sample = SamplePath {
            on: self.cached,
            spread: self.spread,
            reach: 0.0,
            glow_sampled: self.glows,
        };
        self.traced += 1;
        let (c, t) = tr.trace_dist(&r, rng);
        Some((c, t.clamp(tr.scene.eps, self.max_dist), dir))
    }

    /// One jittered sample in every cell.
    fn stratified(&mut self, rng: &mut Sampler) {
        for j in 0..self.m {
            for k in 0..self.nphi {
                let r = rng.next2();
                if let Some((c, t, dir)) = self.shoot(j, k, r, rng) {
                    let cell = &mut self.cells[j * self.nphi + k];
                    cell.add(c, t);
                    cell.hit = dir * t;
                }
            }
        }
    }

    /// Super-sampling (`-as`): `extra` rays where neighbouring cells differ most, in
    /// proportion to the cells' estimated standard deviations (Neyman allocation).
    fn super_sample(&mut self, extra: f64, unbiased: bool, rng: &mut Sampler) {
        let (m, nphi) = (self.m, self.nphi);
        let b: Vec<f64> = self.cells.iter().map(|c| bright(c.mean())).collect();
        let share = if unbiased {
            super_sample_shares_unbiased(&b, m, nphi)
        } else {
            super_sample_shares(&b, m, nphi)
        };
        let ssum: f64 = share.iter().sum();
        if ssum <= 0.0 {
            return;
        }
        // Systematic allocation: cell i gets floor(acc_i) − floor(acc_{i−1}) rays with acc
        // the running share of `extra`, so the total is exactly `extra`.
        let mut acc = rng.next2().0;
        let mut perm: Vec<usize> = Vec::new();
        for (idx, si) in share.iter().enumerate() {
            let before = acc.floor();
            acc += extra * si / ssum;
            let nextra = (acc.floor() - before) as usize;
            let (j, k) = (idx / nphi, idx % nphi);
            // A cell's extra samples form a Latin hypercube over it: stratified in both
            // directions, each sample still uniform over the whole cell.
            perm.clear();
            perm.extend(0..nextra);
            for a in (1..nextra).rev() {
                let b = ((rng.uniform() * (a + 1) as f64) as usize).min(a);
                perm.swap(a, b);
            }
            for (i, &pi) in perm.iter().enumerate() {
                let (u, v) = rng.next2();
                let r = (
                    (i as f64 + u) / nextra as f64,
                    (pi as f64 + v) / nextra as f64,
                );
                if let Some((c, t, _)) = self.shoot(j, k, r, rng) {
                    self.cells[idx].add(c, t);
                }
            }
        }
    }

    /// Whether every cell got a sample (the Hessian needs the whole mesh).
    fn complete(&self) -> bool {
        self.cells.iter().all(|c| c.count > 0)
    }
}

impl Ambient {
    /// The weight of a new value at ambient level `lvl` for a ray of weight `rweight`, and
    /// its hemisphere divisions `(wt, M, N)`: M rings in sin²θ, N columns in φ, M·N ≈ -ad·wt.
    ///
    /// Cached: `wt = 0.5^lvl` (or `1.25·rweight` when the ray weighs less than a tenth of
    /// that), at least 4 rings (52 cells, about Radiance's 7×7). Uncached (`-aa 0`): `wt` is
    /// the ray's weight, so a deeper bounce, whose rays weigh about 0.5/cells, takes a single
    /// sample; the cell count is also capped so that each sample ray keeps a weight of at
    /// least `-lw` (`cells ≤ 0.5·rweight/lw`): beyond that Radiance traces no more rays
    /// either (its ray count stops growing near `-ad 5000` at `-lw 1e-4`).
    pub fn divisions(&self, lvl: u32, rweight: f64, cached: bool, lw: f64) -> (f64, usize, usize) {
        if cached {
            let mut wt = AVGREFL.powi(lvl as i32);
            if rweight < 0.1 * wt {
                wt = 1.25 * rweight;
            }
            let total = (self.ad * wt).max(1.0);
            let m = ((total / PI).sqrt().round() as usize).max(4);
            return (wt, m, (PI * m as f64).round() as usize);
        }
        let total = (self.ad * rweight).max(1.0);
        // The most cells whose rays still weigh at least -lw (at least one: a lighter ray is
        // cut by spawn's own -lw test, or rouletted with -lr < 0).
        let cap = if lw > 0.0 {
            (AVGREFL * rweight / lw).floor().max(1.0)
        } else {
            f64::INFINITY
        };
        let cols = |m: usize| {
            if m == 1 {
                // One ring: up to three columns, a single sample when that is all it may take.
                (total.min(cap).round() as usize).clamp(1, 3)
            } else {
                (PI * m as f64).round() as usize
            }
        };
        let mut m = ((total / PI).sqrt().round() as usize).max(1);
        while m > 1 && (m * cols(m)) as f64 > cap {
            m -= 1;
        }
        (rweight, m, cols(m))
    }

    /// The mean radiance (irradiance / π) that the scene's glows with a radius of influence
    /// bring to `p` (normal `n`) from beyond that radius, where they light a point only
    /// through its ambient light: each is sampled as a light source ([`glow_samples`] times,
    /// points nearer than its radius left out), with shadow rays. A value's sample rays
    /// then do not see these glows (`Ray::glow_sampled`), so the light is counted once. A
    /// small glow found by a few of a value's hundreds of sample rays is otherwise the
    /// value's largest source of noise (docs/ambient.md).
    pub fn glow_light(
        &self,
        tr: &Tracer,
        p: DVec3,
        n: DVec3,
        am: [Option<MatId>; MAX_ANTIMATTER],
        cells: usize,
        rng: &mut Sampler,
    ) -> Color {
        let k = glow_samples(cells);
        let mut sum = Color::ZERO;
        let mut buf = Vec::new();
        for (si, maxrad) in tr.lights.sampled_glows() {
            for _ in 0..k {
                buf.clear();
                tr.lights
                    .sample_glow(tr.scene, (si, p), tr.params.ds, rng, &mut buf);
                for smp in &buf {
                    let c = smp.dir.dot(n);
                    if smp.dist <= maxrad || c <= 0.0 {
                        continue;
                    }
                    let t = tr.shadow((p, smp.dir, smp.dist), si, am, rng);
                    if t != Color::ZERO {
                        // The glow's patterns toward p (the shadow ray brings none).
                        let emitted = smp.radiance * tr.sample_pattern(p, smp);
                        sum += emitted * t * (c * smp.omega);
                    }
                }
            }
        }
        sanitize(sum / (k as f64 * PI))
    }

    /// Compute a new value at a hit by sampling the hemisphere around `n`.
    pub(super) fn sample(
        &self,
        tr: &Tracer,
        ray: &Ray,
        hit: &Hit,
        n: DVec3,
        share: Share,
        rng: &mut Sampler,
    ) -> Option<CachedValue> {
        let lvl = ray.amb_level;
        // CPU time of this thread, not wall time: with more threads than cores a value's
        // wall time includes time spent descheduled.
        let start = if lvl == 0 {
            crate::runinfo::thread_cpu_nanos()
        } else {
            0
        };
        let cached = self.cached();
        let (wt, m, nphi) = self.divisions(lvl, ray.weight, cached, tr.params.lw);
        let mut h = self.hemisphere(tr, ray, hit, n, (m, nphi));
        h.stratified(rng);
        let complete = h.complete();
        let extra = (self.as_ * wt).floor();
        if complete && m * nphi > 49 && extra >= 4.0 * m as f64 {
            h.super_sample(extra, !self.settings().ss_own, rng);
        }
        self.stats
            .sample_rays
            .fetch_add(h.traced, Ordering::Relaxed);
        if h.traced == 0 {
            return None;
        }
        let v = self.new_value(&h, wt, complete, share, rng);
        if v.corral != 0 {
            self.stats.corral_values.fetch_add(1, Ordering::Relaxed);
        }
        let lvl_idx = (lvl as usize).min(7);
        self.stats.new_values[lvl_idx].fetch_add(1, Ordering::Relaxed);
        // Deeper values are made inside a level-0 value's sampling: counting level 0 only
        // counts each nanosecond once.
        let nanos = if lvl == 0 {
            crate::runinfo::thread_cpu_nanos().saturating_sub(start)
        } else {
            0
        };
        self.stats.amb_nanos.fetch_add(nanos, Ordering::Relaxed);
        super::compute::count_thread_work(nanos);
        Some(v)
    }

    /// The hemisphere of a new value at `hit` around `n` with `(M, N)` cells, no sample yet.
    fn hemisphere<'t, 'a>(
        &self,
        tr: &'t Tracer<'a>,
        ray: &'t Ray,
        hit: &'t Hit,
        n: DVec3,
        (m, nphi): (usize, usize),
    ) -> Hemisphere<'t, 'a> {
        let cached = self.cached();
        let ncells = m * nphi;
        let u0 = any_perpendicular(n);
        Hemisphere {
            tr,
            ray,
            hit,
            n,
            u0,
            v0: n.cross(u0),
            m,
            nphi,
            // Without a cache each sample ray stands for its share of this one estimate, so
            // it carries the ray's weight over the cell count (deeper bounces then take one
            // sample: path tracing); a cached value is shared by many rays and its samples
            // carry AVGREFL.
            coef: if cached {
                AVGREFL
            } else {
                AVGREFL / ncells as f64
            },
            // A sample ray stands for its cell: about 2π/cells steradians, a footprint of
            // radius about √(2π/cells)/2 per unit distance (cached values only; the
            // uncached estimate keeps every shadow ray).
            spread: if cached {
                0.5 * (2.0 * PI / ncells as f64).sqrt()
            } else {
                0.0
            },
            cached,
            // Glows beyond their radius are sampled explicitly, their emission hidden from
            // the value's own sample rays (cached values only).
            glows: cached
                && self.settings().glow_sampling
                && tr.lights.sampled_glows().next().is_some(),
            max_dist: self.max_dist,
            traced: 0,
            cells: vec![Cell::default(); ncells],
        }
    }

    /// The value a sampled hemisphere makes.
    fn new_value(
        &self,
        h: &Hemisphere,
        wt: f64,
        complete: bool,
        share: Share,
        rng: &mut Sampler,
    ) -> CachedValue {
        let (cached, m, nphi) = (h.cached, h.m, h.nphi);
        let (val, lb) = self.hemisphere_light(h, rng);
        let shape = self.shape(h, &lb, val, wt, complete);
        let mut share = if cached {
            self.share_factor(share, bright(val))
        } else {
            1.0
        };
        // A glow's radius of influence is a seam in the indirect light (the glow is direct
        // light inside, indirect outside): no share reach across it.
        if share > 1.0 {
            let base = self.aa() * shape.reach * shape.rad[1];
            for (si, maxrad) in h.tr.lights.sampled_glows() {
                let gap = ((h.hit.point - h.tr.lights.sources[si].center).length() - maxrad).abs();
                share = share.min((gap / base).max(1.0));
            }
        }
        let corral = if self.settings().corral && cached && m >= CORRAL_MIN_DIVISIONS {
            let hits: Vec<Option<DVec3>> = h
                .cells
                .iter()
                .map(|c| (c.count > 0).then_some(c.hit))
                .collect();
            let reach = self.aa() * shape.reach * share;
            corral_flags(&hits, (m, nphi), h.n, (h.u0, shape.u), shape.rad, reach)
        } else {
            0
        };
        CachedValue {
            id: self.cache.next_id(),
            pos: h.hit.point,
            n: h.n,
            u: shape.u,
            lvl: h.ray.amb_level,
            weight: wt,
            rad: shape.rad,
            gpos: shape.gpos,
            gdir: shape.gdir,
            corral,
            val,
            reach: shape.reach,
            share,
        }
    }

    /// The value's light (the mean of its cells, outliers limited, plus the sampled glows)
    /// and the cells' brightness after the outlier limit; the light enters `-aw`'s average.
    fn hemisphere_light(&self, h: &Hemisphere, rng: &mut Sampler) -> (Color, Vec<f64>) {
        let mut lval: Vec<Color> = h.cells.iter().map(|c| c.mean()).collect();
        let mut lb: Vec<f64> = lval.iter().map(|c| bright(*c)).collect();
        let limit = self.settings().outlier_limit;
        if h.cached && limit > 0.0 {
            clamp_outliers(&mut lval, &mut lb, outlier_limit(limit, h.traced));
        }
        let count = h.cells.len() as f64;
        let mut val = lval.iter().fold(Color::ZERO, |a, c| a + *c) / count;
        if h.glows {
            val += self.glow_light(h.tr, h.hit.point, h.n, h.hit.antimatter, h.cells.len(), rng);
        }
        let b = bright(val);
        if self.aw > 0.0 && b > 0.0 && b.is_finite() {
            if let Ok(mut g) = self.log_sum.lock() {
                g.0 += b.ln();
                g.1 += 1;
            }
        }
        (val, lb)
    }
}

/// Source samples per glow in [`Ambient::glow_light`] for a value of `cells` hemisphere
/// cells: one per 32 cells, at least 8 and at most 64 (shadow rays are cheap next to the
/// value's sample rays, and a partly hidden glow needs several).
pub fn glow_samples(cells: usize) -> usize {
    (cells / 32).clamp(8, 64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::options::RenderParams;

    #[test]
    fn divisions_follow_weight_and_lw() {
        let params = RenderParams {
            ab: 2,
            ad: 1024,
            ..RenderParams::default()
        };
        let amb = Ambient::new(&params, 10.0, 1).unwrap();
        let cells = |(_, m, n): (f64, usize, usize)| m * n;
        // Cached: 0.5^level, at least 4 rings, whatever the ray's weight above a tenth of it.
        let (wt, m, _) = amb.divisions(0, 1.0, true, 1e-4);
        assert_eq!((wt, m), (1.0, 18));
        assert!((cells(amb.divisions(1, 0.4, true, 1e-4)) as f64 - 512.0).abs() < 40.0);
        assert_eq!(amb.divisions(3, 1e-6, true, 1e-4).1, 4);
        // Uncached: the ray's weight; a first-bounce ray (0.5/cells) takes one sample.
        let c0 = cells(amb.divisions(0, 1.0, false, 1e-4));
        assert!((c0 as f64 - 1024.0).abs() < 60.0, "{c0}");
        assert_eq!(cells(amb.divisions(1, 0.5 / c0 as f64, false, 1e-4)), 1);
        // Every sample ray keeps a weight of at least -lw: 0.5·w/cells >= lw.
        for w in [1.0, 0.3, 0.05, 0.01] {
            for lw in [1e-4, 1e-3, 2e-3] {
                let c = cells(amb.divisions(0, w, false, lw)) as f64;
                assert!(c == 1.0 || 0.5 * w / c >= lw, "w {w} lw {lw}: {c} cells");
            }
        }
        // -lw 0: no cap.
        let big = RenderParams {
            ab: 1,
            ad: 20000,
            ..RenderParams::default()
        };
        let amb = Ambient::new(&big, 10.0, 1).unwrap();
        assert!(cells(amb.divisions(0, 1.0, false, 0.0)) > 19000);
        assert!(cells(amb.divisions(0, 1.0, false, 1e-4)) <= 5000);
    }
}
