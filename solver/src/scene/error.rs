//! The importer's error type. Every error names the file and, where the parser
//! knows them, the line and the item (face, polygon, material) that is wrong.

use super::{SourceRef, Warning};
use std::path::{Path, PathBuf};

/// Why a scene, geometry, material, config or display file cannot be imported.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file cannot be opened or read.
    #[error("cannot read {}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// A malformed or out-of-range piece of input: `at` names file, line and item.
    #[error("{at}: {message}")]
    Input { at: SourceRef, message: String },
    /// Nothing to solve: no polygons, or none survived cleaning.
    #[error("empty scene: {0}")]
    Empty(String),
    /// No polygon emits light, so every radiance would be zero.
    #[error("no emitter: {0}")]
    NoEmitter(String),
    /// `strict` turned an import warning into an error.
    #[error("strict import: {warning}{}", others_text(*others))]
    Strict { warning: Warning, others: usize },
}

fn others_text(others: usize) -> String {
    match others {
        0 => String::new(),
        1 => " (and 1 more warning)".to_owned(),
        n => format!(" (and {n} more warnings)"),
    }
}

impl SceneError {
    /// An input error at `file:line (item)`.
    pub(crate) fn at(
        file: &Path,
        line: Option<usize>,
        item: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        SceneError::Input {
            at: SourceRef {
                file: file.to_path_buf(),
                line,
                item: item.into(),
            },
            message: message.into(),
        }
    }

    pub(crate) fn io(path: &Path, source: std::io::Error) -> Self {
        SceneError::Io {
            path: path.to_path_buf(),
            source,
        }
    }

    /// The location this error names, when it names one.
    pub fn source_ref(&self) -> Option<&SourceRef> {
        match self {
            SceneError::Input { at, .. } => Some(at),
            SceneError::Strict { warning, .. } => Some(&warning.source),
            _ => None,
        }
    }
}
