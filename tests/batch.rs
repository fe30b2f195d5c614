//! End-to-end tests of the batch toolkit: tplan → tpiece ×N → tmerge → tassemble → tstat,
//! run as real processes on real job directories, with crashes injected.

mod common;

use common::{compare, reduce, run_ok, PixelsF64};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};
use tessera::image::{read_picture, Image};

fn bin(name: &str) -> PathBuf {
    match name {
        "tplan" => PathBuf::from(env!("CARGO_BIN_EXE_tplan")),
        "tpiece" => PathBuf::from(env!("CARGO_BIN_EXE_tpiece")),
        "tmerge" => PathBuf::from(env!("CARGO_BIN_EXE_tmerge")),
        "tassemble" => PathBuf::from(env!("CARGO_BIN_EXE_tassemble")),
        "tstat" => PathBuf::from(env!("CARGO_BIN_EXE_tstat")),
        "tpict" => PathBuf::from(env!("CARGO_BIN_EXE_tpict")),
        _ => unreachable!(),
    }
}

fn demo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("demo")
}

fn cmd(name: &str) -> Command {
    let mut c = Command::new(bin(name));
    c.env("RAYPATH", demo());
    c.env_remove("SLURM_ARRAY_JOB_ID");
    c.env_remove("SLURM_JOB_ID");
    c.env_remove("SLURM_CPUS_PER_TASK");
    c
}

/// Render options shared by the jobs and the single-process references.
fn view_args(x: u32, y: u32, amb: &[&str]) -> Vec<String> {
    let mut v: Vec<String> = vec![
        "-vf".into(),
        demo().join("demo.vf").display().to_string(),
        "-x".into(),
        x.to_string(),
        "-y".into(),
        y.to_string(),
    ];
    v.extend(amb.iter().map(|s| s.to_string()));
    v.push(demo().join("demo.rad").display().to_string());
    v
}

fn plan(job: &Path, plan_args: &[&str], args: &[String]) {
    let mut c = cmd("tplan");
    c.args(plan_args).arg("-o").arg(job).arg("--").args(args);
    run_ok(&mut c);
}

fn worker(job: &Path, id: &str, extra: &[&str]) -> Command {
    let mut c = cmd("tpiece");
    c.arg(job)
        .args(["--worker-id", id, "--threads", "1", "-q"])
        .args(extra);
    c
}

fn run_workers(job: &Path, n: usize, extra: &[&str]) {
    run_workers_env(job, n, extra, &[]);
}

fn run_workers_env(job: &Path, n: usize, extra: &[&str], env: &[(&str, &str)]) {
    let mut kids: Vec<Child> = (0..n)
        .map(|i| {
            worker(job, &format!("w{i}"), extra)
                .envs(env.iter().copied())
                .stderr(Stdio::piped())
                .spawn()
                .expect("start tpiece")
        })
        .collect();
    for k in kids.drain(..) {
        let out = k.wait_with_output().unwrap();
        assert!(
            out.status.success(),
            "tpiece failed: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

fn assemble(job: &Path) -> Image {
    let out = job.join("out.hdr");
    let _ = std::fs::remove_file(&out);
    run_ok(cmd("tassemble").arg(job).arg("-o").arg(&out));
    read_picture(&out).unwrap()
}

fn tpict(args: &[String]) -> Image {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("ref.hdr");
    run_ok(cmd("tpict").arg("-o").arg(&out).args(args));
    read_picture(&out).unwrap()
}

/// The entry names in a job's `tasks/`.
fn task_entries(job: &Path) -> Vec<String> {
    std::fs::read_dir(job.join("tasks"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect()
}

fn stat(job: &Path) -> serde_json::Value {
    let out = run_ok(cmd("tstat").arg(job).arg("--json"));
    serde_json::from_slice(&out).unwrap()
}

/// Pictures with indirect light compared here are rendered with `-ps 1`: adaptive pixel
/// sampling decides from the ambient values at a cell's corners whether a light's edge pixels
/// are traced or interpolated, a difference of a few pixels that says nothing about the job.
fn within_tolerance(a: &Image, b: &Image, what: &str) {
    let (w, h) = ((a.width / 2).max(1), (a.height / 2).max(1));
    let c = compare(&reduce(a, w, h), &reduce(b, w, h), 0.05);
    eprintln!("{what}: {c:?}");
    assert!(
        c.rms <= 0.10 && c.max <= 1.5 && c.mean_lum <= 0.02,
        "{what}: {c:?}"
    );
}

/// At `-ab 0` a job's picture is bit-identical to tpict's, and its tiles' edges lie on the
/// sampling grid (cells of `cell_size(-ps)` pixels), so no cell is traced by two tiles: a
/// one-tile plan traces exactly the rays of one `tpict -n 1` render, and more tiles add only
/// the samples on their shared edges (traced by both). Checked on the default plan and on
/// plans of many small tiles, at `-ps 4` and 3.
#[test]
fn ab0_jobs_are_pixel_identical_to_tpict_at_any_worker_count() {
    for ps in ["4", "3"] {
        let args = view_args(96, 72, &["-ab", "0", "-ps", ps]);
        let d = tempfile::tempdir().unwrap();
        let stats = d.path().join("stats.json");
        let mut refargs = vec!["-n".to_string(), "1".into(), "--stats".into()];
        refargs.push(stats.display().to_string());
        refargs.extend(args.iter().cloned());
        let reference = tpict(&refargs);
        let st: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
        let rays = st["total_rays"].as_u64().unwrap();
        for (n, tiles) in [(1usize, None), (1, Some(40)), (2, Some(60)), (4, Some(120))] {
            let job = d.path().join(format!("job{n}-{tiles:?}"));
            let mut p = vec!["--workers".to_string(), n.to_string()];
            if let Some(t) = tiles {
                p.extend(["--tiles".to_string(), t.to_string()]);
            }
            let p: Vec<&str> = p.iter().map(|s| s.as_str()).collect();
            plan(&job, &p, &args);
            let m: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(job.join("manifest.json")).unwrap())
                    .unwrap();
            let plan_tiles = m["frames"][0]["tiles"].as_array().unwrap();
            let g = tessera::render::cell_size(ps.parse().unwrap()) as u64;
            let (w, h) = (reference.width as u64, reference.height as u64);
            for t in plan_tiles {
                let (x0, y0) = (t["x0"].as_u64().unwrap(), t["y0"].as_u64().unwrap());
                let (x1, y1) = (x0 + t["w"].as_u64().unwrap(), y0 + t["h"].as_u64().unwrap());
                for (v, end) in [(x0, w), (x1, w), (y0, h), (y1, h)] {
                    assert!(
                        v.is_multiple_of(g) || v == end,
                        "-ps {ps}: tile {t} is off the grid"
                    );
                }
            }
            if let Some(t) = tiles {
                assert!(plan_tiles.len() >= t / 2, "{} tiles", plan_tiles.len());
            }
            run_workers(&job, n, &[]);
            let img = assemble(&job);
            let what = format!("-ps {ps}, {n} workers, {} tiles", plan_tiles.len());
            assert_eq!((img.width, img.height), (reference.width, reference.height));
            assert!(img.pixels == reference.pixels, "{what}: picture differs");
            let st = stat(&job);
            assert_eq!(st["done"], st["tiles"]);
            let job_rays = st["aggregate"]["rays"].as_u64().unwrap();
            eprintln!("{what}: rays {job_rays} against {rays}");
            // A tile traces the samples on its own edges, so a sample on an edge between two
            // tiles is traced by both; one tile traces exactly one render's rays.
            if plan_tiles.len() == 1 {
                assert_eq!(job_rays, rays, "{what}: rays");
            } else {
                assert!(job_rays >= rays, "{what}: rays {job_rays} < {rays}");
                // Tiles of 8×8 pixels and less here: their edges add at most 30%.
                assert!(
                    job_rays as f64 <= 1.3 * rays as f64,
                    "{what}: rays {job_rays} against {rays}"
                );
            }
        }
        // One worker whose three tile loops share the scene: the same picture.
        let job = d.path().join("job-loops");
        plan(&job, &["--workers", "3", "--tiles", "60"], &args);
        let out = cmd("tpiece")
            .arg(&job)
            .args(["--worker-id", "loops", "--threads", "3", "-q"])
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let img = assemble(&job);
        assert!(
            img.pixels == reference.pixels,
            "-ps {ps}, 3 tile loops: picture differs"
        );
        let st = stat(&job);
        assert_eq!(st["done"], st["tiles"]);
        // Every tile, and every piece its loops split off for each other, by this worker.
        let tasks = st["tiles"].as_u64().unwrap() + st["pieces"].as_u64().unwrap();
        assert_eq!(st["workers"][0]["tiles_done"], tasks, "{st}");
    }
}

/// Workers take the top-level geometry from the job's scene image (tplan writes it); a
/// damaged or missing image is refused with the reason, the scene is built instead and a
/// new image is written; the pictures are those of tpict either way.
#[test]
fn workers_use_sound_scene_images_and_replace_bad_ones() {
    let args = view_args(48, 36, &["-ab", "0"]);
    let mut refargs = vec!["-n".to_string(), "1".into()];
    refargs.extend(args.iter().cloned());
    let reference = tpict(&refargs);
    let d = tempfile::tempdir().unwrap();
    let run = |job: &Path, id: &str| -> String {
        let out = cmd("tpiece")
            .arg(job)
            .args(["--worker-id", id, "--threads", "1"])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr).into_owned();
        assert!(out.status.success(), "{err}");
        // A worker whose only open tiles are its own does not say it waits for others.
        assert!(!err.contains("waiting for 0"), "{err}");
        err
    };
    for damage in ["none", "flip", "remove", "truncate", "directory"] {
        let job = d.path().join(format!("job-{damage}"));
        plan(&job, &["--workers", "1", "--tiles", "6"], &args);
        let image = job.join("scene.img");
        let good = std::fs::read(&image).unwrap();
        assert!(good.starts_with(b"TSSCNIMG"));
        match damage {
            "flip" => {
                let mut b = good.clone();
                let k = b.len() * 2 / 3;
                b[k] ^= 1;
                std::fs::write(&image, b).unwrap();
            }
            "remove" => std::fs::remove_file(&image).unwrap(),
            "truncate" => std::fs::write(&image, &good[..100]).unwrap(),
            "directory" => {
                // Neither readable nor replaceable: the worker renders without it.
                std::fs::remove_file(&image).unwrap();
                std::fs::create_dir(&image).unwrap();
                std::fs::write(image.join("x"), b"x").unwrap();
            }
            _ => {}
        }
        let err = run(&job, "w0");
        let img = assemble(&job);
        assert!(img.pixels == reference.pixels, "{damage}: picture differs");
        let want = match damage {
            "none" => None,
            "flip" => Some("checksum mismatch"),
            "remove" => Some("there is none"),
            "directory" => Some("not used ("),
            _ => Some("truncated"),
        };
        match want {
            None => assert!(!err.contains("scene.img"), "{err}"),
            Some(w) if damage == "directory" => {
                assert!(
                    err.contains(w) && err.contains("cannot write a new one"),
                    "{err}"
                );
            }
            Some(w) => {
                assert!(
                    err.contains("scene.img: not used (") && err.contains(w),
                    "{damage}: {err}"
                );
                assert!(err.contains("wrote a new one"), "{err}");
                // The new image is the planner's, byte for byte but for the names of the
                // files the surfaces came from (the job's flattened scene), and sound.
                let again = std::fs::read(&image).unwrap();
                assert!(again.starts_with(b"TSSCNIMG"));
                let err = run(&job, "w1");
                assert!(!err.contains("scene.img"), "{damage}, second worker: {err}");
            }
        }
    }
}

#[test]
fn ambient_values_are_shared_and_not_recomputed() {
    let amb = [
        "-ab", "1", "-ad", "256", "-as", "0", "-aa", ".15", "-ps", "1",
    ];
    let args = view_args(120, 90, &amb);
    let reference = tpict(&args);
    let mut counts = Vec::new();
    let mut pictures = Vec::new();
    for n in [1usize, 2, 4] {
        let d = tempfile::tempdir().unwrap();
        let job = d.path().join("job");
        let tiles = (80 * n).to_string();
        plan(
            &job,
            &["--workers", &n.to_string(), "--tiles", &tiles],
            &args,
        );
        run_workers(&job, n, &["--amb-flush", "auto"]);
        let img = assemble(&job);
        let st = stat(&job);
        let made = st["aggregate"]["new_values"].as_u64().unwrap();
        let shared_in = st["aggregate"]["shared_in"].as_u64().unwrap();
        eprintln!("{n} workers: {made} new values, {shared_in} shared in");
        if n > 1 {
            assert!(shared_in > 0, "{n} workers shared nothing");
            // Every worker used values another one computed.
            for w in st["workers"].as_array().unwrap() {
                assert!(w["shared_in"].as_u64().unwrap() > 0, "{w}");
            }
        }
        // The merged store holds every value once.
        run_ok(cmd("tmerge").arg(&job));
        let idx: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(job.join("merged/store.json")).unwrap())
                .unwrap();
        assert_eq!(idx["records"].as_u64().unwrap(), made);
        within_tolerance(&img, &reference, &format!("{n} workers vs tpict"));
        counts.push(made);
        pictures.push(img);
    }
    within_tolerance(&pictures[2], &pictures[0], "4 workers vs 1");
    let ratio = counts[2] as f64 / counts[0] as f64;
    eprintln!("new values 4 workers / 1 worker = {ratio:.3}");
    assert!(
        ratio <= 1.10,
        "4 workers made {} values, 1 worker {}",
        counts[2],
        counts[0]
    );
}

/// A tiny deterministic generator for the fault campaign.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
}

fn kill9(c: &mut Child) {
    let _ = c.kill(); // SIGKILL on Unix
    let _ = c.wait();
}

/// Every whole record of every worker log must be in the merged store.
fn assert_logs_in_store(job: &Path) {
    use std::collections::HashSet;
    use tessera::ambient::log::LogReader;
    let idx: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(job.join("merged/store.json")).unwrap())
            .unwrap();
    let store = job.join("merged").join(idx["store"].as_str().unwrap());
    let mut r = LogReader::open(&store, None, false).unwrap();
    let ids: HashSet<_> = r.read_available().unwrap().iter().map(|x| x.id).collect();
    let mut total = 0;
    for e in std::fs::read_dir(job.join("amb")).unwrap() {
        let p = e.unwrap().path();
        let Ok(mut r) = LogReader::open(&p, None, false) else {
            continue; // a log whose header was never completed holds no record
        };
        for rec in r.read_available().unwrap() {
            total += 1;
            assert!(
                ids.contains(&rec.id),
                "{}: record {:?} not merged",
                p.display(),
                rec.id
            );
        }
    }
    assert!(total > 0);
}

#[test]
fn killed_workers_lose_nothing() {
    let rounds: u64 = std::env::var("TESSERA_FAULT_ROUNDS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(20);
    // Every pixel traced (`-ps 1`): with adaptive pixel sampling a cell whose corners happen
    // to agree is interpolated, and whether a light's edge pixel is traced then depends on
    // the ambient values at the corners; once in about six campaigns two pixels of the
    // luminaire came out dark (rms 7.6%, max 195%), which says nothing about lost work.
    let amb = [
        "-ab", "1", "-ad", "128", "-as", "0", "-aa", ".2", "-ps", "1",
    ];
    let args = view_args(64, 48, &amb);
    let d = tempfile::tempdir().unwrap();
    // The fault-free picture.
    let clean = d.path().join("clean");
    // Many small tiles (the default plan would give few at this cost): kills land mid-job.
    plan(&clean, &["--tiles", "320", "--lease", "0.3"], &args);
    run_workers(&clean, 2, &[]);
    let clean_img = assemble(&clean);
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let mut kills = 0;
    let mut reclaimed = 0;
    for round in 0..rounds {
        let job = d.path().join(format!("job{round}"));
        plan(&job, &["--tiles", "320", "--lease", "0.3"], &args);
        let mut kids: Vec<Option<Child>> = (0..4)
            .map(|i| {
                Some(
                    worker(&job, &format!("r{round}w{i}"), &["--amb-flush", "5"])
                        .stderr(Stdio::null())
                        .spawn()
                        .unwrap(),
                )
            })
            .collect();
        // Kill 1–3 random workers at random times; restart about half of them (sometimes
        // under the same id, as a requeued SLURM task would be).
        let victims = 1 + rng.below(3);
        for _ in 0..victims {
            std::thread::sleep(Duration::from_millis(20 + rng.below(250)));
            let i = rng.below(4) as usize;
            if let Some(mut c) = kids[i].take() {
                kill9(&mut c);
                kills += 1;
            }
            if rng.below(2) == 0 {
                let id = if rng.below(2) == 0 {
                    format!("r{round}w{i}")
                } else {
                    format!("r{round}x{i}")
                };
                kids[i] = Some(
                    worker(&job, &id, &["--amb-flush", "5"])
                        .stderr(Stdio::null())
                        .spawn()
                        .unwrap(),
                );
            }
        }
        // A merge while workers run is safe (its result is checked below, after the final one).
        run_ok(cmd("tmerge").arg(&job));
        // Survivors finish the job, re-claiming what the dead held.
        let deadline = Instant::now() + Duration::from_secs(120);
        let mut all_dead = true;
        for c in kids.iter_mut().flatten() {
            all_dead = false;
            loop {
                if let Some(st) = c.try_wait().unwrap() {
                    assert!(st.success(), "round {round}: a worker failed");
                    break;
                }
                assert!(Instant::now() < deadline, "round {round}: workers hang");
                std::thread::sleep(Duration::from_millis(20));
            }
        }
        if all_dead {
            run_workers(&job, 1, &[]);
        } else {
            // Nothing may be left: a worker only exits when every tile is done.
            let st = stat(&job);
            assert_eq!(st["done"], st["tiles"], "round {round}");
        }
        let img = assemble(&job);
        within_tolerance(&img, &clean_img, &format!("round {round}"));
        reclaimed += stat(&job)["aggregate"]["reclaimed"].as_u64().unwrap();
        // Every tile result exists exactly once and covers its own rectangle.
        let tiles = std::fs::read_dir(job.join("tiles"))
            .unwrap()
            .filter(|e| {
                e.as_ref()
                    .unwrap()
                    .file_name()
                    .to_string_lossy()
                    .ends_with(".tile")
            })
            .count();
        // (Pieces split off a tile at the end of the job have results of their own.)
        let st = stat(&job);
        let tasks = st["tiles"].as_u64().unwrap() + st["pieces"].as_u64().unwrap();
        assert_eq!(tiles as u64, tasks, "round {round}");
        assert_eq!(st["pieces_done"], st["pieces"], "round {round}");
        // Every task has exactly one state entry, and it is `done`: no tile was finished
        // twice into two states, none was left claimed or to do.
        let mut entries = std::collections::HashMap::<String, Vec<String>>::new();
        for e in std::fs::read_dir(job.join("tasks")).unwrap() {
            let name = e.unwrap().file_name().to_string_lossy().into_owned();
            if let Some((task, state)) = name.split_once('.') {
                if task.starts_with('f') && state != "made" {
                    entries.entry(task.into()).or_default().push(state.into());
                }
            }
        }
        assert_eq!(entries.len() as u64, tiles as u64, "round {round}");
        for (task, states) in &entries {
            assert_eq!(states, &["done"], "round {round}: task {task}");
        }
        run_ok(cmd("tmerge").arg(&job));
        assert_logs_in_store(&job);
        let _ = std::fs::remove_dir_all(&job);
    }
    assert!(kills >= rounds, "{kills} kills in {rounds} rounds");
    // The kills hit workers holding tiles: others took those over.
    eprintln!("{kills} kills, {reclaimed} tiles re-claimed in {rounds} rounds");
    assert!(
        reclaimed >= rounds / 5,
        "{reclaimed} re-claims in {rounds} rounds"
    );
}

/// Plan a 48×36 `-ab 0` job of about `tiles` tiles with a lease of 0.5 s whose first tile
/// is claimed by the ghost owner `ghost.0000dead`; its `tasks/`.
fn ghost_job(job: &Path, tiles: &str) -> PathBuf {
    plan(
        job,
        &["--tiles", tiles, "--lease", "0.5"],
        &view_args(48, 36, &["-ab", "0"]),
    );
    let tasks = job.join("tasks");
    std::fs::rename(
        tasks.join("f00000-t00000.todo"),
        tasks.join("f00000-t00000.claim.ghost.0000dead"),
    )
    .unwrap();
    tasks
}

/// `tpiece -q` prints nothing, also while it waits for a tile another worker holds; its
/// tile loops (`--threads 2`) share the job like separate workers.
#[test]
fn quiet_workers_say_nothing() {
    let d = tempfile::tempdir().unwrap();
    let job = d.path().join("job");
    let tasks = ghost_job(&job, "6");
    let out = cmd("tpiece")
        .arg(&job)
        .args(["--worker-id", "quiet", "--threads", "2", "-q"])
        .output()
        .unwrap();
    assert!(out.status.success());
    assert!(tasks.join("f00000-t00000.done").exists());
    assert_eq!(String::from_utf8_lossy(&out.stderr), "");
    assemble(&job);
}

#[test]
fn stale_claims_are_reclaimed_after_the_lease() {
    let d = tempfile::tempdir().unwrap();
    let job = d.path().join("job");
    let tasks = ghost_job(&job, "3");
    // Its heartbeat never changes.
    std::fs::write(
        job.join("workers/ghost.0000dead.json"),
        r#"{"worker_id":"ghost","owner":"ghost.0000dead","host":"x","pid":1,"state":"running","beat":7,"started_unix":0,"updated_unix":4102444800,"threads":1,"tiles_done":0,"t_render":0,"t_spec":0,"t_amb":0,"t_idle":0,"t_sync":0,"new_values":0,"shared_in":0,"shared_out":0,"amb_flush":0,"rays":0,"cpu_seconds":0,"error":null}"#,
    )
    .unwrap();
    // A worker that died in 1970 is stale; the ghost, whose record is dated 2100 (a host
    // whose clock disagrees), counts as live for tstat, which is informational only.
    let ghost = std::fs::read_to_string(job.join("workers/ghost.0000dead.json")).unwrap();
    std::fs::write(
        job.join("workers/old.00000001.json"),
        ghost
            .replace("ghost.0000dead", "old.00000001")
            .replace("4102444800", "1"),
    )
    .unwrap();
    let st = stat(&job);
    assert_eq!(st["aggregate"]["stale"], 1, "{st}");
    assert_eq!(st["aggregate"]["live"], 1, "{st}");
    assert_eq!(st["frames"][0]["claimed"], 1, "{st}");
    // The dead worker is shown stale, not as the `running` its last record says.
    assert_eq!(
        st["shown_state"],
        serde_json::json!(["running", "stale"]),
        "{st}"
    );
    let text = cmd("tstat").arg(&job).output().unwrap();
    let text = String::from_utf8_lossy(&text.stdout);
    assert!(text.ends_with('\n'), "{text}");
    assert!(text.contains("wall-s") && text.contains("CPU-s"), "{text}");
    assert!(
        text.lines()
            .any(|l| l.contains("old.00000001") && l.contains("stale")),
        "{text}"
    );
    let t = Instant::now();
    // Not quiet (`-q` silences the waiting lines too: quiet_workers_say_nothing).
    let mut live = cmd("tpiece")
        .arg(&job)
        .args(["--worker-id", "live", "--threads", "1"])
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // A staleness test that trusted the ghost's clock (year 2100) would wait forever.
    loop {
        if let Some(st) = live.try_wait().unwrap() {
            assert!(st.success());
            break;
        }
        if t.elapsed() > Duration::from_secs(60) {
            kill9(&mut live);
            panic!("the worker did not re-claim the ghost's tile within 60 s");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    // Its clock in the future does not matter: staleness is judged by the lease only.
    assert!(t.elapsed() >= Duration::from_millis(500));
    assert!(tasks.join("f00000-t00000.done").exists());
    // While it waited, it said what for.
    let err = live.wait_with_output().unwrap().stderr;
    let err = String::from_utf8_lossy(&err);
    assert!(
        err.contains("waiting for 1 tile(s) other workers hold (ghost.0000dead)"),
        "{err}"
    );
    assemble(&job);
}

/// tstat shows a worker whose heartbeat is late (three beat intervals) but within the
/// lease as suspect, not live, and counts done tiles no heartbeat reports yet.
#[test]
fn tstat_shows_suspect_workers_and_unreported_tiles() {
    let d = tempfile::tempdir().unwrap();
    let job = d.path().join("job");
    plan(
        &job,
        &["--tiles", "3", "--lease", "180"],
        &view_args(48, 36, &["-ab", "0"]),
    );
    let tasks = job.join("tasks");
    std::fs::rename(
        tasks.join("f00000-t00000.todo"),
        tasks.join("f00000-t00000.claim.quiet.00000001"),
    )
    .unwrap();
    std::fs::rename(
        tasks.join("f00000-t00001.todo"),
        tasks.join("f00000-t00001.done"),
    )
    .unwrap();
    let now = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .as_secs_f64();
    // Beats every 10 s at a lease of 180 s: silent for 45 s is suspect.
    std::fs::write(
        job.join("workers/quiet.00000001.json"),
        format!(
            r#"{{"worker_id":"quiet","owner":"quiet.00000001","host":"x","pid":1,"state":"running","beat":7,"started_unix":{},"updated_unix":{},"threads":1,"tiles_done":0,"t_render":0,"t_spec":0,"t_amb":0,"t_idle":0,"t_sync":0,"new_values":0,"shared_in":0,"shared_out":0,"amb_flush":0,"rays":0,"cpu_seconds":0,"error":null}}"#,
            now - 100.0,
            now - 45.0
        ),
    )
    .unwrap();
    let st = stat(&job);
    assert_eq!(st["aggregate"]["suspect"], 1, "{st}");
    assert_eq!(st["aggregate"]["live"], 0, "{st}");
    assert_eq!(st["aggregate"]["unreported_tiles"], 1, "{st}");
    let text = String::from_utf8(run_ok(cmd("tstat").arg(&job))).unwrap();
    assert!(
        text.contains("1 suspect") && text.contains("unreported"),
        "{text}"
    );
}

#[test]
fn late_workers_duplicate_ids_and_merges_are_harmless() {
    let d = tempfile::tempdir().unwrap();
    let job = d.path().join("job");
    let args = view_args(48, 36, &["-ab", "1", "-ad", "64", "-as", "0", "-ps", "1"]);
    plan(&job, &["--tiles", "8"], &args);
    // Two workers with the same id: distinct owners, distinct logs, one picture.
    let a = worker(&job, "same", &[]).spawn().unwrap();
    let b = worker(&job, "same", &[]).spawn().unwrap();
    assert!(a.wait_with_output().unwrap().status.success());
    assert!(b.wait_with_output().unwrap().status.success());
    let logs = std::fs::read_dir(job.join("amb")).unwrap().count();
    assert_eq!(logs, 2);
    let pic = assemble(&job);
    // A worker started after everything is done exits at once, successfully.
    let t = Instant::now();
    let out = worker(&job, "late", &[]).output().unwrap();
    assert!(out.status.success());
    assert!(t.elapsed() < Duration::from_secs(5));
    // Merging twice changes nothing the second time; two merges at once both succeed.
    run_ok(cmd("tmerge").arg(&job));
    let first = std::fs::read(job.join("merged/store.json")).unwrap();
    let out = run_ok(cmd("tmerge").arg(&job).arg("--json"));
    let rep: serde_json::Value = serde_json::from_slice(&out).unwrap();
    assert_eq!(rep["added"], 0);
    assert!(rep["written"].is_null());
    assert_eq!(std::fs::read(job.join("merged/store.json")).unwrap(), first);
    let m1 = cmd("tmerge").arg(&job).spawn().unwrap();
    let m2 = cmd("tmerge").arg(&job).spawn().unwrap();
    assert!(m1.wait_with_output().unwrap().status.success());
    assert!(m2.wait_with_output().unwrap().status.success());
    // A new job seeded with the store makes far fewer values.
    let exported = d.path().join("amb.rad");
    run_ok(
        cmd("tmerge")
            .arg(&job)
            .arg("--export-radiance")
            .arg(&exported),
    );
    let job2 = d.path().join("job2");
    let store: serde_json::Value =
        serde_json::from_slice(&std::fs::read(job.join("merged/store.json")).unwrap()).unwrap();
    let store_file = job.join("merged").join(store["store"].as_str().unwrap());
    plan(
        &job2,
        &["--tiles", "8", "--ambient", store_file.to_str().unwrap()],
        &args,
    );
    run_workers(&job2, 1, &[]);
    let st = stat(&job2);
    let before = stat(&job)["aggregate"]["new_values"].as_u64().unwrap();
    let after = st["aggregate"]["new_values"].as_u64().unwrap();
    eprintln!("seeded job: {after} new values (first job {before})");
    assert!(after * 4 < before, "{after} vs {before}");
    within_tolerance(&assemble(&job2), &pic, "seeded job");
    // The Radiance export is a valid ambient file with every value.
    let (_, recs, _) = tessera::ambient::radfile::read_file(&exported).unwrap();
    assert_eq!(recs.len() as u64, store["records"].as_u64().unwrap());
    // ... and seeds a job as well (Radiance's format carries no fingerprint).
    let job3 = d.path().join("job3");
    plan(
        &job3,
        &["--tiles", "8", "--ambient", exported.to_str().unwrap()],
        &args,
    );
    run_workers(&job3, 1, &[]);
    let from_rad = stat(&job3)["aggregate"]["new_values"].as_u64().unwrap();
    eprintln!("job seeded from the Radiance export: {from_rad} new values");
    assert!(from_rad * 4 < before, "{from_rad} vs {before}");
    within_tolerance(&assemble(&job3), &pic, "job seeded from a Radiance file");
}

#[test]
fn bad_input_and_full_disks_fail_cleanly() {
    let d = tempfile::tempdir().unwrap();
    let job = d.path().join("job");
    let args = view_args(32, 24, &["-ab", "0"]);
    plan(&job, &["--tiles", "4"], &args);
    // Planning into an existing job directory is refused.
    let out = cmd("tplan")
        .arg("-o")
        .arg(&job)
        .arg("--")
        .args(&args)
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("not empty"));
    // A lease too long to be a duration (it made every worker panic): refused by tplan,
    // and in a manifest edited by hand by every worker, with an error.
    let out = cmd("tplan")
        .args(["--lease", "1e20", "-o"])
        .arg(d.path().join("long"))
        .arg("--")
        .args(&args)
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--lease"));
    let long = d.path().join("long2");
    plan(&long, &["--tiles", "2"], &args);
    let m = std::fs::read_to_string(long.join("manifest.json")).unwrap();
    let edited = m.replace("\"lease_seconds\": 180.0", "\"lease_seconds\": 1e300");
    assert_ne!(m, edited, "the manifest's lease line");
    std::fs::write(long.join("manifest.json"), edited).unwrap();
    let out = worker(&long, "w", &[]).output().unwrap();
    assert_eq!(out.status.code(), Some(1), "{out:?}");
    assert!(String::from_utf8_lossy(&out.stderr).contains("lease_seconds"));
    // Bad worker ids are refused before anything is touched.
    for bad in ["../x", "a/b", "a.b", ""] {
        let out = cmd("tpiece")
            .arg(&job)
            .args(["--worker-id", bad])
            .output()
            .unwrap();
        assert!(!out.status.success(), "{bad}");
    }
    // A disk-full error on a tile result: clear error, the tile goes back to todo.
    let out = worker(&job, "full", &[])
        .env("TESSERA_FAULT_TILE_ENOSPC", "1")
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("No space left") && err.contains("released"),
        "{err}"
    );
    let names = task_entries(&job);
    assert!(names.iter().all(|n| n.ends_with(".todo")), "{names:?}");
    // The job still completes.
    run_workers(&job, 1, &[]);
    let full = assemble(&job);
    // Missing tiles: tassemble names them and fails; --partial fills black.
    std::fs::remove_file(job.join("tiles/f00000-t00001.tile")).unwrap();
    let out = cmd("tassemble")
        .arg(&job)
        .arg("-o")
        .arg(d.path().join("x.hdr"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("f00000-t00001"));
    assert!(!d.path().join("x.hdr").exists());
    let out = cmd("tassemble")
        .arg(&job)
        .arg("--partial")
        .arg("-o")
        .arg(d.path().join("x.hdr"))
        .output()
        .unwrap();
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("f00000-t00001"));
    // The missing tile is black and named in the header; the rest is the full picture.
    let part = read_picture(&d.path().join("x.hdr")).unwrap();
    let head = std::fs::read(d.path().join("x.hdr")).unwrap();
    assert!(String::from_utf8_lossy(&head[..head.len().min(4096)])
        .contains("TESSERA_MISSING_TILES=f00000-t00001"));
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(job.join("manifest.json")).unwrap()).unwrap();
    let rect = manifest
        .pointer("/frames/0/tiles/1")
        .or_else(|| manifest.pointer("/tiles/1"))
        .cloned()
        .expect("tile 1 in the manifest");
    let (x0, y0, w, h) = (
        rect["x0"].as_u64().unwrap() as usize,
        rect["y0"].as_u64().unwrap() as usize,
        rect["w"].as_u64().unwrap() as usize,
        rect["h"].as_u64().unwrap() as usize,
    );
    assert!(w > 0 && h > 0);
    for (i, p) in part.pixels.iter().enumerate() {
        let (x, y) = (i % part.width, i / part.width);
        if x >= x0 && x < x0 + w && y >= y0 && y < y0 + h {
            assert_eq!(p, &[0.0; 3], "pixel ({x}, {y}) of the missing tile");
        } else {
            assert_eq!(p, &full.pixels[i], "pixel ({x}, {y})");
        }
    }
    // Hostile manifests are refused with the file named.
    let m = std::fs::read_to_string(job.join("manifest.json")).unwrap();
    for (from, to) in [
        (
            "\"scene_file\": \"scene.rad\"",
            "\"scene_file\": \"../../etc/passwd\"",
        ),
        ("\"lease_seconds\": 180.0", "\"lease_seconds\": -1.0"),
        ("\"x0\": 0", "\"x0\": 1"),
        ("\"format\": \"tessera-job\"", "\"format\": \"other\""),
    ] {
        assert!(m.contains(from), "{from}");
        std::fs::write(job.join("manifest.json"), m.replacen(from, to, 1)).unwrap();
        for prog in ["tpiece", "tassemble", "tstat", "tmerge"] {
            let out = cmd(prog).arg(&job).output().unwrap();
            assert!(!out.status.success(), "{prog} accepted {to}");
            assert!(
                String::from_utf8_lossy(&out.stderr).contains("manifest.json"),
                "{prog}: {}",
                String::from_utf8_lossy(&out.stderr)
            );
        }
    }
    std::fs::write(job.join("manifest.json"), "{ not json").unwrap();
    let out = cmd("tstat").arg(&job).output().unwrap();
    assert!(String::from_utf8_lossy(&out.stderr).contains("manifest.json:1:"));
    // A changed scene is refused by workers.
    std::fs::write(job.join("manifest.json"), &m).unwrap();
    let mut scene = std::fs::read_to_string(job.join("scene.rad")).unwrap();
    scene.push_str("\nvoid plastic extra\n0\n0\n5 .5 .5 .5 0 0\n");
    std::fs::write(job.join("scene.rad"), scene).unwrap();
    let out = cmd("tpiece").arg(&job).output().unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("changed since the job was planned"));
}

#[test]
fn animation_frames_are_planned_and_assembled() {
    let d = tempfile::tempdir().unwrap();
    let frames = d.path().join("walk.vf");
    std::fs::write(
        &frames,
        "VIEW= -vp 7.6 0.35 2.1\nVIEW= -vp 7.4 0.55 2.1\nVIEW= -vp 7.2 0.75 2.1\n",
    )
    .unwrap();
    let job = d.path().join("job");
    let args = view_args(40, 30, &["-ab", "0"]);
    let mut c = cmd("tplan");
    c.args(["--tiles", "3", "--frames"])
        .arg(&frames)
        .arg("-o")
        .arg(&job)
        .arg("--")
        .args(&args);
    run_ok(&mut c);
    run_workers(&job, 2, &[]);
    let pat = d.path().join("f%02d.hdr");
    run_ok(
        cmd("tassemble")
            .arg(&job)
            .arg("--all-frames")
            .arg("-o")
            .arg(&pat),
    );
    for f in 0..3 {
        let img = read_picture(&d.path().join(format!("f{f:02}.hdr"))).unwrap();
        assert_eq!(img.header.frame, Some(f));
        assert!(img.pixels_f64().iter().any(|p| p[0] > 0.0));
    }
}

mod manifest_fuzz {
    use proptest::prelude::*;
    use tessera::job::manifest::Manifest;

    fn good() -> String {
        let d = tempfile::tempdir().unwrap();
        let job = d.path().join("job");
        super::plan(
            &job,
            &["--tiles", "5"],
            &super::view_args(16, 12, &["-ab", "0"]),
        );
        std::fs::read_to_string(job.join("manifest.json")).unwrap()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]
        /// Hostile manifests (random byte edits of a valid one) never panic the loader: they
        /// either fail to parse, fail validation, or are valid.
        #[test]
        fn mutated_manifests_never_panic(edits in proptest::collection::vec((any::<usize>(), any::<u8>()), 1..8)) {
            thread_local!(static GOOD: String = good());
            let mut b = GOOD.with(|g| g.clone().into_bytes());
            for (pos, byte) in edits {
                let i = pos % b.len();
                b[i] = byte;
            }
            if let Ok(text) = String::from_utf8(b) {
                if let Ok(m) = serde_json::from_str::<Manifest>(&text) {
                    let _ = m.validate();
                }
            }
        }
    }
}

/// A worker stopped (SIGSTOP) while it renders a tile outlives its lease; another worker
/// re-claims and finishes the tile and the job; when the first resumes it completes its
/// tile too, harmlessly: it exits 0 and the picture is the same.
#[test]
fn a_resumed_slow_worker_finishing_a_reclaimed_tile_is_harmless() {
    let d = tempfile::tempdir().unwrap();
    let job = d.path().join("job");
    let args = view_args(
        64,
        48,
        &[
            "-ab", "1", "-ad", "256", "-as", "0", "-aa", ".1", "-ps", "1",
        ],
    );
    plan(&job, &["--tiles", "2", "--lease", "0.5"], &args);
    // Not quiet: it reports a tile finished after someone else re-claimed it.
    let mut slow = cmd("tpiece")
        .arg(&job)
        .args(["--worker-id", "slow", "--threads", "1"])
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Wait until it holds a tile, then freeze it mid-render.
    let tasks = job.join("tasks");
    let t = Instant::now();
    let held = loop {
        let claimed = std::fs::read_dir(&tasks).unwrap().find_map(|e| {
            let n = e.unwrap().file_name().to_string_lossy().into_owned();
            n.contains(".claim.slow.").then_some(n)
        });
        if let Some(n) = claimed {
            break n;
        }
        assert!(t.elapsed() < Duration::from_secs(30), "no claim");
        std::thread::sleep(Duration::from_millis(2));
    };
    let signal = |sig: &str| {
        let ok = Command::new("kill")
            .args([sig, &slow.id().to_string()])
            .status()
            .unwrap()
            .success();
        assert!(ok, "kill {sig}");
    };
    signal("-STOP");
    let task = held.split('.').next().unwrap().to_string();
    // Another worker re-claims it after the lease and finishes everything.
    run_ok(&mut worker(&job, "fast", &[]));
    assert!(tasks.join(format!("{task}.done")).exists());
    let tile_file = job.join("tiles").join(format!("{task}.tile"));
    let owner_of = |p: &Path| tessera::job::tile::read(p).unwrap().0.owner;
    assert!(owner_of(&tile_file).starts_with("fast."));
    let before = assemble(&job);
    signal("-CONT");
    let t = Instant::now();
    let status = loop {
        if let Some(st) = slow.try_wait().unwrap() {
            break st;
        }
        if t.elapsed() > Duration::from_secs(60) {
            kill9(&mut slow);
            panic!("the resumed worker did not end");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let mut err = String::new();
    std::io::Read::read_to_string(&mut slow.stderr.take().unwrap(), &mut err).unwrap();
    assert!(status.success(), "{err}");
    // Its late result replaced the other one (the later rename wins; both are complete).
    // (Its own task entry was already `done`: on NFS a rename that reports ENOENT is taken
    // as done when the target exists, so it cannot tell and need not.)
    assert!(
        owner_of(&tile_file).starts_with("slow."),
        "the slow worker should have written its tile late: {err}"
    );
    // Still exactly one entry per task, all done; the picture is as good as before.
    let names = task_entries(&job);
    // (Pieces split off have a marker besides their state: `.made`.)
    assert!(
        names
            .iter()
            .all(|n| n.ends_with(".done") || n.ends_with(".made")),
        "{names:?}"
    );
    let after = assemble(&job);
    within_tolerance(&after, &before, "after the slow worker's late result");
}

/// A full disk while a worker appends its ambient log: a clear error naming the log, the
/// tile goes back to todo, and the job completes with another worker.
#[test]
fn a_full_disk_under_the_ambient_log_releases_the_tile() {
    let d = tempfile::tempdir().unwrap();
    let job = d.path().join("job");
    let args = view_args(48, 36, &["-ab", "1", "-ad", "64", "-as", "0", "-ps", "1"]);
    plan(&job, &["--tiles", "2"], &args);
    let out = worker(&job, "full", &[])
        .env("TESSERA_FAULT_LOG_ENOSPC", "1")
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("ambient log")
            && err.contains("No space left")
            && err.contains("released")
            && err.contains(".log"),
        "{err}"
    );
    let names = task_entries(&job);
    assert!(names.iter().all(|n| n.ends_with(".todo")), "{names:?}");
    run_workers(&job, 1, &[]);
    assemble(&job);
}

/// tassemble writes Radiance to stdout, OpenEXR and PNG, all of the same picture.
#[test]
fn tassemble_writes_every_format() {
    let d = tempfile::tempdir().unwrap();
    let job = d.path().join("job");
    plan(&job, &["--tiles", "3"], &view_args(40, 30, &["-ab", "0"]));
    run_workers(&job, 1, &[]);
    let hdr = assemble(&job);
    let out = cmd("tassemble").arg(&job).output().unwrap();
    assert!(out.status.success());
    let stdout_pic = d.path().join("stdout.hdr");
    std::fs::write(&stdout_pic, &out.stdout).unwrap();
    assert!(out.stdout.starts_with(b"#?RADIANCE"));
    assert_eq!(read_picture(&stdout_pic).unwrap().pixels, hdr.pixels);
    let exr = d.path().join("p.exr");
    run_ok(cmd("tassemble").arg(&job).arg("-o").arg(&exr));
    let e = read_picture(&exr).unwrap();
    assert_eq!((e.width, e.height), (hdr.width, hdr.height));
    // EXR keeps half floats; RGBE shares one exponent, so its channels are exact to about
    // 1/256 of the pixel's largest channel.
    for (a, b) in e.pixels.iter().zip(&hdr.pixels) {
        let big = b.iter().fold(0f32, |m, v| m.max(v.abs()));
        for c in 0..3 {
            assert!((a[c] - b[c]).abs() <= 0.01 * big + 1e-4, "{a:?} {b:?}");
        }
    }
    let png = d.path().join("p.png");
    run_ok(cmd("tassemble").arg(&job).arg("-o").arg(&png));
    let bytes = std::fs::read(&png).unwrap();
    assert!(bytes.starts_with(b"\x89PNG\r\n\x1a\n"));
    let img = image::load_from_memory(&bytes).unwrap();
    assert_eq!(
        (img.width() as usize, img.height() as usize),
        (hdr.width, hdr.height)
    );
    // An existing picture is not replaced without --force (it is left as it was).
    std::fs::write(&png, b"mine").unwrap();
    let o = cmd("tassemble")
        .arg(&job)
        .arg("-o")
        .arg(&png)
        .output()
        .unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("exists") && err.contains("--force"), "{err}");
    assert_eq!(std::fs::read(&png).unwrap(), b"mine");
    run_ok(
        cmd("tassemble")
            .arg(&job)
            .arg("--force")
            .arg("-o")
            .arg(&png),
    );
    assert!(std::fs::read(&png).unwrap().starts_with(b"\x89PNG"));
}

/// `tstat --baseline`: speed-up and efficiency against a one-worker job, counting a
/// restarted worker (same id, two incarnations) once.
#[test]
fn tstat_baseline_reports_speedup_per_worker() {
    let d = tempfile::tempdir().unwrap();
    let args = view_args(48, 36, &["-ab", "1", "-ad", "64", "-as", "0", "-ps", "1"]);
    let one = d.path().join("one");
    plan(&one, &["--tiles", "6"], &args);
    run_workers(&one, 1, &[]);
    let two = d.path().join("two");
    plan(&two, &["--tiles", "6"], &args);
    run_workers(&two, 2, &[]);
    // A second incarnation of one of them (it finds nothing to do).
    let w0 = std::fs::read_dir(two.join("workers"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .find(|n| n.ends_with(".json"))
        .unwrap();
    let id = w0.split('.').next().unwrap().to_string();
    run_ok(&mut worker(&two, &id, &[]));
    let out = run_ok(
        cmd("tstat")
            .arg(&two)
            .arg("--json")
            .arg("--baseline")
            .arg(&one),
    );
    let st: serde_json::Value = serde_json::from_slice(&out).unwrap();
    assert_eq!(st["aggregate"]["workers"], 3, "{st}");
    let b = &st["baseline"];
    let speedup = b["speedup"].as_f64().unwrap();
    let eff = b["efficiency"].as_f64().unwrap();
    assert!(speedup > 0.0, "{b}");
    assert!(
        (eff - speedup / 2.0).abs() < 1e-9,
        "two workers, not three: {b}"
    );
    assert!(b["new_values_ratio"].as_f64().unwrap() > 0.5, "{b}");
    assert!(b["new_values"].as_u64().unwrap() > 0, "{b}");
    let text = run_ok(cmd("tstat").arg(&two).arg("--baseline").arg(&one));
    let text = String::from_utf8_lossy(&text);
    assert!(
        text.contains("speed-up") || text.contains("speedup"),
        "{text}"
    );
}

/// Tessera's ambient settings are part of a job's fingerprint: a job planned with other
/// settings (here the light-leak test off) refuses the logs of a job planned with the
/// defaults, with a warning, while a job with the same settings takes their values.
#[test]
fn logs_of_other_ambient_settings_are_refused() {
    let d = tempfile::tempdir().unwrap();
    let amb = ["-ab", "1", "-aa", ".2", "-ad", "64", "-as", "0", "-ps", "1"];
    let args = view_args(48, 36, &amb);
    let mut other_args = view_args(48, 36, &amb);
    other_args.splice(0..0, ["--amb-corral".to_string(), "off".to_string()]);
    let first = d.path().join("first");
    plan(&first, &["--workers", "1"], &args);
    run_workers(&first, 1, &[]);
    let logs: Vec<PathBuf> = std::fs::read_dir(first.join("amb"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "log"))
        .collect();
    assert!(!logs.is_empty());
    // Each job: seed its amb/ with the first job's logs (under another worker's name), run a
    // worker and read what it took and said.
    let seeded = |name: &str, args: &[String]| {
        let job = d.path().join(name);
        plan(&job, &["--workers", "1"], args);
        for (i, l) in logs.iter().enumerate() {
            std::fs::copy(l, job.join("amb").join(format!("earlier{i}.log"))).unwrap();
        }
        let out = worker(&job, "w0", &[]).output().unwrap();
        assert!(out.status.success());
        let st = stat(&job);
        let shared_in = st["aggregate"]["shared_in"].as_u64().unwrap();
        (shared_in, String::from_utf8_lossy(&out.stderr).into_owned())
    };
    let (same_in, same_err) = seeded("same", &args);
    let (other_in, other_err) = seeded("other", &other_args);
    eprintln!("same settings: {same_in} values shared in; other settings: {other_in}");
    assert!(same_in > 0, "{same_err}");
    assert!(!same_err.contains("ignoring ambient log"), "{same_err}");
    assert_eq!(other_in, 0, "{other_err}");
    assert!(other_err.contains("ignoring ambient log"), "{other_err}");
}

/// tplan suggests `--allow-commands` for a scene's inline commands and takes it before
/// `--` (as its own option) as well as after it (as tpict's).
#[test]
fn tplan_takes_allow_commands_as_its_own_option() {
    let d = tempfile::tempdir().unwrap();
    let scene = d.path().join("cmd.rad");
    std::fs::write(
        &scene,
        "!echo void light l 0 0 3 1 1 1\n!echo l sphere s 0 0 4 0 0 0 1\n",
    )
    .unwrap();
    let args = |job: &str| {
        let mut c = cmd("tplan");
        c.arg("-o").arg(d.path().join(job));
        c
    };
    let view = [
        "-vp", "0", "-5", "0", "-vd", "0", "1", "0", "-x", "16", "-y", "16",
    ];
    let refused = args("refused")
        .arg("--")
        .args(view)
        .arg(&scene)
        .output()
        .unwrap();
    assert!(!refused.status.success());
    assert!(String::from_utf8_lossy(&refused.stderr).contains("--allow-commands"));
    run_ok(
        args("before")
            .arg("--allow-commands")
            .arg("--")
            .args(view)
            .arg(&scene),
    );
    run_ok(
        args("after")
            .arg("--")
            .arg("--allow-commands")
            .args(view)
            .arg(&scene),
    );
}

/// A job whose directory is deleted under a running worker makes the worker fail (it must
/// never report success), and `tstat` reports deleted task entries as damage, not as tiles
/// to do, with a non-zero exit.
#[test]
fn damaged_jobs_are_reported_not_finished() {
    let d = tempfile::tempdir().unwrap();
    let job = d.path().join("job");
    let args = view_args(160, 120, &["-ab", "1", "-ad", "64", "-as", "0"]);
    plan(&job, &["--tiles", "160"], &args);
    // Entries deleted: tstat says so.
    let first = std::fs::read_dir(job.join("tasks"))
        .unwrap()
        .next()
        .unwrap()
        .unwrap()
        .path();
    std::fs::remove_file(&first).unwrap();
    let out = cmd("tstat").arg(&job).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(!out.status.success());
    assert!(text.contains("DAMAGED: 1 tiles"), "{text}");
    let st: serde_json::Value = serde_json::from_slice(
        &cmd("tstat")
            .arg(&job)
            .arg("--json")
            .output()
            .unwrap()
            .stdout,
    )
    .unwrap();
    assert_eq!(st["frames"][0]["missing"], 1);
    // The whole directory deleted while a worker runs: the worker fails.
    let job2 = d.path().join("job2");
    // Several seconds of work on one thread: the deletion comes long before the end.
    let long = view_args(320, 240, &["-ab", "1", "-ad", "256", "-as", "0"]);
    plan(&job2, &["--tiles", "160"], &long);
    let w = worker(&job2, "w0", &[])
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(300));
    let _ = std::fs::remove_dir_all(&job2);
    let out = w.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    if job2.exists() {
        // The worker recreated nothing; a leftover means rm raced a temporary file.
        let _ = std::fs::remove_dir_all(&job2);
    }
    assert!(
        !out.status.success(),
        "a worker that lost its job reported success: {err}"
    );
}

/// `tmerge` on a job whose `merged/` was deleted makes it again and merges every log.
#[test]
fn tmerge_recreates_a_deleted_merged_directory() {
    let d = tempfile::tempdir().unwrap();
    let job = d.path().join("job");
    plan(
        &job,
        &["--tiles", "4"],
        &view_args(32, 24, &["-ab", "1", "-aa", ".2", "-ad", "64", "-as", "0"]),
    );
    run_workers(&job, 1, &[]);
    std::fs::remove_dir_all(job.join("merged")).unwrap();
    let out = cmd("tmerge").arg(&job).output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(job.join("merged/store.json").is_file());
}

/// Tiles split while they render (forced, `TESSERA_FAULT_SPLIT_EAGER`: at every cell while
/// nothing is left to claim and 16 cells or more are): pieces are split off by rows and by
/// columns, claimed by the other workers and split again, and the picture is tpict's bit
/// for bit at `-ab 0`; `tstat` counts the pieces with their tiles; `--no-split` makes none.
#[test]
fn split_tiles_give_tpicts_pixels() {
    let eager = [("TESSERA_FAULT_SPLIT_EAGER", "1")];
    let d = tempfile::tempdir().unwrap();
    for (ps, x, y) in [("4", 96, 72), ("1", 40, 30)] {
        let args = view_args(x, y, &["-ab", "0", "-ps", ps]);
        let reference = tpict(&args);
        let (mut by_rows, mut by_cols) = (0, 0);
        // One tile, and tiles of half the picture's rows.
        for (tiles, workers) in [(1usize, 2usize), (2, 3)] {
            let job = d.path().join(format!("ps{ps}-t{tiles}"));
            let w = workers.to_string();
            let size = format!("{x}x{}", y / 2);
            let mut p = vec!["--workers", &w];
            if tiles == 1 {
                p.extend(["--tiles", "1"]);
            } else {
                p.extend(["--tile-size", &size]);
            }
            plan(&job, &p, &args);
            run_workers_env(&job, workers, &[], &eager);
            let img = assemble(&job);
            let what = format!("-ps {ps}, {tiles} tile(s), {workers} workers");
            assert!(img.pixels == reference.pixels, "{what}: picture differs");
            let st = stat(&job);
            assert_eq!(st["done"], st["tiles"], "{what}");
            let pieces = st["pieces"].as_u64().unwrap();
            assert!(pieces >= 2, "{what}: {pieces} pieces");
            assert_eq!(st["pieces_done"].as_u64(), Some(pieces), "{what}");
            assert_eq!(st["aggregate"]["split"].as_u64(), Some(pieces), "{what}");
            assert_eq!(
                st["aggregate"]["unreported_tiles"].as_u64(),
                Some(0),
                "{what}"
            );
            for e in task_entries(&job) {
                let task = e.split_once('.').unwrap().0;
                if let Some(id) = tessera::job::piece::parse(task).and_then(|id| id.piece) {
                    if id.w == x as usize {
                        by_rows += 1;
                    } else {
                        by_cols += 1;
                    }
                }
            }
        }
        assert!(
            by_rows > 0 && by_cols > 0,
            "-ps {ps}: {by_rows} by rows, {by_cols} by columns"
        );
        // `tstat --costs` gives each tile once, its pieces' seconds added; a piece's lost
        // result is named by tassemble, which writes nothing.
        let job = d.path().join(format!("ps{ps}-t1"));
        let costs: serde_json::Value =
            serde_json::from_slice(&run_ok(cmd("tstat").arg(&job).args(["--costs", "0"]))).unwrap();
        assert_eq!(costs["tiles"].as_array().map(|t| t.len()), Some(1));
        let piece = task_entries(&job)
            .into_iter()
            .find(|e| e.ends_with(".done") && e.len() > 20)
            .unwrap();
        let piece = piece.trim_end_matches(".done");
        std::fs::remove_file(job.join("tiles").join(format!("{piece}.tile"))).unwrap();
        let out = d.path().join("lost.hdr");
        let o = cmd("tassemble")
            .arg(&job)
            .arg("-o")
            .arg(&out)
            .output()
            .unwrap();
        assert!(!o.status.success() && !out.exists());
        assert!(String::from_utf8_lossy(&o.stderr).contains(piece));
        // Splitting turned off: no pieces, the same picture.
        let job = d.path().join(format!("ps{ps}-nosplit"));
        plan(
            &job,
            &["--tiles", "1", "--workers", "2", "--no-split"],
            &args,
        );
        run_workers_env(&job, 2, &[], &eager);
        assert!(assemble(&job).pixels == reference.pixels);
        assert_eq!(stat(&job)["pieces"].as_u64(), Some(0));
    }
}

/// One worker with two tile loops on a one-tile plan, splitting as it does by default (no
/// fault injection): the idle loop's wait lets its sibling split a tile of about 70 ms
/// (on the machine this was written on), too short for a split between processes (the
/// first look after 50 ms, each half at least 50 ms: the worker of the commit before made
/// no piece in 5 runs of this frame), and the picture is tpict's bit for bit at `-ab 0`.
#[test]
fn a_worker_splits_a_lone_tile_among_its_loops() {
    let args = view_args(400, 300, &["-ab", "0"]);
    let reference = tpict(&args);
    let d = tempfile::tempdir().unwrap();
    let job = d.path().join("job");
    plan(&job, &["--tiles", "1", "--workers", "2"], &args);
    run_ok(
        cmd("tpiece")
            .arg(&job)
            .args(["--worker-id", "pair", "--threads", "2", "-q"]),
    );
    assert!(assemble(&job).pixels == reference.pixels, "picture differs");
    let st = stat(&job);
    let pieces = st["pieces"].as_u64().unwrap();
    assert!(pieces >= 1, "{pieces} pieces: {st}");
    assert_eq!(st["pieces_done"].as_u64(), Some(pieces));
}

/// Workers killed while they own tiles and pieces (splitting forced as above): the survivors
/// take them over after the lease and render each whole, and the picture is still tpict's bit
/// for bit at `-ab 0`, with every tile and piece done once.
#[test]
fn killed_owners_of_pieces_lose_nothing() {
    let eager = [("TESSERA_FAULT_SPLIT_EAGER", "1")];
    let args = view_args(400, 300, &["-ab", "0", "-ps", "1"]);
    let reference = tpict(&args);
    let d = tempfile::tempdir().unwrap();
    let mut rng = Rng(0x2545_F491_4F6C_DD1D);
    let mut reclaimed = 0;
    for round in 0..6 {
        let job = d.path().join(format!("job{round}"));
        plan(
            &job,
            &["--tiles", "2", "--workers", "3", "--lease", "0.3"],
            &args,
        );
        let mut kids: Vec<Child> = (0..3)
            .map(|i| {
                worker(&job, &format!("r{round}w{i}"), &[])
                    .envs(eager)
                    .stderr(Stdio::null())
                    .spawn()
                    .unwrap()
            })
            .collect();
        std::thread::sleep(Duration::from_millis(30 + rng.below(120)));
        let victim = rng.below(3) as usize;
        kill9(&mut kids[victim]);
        for (i, c) in kids.iter_mut().enumerate() {
            if i != victim {
                assert!(
                    c.wait().unwrap().success(),
                    "round {round}: a worker failed"
                );
            }
        }
        let img = assemble(&job);
        assert!(
            img.pixels == reference.pixels,
            "round {round}: picture differs"
        );
        let st = stat(&job);
        assert_eq!(st["done"], st["tiles"], "round {round}");
        assert_eq!(st["pieces_done"], st["pieces"], "round {round}");
        reclaimed += st["aggregate"]["reclaimed"].as_u64().unwrap();
        for e in task_entries(&job) {
            assert!(
                e.ends_with(".done") || e.ends_with(".made"),
                "round {round}: {e}"
            );
        }
    }
    eprintln!("{reclaimed} tasks re-claimed in 6 rounds");
    // The kills land while the victim renders (three workers share two tiles and their
    // pieces for about half a second): its task is taken over.
    assert!(reclaimed >= 2, "{reclaimed} re-claims in 6 rounds");
}
