//! [`MappedSolution`]: a validated solution file mapped into memory, with the
//! accessors the runtime streams to the GPU and the checks it defers to that
//! stream.

use super::super::error::{FormatError, Problem};
use super::super::layout;
use super::super::texture::{self, TextureInfo};
use super::super::{Header, Lighting, Solution, Texture};
use super::content::check_finite_coefficients;
use super::{materialize, parse_checking, BatchInfo, Parsed};
use std::path::{Path, PathBuf};

/// A validated solution file mapped into memory: the runtime uploads
/// [`vertex_bytes`](Self::vertex_bytes), [`coefficient_bytes`](Self::coefficient_bytes)
/// and [`index_bytes`](Self::index_bytes) to GPU buffers as they are (little-endian,
/// each slice starting 64-byte aligned in memory).
pub struct MappedSolution {
    path: PathBuf,
    map: memmap2::Mmap,
    parsed: Parsed,
}

impl std::fmt::Debug for MappedSolution {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MappedSolution")
            .field("path", &self.path)
            .field("file_len", &self.parsed.file_len)
            .field("batches", &self.parsed.batches)
            .finish_non_exhaustive()
    }
}

impl MappedSolution {
    /// Maps and validates a solution file (every check of [`decode`](crate::format::decode), including all
    /// checksums) before returning; only per-batch and per-section tables (bounded
    /// by the file's length) are allocated.
    pub fn open(path: impl AsRef<Path>) -> Result<Self, FormatError> {
        Self::map_and_parse(path.as_ref(), true)
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// `(major, minor)` format version of the file.
    pub fn version(&self) -> (u16, u16) {
        self.parsed.version
    }

    pub fn file_len(&self) -> u64 {
        self.parsed.file_len
    }

    pub fn header(&self) -> &Header {
        &self.parsed.header
    }

    pub fn batches(&self) -> &[BatchInfo] {
        &self.parsed.batches
    }

    /// The exposure key, lights and environment (minor version 1), checked
    /// in full by the open; `None` for an x.0 file.
    pub fn lighting(&self) -> Option<&Lighting> {
        self.parsed.lighting.as_ref()
    }

    fn section(&self, batch: usize, which: usize) -> &[u8] {
        let range = &self.parsed.ranges[batch][which];
        self.map.get(range.clone()).unwrap_or(&[])
    }

    /// Batch `batch`'s vertices: `vertex_count × 36` bytes, each vertex 9
    /// little-endian f32 (position, normal, tangent), the layout of [`Vertex`](crate::format::Vertex).
    ///
    /// # Panics
    /// If `batch >= self.batches().len()`.
    pub fn vertex_bytes(&self, batch: usize) -> &[u8] {
        self.section(batch, 0)
    }

    /// Batch `batch`'s coefficients, vertex-major, then coefficient, then RGB:
    /// little-endian f32, or f16 (multiply by the batch's scale).
    ///
    /// # Panics
    /// If `batch >= self.batches().len()`.
    pub fn coefficient_bytes(&self, batch: usize) -> &[u8] {
        self.section(batch, 1)
    }

    /// Batch `batch`'s triangle list: `index_count` little-endian u32.
    ///
    /// # Panics
    /// If `batch >= self.batches().len()`.
    pub fn index_bytes(&self, batch: usize) -> &[u8] {
        self.section(batch, 2)
    }

    /// Copies the file into an in-memory [`Solution`] (f16 coefficients widened to
    /// f32 and multiplied by their scale, textures decoded). Fails only if a
    /// texture does not decode: possible after
    /// [`open_deferring_checksums`](Self::open_deferring_checksums), which does
    /// not decode textures, or if the file was changed in place.
    pub fn to_solution(&self) -> Result<Solution, FormatError> {
        materialize(&self.map, &self.parsed).map_err(|p| FormatError::in_file(&self.path, p))
    }

    /// The file's textures (format 2; empty for 1.x), as their sections declare
    /// them.
    pub fn textures(&self) -> &[TextureInfo] {
        &self.parsed.textures
    }

    /// Texture `k`'s encoded image (the PNG stream, after the section's prefix).
    ///
    /// # Panics
    /// If `k >= self.textures().len()`.
    pub fn texture_bytes(&self, k: usize) -> &[u8] {
        let (range, _, _) = &self.parsed.texture_sections[k];
        self.map.get(range.clone()).unwrap_or(&[])
    }

    /// Texture `k`, its section's CRC-32 verified (also after
    /// [`open_deferring_checksums`](Self::open_deferring_checksums), which
    /// leaves it) and decoded to 8-bit sRGB RGBA. Allocates at most the decoded
    /// image (width × height × 4, within the caps `open` checked) plus 1 MiB.
    ///
    /// # Panics
    /// If `k >= self.textures().len()`.
    pub fn decode_texture(&self, k: usize) -> Result<Texture, FormatError> {
        let (range, index, stored) = &self.parsed.texture_sections[k];
        let start = range.start - layout::TEXTURE_PREFIX_LEN;
        let section = self.map.get(start..range.end).unwrap_or(&[]);
        let computed = crc32fast::hash(section);
        if computed != *stored {
            return Err(FormatError::in_file(
                &self.path,
                Problem::Checksum {
                    what: format!("section {index} (texture {k})"),
                    stored: *stored,
                    computed,
                },
            ));
        }
        let info = self.parsed.textures[k];
        texture::decode_png(self.texture_bytes(k), info.width, info.height).map_err(|reason| {
            FormatError::in_file(
                &self.path,
                Problem::Texture {
                    texture: k as u32,
                    reason,
                },
            )
        })
    }

    /// Batch `batch`'s UV + E/π section: `vertex_count × 20` bytes, each vertex
    /// 5 little-endian f32 (u, v, E/π RGB), the layout of [`TexturedVertex`](crate::format::TexturedVertex);
    /// empty for an untextured batch.
    ///
    /// # Panics
    /// If `batch >= self.batches().len()`.
    pub fn textured_vertex_bytes(&self, batch: usize) -> &[u8] {
        self.section(batch, 3)
    }

    /// Maps and validates a solution file like [`open`](Self::open), except
    /// that the CRC-32 of each batch's vertex, coefficient and index sections is
    /// not computed: the caller checks each one with
    /// [`verify_section`](Self::verify_section) as it copies the section, so
    /// the file's bulk is read once for checksum and copy together. Every other
    /// check runs (the metadata and settings checksums, bounds, counts, finite
    /// vertices, frames, indices below the vertex count) except the coefficients'
    /// finite check, which the caller makes as it streams them
    /// ([`verify_finite_coefficients`](Self::verify_finite_coefficients)); nothing
    /// the deferred checks guard is needed for memory safety, so a caller that
    /// never verifies only loses the detection of corrupted or non-finite values.
    pub fn open_deferring_checksums(path: impl AsRef<Path>) -> Result<Self, FormatError> {
        Self::map_and_parse(path.as_ref(), false)
    }

    fn map_and_parse(path: &Path, batch_checksums: bool) -> Result<Self, FormatError> {
        let file = std::fs::File::open(path).map_err(|e| FormatError::io("open", path, e))?;
        let len = file
            .metadata()
            .map_err(|e| FormatError::io("inspect", path, e))?
            .len();
        if len < layout::PREAMBLE_LEN as u64 {
            // Also avoids mapping an empty file, which some platforms refuse.
            return Err(FormatError::in_file(
                path,
                Problem::TooShort {
                    len,
                    min: layout::PREAMBLE_LEN as u64,
                },
            ));
        }
        // SAFETY: `Mmap` hands out `&[u8]` that Rust assumes immutable for the
        // map's lifetime. That holds as long as no process modifies or truncates
        // the file while it is mapped. The solver never writes a solution file in
        // place: `write_solution` writes a new temporary file and renames it over
        // the old name, which leaves the inode we mapped untouched (readers of the
        // old file keep the old bytes). Another tool truncating the file in place
        // would make later accesses fault (SIGBUS) and in-place edits would change
        // bytes after validation; the reader never trusts validated values for
        // memory safety (all later slicing is bounds-checked), so such edits can
        // only yield wrong pixels, not out-of-bounds access.
        let map = unsafe { memmap2::Mmap::map(&file) }
            .map_err(|e| FormatError::io("memory-map", path, e))?;
        let parsed =
            parse_checking(&map, batch_checksums).map_err(|p| FormatError::in_file(path, p))?;
        Ok(MappedSolution {
            path: path.to_path_buf(),
            map,
            parsed,
        })
    }

    fn slot(section: BatchSection) -> usize {
        match section {
            BatchSection::Vertices => 0,
            BatchSection::Coefficients => 1,
            BatchSection::Indices => 2,
            BatchSection::TexturedVertices => 3,
        }
    }

    /// Index in the section table of batch `batch`'s `section`, as the batch
    /// table (whose checksum `open` verified) gave it; `usize::MAX` for the
    /// textured vertices of an untextured batch.
    fn section_index(&self, batch: usize, section: BatchSection) -> usize {
        self.parsed.batch_sections[batch][Self::slot(section)].0
    }

    /// The CRC-32 (IEEE) the file stores for batch `batch`'s `section`: what
    /// `crc32fast::hash` of [`vertex_bytes`](Self::vertex_bytes) (or the
    /// coefficient, index or textured-vertex bytes) must equal (0 for the
    /// textured vertices of an untextured batch, the CRC of no bytes).
    ///
    /// # Panics
    /// If `batch >= self.batches().len()`.
    pub fn section_crc(&self, batch: usize, section: BatchSection) -> u32 {
        self.parsed.batch_sections[batch][Self::slot(section)].1
    }

    /// Checks that `bytes`, batch `batch`'s coefficients from coefficient
    /// `first` on, hold no Inf or NaN: the check that
    /// [`open_deferring_checksums`](Self::open_deferring_checksums) leaves to the
    /// streaming upload (which reads every coefficient anyway). On failure, the
    /// error `open` gives for the same value (file, batch, coefficient index).
    ///
    /// # Panics
    /// If `batch >= self.batches().len()`.
    pub fn verify_finite_coefficients(
        &self,
        batch: usize,
        first: u64,
        bytes: &[u8],
    ) -> Result<(), FormatError> {
        check_finite_coefficients(batch, self.parsed.batches[batch].scalar, first, bytes)
            .map_err(|p| FormatError::in_file(&self.path, p))
    }

    /// Checks `computed`, the CRC-32 of batch `batch`'s `section` as the caller
    /// read it, against the stored one: on mismatch, the same error `open`
    /// gives (naming the file, the section and its batch).
    ///
    /// # Panics
    /// If `batch >= self.batches().len()`.
    pub fn verify_section(
        &self,
        batch: usize,
        section: BatchSection,
        computed: u32,
    ) -> Result<(), FormatError> {
        let stored = self.section_crc(batch, section);
        if stored == computed {
            return Ok(());
        }
        let index = self.section_index(batch, section);
        let what = match section {
            BatchSection::Vertices => "vertices",
            BatchSection::Coefficients => "coefficients",
            BatchSection::Indices => "indices",
            BatchSection::TexturedVertices => "textured vertices",
        };
        Err(FormatError::in_file(
            &self.path,
            Problem::Checksum {
                what: format!("section {index} ({what} of batch {batch})"),
                stored,
                computed,
            },
        ))
    }

    /// The bytes of batch `batch`'s `section`.
    ///
    /// # Panics
    /// If `batch >= self.batches().len()`.
    pub fn section_bytes(&self, batch: usize, section: BatchSection) -> &[u8] {
        match section {
            BatchSection::Vertices => self.vertex_bytes(batch),
            BatchSection::Coefficients => self.coefficient_bytes(batch),
            BatchSection::Indices => self.index_bytes(batch),
            BatchSection::TexturedVertices => self.textured_vertex_bytes(batch),
        }
    }

    /// Tells the kernel that this process is done with batch `batch`'s
    /// `section` for now (`madvise(MADV_DONTNEED)`, rounded out to whole pages):
    /// its pages leave the process's resident set but stay in the page cache,
    /// and a later read maps them again. The runtime calls it once a section is
    /// on the GPU, so the map and the GPU copy are not both resident. Advisory:
    /// failure (or a platform without `madvise`) changes nothing.
    ///
    /// # Panics
    /// If `batch >= self.batches().len()`.
    pub fn release_section(&self, batch: usize, section: BatchSection) {
        let bytes = self.section_bytes(batch, section);
        if bytes.is_empty() {
            return;
        }
        #[cfg(unix)]
        {
            let offset = bytes.as_ptr() as usize - self.map.as_ptr() as usize;
            // SAFETY: the map is a read-only shared mapping of a file, so
            // MADV_DONTNEED only drops page-table entries: a later access faults
            // the same file bytes back in from the page cache (nothing was
            // written through the map, so nothing is lost), and `&[u8]` borrows
            // of the map keep seeing the same contents under the invariant of
            // `open` (the file is replaced by rename, never edited in place).
            let _ = unsafe {
                self.map.unchecked_advise_range(
                    memmap2::UncheckedAdvice::DontNeed,
                    offset,
                    bytes.len(),
                )
            };
        }
    }
}

/// One of a batch's bulk sections.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BatchSection {
    Vertices,
    Coefficients,
    Indices,
    /// Format 2, textured batches: per-vertex u, v, E/π (empty otherwise).
    TexturedVertices,
}

#[cfg(test)]
mod deferred_checksum_tests {
    use super::*;
    use crate::format::tests::sample_solution;
    use crate::format::{write_solution, ScalarType};

    fn written() -> (tempfile::TempDir, PathBuf) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("sample.sol");
        write_solution(&path, &sample_solution()).unwrap();
        (dir, path)
    }

    const SECTIONS: [BatchSection; 3] = [
        BatchSection::Vertices,
        BatchSection::Coefficients,
        BatchSection::Indices,
    ];

    /// Every stored CRC is the CRC-32 of the section's bytes, and verifying it
    /// passes: the getter reads the same table entry `parse` checks.
    #[test]
    fn stored_crcs_match_the_sections_and_verify() {
        let (_dir, path) = written();
        let file = MappedSolution::open_deferring_checksums(&path).unwrap();
        for b in 0..file.batches().len() {
            for section in SECTIONS {
                let bytes = file.section_bytes(b, section);
                let crc = crc32fast::hash(bytes);
                assert_eq!(file.section_crc(b, section), crc, "batch {b} {section:?}");
                file.verify_section(b, section, crc).unwrap();
            }
        }
    }

    /// A NaN coefficient: `open` refuses the file (at its checksum, which the
    /// edit breaks, before the content check); the deferring constructor leaves
    /// the coefficients' finite check to the stream, where
    /// `verify_finite_coefficients` names the coefficient by its index in the
    /// section, also when the piece checked starts past the section's start.
    #[test]
    fn a_nan_coefficient_is_refused_by_the_streaming_finite_check() {
        let (_dir, path) = written();
        let (offset, scalar) = {
            let file = MappedSolution::open(&path).unwrap();
            let base = file.map.as_ptr() as usize;
            (
                file.coefficient_bytes(0).as_ptr() as usize - base,
                file.batches()[0].scalar,
            )
        };
        assert_eq!(scalar, ScalarType::F32, "batch 0 of the sample stores f32");
        let mut bytes = std::fs::read(&path).unwrap();
        // Coefficient 2 of batch 0 becomes a quiet NaN.
        bytes[offset + 8..offset + 12].copy_from_slice(&f32::NAN.to_le_bytes());
        std::fs::write(&path, &bytes).unwrap();

        assert!(MappedSolution::open(&path).is_err());
        let file = MappedSolution::open_deferring_checksums(&path).unwrap();
        let coefficients = file.coefficient_bytes(0);
        let whole = file
            .verify_finite_coefficients(0, 0, coefficients)
            .unwrap_err()
            .to_string();
        assert!(whole.contains("batch 0: coefficient 2 (f32)"), "{whole}");
        assert!(whole.contains("sample.sol"), "{whole}");
        let piece = file
            .verify_finite_coefficients(0, 1, &coefficients[4..])
            .unwrap_err()
            .to_string();
        assert_eq!(piece, whole);
        file.verify_finite_coefficients(0, 3, &coefficients[12..])
            .unwrap();
    }

    /// One flipped coefficient byte: `open` refuses the file; the deferring
    /// constructor accepts it (the byte stays a finite half), and verifying the
    /// section gives the very error `open` gave.
    #[test]
    fn a_flipped_coefficient_byte_is_refused_by_both_paths_with_one_error() {
        let (_dir, path) = written();
        let (batch, offset) = {
            let file = MappedSolution::open(&path).unwrap();
            // Batch 1 is the f16 glossy triangle; flip the low byte of its first
            // half, which changes the mantissa only (still finite).
            let base = file.map.as_ptr() as usize;
            (1, file.coefficient_bytes(1).as_ptr() as usize - base)
        };
        let mut bytes = std::fs::read(&path).unwrap();
        bytes[offset] ^= 0x01;
        std::fs::write(&path, &bytes).unwrap();

        let refused = MappedSolution::open(&path).unwrap_err().to_string();
        assert!(refused.contains("CRC-32"), "{refused}");
        assert!(refused.contains("coefficients of batch 1"), "{refused}");
        assert!(refused.contains("sample.sol"), "{refused}");

        let file = MappedSolution::open_deferring_checksums(&path).unwrap();
        let computed = crc32fast::hash(file.coefficient_bytes(batch));
        let streamed = file
            .verify_section(batch, BatchSection::Coefficients, computed)
            .unwrap_err()
            .to_string();
        assert_eq!(streamed, refused);
        // The untouched sections still verify.
        for section in [BatchSection::Vertices, BatchSection::Indices] {
            let crc = crc32fast::hash(file.section_bytes(batch, section));
            file.verify_section(batch, section, crc).unwrap();
        }
    }

    /// The deferring constructor still refuses what the checksums do not guard:
    /// a corrupted settings section (its CRC is always checked) and a bad
    /// metadata checksum.
    #[test]
    fn deferring_still_checks_metadata_and_settings() {
        let (_dir, path) = written();
        let clean = std::fs::read(&path).unwrap();
        let settings_at = {
            let file = MappedSolution::open(&path).unwrap();
            let text = &file.header().settings_json;
            let at = clean
                .windows(text.len())
                .position(|w| w == text.as_bytes())
                .unwrap();
            at
        };
        let mut bytes = clean.clone();
        bytes[settings_at] ^= 0x01;
        std::fs::write(&path, &bytes).unwrap();
        let error = MappedSolution::open_deferring_checksums(&path)
            .unwrap_err()
            .to_string();
        assert!(
            error.contains("CRC-32") && error.contains("settings"),
            "{error}"
        );
        let mut bytes = clean;
        bytes[layout::PREAMBLE_LEN] ^= 0x01;
        std::fs::write(&path, &bytes).unwrap();
        let error = MappedSolution::open_deferring_checksums(&path)
            .unwrap_err()
            .to_string();
        assert!(error.contains("header and tables"), "{error}");
    }
}
