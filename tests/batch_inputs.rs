//! A job carries the files its scene reads by relative name (function files, data files,
//! pictures): `tplan` copies them into `JOB/files/`, so workers started anywhere, without a
//! RAYPATH, render the same picture as `tpict` in the scene's directory.

mod common;

use common::*;
use std::path::{Path, PathBuf};
use std::process::Command;
use tessera::image::read_picture;

fn scene_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scenes/patterns")
}

fn tool(name: &str, dir: &Path) -> Command {
    let exe = match name {
        "tplan" => env!("CARGO_BIN_EXE_tplan"),
        "tpiece" => env!("CARGO_BIN_EXE_tpiece"),
        "tassemble" => env!("CARGO_BIN_EXE_tassemble"),
        _ => env!("CARGO_BIN_EXE_tpict"),
    };
    let mut c = Command::new(exe);
    c.current_dir(dir)
        .env_remove("RAYPATH")
        .env_remove("SLURM_ARRAY_JOB_ID")
        .env_remove("SLURM_JOB_ID")
        .env_remove("SLURM_CPUS_PER_TASK");
    c
}

#[test]
fn jobs_carry_the_files_their_scene_reads() {
    let t = tempfile::tempdir().unwrap();
    let job = t.path().join("job");
    let args = [
        "-vf",
        "patterns.vf",
        "-x",
        "48",
        "-y",
        "40",
        "-ab",
        "0",
        "-ps",
        "1",
        "-av",
        ".05",
        ".05",
        ".05",
    ];
    for scene in ["patterns.rad", "datapat.rad"] {
        let _ = std::fs::remove_dir_all(&job);
        run_ok(
            tool("tplan", &scene_dir())
                .args(["--workers", "1", "-o"])
                .arg(&job)
                .arg("--")
                .args(args)
                .arg(scene),
        );
        let files = job.join("files");
        let wanted: &[&str] = if scene == "patterns.rad" {
            &["tiles.cal", "lum.dat"]
        } else {
            &["grad.dat", "bump.dat", "pic.hdr"]
        };
        for f in wanted {
            assert!(files.join(f).is_file(), "{f} not copied into the job");
        }
        // The worker runs elsewhere, without a RAYPATH.
        run_ok(
            tool("tpiece", t.path())
                .arg(&job)
                .args(["--threads", "1", "-q"]),
        );
        let out = t.path().join("job.hdr");
        let _ = std::fs::remove_file(&out);
        run_ok(tool("tassemble", t.path()).arg(&job).arg("-o").arg(&out));
        let reference = t.path().join("ref.hdr");
        let _ = std::fs::remove_file(&reference);
        run_ok(
            tool("tpict", &scene_dir())
                .args(["-n", "1"])
                .args(args)
                .arg("-o")
                .arg(&reference)
                .arg(scene),
        );
        let (a, b) = (
            read_picture(&out).unwrap(),
            read_picture(&reference).unwrap(),
        );
        assert_eq!(
            a.pixels, b.pixels,
            "{scene}: the job's picture differs from tpict's"
        );
    }
}

/// The job's fingerprint covers the copied files: a worker refuses a job whose function or
/// data file changed after planning, as it refuses a changed scene, since its ambient values
/// would mix with values computed from the old file.
#[test]
fn a_changed_job_file_is_refused() {
    let t = tempfile::tempdir().unwrap();
    let job = t.path().join("job");
    run_ok(
        tool("tplan", &scene_dir())
            .args(["--workers", "1", "-o"])
            .arg(&job)
            .arg("--")
            .args(["-vf", "patterns.vf", "-x", "16", "-y", "16", "-ab", "1"])
            .arg("datapat.rad"),
    );
    let data = job.join("files/grad.dat");
    let mut text = std::fs::read_to_string(&data).unwrap();
    text.push_str("\n# edited after planning\n");
    std::fs::write(&data, text).unwrap();
    let out = tool("tpiece", t.path())
        .arg(&job)
        .args(["--threads", "1", "-q"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "tpiece accepted a changed job file");
    assert!(err.contains("fingerprint"), "unclear error: {err}");
}

/// A file named with `..` (`../up.cal`) cannot travel with the job (a worker would look for
/// it outside the job's folders): tplan refuses it, naming the file, and makes no job.
#[test]
fn names_that_climb_out_of_the_job_are_refused() {
    let t = tempfile::tempdir().unwrap();
    let d = t.path().join("scene");
    std::fs::create_dir_all(&d).unwrap();
    std::fs::write(t.path().join("up.cal"), "up = 1;\n").unwrap();
    std::fs::write(
        d.join("s.rad"),
        "void brightfunc b 2 up ../up.cal 0 0\n\
         b light l 0 0 3 1 1 1\n\
         l sphere s 0 0 4 0 0 0 1\n",
    )
    .unwrap();
    let o = tool("tplan", &d)
        .env("RAYPATH", ".")
        .args([
            "--tiles", "1", "-o", "job", "--", "-x", "8", "-y", "8", "s.rad",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    assert!(err.contains("../up.cal") && err.contains("'..'"), "{err}");
    assert!(!d.join("job").exists());
}
