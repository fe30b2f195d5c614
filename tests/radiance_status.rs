//! A summary line in the normal test output saying whether the comparisons against real
//! Radiance ran: tests that need Radiance pass silently when it is absent (their
//! "skipping" message is captured), so this target (no test harness, its output is not
//! captured) says so once. With `TESSERA_REQUIRE_RADIANCE=1` (CI) a missing Radiance fails.

mod common;

fn main() {
    let required = std::env::var("TESSERA_REQUIRE_RADIANCE").as_deref() == Ok("1");
    match common::radiance_bin_quiet() {
        Some(dir) => println!(
            "radiance_status: real Radiance found in {}: the comparisons against rpict, \
             rtrace, lookamb and getinfo ran",
            dir.display()
        ),
        None if required => {
            eprintln!("radiance_status: Radiance not found but TESSERA_REQUIRE_RADIANCE=1");
            std::process::exit(1);
        }
        None => println!(
            "radiance_status: SKIPPED - real Radiance not found (set TESSERA_RADIANCE_BIN or \
             put rpict on PATH): every comparison against Radiance passed without running"
        ),
    }
}
