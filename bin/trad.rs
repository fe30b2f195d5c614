//! `trad`: see `tessera::job::rad`.
fn main() {
    std::process::exit(tessera::job::rad::trad_main());
}
