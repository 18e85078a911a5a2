//! Small file helpers for the `solve` command: atomic writes and derived paths.
//!
//! Every file the command writes (checkpoint, stats JSON, preview PNG) goes through
//! [`write_atomic`], so a crash or Ctrl-C never leaves a half-written file under its
//! final name (brief, "Standards"). The solution file itself is written by
//! [`write_solution`], through `format::write_solution`, which is atomic in the
//! same way.

use anyhow::Context;
use solution::format::{split_to_storage_range, Solution, PORTABLE_STORAGE_RANGE};
use std::path::{Path, PathBuf};

/// Writes a solution file (the final one, or the partial one a checkpoint
/// leaves for a viewer), whichever method produced it, with every batch cut to
/// the storage-buffer range every Vulkan device binds
/// ([`split_to_storage_range`]), so that no runtime refuses a batch as too
/// large to bind; `solution` is left as written. `what` names the file in the
/// error.
pub fn write_solution(path: &Path, solution: &mut Solution, what: &str) -> anyhow::Result<()> {
    write_solution_within(path, solution, what, PORTABLE_STORAGE_RANGE)
}

/// [`write_solution`] with the batch limit as a parameter (tests use a small one).
#[allow(clippy::disallowed_methods)] // An edge: writes the solution.
fn write_solution_within(
    path: &Path,
    solution: &mut Solution,
    what: &str,
    max_bytes: u64,
) -> anyhow::Result<()> {
    // The exposure key from the final radiance: the Gauss–Seidel and
    // global-cube solves replace the batches after `Solver::to_solution`.
    if solution.lighting.is_some() {
        let key = crate::solve::exposure_key(solution);
        if let Some(lighting) = solution.lighting.as_mut() {
            lighting.exposure_key = key;
        }
    }
    solution.batches = split_to_storage_range(std::mem::take(&mut solution.batches), max_bytes);
    solution::format::write_solution(path, solution)
        .with_context(|| format!("writing {what} {}", path.display()))
}

/// Writes `bytes` to `path` atomically through the contract crate's one writer
/// ([`solution::atomic::write_atomically`]: temporary file in the same folder,
/// fsync, rename, directory fsync).
#[allow(clippy::disallowed_methods)] // An edge: writes the statistics and previews.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    solution::atomic::write_bytes_atomically(path, bytes)
        .with_context(|| format!("writing {}", path.display()))
}

/// `OUT.checkpoint`: the full output name with `.checkpoint` appended, so that
/// `box.sol` and `box.sol2` never share a checkpoint.
pub fn checkpoint_path(out: &Path) -> PathBuf {
    let mut name = out.as_os_str().to_owned();
    name.push(".checkpoint");
    PathBuf::from(name)
}

/// Creates the folder that will hold `path` when it is missing, and checks that a
/// file can be created there (by creating and removing a temporary file beside it,
/// as [`write_atomic`] will).
pub fn check_writable(path: &Path) -> anyhow::Result<()> {
    if path.file_name().is_none() || path.is_dir() {
        anyhow::bail!("output {} is not a file name", path.display());
    }
    if let Some(parent) = path.parent() {
        if !parent.as_os_str().is_empty() && !parent.exists() {
            #[allow(clippy::disallowed_methods)] // An edge: makes the folder the output goes in.
            std::fs::create_dir_all(parent)
                .with_context(|| format!("creating folder {}", parent.display()))?;
        }
    }
    let dir = match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent,
        _ => Path::new("."),
    };
    let probe = tempfile::Builder::new()
        .prefix(".tmp")
        .tempfile_in(dir)
        .with_context(|| format!("cannot write {}", path.display()))?;
    probe
        .close()
        .with_context(|| format!("removing the probe file in {}", dir.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atomic_write_replaces_and_leaves_no_temp_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.json");
        write_atomic(&path, b"first").unwrap();
        write_atomic(&path, b"second").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"second");
        let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(names.len(), 1, "only the final file remains");
    }

    #[test]
    fn atomic_write_into_missing_folder_names_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("missing").join("a.json");
        let err = write_atomic(&path, b"x").unwrap_err();
        assert!(format!("{err:#}").contains("a.json"), "{err:#}");
    }

    #[test]
    fn writability_is_checked_and_folders_created() {
        let dir = tempfile::tempdir().unwrap();
        let nested = dir.path().join("a").join("b.sol");
        check_writable(&nested).unwrap();
        assert!(dir.path().join("a").is_dir());
        assert_eq!(std::fs::read_dir(dir.path().join("a")).unwrap().count(), 0);
        let err = check_writable(dir.path()).unwrap_err();
        assert!(format!("{err:#}").contains("not a file name"), "{err:#}");
    }

    /// The solve command writes every file through the cut: the shared box
    /// room (`solution::view::fixture`, one batch) under a limit of 40
    /// vertices (12 bytes each) reads back as several batches, each within
    /// the limit, drawing every triangle it had.
    #[test]
    fn solution_files_are_written_with_batches_cut_to_the_limit() {
        let mut room = solution::view::fixture::box_room();
        let triangles = room.batches[0].indices.len() / 3;
        assert!(room.batches[0].vertices.len() > 40);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("room.sol");
        write_solution_within(&path, &mut room, "solution", 40 * 12).unwrap();
        let read = solution::format::read_solution(&path).unwrap();
        assert!(read.batches.len() > 1);
        assert!(read.batches.iter().all(|b| b.vertices.len() <= 40));
        let read_triangles: usize = read.batches.iter().map(|b| b.indices.len() / 3).sum();
        assert_eq!(read_triangles, triangles);
    }

    #[test]
    fn checkpoint_path_appends_suffix() {
        assert_eq!(
            checkpoint_path(Path::new("out/box.sol")),
            PathBuf::from("out/box.sol.checkpoint")
        );
    }
}
