//! `ttrace`: see `tessera::ttrace`.
fn main() {
    std::process::exit(tessera::ttrace::ttrace_main());
}
