//! A summary line in the normal test output saying whether the comparisons against real
//! Radiance ran. Tests that need Radiance are marked ignored when `build.rs` did not find
//! it (tests/README.md); this target (no test harness, its output is not captured) says so
//! once, and warns when Radiance was found at build time but is missing now (those tests
//! then return early). With `TESSERA_REQUIRE_RADIANCE=1` (CI) a missing Radiance fails.

mod common;

fn main() {
    let required = std::env::var("TESSERA_REQUIRE_RADIANCE").as_deref() == Ok("1");
    match common::radiance_bin_quiet() {
        Some(dir) if !cfg!(radiance) => println!(
            "radiance_status: SKIPPED - real Radiance is in {} but was not found when the \
             tests were built: the comparisons against it are ignored; set \
             TESSERA_RADIANCE_BIN={} (or touch build.rs) and rerun",
            dir.display(),
            dir.display()
        ),
        Some(dir) => println!(
            "radiance_status: real Radiance found in {}: the comparisons against rpict, \
             rtrace, lookamb and getinfo ran",
            dir.display()
        ),
        None if required => {
            eprintln!("radiance_status: Radiance not found but TESSERA_REQUIRE_RADIANCE=1");
            std::process::exit(1);
        }
        None if cfg!(radiance) => println!(
            "radiance_status: SKIPPED - real Radiance was found when the tests were built \
             but not now: the comparisons against Radiance returned early without checking \
             (set TESSERA_RADIANCE_BIN, see tests/README.md)"
        ),
        None => println!(
            "radiance_status: real Radiance not found: the comparisons against Radiance are \
             reported as ignored (install it as tests/README.md says, then rerun)"
        ),
    }
}
