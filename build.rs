//! Build script: tells the tests whether real Radiance is installed, so that the tests
//! comparing against it are reported as ignored (with how to install it) when it is not,
//! instead of passing without checking anything. It looks where `tests/common` does:
//! `TESSERA_RADIANCE_BIN`, `PATH`, the venv that `.ci/run` makes. With
//! `TESSERA_REQUIRE_RADIANCE=1` (CI) the tests always run, and fail if Radiance is missing.

use std::path::{Path, PathBuf};

fn has_radiance(dir: &Path) -> bool {
    dir.join("rpict").is_file() && dir.join("oconv").is_file()
}

fn venv_bins() -> Vec<PathBuf> {
    let mut out = vec![PathBuf::from(
        "/opt/radvenv/lib/python3.11/site-packages/pyradiance/bin",
    )];
    let venv = std::env::var_os("TESSERA_VENV")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache/tessera-venv")));
    if let Some(lib) = venv.map(|v| v.join("lib")) {
        if let Ok(rd) = std::fs::read_dir(lib) {
            for e in rd.flatten() {
                out.push(e.path().join("site-packages/pyradiance/bin"));
            }
        }
    }
    out
}

fn main() {
    println!("cargo::rustc-check-cfg=cfg(radiance)");
    for v in [
        "TESSERA_RADIANCE_BIN",
        "TESSERA_REQUIRE_RADIANCE",
        "TESSERA_VENV",
        "PATH",
    ] {
        println!("cargo::rerun-if-env-changed={v}");
    }
    println!("cargo::rerun-if-changed=build.rs");
    let required = std::env::var("TESSERA_REQUIRE_RADIANCE").as_deref() == Ok("1");
    let mut dirs: Vec<PathBuf> = std::env::var_os("TESSERA_RADIANCE_BIN")
        .map(PathBuf::from)
        .into_iter()
        .collect();
    if let Some(path) = std::env::var_os("PATH") {
        dirs.extend(std::env::split_paths(&path));
    }
    dirs.extend(venv_bins());
    if required || dirs.iter().any(|d| has_radiance(d)) {
        println!("cargo::rustc-cfg=radiance");
    }
}
