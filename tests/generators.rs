//! The built-in generators (`src/scene/gen/`) against the real Radiance programs: each
//! generator on a sweep of arguments, both outputs read by the scene reader and compared
//! primitive by primitive (type, name, modifier, strings, numbers within 1e-6 relative or
//! 1e-9 absolute). Pipelines into `xform` are built in too. Skips (with a message) when
//! Radiance is not installed.

mod common;

use std::path::{Path, PathBuf};

use tessera::scene::{parse_scene_text, Primitive, ReadOptions};

/// Radiance's library folder next to its binaries.
fn lib_dir(bin: &Path) -> PathBuf {
    bin.parent().map(|p| p.join("lib")).unwrap_or_default()
}

/// Run a real command line through `sh` in `dir` (Radiance's programs first on PATH).
fn run_real(bin: &Path, cmd: &str, dir: &Path) -> Result<String, String> {
    let path = format!(
        "{}:{}",
        bin.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let o = std::process::Command::new("sh")
        .arg("-c")
        .arg(cmd)
        .current_dir(dir)
        .env("PATH", path)
        .env("RAYPATH", format!(".:{}", lib_dir(bin).display()))
        .output()
        .map_err(|e| e.to_string())?;
    if !o.status.success() {
        return Err(format!(
            "'{cmd}' failed: {}",
            String::from_utf8_lossy(&o.stderr)
        ));
    }
    Ok(String::from_utf8_lossy(&o.stdout).into_owned())
}

fn opts(bin: &Path, dir: &Path) -> ReadOptions {
    ReadOptions {
        allow_commands: false,
        raypath: vec![dir.to_path_buf(), lib_dir(bin)],
        ..ReadOptions::default()
    }
}

/// Within 1e-6 relative, or one unit of the sixth decimal: the skies' directions and
/// Perez coefficients are printed with `%f`, and a value at a rounding boundary may round
/// either way.
fn close(a: f64, b: f64) -> bool {
    let d = (a - b).abs();
    d <= 1e-6 * a.abs().max(b.abs()) + 1e-9 || (d <= 1.000001e-6 && b == (b * 1e6).round() / 1e6)
}

/// The first difference between two primitive lists, if any.
fn difference(ours: &[Primitive], real: &[Primitive]) -> Option<String> {
    if ours.len() != real.len() {
        return Some(format!(
            "{} primitives, real {}: ours {:?}, real {:?}",
            ours.len(),
            real.len(),
            ours.iter().map(|p| &p.name).collect::<Vec<_>>(),
            real.iter().map(|p| &p.name).collect::<Vec<_>>()
        ));
    }
    for (k, (a, b)) in ours.iter().zip(real).enumerate() {
        let same = a.modifier == b.modifier
            && a.ptype == b.ptype
            && a.name == b.name
            && a.sargs == b.sargs
            && a.iargs == b.iargs
            && a.rargs.len() == b.rargs.len()
            && a.rargs.iter().zip(&b.rargs).all(|(x, y)| close(*x, *y));
        if !same {
            return Some(format!(
                "primitive {k}:\n ours {} {} {} {:?} {:?}\n real {} {} {} {:?} {:?}",
                a.modifier,
                a.ptype,
                a.name,
                a.sargs,
                a.rargs,
                b.modifier,
                b.ptype,
                b.name,
                b.sargs,
                b.rargs
            ));
        }
    }
    None
}

/// Compare the built-in expansion of each command line with the real programs' output;
/// returns the number of primitives compared. Every mismatch is listed before failing.
fn check_all(bin: &Path, dir: &Path, cmds: &[String]) -> usize {
    let mut failures = Vec::new();
    let mut count = 0;
    for cmd in cmds {
        let real = match run_real(bin, cmd, dir) {
            Ok(t) => t,
            Err(e) => {
                failures.push(e);
                continue;
            }
        };
        let real = match parse_scene_text(&real, "real", &ReadOptions::default()) {
            Ok(p) => p,
            Err(e) => {
                failures.push(format!("{cmd}: real output does not parse: {e}"));
                continue;
            }
        };
        let ours = match parse_scene_text(&format!("!{cmd}\n"), "ours", &opts(bin, dir)) {
            Ok(p) => p,
            Err(e) => {
                failures.push(format!("{cmd}: {e}"));
                continue;
            }
        };
        count += real.len();
        if let Some(d) = difference(&ours, &real) {
            failures.push(format!("{cmd}: {d}"));
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} commands differ:\n{}",
        failures.len(),
        cmds.len(),
        failures.join("\n")
    );
    count
}

fn setup() -> Option<(PathBuf, tempfile::TempDir)> {
    let bin = common::radiance_bin()?;
    Some((bin, tempfile::tempdir().unwrap()))
}

const SITES: [&str; 5] = [
    "",
    "-a 40 -o 105 -m 105",
    "-a -33.9 -o -151.2 -m -150",
    "-a 60 -o -10 -m -15",
    "-a 0 -o 0 -m 0",
];

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn gensky_dates_times_sites_and_sky_types() {
    let Some((bin, dir)) = setup() else { return };
    let mut cmds = Vec::new();
    for (month, day) in [(1, 5), (3, 21), (6, 21), (9, 1), (12, 31)] {
        for time in ["6", "8.5", "12", "15:30", "+10", "19"] {
            for (k, site) in SITES.iter().enumerate() {
                for (j, sky) in ["+s", "-s", "+i", "-i", "-c", "-u"].iter().enumerate() {
                    // Every sky type on every site, not every combination of all.
                    if (j + k + month as usize).is_multiple_of(3) || time == "12" {
                        cmds.push(format!("gensky {month} {day} {time} {sky} {site}"));
                    }
                }
            }
        }
    }
    let n = check_all(&bin, dir.path(), &cmds);
    eprintln!("gensky: {} commands, {n} primitives equal", cmds.len());
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn gensky_options() {
    let Some((bin, dir)) = setup() else { return };
    let mut cmds: Vec<String> = [
        "3 21 12 -t 4",
        "3 21 12 -t 1.5 +i",
        "3 21 12 -b 20",
        "3 21 12 -c -b 20",
        "3 21 12 -B 100",
        "3 21 12 -u -B 80",
        "3 21 12 +i -B 80",
        "3 21 12 -r 1e6",
        "3 21 12 -R 500",
        "3 21 12 +i -R 500",
        "3 21 12 -r 0",
        "3 21 12 -B 50 -b 3",
        "3 21 12 -b 3 -B 50",
        "3 21 12 -R 50 -r 3",
        "3 21 12 -g 0",
        "3 21 12 -g .5 -c",
        "3 21 12 -y 2020",
        "7 4 9:45 -y 1999 -a 45 -o 75 -m 75",
        "3 21 +12:30 -y 2021",
        "3 21 12 -y 2020 -m 90",
        "3 21 12:30EST",
        "6 21 14:30PDT -a 37.8 -o 122.3 -m 120",
        "6 21 14:30pdt -a 37.8 -o 122.3 -i",
        "10 10 11CET -a 48.1 -o -11.6",
        "3 21 12:30NZST -a -41 -o -175",
        "2 30 12",
        "3 21 12:75",
        "3 21 25",
        "3 21 .5",
        "3 21 12:",
        "3 21 12 -s -c",
        "3 21 12 -c +s",
        "3 21 12 +c",
        "3 21 12 -a 89 -o 0 -m 0",
        "6 21 12 -a 10",
        "6 21 12 -a 23.44 -o 0 -m 0",
    ]
    .iter()
    .map(|a| format!("gensky {a}"))
    .collect();
    for ang in [
        "88 10",
        "89 10 -i",
        "88 10 -c",
        "88 10 -u",
        "-1 10",
        "-1 10 -c",
        "-1 10 -i",
        "0 10",
        "0.5 10",
        "5 10 +i",
        "-5 10 +i",
        "30 10 -b 0",
        "30 -170 -g .3",
        "45 90 -t 6",
        "60 -90 +i -r 2e6",
    ] {
        cmds.push(format!("gensky -ang {ang}"));
    }
    let n = check_all(&bin, dir.path(), &cmds);
    eprintln!(
        "gensky options: {} commands, {n} primitives equal",
        cmds.len()
    );
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn gendaylit_conditions() {
    let Some((bin, dir)) = setup() else { return };
    let mut cmds: Vec<String> = [
        "3 21 12 -W 600 100",
        "3 21 12 -W 0 100",
        "3 21 12 -W 600 0",
        "3 21 12 -W 1 300",
        "3 21 12 -W 900 40",
        "3 21 12 -W 300 150",
        "3 21 12 -W 100 250",
        "3 21 12 -G 400 100",
        "3 21 12 -G 50 200",
        "3 21 12 -L 60000 15000",
        "3 21 12 -L 20000 25000",
        "3 21 12 -P 3 .2",
        "3 21 12 -E 500",
        "3 21 12 -E 150",
        "3 21 12 -E 800",
        "3 21 12 -W 600 100 -O 1",
        "3 21 12 -W 600 100 -O 2",
        "3 21 12 -W 600 100 -s",
        "3 21 12 -W 600 100 -c",
        "3 21 12 -W 600 100 -g .5 -d 10",
        "3 21 12 -W 600 100 -w -t 3 -b 2",
        "3 21 5 -W 600 100",
        "3 21 20 -W 600 100",
        "3 21 +12 -W 600 100 -a 50 -o 10 -m 15",
        "3 21 12 -y 2020 -W 600 100",
        "3 21 12.7 -W 600 100",
        "3 21 12:30PDT -W 600 100",
        "6 21 7 -W 300 200",
        "6 21 18 -W 200 150 -a 40 -o 105 -m 105",
        "12 21 9 -W 500 80 -a 55 -o -12 -m -15",
        "9 1 16 -W 700 60 -a -33.9 -o -151.2 -m -150",
        "1 15 12 -W 400 200 -a 70 -o -20 -m -15",
    ]
    .iter()
    .map(|a| format!("gendaylit {a}"))
    .collect();
    for ang in [
        "30 20 -W 500 50",
        "30 20 -W 500 50 -O 1",
        "30 20",
        "30 20 -W 500 50 -W 600 100",
        "30 20 -W 500 50 -P 2 .2",
        "89 0 -W 500 100",
        "-5 10 -W 600 100",
        "0 10 -W 600 1",
        "1 10 -W 600 1",
        "10 20 -P 1.02 .5",
        "10 20 -P 1.1 .05",
        "10 20 -P 1.3 .1",
        "10 20 -P 1.7 .1",
        "10 20 -P 2.5 .4",
        "10 20 -P 5 .1",
        "10 20 -P 7 .1",
        "10 20 -P 11 .1",
        "45 -60 -L 80000 20000 -O 2",
        "60 120 -G 600 120 -s -g .1",
    ] {
        cmds.push(format!("gendaylit -ang {ang}"));
    }
    let n = check_all(&bin, dir.path(), &cmds);
    eprintln!("gendaylit: {} commands, {n} primitives equal", cmds.len());
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn genprism_genblinds() {
    let Some((bin, dir)) = setup() else { return };
    std::fs::write(dir.path().join("v.txt"), "0 0\n1 0\n1 1\n0.5 1.5\n").unwrap();
    let mut cmds: Vec<String> = [
        "mat p 3 0 0 1 0 0 1 -l 0 0 2",
        "mat p 3 0 0 1 0 0 1 -l 1 1 -2",
        "mat p 3 0 0 0 1 1 0 -c",
        "mat p 3 0 0 0 1 1 0 -e -c",
        "mat p 5 0 0 2 0 2.5 1 1 2 -0.5 1 -l .2 -.1 .7 -e",
        "mat p VFILE",
        "mat p VFILE -l 0 0 -1 -c",
    ]
    .iter()
    .map(|a| {
        // The vertex file by its full path: the test's working directory is not `dir`.
        let v = dir.path().join("v.txt");
        format!("genprism {}", a.replace("VFILE", &v.display().to_string()))
    })
    .collect();
    for a in [
        "mat b 0.05 1 0.2 2 30",
        "mat b 0.05 1 0.2 2 -45",
        "mat b 0.1 2 1.5 20 0",
        "mat c 0.05 1 0.1 1 0 -r 0.05",
        "mat c 0.05 1 0.1 1 20 +r 0.1",
        "mat c 0.05 1 0.1 2 20 -r 0.5",
        "mat c 0.08 1.2 1 5 -30 +r 0.2",
    ] {
        cmds.push(format!("genblinds {a}"));
    }
    let n = check_all(&bin, dir.path(), &cmds);
    eprintln!(
        "genprism/genblinds: {} commands, {n} primitives equal",
        cmds.len()
    );
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn genrev_genworm() {
    let Some((bin, dir)) = setup() else { return };
    std::fs::write(
        dir.path().join("curve.cal"),
        "zz(t) = 2*t;\nrr(t) = 1 + .3*sin(3*PI*t);\n",
    )
    .unwrap();
    let mut cmds: Vec<String> = [
        "mat vase t '0.5+0.2*sin(PI*t)' 3",
        "mat d 0 1-t 2",
        "mat n t 1 2.6",
        "mat n t 1+t 2 -s",
        "mat n t '1+t*t' 3 -s",
        "mat n 't*t' 1 2 -s",
        "mat n 0 1-t 2 -s",
        "mat n 1-t 1 1 -s",
        "mat n 1-t 1+t 1 -s",
        "mat n 0 1 1 -s",
        "mat n 'z0*t' q 4 -e 'z0=2;q=1'",
        "mat n t 1 2 -e 'z(t)=5*t'",
        "mat n 'zz(t)' 'rr(t)' 12 -f curve.cal -s",
        "mat trumpet 'hermite(0,3,0,-5,t)' 'hermite(0,1.5,4,3,t)' 16",
        "mat b 'bezier(0,1,2,2,t)' 'bspline(0,1,1,0,t)' 7 -s",
        "mat w 'cos(2*PI*t)' '.5+sin(2*PI*t)' 9",
    ]
    .iter()
    .map(|a| format!("genrev {a}"))
    .collect();
    for a in [
        "mat w t 0 0 '0.2-0.1*t' 1",
        "mat w t 0 0 .1 3",
        "mat stem 'hermite(0,10,5,15,t)' 'hermite(-.5,-15,-20,-10,t)' 'hermite(0,5,0,5,t)' .15 10",
        "mat s 'cos(2*PI*t)' 'sin(2*PI*t)' t '.1+.05*sin(6*PI*t)' 20",
        "mat s 'x(t)' 0 0 'r(t)' 4 -e 'x(t)=t*t;r(t)=.2*(1-t)+.01'",
        "mat s 'zz(t)' 0 0 .1 2.5 -f curve.cal",
    ] {
        cmds.push(format!("genworm {a}"));
    }
    let n = check_all(&bin, dir.path(), &cmds);
    eprintln!(
        "genrev/genworm: {} commands, {n} primitives equal",
        cmds.len()
    );
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn gensurf_plain_smooth_inverted_valid() {
    let Some((bin, dir)) = setup() else { return };
    std::fs::write(
        dir.path().join("saddle.cal"),
        "sx(s,t) = 2*s - 1;\nsy(s,t) = 2*t - 1;\nsz(s,t) = sx(s,t)*sx(s,t) - sy(s,t)*sy(s,t);\n",
    )
    .unwrap();
    let mut cmds = Vec::new();
    for a in [
        "mat s s t 's*t' 1 2",
        "mat s s t 0 2 2",
        "mat s s t 's*t' 1 1 -i",
        "mat c 'cos(PI*s)' 'sin(PI*s)' t 2 1 -s",
        "mat c s t 's*s+t*t*t' 2 2 -s",
        "mat c s t 's*s+t*t*t' 1 2 -s",
        "mat c s t 's*s+t*t*t' 3 4 -s -i",
        "mat c s t 's*t' 1 1 -s",
        "mat c s t 's*t' 1 1 -s -i",
        "mat c s t 0 1 1 -s",
        "mat c s t 's*t*t' 1 1 -e 'valid(s,t)=if(s+t-1.5,-1,1)'",
        "mat c s t 's*t*t' 4 4 -e 'valid(s,t)=if(s+t-1.7,-1,1)'",
        "mat c s t 's*t*t' 3 3 -i -e 'valid(s,t)=if(.2+s-t,1,-1)'",
        "mat c s t 's*s+t*t*t' 1 1 -s -e 'valid(s,t)=if(s+.1,1,-1)'",
        "mat sad 'sx(s,t)' 'sy(s,t)' 'sz(s,t)' 6 5 -f saddle.cal",
        "mat sad 'sx(s,t)' 'sy(s,t)' 'sz(s,t)' 6 5 -f saddle.cal -s",
        "mat sph 'sin(PI*s)*cos(2*PI*t)' 'sin(PI*s)*sin(2*PI*t)' 'cos(PI*s)' 6 8 -s",
        "mat tor '(1+.3*cos(2*PI*s))*cos(2*PI*t)' '(1+.3*cos(2*PI*s))*sin(2*PI*t)' '.3*sin(2*PI*s)' 5 7",
    ] {
        cmds.push(format!("gensurf {a}"));
    }
    let n = check_all(&bin, dir.path(), &cmds);
    eprintln!("gensurf: {} commands, {n} primitives equal", cmds.len());
}

/// Generators piped into `xform` are built in too: the same primitives as the real
/// pipeline, and no `--allow-commands` needed.
#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn pipelines_into_xform() {
    let Some((bin, dir)) = setup() else { return };
    let cmds: Vec<String> = [
        "gensky 3 21 12 | xform -rz 30",
        "gendaylit 3 21 12 -W 600 100 | xform -n sky -rz -90",
        "genrev daf_yellow trumpet 'hermite(0,3,0,-5,t)' 'hermite(0,1.5,4,3,t)' 16 | xform -rx -90",
        "genrev m v t '1+t*t' 5 -s | xform -s 2 -t 1 2 3",
        "genprism m p 3 0 0 1 0 0 1 | xform -a 3 -t 2 0 0 | xform -m other -rz 45",
        "genbox m b 1 2 3 | xform -I -t 1 0 0",
        "genblinds m b .05 1 .5 5 30 | xform -rx 90",
        "gensurf m s s t 's*t' 2 2 -s | xform -mz",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let n = check_all(&bin, dir.path(), &cmds);
    eprintln!("pipelines: {} commands, {n} primitives equal", cmds.len());
}

/// Options that are not built in are reported so (the reader then runs the real program
/// with `--allow-commands`, or names the command and the option); invalid arguments are
/// errors naming the program.
#[test]
fn unsupported_and_bad_arguments() {
    use tessera::scene::gen::{generate, ArgError, GenContext};
    use tessera::scene::Location;
    let loc = Location::new("t", 1);
    let cx = GenContext {
        loc: &loc,
        raypath: &[],
        max_primitives: 1 << 22,
    };
    let run = |s: &str| {
        let w: Vec<String> = s.split_whitespace().map(String::from).collect();
        generate(&w, &cx).expect("a built-in generator")
    };
    for s in [
        "gendaylit 3 21 12 -W 600 100 -i 60",
        "gendaylit 3 21 12 -W 600 100 -C",
        "genprism m p 3 0 0 1 0 0 1 -r .1",
        "genbox m b 1 2 3 -r .1 -i",
        "gensurf m s s t - 2 2",
        "gensurf m s s t s*t 2 2 -s -e valid(s,t)=.5-s",
    ] {
        assert!(matches!(run(s), Err(ArgError::Unsupported(_))), "{s}");
    }
    for (s, msg) in [
        ("gensky 3 21", "gensky: too few"),
        ("gensky 13 21 12", "gensky: bad month"),
        ("gensky 3 21 12:30XYZ", "unknown time zone: XYZ"),
        ("gensky 3 21 +12PST", "bad time format"),
        ("gensky 3 21 12 -a", "missing value for -a"),
        ("gensky 3 21 12 -a x", "'x' is not a number"),
        ("gensky 3 21 12 -x", "unknown option: -x"),
        ("gensky -defaults", "-defaults"),
        ("gendaylit 3 21 12 -W 600", "missing value for -W"),
        ("gendaylit 3 21 12 -O 7", "-O takes"),
        ("genprism m p 2 0 0 1 1", "not enough vertices"),
        ("genprism m p 3 0 0 1 0 0 1 -l 0 0 0", "illegal extrusion"),
        ("genrev m r t 1 0", "nseg must be at least 1"),
        ("genrev m r t sqrt(-1-t) 2", "genrev: evaluating r(t)"),
        ("genworm m w t 0 0", "genworm: too few"),
        ("gensurf m s s t 0 2 2 -o", "Wavefront"),
        ("genblinds m b .05 1 .2 2", "genblinds: wrong number"),
        ("genblinds m b .5 1 .2 2 0 -r .1", "at least half the depth"),
    ] {
        match run(s) {
            Err(ArgError::Bad(e)) => assert!(e.contains(msg), "{s}: {e}"),
            other => panic!("{s}: {other:?}"),
        }
    }
}

/// Reading an inline command with an option that is not built in, without
/// `--allow-commands`, names the command and the option.
#[test]
fn unsupported_option_names_command_and_option() {
    let e = parse_scene_text(
        "\n!genprism m p 3 0 0 1 0 0 1 -r .1 | xform -rz 10\n",
        "e.rad",
        &ReadOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.starts_with("e.rad:2: inline command 'genprism' needs --allow-commands")
            && e.contains("genprism option -r"),
        "{e}"
    );
}

use proptest::prelude::*;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]
    /// No word list makes a generator panic.
    #[test]
    fn generator_arguments_never_panic(
        prog in proptest::sample::select(tessera::scene::gen::GENERATORS.to_vec()),
        words in proptest::collection::vec(
            proptest::prop_oneof![
                proptest::sample::select(vec![
                    "-s", "+s", "-i", "+i", "-c", "-u", "-ang", "-a", "-o", "-m", "-y", "-b",
                    "-B", "-r", "+r", "-R", "-g", "-t", "-W", "-G", "-L", "-E", "-P", "-O", "-d",
                    "-e", "-f", "-l", "-defaults", "-", "3", "21", "12:30", "+10", "12:30EST",
                    "0", "1", "2", "4", "-1", "0.5", "1e9", "1e308", "nan", "x", "t", "s*t",
                    "valid(s,t)=s-.5", "z(t)=t", "sqrt(-1)", "1/0", "t*t", "0 0", "87", "-90",
                    "hermite(0,1,0,0,t)", "a.cal",
                ]).prop_map(String::from),
                "[ -~]{0,6}",
            ],
            0..14,
        ),
    ) {
        use tessera::scene::gen::{generate, GenContext};
        let loc = tessera::scene::Location::new("p", 1);
        let cx = GenContext {
            loc: &loc,
            raypath: &[],
            max_primitives: 1 << 22,
        };
        let mut w = vec![prog.to_string()];
        w.extend(words);
        let _ = generate(&w, &cx);
    }
}
