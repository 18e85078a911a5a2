//! Texture sections: 8-bit sRGB images stored as PNG, checked before decoding.
//!
//! A texture section is a 16-byte prefix (width, height, encoding, reserved)
//! followed by a PNG stream. The reader checks the prefix and the PNG's IHDR
//! chunk against each other and against the caps in [`super::layout`] before
//! anything is decoded, so a hostile file cannot make a reader allocate more
//! than [`layout::MAX_DECODED_TEXTURE_BYTES`] nor more than
//! [`layout::DEFLATE_MAX_RATIO`] times the PNG's length (the most deflate can
//! expand). PNG rather than a block-compressed format: lossless, so the texture
//! the solver integrated is the one every renderer shows, and decodable by the
//! `png` crate without a GPU; the runtime decodes once at load (the one exception
//! to "uploaded as stored", docs/solution-format.md).

use super::error::Problem;
use super::layout::{self, Fields};
use super::Texture;

/// What a texture section declares, as the runtime needs it to size images.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TextureInfo {
    pub width: u32,
    pub height: u32,
    /// Length of the encoded image (the section less its prefix).
    pub encoded_bytes: u64,
}

impl TextureInfo {
    /// Bytes of the decoded RGBA8 image (mip level 0).
    pub fn decoded_bytes(&self) -> u64 {
        u64::from(self.width) * u64::from(self.height) * 4
    }
}

const PNG_SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', b'\r', b'\n', 0x1A, b'\n'];

fn bad(texture: u32, reason: impl Into<String>) -> Problem {
    Problem::Texture {
        texture,
        reason: reason.into(),
    }
}

/// Checks a texture section's prefix and its PNG header (signature, IHDR:
/// dimensions equal to the prefix's and within [`layout::MAX_TEXTURE_SIZE`], 8-bit
/// samples, a known colour type, raw scanlines deflate could produce from the
/// stream's length). Reads 16 + 33 bytes; decodes nothing.
pub(crate) fn check_section(
    texture: u32,
    section: &[u8],
    newer: bool,
) -> Result<TextureInfo, Problem> {
    use layout::texture as tf;
    let prefix = Fields::new(section, layout::TEXTURE_PREFIX_LEN).ok_or_else(|| {
        bad(
            texture,
            format!(
                "the section has {} bytes, fewer than its {}-byte prefix",
                section.len(),
                layout::TEXTURE_PREFIX_LEN
            ),
        )
    })?;
    let (width, height) = (prefix.u32(tf::WIDTH), prefix.u32(tf::HEIGHT));
    let encoding = prefix.u32(tf::ENCODING);
    if encoding != layout::ENCODING_PNG_SRGB8 {
        return Err(Problem::UnknownCode {
            field: format!("texture {texture}: encoding"),
            code: encoding,
        });
    }
    if prefix.u32(tf::RESERVED) != 0 && !newer {
        return Err(Problem::Reserved {
            field: format!("texture {texture}: reserved word"),
            value: prefix.u32(tf::RESERVED).into(),
        });
    }
    check_dimensions(texture, width, height)?;
    let png = &section[layout::TEXTURE_PREFIX_LEN..];
    check_png_header(texture, width, height, png)?;
    Ok(TextureInfo {
        width,
        height,
        encoded_bytes: png.len() as u64,
    })
}

fn check_dimensions(texture: u32, width: u32, height: u32) -> Result<(), Problem> {
    for (what, value) in [("width", width), ("height", height)] {
        if value == 0 {
            return Err(bad(texture, format!("the {what} is 0")));
        }
        if value > layout::MAX_TEXTURE_SIZE {
            return Err(Problem::TooLarge {
                what: format!("texture {texture}: {what}"),
                value: value.into(),
                limit: layout::MAX_TEXTURE_SIZE.into(),
                reason: "GPUs guarantee 16384 (maxImageDimension2D) and it bounds a decoded texture at 1 GiB",
            });
        }
    }
    Ok(())
}

/// Samples per pixel of an 8-bit PNG colour type (grey, RGB, palette, grey +
/// alpha, RGBA), `None` for an unknown type.
fn channels(color_type: u8) -> Option<u64> {
    match color_type {
        0 | 3 => Some(1),
        2 => Some(3),
        4 => Some(2),
        6 => Some(4),
        _ => None,
    }
}

fn check_png_header(texture: u32, width: u32, height: u32, png: &[u8]) -> Result<(), Problem> {
    if png.get(..8) != Some(&PNG_SIGNATURE[..]) {
        return Err(bad(
            texture,
            "the image is not a PNG stream (wrong signature)",
        ));
    }
    // The IHDR chunk must come first: length 13, type, then width, height, bit
    // depth, colour type, compression, filter, interlace (PNG spec, 11.2.2).
    let ihdr = png
        .get(8..8 + 8 + 13)
        .ok_or_else(|| bad(texture, "the PNG stream ends inside its IHDR chunk"))?;
    let be = |at: usize| u32::from_be_bytes([ihdr[at], ihdr[at + 1], ihdr[at + 2], ihdr[at + 3]]);
    if be(0) != 13 || &ihdr[4..8] != b"IHDR" {
        return Err(bad(
            texture,
            "the PNG stream does not start with an IHDR chunk",
        ));
    }
    let (png_width, png_height) = (be(8), be(12));
    if (png_width, png_height) != (width, height) {
        return Err(bad(
            texture,
            format!(
                "the PNG is {png_width}×{png_height} but the section declares {width}×{height}"
            ),
        ));
    }
    let (depth, color_type) = (ihdr[16], ihdr[17]);
    let Some(samples) = channels(color_type).filter(|_| depth == 8) else {
        return Err(bad(
            texture,
            format!("bit depth {depth}, colour type {color_type}: the format stores 8-bit grey, grey + alpha, RGB, RGBA or palette PNGs"),
        ));
    };
    let raw = u64::from(height) * (1 + u64::from(width) * samples);
    let most = layout::DEFLATE_MAX_RATIO.saturating_mul(png.len() as u64);
    if raw > most {
        return Err(bad(
            texture,
            format!(
                "{width}×{height} needs {raw} bytes of scanlines but deflate expands its {} bytes to at most {most} (truncated or hostile)",
                png.len()
            ),
        ));
    }
    Ok(())
}

/// Decodes a PNG stream to 8-bit sRGB RGBA (grey replicated, palette expanded,
/// missing alpha set to 255), refusing anything but a complete 8-bit image of
/// `width × height`. The decoder may allocate at most the decoded image plus
/// 1 MiB of working memory (`png::Limits`).
pub fn decode_png(png: &[u8], width: u32, height: u32) -> Result<Texture, String> {
    let decoded = u64::from(width) * u64::from(height) * 4;
    let limit = usize::try_from(decoded + (1 << 20)).map_err(|_| "too large for this machine")?;
    let mut decoder =
        png::Decoder::new_with_limits(std::io::Cursor::new(png), png::Limits { bytes: limit });
    decoder.set_transformations(png::Transformations::ALPHA);
    let mut reader = decoder.read_info().map_err(|e| format!("PNG: {e}"))?;
    let (w, h) = reader.info().size();
    if (w, h) != (width, height) {
        return Err(format!("the PNG is {w}×{h}, not {width}×{height}"));
    }
    let size = reader
        .output_buffer_size()
        .ok_or("the PNG's size overflows")?;
    if size as u64 > decoded {
        return Err(format!(
            "the PNG decodes to {size} bytes, more than {decoded}"
        ));
    }
    let mut buffer = vec![0u8; size];
    let frame = reader
        .next_frame(&mut buffer)
        .map_err(|e| format!("PNG: {e}"))?;
    buffer.truncate(frame.buffer_size());
    let pixels = (u64::from(width) * u64::from(height)) as usize;
    let rgba = match (frame.color_type, frame.bit_depth) {
        (png::ColorType::Rgba, png::BitDepth::Eight) if buffer.len() == pixels * 4 => buffer,
        (png::ColorType::GrayscaleAlpha, png::BitDepth::Eight) if buffer.len() == pixels * 2 => {
            buffer
                .chunks_exact(2)
                .flat_map(|ga| [ga[0], ga[0], ga[0], ga[1]])
                .collect()
        }
        (color, depth) => {
            return Err(format!(
                "the PNG decodes to {color:?} at {depth:?} bits ({} bytes), not 8-bit RGBA",
                buffer.len()
            ))
        }
    };
    Ok(Texture {
        width,
        height,
        rgba,
    })
}

/// Encodes a texture as an RGBA8 PNG (lossless).
pub fn encode_png(texture: &Texture) -> Result<Vec<u8>, String> {
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, texture.width, texture.height);
    encoder.set_color(png::ColorType::Rgba);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_compression(png::Compression::Fast);
    let mut writer = encoder.write_header().map_err(|e| e.to_string())?;
    writer
        .write_image_data(&texture.rgba)
        .map_err(|e| e.to_string())?;
    writer.finish().map_err(|e| e.to_string())?;
    Ok(out)
}

/// The whole texture section: prefix and PNG.
pub(crate) fn section_bytes(texture: &Texture, png: &[u8]) -> Vec<u8> {
    let mut bytes = vec![0u8; layout::TEXTURE_PREFIX_LEN];
    let mut f = layout::FieldsMut::new(&mut bytes);
    f.u32(layout::texture::WIDTH, texture.width);
    f.u32(layout::texture::HEIGHT, texture.height);
    f.u32(layout::texture::ENCODING, layout::ENCODING_PNG_SRGB8);
    bytes.extend_from_slice(png);
    bytes
}

/// Checks an in-memory texture: dimensions within the cap and `rgba` of
/// `width × height × 4` bytes.
pub(crate) fn check_texture(index: u32, texture: &Texture) -> Result<(), Problem> {
    check_dimensions(index, texture.width, texture.height)?;
    let expected = u64::from(texture.width) * u64::from(texture.height) * 4;
    if texture.rgba.len() as u64 != expected {
        return Err(bad(
            index,
            format!(
                "{} RGBA bytes for {}×{} pixels (expected {expected})",
                texture.rgba.len(),
                texture.width,
                texture.height
            ),
        ));
    }
    Ok(())
}
