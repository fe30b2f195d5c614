//! `ttrace`: values at points, as rtrace computes them (docs/ttrace.md).
//!
//! Rays come on standard input (origin and direction per record, `-f` formats); each is
//! traced through the scene as rtrace traces it, with rtrace's defaults, and its results
//! (`-o` specifiers) are written in input order. `-I` gives the irradiance at each ray's
//! origin, the direction taken as the surface normal; `-i` the irradiance at the first
//! surface a ray hits. Rays are traced in batches on the session's threads; each ray's
//! random numbers depend only on its record number, and with `-ab` > 0 the rays go in
//! waves whose new irradiance values are filed in input order ([`trace_batch`]), so the
//! values are the same whatever `-n`. A record whose direction is zero is rtrace's flush
//! request: it gets a record of zeros and the output is flushed.
//!
//! Output is kept until a flush (`-x N` records, a zero-direction record, 64 MiB of
//! results) or the end of the input, so a run that fails on a bad record before then writes
//! nothing.

pub mod grid;
pub mod records;

use crate::options::rtrace::{parse_rtrace_args, Format, RtraceOptions, TraceCommand};
use crate::render::picture::{irradiance, irradiance_at};
use crate::render::ray::{Ray, NO_INST};
use crate::render::sampler::Sampler;
use crate::render::trace::{IndirectLight, Tracer};
use crate::runinfo::SOFTWARE;
use crate::scene::ReadOptions;
use crate::session::{SceneSource, Session};
use anyhow::{bail, Context, Result};
use glam::DVec3;
use rayon::prelude::*;
use records::{FieldWriter, InRay, RayReader};
use std::io::{BufRead, Write};
use std::path::Path;

/// Rays traced per batch (without `-x`).
const BATCH: usize = 4096;
/// Results kept before they are written.
const KEEP_BYTES: usize = 64 << 20;
/// Largest side of a `-fc` picture.
const MAX_PICTURE_SIDE: usize = 1 << 15;
/// rtrace's distance for a ray that hits nothing (`FHUGE`).
const FHUGE: f64 = 1e10;

/// What one ray gives.
struct Traced {
    value: DVec3,
    org: DVec3,
    dir: DVec3,
    point: DVec3,
    n_facing: DVec3,
    normal: DVec3,
    dist: f64,
    /// The effective distance (`l`): through mirrors to what they reflect.
    eff: f64,
    names: Option<(String, String, String)>,
}

/// Entry point of `ttrace`.
pub fn ttrace_main() -> i32 {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let cmd = match parse_rtrace_args(&args) {
        Ok(c) => c,
        Err(e) => {
            eprintln!(
                "{}",
                crate::runinfo::printable(&format!("ttrace: error: {e}"))
            );
            return 1;
        }
    };
    let o = match cmd {
        TraceCommand::PrintVersion => {
            println!("{SOFTWARE}");
            return 0;
        }
        TraceCommand::PrintHelp => {
            print!("{}", crate::options::rtrace::trace_help());
            return 0;
        }
        TraceCommand::Trace(o) => o,
    };
    let stdin = std::io::stdin();
    let stdout = std::io::stdout();
    match run(&o, &args, stdin.lock(), &mut stdout.lock()) {
        Ok(()) => 0,
        Err(e) => {
            eprintln!(
                "{}",
                crate::runinfo::printable(&format!("ttrace: error: {e:#}"))
            );
            1
        }
    }
}

/// Trace the rays of `input` with options `o`, writing results to `out`.
pub fn run(
    o: &RtraceOptions,
    args: &[String],
    input: impl BufRead,
    out: &mut dyn Write,
) -> Result<()> {
    if let Some(why) = o.params.refused() {
        bail!("{why}");
    }
    if o.params.ax.is_some() || o.params.axt.is_some() || o.params.axm.is_some() {
        bail!("-ax, -axg, -axt and -axm vary -aa from frame to frame: ttrace has no frames");
    }
    let t = &o.trace;
    if t.output != Format::Ascii && t.spec.contains(['m', 'M', 's']) {
        bail!("names (-o m, M, s) need text output (-fa or -f?a)");
    }
    if t.picture {
        if t.flush == 0 || t.yres == 0 {
            bail!("-fc writes a picture: give its size with -x and -y");
        }
        if t.spec != "v" {
            bail!("-fc writes values only: use -ov");
        }
        if t.flush > MAX_PICTURE_SIDE || t.yres > MAX_PICTURE_SIDE {
            bail!(
                "-fc: a picture of {} x {} pixels is too large",
                t.flush,
                t.yres
            );
        }
    }
    let mut ro = ReadOptions::from_env();
    ro.allow_commands |= o.run.allow_commands;
    ro.obj_material.clone_from(&o.run.obj_material);
    if let Some(n) = o.run.max_primitives {
        ro.max_primitives = n;
    }
    let source = SceneSource::read(&o.scene_files, &ro, &o.params)?;
    let mut session = Session::start(o.params.clone(), source, o.run.threads)?;
    if o.run.warnings {
        for w in &session.warnings {
            eprintln!("ttrace: warning - {w}");
        }
    }
    let amb_file = match &o.run.amb_file {
        Some(af) if session.cached_ambient().is_some() => {
            if let Some(w) = session.load_ambient_file(Path::new(af))? {
                eprintln!("ttrace: warning - {w}");
            }
            Some(af.clone())
        }
        _ => None,
    };
    if let Some(path) = &o.run.amb_log {
        if session.cached_ambient().is_some() {
            if let Some(w) = session.open_log(Path::new(path), o.run.amb_force, o.run.amb_flush)? {
                eprintln!("ttrace: warning - {w}");
            }
        }
    }
    let mut pending: Vec<u8> = Vec::new();
    let mut picture: Vec<[f32; 3]> = Vec::new();
    if t.header && !t.picture {
        pending.extend_from_slice(
            format!(
                "#?RADIANCE\nttrace {}\nSOFTWARE= {SOFTWARE}\nNCOMP=3\nFORMAT={}\n\n",
                args.join(" "),
                t.output.header_name()
            )
            .as_bytes(),
        );
    }
    let limit = if t.flush > 0 && t.yres > 0 {
        Some((t.flush * t.yres) as u64)
    } else {
        None
    };
    let batch = if t.flush > 0 { t.flush } else { BATCH };
    let mut reader = RayReader::new(input, t.input);
    let mut waves = 0u32;
    let mut done = 0u64;
    let mut last: Option<InRay> = None;
    loop {
        // A batch: up to `batch` rays, cut short by a flush record or the end.
        let mut rays = Vec::with_capacity(batch);
        let mut flush_record = None;
        let mut ended = false;
        while rays.len() < batch && limit.is_none_or(|l| done + (rays.len() as u64) < l) {
            match reader.next_ray()? {
                None => {
                    ended = true;
                    break;
                }
                Some(r) if r.dir == DVec3::ZERO => {
                    flush_record = Some(r);
                    break;
                }
                Some(r) => rays.push(r),
            }
        }
        let first = done;
        let traced = trace_batch(&session, o, &rays, first, &mut waves);
        if let Some(e) = session.scene.fatal_error() {
            bail!("{e}");
        }
        done += rays.len() as u64;
        if t.picture {
            picture.extend(traced.iter().map(|r| r.value.as_vec3().to_array()));
            if flush_record.is_some() {
                picture.push([0.0; 3]);
                done += 1;
            }
            if ended || limit.is_some_and(|l| done >= l) {
                break;
            }
            continue;
        }
        let mut w = FieldWriter::new(t.output);
        for r in &traced {
            write_record(&mut w, &t.spec, r);
        }
        let mut flush = t.flush > 0;
        if let Some(r) = rays.last() {
            last = Some(*r);
        }
        if flush_record.is_some() {
            write_record(&mut w, &t.spec, &bogus(last.as_ref()));
            flush = true;
            done += 1;
        }
        pending.extend_from_slice(&w.out);
        if flush || pending.len() >= KEEP_BYTES {
            out.write_all(&pending)
                .and_then(|()| out.flush())
                .context("cannot write the results")?;
            pending.clear();
        }
        if ended || limit.is_some_and(|l| done >= l) {
            break;
        }
    }
    session.finish()?;
    if let Some(af) = &amb_file {
        session.save_ambient_file(Path::new(af))?;
    }
    if t.picture {
        let (w, h) = (t.flush, t.yres);
        if picture.len() != w * h {
            bail!(
                "-fc: a picture of {w} x {h} needs {} records, the input held {}",
                w * h,
                picture.len()
            );
        }
        let mut img = crate::image::Image {
            width: w,
            height: h,
            pixels: picture,
            header: Default::default(),
        };
        img.header.software = Some(SOFTWARE.to_string());
        img.header
            .commands
            .push(format!("ttrace {}", args.join(" ")));
        let mut sink = &mut *out;
        crate::image::hdr::write_hdr(&mut sink, &img).context("cannot write the picture")?;
        out.flush().context("cannot write the picture")?;
        return Ok(());
    }
    out.write_all(&pending)
        .and_then(|()| out.flush())
        .context("cannot write the results")?;
    Ok(())
}

/// The record rtrace writes for a zero direction (measured): a value of zero, the origin
/// and direction of the ray before it (zeros for the first) with its origin as the point,
/// no surface, rtrace's distance for a miss.
fn bogus(prev: Option<&InRay>) -> Traced {
    let (org, dir) = prev.map_or((DVec3::ZERO, DVec3::ZERO), |r| {
        (r.org, r.dir.normalize_or_zero())
    });
    Traced {
        value: DVec3::ZERO,
        org,
        dir,
        point: org,
        n_facing: DVec3::ZERO,
        normal: DVec3::ZERO,
        dist: FHUGE,
        eff: FHUGE,
        names: Some(("*".into(), "*".into(), "*".into())),
    }
}

/// What a ray's value is (`-I`, `-i`, `-ld`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ValueKind {
    /// `-I`: irradiance at the origin.
    pub at_origin: bool,
    /// `-i`: irradiance at the first surface hit.
    pub at_hit: bool,
    /// `-ld`: the ray ends at the length of its direction.
    pub limit_distance: bool,
}

/// The value of ray `r`, record `index` of its input (its random numbers depend on that
/// alone), on the calling thread: what `ttrace` writes as `v`, and what a point job's
/// workers compute for the same record.
pub fn ray_value(tr: &Tracer, kind: ValueKind, r: &InRay, index: u64) -> DVec3 {
    let len = r.dir.length();
    if len <= 0.0 || !len.is_finite() {
        return DVec3::ZERO;
    }
    let dir = r.dir / len;
    let mut rng = Sampler::for_pixel(0, index as u32, (index >> 32) as u32, 0x7472);
    let org = r.org - tr.scene.origin;
    let v = if kind.at_origin {
        irradiance_at(tr, org, dir, &mut rng)
    } else {
        let tmax = if kind.limit_distance {
            len
        } else {
            f64::INFINITY
        };
        let ray = Ray::primary(org, dir, tmax);
        if kind.at_hit {
            irradiance(tr, &ray, &mut rng)
        } else {
            tr.trace_dist(&ray, &mut rng).0
        }
    };
    crate::color::sanitize(v)
}

/// Largest wave of rays traced side by side with a cached ambient calculation.
const MAX_WAVE: usize = 256;

/// Rays of a batch that go into waves one after the other are this far apart in the input.
const STRIDE: usize = 64;

/// Trace a batch of rays (the first is record `first`) on the session's threads, results in
/// input order. With a cached ambient calculation the rays go in **waves** of 1, 2, 4, …
/// up to [`MAX_WAVE`] rays (counted by `waves` across batches): every ray of a wave sees
/// the values and shadow answers of the waves before it and its own (made privately, its
/// shadow answers in an epoch of its own), and the wave's values and shadow answers go to
/// the shared cache and table in a fixed order when it ends.
/// No ray sees what another ray of its wave makes, so the values do not depend on the
/// thread count (`-n`), only on the input. Rays of one wave would compute the same values
/// side by side where they are neighbours, so the waves take the batch's rays [`STRIDE`]
/// apart (every 64th, then the ones after those, …: neighbours on a grid fall in different
/// waves), and the first waves are small while the cache is empty.
fn trace_batch(
    session: &Session,
    o: &RtraceOptions,
    rays: &[InRay],
    first: u64,
    waves: &mut u32,
) -> Vec<Traced> {
    let Some(amb) = session.cached_ambient() else {
        return session.install(|| {
            rays.par_iter()
                .enumerate()
                .with_max_len(16)
                .map(|(k, r)| trace_one(session, o, r, first + k as u64))
                .collect()
        });
    };
    // The rays in a fixed order that puts neighbours of the input (neighbours on a grid)
    // in different waves: every STRIDE-th ray first, then the ones after them, ...
    let n = rays.len();
    let stride = STRIDE.min(n).max(1);
    let order: Vec<usize> = (0..stride).flat_map(|r| (r..n).step_by(stride)).collect();
    let mut out: Vec<Option<Traced>> = (0..n).map(|_| None).collect();
    let mut start = 0;
    while start < n {
        let size = (1usize << (*waves).min(8)).min(MAX_WAVE);
        *waves = waves.saturating_add(1);
        let end = (start + size).min(n);
        type Made = (
            Traced,
            Vec<crate::ambient::cache::CachedValue>,
            Vec<(u64, u64)>,
        );
        let made: Vec<Made> = session.install(|| {
            order[start..end]
                .par_iter()
                .with_max_len(1)
                .map(|&k| {
                    let index = first + k as u64;
                    crate::ambient::cache::begin_private();
                    crate::light::viscache::new_epoch(index.wrapping_add(1));
                    let t = trace_one(session, o, &rays[k], index);
                    let shadows = crate::light::viscache::end_epoch();
                    (t, crate::ambient::cache::end_private(), shadows)
                })
                .collect()
        });
        for (&k, (t, values, shadows)) in order[start..end].iter().zip(made) {
            amb.cache.commit(values);
            if let (false, Some(table)) = (shadows.is_empty(), amb.shadow_table()) {
                crate::light::viscache::learn(table, &shadows);
            }
            out[k] = Some(t);
        }
        start = end;
    }
    out.into_iter().flatten().collect()
}

fn trace_one(session: &Session, o: &RtraceOptions, r: &InRay, index: u64) -> Traced {
    let tr = session.tracer();
    let scene = &session.scene;
    let len = r.dir.length();
    let dir = r.dir / len;
    let kind = ValueKind {
        at_origin: o.trace.irradiance_at_origin,
        at_hit: o.params.i,
        limit_distance: o.trace.limit_distance,
    };
    let value = ray_value(&tr, kind, r, index);
    let wants_hit = o
        .trace
        .spec
        .contains(['p', 'n', 'N', 'l', 'L', 'm', 'M', 's']);
    let org = r.org - scene.origin;
    if o.trace.irradiance_at_origin {
        return Traced {
            value,
            org: r.org,
            dir,
            point: r.org,
            n_facing: dir,
            normal: dir,
            dist: 0.0,
            eff: 0.0,
            names: Some(("*".into(), "*".into(), "*".into())),
        };
    }
    let tmax = if o.trace.limit_distance {
        len
    } else {
        f64::INFINITY
    };
    let ray = Ray::primary(org, dir, tmax);
    let mut t = Traced {
        value,
        org: r.org,
        dir,
        point: DVec3::ZERO,
        n_facing: DVec3::ZERO,
        normal: DVec3::ZERO,
        dist: FHUGE,
        eff: FHUGE,
        names: None,
    };
    if wants_hit {
        match tr.intersect(&ray) {
            Some(h) => {
                t.point = h.point + scene.origin;
                t.normal = h.normal;
                t.n_facing = if h.back { -h.normal } else { h.normal };
                t.dist = h.t;
                t.eff = effective_distance(&tr, &ray, &h);
                if o.trace.spec.contains(['m', 'M', 's']) {
                    let info = scene.hit_info(h.href());
                    let material = info
                        .material
                        .map_or("*".to_string(), |m| scene.materials[m].name.clone());
                    let surface = if h.inst == NO_INST {
                        scene.objects.name(h.obj).to_string()
                    } else {
                        let set = &scene.sets[scene.placements[h.inst as usize].set];
                        match &set.geom {
                            crate::scene::sets::SetGeom::Objects(objs) => {
                                objs.name(h.obj).to_string()
                            }
                            crate::scene::sets::SetGeom::Mesh { .. } => set.file.clone(),
                        }
                    };
                    t.names = Some((info.modifier.to_string(), material, surface));
                }
            }
            None => t.names = Some(("*".into(), "*".into(), "*".into())),
        }
    }
    t
}

/// rtrace's effective distance of a ray (`-ol`): its first hit's, plus, where that hit is
/// a bare mirror seen from the front, the effective distance of the reflected ray (as far
/// as `-lr` lets the reflections go); a reflection that escapes adds rtrace's `FHUGE`.
fn effective_distance(
    tr: &crate::render::trace::Tracer,
    ray: &Ray,
    h: &crate::render::ray::Hit,
) -> f64 {
    let mut total = h.t;
    let (mut ray, mut h) = (*ray, *h);
    for _ in 0..tr.params.lr.unsigned_abs().clamp(1, 64) {
        let bare_mirror = match h.material.map(|m| tr.scene.material(m)) {
            Some(crate::material::Material::Mirror(m)) => {
                m.alternate.is_none() && !m.alternate_void
            }
            _ => false,
        };
        if !bare_mirror || h.back {
            break;
        }
        let dir = crate::material::reflect(ray.dir, h.normal);
        ray = Ray::primary(h.point, dir, f64::INFINITY);
        match tr.intersect(&ray) {
            Some(next) => {
                total += next.t;
                h = next;
            }
            None => return total + FHUGE,
        }
    }
    total
}

fn write_record(w: &mut FieldWriter, spec: &str, r: &Traced) {
    for c in spec.chars() {
        match c {
            'v' => w.vec3(r.value),
            'o' => w.vec3(r.org),
            'd' => w.vec3(r.dir),
            'p' => w.vec3(r.point),
            'n' => w.vec3(r.n_facing),
            'N' => w.vec3(r.normal),
            'l' => w.num(r.eff),
            'L' => w.num(r.dist),
            'w' => w.num(1.0),
            'm' | 'M' | 's' => {
                let (m, mat, s) = r.names.as_ref().map_or(("*", "*", "*"), |(a, b, c)| {
                    (a.as_str(), b.as_str(), c.as_str())
                });
                w.name(match c {
                    'm' => m,
                    'M' => mat,
                    _ => s,
                });
            }
            _ => {}
        }
    }
    w.end();
}
