//! Animations: ambient accuracy that varies with time (`-ax`, `-axg`, the seed paper's
//! §4.1) spreads the ambient calculation over the first frames of a job and ends at the
//! final accuracy; per-frame costs are reported by `tstat`.

mod common;

use common::*;
use std::path::{Path, PathBuf};
use std::process::Command;

fn demo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("demo")
}

fn tool(name: &str) -> Command {
    let exe = match name {
        "tplan" => env!("CARGO_BIN_EXE_tplan"),
        "tpiece" => env!("CARGO_BIN_EXE_tpiece"),
        "tstat" => env!("CARGO_BIN_EXE_tstat"),
        _ => env!("CARGO_BIN_EXE_tassemble"),
    };
    let mut c = Command::new(exe);
    c.current_dir(demo())
        .env_remove("SLURM_ARRAY_JOB_ID")
        .env_remove("SLURM_JOB_ID")
        .env_remove("SLURM_CPUS_PER_TASK");
    c
}

/// A views file in `dir` holding the demo's view `n` times (a job of `n` still frames).
fn still_views(dir: &Path, n: usize) -> PathBuf {
    let vf = dir.join("frames.vf");
    let line = std::fs::read_to_string(demo().join("demo.vf")).unwrap();
    std::fs::write(&vf, format!("{}\n", line.trim()).repeat(n)).unwrap();
    vf
}

/// Plan a job for one worker at `job` (`plan`: tplan's frame arguments; `opts`: the render
/// options and scene after `--`), render it with one single-thread worker and return
/// `tstat --json`'s per-frame records.
fn run_job(job: &Path, plan: &[&std::ffi::OsStr], opts: &[&str]) -> Vec<serde_json::Value> {
    run_ok(
        tool("tplan")
            .args(["--workers", "1"])
            .args(plan)
            .arg("-o")
            .arg(job)
            .arg("--")
            .args(opts),
    );
    run_ok(tool("tpiece").arg(job).args(["--threads", "1", "-q"]));
    let out = run_ok(tool("tstat").arg(job).arg("--json"));
    let v: serde_json::Value = serde_json::from_slice(&out).unwrap();
    v["frames"].as_array().unwrap().clone()
}

/// `--frames FILE` as tplan arguments.
fn frames_arg(vf: &Path) -> [&std::ffi::OsStr; 2] {
    ["--frames".as_ref(), vf.as_os_str()]
}

/// New ambient values per frame of a job of `frames` identical views with `accuracy`.
fn values_per_frame(dir: &Path, frames: usize, accuracy: &[&str]) -> Vec<u64> {
    let vf = still_views(dir, frames);
    let job = dir.join(format!("job{}", accuracy.join("_")));
    let mut opts = vec!["-vf", "demo.vf", "-x", "64", "-y", "48", "-ab", "1"];
    opts.extend_from_slice(accuracy);
    opts.push("demo.rad");
    run_job(&job, &frames_arg(&vf), &opts)
        .iter()
        .map(|f| f["new_values"].as_u64().unwrap())
        .collect()
}

#[test]
fn time_varying_accuracy_spreads_the_first_frames_cost() {
    let t = tempfile::tempdir().unwrap();
    let constant = values_per_frame(t.path(), 5, &["-aa", ".1"]);
    let varying = values_per_frame(t.path(), 5, &["-ax", ".5", ".1", ".1"]);
    eprintln!("new values per frame: -aa .1 {constant:?}, -ax .5 .1 .1 {varying:?}");
    assert!(constant[0] > 0);
    // Frame 0 at -aa .5 makes far fewer values than at .1 (about (.1/.5)² as many).
    assert!(
        varying[0] * 3 < constant[0],
        "-ax: {varying:?} vs -aa: {constant:?}"
    );
    // The peak is lower and the whole animation makes fewer values.
    let peak = |v: &[u64]| *v.iter().max().unwrap();
    assert!(peak(&varying) < peak(&constant));
    assert!(varying.iter().sum::<u64>() < constant.iter().sum::<u64>());
}

#[test]
fn ax_options_are_checked_and_recorded() {
    let t = tempfile::tempdir().unwrap();
    // A tightening schedule only; a ratio below 1.
    for bad in [
        &["-ax", ".1", ".5", ".1"][..],
        &["-ax", ".5", "0", ".1"],
        &["-axg", ".5", ".1", "2"],
    ] {
        let out = Command::new(tpict_bin())
            .current_dir(demo())
            .args(["-vf", "demo.vf", "-x", "8", "-y", "8", "-ab", "1"])
            .args(bad)
            .arg("demo.rad")
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{bad:?} accepted");
        assert!(err.contains(bad[0]), "{bad:?}: {err}");
    }
    // The schedule is in the picture header (with the other options) and in the
    // manifest's fingerprint: a job planned with -ax differs from one without.
    let pic = t.path().join("p.hdr");
    run_ok(
        Command::new(tpict_bin())
            .current_dir(demo())
            .args(["-vf", "demo.vf", "-x", "8", "-y", "8", "-ab", "1"])
            .args(["-axg", ".4", ".1", ".5", "-o"])
            .arg(&pic)
            .arg("demo.rad"),
    );
    let bytes = std::fs::read(&pic).unwrap();
    let header = String::from_utf8_lossy(&bytes[..bytes.len().min(4000)]).to_string();
    assert!(header.contains("-axg .4 .1 .5"), "{header}");
    let fp = |args: &[&str]| {
        let job = t.path().join(format!("j{}", args.len()));
        run_ok(
            tool("tplan")
                .args(["--workers", "1", "-o"])
                .arg(&job)
                .arg("--")
                .args(["-vf", "demo.vf", "-x", "8", "-y", "8", "-ab", "1"])
                .args(args)
                .arg("demo.rad"),
        );
        let m: serde_json::Value =
            serde_json::from_slice(&std::fs::read(job.join("manifest.json")).unwrap()).unwrap();
        m["fingerprint"].as_str().unwrap().to_string()
    };
    assert_ne!(fp(&[]), fp(&["-ax", ".4", ".2", ".1"]));
}

/// `--same-seeds`: frames of a static view sample every pixel as the first frame did, so
/// at `-ab 0` (no cache) they are identical; with per-frame seeds (rpict's way) they differ.
#[test]
fn same_seeds_keep_static_frames_still() {
    let t = tempfile::tempdir().unwrap();
    let vf = still_views(t.path(), 3);
    let frames = |extra: &[&str]| {
        let job = t.path().join(format!("job{}", extra.len()));
        let mut opts = vec!["-vf", "demo.vf", "-x", "32", "-y", "24", "-ab", "0"];
        opts.extend_from_slice(extra);
        opts.push("demo.rad");
        run_job(&job, &frames_arg(&vf), &opts);
        (0..3)
            .map(|k| {
                let out = t.path().join(format!("f{}-{k}.hdr", extra.len()));
                run_ok(
                    tool("tassemble")
                        .arg(&job)
                        .args(["--frame", &k.to_string(), "-o"])
                        .arg(&out),
                );
                tessera::image::read_picture(&out).unwrap().pixels
            })
            .collect::<Vec<_>>()
    };
    let per_frame = frames(&[]);
    assert_ne!(per_frame[0], per_frame[1], "per-frame seeds should differ");
    let same = frames(&["--same-seeds"]);
    assert_eq!(same[0], same[1]);
    assert_eq!(same[0], same[2]);
}

/// A keyframed path makes its frames (ends on the keys), and tassemble makes a contact
/// sheet of them and PNG frames with a smoothed exposure.
#[test]
fn keyframed_paths_and_previews() {
    let t = tempfile::tempdir().unwrap();
    let keys = t.path().join("keys.vf");
    std::fs::write(
        &keys,
        "-vtv -vp 7.6 .35 2.1 -vd -5.2 4.6 -1.5 -vu 0 0 1 -vh 80 -vv 60\n\
         # a comment line\n\
         rview -vp 6.2 2.4 1.7 -vd -1 .25 -.25\n\
         VIEW= -vp 4.6 4.6 1.7 -vd -.7 -1 -.2\n",
    )
    .unwrap();
    let job = t.path().join("job");
    run_ok(
        tool("tplan")
            .args(["--workers", "1", "--path"])
            .arg(&keys)
            .args(["--path-frames", "5", "-o"])
            .arg(&job)
            .arg("--")
            .args(["-x", "40", "-y", "30", "-ab", "0", "demo.rad"]),
    );
    let m: serde_json::Value =
        serde_json::from_slice(&std::fs::read(job.join("manifest.json")).unwrap()).unwrap();
    let frames = m["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 5);
    let vp = |k: usize| frames[k]["view"]["vp"].clone();
    assert_eq!(vp(0), serde_json::json!([7.6, 0.35, 2.1]));
    assert_eq!(vp(2), serde_json::json!([6.2, 2.4, 1.7]));
    assert_eq!(vp(4), serde_json::json!([4.6, 4.6, 1.7]));
    run_ok(tool("tpiece").arg(&job).args(["--threads", "1", "-q"]));
    let sheet = t.path().join("sheet.png");
    let pattern = t.path().join("f%d.png");
    run_ok(
        tool("tassemble")
            .arg(&job)
            .args(["--all-frames", "--temporal-exposure", "--thumb-width", "20"])
            .arg("--contact-sheet")
            .arg(&sheet)
            .arg("-o")
            .arg(&pattern),
    );
    let s = image::open(&sheet).unwrap();
    // 5 thumbnails 20 pixels across on a 3×2 grid with 2-pixel gaps.
    let (w, h) = (
        frames[0]["xres"].as_u64().unwrap() as f64,
        frames[0]["yres"].as_u64().unwrap() as f64,
    );
    let th = (h * 20.0 / w).round() as u32;
    assert_eq!((s.width(), s.height()), (3 * 22 - 2, 2 * (th + 2) - 2));
    for k in 0..5 {
        assert!(t.path().join(format!("f{k}.png")).is_file());
    }
    // Bad path inputs are refused with a reason.
    std::fs::write(&keys, "-vp 1 1 1\n").unwrap();
    let out = tool("tplan")
        .args(["--path"])
        .arg(&keys)
        .args(["--path-frames", "5", "-o"])
        .arg(t.path().join("job2"))
        .args(["--", "demo.rad"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("at least two key views"));
    // A billion frames is refused before any view is made (it took 13.7 GB and rising).
    std::fs::write(
        &keys,
        "-vp 1 1 1 -vd 0 1 0
-vp 2 1 1
",
    )
    .unwrap();
    let out = tool("tplan")
        .args(["--path"])
        .arg(&keys)
        .args(["--path-frames", "1000000000", "-o"])
        .arg(t.path().join("job3"))
        .args(["--", "demo.rad"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("at most 99999 frames"), "{err}");
}

/// `-axm`: where the camera turns away, tiles whose surfaces leave the view render at a
/// relaxed accuracy (fewer new values); `tpict` refuses the option.
#[test]
fn moving_direction_accuracy_relaxes_what_leaves_the_view() {
    let t = tempfile::tempdir().unwrap();
    let keys = t.path().join("keys.vf");
    // A half turn: most of what a frame sees is out of view two frames later.
    std::fs::write(
        &keys,
        "-vtv -vp 4 3 1.6 -vd -1 0 0 -vu 0 0 1 -vh 50 -vv 40\n-vd 0 1 0\n-vd 1 0 0\n",
    )
    .unwrap();
    let values = |extra: &[&str]| -> u64 {
        let job = t.path().join(format!("job{}", extra.len()));
        let mut opts = vec!["-x", "48", "-y", "36", "-ab", "1", "-aa", ".1"];
        opts.extend_from_slice(extra);
        opts.push("demo.rad");
        let plan = [
            "--path".as_ref(),
            keys.as_os_str(),
            "--path-frames".as_ref(),
            "9".as_ref(),
        ];
        run_job(&job, &plan, &opts)
            .iter()
            .map(|f| f["new_values"].as_u64().unwrap())
            .sum()
    };
    let (full, relaxed) = (values(&[]), values(&["-axm", "3", "2"]));
    eprintln!("new values: constant {full}, -axm 3 2 {relaxed}");
    assert!(relaxed * 10 < full * 9, "{relaxed} vs {full}");
    let out = Command::new(tpict_bin())
        .current_dir(demo())
        .args([
            "-vf", "demo.vf", "-x", "8", "-y", "8", "-ab", "1", "-axm", "2", "3",
        ])
        .arg("demo.rad")
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("-axm"));
}

/// `-axt`: tpict's view sequences choose each frame's `-aa` from the previous frame's cost
/// (recorded as `TESSERA_FRAME_AA=` in each picture), and the accuracy takes effect: an
/// impossible budget keeps the loosest accuracy and makes far fewer values.
#[test]
fn time_budget_picks_each_frames_accuracy() {
    let t = tempfile::tempdir().unwrap();
    let line = std::fs::read_to_string(demo().join("demo.vf")).unwrap();
    let run = |budget: &str, tag: &str| -> (Vec<String>, u64) {
        let pattern = t.path().join(format!("{tag}%d.hdr"));
        let stats = t.path().join(format!("{tag}.json"));
        let mut child = Command::new(tpict_bin())
            .current_dir(demo())
            .args(["-S", "1", "-o"])
            .arg(&pattern)
            .arg("--stats")
            .arg(&stats)
            .args(["-vf", "demo.vf", "-x", "32", "-y", "24", "-ab", "1"])
            // -aa below START: the cache must file values for START all the same.
            .args(["-aa", ".1", "-axt", budget, ".4", ".1", "demo.rad"])
            .stdin(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        use std::io::Write;
        let input = format!("{}\n", line.trim()).repeat(3);
        child
            .stdin
            .take()
            .unwrap()
            .write_all(input.as_bytes())
            .unwrap();
        assert!(child.wait().unwrap().success());
        let aa = (1..=3)
            .map(|k| frame_aa_header(&t.path().join(format!("{tag}{k}.hdr"))))
            .collect();
        let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&stats).unwrap()).unwrap();
        let cached = v["ambient"]["cached_values"].as_u64().unwrap_or_else(|| {
            panic!("no ambient.cached_values in {v}");
        });
        (aa, cached)
    };
    // A generous budget tightens to the end accuracy after the first frame; an impossible
    // one keeps the loosest.
    let (easy, easy_values) = run("1000", "easy");
    let (hard, hard_values) = run("0.000001", "hard");
    assert_eq!(easy, ["0.4", "0.1", "0.1"]);
    assert_eq!(hard, ["0.4", "0.4", "0.4"]);
    assert!(
        (hard_values as f64) < 0.7 * easy_values as f64,
        "values at -aa .4: {hard_values}, tightened to .1: {easy_values}"
    );
}

/// The `TESSERA_FRAME_AA=` value of a picture's header ("none" without one).
fn frame_aa_header(path: &Path) -> String {
    let bytes = std::fs::read(path).unwrap();
    let text = String::from_utf8_lossy(&bytes[..bytes.len().min(4000)]).to_string();
    text.lines()
        .find_map(|l| l.strip_prefix("TESSERA_FRAME_AA="))
        .unwrap_or("none")
        .trim()
        .to_string()
}

/// `-axt` in a job: each frame's `-aa` is decided once from the latest finished frame's CPU
/// time (recorded in `JOB/budget/`), reported by tstat, written in the assembled headers,
/// and taken by every tile; `-axt` with `-ax` is refused.
#[test]
fn time_budget_in_jobs() {
    let t = tempfile::tempdir().unwrap();
    let vf = still_views(t.path(), 3);
    let job_run = |budget: &str, tag: &str| -> (Vec<f64>, Vec<u64>, PathBuf) {
        let job = t.path().join(tag);
        let opts = [
            "-vf", "demo.vf", "-x", "32", "-y", "24", "-ab", "1", "-aa", ".1", "-axt", budget,
            ".4", ".1", "demo.rad",
        ];
        let frames = run_job(&job, &frames_arg(&vf), &opts);
        let aa = frames.iter().map(|f| f["aa"].as_f64().unwrap()).collect();
        let values = frames
            .iter()
            .map(|f| f["new_values"].as_u64().unwrap())
            .collect();
        (aa, values, job)
    };
    let (easy, easy_values, job) = job_run("1000", "easy");
    assert_eq!(easy, [0.4, 0.1, 0.1]);
    let (hard, hard_values, _) = job_run("0.000001", "hard");
    assert_eq!(hard, [0.4, 0.4, 0.4]);
    // Frame 1 tightens from .4 to .1 with a generous budget: it makes many more values.
    assert!(
        hard_values[1] * 2 < easy_values[1],
        "values: hard {hard_values:?} easy {easy_values:?}"
    );
    let record: serde_json::Value =
        serde_json::from_slice(&std::fs::read(job.join("budget/f00001.json")).unwrap()).unwrap();
    assert_eq!(record["from_frame"].as_u64(), Some(0));
    assert!(record["from_cpu_seconds"].as_f64().unwrap() > 0.0);
    let pic = t.path().join("f1.hdr");
    run_ok(
        tool("tassemble")
            .arg(&job)
            .args(["--frame", "1", "-o"])
            .arg(&pic),
    );
    assert_eq!(frame_aa_header(&pic), "0.1");
    // A damaged record stops the worker with the file's name rather than being replaced.
    std::fs::write(job.join("budget/f00002.json"), b"{\"frame\": 2, \"aa\": 7}").unwrap();
    let out = tool("tstat").arg(&job).output().unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("f00002.json"));
    let out = tool("tplan")
        .args(["-o"])
        .arg(t.path().join("both"))
        .args([
            "--", "-vf", "demo.vf", "-ab", "1", "-axt", "1", ".4", ".1", "-ax", ".4", ".1", ".1",
            "demo.rad",
        ])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("-axt"));
    // -ax and -axg together: refused too (a repeated -ax still replaces the earlier one).
    let both = |a: &str, b: &str| {
        tool("tplan")
            .args(["-o"])
            .arg(t.path().join(format!("both{a}{b}")))
            .args([
                "--", "-vf", "demo.vf", "-ab", "1", a, ".4", ".1", ".1", b, ".4", ".1", ".5",
                "demo.rad",
            ])
            .output()
            .unwrap()
    };
    let out = both("-ax", "-axg");
    assert!(!out.status.success());
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("-ax and -axg"),
        "{out:?}"
    );
    assert!(both("-ax", "-ax").status.success());
}

/// Workers take tiles frame by frame: every tile of a frame before any of the next.
#[test]
fn tiles_are_claimed_in_frame_order() {
    let t = tempfile::tempdir().unwrap();
    let vf = still_views(t.path(), 3);
    let job = t.path().join("job");
    run_ok(
        tool("tplan")
            .args(["--workers", "2", "--tiles", "6", "--frames"])
            .arg(&vf)
            .arg("-o")
            .arg(&job)
            .arg("--")
            .args([
                "-vf", "demo.vf", "-x", "24", "-y", "18", "-ab", "0", "demo.rad",
            ]),
    );
    let out = tool("tpiece")
        .arg(&job)
        .args(["--threads", "1"])
        .output()
        .unwrap();
    assert!(out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    let frames: Vec<u32> = err
        .split_whitespace()
        .filter_map(|w| w.strip_prefix('f'))
        .filter_map(|w| w.split_once("-t"))
        .filter_map(|(f, _)| f.parse().ok())
        .collect();
    assert!(frames.len() > 6, "no tile reports: {err}");
    assert!(frames.windows(2).all(|w| w[0] <= w[1]), "order: {frames:?}");
    assert_eq!(frames.last(), Some(&2));
}

/// `Session::share_still_seen` on a known camera move: the same view sees everything again,
/// a view turned away sees nothing of it, a view half turned sees part of it.
#[test]
fn reprojection_on_a_known_camera_move() {
    use tessera::options::RenderParams;
    use tessera::scene::ReadOptions;
    use tessera::session::{Region, SceneSource, Session};
    use tessera::view::View;
    let t = tempfile::tempdir().unwrap();
    let scene = t.path().join("box.rad");
    // A closed box 10 on a side around the origin, the camera at its centre.
    std::fs::write(
        &scene,
        "void plastic w 0 0 5 .5 .5 .5 0 0\n!genbox w b 10 10 10 -i | xform -t -5 -5 -5\n",
    )
    .unwrap();
    let params = RenderParams::default();
    let ro = ReadOptions {
        allow_commands: false,
        raypath: vec![t.path().to_path_buf()],
        ..ReadOptions::default()
    };
    let src = SceneSource::read(&[scene.display().to_string()], &ro, &params).unwrap();
    let session = Session::start(params, src, Some(1)).unwrap();
    let view = |d: [f64; 3]| {
        View {
            vp: glam::DVec3::ZERO,
            vd: glam::DVec3::from_array(d),
            vh: 40.0,
            vv: 40.0,
            ..View::default()
        }
        .frame()
        .unwrap()
    };
    let now = view([1.0, 0.0, 0.0]);
    let all = Region {
        x0: 0,
        y0: 0,
        x1: 64,
        y1: 64,
    };
    let share = |later: &tessera::view::ViewFrame, r: Region| {
        session.share_still_seen(&now, (64, 64), r, later)
    };
    assert_eq!(share(&now, all), 1.0);
    assert_eq!(share(&view([-1.0, 0.0, 0.0]), all), 0.0);
    assert_eq!(share(&view([0.0, 1.0, 0.0]), all), 0.0);
    // Turned 20° to the left (+y): the left part of the picture stays in view, the right
    // part leaves it.
    let half = view([1.0, 20f64.to_radians().tan(), 0.0]);
    let left = Region { x1: 32, ..all };
    let right = Region { x0: 32, ..all };
    assert_eq!(share(&half, left), 1.0);
    assert_eq!(share(&half, right), 0.0);
}
