//! `tgrid`: see `tessera::ttrace::grid`.
fn main() {
    std::process::exit(tessera::ttrace::grid::tgrid_main());
}
