//! `tstat`: see `tessera::job::cli`.
fn main() {
    std::process::exit(tessera::job::cli::tstat_main());
}
