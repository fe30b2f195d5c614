//! Special files in a job directory (issue 27 item 8): a FIFO, a symbolic link to
//! `/dev/zero` or a link out of the job, put where a manifest, heartbeat, ambient log, tile,
//! merged store index or the flattened scene belongs, never blocks `tpiece`, `tmerge`,
//! `tassemble` or `tstat` and is never read: each tool ends within seconds, with a clear
//! error naming the file or by ignoring it.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn bin(name: &str) -> PathBuf {
    PathBuf::from(match name {
        "tplan" => env!("CARGO_BIN_EXE_tplan"),
        "tpiece" => env!("CARGO_BIN_EXE_tpiece"),
        "tmerge" => env!("CARGO_BIN_EXE_tmerge"),
        "tassemble" => env!("CARGO_BIN_EXE_tassemble"),
        _ => env!("CARGO_BIN_EXE_tstat"),
    })
}

/// Run a tool, killing it after 20 s: (finished in time, exit success, stderr).
fn run(name: &str, args: &[&std::ffi::OsStr]) -> (bool, bool, String) {
    let mut c = Command::new(bin(name))
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    loop {
        if let Some(st) = c.try_wait().unwrap() {
            let mut err = String::new();
            use std::io::Read;
            c.stderr.take().unwrap().read_to_string(&mut err).unwrap();
            return (true, st.success(), err);
        }
        if start.elapsed() > Duration::from_secs(20) {
            let _ = c.kill();
            let _ = c.wait();
            return (false, false, String::new());
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn mkfifo(p: &Path) {
    let _ = std::fs::remove_file(p);
    assert!(Command::new("mkfifo").arg(p).status().unwrap().success());
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let t = to.join(e.file_name());
        if e.file_type().unwrap().is_dir() {
            copy_dir(&e.path(), &t);
        } else {
            std::fs::copy(e.path(), &t).unwrap();
        }
    }
}

/// Each tool of the job directory with its arguments on `job` (tassemble writing `out`).
fn tools_on<'a>(job: &'a Path, out: &'a Path) -> [(&'static str, Vec<&'a std::ffi::OsStr>); 4] {
    let w = |s: &'static str| std::ffi::OsStr::new(s);
    [
        (
            "tpiece",
            vec![
                job.as_os_str(),
                w("--threads"),
                w("1"),
                w("-q"),
                w("--no-wait"),
            ],
        ),
        ("tmerge", vec![job.as_os_str()]),
        ("tstat", vec![job.as_os_str()]),
        ("tassemble", vec![job.as_os_str(), w("-o"), out.as_os_str()]),
    ]
}

/// A lamp over a floor.
const SCENE: &str = "void light l 0 0 3 5 5 5\nl sphere b 0 0 4 0 0 2 .2\n\
     void plastic w 0 0 5 .5 .5 .5 0 0\nw polygon f 0 0 12 -2 -2 0 2 -2 0 2 2 0 -2 2 0\n";

#[test]
fn special_files_in_a_job_never_block_or_get_read() {
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    std::fs::write(d.join("s.rad"), SCENE).unwrap();
    std::fs::write(d.join("outside.txt"), "{}").unwrap();
    // A finished job to damage.
    let base = d.join("base");
    let o = Command::new(bin("tplan"))
        .current_dir(d)
        .args(["--tiles", "4", "--workers", "1", "-o"])
        .arg(&base)
        .args([
            "--", "-vp", "0", "-5", "3", "-vd", "0", "1", "-.5", "-x", "32", "-y", "24", "-ab",
            "1", "s.rad",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (done, ok, err) = run(
        "tpiece",
        &[
            base.as_os_str(),
            "--threads".as_ref(),
            "1".as_ref(),
            "-q".as_ref(),
        ],
    );
    assert!(done && ok, "{err}");
    let (_, ok, err) = run("tmerge", &[base.as_os_str()]);
    assert!(ok, "{err}");
    let one = |dir: &Path, sub: &str, ext: &str| -> PathBuf {
        std::fs::read_dir(dir.join(sub))
            .unwrap()
            .map(|e| e.unwrap().path())
            .find(|p| p.extension().is_some_and(|e| e == ext))
            .unwrap()
    };
    // (what is replaced, how): each case in a fresh copy of the job.
    type Where<'a> = Box<dyn Fn(&Path) -> PathBuf + 'a>;
    let targets: Vec<(&str, Where)> = vec![
        ("manifest", Box::new(|j: &Path| j.join("manifest.json"))),
        ("heartbeat", Box::new(|j: &Path| one(j, "workers", "json"))),
        ("ambient log", Box::new(|j: &Path| one(j, "amb", "log"))),
        ("tile", Box::new(|j: &Path| one(j, "tiles", "tile"))),
        (
            "store index",
            Box::new(|j: &Path| j.join("merged/store.json")),
        ),
        ("scene", Box::new(|j: &Path| j.join("scene.rad"))),
    ];
    let mut n = 0;
    for (what, path_of) in &targets {
        for kind in ["fifo", "zero", "outside"] {
            n += 1;
            let job = d.join(format!("job{n}"));
            copy_dir(&base, &job);
            let p = path_of(&job);
            let _ = std::fs::remove_file(&p);
            match kind {
                "fifo" => mkfifo(&p),
                "zero" => std::os::unix::fs::symlink("/dev/zero", &p).unwrap(),
                _ => std::os::unix::fs::symlink(d.join("outside.txt"), &p).unwrap(),
            }
            let out = d.join(format!("out{n}.hdr"));
            for (tool, args) in tools_on(&job, &out) {
                let (done, ok, err) = run(tool, &args);
                assert!(done, "{tool} blocked on a {kind} as the {what}");
                assert!(!err.contains("panicked"), "{tool}, {kind} {what}: {err}");
                // The manifest and the tiles are needed: their tools fail, naming the file.
                if !ok {
                    assert!(
                        err.contains("error") && err.len() < 4000,
                        "{tool}, {kind} {what}: {err}"
                    );
                }
                if *what == "manifest" {
                    assert!(!ok, "{tool} accepted a {kind} manifest");
                    assert!(err.contains("manifest.json"), "{tool}: {err}");
                }
            }
        }
    }
}

/// Crafted heartbeats (issue 27 item 12): counters near 2^64 that would wrap the sums,
/// times of 1e300 or infinity, an owner that is not the file's name. tstat leaves each out
/// with a warning naming the file and why, and its sums stay those of the real workers.
#[test]
fn crafted_heartbeats_are_left_out() {
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    std::fs::write(d.join("s.rad"), SCENE).unwrap();
    let job = d.join("job");
    let o = Command::new(bin("tplan"))
        .current_dir(d)
        .args(["--tiles", "2", "-o"])
        .arg(&job)
        .args([
            "--", "-vp", "0", "-5", "3", "-vd", "0", "1", "-.5", "-x", "16", "-y", "12", "s.rad",
        ])
        .output()
        .unwrap();
    assert!(o.status.success());
    let (done, ok, err) = run("tpiece", &[job.as_os_str(), "-q".as_ref()]);
    assert!(done && ok, "{err}");
    let real = std::fs::read_dir(job.join("workers"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .next()
        .unwrap();
    let text = std::fs::read_to_string(&real).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let craft = |name: &str, f: &dyn Fn(&mut serde_json::Value)| {
        let mut w = v.clone();
        w["owner"] = serde_json::Value::String(name.to_string());
        f(&mut w);
        std::fs::write(
            job.join("workers").join(format!("{name}.json")),
            w.to_string(),
        )
        .unwrap();
    };
    craft("wrap", &|w| w["rays"] = serde_json::json!(u64::MAX - 5));
    craft("huge", &|w| w["cpu_seconds"] = serde_json::json!(1e300));
    craft("liar", &|w| w["owner"] = serde_json::json!("someone-else"));
    let o = Command::new(bin("tstat")).arg(&job).output().unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    let err = String::from_utf8_lossy(&o.stderr);
    let all = format!("{out}{err}");
    for name in ["wrap.json", "huge.json", "liar.json"] {
        assert!(all.contains(&format!("heartbeat {name}")), "{name}: {all}");
    }
    assert!(!all.contains("inf") && !all.contains("e300"), "{all}");
    let real_rays = v["rays"].as_u64().unwrap();
    assert!(all.contains(&format!("{real_rays} rays")), "{all}");
}

/// A FIFO (or a link to /dev/zero) in place of one of the job's folders never blocks a
/// tool: the folder handle a worker keeps to sync its renames is opened as a directory
/// (found by `bench/fuzz_special.sh`: `tiles/` as a FIFO blocked tpiece at its first tile).
#[test]
fn special_files_in_place_of_job_folders_never_block() {
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    std::fs::write(d.join("s.rad"), SCENE).unwrap();
    let mut n = 0;
    for folder in ["tiles", "tasks", "workers", "amb", "merged"] {
        for kind in ["fifo", "zero"] {
            n += 1;
            let job = d.join(format!("job{n}"));
            let o = Command::new(bin("tplan"))
                .current_dir(d)
                .args(["--tiles", "2", "-o"])
                .arg(&job)
                .args([
                    "--", "-vp", "0", "-5", "3", "-vd", "0", "1", "-.5", "-x", "16", "-y", "12",
                    "s.rad",
                ])
                .output()
                .unwrap();
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
            let p = job.join(folder);
            if p.exists() {
                std::fs::remove_dir_all(&p).unwrap();
            }
            match kind {
                "fifo" => mkfifo(&p),
                _ => std::os::unix::fs::symlink("/dev/zero", &p).unwrap(),
            }
            let out = d.join(format!("out{n}.hdr"));
            for (tool, args) in tools_on(&job, &out) {
                let (done, _, err) = run(tool, &args);
                assert!(done, "{tool} blocked on a {kind} as {folder}/");
                assert!(!err.contains("panicked"), "{tool}, {kind} {folder}: {err}");
            }
        }
    }
}
