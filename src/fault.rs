//! Fault injection for tests: hooks that make a worker behave as if a disk were full, so
//! that tests can check the error paths end to end through the real binaries.
//!
//! Compiled in only with the `fault-injection` feature, which only test builds turn on
//! (`Cargo.toml`'s dev-dependency on this package); in any other build [`injected`] is
//! `false` and reads nothing. The hooks and the tests that use them are listed in
//! docs/batch.md.

/// Whether the test environment asks for fault `name` (`TESSERA_FAULT_<name>` is set).
#[inline]
pub fn injected(name: &str) -> bool {
    #[cfg(feature = "fault-injection")]
    {
        std::env::var_os(format!("TESSERA_FAULT_{name}")).is_some()
    }
    #[cfg(not(feature = "fault-injection"))]
    {
        let _ = name;
        false
    }
}
