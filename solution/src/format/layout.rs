//! Byte layout of the solution file: sizes, offsets and codes.
//!
//! `docs/solution-format.md` is the specification; the constants here are that
//! document's tables in code. All integers and floats are little-endian.
//!
//! ```text
//! [preamble 64][header 216][batch table 56×B][section table 32×S] pad
//! [section 0: settings JSON] pad [vertices of batch 0] pad [coefficients of batch 0]
//! pad [indices of batch 0] pad [vertices of batch 1] ...
//! ```
//!
//! Every section starts at a multiple of [`SECTION_ALIGN`] and padding bytes are zero.

use super::{Representation, ScalarType, SolveMode};

/// The first 8 bytes. Like PNG's signature: a non-ASCII first byte catches 7-bit
/// transfers, and the CR LF, ^Z, LF tail catches newline conversion and stops
/// `type` on DOS.
pub const MAGIC: [u8; 8] = [0x89, b'R', b'A', b'D', b'\r', b'\n', 0x1A, b'\n'];

/// The newest major version. 2 adds textured batches (a texture index, a factor
/// and a per-vertex UV + E/π section per batch) and texture sections; 3 adds a
/// second texture slot per batch (an emission texture index and factor, the
/// emission map of a surface that also has a diffuse map). Readers read major
/// versions 1, 2 and 3 and refuse any other. A writer writes the lowest major
/// version that holds the solution: [`UNTEXTURED_VERSION_MAJOR`].0 when it has
/// no textures, so those files are byte for byte what version-1 writers wrote
/// and version-1 readers still read them; [`TEXTURED_VERSION_MAJOR`].0 when no
/// batch uses the second slot, so those files are what version-2 writers
/// wrote; 3.0 otherwise. Each step is a major one by the versioning policy: a
/// reader that skipped the new fields would misdraw (a 1.0 reader would draw
/// E/π as radiance, a 2.0 reader would draw a textured emitter without its
/// emission).
pub const VERSION_MAJOR: u16 = 3;
/// The major version of files with textures but no second texture slot (the
/// version-2 layout).
pub const TEXTURED_VERSION_MAJOR: u16 = 2;
/// The major version of files without textures (the version-1 layout).
pub const UNTEXTURED_VERSION_MAJOR: u16 = 1;
/// The newest minor version this code writes and fully understands. Files with a
/// newer minor version are read by skipping fields and sections this code does
/// not know (see the versioning policy in the specification). Minor version 1
/// (1.1, 2.1, 3.1; issue 41) appends the exposure key and the lights and
/// environment section indices to the header and adds those two section
/// kinds; a writer uses it only for a solution with lights, so every other
/// file stays x.0 byte for byte.
pub const VERSION_MINOR: u16 = 1;
/// The minor version of a file with lights ([`super::Lighting`]).
pub const LIGHTING_VERSION_MINOR: u16 = 1;

/// Every section (settings, vertices, coefficients, indices) starts at a multiple
/// of this many bytes. 64 is a cache line and the widest SIMD load (AVX-512), and
/// since a memory map starts on a page boundary, file offsets keep this alignment
/// in memory: a reader may reinterpret a section as `[f32]`, `[u16]`, `[u32]` or
/// `[Vertex]` in place, and copies into GPU staging memory run at full width. It
/// costs at most 63 bytes per section.
pub const SECTION_ALIGN: u64 = 64;

/// Size of the preamble (magic, version, lengths, counts, metadata checksum).
pub const PREAMBLE_LEN: usize = 64;
/// Size of the header block in version 1.0 (newer minor versions may append).
pub const HEADER_LEN: usize = 216;
/// Size of the header block in minor version 1 (1.1, 2.1, 3.1): the exposure
/// key and two section indices appended, and a reserved word.
pub const HEADER_LEN_V1_1: usize = 232;
/// Size of one batch-table entry in version 1.0.
pub const BATCH_ENTRY_LEN: usize = 56;
/// Size of one batch-table entry in version 2.0 (texture fields appended, the
/// 1.0 reserved word used for the texture index).
pub const BATCH_ENTRY_LEN_V2: usize = 72;
/// Size of one batch-table entry in version 3.0 (the emission slot appended).
pub const BATCH_ENTRY_LEN_V3: usize = 88;
/// Size of one stored textured vertex: u, v, E/π RGB as 5 × f32.
pub const TEXTURED_VERTEX_LEN: usize = 20;
/// Size of the prefix of a texture section before its encoded image: width,
/// height, encoding, reserved (4 × u32).
pub const TEXTURE_PREFIX_LEN: usize = 16;

/// The header length a minor version defines: the 1.0 header, or from minor
/// version 1 on the 1.1 header (exposure key and two section indices
/// appended). A newer minor version than this reader's holds the 1.1 fields.
pub fn header_len(minor: u16) -> usize {
    if minor >= LIGHTING_VERSION_MINOR {
        HEADER_LEN_V1_1
    } else {
        HEADER_LEN
    }
}

/// The batch-entry length a major version defines.
pub fn batch_entry_len(major: u16) -> usize {
    match major {
        0 | 1 => BATCH_ENTRY_LEN,
        2 => BATCH_ENTRY_LEN_V2,
        _ => BATCH_ENTRY_LEN_V3,
    }
}
/// Size of one section-table entry in version 1.0.
pub const SECTION_ENTRY_LEN: usize = 32;
/// Size of one stored vertex: position, normal, tangent as 9 × f32.
pub const VERTEX_LEN: usize = 36;

/// Preamble field offsets.
pub mod preamble {
    pub const MAGIC: usize = 0;
    pub const VERSION_MAJOR: usize = 8;
    pub const VERSION_MINOR: usize = 10;
    /// CRC-32 of bytes `0..metadata_length` with these four bytes read as zero.
    pub const METADATA_CRC: usize = 12;
    pub const FILE_LENGTH: usize = 16;
    pub const METADATA_LENGTH: usize = 24;
    pub const HEADER_LENGTH: usize = 32;
    pub const BATCH_COUNT: usize = 36;
    pub const BATCH_ENTRY_LENGTH: usize = 40;
    pub const SECTION_COUNT: usize = 44;
    pub const SECTION_ENTRY_LENGTH: usize = 48;
    pub const RESERVED_0: usize = 52;
    pub const RESERVED_1: usize = 56;
}

/// Header block field offsets, relative to the header's start (byte 64).
pub mod header {
    pub const UNITS_PER_METRE: usize = 0;
    pub const RECENTRE_OFFSET: usize = 8;
    pub const CAMERA_EYE: usize = 32;
    pub const CAMERA_TARGET: usize = 56;
    pub const CAMERA_UP: usize = 80;
    pub const CAMERA_FOV_Y_DEG: usize = 104;
    pub const CAMERA_WIDTH: usize = 112;
    pub const CAMERA_HEIGHT: usize = 116;
    pub const BOUNDS_MIN: usize = 120;
    pub const BOUNDS_MAX: usize = 132;
    pub const UP_AXIS: usize = 144;
    pub const MODE: usize = 148;
    pub const PARTIAL: usize = 152;
    pub const SETTINGS_SECTION: usize = 156;
    pub const SHOTS: usize = 160;
    pub const RAYS: usize = 168;
    pub const SECONDS: usize = 176;
    pub const UNSHOT_FRACTION: usize = 184;
    pub const EMITTED_POWER: usize = 192;
    pub const AMBIENT: usize = 200;
    pub const RESERVED: usize = 212;
    /// Minor version 1: f32, the log-average radiance (0 when not computed).
    pub const EXPOSURE_KEY: usize = 216;
    /// Minor version 1: the lights section's index, or [`super::NO_SECTION`].
    pub const LIGHTS_SECTION: usize = 220;
    /// Minor version 1: the environment section's index, or
    /// [`super::NO_SECTION`].
    pub const ENVIRONMENT_SECTION: usize = 224;
    /// Minor version 1: reserved (0).
    pub const RESERVED_V1_1: usize = 228;
}

/// Batch-table entry field offsets.
pub mod batch {
    pub const REPRESENTATION: usize = 0;
    pub const REPRESENTATION_PARAMETER: usize = 4;
    pub const SCALAR: usize = 8;
    pub const SCALE: usize = 12;
    pub const FRAME_CONVENTION: usize = 16;
    pub const BASIS_CONVENTION: usize = 20;
    pub const VERTEX_COUNT: usize = 24;
    pub const INDEX_COUNT: usize = 32;
    pub const VERTICES_SECTION: usize = 40;
    pub const COEFFICIENTS_SECTION: usize = 44;
    pub const INDICES_SECTION: usize = 48;
    /// Version 1: reserved (0). Version 2: the texture index ([`super::NO_TEXTURE`]
    /// for an untextured batch).
    pub const RESERVED: usize = 52;
    /// Version 2: index of the texture (among the file's texture sections, in
    /// section-table order), or [`super::NO_TEXTURE`].
    pub const TEXTURE: usize = 52;
    /// Version 2: section index of the per-vertex UV + E/π section, or
    /// [`super::NO_TEXTURE`] for an untextured batch.
    pub const TEXTURED_VERTICES_SECTION: usize = 56;
    /// Version 2: f32×3, the linear factor of the texture (0 when untextured).
    pub const TEXTURE_FACTOR: usize = 60;
    /// Version 3: index of the batch's emission texture, the second slot, or
    /// [`super::NO_TEXTURE`]; only a textured batch may have one.
    pub const EMISSION_TEXTURE: usize = 72;
    /// Version 3: f32×3, the linear factor of the emission texture (Ke; 0 when
    /// the slot is empty).
    pub const EMISSION_FACTOR: usize = 76;
}

/// Texture-section prefix field offsets (u32 each), relative to the section's
/// start; the encoded image follows at [`TEXTURE_PREFIX_LEN`].
pub mod texture {
    pub const WIDTH: usize = 0;
    pub const HEIGHT: usize = 4;
    pub const ENCODING: usize = 8;
    pub const RESERVED: usize = 12;
}

/// A header section index that refers to no section (minor version 1: a
/// file without lights or without an environment).
pub const NO_SECTION: u32 = u32::MAX;

/// The batch fields of an untextured batch in version 2 (texture index and
/// textured-vertices section).
pub const NO_TEXTURE: u32 = u32::MAX;

/// Texture encoding code: a PNG image, 8 bits per channel, grey, grey + alpha,
/// RGB, RGBA or an 8-bit palette, its samples sRGB-encoded.
pub const ENCODING_PNG_SRGB8: u32 = 1;

/// The largest texture width or height: 16384 is what every Vulkan 1.x desktop
/// GPU supports (`maxImageDimension2D`) and bounds one decoded texture at
/// 1 GiB of RGBA8.
pub const MAX_TEXTURE_SIZE: u32 = 16384;

/// The most decoded texture bytes (RGBA8, before mip levels, summed over a
/// file's textures) a reader accepts: 2 GiB, two textures of the largest size.
/// Textures are the one part of a file whose decoded size exceeds its stored
/// size, so this and [`DEFLATE_MAX_RATIO`] bound what decoding may allocate.
pub const MAX_DECODED_TEXTURE_BYTES: u64 = 2 << 30;

/// Deflate (RFC 1951) cannot expand a stream by more than 1032:1 (a 258-byte
/// match coded in 2 bits), so a PNG whose raw scanlines (rows × (1 + row bytes))
/// exceed 1032 × its whole length cannot be complete: refused before decoding.
pub const DEFLATE_MAX_RATIO: u64 = 1032;

/// Section-table entry field offsets.
pub mod section {
    pub const KIND: usize = 0;
    pub const CRC: usize = 4;
    pub const OFFSET: usize = 8;
    pub const LENGTH: usize = 16;
    pub const RESERVED: usize = 24;
}

/// Representation codes (batch field `representation`). Zero is never a valid
/// code, so a zeroed entry is refused.
pub const REPRESENTATION_SH: u32 = 1;
pub const REPRESENTATION_CUBE: u32 = 2;

/// Scalar type codes (batch field `scalar`).
pub const SCALAR_F32: u32 = 1;
pub const SCALAR_F16: u32 = 2;

/// Solve mode codes (header field `mode`).
pub const MODE_DIFFUSE: u32 = 1;
pub const MODE_DIRECTIONAL: u32 = 2;

/// Frame convention (batch field `frame_convention`): n = the normal of the vertex's
/// planar input polygon (or its smoothed normal), t = the normalized first edge of
/// that polygon (or a tangent derived the same way everywhere), b = n × t;
/// directions are θ from n and φ from t toward b (design notes, "Local frames and
/// SH"). The stored `normal` is n and `tangent` is t.
pub const FRAME_POLYGON_NTB: u32 = 1;

/// Basis convention (batch field `basis_convention`) of SH batches: real,
/// orthonormal spherical harmonics over the unit sphere, coefficient index
/// `l² + l + m`, m < 0 the sine terms (∝ sin(|m|φ)), m > 0 the cosine terms
/// (∝ cos(mφ)), no Condon–Shortley phase, so Y_1,−1 ∝ +y (b), Y_1,0 ∝ +z (n) and
/// Y_1,1 ∝ +x (t) in the frame.
pub const BASIS_SH_REAL_ORTHONORMAL: u32 = 1;

/// Basis convention of cube batches (Immel, Cohen and Greenberg's (1986) global cube): D = 6·k² directions at
/// the centres of a k × k grid of cells on each face of the cube [−1, 1]³ in the
/// frame (x = t, y = b, z = n). Faces in the order +x, −x, +y, −y, +z, −z; on the
/// face of axis a with sign s the in-face axes are (u, v) = (y, z), (z, x), (x, y)
/// for a = x, y, z; cell (i, j) (row i along v, column j along u) points along
/// normalize(s·e_a + u_j·e_u + v_i·e_v) with u_j = −1 + (2j + 1)/k and
/// v_i = −1 + (2i + 1)/k; its index is (face·k + i)·k + j.
pub const BASIS_CUBE_CELL_CENTRES: u32 = 2;

/// Section kinds (section field `kind`).
pub const SECTION_SETTINGS: u32 = 1;
pub const SECTION_VERTICES: u32 = 2;
pub const SECTION_COEFFICIENTS: u32 = 3;
pub const SECTION_INDICES: u32 = 4;
/// Version 2: per-vertex u, v, E/π of a textured batch.
pub const SECTION_TEXTURED_VERTICES: u32 = 5;
/// Version 2: one texture, a [`TEXTURE_PREFIX_LEN`]-byte prefix and an encoded
/// image.
pub const SECTION_TEXTURE: u32 = 6;

/// Minor version 1: the lights, UTF-8 JSON text.
pub const SECTION_LIGHTS: u32 = 7;
/// Minor version 1: the environment, a prefix and RGB f32 texels
/// (`lighting.rs`).
pub const SECTION_ENVIRONMENT: u32 = 8;

/// The largest section kind a major version defines.
pub fn last_section_kind(major: u16) -> u32 {
    if major >= 2 {
        SECTION_TEXTURE
    } else {
        SECTION_INDICES
    }
}

/// Whether version `major.minor` (at most this reader's minor) defines the
/// section kind `kind`.
pub fn section_kind_known(major: u16, minor: u16, kind: u32) -> bool {
    (SECTION_SETTINGS..=last_section_kind(major)).contains(&kind)
        || (minor >= LIGHTING_VERSION_MINOR
            && (kind == SECTION_LIGHTS || kind == SECTION_ENVIRONMENT))
}

/// The largest SH order L anything in the project handles: the solver's settings
/// (`max_sh_order`), the writer and the reader all refuse more. 64 is the solver's
/// default cap, and the order at which two costs that grow with L are still
/// acceptable:
///
/// * **f32 accuracy.** The runtime evaluates the basis in f32; its error bound
///   [`crate::sh::f32_basis_tolerance`] grows as (L + 1)² and is 1.0e-3 of the
///   band's envelope at L = 64 (test `f32_matches_f64_within_stated_tolerance`
///   checks it at this order), about twice the half-float colour target's 2⁻¹¹;
///   at L = 100 it would be 2.4e-3, five times that target.
/// * **Shader cost.** A vertex costs (L + 1)² basis terms per view: 4,225 at
///   L = 64 against 10,201 at L = 100 (2.4×), and the per-frame bound
///   [`super::DEFAULT_MAX_FRAME_COST`] is spent that much faster.
///
/// Lobes that need more (α below about 0.04 at the default 1e-3 error target; the
/// design notes' α = 0.02 needs about 100) are capped at this order with the
/// solver's warning. The cap also stops a hostile header from making a reader size
/// anything by an absurd order even when the batch has no vertices.
pub const MAX_SH_ORDER: u32 = 64;

/// The largest cube resolution k (D = 6k² ≤ 6,291,456 directions), for the same
/// reason as [`MAX_SH_ORDER`].
pub const MAX_CUBE_RESOLUTION: u32 = crate::cube::MAX_RESOLUTION;

/// Vertex and index counts are u64 on disk (so no hostile value can wrap) but
/// at most this in version 1: indices are u32 and a Vulkan draw counts in u32.
pub const MAX_COUNT: u64 = u32::MAX as u64;

/// Human name of a section kind.
pub fn section_kind_name(kind: u32) -> &'static str {
    match kind {
        SECTION_SETTINGS => "settings",
        SECTION_VERTICES => "vertices",
        SECTION_COEFFICIENTS => "coefficients",
        SECTION_INDICES => "indices",
        SECTION_TEXTURED_VERTICES => "textured vertices",
        SECTION_TEXTURE => "texture",
        SECTION_LIGHTS => "lights",
        SECTION_ENVIRONMENT => "environment",
        _ => "unknown",
    }
}

/// `(code, parameter)` of a representation.
pub fn representation_code(representation: Representation) -> (u32, u32) {
    match representation {
        Representation::Sh { order } => (REPRESENTATION_SH, order),
        Representation::Cube { directions } => (REPRESENTATION_CUBE, directions),
    }
}

/// The basis convention a representation is stored in (version 1 has one per
/// representation).
pub fn basis_convention(representation: Representation) -> u32 {
    match representation {
        Representation::Sh { .. } => BASIS_SH_REAL_ORTHONORMAL,
        Representation::Cube { .. } => BASIS_CUBE_CELL_CENTRES,
    }
}

/// `(code, scale)` of a scalar type; f32 stores scale 1.
pub fn scalar_code(scalar: ScalarType) -> (u32, f32) {
    match scalar {
        ScalarType::F32 => (SCALAR_F32, 1.0),
        ScalarType::F16 { scale } => (SCALAR_F16, scale),
    }
}

/// Bytes per stored coefficient.
pub fn scalar_size(scalar: ScalarType) -> u64 {
    match scalar {
        ScalarType::F32 => 4,
        ScalarType::F16 { .. } => 2,
    }
}

pub fn mode_code(mode: SolveMode) -> u32 {
    match mode {
        SolveMode::Diffuse => MODE_DIFFUSE,
        SolveMode::Directional => MODE_DIRECTIONAL,
    }
}

pub fn mode_from_code(code: u32) -> Option<SolveMode> {
    match code {
        MODE_DIFFUSE => Some(SolveMode::Diffuse),
        MODE_DIRECTIONAL => Some(SolveMode::Directional),
        _ => None,
    }
}

/// Rounds `value` up to a multiple of [`SECTION_ALIGN`]; `None` on overflow.
pub fn align_up(value: u64) -> Option<u64> {
    value
        .checked_add(SECTION_ALIGN - 1)
        .map(|v| v / SECTION_ALIGN * SECTION_ALIGN)
}

/// CRC-32 (IEEE, as zlib and PNG) of the metadata region, with the four bytes of
/// the checksum field itself read as zero.
pub fn metadata_crc(metadata: &[u8]) -> u32 {
    let crc_at = preamble::METADATA_CRC;
    let mut hasher = crc32fast::Hasher::new();
    hasher.update(metadata.get(..crc_at).unwrap_or(metadata));
    hasher.update(&[0; 4]);
    if let Some(rest) = metadata.get(crc_at + 4..) {
        hasher.update(rest);
    }
    hasher.finalize()
}

/// Reads little-endian fields out of a block whose length was checked when the
/// reader was made, so that no read can go out of bounds.
pub struct Fields<'a> {
    bytes: &'a [u8],
}

impl<'a> Fields<'a> {
    /// `None` unless `bytes` holds at least `len` bytes.
    pub fn new(bytes: &'a [u8], len: usize) -> Option<Self> {
        (bytes.len() >= len).then_some(Fields { bytes })
    }

    fn array<const N: usize>(&self, at: usize) -> [u8; N] {
        let mut out = [0; N];
        // `new` checked the length against the fixed block size and every offset
        // used is a constant inside that block, so `get` always succeeds; a miss
        // would read zeros, which no validation step accepts as a code.
        if let Some(src) = self.bytes.get(at..at + N) {
            out.copy_from_slice(src);
        }
        out
    }

    pub fn u16(&self, at: usize) -> u16 {
        u16::from_le_bytes(self.array(at))
    }
    pub fn u32(&self, at: usize) -> u32 {
        u32::from_le_bytes(self.array(at))
    }
    pub fn u64(&self, at: usize) -> u64 {
        u64::from_le_bytes(self.array(at))
    }
    pub fn f32(&self, at: usize) -> f32 {
        f32::from_le_bytes(self.array(at))
    }
    pub fn f64(&self, at: usize) -> f64 {
        f64::from_le_bytes(self.array(at))
    }
    pub fn f32x3(&self, at: usize) -> [f32; 3] {
        [self.f32(at), self.f32(at + 4), self.f32(at + 8)]
    }
    pub fn f64x3(&self, at: usize) -> [f64; 3] {
        [self.f64(at), self.f64(at + 8), self.f64(at + 16)]
    }
}

/// Writes little-endian fields into a fixed-size block.
pub struct FieldsMut<'a> {
    bytes: &'a mut [u8],
}

impl<'a> FieldsMut<'a> {
    /// The caller sizes `bytes` to the block; writes past its end are a bug in
    /// this module and panic (no file content can reach them).
    pub fn new(bytes: &'a mut [u8]) -> Self {
        FieldsMut { bytes }
    }
    fn put(&mut self, at: usize, src: &[u8]) {
        self.bytes[at..at + src.len()].copy_from_slice(src);
    }
    pub fn u16(&mut self, at: usize, v: u16) {
        self.put(at, &v.to_le_bytes());
    }
    pub fn u32(&mut self, at: usize, v: u32) {
        self.put(at, &v.to_le_bytes());
    }
    pub fn u64(&mut self, at: usize, v: u64) {
        self.put(at, &v.to_le_bytes());
    }
    pub fn f32(&mut self, at: usize, v: f32) {
        self.put(at, &v.to_le_bytes());
    }
    pub fn f64(&mut self, at: usize, v: f64) {
        self.put(at, &v.to_le_bytes());
    }
    pub fn f32x3(&mut self, at: usize, v: [f32; 3]) {
        for (k, x) in v.into_iter().enumerate() {
            self.f32(at + 4 * k, x);
        }
    }
    pub fn f64x3(&mut self, at: usize, v: [f64; 3]) {
        for (k, x) in v.into_iter().enumerate() {
            self.f64(at + 8 * k, x);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The offset tables must tile each block exactly, with every field on a
    /// multiple of its own size, so that the blocks can be read as C structs.
    #[test]
    fn blocks_are_tiled_and_aligned() {
        assert_eq!(preamble::RESERVED_1 + 8, PREAMBLE_LEN);
        assert_eq!(header::RESERVED + 4, HEADER_LEN);
        assert_eq!(header::EXPOSURE_KEY, HEADER_LEN);
        assert_eq!(header::RESERVED_V1_1 + 4, HEADER_LEN_V1_1);
        assert_eq!(HEADER_LEN_V1_1 % 8, 0);
        assert_eq!(batch::RESERVED + 4, BATCH_ENTRY_LEN);
        assert_eq!(batch::TEXTURE_FACTOR + 12, BATCH_ENTRY_LEN_V2);
        assert_eq!(batch::EMISSION_TEXTURE, BATCH_ENTRY_LEN_V2);
        assert_eq!(batch::EMISSION_FACTOR + 12, BATCH_ENTRY_LEN_V3);
        assert_eq!(BATCH_ENTRY_LEN_V3 % 8, 0);
        assert_eq!(texture::RESERVED + 4, TEXTURE_PREFIX_LEN);
        assert_eq!(BATCH_ENTRY_LEN_V2 % 8, 0);
        assert_eq!(
            std::mem::size_of::<super::super::TexturedVertex>(),
            TEXTURED_VERTEX_LEN
        );
        assert_eq!(section::RESERVED + 8, SECTION_ENTRY_LEN);
        for len in [PREAMBLE_LEN, HEADER_LEN, BATCH_ENTRY_LEN, SECTION_ENTRY_LEN] {
            assert_eq!(len % 8, 0);
        }
        for at in [
            header::UNITS_PER_METRE,
            header::RECENTRE_OFFSET,
            header::CAMERA_EYE,
            header::CAMERA_TARGET,
            header::CAMERA_UP,
            header::CAMERA_FOV_Y_DEG,
            header::SHOTS,
            header::RAYS,
            header::SECONDS,
            header::UNSHOT_FRACTION,
            header::EMITTED_POWER,
            batch::VERTEX_COUNT,
            batch::INDEX_COUNT,
            section::OFFSET,
            section::LENGTH,
        ] {
            assert_eq!(at % 8, 0, "u64/f64 field at {at}");
        }
        assert_eq!(std::mem::size_of::<super::super::Vertex>(), VERTEX_LEN);
    }

    #[test]
    fn align_up_rounds_to_section_alignment() {
        assert_eq!(align_up(0), Some(0));
        assert_eq!(align_up(1), Some(64));
        assert_eq!(align_up(64), Some(64));
        assert_eq!(align_up(65), Some(128));
        assert_eq!(align_up(u64::MAX), None);
    }
}
