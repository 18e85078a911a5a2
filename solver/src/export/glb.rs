//! The binary glTF container (glTF 2.0 specification, §4.4): a 12-byte header,
//! a JSON chunk padded with spaces and a BIN chunk padded with zeros, each
//! chunk length a multiple of 4; and the `uri` of a `.bin` written beside a
//! `.gltf`.

use std::io::{self, Write};

/// `glTF` in ASCII, little-endian (§4.4.2).
const MAGIC: u32 = 0x4654_6C67;
/// The container version this writes.
const VERSION: u32 = 2;
/// Chunk types (§4.4.3): `JSON` and `BIN\0` in ASCII, little-endian.
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;
/// The header (magic, version, length) and one chunk header (length, type).
const HEADER_BYTES: u64 = 12;
const CHUNK_HEADER_BYTES: u64 = 8;

/// The total length of a `.glb` with `json` and `bin` bytes (the chunk data
/// padded to multiples of 4; an empty `bin` has no BIN chunk), in u64 so that
/// a caller can compare it with the u32 the header holds.
pub fn glb_length(json: u64, bin: u64) -> u64 {
    let pad = |n: u64| n.div_ceil(4) * 4;
    let bin_chunk = if bin == 0 {
        0
    } else {
        CHUNK_HEADER_BYTES + pad(bin)
    };
    HEADER_BYTES + CHUNK_HEADER_BYTES + pad(json) + bin_chunk
}

/// Writes a `.glb`. The caller has checked [`glb_length`] against `u32::MAX`
/// ([`super::MAX_GLTF_BYTES`]); a larger one is refused here too.
pub fn write_glb(out: &mut impl Write, json: &[u8], bin: &[u8]) -> io::Result<()> {
    let too_large = || io::Error::new(io::ErrorKind::InvalidInput, "a .glb is limited to 4 GiB");
    let total =
        u32::try_from(glb_length(json.len() as u64, bin.len() as u64)).map_err(|_| too_large())?;
    let padded = |n: usize| n.div_ceil(4) * 4;
    out.write_all(&MAGIC.to_le_bytes())?;
    out.write_all(&VERSION.to_le_bytes())?;
    out.write_all(&total.to_le_bytes())?;
    // Each padded length is at most `total`, so the conversions cannot fail.
    let json_len = u32::try_from(padded(json.len())).map_err(|_| too_large())?;
    out.write_all(&json_len.to_le_bytes())?;
    out.write_all(&CHUNK_JSON.to_le_bytes())?;
    out.write_all(json)?;
    out.write_all(&b"   "[..padded(json.len()) - json.len()])?;
    if !bin.is_empty() {
        let bin_len = u32::try_from(padded(bin.len())).map_err(|_| too_large())?;
        out.write_all(&bin_len.to_le_bytes())?;
        out.write_all(&CHUNK_BIN.to_le_bytes())?;
        out.write_all(bin)?;
        out.write_all(&[0u8; 3][..padded(bin.len()) - bin.len()])?;
    }
    Ok(())
}

/// A file name as a relative URI reference (RFC 3986): every byte outside
/// the unreserved set `A–Z a–z 0–9 - . _ ~` percent-encoded, so spaces,
/// `#`, `?`, `%` and non-ASCII names survive a viewer's URI parser.
pub fn file_name_uri(name: &str) -> String {
    let mut uri = String::with_capacity(name.len());
    for byte in name.bytes() {
        if byte.is_ascii_alphanumeric() || b"-._~".contains(&byte) {
            uri.push(char::from(byte));
        } else {
            uri.push_str(&format!("%{byte:02X}"));
        }
    }
    uri
}
