//! Command-line pieces shared by the benches that read `--name value` numbers
//! (`bench/lookups.rs`, `bench/vistable.rs`), included with `#[path]`.

/// The arguments after the program name, without the `--bench` that `cargo bench` adds.
pub fn bench_args() -> Vec<String> {
    std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect()
}

/// The number after option `name` from `it`: finite and above 0, or at least 0 when
/// `zero_ok`; else an error naming the option.
pub fn number<'a>(
    it: &mut impl Iterator<Item = &'a String>,
    name: &str,
    zero_ok: bool,
) -> Result<f64, String> {
    it.next()
        .and_then(|v| v.parse::<f64>().ok())
        .filter(|v| v.is_finite() && (*v > 0.0 || (zero_ok && *v == 0.0)))
        .ok_or(if zero_ok {
            format!("{name} needs a number of at least 0")
        } else {
            format!("{name} needs a positive number")
        })
}
