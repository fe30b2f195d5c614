//! tpict's command line, through the real binary: errors (one line, `file:line`, non-zero
//! exit, no panic, no output file), option handling like rpict's (`-defaults`, `-version`,
//! `@file`, `-vf`, `-x/-y`, `-pa`), outputs (`-o` RGBE / EXR / PNG, stdout, no clobbering),
//! sequences (`-S`), `-e`, `-t`, `-i`, thread-count independence, and that real Radiance
//! (`getinfo`, `pvalue`) reads tpict's pictures.

mod common;

use common::*;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use tessera::image::{read_picture, Image};

/// The folder of this file's scenes.
fn scenes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scenes/cli")
}

/// A tpict command running in `dir`, with no environment that changes its behaviour.
fn tpict_in(dir: &Path) -> Command {
    let mut c = Command::new(tpict_bin());
    c.current_dir(dir)
        .env_remove("TESSERA_ALLOW_COMMANDS")
        .env_remove("SLURM_CPUS_PER_TASK")
        .stdin(Stdio::null());
    c
}

/// A temporary folder holding copies of this file's scenes.
fn workdir() -> tempfile::TempDir {
    let t = tempfile::tempdir().unwrap();
    for f in ["room.rad", "room.vf", "lamp.rad"] {
        std::fs::copy(scenes().join(f), t.path().join(f)).unwrap();
    }
    t
}

fn output(c: &mut Command) -> Output {
    c.output().expect("cannot start tpict")
}

/// Run a command that must fail cleanly: non-zero exit (not a signal), no panic message.
/// Returns its stderr.
fn fails(c: &mut Command) -> String {
    let o = output(c);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(
        !o.status.success(),
        "{c:?} succeeded but should fail; stderr:\n{err}"
    );
    assert_eq!(
        o.status.code(),
        Some(1),
        "{c:?}: exit status {}: {err}",
        o.status
    );
    assert!(
        !err.contains("panicked") && !err.contains("RUST_BACKTRACE"),
        "{c:?} panicked:\n{err}"
    );
    err
}

/// The single line of an error message (asserting there is exactly one).
fn one_line(err: &str) -> &str {
    let lines: Vec<&str> = err.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "expected a one-line error, got:\n{err}");
    lines[0]
}

/// Small fast render options over room.rad.
const SMALL: &[&str] = &["-vf", "room.vf", "-x", "32", "-y", "32", "-ab", "0"];

fn header_text(bytes: &[u8]) -> String {
    let end = bytes
        .windows(2)
        .position(|w| w == b"\n\n")
        .expect("no end of header");
    String::from_utf8_lossy(&bytes[..end]).into_owned()
}

/// The bytes after the header (resolution line and pixels).
fn after_header(bytes: &[u8]) -> &[u8] {
    let end = bytes
        .windows(2)
        .position(|w| w == b"\n\n")
        .expect("no end of header");
    &bytes[end + 2..]
}

fn largest(p: [f32; 3]) -> f32 {
    p[0].max(p[1]).max(p[2])
}

/// Two pictures agree within RGBE precision (each channel within 1% of the pixel's largest
/// channel, plus a tiny absolute slack).
fn assert_rgbe_close(a: &Image, b: &Image, what: &str) {
    assert_eq!(
        (a.width, a.height),
        (b.width, b.height),
        "{what}: sizes differ"
    );
    for (i, (p, q)) in a.pixels.iter().zip(&b.pixels).enumerate() {
        let tol = 0.01 * largest(*p).max(largest(*q)) + 1e-6;
        for c in 0..3 {
            assert!(
                (p[c] - q[c]).abs() <= tol,
                "{what}: pixel {i} channel {c}: {} vs {}",
                p[c],
                q[c]
            );
        }
    }
}

// ---------------------------------------------------------------------------------------
// Malformed scenes

/// Render `files` (written into a fresh folder; the first is the scene given to tpict) to
/// out.hdr; it must fail with one line naming `want_loc`, containing every `want` fragment,
/// and leave no output file.
fn scene_error(files: &[(&str, &str)], want_loc: &str, want: &[&str]) {
    let t = workdir();
    for (name, text) in files {
        std::fs::write(t.path().join(name), text).unwrap();
    }
    let err = fails(
        tpict_in(t.path())
            .args(SMALL)
            .args(["-o", "out.hdr"])
            .arg(files[0].0),
    );
    let line = one_line(&err);
    assert!(
        line.contains(want_loc),
        "error should name {want_loc}: {line}"
    );
    for w in want {
        assert!(line.contains(w), "error should contain '{w}': {line}");
    }
    assert!(
        !t.path().join("out.hdr").exists(),
        "an output file was written despite the error"
    );
    assert_no_files_like(t.path(), "out");
}

/// No file in `dir` has `part` in its name (no output, no temporary file left behind).
fn assert_no_files_like(dir: &Path, part: &str) {
    let left: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(part))
        .collect();
    assert!(left.is_empty(), "leftover output files {left:?}");
}

const LAMP: &str =
    "void light bright\n0\n0\n3 100 100 100\n\nbright sphere lamp\n0\n0\n4 0 0 2 .1\n";

#[test]
fn truncated_record_is_a_located_error() {
    // Line 5 starts a plastic whose real arguments stop after 2 of 5.
    let text = format!("{LAMP}void plastic red\n0\n0\n5 .5 .5\n");
    scene_error(&[("bad.rad", &text)], "bad.rad:", &["end of file"]);
    // The line reported is one of the truncated primitive's lines (11..14).
    let t = workdir();
    std::fs::write(t.path().join("bad.rad"), &text).unwrap();
    let err = fails(tpict_in(t.path()).args(SMALL).arg("bad.rad"));
    let line = one_line(&err);
    assert!(
        (11..=14).any(|n| line.contains(&format!("bad.rad:{n}:"))),
        "{line}"
    );
}

#[test]
fn wrong_count_is_a_located_error() {
    let text = format!("{LAMP}\nvoid plastic red\n0\nzero\n5 .5 .5 .5 0 0\n");
    scene_error(&[("bad.rad", &text)], "bad.rad:13:", &["zero"]);
    // A count larger than the arguments present runs into the next primitive's words.
    let text = format!("{LAMP}\nvoid plastic red\n0\n0\n7 .5 .5 .5 0 0\n");
    scene_error(&[("bad.rad", &text)], "bad.rad:", &["red"]);
}

#[test]
fn non_number_is_a_located_error() {
    let text = format!("{LAMP}\nvoid plastic red\n0\n0\n5 .5 .5 abc 0 0\n");
    scene_error(&[("bad.rad", &text)], "bad.rad:14:", &["abc"]);
    let text = format!("{LAMP}\nvoid plastic red\n0\n2 1 x\n5 .5 .5 .5 0 0\n");
    scene_error(&[("bad.rad", &text)], "bad.rad:13:", &["x"]);
}

#[test]
fn unknown_type_is_a_located_error() {
    let text = format!("{LAMP}\nvoid plastik red\n0\n0\n5 .5 .5 .5 0 0\n");
    scene_error(&[("bad.rad", &text)], "bad.rad:11:", &["plastik"]);
}

#[test]
fn missing_scene_file_is_an_error() {
    let t = workdir();
    let err = fails(
        tpict_in(t.path())
            .args(SMALL)
            .args(["-o", "out.hdr", "nosuch.rad"]),
    );
    let line = one_line(&err);
    assert!(line.contains("nosuch.rad"), "{line}");
    assert!(!t.path().join("out.hdr").exists());
    // A missing file named by an xform inside a scene: located at the xform line.
    let text = format!("{LAMP}\n!xform -t 1 0 0 gone.rad\n");
    scene_error(&[("main.rad", &text)], "main.rad:11:", &["gone.rad"]);
}

#[test]
fn xform_include_loop_is_a_located_error() {
    scene_error(
        &[
            ("a.rad", &format!("{LAMP}\n!xform -t 0 0 1 b.rad\n")),
            ("b.rad", "# b includes a\n!xform -t 0 0 1 a.rad\n"),
        ],
        ".rad:",
        &["recursion"],
    );
    // A file including itself.
    scene_error(
        &[("self.rad", "!xform -s 2 self.rad\n")],
        "self.rad:1:",
        &["recursion"],
    );
}

#[test]
fn a_damaged_octree_argument_is_one_error_line() {
    let t = workdir();
    std::fs::write(t.path().join("scene.oct"), b"#?RADIANCE\noconv x\n\n").unwrap();
    let err = fails(
        tpict_in(t.path())
            .args(SMALL)
            .args(["-o", "out.hdr", "scene.oct"]),
    );
    let line = one_line(&err);
    assert!(line.contains("scene.oct"), "{line}");
    assert!(line.contains("truncated"), "{line}");
    assert!(!t.path().join("out.hdr").exists());
}

#[test]
fn unsupported_primitive_types_are_named_with_location() {
    for (ty, args) in [
        ("specfunc", "2 sf funcs.cal\n0\n2 380 780\n"),
        ("prism1", "5 coef dx dy dz prism.cal\n0\n0\n"),
    ] {
        let text =
            format!("{LAMP}\nvoid {ty} pat\n{args}\npat plastic red\n0\n0\n5 .5 .5 .5 0 0\n");
        scene_error(
            &[("pat.rad", &text)],
            "pat.rad:11:",
            &[&format!("unsupported primitive type {ty}")],
        );
    }
}

/// A pattern whose function file is missing: the error names the scene file and line, the
/// primitive and the file it could not find.
#[test]
fn missing_function_files_are_named() {
    for (ty, args) in [
        ("brightfunc", "2 refl funcs.cal\n0\n0\n"),
        ("texfunc", "4 dx dy dz funcs.cal\n0\n0\n"),
        ("mixfunc", "4 red grey mix funcs.cal\n0\n0\n"),
    ] {
        let text =
            format!("{LAMP}\nvoid {ty} pat\n{args}\npat plastic red\n0\n0\n5 .5 .5 .5 0 0\n");
        scene_error(
            &[("pat.rad", &text)],
            "pat.rad:11:",
            &["funcs.cal", "cannot find function file"],
        );
    }
}

/// Errors in expressions: a syntax error is a load-time error naming the scene file and
/// line; an undefined variable met while rendering stops the render (rpict's fatal error),
/// names the variable and the primitive, and writes no picture.
#[test]
fn expression_errors_stop_with_a_message() {
    let floor = "\npat plastic red\n0\n0\n5 .5 .5 .5 0 0\n\
                 red polygon floor\n0\n0\n12 -9 -9 0 9 -9 0 9 9 0 -9 9 0\n";
    let text = format!("{LAMP}\nvoid brightfunc pat\n2 Px*(2 .\n0\n0\n{floor}");
    scene_error(&[("pat.rad", &text)], "pat.rad:11", &["')' expected"]);
    let text = format!("{LAMP}\nvoid brightfunc pat\n2 Px*nosuchvar .\n0\n0\n{floor}");
    scene_error(
        &[("pat.rad", &text)],
        "pat.rad:11",
        &["nosuchvar", "undefined"],
    );
}

/// A one-thread render hands its rows to the output as it goes (through a temporary file):
/// the same picture on standard output and in `-o`, the same pixels as on two threads, and
/// nothing at all, on standard output or in `-o`, when the render stops on an error.
#[test]
fn one_thread_pictures_stream_and_fail_cleanly() {
    let t = workdir();
    for ps in ["1", "4"] {
        let run = |n: &str, extra: &[&str]| {
            let mut c = tpict_in(t.path());
            c.args([
                "-vf", "room.vf", "-x", "64", "-y", "48", "-ab", "0", "-ps", ps,
            ])
            .args(["-n", n])
            .args(extra)
            .arg("room.rad");
            let o = output(&mut c);
            assert!(
                o.status.success(),
                "{c:?}: {}",
                String::from_utf8_lossy(&o.stderr)
            );
            o.stdout
        };
        let one = run("1", &[]);
        let pic = read_picture_bytes(&one);
        assert!(
            pic.pixels.iter().any(|p| largest(*p) > 0.0),
            "-ps {ps}: a black picture"
        );
        assert_eq!(after_header(&one), after_header(&run("2", &[])), "-ps {ps}");
        let _ = std::fs::remove_file(t.path().join("o.hdr"));
        run("1", &["-o", "o.hdr"]);
        let file = std::fs::read(t.path().join("o.hdr")).unwrap();
        assert_eq!(after_header(&file), after_header(&one), "-ps {ps}");
    }
    let floor = "\npat plastic red\n0\n0\n5 .5 .5 .5 0 0\n\
                 red polygon floor\n0\n0\n12 -9 -9 0 9 -9 0 9 9 0 -9 9 0\n";
    std::fs::write(
        t.path().join("bad.rad"),
        format!("{LAMP}\nvoid brightfunc pat\n2 Px*nosuchvar .\n0\n0\n{floor}"),
    )
    .unwrap();
    for out in [None, Some("bad.hdr")] {
        let mut c = tpict_in(t.path());
        c.args(SMALL).args(["-n", "1"]);
        if let Some(o) = out {
            c.args(["-o", o]);
        }
        let o = output(c.arg("bad.rad"));
        assert!(!o.status.success());
        assert!(o.stdout.is_empty(), "{} bytes written", o.stdout.len());
        assert_no_files_like(t.path(), "bad.hdr");
    }
}

/// A picture from its bytes.
fn read_picture_bytes(bytes: &[u8]) -> Image {
    let t = tempfile::NamedTempFile::new().unwrap();
    std::fs::write(t.path(), bytes).unwrap();
    read_picture(t.path()).unwrap()
}

// ---------------------------------------------------------------------------------------
// Inline commands

fn command_scene(t: &Path) {
    std::fs::write(
        t.join("main.rad"),
        "# the lamp comes from another file\n!cat lamp.rad\n",
    )
    .unwrap();
}

#[test]
fn inline_command_needs_allow_commands() {
    let t = workdir();
    command_scene(t.path());
    let err = fails(
        tpict_in(t.path())
            .args(SMALL)
            .args(["-o", "out.hdr", "main.rad"]),
    );
    let line = one_line(&err);
    for w in ["main.rad:2:", "cat", "--allow-commands"] {
        assert!(line.contains(w), "error should contain '{w}': {line}");
    }
    assert!(!t.path().join("out.hdr").exists());
    // A command that is not even a program name.
    std::fs::write(
        t.path().join("echo.rad"),
        "\n\n\n!echo void plastic x 0 0 5 1 1 1 0 0\n",
    )
    .unwrap();
    let err = fails(tpict_in(t.path()).args(SMALL).arg("echo.rad"));
    let line = one_line(&err);
    for w in ["echo.rad:4:", "echo", "--allow-commands"] {
        assert!(line.contains(w), "error should contain '{w}': {line}");
    }
}

#[test]
fn inline_command_runs_with_flag_or_env() {
    let t = workdir();
    command_scene(t.path());
    let p = t.path();
    run_ok(
        tpict_in(p)
            .args(SMALL)
            .args(["-o", "direct.hdr", "lamp.rad"]),
    );
    run_ok(
        tpict_in(p)
            .args(SMALL)
            .args(["--allow-commands", "-o", "flag.hdr", "main.rad"]),
    );
    run_ok(
        tpict_in(p)
            .env("TESSERA_ALLOW_COMMANDS", "1")
            .args(SMALL)
            .args(["-o", "env.hdr", "main.rad"]),
    );
    let direct = read_picture(&p.join("direct.hdr")).unwrap();
    assert!(
        direct.pixels.iter().any(|q| largest(*q) > 0.01),
        "black picture"
    );
    for f in ["flag.hdr", "env.hdr"] {
        let got = read_picture(&p.join(f)).unwrap();
        assert_eq!(
            got.pixels, direct.pixels,
            "{f} differs from rendering lamp.rad"
        );
    }
    // `!echo` output is read as scene text.
    std::fs::write(
        p.join("echo.rad"),
        "!echo void light glowy 0 0 3 5 5 5\n!echo glowy sphere s 0 0 4 0 0 2 .5\n",
    )
    .unwrap();
    run_ok(
        tpict_in(p)
            .args(SMALL)
            .args(["--allow-commands", "-o", "echo.hdr", "echo.rad"]),
    );
    let img = read_picture(&p.join("echo.hdr")).unwrap();
    assert!(
        img.pixels.iter().any(|q| (q[0] - 5.0).abs() < 0.05),
        "the echoed light sphere is not visible"
    );
}

// ---------------------------------------------------------------------------------------
// Options

#[test]
fn motion_blur_is_refused_not_ignored() {
    let t = workdir();
    let err = fails(
        tpict_in(t.path())
            .args(["-vf", "room.vf", "-x", "16", "-y", "16", "-pm", ".5"])
            .args(["-o", "out.hdr", "room.rad"]),
    );
    let line = one_line(&err);
    assert!(line.contains("-pm"), "{line}");
    assert!(line.contains("not supported"), "{line}");
    assert!(!t.path().join("out.hdr").exists());
}

/// A participating medium is refused, never ignored: `-me` above zero and the `mist`
/// material (rpict's mean drops from 0.199 to 0.054 on a room with `-me .3`).
#[test]
fn mist_is_refused_not_ignored() {
    let t = workdir();
    let err = fails(
        tpict_in(t.path())
            .args([
                "-vf", "room.vf", "-x", "16", "-y", "16", "-me", ".3", ".3", ".3",
            ])
            .args(["-o", "out.hdr", "room.rad"]),
    );
    let line = one_line(&err);
    assert!(
        line.contains("-me") && line.contains("not supported"),
        "{line}"
    );
    assert!(!t.path().join("out.hdr").exists());
    // Zero extinction is no medium: accepted, like -ma and -mg alone.
    run_ok(
        tpict_in(t.path())
            .args(["-vf", "room.vf", "-x", "8", "-y", "8", "-me", "0", "0", "0"])
            .args([
                "-ma", ".5", ".5", ".5", "-mg", ".3", "-o", "ok.hdr", "room.rad",
            ]),
    );
    let text =
        format!("{LAMP}\nvoid mist fog\n0\n0\n3 .1 .1 .1\nfog sphere vol\n0\n0\n4 0 0 1 .5\n");
    scene_error(
        &[("fog.rad", &text)],
        "fog.rad:",
        &["unsupported primitive type mist"],
    );
}

#[test]
fn unknown_options_are_errors() {
    let t = workdir();
    for bad in ["-zz", "-vq", "-abc", "--frobnicate", "-pXX"] {
        let err = fails(
            tpict_in(t.path())
                .args(["-vf", "room.vf", "-x", "16", "-y", "16", bad])
                .args(["-o", "out.hdr", "room.rad"]),
        );
        let line = one_line(&err);
        assert!(line.contains(bad), "error should name {bad}: {line}");
        assert!(!t.path().join("out.hdr").exists());
    }
    // Bad values too.
    for bad in [
        &["-x", "ten"][..],
        &["-dj", "2"],
        &["-vp", "1", "2"],
        &["-ps", "0"],
    ] {
        let err = fails(
            tpict_in(t.path())
                .args(["-vf", "room.vf"])
                .args(bad)
                .args(["-o", "out.hdr", "room.rad"]),
        );
        let line = one_line(&err);
        assert!(
            line.contains(bad[0]),
            "error should name {}: {line}",
            bad[0]
        );
    }
}

#[test]
fn options_after_scene_files_are_errors() {
    let t = workdir();
    let err =
        fails(tpict_in(t.path()).args(["-vf", "room.vf", "-o", "out.hdr", "room.rad", "-x", "16"]));
    let line = one_line(&err);
    assert!(line.contains("-x") && line.contains("room.rad"), "{line}");
    assert!(!t.path().join("out.hdr").exists());
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn defaults_print_rpicts_layout_with_given_options() {
    let t = workdir();
    let o = output(tpict_in(t.path()).args(["-ab", "2", "-x", "300", "-vh", "30", "-defaults"]));
    assert!(o.status.success());
    let ours = String::from_utf8(o.stdout).unwrap();
    assert!(ours.lines().any(|l| l.starts_with("-ab 2 ")), "{ours}");
    assert!(ours.lines().any(|l| l.starts_with("-x  300 ")), "{ours}");
    assert!(
        ours.lines().any(|l| l.starts_with("-vh 30.000000\t")),
        "{ours}"
    );
    assert!(ours.lines().any(|l| l.starts_with("-vtv\t")), "{ours}");
    let Some(bin) = radiance_bin() else { return };
    let theirs =
        run_ok(radiance(&bin, "rpict").args(["-ab", "2", "-x", "300", "-vh", "30", "-defaults"]));
    let theirs = String::from_utf8(theirs).unwrap();
    // Same options in the same order and layout. Allow lines for options tpict does not
    // have (rpict may print e.g. spectral options) only at the end.
    let ol: Vec<&str> = ours.lines().collect();
    let tl: Vec<&str> = theirs.lines().collect();
    for (k, l) in ol.iter().enumerate() {
        assert_eq!(Some(l), tl.get(k), "line {} of -defaults differs", k + 1);
    }
}

#[test]
fn version_is_printed() {
    let o = output(Command::new(tpict_bin()).arg("-version"));
    assert!(o.status.success());
    let s = String::from_utf8(o.stdout).unwrap();
    assert!(s.contains("tpict"), "{s}");
    assert!(s.contains(env!("CARGO_PKG_VERSION")), "{s}");
}

#[test]
fn at_file_options_are_read() {
    let t = workdir();
    let p = t.path();
    std::fs::write(
        p.join("opts.txt"),
        "# render options\n-vf room.vf\n-x 24 -y 12   # maxima\n-ab 0 -av .1 .1 .1\n",
    )
    .unwrap();
    run_ok(tpict_in(p).args([
        "@opts.txt",
        "-vh",
        "20",
        "-vv",
        "20",
        "-o",
        "at.hdr",
        "room.rad",
    ]));
    let img = read_picture(&p.join("at.hdr")).unwrap();
    assert_eq!((img.width, img.height), (12, 12));
    let v = img.header.view.clone().unwrap();
    assert!(v.contains("-vp 0 -4 1.5"), "{v}");
    assert!(v.contains("-vh 20"), "{v}");
    // The same with the options given directly.
    run_ok(tpict_in(p).args([
        "-vf",
        "room.vf",
        "-x",
        "24",
        "-y",
        "12",
        "-ab",
        "0",
        "-av",
        ".1",
        ".1",
        ".1",
        "-vh",
        "20",
        "-vv",
        "20",
        "-o",
        "direct.hdr",
        "room.rad",
    ]));
    let direct = read_picture(&p.join("direct.hdr")).unwrap();
    assert_eq!(direct.pixels, img.pixels);
    // A missing @file is an error naming it.
    let err = fails(tpict_in(p).args(["@nosuch.opt", "room.rad"]));
    assert!(one_line(&err).contains("nosuch.opt"), "{err}");
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn view_file_with_view_and_rview_lines() {
    let t = workdir();
    let p = t.path();
    std::fs::write(
        p.join("two.vf"),
        "VIEW= -vtv -vp 0 -4 1.5 -vd 0 1 -0.3 -vu 0 0 1 -vh 40 -vv 40\n\
         some other line that is not a view\n\
         rview -vh 30 -vv 20 -vp 0.5 -4 1.5\n",
    )
    .unwrap();
    run_ok(tpict_in(p).args([
        "-vf", "two.vf", "-x", "64", "-y", "64", "-o", "v.hdr", "room.rad",
    ]));
    let img = read_picture(&p.join("v.hdr")).unwrap();
    let v = img.header.view.clone().unwrap();
    for w in ["-vtv", "-vp 0.5 -4 1.5", "-vh 30", "-vv 20", "-vu 0 0 1"] {
        assert!(v.contains(w), "VIEW= should contain '{w}': {v}");
    }
    // tan 15° / tan 10° = 1.5196: 64 × 42.
    assert_eq!((img.width, img.height), (64, 42));
    let Some(bin) = radiance_bin() else { return };
    let oct = oconv(&bin, p, &["room.rad"]);
    let data = run_ok(
        radiance(&bin, "rpict")
            .current_dir(p)
            .args(["-vf", "two.vf", "-x", "64", "-y", "64"])
            .arg(&oct),
    );
    std::fs::write(p.join("r.hdr"), data).unwrap();
    let r = read_picture(&p.join("r.hdr")).unwrap();
    assert_eq!((img.width, img.height), (r.width, r.height));
}

fn oconv(bin: &Path, dir: &Path, files: &[&str]) -> PathBuf {
    let oct = dir.join("scene.oct");
    let data = run_ok(radiance(bin, "oconv").current_dir(dir).args(files));
    std::fs::write(&oct, data).unwrap();
    oct
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn resolution_is_a_maximum_fitted_to_the_view_aspect() {
    let t = workdir();
    let p = t.path();
    let cases: &[(&[&str], (usize, usize))] = &[
        (
            &["-vh", "60", "-vv", "40", "-x", "64", "-y", "64"],
            (64, 40),
        ),
        (
            &["-vh", "40", "-vv", "60", "-x", "64", "-y", "64"],
            (40, 64),
        ),
        (
            &["-vh", "45", "-vv", "45", "-x", "64", "-y", "32"],
            (32, 32),
        ),
        (
            &["-vtl", "-vh", "4", "-vv", "3", "-x", "64", "-y", "64"],
            (64, 48),
        ),
    ];
    let bin = radiance_bin();
    let oct = bin.as_ref().map(|b| oconv(b, p, &["room.rad"]));
    for (k, (opts, want)) in cases.iter().enumerate() {
        let out = format!("res{k}.hdr");
        run_ok(
            tpict_in(p)
                .args(["-vp", "0", "-4", "1", "-vd", "0", "1", "0", "-ps", "1"])
                .args(*opts)
                .args(["-o", &out, "room.rad"]),
        );
        let img = read_picture(&p.join(&out)).unwrap();
        assert_eq!((img.width, img.height), *want, "{opts:?}");
        assert!(img.header.pixaspect.is_none_or(|a| (a - 1.0).abs() < 0.005));
        if let (Some(bin), Some(oct)) = (&bin, &oct) {
            let data = run_ok(
                radiance(bin, "rpict")
                    .current_dir(p)
                    .args(["-vp", "0", "-4", "1", "-vd", "0", "1", "0", "-ps", "1"])
                    .args(*opts)
                    .arg(oct),
            );
            let rp = p.join(format!("r{k}.hdr"));
            std::fs::write(&rp, data).unwrap();
            let r = read_picture(&rp).unwrap();
            assert_eq!((r.width, r.height), *want, "rpict {opts:?}");
        }
    }
}

#[test]
fn pixel_aspect_zero_keeps_resolution_and_writes_pixaspect() {
    let t = workdir();
    let p = t.path();
    run_ok(tpict_in(p).args([
        "-vp", "0", "-4", "1", "-vd", "0", "1", "0", "-vh", "60", "-vv", "40", "-x", "64", "-y",
        "64", "-pa", "0", "-o", "pa.hdr", "room.rad",
    ]));
    let bytes = std::fs::read(p.join("pa.hdr")).unwrap();
    let head = header_text(&bytes);
    let line = head
        .lines()
        .find(|l| l.starts_with("PIXASPECT="))
        .unwrap_or_else(|| panic!("no PIXASPECT= in\n{head}"));
    let pa: f64 = line["PIXASPECT=".len()..].trim().parse().unwrap();
    // (tan 20° / tan 30°) × 64/64, as rpict writes it (0.630415).
    let want = (20f64.to_radians().tan() / 30f64.to_radians().tan()) * 64.0 / 64.0;
    assert!((pa - want).abs() < 1e-5, "PIXASPECT={pa}, want {want}");
    let img = read_picture(&p.join("pa.hdr")).unwrap();
    assert_eq!((img.width, img.height), (64, 64));
}

// ---------------------------------------------------------------------------------------
// Outputs

#[test]
fn output_hdr_has_rpict_header() {
    let t = workdir();
    let p = t.path();
    run_ok(tpict_in(p).args(SMALL).args(["-o", "out.hdr", "room.rad"]));
    let bytes = std::fs::read(p.join("out.hdr")).unwrap();
    let head = header_text(&bytes);
    let lines: Vec<&str> = head.lines().collect();
    assert_eq!(lines[0], "#?RADIANCE");
    assert!(
        lines
            .iter()
            .any(|l| l.starts_with("tpict ") && l.contains("-x 32") && l.contains("room.rad")),
        "no command line in\n{head}"
    );
    assert!(lines.iter().any(|l| l.starts_with("SOFTWARE=")), "{head}");
    let view = lines
        .iter()
        .find(|l| l.starts_with("VIEW="))
        .unwrap_or_else(|| panic!("no VIEW= in\n{head}"));
    assert!(view.contains("-vp 0 -4 1.5"), "{view}");
    assert!(view.contains("-vtv"), "{view}");
    assert!(lines.contains(&"FORMAT=32-bit_rle_rgbe"), "{head}");
    assert!(
        after_header(&bytes).starts_with(b"-Y 32 +X 32\n")
            || after_header(&bytes).starts_with(b"-Y       32 +X       32\n")
    );
    let img = read_picture(&p.join("out.hdr")).unwrap();
    assert_eq!((img.width, img.height), (32, 32));
    assert_finite(&img);
}

#[test]
fn output_never_overwrites_an_existing_file() {
    let t = workdir();
    let p = t.path();
    std::fs::write(p.join("keep.hdr"), b"precious").unwrap();
    let err = fails(tpict_in(p).args(SMALL).args(["-o", "keep.hdr", "room.rad"]));
    assert!(one_line(&err).contains("File exists"), "{err}");
    assert_eq!(std::fs::read(p.join("keep.hdr")).unwrap(), b"precious");
    for f in ["keep.exr", "keep.png"] {
        std::fs::write(p.join(f), b"precious").unwrap();
        let err = fails(tpict_in(p).args(SMALL).args(["-o", f, "room.rad"]));
        assert!(one_line(&err).contains("File exists"), "{err}");
        assert_eq!(std::fs::read(p.join(f)).unwrap(), b"precious");
    }
}

#[test]
fn output_exr_matches_hdr_within_rgbe_precision() {
    let t = workdir();
    let p = t.path();
    let opts = [
        "-vf", "room.vf", "-x", "48", "-y", "48", "-ps", "1", "-pj", "0", "-n", "1",
    ];
    run_ok(tpict_in(p).args(opts).args(["-o", "x.hdr", "room.rad"]));
    run_ok(tpict_in(p).args(opts).args(["-o", "x.exr", "room.rad"]));
    let exr = std::fs::read(p.join("x.exr")).unwrap();
    assert_eq!(&exr[..4], &[0x76, 0x2f, 0x31, 0x01], "not an OpenEXR file");
    let a = read_picture(&p.join("x.exr")).unwrap();
    let b = read_picture(&p.join("x.hdr")).unwrap();
    assert_finite(&a);
    assert!(b.pixels.iter().any(|q| largest(*q) > 0.01));
    assert_rgbe_close(&a, &b, "exr vs hdr");
}

#[test]
fn output_png_is_a_png_of_the_right_size() {
    let t = workdir();
    let p = t.path();
    run_ok(tpict_in(p).args([
        "-vf", "room.vf", "-x", "40", "-y", "30", "-o", "x.png", "room.rad",
    ]));
    let png = std::fs::read(p.join("x.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    assert_eq!(&png[12..16], b"IHDR");
    let w = u32::from_be_bytes(png[16..20].try_into().unwrap());
    let h = u32::from_be_bytes(png[20..24].try_into().unwrap());
    // -vh 40 -vv 40 into at most 40×30: 30×30.
    assert_eq!((w, h), (30, 30));
}

#[test]
fn stdout_when_no_output_file() {
    let t = workdir();
    let p = t.path();
    let data = run_ok(
        tpict_in(p)
            .args(SMALL)
            .args(["-ps", "1", "-pj", "0", "room.rad"]),
    );
    assert!(data.starts_with(b"#?RADIANCE\n"));
    std::fs::write(p.join("stdout.hdr"), &data).unwrap();
    let img = read_picture(&p.join("stdout.hdr")).unwrap();
    assert_eq!((img.width, img.height), (32, 32));
    run_ok(
        tpict_in(p)
            .args(SMALL)
            .args(["-ps", "1", "-pj", "0", "-o", "file.hdr", "room.rad"]),
    );
    let file = std::fs::read(p.join("file.hdr")).unwrap();
    assert_eq!(after_header(&file), after_header(&data));
}

// ---------------------------------------------------------------------------------------
// Sequences

const VIEWS: &str = "VIEW= -vtv -vp 0 -4 1.5 -vd 0 1 -0.3 -vu 0 0 1 -vh 40 -vv 40\n\
                     VIEW= -vp 1 -4 1.5\n\
                     rview -vtv -vp 2 -4 1.5 -vd 0 1 -0.3 -vh 30 -vv 30\n";

/// Run `tpict -x 24 -y 24 -ab 0 -ps 1 -S 1 extra... room.rad` in `p` with `views` on its
/// standard input.
fn sequence_run(p: &Path, extra: &[&str], views: &[u8]) -> Output {
    let mut c = tpict_in(p);
    c.args(["-x", "24", "-y", "24", "-ab", "0", "-ps", "1", "-S", "1"])
        .args(extra)
        .arg("room.rad")
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let mut child = c.spawn().unwrap();
    child.stdin.take().unwrap().write_all(views).unwrap();
    child.wait_with_output().unwrap()
}

fn sequence(p: &Path, extra: &[&str]) -> Output {
    let o = sequence_run(p, extra, VIEWS.as_bytes());
    assert!(
        o.status.success(),
        "sequence failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

fn check_frame_view(img: &Image, n: u32) {
    assert_eq!(img.header.frame, Some(n), "FRAME=");
    let v = img.header.view.clone().unwrap();
    let vp = ["-vp 0 -4 1.5", "-vp 1 -4 1.5", "-vp 2 -4 1.5"][n as usize - 1];
    assert!(v.contains(vp), "frame {n}: VIEW= {v}");
    assert!(v.contains("-vd 0 1 -0.3"), "frame {n}: VIEW= {v}");
    if n == 3 {
        assert!(v.contains("-vh 30"), "frame {n}: VIEW= {v}");
    } else {
        assert!(v.contains("-vh 40"), "frame {n}: VIEW= {v}");
    }
}

#[test]
fn sequence_to_numbered_files_skips_existing_frames() {
    let t = workdir();
    let p = t.path();
    std::fs::write(p.join("frame002.hdr"), b"").unwrap();
    sequence(p, &["-o", "frame%03d.hdr"]);
    assert_eq!(
        std::fs::read(p.join("frame002.hdr")).unwrap(),
        b"",
        "existing frame was touched"
    );
    for n in [1, 3] {
        let f = p.join(format!("frame{n:03}.hdr"));
        let img = read_picture(&f).unwrap();
        assert_finite(&img);
        check_frame_view(&img, n);
        let head = header_text(&std::fs::read(&f).unwrap());
        assert!(head.lines().any(|l| l == format!("FRAME={n}")), "{head}");
    }
    assert!(!p.join("frame004.hdr").exists() && !p.join("frame000.hdr").exists());
}

#[test]
fn sequence_without_output_concatenates_on_stdout() {
    let t = workdir();
    let p = t.path();
    let o = sequence(p, &[]);
    let mut r = std::io::BufReader::new(&o.stdout[..]);
    for n in 1..=3 {
        let img = tessera::image::hdr::read_hdr(&mut r)
            .unwrap_or_else(|e| panic!("picture {n} on stdout: {e}"));
        assert_eq!((img.width, img.height), (24, 24));
        check_frame_view(&img, n);
    }
    let mut rest = Vec::new();
    std::io::Read::read_to_end(&mut r, &mut rest).unwrap();
    assert!(
        rest.is_empty(),
        "{} bytes after the third picture",
        rest.len()
    );
}

// ---------------------------------------------------------------------------------------
// Messages

#[test]
fn error_file_gets_messages_appended() {
    let t = workdir();
    let p = t.path();
    std::fs::write(p.join("err.txt"), "earlier message\n").unwrap();
    // A scene without light sources: a warning, and a picture.
    std::fs::write(
        p.join("dark.rad"),
        "void plastic grey\n0\n0\n5 .5 .5 .5 0 0\ngrey sphere s\n0\n0\n4 0 0 1 1\n",
    )
    .unwrap();
    let o = output(
        tpict_in(p)
            .args(SMALL)
            .args(["-e", "err.txt", "-o", "dark.hdr", "dark.rad"]),
    );
    assert!(o.status.success());
    assert!(p.join("dark.hdr").exists());
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        !stderr.contains("light"),
        "warning went to stderr: {stderr}"
    );
    let text = std::fs::read_to_string(p.join("err.txt")).unwrap();
    assert!(text.starts_with("earlier message\n"), "{text}");
    assert!(text.contains("no light sources"), "{text}");
    // An error is appended too, after the warning.
    let o = output(
        tpict_in(p)
            .args(SMALL)
            .args(["-e", "err.txt", "-o", "x.hdr", "nosuch.rad"]),
    );
    assert_eq!(o.status.code(), Some(1));
    let text2 = std::fs::read_to_string(p.join("err.txt")).unwrap();
    assert!(text2.starts_with(&text), "earlier contents changed");
    assert!(text2[text.len()..].contains("nosuch.rad"), "{text2}");
}

#[test]
fn progress_reports_every_second() {
    let t = workdir();
    let p = t.path();
    // Enough work for about two seconds on one thread: 100 small lamps over the room.
    let mut scene = std::fs::read_to_string(p.join("room.rad")).unwrap();
    for k in 0..100 {
        let (x, y) = ((k % 10) as f64 * 0.8 - 3.6, (k / 10) as f64 * 0.8 - 3.6);
        scene.push_str(&format!(
            "\nbright sphere l{k}\n0\n0\n4 {x} {y} {} .05\n",
            2.0 + (k % 7) as f64 * 0.1
        ));
    }
    std::fs::write(p.join("big.rad"), scene).unwrap();
    // On a faster machine, retry larger until the render lasts well over a second.
    let mut last = None;
    for res in ["200", "400", "800"] {
        let out = format!("t{res}.hdr");
        let start = std::time::Instant::now();
        let o = output(tpict_in(p).args([
            "-vf", "room.vf", "-x", res, "-y", res, "-ps", "1", "-n", "1", "-t", "1", "-o", &out,
            "big.rad",
        ]));
        let took = start.elapsed().as_secs_f64();
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(o.status.success(), "{err}");
        last = Some((took, err));
        if took > 1.3 {
            break;
        }
    }
    let (took, err) = last.unwrap();
    assert!(took > 1.3, "render too fast ({took:.2} s) to test -t 1");
    let reports: Vec<&str> = err
        .lines()
        .filter(|l| l.contains("rays,") && l.contains("% after"))
        .collect();
    assert!(
        reports.len() >= 2,
        "expected a report each second over {took:.1} s plus a final one:\n{err}"
    );
    assert!(
        reports.iter().any(|l| !l.contains("100.00%")),
        "no intermediate report:\n{err}"
    );
}

// ---------------------------------------------------------------------------------------
// Irradiance

/// Parallel view from z = 1 straight down over the lamp scene, 2 units square.
const DOWN: &[&str] = &[
    "-vtl", "-vp", "0", "0", "1", "-vd", "0", "0", "-1", "-vu", "0", "1", "0", "-vh", "4", "-vv",
    "4", "-x", "9", "-y", "9", "-ps", "1", "-pj", "0", "-ab", "0", "-av", "0", "0", "0",
];

/// Irradiance on the floor at (x, y, 0) from the lamp (radius .1, radiance 100, centre at
/// height 2): E = π L (r/d)² cos θ, exact for a sphere above the horizon.
fn lamp_irradiance(x: f64, y: f64) -> f64 {
    let (l, r, h) = (100.0, 0.1, 2.0);
    let d2 = x * x + y * y + h * h;
    std::f64::consts::PI * l * r * r / d2 * (h / d2.sqrt())
}

/// The floor point at the centre of pixel (column i, row j from the top) of a DOWN view.
fn floor_point(i: usize, j: usize, n: usize, size: f64) -> (f64, f64) {
    let x = ((i as f64 + 0.5) / n as f64 - 0.5) * size;
    let y = (0.5 - (j as f64 + 0.5) / n as f64) * size;
    (x, y)
}

#[test]
fn irradiance_option_gives_analytic_irradiance() {
    let t = workdir();
    let p = t.path();
    run_ok(
        tpict_in(p)
            .args(DOWN)
            .args(["-i", "-o", "i.hdr", "lamp.rad"]),
    );
    let img = read_picture(&p.join("i.hdr")).unwrap();
    assert_eq!((img.width, img.height), (9, 9));
    for j in 0..9 {
        for i in 0..9 {
            let (x, y) = floor_point(i, j, 9, 4.0);
            let want = lamp_irradiance(x, y);
            let got = img.get(i, j);
            for c in got {
                let rel = (c as f64 - want).abs() / want;
                assert!(
                    rel < 0.01,
                    "pixel ({i},{j}) at ({x:.2},{y:.2}): E = {c}, want {want:.5}"
                );
            }
        }
    }
}

// ---------------------------------------------------------------------------------------
// Threads

fn thread_independent(extra: &[&str]) {
    let t = workdir();
    let p = t.path();
    let mut files = Vec::new();
    for n in ["1", "2"] {
        let out = format!("n{n}.hdr");
        run_ok(
            tpict_in(p)
                .args(["-vf", "room.vf", "-x", "64", "-y", "64", "-ab", "0"])
                .args(extra)
                .args(["-n", n, "-o", &out, "room.rad"]),
        );
        files.push(std::fs::read(p.join(&out)).unwrap());
    }
    assert!(
        after_header(&files[0]) == after_header(&files[1]),
        "{extra:?}: -n 1 and -n 2 pictures differ"
    );
    // With the thread count from the environment the command lines are equal too, so the
    // whole files must be identical.
    let mut whole = Vec::new();
    for n in ["1", "2"] {
        let sub = p.join(format!("env{n}"));
        std::fs::create_dir(&sub).unwrap();
        run_ok(
            tpict_in(&sub)
                .env("SLURM_CPUS_PER_TASK", n)
                .args(["-vf", "../room.vf", "-x", "64", "-y", "64", "-ab", "0"])
                .args(extra)
                .args(["-o", "out.hdr", "../room.rad"]),
        );
        whole.push(std::fs::read(sub.join("out.hdr")).unwrap());
    }
    assert!(
        whole[0] == whole[1],
        "{extra:?}: files differ byte for byte"
    );
    assert!(after_header(&whole[0]) == after_header(&files[0]));
}

#[test]
fn threads_do_not_change_the_picture_default_sampling() {
    thread_independent(&[]);
}

#[test]
fn threads_do_not_change_the_picture_every_pixel() {
    thread_independent(&["-ps", "1"]);
}

#[test]
fn threads_do_not_change_the_picture_with_jitter() {
    thread_independent(&["-dj", ".5", "-pj", ".67", "-ps", "1"]);
    thread_independent(&["-dj", ".5", "-pj", ".67"]);
}

// ---------------------------------------------------------------------------------------
// Real Radiance reads tpict's pictures

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn radiance_reads_tpicts_pictures() {
    let Some(bin) = radiance_bin() else { return };
    let t = workdir();
    let p = t.path();
    run_ok(tpict_in(p).args([
        "-vf", "room.vf", "-x", "40", "-y", "30", "-o", "x.hdr", "room.rad",
    ]));
    let f = p.join("x.hdr");
    let info = String::from_utf8(run_ok(radiance(&bin, "getinfo").arg(&f))).unwrap();
    for w in [
        "#?RADIANCE",
        "tpict ",
        "SOFTWARE=",
        "VIEW=",
        "FORMAT=32-bit_rle_rgbe",
    ] {
        assert!(info.contains(w), "getinfo shows no {w}:\n{info}");
    }
    let dims = String::from_utf8(run_ok(radiance(&bin, "getinfo").arg("-d").arg(&f))).unwrap();
    let words: Vec<&str> = dims.split_whitespace().collect();
    assert_eq!(words[words.len() - 4..], ["-Y", "30", "+X", "30"], "{dims}");
    let vals = String::from_utf8(run_ok(
        radiance(&bin, "pvalue").args(["-h", "-H", "-d"]).arg(&f),
    ))
    .unwrap();
    let nums: Vec<f64> = vals
        .split_whitespace()
        .map(|w| w.parse().unwrap())
        .collect();
    let img = read_picture(&f).unwrap();
    assert_eq!(nums.len(), 3 * img.pixels.len());
    let theirs = Image::from_pixels(
        img.width,
        img.height,
        nums.chunks(3)
            .map(|c| [c[0] as f32, c[1] as f32, c[2] as f32])
            .collect(),
    )
    .unwrap();
    assert!(img.pixels.iter().any(|q| largest(*q) > 0.01));
    assert_rgbe_close(&img, &theirs, "pvalue vs read_picture");
}

/// Standard input without a view line (`VIEW=`, `rview ...`): like rpict, nothing is rendered
/// and a warning says so (no silent success).
#[test]
fn sequence_without_view_lines_warns() {
    let t = workdir();
    let p = t.path();
    let o = sequence_run(p, &["-o", "f%d.hdr"], b"-vtv -vp 0 -4 1.5 -vd 0 1 -0.3\n");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("warning - no output produced"), "{err}");
    assert!(!p.join("f1.hdr").exists());
}

/// `--help`, `-h` and `--version` answer (they were errors), and the help names Tessera's
/// own options.
#[test]
fn help_and_version_answer() {
    let t = tempfile::tempdir().unwrap();
    for flag in ["--help", "-h"] {
        let out = output(tpict_in(t.path()).arg(flag));
        assert!(out.status.success(), "{flag}");
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(
            text.contains("usage: tpict") && text.contains("--amb-share-max"),
            "{text}"
        );
    }
    let out = output(tpict_in(t.path()).arg("--version"));
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains("Tessera tpict"));
}

/// A picture that cannot fit in memory is refused up front with what to do instead (it
/// aborted with "memory allocation of 82567200000 bytes failed").
#[test]
fn pictures_beyond_memory_are_refused() {
    let t = tempfile::tempdir().unwrap();
    std::fs::write(
        t.path().join("s.rad"),
        "void light l 0 0 3 1 1 1\nl sphere s 0 0 4 0 0 0 1\n",
    )
    .unwrap();
    let err = fails(
        tpict_in(t.path())
            .args(["-x", "1000000", "-y", "1000000", "-vp", "0", "-5", "0"])
            .args(["-vd", "0", "1", "0", "-o", "big.hdr", "s.rad"]),
    );
    assert!(err.contains("GiB") && err.contains("tplan"), "{err}");
    assert!(!t.path().join("big.hdr").exists());
}

/// An output named for a format Tessera does not write, or in a folder that does not
/// exist, is refused before rendering, with one error line; nothing is written.
#[test]
fn bad_output_names_are_refused_before_rendering() {
    let t = workdir();
    let d = t.path();
    for (name, want) in [
        ("out.jpg", "not .jpg"),
        ("out.TIFF", "not .TIFF"),
        ("no/such/dir/out.hdr", "does not exist"),
    ] {
        let err = fails(
            tpict_in(d)
                .args(["-vf", "room.vf", "-x", "16", "-y", "16", "-o", name])
                .arg("room.rad"),
        );
        assert!(one_line(&err).contains(want), "{name}: {err}");
        assert!(!d.join(name).exists());
    }
    // Any other name is a Radiance picture.
    let out = output(
        tpict_in(d)
            .args(["-vf", "room.vf", "-x", "16", "-y", "16", "-o", "out.pic"])
            .arg("room.rad"),
    );
    assert!(out.status.success());
    assert!(read_picture(&d.join("out.pic")).is_ok());
}

/// An empty scene (nothing on standard input, or empty files) is an error, not a black
/// picture (rpict reads an octree, which oconv does not make of nothing); a scene of
/// materials only still renders (black), as rpict renders it.
#[test]
fn an_empty_scene_is_an_error() {
    let t = workdir();
    let d = t.path();
    std::fs::write(d.join("empty.rad"), "# nothing\n").unwrap();
    let err = fails(
        tpict_in(d)
            .args(["-x", "8", "-y", "8", "-o", "e.hdr"])
            .stdin(std::process::Stdio::null()),
    );
    assert!(
        one_line(&err).contains("<stdin>: the scene is empty"),
        "{err}"
    );
    let err = fails(tpict_in(d).args(["-x", "8", "-y", "8", "-o", "e.hdr", "empty.rad"]));
    assert!(
        one_line(&err).contains("empty.rad: the scene is empty"),
        "{err}"
    );
    assert!(!d.join("e.hdr").exists());
}
