//! Errors of the solution-file codec.
//!
//! A [`Problem`] says precisely what is wrong with the bytes (or, on the writing
//! side, with the in-memory [`Solution`](super::Solution)); a [`FormatError`] adds the
//! file it came from where there is one.

use std::path::PathBuf;

/// What is wrong with a solution file or with a solution about to be written.
///
/// Messages name the section, batch, vertex or field and the offending value, so a
/// user can tell a truncated download from a writer bug.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Problem {
    #[error("the file has {len} bytes, fewer than the {min}-byte preamble of a solution file")]
    TooShort { len: u64, min: u64 },

    #[error(
        "not a solution file: the first 8 bytes are {found:02x?}, a solution file starts with {expected:02x?}"
    )]
    BadMagic { found: [u8; 8], expected: [u8; 8] },

    #[error(
        "format version {major}.{minor} is not supported: this reader reads major versions 1 to {known_major} (minor versions up to {known_minor} fully, newer minor versions by skipping what it does not know)"
    )]
    UnsupportedVersion {
        major: u16,
        minor: u16,
        known_major: u16,
        known_minor: u16,
    },

    #[error(
        "the preamble says the file has {declared} bytes but it has {actual} (truncated, or data appended)"
    )]
    LengthMismatch { declared: u64, actual: u64 },

    #[error("{what} ends at byte {end} but the file has {len} bytes")]
    OutOfBounds { what: String, end: u128, len: u64 },

    #[error("{what}: stored CRC-32 {stored:08x} but the bytes give {computed:08x} (the file is corrupted)")]
    Checksum {
        what: String,
        stored: u32,
        computed: u32,
    },

    #[error("{what} is {value}, which is not valid here: {reason}")]
    BadLength {
        what: String,
        value: u64,
        reason: String,
    },

    #[error("{what} starts at byte {offset}, which is not a multiple of {align}")]
    Misaligned {
        what: String,
        offset: u64,
        align: u64,
    },

    #[error("{first} and {second} overlap")]
    Overlap { first: String, second: String },

    #[error("padding byte {at} is {value:#04x}, not zero (the file is corrupted)")]
    NonZeroPadding { at: u64, value: u8 },

    #[error("{field}: unknown code {code}")]
    UnknownCode { field: String, code: u32 },

    #[error("{field} is {value} but must be zero in this format version")]
    Reserved { field: String, value: u64 },

    #[error("{what} refers to section {index} but the file has {count} sections")]
    MissingSection {
        what: String,
        index: u32,
        count: u32,
    },

    #[error("{what} is section {index}, whose kind is {kind}; expected kind {expected} ({expected_name})")]
    WrongSectionKind {
        what: String,
        index: u32,
        kind: u32,
        expected: u32,
        expected_name: &'static str,
    },

    #[error("section {index} is used twice (by {first} and by {second})")]
    SectionReused {
        index: u32,
        first: String,
        second: String,
    },

    #[error("section {index} ({kind_name}) is not used by any batch")]
    UnusedSection { index: u32, kind_name: &'static str },

    #[error("{what}: {count} {unit} need {expected} bytes but {section} has {actual} bytes")]
    SizeMismatch {
        what: String,
        count: u64,
        unit: &'static str,
        expected: u128,
        section: String,
        actual: u64,
    },

    #[error("{what} is {value}, above the limit of {limit}: {reason}")]
    TooLarge {
        what: String,
        value: u64,
        limit: u64,
        reason: &'static str,
    },

    #[error(
        "batch {batch}: {count} indices is not a whole number of triangles (not a multiple of 3)"
    )]
    NotTriangles { batch: usize, count: u64 },

    #[error(
        "batch {batch}: index {position} is {index} but the batch has {vertex_count} vertices"
    )]
    IndexOutOfRange {
        batch: usize,
        position: u64,
        index: u32,
        vertex_count: u64,
    },

    #[error("batch {batch}: has {found} coefficients; {vertices} vertices × {per_channel} per channel × 3 channels = {expected}")]
    CoefficientCount {
        batch: usize,
        found: u64,
        vertices: u64,
        per_channel: u64,
        expected: u128,
    },

    #[error("{what} is not finite ({value})")]
    NonFinite { what: String, value: String },

    #[error("{what}: {reason}")]
    Invalid { what: String, reason: String },

    #[error("texture {texture}: {reason}")]
    Texture { texture: u32, reason: String },

    #[error("the per-frame cost is {cost} basis terms per view (Σ vertices × (L + 1)², 4 per global-cube vertex), above the limit of {limit}; pass {flag} {cost} (or more) to draw it anyway")]
    FrameCost {
        cost: u64,
        limit: u64,
        flag: &'static str,
    },

    #[error("batch {batch}: coefficient {position} is {value}; divided by the f16 scale {scale} it is outside the half-precision range (±65504); use a larger scale (see format::f16_scale_for)")]
    F16Overflow {
        batch: usize,
        position: u64,
        value: f32,
        scale: f32,
    },
}

/// An error reading or writing a solution file: the [`Problem`] with the file's path
/// where there is one, or an I/O failure.
#[derive(Debug, thiserror::Error)]
pub enum FormatError {
    /// The file (or the solution being written to it) is invalid.
    #[error("{}: {problem}", path.display())]
    File {
        path: PathBuf,
        problem: Box<Problem>,
    },

    /// Invalid bytes or solution with no file involved ([`encode`](super::encode),
    /// [`decode`](super::decode)).
    #[error(transparent)]
    Problem(Box<Problem>),

    /// The operating system refused an operation on the file.
    #[error("cannot {action} {}", path.display())]
    Io {
        action: &'static str,
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

// Boxed so that `Result<_, FormatError>` stays small (a `Problem` with its names
// is over 100 bytes); errors are rare, so the allocation costs nothing that matters.
impl From<Problem> for FormatError {
    fn from(problem: Problem) -> Self {
        FormatError::Problem(Box::new(problem))
    }
}

impl FormatError {
    /// The problem with the data, if this is not an I/O error.
    pub fn problem(&self) -> Option<&Problem> {
        match self {
            FormatError::File { problem, .. } | FormatError::Problem(problem) => Some(&**problem),
            FormatError::Io { .. } => None,
        }
    }

    /// The file this error is about, where known.
    pub fn path(&self) -> Option<&std::path::Path> {
        match self {
            FormatError::File { path, .. } | FormatError::Io { path, .. } => Some(path),
            FormatError::Problem(_) => None,
        }
    }

    pub(crate) fn in_file(path: &std::path::Path, problem: Problem) -> Self {
        FormatError::File {
            path: path.to_path_buf(),
            problem: Box::new(problem),
        }
    }

    pub(crate) fn io(action: &'static str, path: &std::path::Path, source: std::io::Error) -> Self {
        FormatError::Io {
            action,
            path: path.to_path_buf(),
            source,
        }
    }
}
