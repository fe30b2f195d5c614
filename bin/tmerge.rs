//! `tmerge`: see `tessera::job::cli`.
fn main() {
    std::process::exit(tessera::job::cli::tmerge_main());
}
