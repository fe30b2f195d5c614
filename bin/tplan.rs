//! `tplan`: see `tessera::job::cli`.
fn main() {
    std::process::exit(tessera::job::cli::tplan_main());
}
