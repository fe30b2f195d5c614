//! Memory bombs (issue 27 items 5, 6 and 7): what a small input can multiply is bounded
//! before it exhausts memory, and the error names the line that multiplied it.
//! - a scene that expands (generators, `xform` arrays, chains of files each arraying the
//!   previous) to more than `--max-primitives` primitives (default 2²²) is refused at the
//!   line that crossed the limit, and renders when the limit is raised;
//! - a `brighttext` of ten million one-letter lines renders within 800 MB of address space
//!   (its lines are packed; it took about 140 bytes a line before);
//! - a `tpiece` whose tile cannot fit in the memory its process may use (here `RLIMIT_AS`,
//!   as `ulimit -v` or a SLURM job's `--mem` would set) refuses it before rendering and
//!   hands the claim back.

use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn bin(name: &str) -> PathBuf {
    PathBuf::from(match name {
        "tplan" => env!("CARGO_BIN_EXE_tplan"),
        "tpiece" => env!("CARGO_BIN_EXE_tpiece"),
        _ => env!("CARGO_BIN_EXE_tpict"),
    })
}

/// A tool run in `dir` (RAYPATH=.), its address space limited to `limit` bytes if given.
fn run_in(dir: &Path, name: &str, args: &[&str], limit: Option<u64>) -> Output {
    let mut c = Command::new(bin(name));
    c.current_dir(dir).env("RAYPATH", ".").args(args);
    if let Some(bytes) = limit {
        // SAFETY: only setrlimit, which is async-signal-safe, runs between fork and exec.
        unsafe {
            c.pre_exec(move || {
                let r = libc::rlimit {
                    rlim_cur: bytes as libc::rlim_t,
                    rlim_max: bytes as libc::rlim_t,
                };
                if libc::setrlimit(libc::RLIMIT_AS, &r) != 0 {
                    return Err(std::io::Error::last_os_error());
                }
                Ok(())
            });
        }
    }
    c.output().unwrap()
}

const VIEW: [&str; 10] = ["-x", "8", "-y", "8", "-vp", "0", "-9", "0", "-vd", "0"];

fn tpict(dir: &Path, scene: &str, more: &[&str]) -> Output {
    let mut a: Vec<&str> = VIEW.to_vec();
    a.extend(["1", "0", "-o", "out.hdr"]);
    a.extend(more);
    a.push(scene);
    let _ = std::fs::remove_file(dir.join("out.hdr"));
    run_in(dir, "tpict", &a, None)
}

fn refused(o: &Output, want: &str) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(err.contains(want), "want '{want}' in: {err}");
}

#[test]
fn scenes_that_multiply_primitives_are_refused_at_the_line_that_did_it() {
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    let w = |name: &str, text: &str| std::fs::write(d.join(name), text).unwrap();
    w(
        "lamp.rad",
        "void light l 0 0 3 9 9 9\nl sphere sun 0 0 4 0 -5 5 .5\n",
    );
    let head = "void plastic m 0 0 5 .5 .5 .5 0 0\n# a comment\n";
    w("rev.rad", &format!("{head}!genrev m r 't' 1 2000\n"));
    w("worm.rad", &format!("{head}!genworm m w t 0 0 .1 3000\n"));
    w("surf.rad", &format!("{head}!gensurf m s t s 0 40 40\n"));
    w(
        "array.rad",
        &format!("{head}!genbox m b 1 1 1 | xform -a 600 -t 2 0 0\n"),
    );
    // Nine files, each an array of ten of the one before: 10⁹ spheres from 400 bytes.
    w("x0.rad", &format!("{head}m sphere s 0 0 4 0 0 0 .1\n"));
    for k in 1..=9 {
        w(
            &format!("x{k}.rad"),
            &format!("# level {k}\n!xform -a 10 -t .2 0 0 x{}.rad\n", k - 1),
        );
    }
    for (scene, want) in [
        (
            "rev.rad",
            "rev.rad:3: genrev makes more than 1000 primitives",
        ),
        ("worm.rad", "worm.rad:3: genworm makes more than 1000"),
        ("surf.rad", "surf.rad:3: gensurf makes more than 1000"),
        (
            "array.rad",
            "array.rad:3: the scene expands to more than 1000",
        ),
        ("x9.rad", "x3.rad:2: the scene expands to more than 1000"),
    ] {
        refused(&tpict(d, scene, &["--max-primitives", "1000"]), want);
        assert!(!d.join("out.hdr").exists(), "{scene}");
        // The same scene within a raised limit renders (the chain: its first levels).
        let ok = if scene == "x9.rad" { "x3.rad" } else { scene };
        let o = tpict(d, ok, &["--max-primitives", "100000", "lamp.rad"]);
        assert!(
            o.status.success(),
            "{ok}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
    // The default limit (2²²) stops the chain at level 7 (10⁷ spheres), in bounded memory.
    refused(
        &tpict(d, "x9.rad", &[]),
        "x7.rad:2: the scene expands to more than 4194304 primitives here",
    );
    // A bad limit is an option error.
    refused(
        &tpict(d, "x0.rad", &["--max-primitives", "0"]),
        "--max-primitives",
    );
}

#[test]
fn ten_million_lines_of_text_fit_in_little_memory() {
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    std::fs::write(
        d.join("block.fnt"),
        "32 0\n97 5 153 222 153 48 102 48 102 222 153 222\n",
    )
    .unwrap();
    std::fs::write(d.join("big.txt"), "a\n".repeat(10_000_000)).unwrap();
    std::fs::write(
        d.join("txt.rad"),
        "void brighttext tp 2 block.fnt big.txt 0 11 0 0 0 1 0 0 0 0 -1 1 0\n\
         tp plastic p 0 0 5 1 1 1 0 0\n\
         p polygon wall 0 0 12 0 0 0 1 0 0 1 0 -1 0 0 -1\n\
         void light l 0 0 3 1 1 1\n\
         l sphere sun 0 0 4 0 -5 5 .5\n",
    )
    .unwrap();
    let args = [
        "-vp", ".5", "-3", "-.5", "-vd", "0", "1", "0", "-x", "16", "-y", "16", "-n", "1", "-o",
        "out.hdr", "txt.rad",
    ];
    let o = run_in(d, "tpict", &args, Some(800 << 20));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let img = tessera::image::read_picture(&d.join("out.hdr")).unwrap();
    // The glyph of the first lines is lit; the background is not.
    assert!(img.pixels.iter().any(|p| p[0] > 0.0));
}

#[test]
fn a_tile_larger_than_the_memory_a_worker_may_use_is_handed_back() {
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    std::fs::write(
        d.join("s.rad"),
        "void plastic m 0 0 5 .5 .5 .5 0 0\nm sphere s 0 0 4 0 0 0 1\n\
         void light l 0 0 3 9 9 9\nl sphere sun 0 0 4 0 -5 5 .5\n",
    )
    .unwrap();
    // One tile of 16384² pixels: about 8 GiB to hold, against a 3 GiB address space.
    let o = run_in(
        d,
        "tplan",
        &[
            "-o", "job", "--tiles", "1", "--", "-vp", "0", "-9", "0", "-vd", "0", "1", "0", "-x",
            "16384", "-y", "16384", "-ab", "0", "s.rad",
        ],
        None,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = run_in(d, "tpiece", &["job", "--threads", "1"], Some(3 << 30));
    refused(&o, "plan the job with smaller tiles");
    let tasks: Vec<String> = std::fs::read_dir(d.join("job/tasks"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(
        tasks,
        ["f00000-t00000.todo"],
        "the claim was not handed back"
    );
}
