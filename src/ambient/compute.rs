//! The ambient calculation's facade (Ward, Rubinstein & Clear 1988; gradients after Ward &
//! Heckbert 1992): [`Ambient`] is set up once per render from the options and answers every
//! request for indirect light at a shading point, from the cache when cached values apply
//! ([`super::lookup`]), else with a new value ([`super::sample`]) that it caches.
//!
//! A value is the mean incoming radiance (irradiance/π), independent of the surface's
//! reflectance, so it serves every material.

use super::cache::AmbientCache;
use super::settings::{caches, computes, AmbientSettings, AS0_SPLIT_LIMIT, CACHE_MIN_AA};
use super::striped::Striped;
use crate::color::{bright, Color};
use crate::light::viscache::VisQuery;
use crate::options::render::RenderParams;
use crate::render::ray::{Hit, Ray};
use crate::render::sampler::Sampler;
use crate::render::trace::{DirectPlan, IndirectLight, IndirectRequest, Tracer};
use glam::DVec3;
use std::collections::HashSet;
use std::sync::atomic::{AtomicU64, Ordering};

/// Radiance's average reflectance assumed for ambient rays.
pub const AVGREFL: f64 = 0.5;

/// Counters of the ambient calculation (the seed paper's T_amb among them).
#[derive(Debug, Default)]
pub struct AmbientStats {
    /// Cache lookups.
    pub lookups: Striped,
    /// Lookups answered by interpolation.
    pub hits: Striped,
    /// New values computed, by ambient level (index clamped to 7).
    pub new_values: [AtomicU64; 8],
    /// CPU nanoseconds (of the threads that made them) spent computing new level-0 values,
    /// including their child rays and the deeper values made inside them, so nothing is
    /// counted twice.
    pub amb_nanos: AtomicU64,
    /// Hemisphere sample rays traced.
    pub sample_rays: Striped,
    /// New values that got light-leak (corral) flags.
    pub corral_values: AtomicU64,
    /// Light-leak test rays traced at lookups.
    pub leak_tests: Striped,
    /// Cached values rejected at a lookup because a leak-test ray was blocked.
    pub leak_rejects: Striped,
    /// Shadow rays at sample hits answered from their footprint's cube instead of traced
    /// (see [`crate::light::viscache`]).
    pub shadows_reused: Striped,
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

/// Identities of calculations ([`Ambient::owner`]).
static NEXT_OWNER: AtomicU64 = AtomicU64::new(1);

thread_local! {
    /// New values this thread made and the CPU nanoseconds of its level-0 values
    /// ([`thread_work`]).
    static THREAD_WORK: std::cell::Cell<(u64, u64)> = const { std::cell::Cell::new((0, 0)) };
    /// This thread's `-aa` and the calculation it applies to ([`Ambient::with_accuracy`]).
    static THREAD_AA: std::cell::Cell<Option<(u64, f64)>> = const { std::cell::Cell::new(None) };
}

/// The ambient calculation with its shared cache.
pub struct Ambient {
    /// The shared cache.
    pub cache: AmbientCache,
    /// Counters.
    pub stats: AmbientStats,
    /// Tessera's settings of the calculation (fixed when it is set up).
    settings: AmbientSettings,
    /// This calculation's identity for per-thread caches.
    owner: u64,
    ab: u32,
    /// `-aa` now (f64 bits): fixed, or set per frame by an `-ax` schedule.
    aa_bits: AtomicU64,
    /// The largest `-aa` of the run: values are filed in the cache for it.
    aa_max: f64,
    pub(super) ad: f64,
    pub(super) minarad: f64,
    pub(super) maxarad: f64,
    pub(super) max_dist: f64,
    pub(super) as_: f64,
    av: Color,
    /// `-aw`: weight of `-av` in the moving log-average (0: `-av` stays fixed).
    pub(super) aw: f64,
    /// Σ ln(brightness) of the new values and their count, for `-aw`.
    pub(super) log_sum: std::sync::Mutex<(f64, u64)>,
    exclude: HashSet<String>,
    include: Option<HashSet<String>>,
    /// The shadow answers its threads share (made on first use).
    vis: std::sync::OnceLock<crate::light::viscache::VisTable>,
}

/// New ambient values the calling thread has made so far (every calculation, all levels)
/// and the CPU nanoseconds of its level-0 values: what a render on this thread alone made.
pub fn thread_work() -> (u64, u64) {
    THREAD_WORK.with(|c| c.get())
}

/// Count a new value made on this thread and the CPU nanoseconds it took (0 below level 0).
pub(super) fn count_thread_work(nanos: u64) {
    THREAD_WORK.with(|c| {
        let (n, t) = c.get();
        c.set((n + 1, t.saturating_add(nanos)));
    });
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
        let size = scene_size.max(f64::MIN_POSITIVE);
        let (minarad, maxarad) = if params.ar > 0 {
            let min = size / params.ar as f64;
            (min, (64.0 * min).min(0.2 * size))
        } else {
            (size * 1e-6, 0.2 * size)
        };
        let aa = params.aa.max(0.0);
        // Under -ax (and -axt) values are filed for the loosest accuracy, so that every
        // later (tighter) lookup finds them in the cells it reads.
        // -axm relaxes regions leaving the view by its factor on top.
        let loosest = params.ax.map_or(aa, |s| s.start.max(aa));
        let loosest = params.axt.map_or(loosest, |b| b.start.max(loosest));
        let aa_max = loosest * params.axm.map_or(1.0, |m| m.relax);
        let settings = params.amb.clone();
        let (ad, as_) = split_divisions(params);
        Some(Ambient {
            // Radii never exceed maxarad (a fifth of the scene's size); twice the size leaves
            // room for other renderers' stores (rpict's octree cube is larger).
            cache: AmbientCache::new(minarad, aa_max.max(0.01), origin_id)
                .with_max_radius(2.0 * size),
            stats: AmbientStats::default(),
            ab: params.ab as u32,
            aa_bits: AtomicU64::new(aa.to_bits()),
            aa_max,
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
            vis: std::sync::OnceLock::new(),
        })
    }

    /// Tessera's settings this calculation runs with.
    pub fn settings(&self) -> &AmbientSettings {
        &self.settings
    }

    /// Whether values are cached ([`caches`]); else every request is a fresh estimate.
    pub fn cached(&self) -> bool {
        self.aa() > CACHE_MIN_AA
    }

    /// `-aa` now: this thread's, while it renders under [`Ambient::with_accuracy`], else
    /// the calculation's.
    #[inline]
    pub fn aa(&self) -> f64 {
        match THREAD_AA.with(|c| c.get()) {
            Some((owner, aa)) if owner == self.owner => aa,
            _ => f64::from_bits(self.aa_bits.load(Ordering::Relaxed)),
        }
    }

    /// Run `f` with `-aa` `aa` on this thread only (clamped as [`Ambient::set_accuracy`]
    /// clamps it), for renders on several threads at once that each need their own
    /// accuracy (the tile loops of one worker: tiles of frames with different `-aa` run
    /// side by side). Everything `f` computes must run on the calling thread.
    pub fn with_accuracy<T>(&self, aa: Option<f64>, f: impl FnOnce() -> T) -> T {
        let Some(aa) = aa.filter(|a| a.is_finite() && self.cached()) else {
            return f();
        };
        let aa = aa.clamp(CACHE_MIN_AA * 2.0, self.aa_max.max(CACHE_MIN_AA * 2.0));
        let before = THREAD_AA.with(|c| c.replace(Some((self.owner, aa))));
        // Restored on unwinding too.
        struct Restore(Option<(u64, f64)>);
        impl Drop for Restore {
            fn drop(&mut self) {
                THREAD_AA.with(|c| c.set(self.0));
            }
        }
        let _restore = Restore(before);
        f()
    }

    /// Set `-aa` for the next frame (an `-ax` schedule), between renders: within the
    /// run's loosest accuracy (the cache's filing) and above the uncached limit.
    pub fn set_accuracy(&self, aa: f64) {
        if self.cached() && aa.is_finite() {
            let aa = aa.clamp(CACHE_MIN_AA * 2.0, self.aa_max.max(CACHE_MIN_AA * 2.0));
            self.aa_bits.store(aa.to_bits(), Ordering::Relaxed);
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
        // A point that is no surface (ttrace -I) has no modifier to exclude.
        if hit.obj == crate::render::ray::NO_OBJECT {
            return false;
        }
        let m = tr.scene.hit_info(hit.href()).modifier;
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

impl IndirectLight for Ambient {
    fn reflected(
        &self,
        tr: &Tracer,
        ray: &Ray,
        hit: &Hit,
        req: IndirectRequest,
        rng: &mut Sampler,
    ) -> Color {
        let refl = req.refl;
        let rb = bright(refl);
        if rb <= 0.0 {
            return Color::ZERO;
        }
        let share = Share {
            refl: rb,
            other: req.other,
        };
        match self.value(tr, ray, hit, req.normal, share, rng) {
            Outcome::Value(v) => refl * v,
            Outcome::Fallback => refl * self.fallback(),
        }
    }

    /// Eye paths of the overture (`fill_only`, ambient level 0) need no direct light, whose
    /// colour is discarded, except a rough estimate of it for the share reach
    /// ([`OVERTURE_DIRECT_WEIGHT`]). On a cached value's sample path, shadow rays are reused
    /// within the sample's footprint ([`crate::light::viscache`]).
    fn direct_plan(&self, ray: &Ray, hit: &Hit, fill_only: bool) -> DirectPlan {
        if fill_only && ray.amb_level == 0 {
            return if self.settings.share_max > 1.0 {
                DirectPlan::Estimate {
                    weight: ray.weight * OVERTURE_DIRECT_WEIGHT,
                }
            } else {
                DirectPlan::Skip
            };
        }
        let s = &ray.sample;
        let reuse = if self.settings.shadow_reuse && s.spread > 0.0 {
            let footprint = (s.reach + hit.t) * s.spread;
            VisQuery::new(self.owner, vis_key(hit), hit.back, footprint, hit.point)
                .map(|q| q.with_trust(self.settings.shadow_trust))
        } else {
            None
        };
        DirectPlan::Full(reuse)
    }

    fn shadow_table(&self) -> Option<&crate::light::viscache::VisTable> {
        Some(self.vis.get_or_init(Default::default))
    }

    fn count_reused_shadows(&self, n: u64) {
        self.stats.shadows_reused.fetch_add(n, Ordering::Relaxed);
    }
}

/// The ray weight factor of the overture's direct-light estimate
/// ([`IndirectLight::direct_plan`]): a light ray weight means fewer source partitions and
/// weak sources left untested.
pub const OVERTURE_DIRECT_WEIGHT: f64 = 0.05;

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

/// The object a footprint's shadow answers belong to: the scene's own objects by index,
/// instanced ones by index and placement.
fn vis_key(hit: &Hit) -> usize {
    if hit.is_top() {
        hit.obj
    } else {
        hit.obj ^ ((hit.inst as usize + 1) << 40)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::ambient::cache::CachedValue;
    use crate::ambient::ValueId;

    pub(crate) const X: DVec3 = DVec3::X;
    pub(crate) const Y: DVec3 = DVec3::Y;
    pub(crate) const Z: DVec3 = DVec3::Z;

    /// The elevation (degrees) of `q` seen from `p` above the plane of normal `n`.
    pub(crate) fn elevation(p: DVec3, n: DVec3, q: DVec3) -> f64 {
        (n.dot((q - p).normalize())).asin().to_degrees()
    }

    /// A level-0 value at `pos` facing +z, radii 1, no gradients, grey `val`.
    pub(crate) fn unit_value(pos: DVec3, val: f64, corral: u32, reach: f64) -> CachedValue {
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
    pub(crate) fn test_ambient() -> Ambient {
        test_ambient_with(AmbientSettings::default())
    }

    /// [`test_ambient`] with other settings.
    pub(crate) fn test_ambient_with(amb: AmbientSettings) -> Ambient {
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
}
