//! A mutation fuzzer for every reader of outside input: scene text (lexer, reader and scene
//! build with its BVH), rpict's option language, view lines, RGBE and EXR pictures, Tessera's
//! ambient log, Radiance's ambient files, job manifests, task entry names, the function
//! language (`.cal` files and expressions: compiled and evaluated), and octrees and meshes
//! (read, built into an instance's object set, traced).
//!
//! Each target starts from valid seeds and mutates them (byte flips, inserts, deletions,
//! duplicated runs, splices, interesting numbers); a case passes when the reader returns,
//! with a value or an error. A panic or a case running longer than 10 s is a finding: its
//! input is saved under `target/fuzz-findings/` and the run fails.
//!
//! `cargo test --release --test fuzz` runs every target for 2 s (the test suite's quick run);
//! `bench/fuzz.sh SECONDS [TARGET]` runs a campaign (`-- --seconds N --target NAME`).
//! No harness: the summary lines (cases run, findings) show in the test output.

use std::io::Cursor;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use tessera::ambient::log::{encode_log, LogHeader, LogReader};
use tessera::ambient::{AmbRecord, ValueId};
use tessera::image::Image;

/// A small deterministic generator (xorshift64*).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

const INTERESTING: &[&str] = &[
    "0",
    "-1",
    "1e308",
    "-1e308",
    "1e-320",
    "nan",
    "inf",
    "-inf",
    "4294967296",
    "1e19",
    "99999999999999999999",
    "\n",
    "!",
    "\"",
    "void",
    "-",
    "@",
    "$",
    "\0",
    "1e20",
];

/// One mutation of `data`, drawing material from `seeds`.
fn mutate(rng: &mut Rng, data: &mut Vec<u8>, seeds: &[Vec<u8>]) {
    let n = data.len();
    match rng.below(8) {
        0 if n > 0 => {
            let i = rng.below(n);
            data[i] ^= 1 << rng.below(8);
        }
        1 if n > 0 => {
            let i = rng.below(n);
            data[i] = rng.next() as u8;
        }
        2 => {
            let i = rng.below(n + 1);
            data.insert(i, rng.next() as u8);
        }
        3 if n > 0 => {
            let i = rng.below(n);
            let len = rng.below(16).min(n - i);
            data.drain(i..i + len);
        }
        4 if n > 0 => {
            // Duplicate a run (repeated records, long tokens).
            let i = rng.below(n);
            let len = (rng.below(64) + 1).min(n - i);
            let run: Vec<u8> = data[i..i + len].to_vec();
            let at = rng.below(n + 1);
            for _ in 0..=rng.below(4) {
                data.splice(at..at, run.iter().copied());
            }
        }
        5 => {
            let w = INTERESTING[rng.below(INTERESTING.len())].as_bytes();
            let i = rng.below(n + 1);
            data.splice(i..i, w.iter().copied());
        }
        6 => {
            // Splice in part of another seed.
            let s = &seeds[rng.below(seeds.len())];
            if !s.is_empty() {
                let i = rng.below(s.len());
                let len = rng.below(64).min(s.len() - i);
                let at = rng.below(n + 1);
                data.splice(at..at, s[i..i + len].iter().copied());
            }
        }
        _ if n > 4 => {
            // Overwrite 4 bytes with an extreme little-endian number.
            let i = rng.below(n - 3);
            let v: [u8; 4] = match rng.below(4) {
                0 => f32::INFINITY.to_le_bytes(),
                1 => f32::NAN.to_le_bytes(),
                2 => u32::MAX.to_le_bytes(),
                _ => 3e38f32.to_le_bytes(),
            };
            data[i..i + 4].copy_from_slice(&v);
        }
        _ => data.push(rng.next() as u8),
    }
    data.truncate(1 << 20);
}

/// What a target runs on one input.
type RunFn = Box<dyn Fn(&[u8]) + Sync>;

/// A fuzz target: its seeds and what it runs on an input.
struct Target {
    name: &'static str,
    seeds: Vec<Vec<u8>>,
    run: RunFn,
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).to_path_buf()
}

fn file_seeds(paths: &[&str]) -> Vec<Vec<u8>> {
    paths
        .iter()
        .filter_map(|p| std::fs::read(root().join(p)).ok())
        .collect()
}

fn record(seq: u64) -> AmbRecord {
    AmbRecord {
        id: ValueId { origin: 3, seq },
        pos: glam::DVec3::new(seq as f64, 1.0, 2.0),
        ndir: glam::DVec3::Z,
        udir: glam::DVec3::X,
        lvl: 0,
        weight: 1.0,
        rad: [0.1, 0.2],
        gpos: [0.01, 0.0],
        gdir: [0.0, 0.02],
        corral: 5,
        val: [0.5, 0.4, 0.3],
        reach: 1.5,
        share: 1.0,
    }
}

fn picture() -> Image {
    let mut img = Image::new(9, 7);
    for (i, p) in img.pixels.iter_mut().enumerate() {
        *p = [i as f32 * 0.1, 1.0 / (1.0 + i as f32), 3.0];
    }
    img
}

/// Write `data` to a scratch file of this thread and return its path.
fn scratch(dir: &Path, name: &str, data: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, data).unwrap();
    p
}

/// Build a scene of one instance (`text`) whose file is in `dir`, and trace a few rays.
fn instance_scene(dir: &Path, text: &str) {
    use tessera::render::world::Scene;
    use tessera::scene::{parse_scene_text, ReadOptions};
    let opts = ReadOptions {
        allow_commands: false,
        raypath: vec![dir.to_path_buf()],
        ..ReadOptions::default()
    };
    let Ok(prims) = parse_scene_text(text, "fuzz.rad", &opts) else {
        return;
    };
    if let Ok(scene) = Scene::build_read(&prims, &opts) {
        for k in 0..8 {
            let dir = glam::DVec3::new(k as f64 - 3.5, 1.0, (k % 3) as f64 - 1.0).normalize();
            let _ = scene.closest(-dir * 10.0, dir, f64::INFINITY, |a, b| a.key() > b.key());
        }
    }
}

fn targets(dir: Arc<tempfile::TempDir>) -> Vec<Target> {
    use tessera::render::world::Scene;
    use tessera::scene::{parse_scene_text, ReadOptions};
    let mut v = Vec::new();
    v.push(Target {
        name: "scene",
        seeds: file_seeds(&[
            "demo/demo_room.rad",
            "tests/scenes/spheres.rad",
            "tests/scenes/mirrors.rad",
            "tests/scenes/glassy.rad",
            "tests/scenes/aniso_slab.rad",
        ]),
        run: Box::new(|b| {
            let opts = ReadOptions::default();
            if let Ok(prims) = parse_scene_text(&text(b), "fuzz.rad", &opts) {
                let _ = Scene::build(&prims);
            }
        }),
    });
    v.push(Target {
        name: "cal",
        seeds: cal_seeds(),
        run: Box::new(run_cal),
    });
    v.push(Target {
        name: "options",
        seeds: vec![
            b"-vtv -vp 1 2 3 -vd 0 1 0 -x 64 -y 48 -ab 2 -aa .1 -ad 512 -i+ -ps 1 s.rad".to_vec(),
            b"-av .1 .1 .1 -ae glass -ae win -amb-x --amb-share-max 1 --no-overture a b".to_vec(),
            b"-defaults -version -S 3 -o f%03d.hdr -n 2 --stats s.json --amb-log l x.rad".to_vec(),
        ],
        run: Box::new(|b| {
            let words = tessera::options::split_words(&text(b));
            let _ = tessera::options::parse_rpict_args(&words);
        }),
    });
    v.push(Target {
        name: "view",
        seeds: vec![
            b"VIEW= -vtv -vp 2 3 1.5 -vd 1 0 0 -vu 0 0 1 -vh 60 -vv 45 -vs .1 -vl 0".to_vec(),
            b"rview -vta -vh 180 -vv 180 -vo 1 -va 100".to_vec(),
        ],
        run: Box::new(|b| {
            let base = tessera::view::View::default();
            if let Ok(Some(v)) = tessera::view::parse_view_line(&text(b), &base) {
                let _ = v.frame();
            }
        }),
    });
    let mut hdr = Vec::new();
    tessera::image::hdr::write_hdr(&mut hdr, &picture()).unwrap();
    v.push(Target {
        name: "rgbe",
        seeds: vec![hdr],
        run: Box::new(|b| {
            let _ = tessera::image::hdr::read_hdr(&mut Cursor::new(b));
        }),
    });
    let exr_path = dir.path().join("seed.exr");
    tessera::image::exr::write_exr(&exr_path, &picture()).unwrap();
    let d = dir.clone();
    v.push(Target {
        name: "exr",
        seeds: vec![std::fs::read(&exr_path).unwrap()],
        run: Box::new(move |b| {
            let p = scratch(d.path(), "case.exr", b);
            let _ = tessera::image::exr::read_exr(&p);
        }),
    });
    // Octrees and meshes: read, then built as an instance's object set (its BVH too).
    let d = dir.clone();
    v.push(Target {
        name: "octree",
        seeds: file_seeds(&["tests/data/inst_frozen.oct"]),
        run: Box::new(move |b| {
            let _ = tessera::scene::octree::parse_octree(b, "case.oct");
            scratch(d.path(), "case.oct", b);
            instance_scene(d.path(), "void instance i 1 case.oct 0 0\n");
        }),
    });
    let d = dir.clone();
    v.push(Target {
        name: "mesh",
        seeds: file_seeds(&["tests/data/inst_small.rtm"]),
        run: Box::new(move |b| {
            let _ = tessera::scene::rtm::parse_mesh(b, "case.rtm");
            scratch(d.path(), "case.rtm", b);
            instance_scene(d.path(), "void mesh m 1 case.rtm -rz 30 0 0\n");
        }),
    });
    let d = dir.clone();
    v.push(Target {
        name: "obj",
        seeds: file_seeds(&["tests/scenes/obj/model.obj"]),
        run: Box::new(move |b| {
            let _ = tessera::scene::obj::parse_obj(&text(b), "case.obj");
            scratch(d.path(), "case.obj", b);
            instance_scene(
                d.path(),
                "void plastic red 0 0 5 1 0 0 0 0\nvoid mesh m 3 case.obj -m red 0 0\n",
            );
        }),
    });
    let records: Vec<AmbRecord> = (0..6).map(record).collect();
    let log = encode_log(&LogHeader::new([9; 32], "-ab 1 -aa .2"), &records);
    let d = dir.clone();
    v.push(Target {
        name: "amblog",
        seeds: vec![log],
        run: Box::new(move |b| {
            let p = scratch(d.path(), "case.log", b);
            if let Ok(mut r) = LogReader::open(&p, None, false) {
                while let Ok(recs) = r.read_available() {
                    if recs.is_empty() {
                        break;
                    }
                }
            }
        }),
    });
    let mut rad = Vec::new();
    tessera::ambient::radfile::write_header(&mut rad, "rpict -ab 1", "fuzz").unwrap();
    for r in &records {
        tessera::ambient::radfile::write_record(&mut rad, r).unwrap();
    }
    let d = dir.clone();
    v.push(Target {
        name: "radambient",
        seeds: vec![rad],
        run: Box::new(move |b| {
            let p = scratch(d.path(), "case.amb", b);
            let _ = tessera::ambient::radfile::read_file(&p);
        }),
    });
    v.push(Target {
        name: "manifest",
        seeds: vec![manifest_seed(dir.path())],
        run: Box::new(|b| {
            if let Ok(m) = serde_json::from_slice::<tessera::job::manifest::Manifest>(b) {
                let _ = m.validate();
            }
        }),
    });
    v.push(Target {
        name: "task-names",
        seeds: vec![
            b"f00000-t00012.todo".to_vec(),
            b"f00003-t00001.claim.node7-1234.0badf00d".to_vec(),
            b"f00001-t00002.done".to_vec(),
        ],
        run: Box::new(|b| {
            let _ = tessera::job::task::parse_entry(&text(b));
        }),
    });
    v
}

/// A valid job manifest (planned from the demo scene).
/// Seeds for the function language: Tessera's rayinit, snippets, and Radiance's library
/// `.cal` files when Radiance is installed (read in place, never copied).
fn cal_seeds() -> Vec<Vec<u8>> {
    let mut v: Vec<Vec<u8>> = vec![
        tessera::cal::BUILTIN_RAYINIT.as_bytes().to_vec(),
        b"v = Px*2 + 3; w = v + k; k : 10; f(x) = if(x-1, f(x-1)*x, 1); y = f(5)".to_vec(),
        b"g(a) = a(2)+1; sq2(x) = x*x; z = g(sq2) + select(2, 1, 2^-3, 3) {c {n}}".to_vec(),
        b"t = noise3(Px,Py,Pz) + fnoise3(Dx, Dy, Dz)*turbulence(Px, Py, Pz, .01); `l = 2;".to_vec(),
        b"r = v`foo + w` - -2^2 * 1e-3 / .5e1 ; m(a,b) : max(a, b, rand(a)) ; c : m(1, 2)".to_vec(),
    ];
    let bin = std::env::var("TESSERA_RADIANCE_BIN")
        .unwrap_or_else(|_| "/opt/radvenv/lib/python3.11/site-packages/pyradiance/bin".into());
    let lib = Path::new(&bin).parent().map(|p| p.join("lib"));
    if let Some(Ok(rd)) = lib.map(std::fs::read_dir) {
        let mut files: Vec<PathBuf> = rd
            .filter_map(|e| Some(e.ok()?.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "cal"))
            .collect();
        files.sort();
        v.extend(files.iter().filter_map(|p| std::fs::read(p).ok()));
    }
    v
}

/// Compile `b` as a function file and as an expression, then evaluate every definition
/// (functions with 0.5 for each parameter) with a dummy environment.
fn run_cal(b: &[u8]) {
    use tessera::cal::{CalBuilder, CalOptions, Ctx, Dialect, Env};
    let dialects = [
        CalOptions::default(),
        CalOptions {
            dialect: Dialect::Rcalc,
            fold: false,
            rayinit: false,
        },
    ];
    let opts = dialects[b.first().map_or(0, |c| (*c as usize) & 1)];
    let Ok(mut cb) = CalBuilder::with_options(&[], opts) else {
        return;
    };
    let loaded = cb.load_text(b, "fuzz.cal", Ctx::GLOBAL).is_ok();
    let mut exprs = Vec::new();
    if let Ok(e) = cb.expr(&text(b), Ctx::GLOBAL, "fuzz:1") {
        exprs.push(e);
    }
    let mut funcs = Vec::new();
    if loaded {
        for (name, params) in cb.definitions() {
            match params {
                None => exprs.extend(cb.expr(&name, Ctx::GLOBAL, "fuzz:2").ok()),
                Some(n) => funcs.extend(cb.func(&name, Ctx::GLOBAL).ok().map(|f| (f, n))),
            }
        }
    }
    let prog = cb.finish();
    let mut chan = [0.25; 27];
    chan[6] = 0.5;
    let env = Env {
        chan,
        args: &[1.0, 2.0],
        brdf: Some([0.0, 0.0, 1.0, 0.5, 1.0, 1.0, 1.0]),
    };
    let mut ev = prog.begin(&env);
    for e in exprs {
        let _ = ev.eval(e);
    }
    for (f, n) in funcs {
        let _ = ev.call(f, &vec![0.5; n]);
    }
}

fn manifest_seed(dir: &Path) -> Vec<u8> {
    let job = dir.join("seedjob");
    let req = tessera::job::manifest::PlanRequest {
        tiles: Some(4),
        tile_size: None,
        workers: Some(2),
        threads: None,
        frames: None,
        views: None,
        path: None,
        lease: None,
        no_split: false,
        ambient: None,
        amb_force: false,
        args: vec![
            "-vf".into(),
            root().join("tests/scenes/spheres.vf").display().to_string(),
            "-x".into(),
            "40".into(),
            "-y".into(),
            "30".into(),
            "-ab".into(),
            "1".into(),
            root()
                .join("tests/scenes/spheres.rad")
                .display()
                .to_string(),
        ],
        command: "fuzz".into(),
        finish: None,
        points: None,
    };
    let _ = tessera::job::manifest::create_job(&job, &req);
    std::fs::read(job.join("manifest.json")).unwrap_or_else(|_| b"{}".to_vec())
}

/// Run `t` for `secs`; returns (cases, findings).
fn campaign(t: &Target, secs: f64, seed: u64, findings_dir: &Path) -> (u64, u64) {
    let deadline = Instant::now() + Duration::from_secs_f64(secs);
    let mut rng = Rng(seed | 1);
    let (mut cases, mut found) = (0u64, 0u64);
    let started = Arc::new(AtomicU64::new(0));
    let busy = Arc::new(AtomicU64::new(0));
    // A watchdog: a case that runs for more than 10 s is a hang.
    let (s2, b2, name) = (started.clone(), busy.clone(), t.name);
    let watchdog = std::thread::spawn(move || loop {
        std::thread::sleep(Duration::from_millis(200));
        let since = b2.load(Ordering::Relaxed);
        if since == u64::MAX {
            return;
        }
        if since > 0 {
            let t0 = s2.load(Ordering::Relaxed);
            let elapsed = epoch_ms().saturating_sub(t0);
            if elapsed > 10_000 {
                eprintln!("fuzz {name}: a case has run for {elapsed} ms: a hang");
                std::process::exit(2);
            }
        }
    });
    while Instant::now() < deadline {
        let mut data = t.seeds[rng.below(t.seeds.len())].clone();
        for _ in 0..=rng.below(8) {
            mutate(&mut rng, &mut data, &t.seeds);
        }
        std::fs::write(findings_dir.join(format!("{}-current.bin", t.name)), &data).ok();
        started.store(epoch_ms(), Ordering::Relaxed);
        busy.store(1, Ordering::Relaxed);
        let ok = catch_unwind(AssertUnwindSafe(|| (t.run)(&data))).is_ok();
        busy.store(0, Ordering::Relaxed);
        cases += 1;
        if !ok {
            found += 1;
            let p = findings_dir.join(format!("{}-panic-{found}.bin", t.name));
            std::fs::write(&p, &data).ok();
            eprintln!("fuzz {}: panic, input saved to {}", t.name, p.display());
        }
    }
    busy.store(u64::MAX, Ordering::Relaxed);
    let _ = watchdog.join();
    let _ = std::fs::remove_file(findings_dir.join(format!("{}-current.bin", t.name)));
    (cases, found)
}

fn epoch_ms() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_millis() as u64)
        .unwrap_or(0)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let arg = |name: &str| {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + 1).cloned())
    };
    let secs: f64 = arg("--seconds").and_then(|s| s.parse().ok()).unwrap_or(2.0);
    let only = arg("--target");
    let seed: u64 = arg("--seed")
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(epoch_ms);
    let findings_dir = root().join("target/fuzz-findings");
    std::fs::create_dir_all(&findings_dir).unwrap();
    // Panics are findings, reported by the loop; keep the output to one line each.
    std::panic::set_hook(Box::new(|_| {}));
    let dir = Arc::new(tempfile::tempdir().unwrap());
    let mut total = 0;
    for t in targets(dir) {
        if only.as_deref().is_some_and(|o| o != t.name) {
            continue;
        }
        assert!(!t.seeds.is_empty(), "{}: no seeds", t.name);
        let (cases, found) = campaign(&t, secs, seed, &findings_dir);
        println!(
            "fuzz {:<12} {cases:>9} cases in {secs} s, {found} panics, 0 hangs (seed {seed})",
            t.name
        );
        total += found;
    }
    if total > 0 {
        eprintln!("fuzz: {total} panics; inputs in {}", findings_dir.display());
        std::process::exit(1);
    }
}
