//! Every tool's `--help` fits a terminal (issue 27 item 20): no line over 100 characters,
//! options indented under their headings (a `\` line continuation in a help string once
//! ate the indentation), and the defaults a user needs shown (`tplan --lease`).

use std::process::Command;

fn help(exe: &str) -> String {
    let o = Command::new(exe).arg("--help").output().unwrap();
    assert!(o.status.success(), "{exe} --help failed");
    String::from_utf8(o.stdout).unwrap()
}

#[test]
fn every_help_fits_in_100_columns() {
    for (name, exe) in [
        ("tpict", env!("CARGO_BIN_EXE_tpict")),
        ("ttrace", env!("CARGO_BIN_EXE_ttrace")),
        ("tplan", env!("CARGO_BIN_EXE_tplan")),
        ("tpiece", env!("CARGO_BIN_EXE_tpiece")),
        ("tmerge", env!("CARGO_BIN_EXE_tmerge")),
        ("tassemble", env!("CARGO_BIN_EXE_tassemble")),
        ("tstat", env!("CARGO_BIN_EXE_tstat")),
        ("trad", env!("CARGO_BIN_EXE_trad")),
        ("tgrid", env!("CARGO_BIN_EXE_tgrid")),
    ] {
        let h = help(exe);
        assert!(h.lines().count() > 5, "{name}: {h}");
        for line in h.lines() {
            assert!(line.chars().count() <= 100, "{name}: too long: {line}");
            assert!(
                !line.starts_with('-'),
                "{name}: option line not indented: {line}"
            );
        }
    }
    let plan = help(env!("CARGO_BIN_EXE_tplan"));
    let lease = format!("[default: {}]", tessera::job::manifest::DEFAULT_LEASE);
    assert!(plan.contains(&lease), "tplan --help: no {lease}");
}

/// Slips a new user makes get one line that says the fix (issue 27 item 19): rpict's
/// options or the scene given to tplan without `--`, and the demo scene run from another
/// folder without its folder on RAYPATH.
#[test]
fn slips_of_a_new_user_get_one_line_that_says_the_fix() {
    let t = tempfile::tempdir().unwrap();
    let job = t.path().join("job");
    let job = job.to_str().unwrap();
    let demo = concat!(env!("CARGO_MANIFEST_DIR"), "/demo");
    let tplan = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_tplan"))
            .args(args)
            .output()
            .unwrap()
    };
    let vf = format!("{demo}/demo.vf");
    let rad = format!("{demo}/demo.rad");
    for (args, want) in [
        (
            vec!["-o", job, "-vf", &vf, &rad],
            "'-vf' is an rpict option",
        ),
        (
            vec!["-o", job, &rad],
            "demo.rad': put rpict's options and the scene after `--`",
        ),
    ] {
        let o = tplan(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.contains(want) && err.contains("-- -vf"), "{err}");
    }
    assert!(!t.path().join("job").exists());
    // The demo from the repository's root without RAYPATH: its room is beside it.
    let o = Command::new(env!("CARGO_BIN_EXE_tpict"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env_remove("RAYPATH")
        .args(["-vf", "demo/demo.vf", "-x", "8", "-y", "8", "demo/demo.rad"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("e.g. RAYPATH=.:demo"), "{err}");
}
