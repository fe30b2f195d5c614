//! Facts about the running program that every tool shares: the software name written into
//! pictures and files, the render thread count, the process's CPU time, this process's
//! origin id for ambient values, and frame file names (`%d` patterns).

use anyhow::{bail, Result};

/// Version string printed by `-version` and written as `SOFTWARE=`.
pub const SOFTWARE: &str = concat!("Tessera tpict ", env!("CARGO_PKG_VERSION"));

/// Render threads per available core at most: more only add switching (`-n 10000` took
/// 91 s for a 16×16 picture).
pub const MAX_THREADS_PER_CORE: usize = 4;

/// Number of render threads: the option (`-n`, `--threads`), else `SLURM_CPUS_PER_TASK`,
/// else all cores; at most [`MAX_THREADS_PER_CORE`] per available core. The second value
/// is a warning when a request was cut down.
pub fn thread_count(opt: Option<usize>) -> (usize, Option<String>) {
    let cores = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1);
    let wanted = opt.map(|n| n.max(1)).or_else(|| {
        std::env::var("SLURM_CPUS_PER_TASK")
            .ok()
            .and_then(|v| v.trim().parse::<usize>().ok())
            .filter(|&n| n > 0)
    });
    let Some(n) = wanted else {
        return (cores, None);
    };
    let cap = cores.saturating_mul(MAX_THREADS_PER_CORE);
    if n > cap {
        let w = format!(
            "{n} threads requested, {cores} cores available: using {cap} \
             ({MAX_THREADS_PER_CORE} per core)"
        );
        return (cap, Some(w));
    }
    (n, None)
}

/// This machine's host name (empty when unknown).
pub fn host_name() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .map(|h| h.trim().to_string())
        .unwrap_or_default()
}

/// An id for this process's ambient values: a hash of host name, process id and start time.
pub fn process_origin_id() -> u64 {
    let host = host_name();
    let t = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_nanos() as u64)
        .unwrap_or(0);
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in host
        .bytes()
        .chain(std::process::id().to_le_bytes())
        .chain(t.to_le_bytes())
    {
        h ^= b as u64;
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h
}

/// User + system CPU seconds of this process (Linux `/proc/self/stat`), or None.
pub fn process_cpu_seconds() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the parenthesised command name; utime and stime are fields 14 and 15.
    let rest = &text[text.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let utime: f64 = f.get(11)?.parse().ok()?;
    let stime: f64 = f.get(12)?.parse().ok()?;
    Some((utime + stime) / 100.0)
}

/// Expand a printf-style frame pattern (`%d`, `%03d`, `%%`).
pub fn frame_name(pattern: &str, n: u32) -> Result<String> {
    let mut out = String::new();
    let mut chars = pattern.chars().peekable();
    let mut used = false;
    while let Some(c) = chars.next() {
        if c != '%' {
            out.push(c);
            continue;
        }
        if chars.peek() == Some(&'%') {
            chars.next();
            out.push('%');
            continue;
        }
        let mut spec = String::new();
        while let Some(&d) = chars.peek() {
            if d.is_ascii_digit() {
                spec.push(d);
                chars.next();
            } else {
                break;
            }
        }
        match chars.next() {
            Some('d') | Some('i') => {
                let zero = spec.starts_with('0');
                let width: usize = spec.parse().unwrap_or(0);
                if zero {
                    out.push_str(&format!("{n:0width$}"));
                } else {
                    out.push_str(&format!("{n:width$}"));
                }
                used = true;
            }
            other => bail!(
                "output pattern '{pattern}': unsupported conversion '%{spec}{}'",
                other.map(String::from).unwrap_or_default()
            ),
        }
    }
    if !used {
        bail!("output pattern '{pattern}' needs a %d for the frame number with -S");
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thread_requests_are_capped_per_core() {
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        assert_eq!(thread_count(Some(1)), (1, None));
        assert_eq!(thread_count(Some(0)).0, 1);
        let (n, w) = thread_count(Some(10_000_000));
        assert_eq!(n, cores * MAX_THREADS_PER_CORE);
        assert!(w.unwrap().contains("10000000 threads requested"));
    }
}
