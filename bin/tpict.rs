//! `tpict`: render Radiance scene files as Radiance's rpict does.
fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    std::process::exit(tessera::tpict::run(&args));
}
