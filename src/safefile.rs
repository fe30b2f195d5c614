//! Opening and reading files that other users' processes share (a job directory): only
//! regular files are read, a FIFO never blocks the reader, a device is never read, a
//! symbolic link is not followed where the protocol names plain files, and no read goes
//! beyond the size the file's format allows.

use std::fs::{File, OpenOptions};
use std::io::{self, Read};
use std::os::unix::fs::OpenOptionsExt;
use std::path::Path;

/// Options to write a file that every user of a shared job directory may replace (mode
/// 0666 before the umask); the caller adds how it is created.
pub fn shared_write() -> std::fs::OpenOptions {
    let mut o = std::fs::OpenOptions::new();
    o.write(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        o.mode(0o666);
    }
    o
}

/// Open the directory `path` (for `fsync` after a rename): `O_DIRECTORY`, so a FIFO or
/// anything else put in its place is refused at once instead of blocking the open.
pub fn open_dir(path: &Path) -> io::Result<File> {
    OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_DIRECTORY | libc::O_NONBLOCK | libc::O_CLOEXEC)
        .open(path)
}

/// Open `path` for reading if it is a regular file. `follow = false` refuses a symbolic
/// link (`O_NOFOLLOW`); the open never blocks (`O_NONBLOCK`, so a FIFO opens at once and is
/// then refused as not regular).
pub fn open_regular(path: &Path, follow: bool) -> io::Result<File> {
    let mut flags = libc::O_NONBLOCK | libc::O_CLOEXEC;
    if !follow {
        flags |= libc::O_NOFOLLOW;
    }
    let f = OpenOptions::new()
        .read(true)
        .custom_flags(flags)
        .open(path)
        .map_err(|e| {
            if e.raw_os_error() == Some(libc::ELOOP) {
                io::Error::new(
                    io::ErrorKind::InvalidData,
                    "is a symbolic link, not a regular file",
                )
            } else {
                e
            }
        })?;
    let md = f.metadata()?;
    if !md.is_file() {
        return Err(io::Error::new(
            io::ErrorKind::InvalidData,
            "is not a regular file (a FIFO, device, socket or directory)",
        ));
    }
    Ok(f)
}

/// Read a whole regular file (not through a symbolic link) of at most `limit` bytes.
pub fn read_bounded(path: &Path, limit: u64) -> io::Result<Vec<u8>> {
    read_regular(path, limit, false)
}

/// [`read_bounded`], following a symbolic link (a user's own input files).
pub fn read_bounded_following(path: &Path, limit: u64) -> io::Result<Vec<u8>> {
    read_regular(path, limit, true)
}

fn read_regular(path: &Path, limit: u64, follow: bool) -> io::Result<Vec<u8>> {
    let f = open_regular(path, follow)?;
    let len = f.metadata()?.len();
    let too_big = || {
        io::Error::new(
            io::ErrorKind::InvalidData,
            format!("is larger than the {limit} bytes its format allows"),
        )
    };
    if len > limit {
        return Err(too_big());
    }
    let mut v = Vec::with_capacity(len as usize);
    f.take(limit + 1).read_to_end(&mut v)?;
    if v.len() as u64 > limit {
        return Err(too_big());
    }
    Ok(v)
}

/// [`read_bounded`] as UTF-8 text.
pub fn read_text_bounded(path: &Path, limit: u64) -> io::Result<String> {
    String::from_utf8(read_bounded(path, limit)?)
        .map_err(|_| io::Error::new(io::ErrorKind::InvalidData, "is not UTF-8 text"))
}

/// True when `path` is a regular file itself (not a symbolic link, FIFO or device).
pub fn is_plain_file(path: &Path) -> bool {
    std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_file())
}

/// Refuse a job file that is not a regular file (a symbolic link, FIFO or device: reading
/// it could block or never end), or a folder of the job's inputs holding one. A missing
/// path is left to the reader's own error.
pub fn check_plain_tree(path: &Path) -> anyhow::Result<()> {
    plain_tree(path, 0)
}

fn plain_tree(path: &Path, depth: usize) -> anyhow::Result<()> {
    let Ok(md) = std::fs::symlink_metadata(path) else {
        return Ok(());
    };
    let ft = md.file_type();
    if ft.is_file() {
        return Ok(());
    }
    if ft.is_dir() && depth < 16 {
        let list = std::fs::read_dir(path)
            .map_err(|e| anyhow::anyhow!("cannot list {}: {e}", path.display()))?;
        for e in list {
            plain_tree(&e?.path(), depth + 1)?;
        }
        return Ok(());
    }
    anyhow::bail!(
        "{}: not a regular file (a symbolic link, FIFO or device in the job directory is \
         never read)",
        path.display()
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn special_files_are_refused_without_blocking() {
        let t = tempfile::tempdir().unwrap();
        let d = t.path();
        std::fs::write(d.join("a"), "hello").unwrap();
        assert_eq!(read_text_bounded(&d.join("a"), 5).unwrap(), "hello");
        assert!(read_bounded(&d.join("a"), 4).is_err());
        std::os::unix::fs::symlink(d.join("a"), d.join("link")).unwrap();
        assert!(read_bounded(&d.join("link"), 100).is_err());
        assert!(open_regular(&d.join("link"), true).is_ok());
        std::os::unix::fs::symlink("/dev/zero", d.join("zero")).unwrap();
        assert!(open_regular(&d.join("zero"), true).is_err());
        let made = std::process::Command::new("mkfifo")
            .arg(d.join("fifo"))
            .status()
            .unwrap();
        assert!(made.success());
        let e = open_regular(&d.join("fifo"), true).unwrap_err();
        assert!(e.to_string().contains("not a regular file"), "{e}");
        assert!(!is_plain_file(&d.join("fifo")));
        assert!(!is_plain_file(&d.join("link")));
        assert!(is_plain_file(&d.join("a")));
    }
}
