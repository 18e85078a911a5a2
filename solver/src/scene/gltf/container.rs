//! The glTF container: a `.glb`'s chunks, and every buffer's bytes (the GLB
//! BIN chunk, a data URI, or a file beside the glTF file), each length
//! checked before a slice is taken.

use super::Context;
use crate::scene::SceneError;
use base64::Engine as _;
use gltf::Document;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::rc::Rc;

/// Splits a binary glTF file (glTF 2.0 specification, chapter 4) into its JSON
/// chunk and its optional BIN chunk, checking every length against the bytes
/// that are there.
pub(super) fn split_glb<'a>(
    ctx: &Context,
    bytes: &'a [u8],
) -> Result<(&'a [u8], Option<&'a [u8]>), SceneError> {
    let word = |at: usize| -> Option<u32> {
        bytes
            .get(at..at + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let truncated = |what: &str| {
        ctx.err(
            "GLB",
            format!(
                "truncated binary glTF: the file ends inside {what} ({} bytes)",
                bytes.len()
            ),
        )
    };
    let version = word(4).ok_or_else(|| truncated("the 12-byte header"))?;
    let length = word(8).ok_or_else(|| truncated("the 12-byte header"))? as usize;
    if version != 2 {
        return Err(ctx.err(
            "GLB",
            format!("binary glTF version {version}: only version 2 is read"),
        ));
    }
    if length > bytes.len() {
        return Err(ctx.err(
            "GLB",
            format!(
                "truncated binary glTF: the header says {length} bytes, the file has {}",
                bytes.len()
            ),
        ));
    }
    let data = &bytes[..length];
    let chunk = |at: usize, what: &str| -> Result<(u32, &'a [u8], usize), SceneError> {
        let data: &'a [u8] = &bytes[..length];
        let (Some(len), Some(kind)) = (word(at), word(at + 4)) else {
            return Err(truncated(&format!("the {what} chunk header")));
        };
        let start = at + 8;
        let end = start as u64 + u64::from(len);
        if end > data.len() as u64 {
            return Err(ctx.err(
                "GLB",
                format!(
                    "truncated binary glTF: the {what} chunk claims {len} bytes from byte {start}, \
                     the file has {} in all",
                    data.len()
                ),
            ));
        }
        let end = end as usize;
        Ok((kind, &data[start..end], end))
    };
    if data.len() < 20 {
        return Err(truncated("the JSON chunk header"));
    }
    const JSON: u32 = 0x4E4F_534A;
    const BIN: u32 = 0x004E_4942;
    let (kind, json, mut next) = chunk(12, "JSON")?;
    if kind != JSON {
        return Err(ctx.err("GLB", "the first chunk of a binary glTF must be JSON"));
    }
    let mut bin = None;
    // Chunks are 4-byte aligned; the BIN chunk, if any, is the second, and
    // chunks of other types are ignored (chapter 4).
    next = next.div_ceil(4) * 4;
    if next + 8 <= data.len() {
        let (kind, body, _) = chunk(next, "BIN")?;
        if kind == BIN {
            bin = Some(body);
        }
    }
    Ok((json, bin))
}

/// One buffer: its first `length` bytes of `bytes`, which several buffers
/// may share (one file named twice is read once).
pub(super) struct Buffer {
    bytes: Rc<[u8]>,
    length: usize,
}

impl Buffer {
    /// The buffer's `byteLength` bytes.
    pub(super) fn data(&self) -> &[u8] {
        &self.bytes[..self.length]
    }
}

/// Each buffer's bytes: the GLB BIN chunk, a data URI decoded, or a file
/// relative to the glTF file, each at least the buffer's `byteLength`. Every
/// source is held once however many buffers name it, so what is allocated is
/// at most the files' sizes and the decoded data URIs (which are smaller than
/// the JSON that holds them).
pub(super) fn load_buffers(
    ctx: &Context,
    document: &Document,
    blob: Option<&[u8]>,
) -> Result<Vec<Buffer>, SceneError> {
    let dir = ctx.path.parent().unwrap_or(Path::new(""));
    let mut files: HashMap<PathBuf, Rc<[u8]>> = HashMap::new();
    let mut bin: Option<Rc<[u8]>> = None;
    let mut out = Vec::new();
    for buffer in document.buffers() {
        let item = format!("buffer {}", buffer.index());
        let length = buffer.length();
        let bytes: Rc<[u8]> = match buffer.source() {
            gltf::buffer::Source::Bin => {
                let Some(blob) = blob else {
                    return Err(ctx.err(
                        item,
                        "the buffer refers to the GLB BIN chunk, and the file has none",
                    ));
                };
                bin.get_or_insert_with(|| Rc::from(blob)).clone()
            }
            gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                Rc::from(decode_data_uri(uri).map_err(|m| ctx.err(item.clone(), m))?)
            }
            gltf::buffer::Source::Uri(uri) => {
                let file = relative_file(dir, uri).map_err(|m| ctx.err(item.clone(), m))?;
                match files.get(&file) {
                    Some(bytes) => bytes.clone(),
                    None => {
                        #[allow(clippy::disallowed_methods)]
                        // An edge: an importer reads the buffers its scene names.
                        let bytes: Rc<[u8]> = Rc::from(std::fs::read(&file).map_err(|e| {
                            ctx.err(
                                item.clone(),
                                format!("uri `{uri}`: cannot read {}: {e}", file.display()),
                            )
                        })?);
                        files.insert(file, bytes.clone());
                        bytes
                    }
                }
            }
        };
        if bytes.len() < length {
            let what = match buffer.source() {
                gltf::buffer::Source::Bin => "the GLB BIN chunk".to_owned(),
                gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                    "the data URI".to_owned()
                }
                gltf::buffer::Source::Uri(uri) => format!("`{uri}`"),
            };
            return Err(ctx.err(
                item,
                format!(
                    "{what} is {} bytes, shorter than the buffer's byteLength {length}",
                    bytes.len()
                ),
            ));
        }
        out.push(Buffer { bytes, length });
    }
    Ok(out)
}

/// The bytes of a base64 data URI (`data:[<type>];base64,<data>`); its size
/// is bounded by the URI's, which is part of the file.
pub(super) fn decode_data_uri(uri: &str) -> Result<Vec<u8>, String> {
    let Some((head, data)) = uri.split_once(',') else {
        return Err("a data URI without a `,` before its data".to_owned());
    };
    if !head.ends_with(";base64") {
        return Err(format!(
            "the data URI `{}` is not base64-encoded: only `;base64,` data URIs are read",
            short_text(head)
        ));
    }
    base64::engine::general_purpose::STANDARD
        .decode(data.trim())
        .map_err(|e| format!("the data URI's base64 does not decode: {e}"))
}

/// A buffer URI as a file beside the glTF file: percent-decoded (RFC 3986,
/// §2.1) and relative; URIs with a scheme name nothing that can be read here.
pub(super) fn relative_file(dir: &Path, uri: &str) -> Result<PathBuf, String> {
    let scheme = uri.split_once(':').map(|(s, _)| s).filter(|s| {
        s.len() > 1
            && s.chars()
                .all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c))
    });
    if let Some(scheme) = scheme {
        return Err(format!(
            "uri `{}`: only relative file names and data URIs are read, not `{scheme}:` URIs",
            short_text(uri)
        ));
    }
    let mut bytes = Vec::with_capacity(uri.len());
    let raw = uri.as_bytes();
    let mut i = 0;
    while i < raw.len() {
        if raw[i] == b'%' {
            let hex = raw
                .get(i + 1..i + 3)
                .and_then(|h| std::str::from_utf8(h).ok())
                .and_then(|h| u8::from_str_radix(h, 16).ok());
            let Some(byte) = hex else {
                return Err(format!(
                    "uri `{}`: a `%` not followed by two hex digits",
                    short_text(uri)
                ));
            };
            bytes.push(byte);
            i += 3;
        } else {
            bytes.push(raw[i]);
            i += 1;
        }
    }
    let name = String::from_utf8(bytes)
        .map_err(|_| format!("uri `{}` does not decode to UTF-8", short_text(uri)))?;
    Ok(dir.join(name))
}

/// The first 60 characters of a text, for messages about long URIs.
fn short_text(text: &str) -> String {
    match text.char_indices().nth(60) {
        Some((at, _)) => format!("{}…", &text[..at]),
        None => text.to_owned(),
    }
}

/// Every buffer view lies inside its buffer.
pub(super) fn check_views(
    ctx: &Context,
    document: &Document,
    buffers: &[Buffer],
) -> Result<(), SceneError> {
    for view in document.views() {
        let buffer = view.buffer().index();
        let end = view.offset() as u64 + view.length() as u64;
        let have = buffers[buffer].data().len() as u64;
        if end > have {
            return Err(ctx.err(
                format!("bufferView {}", view.index()),
                format!(
                    "the view spans bytes {}..{end} of buffer {buffer}, which has {have}: \
                     the buffer is shorter than its views",
                    view.offset()
                ),
            ));
        }
        if let Some(stride) = view.stride() {
            if !(4..=252).contains(&stride) || !stride.is_multiple_of(4) {
                return Err(ctx.err(
                    format!("bufferView {}", view.index()),
                    format!("byteStride {stride} is not a multiple of 4 in 4..=252"),
                ));
            }
        }
    }
    Ok(())
}
