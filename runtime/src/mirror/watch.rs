//! `--watch`: notices when the solver rewrites the solution file.
//!
//! The solver writes by rename (a new file under the final name), so a file
//! whose modification time, size or inode changed is a new, complete file; the
//! reader still validates it, and a file that fails is kept out (the old
//! solution stays on screen) and read again after [`RETRY_AFTER`], in case it
//! was replaced in place by some other writer. Polling `stat` costs a few
//! microseconds, far less than a frame, and needs no inotify.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant, SystemTime};

/// How soon a file that failed to load is tried again when it has not changed.
pub const RETRY_AFTER: Duration = Duration::from_secs(1);

/// What identifies one version of the file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Stamp {
    modified: Option<SystemTime>,
    len: u64,
    inode: u64,
}

impl Stamp {
    /// The file's current stamp (None when it cannot be read: being replaced).
    pub fn of(path: &Path) -> Option<Stamp> {
        let meta = std::fs::metadata(path).ok()?;
        #[cfg(unix)]
        let inode = std::os::unix::fs::MetadataExt::ino(&meta);
        #[cfg(not(unix))]
        let inode = 0;
        Some(Stamp {
            modified: meta.modified().ok(),
            len: meta.len(),
            inode,
        })
    }
}

/// Tracks the version on screen and the last one that failed.
#[derive(Debug)]
pub struct Watch {
    path: PathBuf,
    loaded: Option<Stamp>,
    failed: Option<(Stamp, Instant)>,
}

impl Watch {
    /// Starts watching `path`, whose current version is the one on screen.
    pub fn new(path: &Path) -> Watch {
        Watch {
            path: path.to_path_buf(),
            loaded: Stamp::of(path),
            failed: None,
        }
    }

    /// The stamp of a version worth loading now, if there is one.
    pub fn poll(&self, now: Instant) -> Option<Stamp> {
        let stamp = Stamp::of(&self.path)?;
        if Some(stamp) == self.loaded {
            return None;
        }
        match self.failed {
            Some((bad, when)) if bad == stamp && now.duration_since(when) < RETRY_AFTER => None,
            _ => Some(stamp),
        }
    }

    /// Records that `stamp` is now on screen.
    pub fn loaded(&mut self, stamp: Stamp) {
        self.loaded = Some(stamp);
        self.failed = None;
    }

    /// Records that `stamp` failed to load; true the first time for this
    /// version (so the error is printed once, not at every retry).
    pub fn failed(&mut self, stamp: Stamp, now: Instant) -> bool {
        let first = self.failed.map(|(s, _)| s) != Some(stamp);
        self.failed = Some((stamp, now));
        first
    }

    pub fn path(&self) -> &Path {
        &self.path
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_renamed_file_is_new_and_a_failure_is_retried_later() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("s.sol");
        std::fs::write(&path, b"one").unwrap();
        let mut watch = Watch::new(&path);
        let t0 = Instant::now();
        assert_eq!(watch.poll(t0), None, "the first version is on screen");
        // A new file renamed over it (same size: the inode tells).
        let tmp = dir.path().join("s.sol.tmp");
        std::fs::write(&tmp, b"two").unwrap();
        std::fs::rename(&tmp, &path).unwrap();
        let stamp = watch.poll(t0).expect("a renamed file is a new version");
        assert!(watch.failed(stamp, t0), "first failure is reported");
        assert_eq!(watch.poll(t0 + Duration::from_millis(10)), None);
        let later = t0 + RETRY_AFTER + Duration::from_millis(1);
        assert_eq!(watch.poll(later), Some(stamp), "retried after a while");
        assert!(!watch.failed(stamp, later), "not reported twice");
        watch.loaded(stamp);
        assert_eq!(watch.poll(later), None);
        // A missing file (mid-replacement) is not a version.
        std::fs::remove_file(&path).unwrap();
        assert_eq!(watch.poll(later), None);
    }
}
