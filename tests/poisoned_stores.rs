//! A job directory is shared by many users' processes: a log in `JOB/amb/` with the job's
//! fingerprint and valid CRCs may still hold records no renderer makes (crafted or damaged).
//! Workers and `tmerge` skip such records: before they were validated, infinite radii made a
//! worker allocate without bound, NaN values gave black pixels and 3e38 values pixels of
//! 1.8e37.

mod common;

use common::run_ok;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};
use tessera::ambient::log::{encode_log, LogReader};
use tessera::ambient::AmbRecord;
use tessera::image::read_picture;

fn bin(name: &str) -> PathBuf {
    match name {
        "tplan" => PathBuf::from(env!("CARGO_BIN_EXE_tplan")),
        "tpiece" => PathBuf::from(env!("CARGO_BIN_EXE_tpiece")),
        "tmerge" => PathBuf::from(env!("CARGO_BIN_EXE_tmerge")),
        "tassemble" => PathBuf::from(env!("CARGO_BIN_EXE_tassemble")),
        "tstat" => PathBuf::from(env!("CARGO_BIN_EXE_tstat")),
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

fn plan(job: &Path) {
    run_ok(
        cmd("tplan")
            .args(["--workers", "1", "-o"])
            .arg(job)
            .arg("--")
            .args(["-vf"])
            .arg(demo().join("demo.vf"))
            .args(["-x", "48", "-y", "36", "-ab", "1", "-aa", ".2", "-ad", "64"])
            .args(["-as", "0", "-ps", "1"])
            .arg(demo().join("demo.rad")),
    );
}

/// Run one worker on `job`; it must finish within two minutes (a worker that allocates
/// without bound never does) and succeed.
fn work(job: &Path) -> String {
    let mut child = cmd("tpiece")
        .arg(job)
        .args(["--worker-id", "w-new", "--threads", "1", "-q", "--no-wait"])
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    loop {
        if child.try_wait().unwrap().is_some() {
            break;
        }
        if start.elapsed() > Duration::from_secs(120) {
            let _ = child.kill();
            panic!("the worker did not finish within 2 minutes");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{err}");
    err
}

/// The records of the one log a worker wrote into `job`, and that log's header bytes' owner.
fn worker_log(job: &Path) -> (tessera::ambient::log::LogHeader, Vec<AmbRecord>) {
    let log = std::fs::read_dir(job.join("amb"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|x| x == "log"))
        .expect("a worker log");
    let mut r = LogReader::open(&log, None, false).unwrap();
    let recs = r.read_new().unwrap();
    (r.header().clone(), recs)
}

/// A change that poisons a record.
type Poison = fn(&mut AmbRecord);

#[test]
fn poisoned_logs_are_skipped_by_workers_and_tmerge() {
    let d = tempfile::tempdir().unwrap();
    let first = d.path().join("first");
    plan(&first);
    work(&first);
    let (header, records) = worker_log(&first);
    assert!(records.len() > 20);
    let poisons: [(&str, Poison); 4] = [
        ("infinite radii", |r| r.rad = [f32::INFINITY; 2]),
        ("NaN light", |r| r.val = [f32::NAN; 3]),
        ("3e38 light", |r| r.val = [3e38; 3]),
        ("huge radii", |r| r.rad = [1e9, 1e9]),
    ];
    for (what, poison) in poisons {
        let job = d.path().join(what.replace(' ', "-"));
        plan(&job);
        let bad: Vec<AmbRecord> = records
            .iter()
            .map(|r| {
                let mut b = *r;
                b.id.origin ^= 0xBAD_F00D;
                poison(&mut b);
                b
            })
            .collect();
        std::fs::write(job.join("amb/crafted.log"), encode_log(&header, &bad)).unwrap();
        let err = work(&job);
        // Skipped records are counted: a warning and tstat's aggregate.
        if what != "huge radii" {
            assert!(err.contains("invalid records skipped"), "{what}: {err}");
        }
        let st: serde_json::Value =
            serde_json::from_slice(&run_ok(cmd("tstat").arg(&job).arg("--json"))).unwrap();
        let rejected = st["aggregate"]["rejected"].as_u64().unwrap();
        assert_eq!(rejected, bad.len() as u64, "{what}");
        let text = String::from_utf8(run_ok(cmd("tstat").arg(&job))).unwrap();
        assert!(text.contains("invalid ambient records skipped"), "{text}");
        let out = job.join("out.hdr");
        run_ok(cmd("tassemble").arg(&job).arg("-o").arg(&out));
        let img = read_picture(&out).unwrap();
        let max = img
            .pixels
            .iter()
            .flat_map(|p| p.iter())
            .fold(0f32, |m, &v| {
                if v.is_finite() {
                    m.max(v)
                } else {
                    f32::INFINITY
                }
            });
        let black = img
            .pixels
            .iter()
            .filter(|p| p.iter().all(|&v| v == 0.0))
            .count();
        eprintln!("{what}: brightest pixel {max}, {black} black pixels");
        assert!(max.is_finite() && max < 1e3, "{what}: pixel {max}");
        assert!(
            black * 20 < img.pixels.len(),
            "{what}: {black} black pixels"
        );
        // tmerge's store holds the worker's own values only.
        run_ok(cmd("tmerge").arg(&job));
        let idx: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(job.join("merged/store.json")).unwrap())
                .unwrap();
        let (_, own) = worker_log_named(&job, "w-new");
        let merged = idx["records"].as_u64().unwrap();
        // Huge (finite, valid-looking) radii pass the record check and are refused only by
        // the renderer's cache; the store keeps them.
        let expected = if what == "huge radii" {
            own + bad.len() as u64
        } else {
            own
        };
        assert_eq!(merged, expected, "{what}");
    }
}

/// The number of records in the log of worker `id` in `job`.
fn worker_log_named(job: &Path, id: &str) -> ((), u64) {
    let path = std::fs::read_dir(job.join("amb"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| {
            p.file_name()
                .is_some_and(|n| n.to_string_lossy().contains(id))
        })
        .expect("the worker's log");
    let mut r = LogReader::open(&path, None, false).unwrap();
    ((), r.read_new().unwrap().len() as u64)
}
