//! `tpiece`: see `tessera::job::cli`.
fn main() {
    std::process::exit(tessera::job::cli::tpiece_main());
}
