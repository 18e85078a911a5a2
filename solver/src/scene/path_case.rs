//! A file named with the wrong letter case. Scenes authored on Windows (or
//! macOS) name `SP_LUK.JPG` where the file is `sp_luk.JPG`, which opens there
//! and not on a case-sensitive file system; the folder is listed once and the
//! name matched ignoring ASCII case.

use std::path::{Path, PathBuf};

/// The files in `path`'s folder whose names equal its file name ignoring ASCII
/// case (and differ from it in case), sorted; empty when there are none or the
/// folder cannot be listed. Only the last component is matched: the folders on
/// the way must be spelled as they are.
#[allow(clippy::disallowed_methods)] // An edge: an importer looks in the folder its scene names.
pub(crate) fn case_variants(path: &Path) -> Vec<PathBuf> {
    let Some(name) = path.file_name().and_then(|n| n.to_str()) else {
        return Vec::new();
    };
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let Ok(entries) = std::fs::read_dir(folder) else {
        return Vec::new();
    };
    let mut found: Vec<PathBuf> = entries
        .filter_map(Result::ok)
        .filter(|entry| {
            entry
                .file_name()
                .to_str()
                .is_some_and(|n| n != name && n.eq_ignore_ascii_case(name))
        })
        .map(|entry| path.with_file_name(entry.file_name()))
        .filter(|candidate| candidate.is_file())
        .collect();
    found.sort();
    found
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_the_files_that_differ_only_in_case() {
        let dir = tempfile::tempdir().unwrap();
        for name in ["sp_luk.png", "Sp_Luk.png", "sp_luk.jpg", "other.png"] {
            std::fs::write(dir.path().join(name), b"x").unwrap();
        }
        std::fs::create_dir(dir.path().join("SP_LUK.PNG.d")).unwrap();
        let asked = dir.path().join("SP_LUK.PNG");
        assert_eq!(
            case_variants(&asked),
            [dir.path().join("Sp_Luk.png"), dir.path().join("sp_luk.png")]
        );
        // The exact spelling is not its own variant; a folder is no texture.
        assert!(case_variants(&dir.path().join("other.png")).is_empty());
        assert!(case_variants(&dir.path().join("sp_luk.png.D")).is_empty());
        assert!(case_variants(&dir.path().join("none/x.png")).is_empty());
    }
}
