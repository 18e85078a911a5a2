//! The one atomic file writer that every file the programs write goes through:
//! solution files, checkpoints, statistics, previews and screenshots, reflectance
//! tables, sweep reports.
//!
//! [`write_atomically`] (and [`write_atomically_buffered`], which streams through a
//! buffer) writes into a new temporary file in the target's own
//! directory (so the final rename never crosses a file system), flushes it to disk
//! (`fsync`), renames it over the target and flushes the directory, so that the
//! rename itself survives a power cut. A crash, a full disk or a failing encoder
//! therefore never leaves a partial file under the final name, the previous file
//! stays as it was until the rename, and a reader that has the old file mapped
//! keeps its (unchanged) inode. On any error the temporary file is removed.

// The one writer that may create and rename files: every other goes through it.
#![allow(clippy::disallowed_methods)]

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

/// A step of an atomic write failed; `path` is the target (or, for the temporary
/// file's creation, its directory).
#[derive(Debug, thiserror::Error)]
#[error("cannot {action} {}", path.display())]
pub struct AtomicWriteError {
    pub action: &'static str,
    pub path: PathBuf,
    #[source]
    pub source: io::Error,
}

/// Writes `path` atomically: `write` fills a temporary file beside it (with the
/// permissions a newly created file gets, 0666 less the umask on Unix), which is
/// then flushed to disk, renamed over `path`, and the directory flushed.
///
/// The target is untouched if `write` or any later step fails, and the temporary
/// file is removed. `write` may seek (the solution writer patches its metadata at
/// the end); it should buffer small writes itself.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut File) -> io::Result<()>,
) -> Result<(), AtomicWriteError> {
    let fail = |action: &'static str, at: &Path| {
        let at = at.to_path_buf();
        move |source| AtomicWriteError {
            action,
            path: at,
            source,
        }
    };
    if path.file_name().is_none() {
        return Err(AtomicWriteError {
            action: "write",
            path: path.to_path_buf(),
            source: io::Error::new(io::ErrorKind::InvalidInput, "the path does not name a file"),
        });
    }
    let dir = match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent,
        _ => Path::new("."),
    };
    let mut temp = temp_builder()
        .tempfile_in(dir)
        .map_err(fail("create a temporary file in", dir))?;
    write(temp.as_file_mut()).map_err(fail("write", path))?;
    temp.as_file()
        .sync_all()
        .map_err(fail("flush to disk", path))?;
    // On failure `persist` hands the temporary file back inside the error; dropping
    // it deletes the file.
    temp.persist(path)
        .map_err(|e| fail("rename into place", path)(e.error))?;
    sync_directory(dir);
    Ok(())
}

/// Writes `bytes` to `path` atomically (see [`write_atomically`]).
pub fn write_bytes_atomically(path: &Path, bytes: &[u8]) -> Result<(), AtomicWriteError> {
    write_atomically(path, |file| file.write_all(bytes))
}

/// Writes `path` atomically through a buffer: `write` streams into a
/// [`BufWriter`] over the temporary file (so a large file is written section by
/// section, never assembled in memory first), which is then flushed, synced,
/// renamed and its directory synced exactly as by [`write_atomically`].
///
/// `write` may seek the `BufWriter` (seeking flushes it first), for instance to
/// patch a length or checksum in a header once the content is known. A failure
/// inside `write`, or while flushing its last buffered bytes, leaves the target
/// untouched and removes the temporary file.
pub fn write_atomically_buffered(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<&mut File>) -> io::Result<()>,
) -> Result<(), AtomicWriteError> {
    write_atomically(path, |file| {
        // 1 MiB: large enough that sections of f64s go out in few system calls.
        let mut buffered = BufWriter::with_capacity(1 << 20, file);
        write(&mut buffered)?;
        // `into_inner` flushes and reports a failed flush (dropping a BufWriter
        // would swallow it).
        buffered.into_inner().map_err(|e| e.into_error())?;
        Ok(())
    })
}

/// Hidden temporary names (`.tmp` + random), created with the mode an ordinary
/// `File::create` uses rather than tempfile's private 0600, so that the renamed
/// file is as readable as any other output.
fn temp_builder() -> tempfile::Builder<'static, 'static> {
    let mut builder = tempfile::Builder::new();
    builder.prefix(".tmp").suffix(".partial");
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    builder
}

/// Makes the rename durable (POSIX: the directory entry lives in the directory's
/// data). Failure only weakens durability after a power cut, not atomicity, and
/// some file systems refuse to sync a directory, so it is not reported.
fn sync_directory(dir: &Path) {
    #[cfg(unix)]
    if let Ok(d) = File::open(dir) {
        let _ = d.sync_all();
    }
    #[cfg(not(unix))]
    let _ = dir;
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::{Seek, SeekFrom};

    fn entries(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn writes_the_bytes_and_leaves_nothing_else() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.txt");
        write_bytes_atomically(&path, b"first").unwrap();
        write_bytes_atomically(&path, b"second").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"second");
        assert_eq!(entries(dir.path()), ["out.txt"]);
    }

    #[test]
    fn failing_midway_leaves_the_target_untouched_and_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.sol");
        std::fs::write(&path, b"old contents").unwrap();
        let err = write_atomically(&path, |file| {
            file.write_all(b"half of the new")?;
            Err(io::Error::other("encoder failed"))
        })
        .unwrap_err();
        assert_eq!(err.action, "write");
        assert_eq!(err.path, path);
        assert!(err.to_string().contains("out.sol"), "{err}");
        assert_eq!(std::fs::read(&path).unwrap(), b"old contents");
        assert_eq!(entries(dir.path()), ["out.sol"]);
    }

    #[test]
    fn a_missing_directory_is_named_and_nothing_is_created() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("no/such/dir/out.png");
        let err = write_bytes_atomically(&path, b"x").unwrap_err();
        assert_eq!(err.action, "create a temporary file in");
        assert_eq!(err.path, dir.path().join("no/such/dir"));
        assert!(entries(dir.path()).is_empty());
    }

    #[test]
    fn a_directory_in_the_way_fails_the_rename_and_removes_the_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("taken");
        std::fs::create_dir(&path).unwrap();
        std::fs::write(path.join("inside"), b"kept").unwrap();
        let err = write_bytes_atomically(&path, b"x").unwrap_err();
        assert_eq!(err.action, "rename into place");
        assert_eq!(entries(dir.path()), ["taken"]);
        assert_eq!(std::fs::read(path.join("inside")).unwrap(), b"kept");
    }

    #[cfg(unix)]
    #[test]
    fn the_file_gets_ordinary_permissions() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.json");
        write_bytes_atomically(&path, b"{}").unwrap();
        let atomic = std::fs::metadata(&path).unwrap().permissions().mode() & 0o777;
        let plain_path = dir.path().join("plain");
        std::fs::write(&plain_path, b"{}").unwrap();
        let plain = std::fs::metadata(&plain_path).unwrap().permissions().mode() & 0o777;
        assert_eq!(atomic, plain, "atomic {atomic:o}, File::create {plain:o}");
    }

    #[test]
    fn buffered_writes_stream_seek_and_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("state.ckpt");
        // 3 MiB in 1 KiB pieces: more than the 1 MiB buffer, so the data goes
        // through several flushes; then the length is patched at the front, as the
        // checkpoint writer patches its header.
        let piece: Vec<u8> = (0..1024u32).map(|i| (i * 7 % 251) as u8).collect();
        write_atomically_buffered(&path, |w| {
            w.write_all(&0u64.to_le_bytes())?;
            for _ in 0..3 * 1024 {
                w.write_all(&piece)?;
            }
            let end = w.stream_position()?;
            w.seek(SeekFrom::Start(0))?;
            w.write_all(&(end - 8).to_le_bytes())?;
            Ok(())
        })
        .unwrap();
        let back = std::fs::read(&path).unwrap();
        assert_eq!(back.len(), 8 + 3 * 1024 * 1024);
        assert_eq!(u64::from_le_bytes(back[..8].try_into().unwrap()), 3 << 20);
        assert!(back[8..].chunks(1024).all(|c| c == piece.as_slice()));
        assert_eq!(entries(dir.path()), ["state.ckpt"]);
    }

    #[test]
    fn buffered_failure_midway_leaves_the_target_untouched_and_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("state.ckpt");
        std::fs::write(&path, b"previous checkpoint").unwrap();
        // 2 MiB are already written (and partly flushed to the temporary file)
        // when the encoder fails.
        let err = write_atomically_buffered(&path, |w| {
            w.write_all(&vec![0xAB; 2 << 20])?;
            Err(io::Error::other("section encoder failed"))
        })
        .unwrap_err();
        assert_eq!(err.action, "write");
        assert!(err.to_string().contains("state.ckpt"), "{err}");
        assert_eq!(std::fs::read(&path).unwrap(), b"previous checkpoint");
        assert_eq!(entries(dir.path()), ["state.ckpt"]);
    }
}
