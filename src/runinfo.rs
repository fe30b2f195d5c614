//! Facts about the running program that every tool shares: the software name written into
//! pictures and files, the render thread count, the process's CPU time, this process's
//! origin id for ambient values, and frame file names (`%d` patterns).

use anyhow::{bail, Result};

/// Version string printed by `-version` and written as `SOFTWARE=`.
pub const SOFTWARE: &str = concat!("Tessera tpict ", env!("CARGO_PKG_VERSION"));

/// Number of render threads: the option (`-n`, `--threads`), else `SLURM_CPUS_PER_TASK`,
/// else all cores.
pub fn thread_count(opt: Option<usize>) -> usize {
    if let Some(n) = opt {
        return n.max(1);
    }
    if let Ok(v) = std::env::var("SLURM_CPUS_PER_TASK") {
        if let Ok(n) = v.trim().parse::<usize>() {
            if n > 0 {
                return n;
            }
        }
    }
    std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1)
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
