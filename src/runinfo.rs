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

/// Memory this process can still allocate, if known: the least of the machine's
/// `MemAvailable` (`/proc/meminfo`), what its control group's limit leaves (cgroup v2
/// `memory.max − memory.current`, v1 `memory.limit_in_bytes − memory.usage_in_bytes`: a
/// SLURM job's `--mem`) and what `RLIMIT_AS` leaves of its address space (`ulimit -v`).
pub fn available_memory() -> Option<u64> {
    least([mem_available(), cgroup_headroom(), address_space_headroom()])
}

/// The least of the limits that are known.
fn least(limits: [Option<u64>; 3]) -> Option<u64> {
    limits.into_iter().flatten().min()
}

/// A small text file of the system (at most 64 KiB).
fn small_text(path: &str) -> Option<String> {
    crate::safefile::read_text_bounded(std::path::Path::new(path), 64 << 10).ok()
}

/// `key:  N kB` of a `/proc` status file, in bytes.
fn kib_field(text: &str, key: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with(key))?;
    let kib: u64 = line[key.len()..].split_whitespace().next()?.parse().ok()?;
    kib.checked_mul(1024)
}

/// `MemAvailable` of `/proc/meminfo`.
fn mem_available() -> Option<u64> {
    kib_field(&small_text("/proc/meminfo")?, "MemAvailable:")
}

/// What this process's memory control group still allows (None: no limit, or unknown).
fn cgroup_headroom() -> Option<u64> {
    let groups = small_text("/proc/self/cgroup")?;
    cgroup_headroom_in(&groups, small_text)
}

/// [`cgroup_headroom`] over `/proc/self/cgroup`'s text `groups`, reading files with `read`.
fn cgroup_headroom_in(groups: &str, read: impl Fn(&str) -> Option<String>) -> Option<u64> {
    let num = |p: &str| -> Option<u64> { read(p)?.trim().parse().ok() };
    let mut best: Option<u64> = None;
    for line in groups.lines() {
        let mut f = line.splitn(3, ':');
        let (_, controllers, path) = (f.next()?, f.next()?, f.next()?);
        let path = path.trim_end_matches('/');
        let (limit, usage) = if controllers.is_empty() {
            let d = format!("/sys/fs/cgroup{path}");
            (
                num(&format!("{d}/memory.max")),
                num(&format!("{d}/memory.current")),
            )
        } else if controllers.split(',').any(|c| c == "memory") {
            let d = format!("/sys/fs/cgroup/memory{path}");
            (
                num(&format!("{d}/memory.limit_in_bytes")),
                num(&format!("{d}/memory.usage_in_bytes")),
            )
        } else {
            continue;
        };
        // "max" (v2) does not parse: no limit. v1 says "no limit" with a huge number.
        if let Some(l) = limit.filter(|&l| l < 1 << 60) {
            let left = l.saturating_sub(usage.unwrap_or(0));
            best = Some(best.map_or(left, |b| b.min(left)));
        }
    }
    best
}

/// What `RLIMIT_AS` leaves of this process's address space (None: unlimited or unknown).
#[cfg(unix)]
fn address_space_headroom() -> Option<u64> {
    let mut r = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: `r` is a valid, writable rlimit for the duration of the call.
    if unsafe { libc::getrlimit(libc::RLIMIT_AS, &mut r) } != 0 || r.rlim_cur == libc::RLIM_INFINITY
    {
        return None;
    }
    let used = kib_field(&small_text("/proc/self/status")?, "VmSize:").unwrap_or(0);
    #[allow(clippy::unnecessary_cast)] // rlim_t is not u64 everywhere
    let cur = r.rlim_cur as u64;
    Some(cur.saturating_sub(used))
}

#[cfg(not(unix))]
fn address_space_headroom() -> Option<u64> {
    None
}

/// Bytes a single-process picture of `x`×`y` pixels holds at once: the rendered rows and
/// the picture (12 bytes a pixel each) and its encoding, with room to spare.
pub const PICTURE_BYTES_PER_PIXEL: u64 = 32;

/// Refuse a picture that cannot fit in `available` bytes (None: unknown, then only an
/// overflowing size is refused), with what to do instead.
pub fn check_picture_memory(x: usize, y: usize, available: Option<u64>) -> Result<(), String> {
    check_memory_for(
        x,
        y,
        available,
        "lower -x/-y, or render it as a batch job (tplan splits it into tiles and \
         tassemble writes it)",
    )
}

/// Bytes an `x`×`y` picture needs ([`PICTURE_BYTES_PER_PIXEL`] each); None when that
/// overflows.
fn picture_bytes(x: usize, y: usize) -> Option<u64> {
    (x as u64)
        .checked_mul(y as u64)
        .and_then(|p| p.checked_mul(PICTURE_BYTES_PER_PIXEL))
}

/// Refuse a picture or tile of `x`×`y` pixels that cannot fit in `available` bytes (None:
/// unknown, then only an overflowing size is refused); `advice` says what to do instead.
pub fn check_memory_for(
    x: usize,
    y: usize,
    available: Option<u64>,
    advice: &str,
) -> Result<(), String> {
    let need = picture_bytes(x, y);
    let gib = |b: u64| b as f64 / (1u64 << 30) as f64;
    match (need, available) {
        (None, _) => Err(format!("a {x}x{y} picture is too large to address")),
        (Some(n), Some(a)) if n > a => Err(format!(
            "a {x}x{y} picture needs about {:.1} GiB of memory and {:.1} GiB are available: \
             {advice}",
            gib(n),
            gib(a)
        )),
        _ => Ok(()),
    }
}

/// Pictures needing less than this many bytes are not checked against the memory left by
/// [`check_memory_if_large`]: a process with less than 16 MiB to spare fails anyway, and
/// the check reads five system files.
pub const UNCHECKED_PICTURE_BYTES: u64 = 16 << 20;

/// [`check_memory_for`] with [`available_memory`], asked only when the `x × y` picture needs
/// at least [`UNCHECKED_PICTURE_BYTES`].
pub fn check_memory_if_large(x: usize, y: usize, advice: &str) -> Result<(), String> {
    match picture_bytes(x, y) {
        Some(n) if n < UNCHECKED_PICTURE_BYTES => Ok(()),
        _ => check_memory_for(x, y, available_memory(), advice),
    }
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

/// The clock `id` in nanoseconds (`clock_gettime`), or None.
#[cfg(unix)]
fn clock_nanos(id: libc::clockid_t) -> Option<u64> {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, writable timespec for the duration of the call.
    let rc = unsafe { libc::clock_gettime(id, &mut ts) };
    (rc == 0).then(|| {
        (ts.tv_sec.max(0) as u64)
            .saturating_mul(1_000_000_000)
            .saturating_add(ts.tv_nsec.max(0) as u64)
    })
}

/// User + system CPU seconds of this process (all threads), or None. The process CPU-time
/// clock (`clock_gettime(CLOCK_PROCESS_CPUTIME_ID)`): nanosecond resolution and no file to
/// open, so a worker can read it twice per tile (`/proc/self/stat` counts in 10 ms ticks and
/// costs an open, a read and a close each time).
#[cfg(unix)]
pub fn process_cpu_seconds() -> Option<f64> {
    clock_nanos(libc::CLOCK_PROCESS_CPUTIME_ID).map(|n| n as f64 * 1e-9)
}

/// CPU nanoseconds the calling thread has used (`CLOCK_THREAD_CPUTIME_ID`), or 0 where
/// unknown: time spent descheduled (more threads than cores) does not count.
#[cfg(unix)]
pub fn thread_cpu_nanos() -> u64 {
    clock_nanos(libc::CLOCK_THREAD_CPUTIME_ID).unwrap_or(0)
}

/// CPU nanoseconds of the calling thread: unknown on this platform.
#[cfg(not(unix))]
pub fn thread_cpu_nanos() -> u64 {
    0
}

/// User + system CPU seconds of this process: unknown on this platform.
#[cfg(not(unix))]
pub fn process_cpu_seconds() -> Option<f64> {
    None
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
        assert!(check_picture_memory(640, 480, Some(1 << 30)).is_ok());
        let e = check_picture_memory(100_000, 100_000, Some(24 << 30)).unwrap_err();
        assert!(e.contains("298.0 GiB") && e.contains("tplan"), "{e}");
        assert!(check_picture_memory(usize::MAX, 3, None).is_err());
        assert!(check_picture_memory(100_000, 100_000, None).is_ok());
        assert_eq!(n, cores * MAX_THREADS_PER_CORE);
        assert!(w.unwrap().contains("10000000 threads requested"));
    }

    /// Small pictures are not checked (no system files read); large ones are, and one too
    /// large to address is always refused.
    #[test]
    fn only_large_pictures_ask_for_memory() {
        assert!(check_memory_if_large(64, 64, "x").is_ok());
        assert!(check_memory_if_large(usize::MAX, 3, "x").is_err());
        let side = ((UNCHECKED_PICTURE_BYTES / PICTURE_BYTES_PER_PIXEL) as f64).sqrt() as usize;
        assert!((side * side) as u64 * PICTURE_BYTES_PER_PIXEL <= UNCHECKED_PICTURE_BYTES);
        assert!(check_memory_if_large(side - 1, side - 1, "x").is_ok());
    }

    /// A SLURM job's `--mem` (a control group's limit) bounds the memory a process may use:
    /// v2 (`0::/path`) and v1 (`N:memory:/path`), "max" and v1's huge "no limit".
    #[test]
    fn control_group_limits_are_read() {
        let files = |map: &'static [(&'static str, &'static str)]| {
            move |p: &str| {
                map.iter()
                    .find(|(k, _)| *k == p)
                    .map(|(_, v)| v.to_string())
            }
        };
        let v2 = files(&[
            ("/sys/fs/cgroup/slurm/job1/memory.max", "4294967296\n"),
            ("/sys/fs/cgroup/slurm/job1/memory.current", "1073741824\n"),
        ]);
        assert_eq!(cgroup_headroom_in("0::/slurm/job1\n", v2), Some(3 << 30));
        let unlimited = files(&[
            ("/sys/fs/cgroup/user/memory.max", "max\n"),
            ("/sys/fs/cgroup/user/memory.current", "10\n"),
        ]);
        assert_eq!(cgroup_headroom_in("0::/user\n", unlimited), None);
        let v1 = files(&[
            (
                "/sys/fs/cgroup/memory/job/memory.limit_in_bytes",
                "2147483648",
            ),
            (
                "/sys/fs/cgroup/memory/job/memory.usage_in_bytes",
                "3221225472",
            ),
            (
                "/sys/fs/cgroup/memory/user/memory.limit_in_bytes",
                "9223372036854771712",
            ),
        ]);
        // Over its limit already: nothing left.
        let groups = "5:cpu,cpuacct:/job\n4:memory:/job\n";
        assert_eq!(cgroup_headroom_in(groups, v1), Some(0));
        assert_eq!(cgroup_headroom_in("4:memory:/user\n", v1), None);
        assert_eq!(cgroup_headroom_in("garbage", v1), None);
        // The least known limit wins. (Comparing this machine's answer with a second read
        // of MemAvailable raced with the other tests' allocations: it failed once in CI.)
        assert_eq!(least([Some(5 << 30), None, Some(3 << 30)]), Some(3 << 30));
        assert_eq!(least([None, Some(7), None]), Some(7));
        assert_eq!(least([None, None, None]), None);
        if mem_available().is_some() {
            assert!(available_memory().is_some());
        }
    }
}

/// Longest word an error message shows whole; longer ones are cut in the middle.
const MAX_SHOWN_WORD: usize = 120;

/// An error message made safe to print: control characters other than newline and tab
/// are escaped (`\u{0}`), and a word longer than 120 characters (a 30 MB token from bad
/// input) keeps its first 80 and last 20 characters around a note of its length.
pub fn printable(msg: &str) -> String {
    let mut out = String::with_capacity(msg.len().min(1 << 16));
    let mut word = String::new();
    let flush = |word: &mut String, out: &mut String| {
        let n = word.chars().count();
        if n > MAX_SHOWN_WORD {
            let head: String = word.chars().take(80).collect();
            let tail: String = word.chars().skip(n - 20).collect();
            out.push_str(&format!("{head}…[{n} characters]…{tail}"));
        } else {
            out.push_str(word);
        }
        word.clear();
    };
    for c in msg.chars() {
        if c.is_whitespace() {
            flush(&mut word, &mut out);
            if c == '\n' || c == '\t' || c == ' ' {
                out.push(c);
            } else {
                out.push_str(&c.escape_default().to_string());
            }
        } else if c.is_control() {
            word.push_str(&c.escape_default().to_string());
        } else {
            word.push(c);
        }
    }
    flush(&mut word, &mut out);
    out
}

#[cfg(test)]
mod printable_tests {
    use super::printable;

    #[test]
    fn long_words_are_cut_and_control_bytes_escaped() {
        assert_eq!(printable("a.rad:3: bad\tvalue"), "a.rad:3: bad\tvalue");
        let long = format!("x{}y", "9".repeat(30_000_000));
        let p = printable(&format!("option -x: '{long}' is not a number"));
        assert!(p.len() < 300, "{}", p.len());
        assert!(p.contains("[30000004 characters]") && p.starts_with("option -x: 'x999"));
        assert!(p.ends_with("99y' is not a number"), "{p}");
        assert_eq!(printable("nul \0 here"), "nul \\u{0} here");
    }
}
