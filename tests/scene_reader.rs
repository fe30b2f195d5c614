//! Scene front end: syntax, errors, and built-in genbox/xform compared with real Radiance.

use std::path::{Path, PathBuf};
use std::process::Command;

use proptest::prelude::*;
use tessera::scene::{parse_scene_text, read_scene_files, Primitive, ReadOptions, SceneError};

const PYRAD_BIN: &str = "/opt/radvenv/lib/python3.11/site-packages/pyradiance/bin";
const PYRAD_LIB: &str = "/opt/radvenv/lib/python3.11/site-packages/pyradiance/lib";

/// Directory holding the Radiance binaries, found like the project's other tests do.
fn radiance_bin() -> Option<PathBuf> {
    if let Ok(v) = std::env::var("TESSERA_RADIANCE_BIN") {
        let p = PathBuf::from(v);
        let dir = if p.is_file() {
            p.parent()?.to_path_buf()
        } else {
            p
        };
        return dir.join("xform").is_file().then_some(dir);
    }
    if let Ok(path) = std::env::var("PATH") {
        for d in path.split(':') {
            let d = PathBuf::from(d);
            if d.join("xform").is_file() && d.join("genbox").is_file() {
                return Some(d);
            }
        }
    }
    let d = PathBuf::from(PYRAD_BIN);
    d.join("xform").is_file().then_some(d)
}

fn skip() -> Option<PathBuf> {
    let b = radiance_bin();
    if b.is_none() {
        eprintln!("skipping: Radiance not found");
    }
    b
}

/// Run a Radiance program in `dir` and return its stdout.
fn run_real(bin: &Path, prog: &str, args: &[&str], dir: &Path) -> String {
    let path = format!(
        "{}:{}",
        bin.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let o = Command::new(bin.join(prog))
        .args(args)
        .current_dir(dir)
        .env("PATH", path)
        .env("RAYPATH", format!(".:{PYRAD_LIB}"))
        .output()
        .expect("run radiance");
    assert!(
        o.status.success(),
        "{prog} {args:?} failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8(o.stdout).unwrap()
}

fn opts(dir: &Path) -> ReadOptions {
    ReadOptions {
        allow_commands: false,
        raypath: vec![dir.to_path_buf()],
        ..ReadOptions::default()
    }
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-6 * a.abs().max(b.abs()).max(1.0)
}

fn assert_same(ours: &[Primitive], real: &[Primitive], what: &str) {
    assert_eq!(ours.len(), real.len(), "{what}: primitive count");
    for (k, (a, b)) in ours.iter().zip(real).enumerate() {
        let ctx = format!("{what}: primitive {k} ({} vs {})", a.name, b.name);
        assert_eq!(a.modifier, b.modifier, "{ctx}: modifier");
        assert_eq!(a.ptype, b.ptype, "{ctx}: type");
        assert_eq!(a.name, b.name, "{ctx}: name");
        assert_eq!(a.sargs, b.sargs, "{ctx}: sargs");
        assert_eq!(a.iargs, b.iargs, "{ctx}: iargs");
        assert_eq!(a.rargs.len(), b.rargs.len(), "{ctx}: real count");
        for (x, y) in a.rargs.iter().zip(&b.rargs) {
            assert!(close(*x, *y), "{ctx}: reals {:?} vs {:?}", a.rargs, b.rargs);
        }
    }
}

const BASE: &str = r#"# every transformable kind
void plastic red
0
0
5 1 0 0 0 0
red polygon p1
0
0
12 0 0 0  1 0 0  1 1 0  0 1 .5
red sphere s1 0 0 4 1 2 3 0.5
red bubble b1 0 0 4 -1 2 3 0.25
red cone c1 0 0 8 0 0 0 0 0 1 1 0.5
red cup c2 0 0 8 1 0 0 1 1 1 0 0.5
red cylinder c3 0 0 7 0 0 0 1 2 3 .2
red tube c4 0 0 7 3 2 1 0 0 1 .3
red ring r1 0 0 8 1 1 1 0 .6 .8 0.1 1
void light l 0 0 3 1 1 1
l source sun 0 0 4 1 2 3 0.5
void brightfunc bf
2 a b.cal
0
1 5
void colorpict cp
9 r g b x.hdr picture.cal pic_u pic_v -s 2
0 0
red instance i1
1 foo.oct
0 0
red mesh m1
5 foo.rtm -t 1 2 3
0 0
red alias al red
red texfunc tf
4 x y z tf.cal
0 0
red mixfunc mf
4 red void v m.cal
0 0
void plasfunc pf
2 a b.cal
0 5 1 1 1 0 0
"#;

const NESTED: &str = "void plastic blue 0 0 5 0 0 1 0 0\n\
!xform -n in -m blue -t 1 0 0 -rz 10 base.rad\n\
!genbox blue box 1 2 3 -b .1\n\
blue sphere last 0 0 4 0 0 0 1\n";

fn scene_dir() -> tempfile::TempDir {
    let d = tempfile::tempdir().unwrap();
    std::fs::write(d.path().join("base.rad"), BASE).unwrap();
    std::fs::write(d.path().join("nested.rad"), NESTED).unwrap();
    std::fs::write(
        d.path().join("loop.rad"),
        "# loops\n!xform -t 1 0 0 loop.rad\n",
    )
    .unwrap();
    d
}

#[test]
fn syntax_quotes_comments_whitespace() {
    let text = "# head\nvoid plastic 'my mat'   # trailing\n0\n0 5 .5 +1e-1 1E0 -2. 3\n\n\
                \"my mat\" polygon \"a b\"\n0 0 9 0 0 0\n1 0 0\n 0 1 0\nvoid alias x 'my mat'\n";
    let p = parse_scene_text(text, "t.rad", &ReadOptions::default()).unwrap();
    assert_eq!(p.len(), 3);
    assert_eq!(p[0].name, "my mat");
    assert_eq!(p[0].rargs, vec![0.5, 0.1, 1.0, -2.0, 3.0]);
    assert_eq!(p[1].modifier, "my mat");
    assert_eq!(p[1].name, "a b");
    assert_eq!(p[1].loc.line, 6);
    assert_eq!(&*p[1].loc.file, "t.rad");
    assert_eq!(p[2].ptype, "alias");
    assert_eq!(p[2].sargs, vec!["my mat".to_string()]);
}

#[test]
fn continuation_lines_in_commands() {
    let p = parse_scene_text(
        "!genbox m b \\\n 1 2 \\\n 3\nm sphere s 0 0 4 0 0 0 1\n",
        "c.rad",
        &ReadOptions::default(),
    )
    .unwrap();
    assert_eq!(p.len(), 7);
    assert_eq!(p[0].loc.line, 1);
    assert_eq!(p[6].loc.line, 4);
}

fn err(text: &str) -> String {
    parse_scene_text(text, "e.rad", &ReadOptions::default())
        .unwrap_err()
        .to_string()
}

#[test]
fn error_classes_name_file_and_line() {
    let e = err("void plastic x\n0\n0\n5 1 1 1\n");
    assert!(e.starts_with("e.rad:4: unexpected end of file"), "{e}");
    let e = err("\nvoid plastic x\n0\n0\nfive 1 1 1 1 1\n");
    assert!(
        e.starts_with("e.rad:5: bad real argument count 'five'"),
        "{e}"
    );
    let e = err("void plastic x\n0\n0\n3 1 zz 1\n");
    assert!(
        e.starts_with("e.rad:4: real argument 2 'zz' is not a number"),
        "{e}"
    );
    let e = err("void plastic x\n0\n1 2.5\n0\n");
    assert!(e.starts_with("e.rad:3: integer argument 1"), "{e}");
    let e = err("void plastik x 0 0 0\n");
    assert!(
        e.starts_with("e.rad:1: unknown primitive type 'plastik'"),
        "{e}"
    );
    let e = err("void plastic\n");
    assert!(
        e.starts_with("e.rad:1: unexpected end of file: missing identifier"),
        "{e}"
    );
    let e = err("void plastic x 1 'abc\n");
    assert!(e.starts_with("e.rad:1: unterminated"), "{e}");
    let e = err("\n\n!mkillum 3 21 12 +s\n");
    assert_eq!(
        e,
        "e.rad:3: inline command 'mkillum' needs --allow-commands (or TESSERA_ALLOW_COMMANDS=1): !mkillum 3 21 12 +s"
    );
    let e = err("\n!gendaylit 3 21 12 -W 600 100 -i 60\n");
    assert_eq!(
        e,
        "e.rad:2: inline command 'gendaylit' needs --allow-commands (or TESSERA_ALLOW_COMMANDS=1) (gendaylit option -i is not built in): !gendaylit 3 21 12 -W 600 100 -i 60"
    );
    let e = err("!genbox m b 1 2 3 -r .1 -i\n");
    assert!(
        e.contains("needs --allow-commands") && e.contains("-i"),
        "{e}"
    );
    let e = err("!genbox m b 1 2\n");
    assert!(e.starts_with("e.rad:1: genbox: too few"), "{e}");
    let e = err("!xform -t 1 2 3\n");
    assert!(e.contains("e.rad:1: xform: no file"), "{e}");
    let e = err("\n!xform -t 1 0 0 /nonexistent/file.rad\n");
    assert!(
        e.starts_with("e.rad:2: cannot read scene file '/nonexistent/file.rad'"),
        "{e}"
    );
    let e = err("!xform -t 1 0 0 scene.oct\n");
    assert!(
        e.starts_with("e.rad:1: 'scene.oct' looks like an octree"),
        "{e}"
    );
}

#[test]
fn missing_and_octree_top_level_files() {
    let o = ReadOptions::default();
    let e = read_scene_files(&["/nonexistent/x.rad".to_string()], &o).unwrap_err();
    assert!(matches!(e, SceneError::Io { .. }));
    assert!(
        e.to_string().starts_with("/nonexistent/x.rad: cannot read"),
        "{e}"
    );
    // Octrees are read; a missing one is an I/O error naming it.
    let e = read_scene_files(&["/nonexistent/a.oct".to_string()], &o).unwrap_err();
    assert!(
        e.to_string().starts_with("/nonexistent/a.oct: cannot read"),
        "{e}"
    );
}

#[test]
fn recursion_loop_is_an_error() {
    let d = scene_dir();
    let e = read_scene_files(
        &[d.path().join("loop.rad").to_string_lossy().into_owned()],
        &opts(d.path()),
    )
    .unwrap_err();
    assert!(matches!(e, SceneError::Recursion { .. }));
    let s = e.to_string();
    assert!(s.contains("loop.rad:2: recursion too deep"), "{s}");
}

#[test]
fn commands_run_only_when_allowed() {
    let mut o = ReadOptions::default();
    assert!(parse_scene_text("!echo void plastic x 0 0 5 1 1 1 0 0\n", "c", &o).is_err());
    o.allow_commands = true;
    let p = parse_scene_text("\n!echo void plastic x 0 0 5 1 1 1 0 0\n", "c", &o).unwrap();
    assert_eq!(p.len(), 1);
    assert_eq!(
        &*p[0].loc.file,
        "<command: echo void plastic x 0 0 5 1 1 1 0 0>"
    );
    let e = parse_scene_text("\n!exit 3\n", "c", &o).unwrap_err();
    assert!(
        e.to_string()
            .starts_with("c:2: inline command '!exit 3' failed"),
        "{e}"
    );
    let e = parse_scene_text("!echo void plastic x 0 0 2 1\n", "c", &o).unwrap_err();
    assert!(e.to_string().starts_with("<command: echo"), "{e}");
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn genbox_matches_real_genbox() {
    let Some(bin) = skip() else { return };
    let d = scene_dir();
    for args in [
        "m b 1 2 3",
        "m b 1 2 3 -i",
        "sky_blue room 10 5 8 -i",
        "m b 1 2 3 -b .1",
        "m b 1.5 2 .7 -i -b .2",
        "m b 1 2 3 -r .1",
        "m b 4 2 3 -b .3 -r .25",
        "m b 4 2 3 -r .25 -b .3",
    ] {
        let words: Vec<&str> = args.split(' ').collect();
        let real = run_real(&bin, "genbox", &words, d.path());
        let real = parse_scene_text(&real, "real", &ReadOptions::default()).unwrap();
        let ours = parse_scene_text(&format!("!genbox {args}\n"), "ours", &opts(d.path())).unwrap();
        assert_same(&ours, &real, &format!("genbox {args}"));
    }
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn xform_matches_real_xform() {
    let Some(bin) = skip() else { return };
    let d = scene_dir();
    for args in [
        "-t 1 2 3",
        "-rx 30",
        "-ry 45",
        "-rz 60",
        "-s 2.5",
        "-mx",
        "-my",
        "-mz",
        "-s -1",
        "-t 1 2 3 -rx 30 -s 2 -mz",
        "-mx -my",
        "-I -t 1 0 0",
        "-I -mx -s 3",
        "-n pre -m newmod -rz 90",
        "-c -e -mx -ry 20",
        "-i 2 -rx 30 -t 1 2 3",
        "-t 1 0 0 -i 2 -rx 30 -i 3 -s 1.1",
        "-a 3 -t 1 0 0",
        "-n pre -a 3 -i 1 -t 1 0 0",
        "-t 1 0 0 -a 2 -rz 90",
        "-n pre -a 2 -t 1 0 0 -a 3 -t 0 1 0 -i 2 -rx 3",
        "-a 2 -t 0 0 1 -a 2 -mx -ry 10",
        "-I -a 2 -mz",
    ] {
        for files in ["base.rad", "nested.rad", "base.rad nested.rad"] {
            let mut words: Vec<&str> = vec!["-e"];
            words.extend(args.split(' '));
            words.extend(files.split(' '));
            let real = run_real(&bin, "xform", &words, d.path());
            let real = parse_scene_text(&real, "real", &ReadOptions::default())
                .unwrap_or_else(|e| panic!("parse real xform {args}: {e}"));
            let ours =
                parse_scene_text(&format!("!xform {args} {files}\n"), "ours", &opts(d.path()))
                    .unwrap_or_else(|e| panic!("ours {args}: {e}"));
            assert_same(&ours, &real, &format!("xform {args} {files}"));
        }
    }
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn nested_xform_of_nested_file() {
    let Some(bin) = skip() else { return };
    let d = scene_dir();
    std::fs::write(
        d.path().join("outer.rad"),
        "!xform -n mid -a 2 -t 0 5 0 nested.rad\n!xform -I -s 2 base.rad\n",
    )
    .unwrap();
    let real = run_real(
        &bin,
        "xform",
        &["-e", "-n", "top", "-my", "-rz", "15", "outer.rad"],
        d.path(),
    );
    let real = parse_scene_text(&real, "real", &ReadOptions::default()).unwrap();
    let ours = parse_scene_text(
        "!xform -n top -my -rz 15 outer.rad",
        "ours",
        &opts(d.path()),
    )
    .unwrap();
    assert_same(&ours, &real, "nested");
}

fn data(p: &str) -> String {
    format!("{}/tests/scenes/{p}", env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn examp_expands_like_flat_file() {
    let o = ReadOptions::default();
    let ours = read_scene_files(&[data("examp/examp")], &o).unwrap();
    let flat = read_scene_files(&[data("examp/examp.flat.rad")], &o).unwrap();
    assert_same(&ours, &flat, "examp");
    assert_eq!(ours[1].name, "room.1540");
    assert!(ours[1].loc.file.ends_with("examp/examp"));
    assert_eq!(ours[1].loc.line, 10);
}

/// The daffodil's `genrev … | xform -rx -90` and `genworm` are built in: it reads without
/// `--allow-commands`, primitive for primitive as the flat file made by the real programs.
#[test]
fn daffodil_reads_with_builtin_generators() {
    let o = ReadOptions::default();
    let ours = read_scene_files(&[data("daffodil/daffodil")], &o).unwrap();
    let flat = read_scene_files(&[data("daffodil/daffodil.flat.rad")], &o).unwrap();
    let moved = parse_scene_text(
        &format!("!xform -rz -40 -t 50 40 20 {}\n", data("daffodil/daffodil")),
        "x",
        &o,
    )
    .unwrap();
    assert_same(&moved, &flat, "daffodil");
    assert!(ours.iter().any(|p| p.name == "trumpet.16"));
    let room = read_scene_files(&[data("daffodil/room")], &o).unwrap();
    let flat = read_scene_files(&[data("daffodil/room.flat.rad")], &o).unwrap();
    assert_same(&room, &flat, "room");
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn daffodil_with_commands_matches_flat_file() {
    let Some(bin) = skip() else { return };
    let d = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(data("daffodil/daffodil")).unwrap();
    // Commands go through sh; give that shell Radiance's programs.
    let prefix = format!(
        "!export PATH={}:$PATH RAYPATH=.:{PYRAD_LIB}; ",
        bin.display()
    );
    let text = text.replace("\n!", &format!("\n{prefix}"));
    std::fs::write(d.path().join("daffodil"), text).unwrap();
    let o = ReadOptions {
        allow_commands: true,
        raypath: vec![d.path().to_path_buf()],
        ..ReadOptions::default()
    };
    let ours = parse_scene_text("!xform -rz -40 -t 50 40 20 daffodil", "x", &o).unwrap();
    let flat = read_scene_files(
        &[data("daffodil/daffodil.flat.rad")],
        &ReadOptions::default(),
    )
    .unwrap();
    assert_same(&ours, &flat, "daffodil");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]
    #[test]
    fn parser_never_panics(s in "[ -~\\n\\t]{0,200}") {
        let _ = parse_scene_text(&s, "p", &ReadOptions::default());
    }

    #[test]
    fn parser_never_panics_on_scene_like_text(
        words in proptest::collection::vec(
            prop_oneof![
                Just("void".to_string()), Just("polygon".to_string()), Just("plastic".to_string()),
                Just("0".to_string()), Just("3".to_string()), Just("1e-3".to_string()),
                Just("'a b'".to_string()), Just("#c\n".to_string()), Just("\n".to_string()),
                Just("!xform -t 1 0 0 x\n".to_string()), Just("!genbox m b 1 2 3 -b".to_string()),
                Just("!xform -a 2 -s".to_string()), Just("\\\n".to_string()), Just("\"".to_string()),
                "[a-z.+-]{1,4}",
            ],
            0..40)
    ) {
        let s = words.join(" ");
        let _ = parse_scene_text(&s, "p", &ReadOptions::default());
    }
}
