//! Atomic file output.
//!
//! A picture is first written to a temporary file in the destination's own directory (so the
//! final rename stays on one file system), flushed to disk, and only then given its real name.
//! Readers (and other processes claiming frames) therefore see either no file or a complete one,
//! never a partial file; on any error the temporary file is removed.
//!
//! The temporary file is named `.<name>.<random>.tmp` and created with mode `0666` less the
//! umask, so the finished file has the same permissions as one made by `open(2)`/`creat(2)`.

use std::fs::File;
use std::io::{self, Write};
use std::path::Path;

use tempfile::NamedTempFile;

/// Create a temporary file next to `path`.
fn temp_beside(path: &Path) -> io::Result<NamedTempFile> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let name = path.file_name().ok_or_else(|| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("{}: not a file name", path.display()),
        )
    })?;
    let prefix = format!(".{}.", name.to_string_lossy());
    let mut b = tempfile::Builder::new();
    b.prefix(&prefix).suffix(".tmp");
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        b.permissions(std::fs::Permissions::from_mode(0o666));
    }
    b.tempfile_in(dir)
}

/// Fill a temporary file beside `path` with `f`, then flush it to disk.
fn fill(path: &Path, f: impl FnOnce(&mut File) -> io::Result<()>) -> io::Result<NamedTempFile> {
    let mut tmp = temp_beside(path)?;
    f(tmp.as_file_mut())?;
    tmp.as_file_mut().flush()?;
    tmp.as_file().sync_all()?;
    Ok(tmp)
}

/// Create `path`'s content atomically: `f` writes into a NamedTempFile in the same directory,
/// which is renamed over `path` on success; on error the temp is removed. An existing `path` is
/// replaced.
pub fn write_atomic(path: &Path, f: impl FnOnce(&mut File) -> io::Result<()>) -> io::Result<()> {
    let tmp = fill(path, f)?;
    tmp.persist(path).map(drop).map_err(|e| e.error)
}

/// Like [`write_atomic`] but fails with `AlreadyExists` if `path` exists, for rpict's "-o never
/// clobbers" and `-S` frame claiming.
///
/// The existence check is made twice: before `f` runs (so no work is wasted on a file that is
/// already there) and atomically when the file is given its name (`renameat2(RENAME_NOREPLACE)`,
/// or a hard link where that is unsupported, e.g. on NFS), so of several processes racing for the
/// same name exactly one succeeds and the others' temporary files are removed.
pub fn write_atomic_noclobber(
    path: &Path,
    f: impl FnOnce(&mut File) -> io::Result<()>,
) -> io::Result<()> {
    if path.symlink_metadata().is_ok() {
        return Err(exists(path));
    }
    let tmp = fill(path, f)?;
    tmp.persist_noclobber(path).map(drop).map_err(|e| {
        if e.error.kind() == io::ErrorKind::AlreadyExists {
            exists(path)
        } else {
            e.error
        }
    })
}

fn exists(path: &Path) -> io::Error {
    io::Error::new(
        io::ErrorKind::AlreadyExists,
        format!("{} already exists", path.display()),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn writes_and_replaces() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("a.txt");
        write_atomic(&p, |f| f.write_all(b"one")).unwrap();
        write_atomic(&p, |f| f.write_all(b"two")).unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"two");
        assert_eq!(names(d.path()), ["a.txt"]);
    }

    #[test]
    fn error_leaves_nothing() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("a.txt");
        let e = write_atomic(&p, |f| {
            f.write_all(b"partial")?;
            Err(io::Error::other("boom"))
        })
        .unwrap_err();
        assert_eq!(e.to_string(), "boom");
        assert!(names(d.path()).is_empty());
        // An existing file survives a failed rewrite untouched.
        std::fs::write(&p, b"old").unwrap();
        assert!(write_atomic(&p, |_| Err(io::Error::other("boom"))).is_err());
        assert_eq!(std::fs::read(&p).unwrap(), b"old");
        assert_eq!(names(d.path()), ["a.txt"]);
    }

    #[test]
    fn noclobber() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("f.hdr");
        write_atomic_noclobber(&p, |f| f.write_all(b"first")).unwrap();
        let mut called = false;
        let e = write_atomic_noclobber(&p, |f| {
            called = true;
            f.write_all(b"second")
        })
        .unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::AlreadyExists);
        assert!(!called);
        assert_eq!(std::fs::read(&p).unwrap(), b"first");
        assert_eq!(names(d.path()), ["f.hdr"]);
        // The file appears while f runs: the final step still refuses, and cleans up.
        let q = d.path().join("g.hdr");
        let e = write_atomic_noclobber(&q, |f| {
            std::fs::write(&q, b"other")?;
            f.write_all(b"mine")
        })
        .unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::AlreadyExists);
        assert_eq!(std::fs::read(&q).unwrap(), b"other");
        assert_eq!(names(d.path()), ["f.hdr", "g.hdr"]);
    }

    #[cfg(unix)]
    #[test]
    fn permissions_follow_umask_not_0600() {
        use std::os::unix::fs::PermissionsExt;
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("p.hdr");
        write_atomic(&p, |f| f.write_all(b"x")).unwrap();
        let mode = std::fs::metadata(&p).unwrap().permissions().mode() & 0o777;
        // Same as a freshly created ordinary file.
        let q = d.path().join("q");
        std::fs::write(&q, b"x").unwrap();
        assert_eq!(
            mode,
            std::fs::metadata(&q).unwrap().permissions().mode() & 0o777
        );
    }

    #[test]
    fn relative_name_without_directory() {
        // A bare file name resolves its temp file in the current directory; just check that a
        // path without a file name is refused cleanly.
        assert!(write_atomic(Path::new("/"), |_| Ok(())).is_err());
    }
}
