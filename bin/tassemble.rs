//! `tassemble`: see `tessera::job::cli`.
fn main() {
    std::process::exit(tessera::job::cli::tassemble_main());
}
