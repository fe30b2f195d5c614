//! Direct lighting at a shading point: source samples ordered by their unoccluded potential,
//! shadow rays traced adaptively (`-dt`, `-dc`), untested samples scaled by visibility
//! estimated from the samples tested at this same point (deterministic per pixel, unlike
//! Radiance's run-long per-source statistics).

use super::source::{Partition, SourceSample};
use super::viscache::{self, VisQuery};
use crate::color::{bright, Color};
use crate::render::ray::Hit;
use crate::render::sampler::Sampler;
use crate::render::trace::Tracer;
use glam::DVec3;

/// Shadow rays always traced before the adaptive test may stop (Radiance's MINSHADCNT).
const MIN_SHADOW_TESTS: usize = 2;

/// Per-thread buffers reused by every [`direct`] call (no allocation per shading point).
#[derive(Default)]
struct Scratch {
    samples: Vec<SourceSample>,
    /// The samples with a potential, as sort keys: the potential's bits inverted
    /// (brightest first: positive finite potentials order as their bits) and the sample.
    cands: Vec<(u64, u32)>,
    /// Each sample's unoccluded contribution (read for those in `cands`).
    contrib: Vec<Color>,
    stats: Vec<(f64, u32)>,
    /// `⌈n^dc⌉` by candidate count n, for the `dc` in `nshad_dc` (a `powf` per call saved).
    nshad: Vec<usize>,
    nshad_dc: f64,
}

thread_local! {
    static SCRATCH: std::cell::RefCell<Scratch> = std::cell::RefCell::default();
}

/// Direct light reflected toward the viewer: `coef(l, ω)` is the material's coefficient for
/// light arriving from unit direction `l` over solid angle `ω`.
///
/// `known`: the point's other light known before the shadow tests ([`Tracer::direct`]).
pub fn direct(
    tr: &Tracer,
    (weight, known): (f64, Color),
    hit: &Hit,
    coef: &dyn Fn(DVec3, f64) -> Color,
    rng: &mut Sampler,
    vis: Option<&VisQuery>,
) -> Color {
    let lights = tr.lights;
    if lights.sources.is_empty() {
        return Color::ZERO;
    }
    // The thread's buffers, borrowed for the call; a nested call (none today: shadow rays
    // and source patterns never light a point) would take buffers of its own.
    SCRATCH.with(|s| match s.try_borrow_mut() {
        Ok(mut scratch) => direct_with(tr, (weight, known), hit, coef, rng, vis, &mut scratch),
        Err(_) => direct_with(
            tr,
            (weight, known),
            hit,
            coef,
            rng,
            vis,
            &mut Scratch::default(),
        ),
    })
}

fn direct_with(
    tr: &Tracer,
    (weight, known): (f64, Color),
    hit: &Hit,
    coef: &dyn Fn(DVec3, f64) -> Color,
    rng: &mut Sampler,
    vis: Option<&VisQuery>,
    scratch: &mut Scratch,
) -> Color {
    let lights = tr.lights;
    let p = hit.point;
    let params = tr.params;
    let samples = &mut scratch.samples;
    samples.clear();
    let how = Partition {
        weight,
        ds: params.ds,
        dj: params.dj,
    };
    lights.sample_all(tr.scene, p, how, rng, samples);
    // Potentials. They carry the light each sample's source sends toward p (its patterns:
    // an ies2rad luminaire's distribution), so the tests are ordered, stopped and the
    // untested samples estimated by it; the shadow rays give the transmission only. A
    // sample the surface does not take light from (a zero coefficient: behind it) has no
    // potential whatever its pattern, which is then not evaluated (as Radiance's direct()).
    let cands = &mut scratch.cands;
    cands.clear();
    let contrib = &mut scratch.contrib;
    contrib.clear();
    contrib.resize(samples.len(), Color::ZERO);
    // The coefficients first (held in `contrib` until the potentials replace them), then
    // the patterns of the samples that have one, computed together
    // ([`Tracer::sample_patterns`]).
    for (w, s) in contrib.iter_mut().zip(samples.iter()) {
        *w = coef(s.dir, s.omega);
    }
    tr.sample_patterns(p, samples, contrib);
    for (k, s) in samples.iter().enumerate() {
        let w = std::mem::replace(&mut contrib[k], Color::ZERO);
        if w == Color::ZERO {
            continue;
        }
        let c = w * s.radiance;
        let b = bright(c);
        if b > 0.0 && b.is_finite() {
            contrib[k] = c;
            cands.push((!b.to_bits(), k as u32));
        }
    }
    if cands.is_empty() {
        return Color::ZERO;
    }
    // Brightest first, then by sample: a strict total order (indices are unique), so the
    // unstable sort gives the same order. The keys are integers of 16 bytes, compared
    // inline.
    cands.sort_unstable();
    let potential = |c: &(u64, u32)| f64::from_bits(!c.0);
    let n = cands.len();
    if scratch.nshad_dc.to_bits() != params.dc.to_bits() {
        scratch.nshad.clear();
        scratch.nshad_dc = params.dc;
    }
    while scratch.nshad.len() <= n {
        let k = scratch.nshad.len() as f64;
        scratch
            .nshad
            .push((k.powf(params.dc).ceil() as usize).max(1));
    }
    let nshadcheck = scratch.nshad[n];
    let thresh = if params.dt > 0.0 {
        params.dt / weight.max(1e-6)
    } else {
        0.0
    };
    let mut result = Color::ZERO;
    // Per-source visibility statistics from this point's tests.
    let stats = &mut scratch.stats;
    stats.clear();
    stats.resize(lights.sources.len(), (0.0, 0));
    // Shadow answers reused from the sample's footprint (one counter update per call).
    let mut reused = 0u64;
    let table = match vis {
        Some(_) => tr.ambient.and_then(|a| a.shadow_table()),
        None => None,
    };
    // The shadow-reuse slots of the first tests, fetched together.
    if let (Some(q), Some(t)) = (vis, table) {
        for &(_, k) in cands.iter().take(8) {
            viscache::prefetch(t, q, samples[k as usize].src);
        }
    }
    let mut untested_from = n;
    for (tested, i) in (0..n).enumerate() {
        if thresh > 0.0 && tested >= MIN_SHADOW_TESTS {
            let ahead: f64 = cands[i..(i + nshadcheck).min(n)]
                .iter()
                .map(potential)
                .sum();
            if ahead < thresh * bright(known + result) {
                untested_from = i;
                break;
            }
        }
        let k = cands[i].1 as usize;
        let (c, s) = (contrib[k], &samples[k]);
        let t = match vis {
            Some(q) => {
                let (t, traced) = viscache::shadow(table, q, s.src, || {
                    tr.shadow((p, s.dir, s.dist), s.src, hit.antimatter, rng)
                });
                reused += u64::from(!traced);
                t
            }
            None => tr.shadow((p, s.dir, s.dist), s.src, hit.antimatter, rng),
        };
        let st = &mut stats[s.src];
        st.0 += bright(t).clamp(0.0, 1.0);
        st.1 += 1;
        result += c * t;
    }
    if reused > 0 {
        if let Some(a) = tr.ambient {
            a.count_reused_shadows(reused);
        }
    }
    if untested_from < n {
        let (all_vis, all_n) = stats
            .iter()
            .fold((0.0, 0u32), |acc, s| (acc.0 + s.0, acc.1 + s.1));
        let global = if all_n > 0 {
            all_vis / all_n as f64
        } else {
            0.5
        };
        for &(_, k) in &cands[untested_from..] {
            let (c, st) = (contrib[k as usize], stats[samples[k as usize].src]);
            let vis = if st.1 > 0 { st.0 / st.1 as f64 } else { global };
            result += c * vis;
        }
    }
    result
}
