//! `rad` input files: `tplan --rif FILE --print` prints the rpict options real `rad -n`
//! derives (compared word for word over a sweep of rif files), a job made from a rif file
//! renders its views as frames, and bad rif files fail with file:line.

mod common;

use common::*;
use std::path::Path;
use std::process::Command;

const ROOM: &str = "void plastic white 0 0 5 .6 .6 .6 0 0
white polygon floor 0 0 12 0 0 0 0 5 0 4 5 0 4 0 0
white polygon ceiling 0 0 12 0 0 3 4 0 3 4 5 3 0 5 3
white polygon wall1 0 0 12 0 0 0 4 0 0 4 0 3 0 0 3
white polygon wall2 0 0 12 0 5 0 0 5 3 4 5 3 4 5 0
white polygon wall3 0 0 12 0 0 0 0 0 3 0 5 3 0 5 0
white polygon wall4 0 0 12 4 0 0 4 5 0 4 5 3 4 0 3
void light bright 0 0 3 10 10 10
bright sphere lamp 0 0 4 2 2.5 2.7 .1
";

fn tplan(dir: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_tplan"));
    c.current_dir(dir).env_remove("RAYPATH");
    c
}

/// rad's rpict lines for `rif` (the overture lines to /dev/null left out), options only.
fn rad_lines(bin: &Path, dir: &Path, rif: &str) -> Vec<String> {
    let out = run_ok(radiance(bin, "rad").current_dir(dir).args(["-n", rif]));
    String::from_utf8_lossy(&out)
        .lines()
        .filter_map(|l| l.trim().strip_prefix("rpict "))
        .filter(|l| !l.ends_with("/dev/null"))
        .map(|l| {
            let w: Vec<&str> = l.split_whitespace().collect();
            w[..w.len() - 3].join(" ")
        })
        .collect()
}

fn ours(dir: &Path, rif: &str) -> Vec<String> {
    let out = run_ok(tplan(dir).args(["--rif", rif, "--print"]));
    String::from_utf8_lossy(&out)
        .lines()
        .map(str::to_string)
        .collect()
}

/// Over a sweep of rif files (every QUALITY × DETAIL × VARIABILITY × PENUMBRAS, with
/// zones, exposures, resolutions, UP directions, standard, labelled and unnamed views,
/// REPORT, AMBFILE, render and rpict varied along), tplan prints what rad prints.
#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn rpict_options_equal_rads() {
    let Some(bin) = radiance_bin() else { return };
    let t = tempfile::tempdir().unwrap();
    std::fs::write(t.path().join("room.rad"), ROOM).unwrap();
    let zones = [
        "",
        "ZONE= I 0 4 0 5 0 3",
        "ZONE= Exterior -10 10 -10 10 0 5",
        "ZONE= int 0 4 0 5 0 3",
    ];
    let exposures = [
        "",
        "EXPOSURE= +1",
        "EXPOSURE= 0.5",
        "EXPOSURE= -2",
        "EXP= 3",
    ];
    let resolutions = [
        "",
        "RESOLUTION= 640 480",
        "RES= 300",
        "RESOLUTION= 640 480 1.2",
    ];
    let ups = ["", "UP= Z", "UP= -Y", "UP= X", "UP= +y"];
    let views = [
        "view= X",
        "view= xZ\nview= zl",
        "view= nw -vp 0.5 4.5 1.6 -vd 1 -1 0 -vh 60 -vv 45",
        "view= XYZh\nview= -vp 1 1 1 -vd 0 1 0\nview= xyc",
        "",
        "view= Za -vu 0 1 0\nview= Ys",
    ];
    let extras = [
        "",
        "REPORT= 2 c.err",
        "AMBFILE= x.amb\nrender= -dj .5",
        "rpict= -lr 4",
        "INDIRECT= 2",
        "REPORT= 3\nINDIRECT= 1",
        "OPTFILE= o.opt\nrender= -dj .5 -av 1 1 1\nAMBFILE= o.amb",
    ];
    let levels = ["L", "M", "H"];
    let mut n = 0;
    let mut cases = 0;
    for q in levels {
        for d in levels {
            for v in levels {
                for pen in ["PENUMBRAS= T", "PENUMBRAS= False"] {
                    let pick = |len: usize, k: usize| (n * (k + 3) + n / 7) % len;
                    let rif = format!(
                        "# sweep {n}\nscene= room.rad\nQUALITY= {q}\nDETAIL= {d}\nVARIABILITY= {v}\n{pen}\n{}\n{}\n{}\n{}\n{}\n{}\n",
                        zones[pick(zones.len(), 0)],
                        exposures[pick(exposures.len(), 1)],
                        resolutions[pick(resolutions.len(), 2)],
                        ups[pick(ups.len(), 3)],
                        views[pick(views.len(), 4)],
                        extras[pick(extras.len(), 5)],
                    );
                    let name = format!("s{n}.rif");
                    std::fs::write(t.path().join(&name), &rif).unwrap();
                    let want = rad_lines(&bin, t.path(), &name);
                    let rad_opt = std::fs::read_to_string(t.path().join("o.opt")).ok();
                    let _ = std::fs::remove_file(t.path().join("o.opt"));
                    let got = ours(t.path(), &name);
                    let our_opt = std::fs::read_to_string(t.path().join("o.opt")).ok();
                    let _ = std::fs::remove_file(t.path().join("o.opt"));
                    assert_eq!(our_opt, rad_opt, "OPTFILE of\n{rif}");
                    assert!(!want.is_empty(), "rad printed no rpict line for\n{rif}");
                    assert_eq!(got, want, "rif file:\n{rif}");
                    cases += want.len();
                    n += 1;
                }
            }
        }
    }
    eprintln!("rif: {n} files, {cases} rpict lines equal to rad -n's");
}

/// A rif file with two views makes a job of two frames with rad's options; the views
/// render as tpict renders them with the printed options.
#[test]
fn a_rif_job_renders_its_views_as_frames() {
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    std::fs::write(d.join("room.rad"), ROOM).unwrap();
    std::fs::write(
        d.join("p.rif"),
        "scene= room.rad\nZONE= I 0 4 0 5 0 3\nRESOLUTION= 24 16\nAMBFILE= p.amb\nview= X\nview= corner -vp .5 .5 1.5 -vd 1 1 0\n",
    )
    .unwrap();
    let lines = ours(d, "p.rif");
    assert_eq!(lines.len(), 2);
    let render_job = |job: &Path, extra: &[&str]| -> Vec<tessera::image::Image> {
        run_ok(
            tplan(d)
                .args(["--rif", "p.rif", "--workers", "1"])
                .args(extra)
                .arg("-o")
                .arg(job),
        );
        run_ok(
            Command::new(env!("CARGO_BIN_EXE_tpiece"))
                .current_dir(d)
                .arg(job)
                .args(["--threads", "1", "-q"]),
        );
        let out = job.with_extension("hdr");
        let mut pics = Vec::new();
        for frame in 0.. {
            let _ = std::fs::remove_file(&out);
            let r = Command::new(env!("CARGO_BIN_EXE_tassemble"))
                .arg(job)
                .args(["--frame", &frame.to_string(), "-o"])
                .arg(&out)
                .output()
                .unwrap();
            if !r.status.success() {
                break;
            }
            pics.push(tessera::image::read_picture(&out).unwrap());
        }
        pics
    };
    let both = render_job(&d.join("both"), &[]);
    assert_eq!(both.len(), 2, "one frame per view");
    let corner = render_job(&d.join("corner"), &["--view", "corner"]);
    assert_eq!(corner.len(), 1);
    for (pic, line) in [(&both[0], &lines[0]), (&corner[0], &lines[1])] {
        let reference = d.join("ref.hdr");
        let _ = std::fs::remove_file(&reference);
        let mut args: Vec<String> = line.split_whitespace().map(str::to_string).collect();
        // rad's -af is the job's store; tpict renders without one.
        if let Some(i) = args.iter().position(|w| w == "-af") {
            args.drain(i..i + 2);
        }
        run_ok(
            Command::new(tpict_bin())
                .current_dir(d)
                .args(["-n", "1"])
                .args(&args)
                .arg("-o")
                .arg(&reference)
                .arg("room.rad"),
        );
        let want = tessera::image::read_picture(&reference).unwrap();
        assert_eq!((pic.width, pic.height), (want.width, want.height));
        assert_eq!(
            pic.pixels, want.pixels,
            "the job's frame differs from tpict's ({line})"
        );
    }
    // Frame 1 of the two-view job is the corner view (sampled with its frame's seeds).
    let mean = |p: &tessera::image::Image| {
        p.pixels.iter().map(|c| c[1] as f64).sum::<f64>() / p.pixels.len() as f64
    };
    let (a, b) = (mean(&both[1]), mean(&corner[0]));
    assert!((a / b - 1.0).abs() < 0.05, "frame 1 mean {a} vs {b}");
    // One view by name; an unknown name is refused with the file's views listed.
    let out = run_ok(tplan(d).args(["--rif", "p.rif", "--view", "corner", "--print"]));
    assert_eq!(String::from_utf8_lossy(&out).trim(), lines[1]);
    let out = run_ok(tplan(d).args(["--rif", "p.rif", "--view", "xyZ", "--print"]));
    assert!(String::from_utf8_lossy(&out).starts_with("-vtv -vp 0.2 0.25 2.85"));
    let e = tplan(d)
        .args(["--rif", "p.rif", "--view", "nope", "--print"])
        .output()
        .unwrap();
    assert!(!e.status.success());
    assert!(String::from_utf8_lossy(&e.stderr).contains("X corner"));
}

#[test]
fn bad_rif_files_name_file_and_line() {
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    std::fs::write(d.join("room.rad"), ROOM).unwrap();
    for (text, want) in [
        (
            "scene= room.rad\nQUALITY= L\nBOGUS= 3\n",
            "bad.rif:3: unknown variable 'BOGUS'",
        ),
        (
            "scene= room.rad\nQUALITY= superb\n",
            "bad.rif:2: QUALITY must be",
        ),
        (
            "scene= room.rad\nZONE= I 0 4 0 5\n",
            "bad.rif:2: ZONE needs",
        ),
        (
            "scene= room.rad\nRESOLUTION= big\n",
            "bad.rif:2: RESOLUTION 'big'",
        ),
        (
            "scene= room.rad\nPGMAP= g.pm 1000\n",
            "bad.rif:2: PGMAP is not supported",
        ),
        ("QUALITY= L\n", "no scene files"),
        ("scene= missing.rad\n", "missing.rad"),
    ] {
        std::fs::write(d.join("bad.rif"), text).unwrap();
        let out = tplan(d)
            .args(["--rif", "bad.rif", "--print"])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "accepted:\n{text}");
        assert!(
            err.contains(want),
            "for\n{text}\nwanted '{want}', got: {err}"
        );
    }
}

/// `illum` files (rad would run mkillum on them) are rendered as ordinary surfaces, with a
/// warning; the options printed are rad's.
#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn illum_files_render_as_surfaces() {
    let Some(bin) = radiance_bin() else { return };
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    std::fs::write(d.join("room.rad"), ROOM).unwrap();
    std::fs::write(
        d.join("win.rad"),
        "void glow wg 0 0 4 1 1 1 0\nwg polygon win 0 0 12 0 1 1 0 2 1 0 2 2 0 1 2\n",
    )
    .unwrap();
    std::fs::write(
        d.join("i.rif"),
        "scene= room.rad\nillum= win.rad\nview= X\n",
    )
    .unwrap();
    assert_eq!(ours(d, "i.rif"), rad_lines(&bin, d, "i.rif"));
    let job = d.join("job");
    let out = tplan(d)
        .args(["--rif", "i.rif", "--set", "RES=16", "-o"])
        .arg(&job)
        .output()
        .unwrap();
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("mkillum is not built in"));
    let scene = std::fs::read_to_string(job.join("scene.rad")).unwrap();
    assert!(
        scene.contains("win"),
        "the illum file is not in the job's scene"
    );
}

/// `view= NAME -vf FILE`: the job renders the file's view at the resolution rpict gives it
/// (real `vwrays -d` for the same options), as `--print` says; a name that is no standard
/// view and has no options, a missing view file and an invalid view are errors naming the
/// view (rad renders nothing for them); a blank `view=` leaves rad's default X.
#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn rif_views_from_files_and_bad_views() {
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    std::fs::write(d.join("room.rad"), ROOM).unwrap();
    std::fs::write(
        d.join("desk.vf"),
        "rview -vtv -vp 3.5 4.2 1.6 -vd -.55 -1 -.25 -vu 0 0 1 -vh 70 -vv 55\n",
    )
    .unwrap();
    std::fs::write(
        d.join("v.rif"),
        "scene= room.rad\nUP= Z\nRESOLUTION= 64 64\nview= desk -vf desk.vf\nview= X\n",
    )
    .unwrap();
    let job = d.join("job");
    run_ok(
        tplan(d)
            .args(["--rif", "v.rif", "--view", "desk", "--workers", "1", "-o"])
            .arg(&job),
    );
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(job.join("manifest.json")).unwrap()).unwrap();
    let f = &m["frames"][0];
    assert_eq!(f["view"]["vp"], serde_json::json!([3.5, 4.2, 1.6]), "{f}");
    assert_eq!(f["view"]["vh"], 70.0, "{f}");
    assert_eq!(f["view"]["vv"], 55.0, "{f}");
    let printed = String::from_utf8_lossy(&run_ok(
        tplan(d).args(["--rif", "v.rif", "--view", "desk", "--print"]),
    ))
    .to_string();
    assert!(printed.contains("-vf desk.vf"), "{printed}");
    if let Some(bin) = radiance_bin() {
        // rpict's resolution for the printed options: what vwrays -d reports.
        let words: Vec<&str> = printed.split_whitespace().collect();
        let opt = |o: &str| words[words.iter().position(|w| *w == o).unwrap() + 1];
        let out = run_ok(radiance(&bin, "vwrays").current_dir(d).args([
            "-vf",
            "desk.vf",
            "-x",
            opt("-x"),
            "-y",
            opt("-y"),
            "-d",
        ]));
        let want: Vec<String> = String::from_utf8_lossy(&out)
            .split_whitespace()
            .take(4)
            .map(str::to_string)
            .collect();
        let got = format!("-x {} -y {}", f["xres"], f["yres"]);
        assert_eq!(got, want.join(" "));
        // A blank view= leaves rad's default, X.
        std::fs::write(d.join("blank.rif"), "scene= room.rad\nview=\n").unwrap();
        assert_eq!(ours(d, "blank.rif"), rad_lines(&bin, d, "blank.rif"));
    }
    for (view, want) in [
        ("Q", "view 'Q' is neither a standard view id"),
        ("far -vf nosuch.vf", "view 'far': cannot read nosuch.vf"),
        (
            "flat -vd 0 0 0",
            "view 'flat': invalid view: zero view direction",
        ),
    ] {
        std::fs::write(
            d.join("bad.rif"),
            format!("scene= room.rad\nview= {view}\n"),
        )
        .unwrap();
        for extra in [&["--print"][..], &["-o", "badjob"][..]] {
            let out = tplan(d)
                .args(["--rif", "bad.rif"])
                .args(extra)
                .output()
                .unwrap();
            let err = String::from_utf8_lossy(&out.stderr);
            assert!(!out.status.success(), "view= {view} accepted");
            assert!(
                err.contains("bad.rif: ") && err.contains(want),
                "{view}: {err}"
            );
            assert!(!d.join("badjob").exists());
        }
    }
}

/// Scene entries that are commands (`scene= '!xform … file'`, `scene= '!gensky … | xform
/// …'`, quoted as rad passes them to oconv) are read with the built-in generators: the
/// options printed are rad's (the zone and `-ar` come from the scene they make), and a job
/// of the rif renders what rpict renders of the octree rad's own oconv command makes.
#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn rif_scene_commands_run_built_in() {
    let Some(bin) = radiance_bin() else { return };
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    std::fs::write(d.join("room.rad"), ROOM).unwrap();
    std::fs::write(
        d.join("box.rad"),
        "void plastic red 0 0 5 .6 .1 .1 0 0\n!genbox red crate .6 .4 .5\n",
    )
    .unwrap();
    std::fs::write(
        d.join("c.rif"),
        "scene= room.rad\n\
         scene= '!xform -n crate -s 1.5 -rz 30 -t 1.5 2 0 box.rad'\n\
         scene= \"!xform -n crate2 -a 2 -t .9 0 0 -t 1 .5 0 box.rad\"\n\
         scene= '!gensky 3 21 10 -a 40 -o -10 -m -15 | xform -rz 10'\n\
         RESOLUTION= 48 48\nrender= -ps 1 -pj 0\nview= xyz -vh 60 -vv 60\n",
    )
    .unwrap();
    let ours_lines = ours(d, "c.rif");
    assert_eq!(ours_lines, rad_lines(&bin, d, "c.rif"));
    // rad's oconv command, run by the shell as rad runs it.
    let out = run_ok(radiance(&bin, "rad").current_dir(d).args(["-n", "c.rif"]));
    let text = String::from_utf8_lossy(&out).to_string();
    let oconv = text
        .lines()
        .map(str::trim)
        .find(|l| l.starts_with("oconv "))
        .expect("rad's oconv line");
    let path = format!(
        "{}:{}",
        bin.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    run_ok(
        Command::new("sh")
            .current_dir(d)
            .env("PATH", &path)
            .args(["-c", oconv]),
    );
    let words: Vec<String> = ours_lines[0]
        .split_whitespace()
        .filter(|w| *w != "-af" && !w.ends_with(".amb"))
        .map(str::to_string)
        .collect();
    let reference = d.join("ref.hdr");
    let data = run_ok(
        radiance(&bin, "rpict")
            .current_dir(d)
            .args(&words)
            .arg("c.oct"),
    );
    std::fs::write(&reference, data).unwrap();
    let job = d.join("job");
    run_ok(
        tplan(d)
            .args(["--rif", "c.rif", "--workers", "1", "-o"])
            .arg(&job),
    );
    run_ok(
        Command::new(env!("CARGO_BIN_EXE_tpiece"))
            .arg(&job)
            .args(["--threads", "1", "-q"]),
    );
    let pic = d.join("job.hdr");
    run_ok(
        Command::new(env!("CARGO_BIN_EXE_tassemble"))
            .arg(&job)
            .arg("-o")
            .arg(&pic),
    );
    // rad's QUALITY puts -ps 8 after render='s -ps 1: adaptive sampling on both sides, so
    // the pictures are compared by their means (within 1%, the issue's bound at -ab 0).
    let mean = |p: &Path| {
        let img = tessera::image::read_picture(p).unwrap();
        img.pixels.iter().map(|c| c[1] as f64).sum::<f64>() / img.pixels.len() as f64
    };
    let (a, b) = (mean(&pic), mean(&reference));
    assert!(
        b > 0.0 && (a / b - 1.0).abs() < 0.01,
        "job mean {a} against rpict's {b}"
    );
}

/// rad's last steps: a job from a rif file is finished as rad's pfilt finishes rad's picture
/// (the reduction by the supersampling factor, the EXPOSURE), and `trad` runs a rif end to
/// end (plan, workers, merge, assemble) into rad's picture names. Against real `rad` (its
/// oconv, rpict and pfilt): same sizes and exposure, means within 1% (`-ab 0`), pictures
/// within the suite's tolerance. Without Radiance only Tessera's side is checked.
#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn trad_renders_a_rif_as_rad_does() {
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    std::fs::write(d.join("room.rad"), ROOM).unwrap();
    std::fs::write(
        d.join("p.rif"),
        "scene= room.rad\nZONE= I 0 4 0 5 0 3\nQUALITY= Medium\nEXPOSURE= +1\n\
         RESOLUTION= 64 48\nview= X\nview= corner -vp .5 .5 1.5 -vd 1 1 0\n",
    )
    .unwrap();
    let trad = || {
        let mut c = Command::new(env!("CARGO_BIN_EXE_trad"));
        c.current_dir(d).env_remove("RAYPATH");
        c
    };
    run_ok(trad().args(["p.rif", "--set", "PICTURE=t", "--threads", "2"]));
    assert!(!d.join("t.job").exists(), "the job directory is removed");
    let read = |n: &str| tessera::image::read_picture(&d.join(n)).unwrap();
    let (x, corner) = (read("t_X.hdr"), read("t_corner.hdr"));
    // Medium quality renders at twice the resolution; the 45-degree views are square.
    assert_eq!((x.width, x.height), (48, 48));
    assert_eq!((corner.width, corner.height), (48, 48));
    assert_eq!(x.header.exposure, 2.0);
    // --raw keeps the rendered picture: twice the size, half the value.
    run_ok(trad().args([
        "p.rif",
        "--set",
        "PICTURE=r",
        "--view",
        "X",
        "--raw",
        "--keep-job",
    ]));
    assert!(d.join("r.job").is_dir());
    let raw = read("r_X.hdr");
    assert_eq!((raw.width, raw.height), (96, 96));
    let mean = |p: &tessera::image::Image| {
        p.pixels.iter().map(|c| c[1] as f64).sum::<f64>() / p.pixels.len() as f64
    };
    assert!((mean(&x) / (2.0 * mean(&raw)) - 1.0).abs() < 0.02);
    // An existing job directory is refused before anything is rendered.
    let o = trad()
        .args(["p.rif", "--set", "PICTURE=r", "--job", "r.job"])
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("exists"));
    let Some(bin) = radiance_bin() else { return };
    run_ok(radiance(&bin, "rad").current_dir(d).arg("p.rif"));
    for v in ["X", "corner"] {
        let (ours, theirs) = (d.join(format!("t_{v}.hdr")), d.join(format!("p_{v}.hdr")));
        let (a, b) = (
            tessera::image::read_picture(&ours).unwrap(),
            tessera::image::read_picture(&theirs).unwrap(),
        );
        assert_eq!((a.width, a.height), (b.width, b.height), "{v}");
        assert_eq!(a.header.exposure, b.header.exposure, "{v}");
        assert!(
            (mean(&a) / mean(&b) - 1.0).abs() < 0.01,
            "{v}: mean {} against rad's {}",
            mean(&a),
            mean(&b)
        );
        assert_like_reference(&bin, &ours, &theirs, &AMBIENT, v);
    }
}
