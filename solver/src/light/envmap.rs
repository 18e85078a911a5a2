//! Equirectangular environment maps (issue 41, sky `kind = "map"`): the
//! Radiance RGBE (`.hdr`) reader, pure over bytes, and the lookup of a
//! direction's radiance. OpenEXR maps are read at the importer's edge
//! (`scene/envmap_file.rs`) and handed here as texels.
//!
//! Orientation (docs/lights.md, "Environment maps"): row 0 is the zenith
//! (the scene's up), the last row the nadir, rows uniform in the polar
//! angle θ; column 0 starts at the azimuth of the scene's north, and the
//! columns run toward east, uniform in azimuth φ over 360°: the texel at
//! (φ, θ) shows the sky in the direction cos φ sin θ north + sin φ sin θ
//! east + cos θ up. A `rotation_deg` turns the map about up (toward east).
//! Texel values are radiance, W·sr⁻¹·m⁻² per channel, times `scale`.

use glam::DVec3;
use std::f64::consts::PI;

/// The most texels a map may have: 2²⁶ (8192 × 8192), 768 MiB as f32 RGB.
pub const MAX_TEXELS: u64 = 1 << 26;

/// A map cannot be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EnvMapError {
    #[error("not a Radiance HDR file (it does not start with `#?RADIANCE` or `#?RGBE`)")]
    NotHdr,
    #[error("line {line}: {message}")]
    Header { line: usize, message: String },
    #[error("the map is {width}×{height}, more than the {MAX_TEXELS}-texel limit")]
    TooLarge { width: u64, height: u64 },
    #[error("the pixel data ends in scanline {row} of {height}")]
    Truncated { row: usize, height: usize },
    #[error("scanline {row}: {message}")]
    Scanline { row: usize, message: String },
    #[error("texel {index} is {value}, not a finite radiance ≥ 0")]
    BadTexel { index: usize, value: f32 },
    #[error("the map's {what} is {value}, which must be finite and {range}")]
    Parameter {
        what: &'static str,
        value: f64,
        range: &'static str,
    },
}

/// An equirectangular map of radiance about the scene's up and north.
#[derive(Debug, Clone, PartialEq)]
pub struct EnvMap {
    width: usize,
    height: usize,
    texels: Vec<[f32; 3]>,
    scale: f64,
    /// The rotation about up, radians.
    rotation: f64,
}

impl EnvMap {
    /// A map of `width` × `height` texels (row-major from the zenith row),
    /// each finite and ≥ 0, times `scale` (finite, ≥ 0), turned by
    /// `rotation_deg` about up (finite).
    pub fn new(
        width: usize,
        height: usize,
        texels: Vec<[f32; 3]>,
        scale: f64,
        rotation_deg: f64,
    ) -> Result<Self, EnvMapError> {
        check_size(width as u64, height as u64)?;
        if texels.len() != width * height {
            return Err(EnvMapError::Truncated {
                row: texels.len() / width.max(1),
                height,
            });
        }
        if let Some((index, value)) = texels
            .iter()
            .flatten()
            .enumerate()
            .find(|(_, v)| !(v.is_finite() && **v >= 0.0))
        {
            return Err(EnvMapError::BadTexel {
                index: index / 3,
                value: *value,
            });
        }
        if !(scale.is_finite() && scale >= 0.0) {
            return Err(EnvMapError::Parameter {
                what: "scale",
                value: scale,
                range: "≥ 0",
            });
        }
        if !rotation_deg.is_finite() {
            return Err(EnvMapError::Parameter {
                what: "rotation",
                value: rotation_deg,
                range: "in degrees",
            });
        }
        Ok(EnvMap {
            width,
            height,
            texels,
            scale,
            rotation: rotation_deg.to_radians(),
        })
    }

    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// The radiance toward the unit direction whose components along the
    /// scene's (north, east, up) are `local`: the texel it falls in
    /// (nearest; a map's texels are its samples), times the scale.
    pub fn radiance(&self, local: DVec3) -> DVec3 {
        let theta = local.z.clamp(-1.0, 1.0).acos();
        let phi = (local.y.atan2(local.x) - self.rotation).rem_euclid(2.0 * PI);
        let col = ((phi / (2.0 * PI)) * self.width as f64) as usize;
        let row = ((theta / PI) * self.height as f64) as usize;
        let t = self.texels[row.min(self.height - 1) * self.width + col.min(self.width - 1)];
        DVec3::new(t[0] as f64, t[1] as f64, t[2] as f64) * self.scale
    }

    /// The mean radiance over the upper hemisphere weighted by cos θ, times
    /// π: the irradiance on an open horizontal plane, by the midpoint rule
    /// over the texels (exact for the map as nearest-texel lookup sees it,
    /// up to the rows' sin θ cos θ integrated exactly per row).
    pub fn horizontal_irradiance(&self) -> DVec3 {
        let mut sum = DVec3::ZERO;
        for row in 0..self.height {
            let (t0, t1) = (
                row as f64 * PI / self.height as f64,
                (row + 1) as f64 * PI / self.height as f64,
            );
            if t0 >= 0.5 * PI {
                break;
            }
            let t1 = t1.min(0.5 * PI);
            // ∫ cos θ sin θ dθ over the row, times the column's Δφ.
            let weight = 0.5 * (t1.sin().powi(2) - t0.sin().powi(2)) * 2.0 * PI / self.width as f64;
            for col in 0..self.width {
                let t = self.texels[row * self.width + col];
                sum += DVec3::new(t[0] as f64, t[1] as f64, t[2] as f64) * weight;
            }
        }
        sum * self.scale
    }
}

fn check_size(width: u64, height: u64) -> Result<(), EnvMapError> {
    if width == 0 || height == 0 || width.saturating_mul(height) > MAX_TEXELS {
        return Err(EnvMapError::TooLarge { width, height });
    }
    Ok(())
}

/// Reads a Radiance HDR (RGBE) file (Ward 1991, "Real pixels", Graphics
/// Gems II; the format of Radiance's `color.c`): the `#?RADIANCE` or
/// `#?RGBE` line, header lines up to a blank line (`FORMAT` must be
/// `32-bit_rle_rgbe`; `EXPOSURE` is divided out), the resolution line
/// `-Y height +X width` (the standard orientation only), then scanlines,
/// flat or run-length encoded (the "new" RLE of widths 8 to 32,767).
/// The size is checked against [`MAX_TEXELS`] and the bytes left before
/// anything is allocated.
pub fn parse_hdr(bytes: &[u8]) -> Result<(usize, usize, Vec<[f32; 3]>), EnvMapError> {
    if !(bytes.starts_with(b"#?RADIANCE") || bytes.starts_with(b"#?RGBE")) {
        return Err(EnvMapError::NotHdr);
    }
    let mut at = 0;
    let mut line_no = 0;
    let mut exposure = 1.0f64;
    let next_line = |at: &mut usize| -> Option<String> {
        let end = bytes[*at..].iter().position(|&b| b == b'\n')?;
        let line = String::from_utf8_lossy(&bytes[*at..*at + end])
            .trim()
            .to_owned();
        *at += end + 1;
        Some(line)
    };
    let header_error = |line: usize, message: String| EnvMapError::Header { line, message };
    loop {
        line_no += 1;
        let line =
            next_line(&mut at).ok_or(header_error(line_no, "the header never ends".into()))?;
        if line.is_empty() {
            break;
        }
        if let Some(format) = line.strip_prefix("FORMAT=") {
            if format != "32-bit_rle_rgbe" {
                return Err(header_error(
                    line_no,
                    format!("format `{format}` (only 32-bit_rle_rgbe is read)"),
                ));
            }
        } else if let Some(value) = line.strip_prefix("EXPOSURE=") {
            let e: f64 = value
                .trim()
                .parse()
                .map_err(|_| header_error(line_no, format!("EXPOSURE `{value}`")))?;
            if !(e.is_finite() && e > 0.0) {
                return Err(header_error(line_no, format!("EXPOSURE {e} (must be > 0)")));
            }
            exposure *= e;
        }
    }
    line_no += 1;
    let resolution =
        next_line(&mut at).ok_or(header_error(line_no, "no resolution line".into()))?;
    let (height, width) = parse_resolution(&resolution).ok_or_else(|| {
        header_error(
            line_no,
            format!("resolution `{resolution}` (only `-Y height +X width` is read)"),
        )
    })?;
    check_size(width, height)?;
    let (width, height) = (width as usize, height as usize);
    // Every texel takes at least one byte even run-length encoded (a run
    // of 127 texels takes 2 bytes per channel: 8 for 127): refuse a size
    // the bytes left cannot hold before allocating for it.
    let left = (bytes.len() - at) as u64;
    if (width as u64 * height as u64) > left.saturating_mul(128) {
        return Err(EnvMapError::Truncated { row: 0, height });
    }
    let mut texels = Vec::with_capacity(width * height);
    let mut scanline = vec![[0u8; 4]; width];
    for row in 0..height {
        at = read_scanline(bytes, at, &mut scanline, row, height)?;
        texels.extend(
            scanline
                .iter()
                .map(|rgbe| rgbe_to_radiance(*rgbe, exposure)),
        );
    }
    Ok((width, height, texels))
}

/// `-Y height +X width` → (height, width).
fn parse_resolution(line: &str) -> Option<(u64, u64)> {
    let words: Vec<&str> = line.split_whitespace().collect();
    match words.as_slice() {
        ["-Y", h, "+X", w] => Some((h.parse().ok()?, w.parse().ok()?)),
        _ => None,
    }
}

/// One scanline into `out`, from byte `at`; returns where the next starts.
fn read_scanline(
    bytes: &[u8],
    mut at: usize,
    out: &mut [[u8; 4]],
    row: usize,
    height: usize,
) -> Result<usize, EnvMapError> {
    let width = out.len();
    let truncated = EnvMapError::Truncated { row, height };
    let head = bytes.get(at..at + 4).ok_or(truncated.clone())?;
    let rle = (8..=0x7fff).contains(&width) && head[0] == 2 && head[1] == 2 && head[2] & 0x80 == 0;
    if !rle {
        // Flat: four bytes a texel.
        for texel in out.iter_mut() {
            let b = bytes.get(at..at + 4).ok_or(truncated.clone())?;
            *texel = [b[0], b[1], b[2], b[3]];
            at += 4;
        }
        return Ok(at);
    }
    let encoded = ((head[2] as usize) << 8) | head[3] as usize;
    if encoded != width {
        return Err(EnvMapError::Scanline {
            row,
            message: format!("its run-length header says {encoded} texels, the image {width}"),
        });
    }
    at += 4;
    // Four planes (R, G, B, E), each runs (count > 128: a repeated byte) and
    // literals (count ≤ 128: that many bytes).
    for channel in 0..4 {
        let mut x = 0;
        while x < width {
            let count = *bytes.get(at).ok_or(truncated.clone())? as usize;
            at += 1;
            let (run, n) = if count > 128 {
                (true, count - 128)
            } else {
                (false, count)
            };
            if n == 0 || x + n > width {
                return Err(EnvMapError::Scanline {
                    row,
                    message: format!("a run of {n} texels at {x} of {width}"),
                });
            }
            if run {
                let value = *bytes.get(at).ok_or(truncated.clone())?;
                at += 1;
                out[x..x + n].iter_mut().for_each(|t| t[channel] = value);
            } else {
                let values = bytes.get(at..at + n).ok_or(truncated.clone())?;
                at += n;
                out[x..x + n]
                    .iter_mut()
                    .zip(values)
                    .for_each(|(t, v)| t[channel] = *v);
            }
            x += n;
        }
    }
    Ok(at)
}

/// RGBE to radiance: (m + 0.5) 2^(e − 136) per channel (Radiance's
/// `colr_color`), 0 for e = 0, divided by the header's exposure.
fn rgbe_to_radiance(rgbe: [u8; 4], exposure: f64) -> [f32; 3] {
    if rgbe[3] == 0 {
        return [0.0; 3];
    }
    let f = 2f64.powi(rgbe[3] as i32 - 136) / exposure;
    [0, 1, 2].map(|c| ((rgbe[c] as f64 + 0.5) * f) as f32)
}

/// The RGBE bytes of a radiance (the inverse of [`rgbe_to_radiance`] up to
/// its rounding, for writing test files).
pub fn radiance_to_rgbe(rgb: [f32; 3]) -> [u8; 4] {
    let max = rgb.iter().copied().fold(0.0f32, f32::max) as f64;
    if max < 1e-32 {
        return [0; 4];
    }
    let e = max.log2().floor() as i32 + 1;
    let f = 256.0 / 2f64.powi(e);
    let m = rgb.map(|v| ((v as f64 * f) as u32).min(255) as u8);
    [m[0], m[1], m[2], (e + 128) as u8]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flat (not run-length) HDR file of `texels`.
    fn flat_hdr(width: usize, height: usize, texels: &[[f32; 3]]) -> Vec<u8> {
        let mut out =
            format!("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {height} +X {width}\n").into_bytes();
        for t in texels {
            out.extend(radiance_to_rgbe(*t));
        }
        out
    }

    /// An RLE scanline: one run per channel.
    fn rle_hdr(width: usize, height: usize, value: [f32; 3]) -> Vec<u8> {
        let mut out = format!("#?RGBE\n\n-Y {height} +X {width}\n").into_bytes();
        let rgbe = radiance_to_rgbe(value);
        for _ in 0..height {
            out.extend([2, 2, (width >> 8) as u8, (width & 0xff) as u8]);
            for c in rgbe {
                let mut left = width;
                while left > 0 {
                    let n = left.min(127);
                    out.extend([128 + n as u8, c]);
                    left -= n;
                }
            }
        }
        out
    }

    #[test]
    fn flat_and_run_length_files_read_back_within_rgbe_precision() {
        // RGBE keeps 8 bits of mantissa: a value comes back within 2⁻⁸ of
        // the largest channel, relative.
        let texels: Vec<[f32; 3]> = (0..12)
            .map(|i| [i as f32 * 0.5, 1.0, 1e-3 * i as f32])
            .collect();
        let (w, h, back) = parse_hdr(&flat_hdr(4, 3, &texels)).unwrap();
        assert_eq!((w, h), (4, 3));
        for (a, b) in texels.iter().zip(&back) {
            let max = a.iter().copied().fold(0.0, f32::max);
            for c in 0..3 {
                assert!((a[c] - b[c]).abs() <= max / 256.0 + 1e-30, "{a:?} {b:?}");
            }
        }
        let (w, h, back) = parse_hdr(&rle_hdr(300, 2, [2.0, 0.5, 0.25])).unwrap();
        assert_eq!((w, h, back.len()), (300, 2, 600));
        assert!(back.iter().all(|t| (t[0] - 2.0).abs() <= 2.0 / 256.0));
    }

    #[test]
    fn bad_files_are_refused_before_allocating() {
        assert_eq!(parse_hdr(b"P6\n"), Err(EnvMapError::NotHdr));
        let huge = b"#?RADIANCE\n\n-Y 100000 +X 100000\n".to_vec();
        assert!(matches!(
            parse_hdr(&huge),
            Err(EnvMapError::TooLarge { .. })
        ));
        // A plausible size with almost no data: refused by the bytes left.
        let short = b"#?RADIANCE\n\n-Y 4000 +X 4000\nxx".to_vec();
        assert!(matches!(
            parse_hdr(&short),
            Err(EnvMapError::Truncated { .. })
        ));
        let mut cut = flat_hdr(4, 3, &[[1.0; 3]; 12]);
        cut.truncate(cut.len() - 5);
        assert!(matches!(
            parse_hdr(&cut),
            Err(EnvMapError::Truncated { row: 2, .. })
        ));
        let flipped = b"#?RADIANCE\n\n+Y 2 +X 2\n".to_vec();
        assert!(matches!(
            parse_hdr(&flipped),
            Err(EnvMapError::Header { line: 3, .. })
        ));
        let format = b"#?RADIANCE\nFORMAT=32-bit_rle_xyze\n\n-Y 1 +X 1\n".to_vec();
        assert!(matches!(
            parse_hdr(&format),
            Err(EnvMapError::Header { line: 2, .. })
        ));
    }

    #[test]
    fn lookup_follows_the_stated_orientation() {
        // A 4 × 2 map: the upper row's columns are north, east, south, west
        // quadrants (φ from north toward east); the lower row is black.
        let mut texels = vec![[0.0f32; 3]; 8];
        for (col, texel) in texels.iter_mut().take(4).enumerate() {
            *texel = [col as f32 + 1.0; 3];
        }
        let map = EnvMap::new(4, 2, texels.clone(), 2.0, 0.0).unwrap();
        let up = 0.5f64;
        let dir = |phi_deg: f64| {
            let p = phi_deg.to_radians();
            DVec3::new(p.cos(), p.sin(), up).normalize()
        };
        for (col, phi) in [45.0, 135.0, 225.0, 315.0].into_iter().enumerate() {
            assert_eq!(map.radiance(dir(phi)).x, 2.0 * (col as f64 + 1.0));
        }
        assert_eq!(
            map.radiance(DVec3::new(1.0, 0.0, -0.5).normalize()),
            DVec3::ZERO
        );
        // Turned by 90° toward east, the north quadrant's texel shows east.
        let turned = EnvMap::new(4, 2, texels, 1.0, 90.0).unwrap();
        assert_eq!(turned.radiance(dir(135.0)).x, 1.0);
    }

    #[test]
    fn a_constant_map_gives_pi_l_on_an_open_plane() {
        // ∫ L cos θ dω over the upper hemisphere = πL; the per-row weights
        // are integrated exactly, so only rounding remains (1e-12).
        let map = EnvMap::new(64, 32, vec![[0.5; 3]; 64 * 32], 1.0, 0.0).unwrap();
        assert!((map.horizontal_irradiance().x / (0.5 * PI) - 1.0).abs() < 1e-12);
    }
}
