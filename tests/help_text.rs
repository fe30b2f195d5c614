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
