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
pub use super::hessian::{hessian, hessian_radii};
use super::settings::{caches, computes, AmbientSettings, AS0_SPLIT_LIMIT, CACHE_MIN_AA};
pub use super::settings::{AS0_SPLIT, HESSIAN_CELLS, OUTLIER_LIMIT, SHARE_LIMIT, SHARE_MAX};
use crate::color::{bright, sanitize, Color};
use crate::material::normal::any_perpendicular;
use crate::material::MatId;
use crate::radopt::RenderParams;
use crate::render::ray::{Hit, Ray, RayKind, MAX_ANTIMATTER};
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
    /// New values that got light-leak (corral) flags.
    pub corral_values: AtomicU64,
    /// Light-leak test rays traced at lookups.
    pub leak_tests: AtomicU64,
    /// Cached values rejected at a lookup because a leak-test ray was blocked.
    pub leak_rejects: AtomicU64,
    /// Shadow rays at sample hits answered from their footprint's cube instead of traced
    /// (see [`crate::light::viscache`]).
    pub shadows_reused: AtomicU64,
}

impl AmbientStats {
    /// New values computed so far, all levels.
    pub fn made(&self) -> u64 {
        self.new_values
            .iter()
            .map(|v| v.load(Ordering::Relaxed))
            .sum()
    }
}

/// Number of azimuth sectors of the light-leak ("corral") flags: one bit each in a `u32`.
pub const CORRAL_SECTORS: u32 = 32;

/// Elevation above the shading point's tangent plane of the light-leak test ray.
pub const CORRAL_ELEVATION_DEG: f64 = 20.0;

/// Smallest number of θ divisions of a new value's hemisphere for which flags are computed.
pub const CORRAL_MIN_DIVISIONS: usize = 8;

/// The flag sector of an offset `d` in the frame (u, v) (v = n × u): ⌊atan2(d·v, d·u)·16/π⌋
/// mod 32. A degenerate offset falls in sector 0.
pub fn corral_sector(u: DVec3, v: DVec3, d: DVec3) -> u32 {
    sector_of_angle(d.dot(v).atan2(d.dot(u)))
}

fn sector_of_angle(a: f64) -> u32 {
    let s = (a * (CORRAL_SECTORS as f64 / 2.0) / PI).floor();
    if s.is_finite() {
        (s as i64).rem_euclid(CORRAL_SECTORS as i64) as u32
    } else {
        0
    }
}

/// Flags of every sector that the azimuth interval `[a0, a0 + width]` (radians, width below
/// 2π) touches.
fn corral_span(a0: f64, width: f64) -> u32 {
    let sw = 2.0 * PI / CORRAL_SECTORS as f64;
    let first = sector_of_angle(a0);
    let steps = ((width / sw).ceil() as u32 + 1).min(CORRAL_SECTORS);
    let last = sector_of_angle(a0 + width);
    let mut bits = 0u32;
    for i in 0..steps {
        let s = (first + i) % CORRAL_SECTORS;
        bits |= 1 << s;
        if s == last {
            break;
        }
    }
    bits
}

/// Light-leak ("corral") flags of a new value, from its stratified hemisphere samples.
///
/// `hits[j*nphi + k]` is the hit point (relative to the value's position) of the sample in
/// cell (j, k) (θ ring j with `sin²θ ∈ [j/m, (j+1)/m)`, azimuth column k starting at
/// `φ = 2πk/nphi` in the frame (`u0`, `n × u0`)), None for a cell without a sample. The value's
/// final frame is `u` (v = n × u) with radii `rad`, interpolation accuracy `aa`.
///
/// Flags are computed only when `m ≥ 8` and the "ceiling" — the mean height above the tangent
/// plane of the innermost ring's hits (the overhead samples) — lies beyond the smaller radius.
/// Then every cell of the outermost ring (the samples nearest the tangent plane) whose hit,
/// projected on the tangent plane, lies inside the value's region of use (the ellipse of
/// semi-axes `aa·rad`) marks the sectors its azimuth interval covers: something rises inside
/// the value's reach in that direction (a wall), and a lookup beyond it must check that the
/// value can be seen. With the ceiling beyond `rad0`, its hits in the outermost ring lie at
/// least `√(m−1)·rad0 ≥ 2.6·rad0` away, outside the ellipse (reach at most `2·aa·rad0`) for
/// any `aa` below 1.3, so a plain ceiling never sets a flag.
#[allow(clippy::too_many_arguments)]
pub fn corral_flags(
    hits: &[Option<DVec3>],
    m: usize,
    nphi: usize,
    n: DVec3,
    u0: DVec3,
    u: DVec3,
    rad: [f64; 2],
    aa: f64,
) -> u32 {
    if m < CORRAL_MIN_DIVISIONS || nphi == 0 || hits.len() != m * nphi || aa <= 0.0 {
        return 0;
    }
    let (ra, rb) = (aa * rad[0], aa * rad[1]);
    if !(ra > 0.0 && rb > 0.0 && ra.is_finite() && rb.is_finite()) {
        return 0;
    }
    // The ceiling: mean height of the overhead (innermost ring) hits.
    let (hsum, hcnt) = hits[..nphi]
        .iter()
        .flatten()
        .fold((0.0, 0usize), |(s, c), h| (s + h.dot(n), c + 1));
    let ceiling = if hcnt > 0 { hsum / hcnt as f64 } else { 0.0 };
    if ceiling.is_nan() || ceiling <= rad[0] {
        return 0;
    }
    let v = n.cross(u);
    let v0 = n.cross(u0);
    // Azimuth of u in the (u0, v0) frame: column boundaries shift by it in the (u, v) frame.
    let alpha = u.dot(v0).atan2(u.dot(u0));
    let width = 2.0 * PI / nphi as f64;
    let mut bits = 0u32;
    for (k, h) in hits[(m - 1) * nphi..].iter().enumerate() {
        let Some(h) = h else { continue };
        let (hu, hv) = (h.dot(u) / ra, h.dot(v) / rb);
        if hu * hu + hv * hv < 1.0 {
            bits |= corral_span(k as f64 * width - alpha, width);
        }
    }
    bits
}

/// The end of the light-leak test ray from a shading point `p` (unit normal `n`) toward a
/// cached value at `pv` (unit normal `nv`): the point `Q = pv + t·nv` (t ≥ 0, the smallest)
/// seen from `p` at 20° above the tangent plane of `p`, or `pv + offset·nv` when no such
/// point exists (the value already lies that high, or the normals make it unreachable).
/// Squaring `n·(Q−p) = sin20°·|Q−p|` gives a quadratic in t; roots with `n·(Q−p) ≤ 0` are
/// the mirror solutions below the plane and are dropped.
pub fn corral_target(p: DVec3, n: DVec3, pv: DVec3, nv: DVec3, offset: f64) -> DVec3 {
    let s = CORRAL_ELEVATION_DEG.to_radians().sin();
    let a = pv - p;
    let (na, nb, ab) = (n.dot(a), n.dot(nv), a.dot(nv));
    let qa = nb * nb - s * s;
    let qb = 2.0 * (na * nb - s * s * ab);
    let qc = na * na - s * s * a.length_squared();
    let mut roots = [f64::NAN; 2];
    if qa.abs() > 1e-12 {
        let disc = qb * qb - 4.0 * qa * qc;
        if disc >= 0.0 {
            let sq = disc.sqrt();
            // Numerically stable pair of roots.
            let q = -0.5 * (qb + qb.signum() * sq);
            // q vanishes only with qb = disc = 0 (then qc = 0 too): a double root at 0.
            roots = if q != 0.0 {
                [q / qa, qc / q]
            } else {
                [0.0, 0.0]
            };
        }
    } else if qb.abs() > 1e-300 {
        roots[0] = -qc / qb;
    }
    let best = roots
        .iter()
        .copied()
        .filter(|t| t.is_finite() && *t >= 0.0 && n.dot(a + *t * nv) > 0.0)
        .fold(f64::INFINITY, f64::min);
    if best.is_finite() {
        pv + best * nv
    } else {
        pv + offset * nv
    }
}

/// A value that may apply at a lookup with the share reach (see
/// [`Ambient::interpolate_share`]).
struct Candidate {
    /// Normalised distance² (in the value's radii).
    dt2: f64,
    /// Angle term² between the normals.
    dr2: f64,
    /// The value extrapolated to the lookup.
    val: Color,
    reach: f64,
    share: f64,
}

thread_local! {
    /// Per-thread buffer of [`Candidate`]s (reused between lookups).
    static CANDIDATES: std::cell::RefCell<Vec<Candidate>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// Identities of calculations ([`Ambient::owner`]).
static NEXT_OWNER: AtomicU64 = AtomicU64::new(1);

/// The ambient calculation with its shared cache.
pub struct Ambient {
    /// The shared cache.
    pub cache: AmbientCache,
    /// Counters.
    pub stats: AmbientStats,
    /// Tessera's settings of the calculation (fixed when it is set up).
    settings: AmbientSettings,
    /// This calculation's identity for per-thread caches.
    pub owner: u64,
    ab: u32,
    aa: f64,
    ad: f64,
    minarad: f64,
    maxarad: f64,
    max_dist: f64,
    as_: f64,
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
        if !computes(params.ab, params.ad) {
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
        let settings = params.amb.clone();
        let (ad, as_) = split_divisions(params);
        Some(Ambient {
            cache: AmbientCache::new(minarad, aa.max(0.01), origin_id),
            stats: AmbientStats::default(),
            ab: params.ab as u32,
            aa,
            ad,
            as_,
            owner: NEXT_OWNER.fetch_add(1, Ordering::Relaxed),
            settings,
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

    /// Tessera's settings this calculation runs with.
    pub fn settings(&self) -> &AmbientSettings {
        &self.settings
    }

    /// Whether values are cached ([`caches`]); else every request is a fresh estimate.
    pub fn cached(&self) -> bool {
        self.aa > CACHE_MIN_AA
    }

    /// Indirect light reflected with coefficient `refl` at a hit whose (ray-facing,
    /// unperturbed) normal is `n`.
    #[allow(clippy::too_many_arguments)]
    pub fn reflected(
        &self,
        tr: &Tracer,
        ray: &Ray,
        hit: &Hit,
        refl: Color,
        n: DVec3,
        other: f64,
        rng: &mut Sampler,
    ) -> Color {
        let rb = bright(refl);
        if rb <= 0.0 {
            return Color::ZERO;
        }
        let share = Share { refl: rb, other };
        match self.value(tr, ray, hit, n, share, rng) {
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

    fn value(
        &self,
        tr: &Tracer,
        ray: &Ray,
        hit: &Hit,
        n: DVec3,
        share: Share,
        rng: &mut Sampler,
    ) -> Outcome {
        if ray.amb_level >= self.ab || self.excluded(tr, hit) {
            return Outcome::Fallback;
        }
        if !self.cached() {
            // No cache: Monte Carlo at every bounce.
            return match self.sample(tr, ray, hit, n, Share::NONE, rng) {
                Some(v) => Outcome::Value(v.val),
                None => Outcome::Fallback,
            };
        }
        self.stats.lookups.fetch_add(1, Ordering::Relaxed);
        let am = hit.antimatter;
        let (p, lvl, w) = (hit.point, ray.amb_level, ray.weight);
        let mut found = self.interpolate_share(p, n, lvl, w, share, &mut |o, d, t| {
            tr.occluded(o, d, t, am, rng)
        });
        // Before computing a value, take what other processes have shared meanwhile.
        if found.is_none() && self.cache.refresh() > 0 {
            found = self.interpolate_share(p, n, lvl, w, share, &mut |o, d, t| {
                tr.occluded(o, d, t, am, rng)
            });
        }
        if let Some(v) = found {
            self.stats.hits.fetch_add(1, Ordering::Relaxed);
            return Outcome::Value(v);
        }
        match self.sample(tr, ray, hit, n, share, rng) {
            Some(v) => {
                self.cache.insert(v);
                Outcome::Value(v.val)
            }
            None => Outcome::Fallback,
        }
    }

    /// Weighted interpolation of the cached values valid at `p` (Radiance's acceptance
    /// tests and weights), or None when no value applies.
    ///
    /// `occluded(org, dir, dist)` answers whether an opaque surface blocks the segment from
    /// `org` along the unit `dir` within `dist`; it is asked about values whose light-leak
    /// flag is set in the direction of `p` (see [`Ambient::leaks`]). Pass `&mut |_, _, _|
    /// false` to interpolate without the test.
    pub fn interpolate(
        &self,
        p: DVec3,
        n: DVec3,
        level: u32,
        rweight: f64,
        occluded: &mut dyn FnMut(DVec3, DVec3, f64) -> bool,
    ) -> Option<Color> {
        self.interpolate_share(p, n, level, rweight, Share::NONE, occluded)
    }

    /// [`Ambient::interpolate`] at a surface that reflects the indirect light by
    /// `share.refl` and sends `share.other` (brightness) besides: each value may serve out
    /// to its share reach ([`CachedValue::share`]) as far as the indirect light's part of
    /// the surface's light allows here ([`share_factor`]).
    pub fn interpolate_share(
        &self,
        p: DVec3,
        n: DVec3,
        level: u32,
        rweight: f64,
        share: Share,
        occluded: &mut dyn FnMut(DVec3, DVec3, f64) -> bool,
    ) -> Option<Color> {
        let aa = self.aa;
        let mut maxangle = 10f64.to_radians() + aa;
        if rweight < 0.6 {
            maxangle = (maxangle - PI / 2.0) * rweight.powf(0.13) + PI / 2.0;
        }
        let behind = -self.minarad * aa;
        let mut sum = Color::ZERO;
        let mut wsum = 0.0;
        // Whether a value passes Radiance's own tests (reach 1): else a new value is due, even
        // when values of a larger reach contribute, so values stay as dense as rpict's.
        let mut near = false;
        let aa0 = aa;
        // The share reach applies when the surface sends other light besides.
        let share_on = self.settings.share_max > 1.0 && share.other > 0.0;
        // Radiance's tests of value `v` with acceptance limit `lim` (its normalised
        // distance): Some((dt², δr², extrapolated value)) when it passes.
        let mut test = |v: &CachedValue, lim: f64| -> Option<(f64, f64, Color)> {
            let d = v.n.dot(n);
            if d <= 0.0 {
                return None;
            }
            // Rounding can make d exceed 1 for equal normals: keep the angle term real.
            let dr2 = (2.0 - 2.0 * d).max(0.0);
            if dr2 >= maxangle * maxangle {
                return None;
            }
            let dd = p - v.pos;
            let dn = dd.dot(v.n);
            if dn < behind {
                return None;
            }
            let mut dt2 = (dn / v.rad[0]).powi(2);
            if dt2 >= lim * lim {
                return None;
            }
            let vv = v.n.cross(v.u);
            let du = dd.dot(v.u);
            let dv = dd.dot(vv);
            dt2 += (du / v.rad[0]).powi(2) + (dv / v.rad[1]).powi(2);
            if dt2 >= lim * lim {
                return None;
            }
            let rot = v.n.cross(n);
            let f = if !self.settings.gradients {
                1.0
            } else {
                1.0 + v.gpos[0] * du
                    + v.gpos[1] * dv
                    + v.gdir[0] * rot.dot(v.u)
                    + v.gdir[1] * rot.dot(vv)
            };
            if f <= 0.05 {
                return None;
            }
            let f = f.min(20.0);
            if self.settings.corral && v.corral != 0 && self.leaks(v, p, n, du, dv, occluded) {
                return None;
            }
            Some((dt2, dr2, v.val * f))
        };
        let usable =
            |v: &CachedValue| v.lvl < level || (v.lvl == level && v.weight >= 0.9 * rweight);
        // Add a value that passed with acceptance limit `lim` (hat weight falling to zero
        // there); it is near (no new value due) within `near_lim`.
        let mut add = |dt2: f64, dr2: f64, val: Color, lim: f64, near_lim: f64| {
            near |= dt2 < near_lim * near_lim;
            let w = (1.0 - dr2.sqrt() / maxangle) * (1.0 - dt2.sqrt() / lim);
            sum += val * w;
            wsum += w;
        };
        if !share_on {
            // The cache hands on only values whose reach sphere (|P − P_v| <
            // aa·reach·share·max(rad), implied by the elliptical test) holds P.
            self.cache.for_each_near(p, |v| {
                if !usable(v) {
                    return;
                }
                // This value's acceptance limit: -aa times its reach.
                let lim = aa0 * v.reach;
                if let Some((dt2, dr2, val)) = test(v, lim) {
                    add(dt2, dr2, val, lim, aa0);
                }
            });
            return (near && wsum > FTINY).then(|| sum / wsum);
        }
        // With the share reach: first every value that may apply at its widest, then one
        // share factor for all of them from the nearest one's light (a factor per value would
        // favour the values that are darker than their neighbours).
        let mut cands = CANDIDATES.with(|c| std::mem::take(&mut *c.borrow_mut()));
        cands.clear();
        self.cache.for_each_near(p, |v| {
            if !usable(v) {
                return;
            }
            let sh = v.share.max(1.0);
            if let Some((dt2, dr2, val)) = test(v, aa0 * v.reach * sh) {
                cands.push(Candidate {
                    dt2,
                    dr2,
                    val,
                    reach: v.reach,
                    share: sh,
                });
            }
        });
        let nearest = cands
            .iter()
            .min_by(|a, b| a.dt2.total_cmp(&b.dt2))
            .map(|c| bright(c.val));
        if let Some(b) = nearest {
            let s_here = self.share_factor(share, b);
            for c in &cands {
                let s = c.share.min(s_here);
                let lim = aa0 * c.reach * s;
                if c.dt2 < lim * lim {
                    add(c.dt2, c.dr2, c.val, lim, aa0 * s);
                }
            }
        }
        CANDIDATES.with(|c| *c.borrow_mut() = cands);
        (near && wsum > FTINY).then(|| sum / wsum)
    }

    /// The light-leak test of a flagged value `v` seen from `p` (normal `n`), whose offset in
    /// the value's frame is (du, dv): when the flag of the offset's sector is set, a shadow
    /// ray from `p` toward the point above the value seen at 20° elevation
    /// ([`corral_target`]) must reach it; true when it is blocked (the value would leak
    /// light through a wall).
    fn leaks(
        &self,
        v: &CachedValue,
        p: DVec3,
        n: DVec3,
        du: f64,
        dv: f64,
        occluded: &mut dyn FnMut(DVec3, DVec3, f64) -> bool,
    ) -> bool {
        if v.corral & (1u32 << sector_of_angle(dv.atan2(du))) == 0 {
            return false;
        }
        let d = p - v.pos;
        let dist = d.length();
        if dist.is_nan() || dist <= 1e-4 * v.rad[0] {
            // At the value itself: nothing can stand in between.
            return false;
        }
        let q = corral_target(p, n, v.pos, v.n, 0.05 * dist);
        let to = q - p;
        let len = to.length();
        if !(len > FTINY && len.is_finite()) {
            return false;
        }
        self.stats.leak_tests.fetch_add(1, Ordering::Relaxed);
        // Stop just short of Q, which lies in free space above the value's surface.
        let blocked = occluded(p, to / len, len * (1.0 - 1e-3));
        if blocked {
            self.stats.leak_rejects.fetch_add(1, Ordering::Relaxed);
        }
        blocked
    }

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
                    .sample_glow(tr.scene, si, p, tr.params.ds, rng, &mut buf);
                for smp in &buf {
                    let c = smp.dir.dot(n);
                    if smp.dist <= maxrad || c <= 0.0 {
                        continue;
                    }
                    let t = tr.shadow(p, smp.dir, smp.dist, si, am, rng);
                    sum += smp.radiance * t * (c * smp.omega);
                }
            }
        }
        sanitize(sum / (k as f64 * PI))
    }

    /// Compute a new value at a hit by sampling the hemisphere around `n`.
    fn sample(
        &self,
        tr: &Tracer,
        ray: &Ray,
        hit: &Hit,
        n: DVec3,
        share: Share,
        rng: &mut Sampler,
    ) -> Option<CachedValue> {
        let start = Instant::now();
        let lvl = ray.amb_level;
        let cached = self.cached();
        let (wt, m, nphi) = self.divisions(lvl, ray.weight, cached, tr.params.lw);
        // Without a cache each sample ray stands for its share of this one estimate, so it
        // carries the ray's weight over the cell count (deeper bounces then take one sample:
        // path tracing); a cached value is shared by many rays and its samples carry AVGREFL.
        let coef = if cached {
            AVGREFL
        } else {
            AVGREFL / (m * nphi) as f64
        };
        let u0 = any_perpendicular(n);
        let v0 = n.cross(u0);
        let ncells = m * nphi;
        // Glows beyond their radius are sampled explicitly, their emission hidden from the
        // value's own sample rays (cached values only).
        let glows =
            cached && self.settings.glow_sampling && tr.lights.sampled_glows().next().is_some();
        let mut cells = vec![Cell::default(); ncells];
        let mut traced = 0u64;
        // A sample ray stands for its cell: about 2π/cells steradians, a footprint of radius
        // about √(2π/cells)/2 per unit distance (cached values only; the uncached estimate
        // keeps every shadow ray).
        let spread = if cached {
            0.5 * (2.0 * PI / ncells as f64).sqrt()
        } else {
            0.0
        };
        // One jittered sample in cell (j, k): its value, distance and direction.
        let mut shoot = |j: usize,
                         k: usize,
                         (r1, r2): (f64, f64),
                         rng: &mut Sampler|
         -> Option<(Color, f64, DVec3)> {
            let s2 = (j as f64 + r1) / m as f64;
            let st = s2.sqrt();
            let ct = (1.0 - s2).max(0.0).sqrt();
            let phi = 2.0 * PI * (k as f64 + r2) / nphi as f64;
            let dir = n * ct + (u0 * phi.cos() + v0 * phi.sin()) * st;
            let mut r = tr.spawn(ray, hit, dir, RayKind::Ambient, Color::splat(coef))?;
            r.amb_level = lvl + 1;
            r.spread = spread;
            r.reach = 0.0;
            r.sample_path = cached;
            r.glow_sampled = glows;
            traced += 1;
            let (c, t) = tr.trace_dist(&r, rng);
            Some((c, t.clamp(FTINY, self.max_dist), dir))
        };
        for j in 0..m {
            for k in 0..nphi {
                let r = rng.next2();
                if let Some((c, t, dir)) = shoot(j, k, r, rng) {
                    let cell = &mut cells[j * nphi + k];
                    cell.add(c, t);
                    cell.hit = dir * t;
                }
            }
        }
        let complete = cells.iter().all(|c| c.count > 0);
        // Super-sampling (-as): extra rays where neighbouring cells differ most, in proportion
        // to the cells' estimated standard deviations (Neyman allocation).
        let extra = (self.as_ * wt).floor();
        if complete && ncells > 49 && extra >= 4.0 * m as f64 {
            let b: Vec<f64> = cells.iter().map(|c| bright(c.mean())).collect();
            let share = super_sample_shares(&b, m, nphi);
            let ssum: f64 = share.iter().sum();
            if ssum > 0.0 {
                // Systematic allocation: cell i gets floor(acc_i) − floor(acc_{i−1}) rays with
                // acc the running share of `extra`, so the total is exactly `extra`.
                let mut acc = rng.next2().0;
                let mut perm: Vec<usize> = Vec::new();
                for (idx, si) in share.iter().enumerate() {
                    let before = acc.floor();
                    acc += extra * si / ssum;
                    let nextra = (acc.floor() - before) as usize;
                    let (j, k) = (idx / nphi, idx % nphi);
                    // A cell's extra samples form a Latin hypercube over it: stratified in
                    // both directions, each sample still uniform over the whole cell.
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
                        if let Some((c, t, _)) = shoot(j, k, r, rng) {
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
        let mut lval: Vec<Color> = cells.iter().map(|c| c.mean()).collect();
        let mut lb: Vec<f64> = lval.iter().map(|c| bright(*c)).collect();
        if cached && self.settings.outlier_limit > 0.0 {
            clamp_outliers(
                &mut lval,
                &mut lb,
                outlier_limit(self.settings.outlier_limit, traced),
            );
        }
        let dist: Vec<f64> = cells.iter().map(|c| c.dist(self.max_dist)).collect();
        let count = ncells as f64;
        let mut val = lval.iter().fold(Color::ZERO, |a, c| a + *c) / count;
        if glows {
            val += self.glow_light(tr, hit.point, n, hit.antimatter, ncells, rng);
        }
        let rsum: f64 = dist.iter().map(|d| 1.0 / d).sum();
        let b = bright(val);
        if self.aw > 0.0 && b > 0.0 && b.is_finite() {
            if let Ok(mut g) = self.log_sum.lock() {
                g.0 += b.ln();
                g.1 += 1;
            }
        }
        // Gradients (Ward & Heckbert 1992) of the brightness, relative to the value.
        // Gradients, radii and light-leak flags serve interpolation only: an uncached
        // estimate (-aa 0) is used once and needs none of them.
        let (gpos, gdir) = if cached && b > FTINY && m > 1 && nphi > 1 {
            gradients(&lb, &dist, m, nphi, u0, v0)
        } else {
            (DVec3::ZERO, DVec3::ZERO)
        };
        let scale = if b > FTINY { 1.0 / b } else { 0.0 };
        // Radii: from the Hessian when the mesh of hit points is complete, else the harmonic
        // mean distance (isotropic).
        let hess = if cached && complete && self.settings.hessian && m > 1 && nphi > 2 {
            let pts: Vec<DVec3> = cells.iter().map(|c| c.hit).collect();
            hessian(&pts, &lb, m, nphi, n, u0, v0, self.settings.hessian_cells)
                .and_then(|h| hessian_radii(&h))
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
        // The Hessian's own radii (r0 ≤ r1, as `hessian_radii` returns them), kept for the reach.
        let hess_rad = hess.is_some().then_some(rad);
        let mut u = u;
        let mut v = n.cross(u);
        let mut gp = [gpos.dot(u) * scale, gpos.dot(v) * scale];
        let mut gd = [gdir.dot(u) * scale, gdir.dot(v) * scale];
        // Radiance's post-processing, in order, except that the gradient does not shrink
        // Hessian radii (`rad_i ≤ 1/|gpos_i|`) unless `gradient_limits_radii`: the Hessian
        // already sets them from the light's variation, and a noisy gradient (a bright patch
        // caught by a few cells) would shrink them for noise. The gradient is still capped
        // to the radii below. Radii from the mean distance (no Hessian) keep the limit.
        if self.settings.gradient_radii || hess_rad.is_none() {
            for i in 0..2 {
                if gp[i].abs() * rad[i] > 1.0 {
                    rad[i] = 1.0 / gp[i].abs();
                }
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
        // The room the Hessian leaves beyond the radii used: where `-ar`'s largest radius or
        // the 1:2 aspect limit shrank them, interpolating farther stays within the Hessian's
        // error target, and averages more values' noise.
        let reach = match hess_rad {
            Some(h) if self.settings.reach => {
                let s = wt.sqrt();
                (h[0] / s / rad[0])
                    .min(h[1] / s / rad[1])
                    .clamp(1.0, REACH_MAX)
            }
            _ => 1.0,
        };
        let reach = if reach.is_finite() { reach } else { 1.0 };
        let mut share = if cached {
            self.share_factor(share, bright(val))
        } else {
            1.0
        };
        // A glow's radius of influence is a seam in the indirect light (the glow is direct
        // light inside, indirect outside): no share reach across it.
        if share > 1.0 {
            let base = self.aa * reach * rad[1];
            for (si, maxrad) in tr.lights.sampled_glows() {
                let gap = ((hit.point - tr.lights.sources[si].center).length() - maxrad).abs();
                share = share.min((gap / base).max(1.0));
            }
        }
        let corral = if self.settings.corral && cached && m >= CORRAL_MIN_DIVISIONS {
            let hits: Vec<Option<DVec3>> = cells
                .iter()
                .map(|c| (c.count > 0).then_some(c.hit))
                .collect();
            corral_flags(&hits, m, nphi, n, u0, u, rad, self.aa * reach * share)
        } else {
            0
        };
        if corral != 0 {
            self.stats.corral_values.fetch_add(1, Ordering::Relaxed);
        }
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
            corral,
            val,
            reach,
            share,
        })
    }

    /// How much farther than `-aa` a value of brightness `val` may serve a surface that
    /// reflects it by `share.refl` and sends `share.other` besides:
    /// `√((I + other) / I)` with `I = refl·val`, between 1 and `share_max`. An
    /// interpolation error of the indirect light is `(I + other)/I` times smaller in the
    /// surface's light; for an error growing as the distance, this spacing minimises the
    /// summed squared error for a given number of values (docs/ambient.md).
    pub fn share_factor(&self, share: Share, val: f64) -> f64 {
        if self.settings.share_max <= 1.0 || share.other.is_nan() || share.other <= 0.0 {
            return 1.0;
        }
        let i = share.refl * val;
        if i.is_nan() || i <= 0.0 {
            return self.settings.share_max;
        }
        let f = ((i + share.other) / i).sqrt();
        if f.is_finite() {
            f.clamp(1.0, self.settings.share_max)
        } else {
            self.settings.share_max
        }
    }
}

/// What else a surface sends beside its reflected indirect light ([`Ambient::share_factor`]).
#[derive(Clone, Copy, Debug)]
pub struct Share {
    /// Brightness of the surface's reflectance for the indirect light.
    pub refl: f64,
    /// Brightness of the rest of its light (direct, specular, emitted).
    pub other: f64,
}

impl Share {
    /// Nothing else known: Radiance's rule.
    pub const NONE: Share = Share {
        refl: 1.0,
        other: 0.0,
    };
}

/// The hemisphere divisions and super-sampling rays (`-ad`, `-as`) a cached value uses:
/// as given, except that with `-as 0` a share [`AmbientSettings::as0_split`] of the `-ad`
/// rays is spent on super-sampling: `-ad (1 − split)·N -as split·N`, the same rays per value.
/// The uncached calculation (`-aa 0`) keeps `-ad` and `-as` as given.
pub fn split_divisions(params: &RenderParams) -> (f64, f64) {
    let ad = params.ad.max(0) as f64;
    let split = params.amb.as0_split.clamp(0.0, AS0_SPLIT_LIMIT);
    if caches(params.ab, params.ad, params.aa) && params.as_ <= 0 && split > 0.0 {
        (ad * (1.0 - split), (ad * split).floor())
    } else {
        (ad, params.as_.max(0) as f64)
    }
}

/// Source samples per glow in [`Ambient::glow_light`] for a value of `cells` hemisphere
/// cells: one per 32 cells, at least 8 and at most 64 (shadow rays are cheap next to the
/// value's sample rays, and a partly hidden glow needs several).
pub fn glow_samples(cells: usize) -> usize {
    (cells / 32).clamp(8, 64)
}

/// Largest interpolation reach of a value ([`CachedValue::reach`]), in units of `-aa`.
pub const REACH_MAX: f64 = 2.0;

/// The outlier limit for a value of `samples` sample rays: `f` up to 128 samples, then
/// growing as the square root of the count. A value of many samples catches a small bright
/// source (a caustic, a highlight) often enough that cutting it removes real light: on the
/// spheres scene the fixed limit left the floor's indirect light 20–40% low (docs/ambient.md).
pub fn outlier_limit(f: f64, samples: u64) -> f64 {
    f * (samples as f64 / 128.0).max(1.0).sqrt()
}

/// Limits every cell's brightness to `f` × the sum of all the other cells' brightness
/// (scaling its colour), so that one sample that caught a rare bright path (a highlight seen
/// from below a glossy object, a caustic) cannot make the whole value: with few cells such a
/// spike would otherwise be spread over the value's radii. `b` holds the cells' brightness
/// and is scaled with them. Hemispheres of fewer than 16 cells are left alone.
pub fn clamp_outliers(cells: &mut [Color], b: &mut [f64], f: f64) {
    if cells.len() < 16 {
        return;
    }
    let total: f64 = b.iter().sum();
    if !(total > 0.0 && total.is_finite()) {
        return;
    }
    for (c, bi) in cells.iter_mut().zip(b.iter_mut()) {
        let cap = f * (total - *bi);
        if *bi > cap && *bi > 0.0 {
            let k = cap.max(0.0) / *bi;
            *c *= k;
            *bi *= k;
        }
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

/// The columns k − 1, k and k + 1 of a ring of `nphi` cells, wrapping in φ.
#[inline]
fn phi_neighbours(k: usize, nphi: usize) -> [usize; 3] {
    [(k + nphi - 1) % nphi, k, (k + 1) % nphi]
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
            let cols = phi_neighbours(k, nphi);
            for dj in -1i64..=1 {
                let jj = j as i64 + dj;
                if jj < 0 || jj >= m as i64 {
                    continue;
                }
                let row = jj as usize * nphi;
                for (ci, &kk) in cols.iter().enumerate() {
                    if dj == 0 && ci == 1 {
                        continue;
                    }
                    let d = b[row + kk] - c;
                    s += d * d;
                    cnt += 1;
                }
            }
            out[j * nphi + k] = if cnt > 0 { s / cnt as f64 } else { 0.0 };
        }
    }
    out
}

/// How super-sampling shares its extra rays among the cells (not normalised): the estimated
/// standard deviation of each cell, so that a cell's extra rays are proportional to it — the
/// allocation that minimises the variance of a stratified mean for a given number of samples
/// (Neyman). The variance estimate of [`cell_variances`] is first blurred (half the cell's own,
/// half the mean of its 3×3 neighbourhood, wrapping in φ, clamped at the pole and horizon), so a
/// small bright patch (a sunlit spot) that one cell's sample found also draws rays into the
/// cells around it, which may hold the rest of the patch unseen by their first sample.
pub fn super_sample_shares(b: &[f64], m: usize, nphi: usize) -> Vec<f64> {
    let var = cell_variances(b, m, nphi);
    let mut out = vec![0.0; m * nphi];
    for j in 0..m {
        for k in 0..nphi {
            let mut s = 0.0;
            let cols = phi_neighbours(k, nphi);
            for dj in -1i64..=1 {
                let row = (j as i64 + dj).clamp(0, m as i64 - 1) as usize * nphi;
                for &kk in &cols {
                    s += var[row + kk];
                }
            }
            out[j * nphi + k] = (0.5 * var[j * nphi + k] + 0.5 * s / 9.0).sqrt();
        }
    }
    out
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ambient::ValueId;

    const X: DVec3 = DVec3::X;
    const Y: DVec3 = DVec3::Y;
    const Z: DVec3 = DVec3::Z;

    #[test]
    fn one_dominant_cell_is_clamped_to_the_others_sum() {
        let grey = |x: f64| Color::splat(x);
        let clamp = |cells: &mut [Color], f: f64| {
            let mut b: Vec<f64> = cells.iter().map(|c| bright(*c)).collect();
            clamp_outliers(cells, &mut b, f);
            // The brightness is scaled with the colours.
            for (c, bi) in cells.iter().zip(&b) {
                assert!((bright(*c) - bi).abs() <= 1e-12 * bi.abs().max(1e-300));
            }
        };
        // 51 cells of 0.003 and one highlight of 9 (the spheres case): the highlight may
        // bring at most f × 51 × 0.003.
        let mut cells = vec![grey(0.003); 52];
        cells[17] = Color::new(18.0, 9.0, 0.0);
        let before = bright(cells[17]);
        clamp(&mut cells, 1.0);
        let others = 51.0 * bright(grey(0.003));
        assert!((bright(cells[17]) - others).abs() < 1e-12 * others);
        // Its colour keeps its proportions; the other cells are untouched.
        assert!((cells[17].x / cells[17].y - 2.0).abs() < 1e-12 && cells[17].z == 0.0);
        assert!(cells
            .iter()
            .enumerate()
            .all(|(i, c)| i == 17 || *c == grey(0.003)));
        assert!(bright(cells[17]) < before);
        // A bright but not dominant region (a window over 8 of 52 cells) is left alone.
        let mut window = vec![grey(0.01); 52];
        for c in &mut window[20..28] {
            *c = grey(2.0);
        }
        let copy = window.clone();
        clamp(&mut window, 1.0);
        assert_eq!(window, copy);
        // Black and single-cell hemispheres are left alone.
        let mut black = vec![Color::ZERO; 9];
        clamp(&mut black, 1.0);
        assert!(black.iter().all(|c| *c == Color::ZERO));
        let mut one = vec![grey(5.0)];
        clamp(&mut one, 1.0);
        assert_eq!(one[0], grey(5.0));
    }

    #[test]
    fn the_outlier_limit_loosens_with_the_sample_count() {
        // Up to 128 samples the limit is the base factor; at 4× the samples it is twice it.
        assert_eq!(outlier_limit(2.0, 50), 2.0);
        assert_eq!(outlier_limit(2.0, 128), 2.0);
        assert!((outlier_limit(2.0, 512) - 4.0).abs() < 1e-12);
        assert!(outlier_limit(2.0, 1500) > outlier_limit(2.0, 1000));
        // A spike of 3× the other cells' sum: cut in a value of 120 samples, kept whole in
        // one of 600 (a caustic there is caught often enough to be averaged, not removed).
        let spike = |n: usize| {
            let mut cells = vec![Color::splat(0.01); n];
            cells[3] = Color::splat(0.03 * (n - 1) as f64);
            let mut b: Vec<f64> = cells.iter().map(|c| bright(*c)).collect();
            let before = b[3];
            clamp_outliers(&mut cells, &mut b, outlier_limit(OUTLIER_LIMIT, n as u64));
            b[3] / before
        };
        assert!(spike(120) < 0.7);
        assert_eq!(spike(600), 1.0);
    }

    #[test]
    fn sectors_follow_atan2_in_the_value_frame() {
        let s = |x: f64, y: f64| corral_sector(X, Y, DVec3::new(x, y, 0.0));
        assert_eq!(s(1.0, 0.0), 0);
        assert_eq!(s(0.0, 1.0), 8);
        assert_eq!(s(-1.0, 0.0), 16);
        assert_eq!(s(0.0, -1.0), 24);
        assert_eq!(s(1.0, -1e-9), 31);
        let deg = |a: f64| s(a.to_radians().cos(), a.to_radians().sin());
        assert_eq!(deg(11.0), 0);
        assert_eq!(deg(12.0), 1);
        assert_eq!(deg(-11.0), 31);
        assert_eq!(deg(179.0), 15);
        // The component along the normal does not matter; a null offset is sector 0.
        assert_eq!(corral_sector(X, Y, DVec3::new(0.0, 1.0, 5.0)), 8);
        assert_eq!(corral_sector(X, Y, DVec3::ZERO), 0);
        // Another frame: u = y, v = z × y = −x.
        assert_eq!(corral_sector(Y, -X, DVec3::new(-1.0, 0.0, 0.0)), 8);
        // Spans wrap around.
        let w = 0.3;
        assert_eq!(corral_span(-0.1, w), (1 << 31) | 1 | 2);
        assert_eq!(corral_span(0.01, 0.01), 1);
        assert_eq!(corral_span(0.0, 2.0 * PI - 1e-9).count_ones(), 32);
    }

    fn elevation(p: DVec3, n: DVec3, q: DVec3) -> f64 {
        (n.dot((q - p).normalize())).asin().to_degrees()
    }

    #[test]
    fn target_is_seen_at_twenty_degrees() {
        // Coplanar: Q = pv + |pv − p|·tan20° · n.
        let q = corral_target(DVec3::ZERO, Z, X, Z, 0.01);
        assert!((q - DVec3::new(1.0, 0.0, 20f64.to_radians().tan())).length() < 1e-12);
        // Tilted normals and a value a little below or above the plane.
        let n = DVec3::new(0.1, -0.05, 1.0).normalize();
        for (pv, nv) in [
            (
                DVec3::new(0.7, 0.4, -0.05),
                DVec3::new(-0.15, 0.1, 1.0).normalize(),
            ),
            (
                DVec3::new(-0.3, 0.9, 0.1),
                DVec3::new(0.2, 0.2, 1.0).normalize(),
            ),
            (DVec3::new(0.2, -0.5, 0.0), n),
        ] {
            let p = DVec3::new(0.05, 0.02, 0.0);
            let q = corral_target(p, n, pv, nv, 0.01);
            let t = (q - pv).dot(nv);
            assert!(
                t >= 0.0 && (q - pv - t * nv).length() < 1e-12,
                "{q} off the line"
            );
            let e = elevation(p, n, q);
            assert!((e - 20.0).abs() < 1e-9, "elevation {e}");
        }
        // A value already seen at 45°: no point of its normal line is at 20°; the fallback.
        let pv = DVec3::new(1.0, 0.0, 1.0);
        let q = corral_target(DVec3::ZERO, Z, pv, Z, 0.01);
        assert!((q - (pv + 0.01 * Z)).length() < 1e-12);
        // Degenerate input stays finite.
        let q = corral_target(DVec3::ZERO, Z, DVec3::ZERO, Z, 0.01);
        assert!(q.is_finite());
    }

    /// Hit points of cell-centre directions in a room: a wall x = `wall` (if any), a
    /// ceiling z = `ceil`, nothing else within 1000.
    fn hemisphere(
        m: usize,
        nphi: usize,
        u0: DVec3,
        wall: Option<f64>,
        ceil: f64,
    ) -> Vec<Option<DVec3>> {
        let v0 = Z.cross(u0);
        let mut out = Vec::new();
        for j in 0..m {
            for k in 0..nphi {
                let s2 = (j as f64 + 0.5) / m as f64;
                let (st, ct) = (s2.sqrt(), (1.0 - s2).sqrt());
                let phi = 2.0 * PI * (k as f64 + 0.5) / nphi as f64;
                let d = Z * ct + (u0 * phi.cos() + v0 * phi.sin()) * st;
                let mut t: f64 = 1000.0;
                if d.z > 0.0 {
                    t = t.min(ceil / d.z);
                }
                if let Some(w) = wall {
                    if d.x > 0.0 {
                        t = t.min(w / d.x);
                    }
                }
                out.push(Some(d * t));
            }
        }
        out
    }

    #[test]
    fn flags_mark_the_wall_side_only() {
        let (m, nphi) = (10, 31);
        let u0 = DVec3::new(0.6, 0.8, 0.0);
        // The value's final frame: u at 30° from x.
        let u = DVec3::new(30f64.to_radians().cos(), 30f64.to_radians().sin(), 0.0);
        let v = Z.cross(u);
        let rad = [1.0, 1.5];
        let aa = 0.5;
        let hits = hemisphere(m, nphi, u0, Some(0.3), 3.0);
        let bits = corral_flags(&hits, m, nphi, Z, u0, u, rad, aa);
        let at = |deg: f64| {
            let d = X * deg.to_radians().cos() + Y * deg.to_radians().sin();
            bits & (1 << corral_sector(u, v, d)) != 0
        };
        assert!(at(0.0) && at(30.0) && at(-30.0), "{bits:032b}");
        assert!(
            !at(180.0) && !at(90.0) && !at(-90.0) && !at(120.0),
            "{bits:032b}"
        );
        // The flagged sectors form one run around +x.
        let runs = (0..32)
            .filter(|&i| bits & (1 << i) != 0 && bits & (1 << ((i + 31) % 32)) == 0)
            .count();
        assert_eq!(runs, 1, "{bits:032b}");
        // No wall, a low ceiling, a coarse grid or a wall beyond the reach: no flags.
        let open = hemisphere(m, nphi, u0, None, 3.0);
        assert_eq!(corral_flags(&open, m, nphi, Z, u0, u, rad, aa), 0);
        let low = hemisphere(m, nphi, u0, Some(0.3), 0.8);
        assert_eq!(corral_flags(&low, m, nphi, Z, u0, u, rad, aa), 0);
        let (mc, nc) = (7, 22);
        let coarse = hemisphere(mc, nc, u0, Some(0.3), 3.0);
        assert_eq!(corral_flags(&coarse, mc, nc, Z, u0, u, rad, aa), 0);
        let far = hemisphere(m, nphi, u0, Some(0.9), 3.0);
        assert_eq!(corral_flags(&far, m, nphi, Z, u0, u, rad, aa), 0);
        // A ceiling far above a large value never flags by itself.
        let big = [2.9, 5.8];
        assert_eq!(corral_flags(&open, m, nphi, Z, u0, u, big, 1.0), 0);
        // Missing samples count for nothing.
        let mut holes = hits.clone();
        for h in holes[(m - 1) * nphi..].iter_mut() {
            *h = None;
        }
        assert_eq!(corral_flags(&holes, m, nphi, Z, u0, u, rad, aa), 0);
    }

    /// A level-0 value at `pos` facing +z, radii 1, no gradients, grey `val`.
    fn unit_value(pos: DVec3, val: f64, corral: u32, reach: f64) -> CachedValue {
        CachedValue {
            id: ValueId::default(),
            pos,
            n: Z,
            u: X,
            lvl: 0,
            weight: 1.0,
            rad: [1.0, 1.0],
            gpos: [0.0; 2],
            gdir: [0.0; 2],
            corral,
            val: Color::splat(val),
            reach,
            share: 1.0,
        }
    }

    /// A calculation at `-ab 1 -aa .2` in a scene of size 10.
    fn test_ambient() -> Ambient {
        test_ambient_with(AmbientSettings::default())
    }

    /// [`test_ambient`] with other settings.
    fn test_ambient_with(amb: AmbientSettings) -> Ambient {
        let params = RenderParams {
            ab: 1,
            aa: 0.2,
            amb,
            ..RenderParams::default()
        };
        Ambient::new(&params, 10.0, 1).unwrap()
    }

    #[test]
    fn share_factor_follows_the_indirect_lights_part() {
        let amb = test_ambient_with(AmbientSettings {
            share_max: 3.0,
            ..AmbientSettings::default()
        });
        let s = |refl: f64, other: f64, val: f64| amb.share_factor(Share { refl, other }, val);
        // Nothing else known, or nothing else sent: Radiance's rule.
        assert_eq!(s(0.5, 0.0, 1.0), 1.0);
        assert_eq!(amb.share_factor(Share::NONE, 1.0), 1.0);
        // Indirect 0.5 of a total of 2: √4 = 2.
        assert!((s(0.5, 1.5, 1.0) - 2.0).abs() < 1e-12);
        // Indirect a ninth or less: the cap; black values: the cap.
        assert_eq!(s(0.5, 100.0, 1.0), 3.0);
        assert_eq!(s(0.5, 1.0, 0.0), 3.0);
        // Mostly indirect: barely more than 1; never below.
        assert!((s(0.5, 0.05, 1.0) - 1.1f64.sqrt()).abs() < 1e-12);
        assert!(s(0.5, f64::NAN, 1.0) == 1.0);
        let amb = test_ambient_with(AmbientSettings {
            share_max: 1.0,
            ..AmbientSettings::default()
        });
        let far = Share {
            refl: 0.5,
            other: 100.0,
        };
        assert_eq!(amb.share_factor(far, 1.0), 1.0);
    }

    #[test]
    fn a_wider_reach_adds_weight_but_never_replaces_a_new_value() {
        let params = RenderParams {
            ab: 1,
            aa: 0.2,
            ..RenderParams::default()
        };
        let amb = Ambient::new(&params, 10.0, 1).unwrap();
        let value = |x: f64, v: f64, reach: f64| unit_value(DVec3::new(x, 0.0, 0.0), v, 0, reach);
        let mut clear = |_: DVec3, _: DVec3, _: f64| false;
        // Reach 2 at the origin: the normalised distance 0.3 is beyond aa = 0.2 but within
        // 2·aa. Alone, it does not spare a new value there.
        amb.cache.insert(value(0.0, 1.0, 2.0));
        let p = DVec3::new(0.3, 0.0, 0.0);
        assert!(amb.interpolate(p, Z, 0, 1.0, &mut clear).is_none());
        assert!(amb
            .interpolate(DVec3::new(0.1, 0.0, 0.0), Z, 0, 1.0, &mut clear)
            .is_some());
        // With a reach-1 value within aa of p, the wide value joins the average with the hat
        // weight 1 − 0.3/0.4 = 0.25 (the near value at 0.05 weighs 1 − 0.05/0.2 = 0.75).
        amb.cache.insert(value(0.35, 3.0, 1.0));
        let got = amb.interpolate(p, Z, 0, 1.0, &mut clear).unwrap();
        let want = (0.25 * 1.0 + 0.75 * 3.0) / (0.25 + 0.75);
        assert!((got.x - want).abs() < 1e-9, "{got} vs {want}");
        // Beyond 2·aa it is out of reach: only the near value counts.
        let far = DVec3::new(0.45, 0.0, 0.0);
        let got = amb.interpolate(far, Z, 0, 1.0, &mut clear).unwrap();
        assert!((got.x - 3.0).abs() < 1e-9, "{got}");
    }

    #[test]
    fn lookup_tests_flagged_values_only_in_their_sectors() {
        let amb = test_ambient();
        assert!(amb.settings().corral);
        // A value at the origin facing +z, radius 1, a wall flagged toward +x (sectors 30..1).
        let corral = (1u32 << 30) | (1 << 31) | 1 | 2;
        amb.cache.insert(unit_value(DVec3::ZERO, 1.0, corral, 1.0));
        let mut asked = Vec::new();
        let mut blocked = |o: DVec3, d: DVec3, t: f64| {
            asked.push((o, d, t));
            true
        };
        let east = DVec3::new(0.1, 0.0, 0.0);
        let west = DVec3::new(-0.1, 0.0, 0.0);
        assert!(amb.interpolate(east, Z, 0, 1.0, &mut blocked).is_none());
        assert!(amb.interpolate(west, Z, 0, 1.0, &mut blocked).is_some());
        assert_eq!(asked.len(), 1, "only the flagged direction is tested");
        let (o, d, t) = asked[0];
        assert_eq!(o, east);
        // Toward the point above the value seen at 20°, stopping just short of it.
        let q = o + d * t;
        assert!((elevation(east, Z, q) - 20.0).abs() < 1e-9);
        assert!(q.x.abs() < 1e-3 && (q.z - 0.1 * 20f64.to_radians().tan()).abs() < 1e-3);
        let mut clear = |_: DVec3, _: DVec3, _: f64| false;
        assert!(amb.interpolate(east, Z, 0, 1.0, &mut clear).is_some());
        // Switched off: never asked, never rejected.
        let amb = test_ambient_with(AmbientSettings {
            corral: false,
            ..AmbientSettings::default()
        });
        amb.cache.insert(unit_value(DVec3::ZERO, 1.0, corral, 1.0));
        let mut never = |_: DVec3, _: DVec3, _: f64| -> bool { panic!("asked") };
        assert!(amb.interpolate(east, Z, 0, 1.0, &mut never).is_some());
    }

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
