//! Texture sampling shared by every renderer of a textured solution: the mip
//! chain (what the runtime uploads, level for level) and Vulkan's trilinear
//! filter in f64 (what the CPU reference renderer draws with).
//!
//! Conventions (docs/solution-format.md, "Textures (format 2)"): texels are 8-bit
//! sRGB, decoded to linear per texel *before* filtering (as a Vulkan `*_SRGB`
//! image is, Vulkan spec "Texel Filtering"); UVs follow OBJ (v = 0 is the image's
//! bottom row), so the image coordinate is `t = 1 − v`; the texture repeats.
//!
//! **Mip levels.** Level `k + 1` is `max(1, ⌊w/2⌋) × max(1, ⌊h/2⌋)`, each texel the
//! mean, in linear light, of the 2 × 2 texels above it (1 × 2, 2 × 1 or 1 when the
//! level above is 1 wide or high; with an odd size the last row or column is
//! left out, as Vulkan's level sizes imply), encoded back to sRGB8 by rounding.
//! Averaging sRGB bytes directly would darken a checkerboard's mean by a third
//! (mean of 0 and 255 is 128, i.e. 0.216 linear instead of 0.5).

use crate::format::Texture;
use crate::raster::{linear_to_srgb, srgb_to_linear};

/// One mip level: 8-bit sRGB RGBA, rows top to bottom.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Level {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<u8>,
}

/// The 256 sRGB byte values decoded to linear (IEC 61966-2-1).
fn srgb_table() -> &'static [f32; 256] {
    static TABLE: std::sync::OnceLock<[f32; 256]> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| std::array::from_fn(|k| srgb_to_linear(k as f32 / 255.0)))
}

/// An sRGB byte decoded to linear.
pub fn srgb8_to_linear(byte: u8) -> f32 {
    srgb_table()[byte as usize]
}

/// A linear value encoded to the nearest sRGB byte.
fn linear_to_srgb8(linear: f64) -> u8 {
    (linear_to_srgb(linear as f32) * 255.0 + 0.5).floor() as u8
}

/// A texture and its whole mip chain, down to 1 × 1.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MipChain {
    levels: Vec<Level>,
}

impl MipChain {
    /// Builds the chain from level 0 (`texture` must hold `width × height × 4`
    /// bytes, as the format's reader and writer guarantee; a short buffer reads
    /// as black).
    pub fn new(texture: &Texture) -> MipChain {
        let mut levels = vec![Level {
            width: texture.width.max(1),
            height: texture.height.max(1),
            rgba: texture.rgba.clone(),
        }];
        let expected = levels[0].width as usize * levels[0].height as usize * 4;
        levels[0].rgba.resize(expected, 0);
        while let Some(next) = levels.last().and_then(downsample) {
            levels.push(next);
        }
        MipChain { levels }
    }

    pub fn levels(&self) -> &[Level] {
        &self.levels
    }

    /// Vulkan's level of detail λ = log2 ρ, ρ the larger of the lengths of the
    /// texel-space derivatives along x and along y (Vulkan spec, "Scale Factor
    /// Operation"; the exact form, which implementations may approximate).
    pub fn lod(&self, du_dx: f64, dv_dx: f64, du_dy: f64, dv_dy: f64) -> f64 {
        let (w, h) = (
            f64::from(self.levels[0].width),
            f64::from(self.levels[0].height),
        );
        let along_x = (du_dx * w).hypot(dv_dx * h);
        let along_y = (du_dy * w).hypot(dv_dy * h);
        along_x.max(along_y).log2()
    }

    /// Linear RGB at (u, v) filtered trilinearly at level of detail `lod`
    /// (`minFilter = magFilter = LINEAR`, `mipmapMode = LINEAR`, REPEAT): λ
    /// clamped to [0, last level], the two levels around it blended by its
    /// fraction.
    pub fn sample_trilinear(&self, u: f64, v: f64, lod: f64) -> [f64; 3] {
        let last = (self.levels.len() - 1) as f64;
        let lod = if lod.is_nan() {
            0.0
        } else {
            lod.clamp(0.0, last)
        };
        let lower = lod.floor();
        let f = lod - lower;
        let a = self.sample_bilinear(lower as usize, u, v);
        if f == 0.0 {
            return a;
        }
        let b = self.sample_bilinear((lower as usize + 1).min(self.levels.len() - 1), u, v);
        [0, 1, 2].map(|c| a[c] + (b[c] - a[c]) * f)
    }

    /// Linear RGB at (u, v) on one level, bilinear between the four texels
    /// around `(u·w − ½, (1 − v)·h − ½)`, wrapping (REPEAT).
    pub fn sample_bilinear(&self, level: usize, u: f64, v: f64) -> [f64; 3] {
        let level = &self.levels[level.min(self.levels.len() - 1)];
        let (w, h) = (i64::from(level.width), i64::from(level.height));
        let x = u * w as f64 - 0.5;
        let y = (1.0 - v) * h as f64 - 0.5;
        if !(x.is_finite() && y.is_finite()) {
            return [0.0; 3];
        }
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let texel = |i: f64, j: f64| -> [f64; 3] {
            // `rem_euclid` in f64 first: a huge UV must not overflow the i64.
            let i = i.rem_euclid(w as f64) as usize;
            let j = j.rem_euclid(h as f64) as usize;
            let at = (j * w as usize + i) * 4;
            [0, 1, 2].map(|c| f64::from(srgb8_to_linear(level.rgba[at + c])))
        };
        let (t00, t10) = (texel(x0, y0), texel(x0 + 1.0, y0));
        let (t01, t11) = (texel(x0, y0 + 1.0), texel(x0 + 1.0, y0 + 1.0));
        [0, 1, 2].map(|c| {
            let top = t00[c] + (t10[c] - t00[c]) * fx;
            let bottom = t01[c] + (t11[c] - t01[c]) * fx;
            top + (bottom - top) * fy
        })
    }
}

/// The next mip level, or `None` below 1 × 1.
fn downsample(level: &Level) -> Option<Level> {
    if level.width == 1 && level.height == 1 {
        return None;
    }
    let (w, h) = (level.width as usize, level.height as usize);
    let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
    let (sx, sy) = (if w > 1 { 2 } else { 1 }, if h > 1 { 2 } else { 1 });
    let mut rgba = vec![0u8; nw * nh * 4];
    for j in 0..nh {
        for i in 0..nw {
            let mut sum = [0.0f64; 4];
            for dy in 0..sy {
                for dx in 0..sx {
                    let at = ((j * sy + dy) * w + i * sx + dx) * 4;
                    for (c, total) in sum.iter_mut().take(3).enumerate() {
                        *total += f64::from(srgb8_to_linear(level.rgba[at + c]));
                    }
                    // Alpha is linear coverage, not sRGB.
                    sum[3] += f64::from(level.rgba[at + 3]);
                }
            }
            let n = (sx * sy) as f64;
            let out = (j * nw + i) * 4;
            for c in 0..3 {
                rgba[out + c] = linear_to_srgb8(sum[c] / n);
            }
            rgba[out + 3] = (sum[3] / n).round() as u8;
        }
    }
    Some(Level {
        width: nw as u32,
        height: nh as u32,
        rgba,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An n × n checkerboard of 1-texel squares, black (0) and white (255).
    fn checker(n: u32) -> Texture {
        let rgba = (0..n * n)
            .flat_map(|k| {
                let on = ((k % n) + (k / n)).is_multiple_of(2);
                let b = if on { 255 } else { 0 };
                [b, b, b, 255]
            })
            .collect();
        Texture {
            width: n,
            height: n,
            rgba,
        }
    }

    #[test]
    fn mips_average_in_linear_light_down_to_one_texel() {
        let chain = MipChain::new(&checker(8));
        let sizes: Vec<_> = chain.levels().iter().map(|l| (l.width, l.height)).collect();
        assert_eq!(sizes, vec![(8, 8), (4, 4), (2, 2), (1, 1)]);
        // Black and white average to linear 0.5 (sRGB byte 188), not byte 128.
        let one = &chain.levels()[3].rgba;
        assert_eq!(one[0], linear_to_srgb8(0.5));
        assert_eq!(one[0], 188);
        // Non-square and odd sizes follow Vulkan's ⌊/2⌋ chain.
        let odd = Texture {
            width: 5,
            height: 2,
            rgba: vec![255; 5 * 2 * 4],
        };
        let sizes: Vec<_> = MipChain::new(&odd)
            .levels()
            .iter()
            .map(|l| (l.width, l.height))
            .collect();
        assert_eq!(sizes, vec![(5, 2), (2, 1), (1, 1)]);
    }

    #[test]
    fn bilinear_hits_texel_centres_and_wraps() {
        let chain = MipChain::new(&checker(4));
        // Texel (0, 0) is white; its centre is u = 1/8, v = 1 − 1/8.
        assert_eq!(chain.sample_bilinear(0, 0.125, 0.875), [1.0; 3]);
        assert_eq!(chain.sample_bilinear(0, 0.375, 0.875), [0.0; 3]);
        // REPEAT: one period over is the same texel.
        assert_eq!(chain.sample_bilinear(0, 1.125, -0.125), [1.0; 3]);
        // Halfway between a white and a black centre: linear 0.5.
        let mid = chain.sample_bilinear(0, 0.25, 0.875);
        assert!((mid[0] - 0.5).abs() < 1e-12, "{mid:?}");
        // At the texture's edge (u = 0) the filter blends with the wrapped texel
        // (3, 0), which is black.
        let edge = chain.sample_bilinear(0, 0.0, 0.875);
        assert!((edge[0] - 0.5).abs() < 1e-12, "{edge:?}");
    }

    #[test]
    fn trilinear_blends_levels_by_the_lod_fraction() {
        let chain = MipChain::new(&checker(4));
        // Level 2 (1 × 1) is linear 0.5 ± the sRGB rounding of byte 188.
        let top = srgb8_to_linear(188) as f64;
        let at = |lod| chain.sample_trilinear(0.125, 0.875, lod)[0];
        assert_eq!(at(0.0), 1.0);
        assert_eq!(at(-3.0), 1.0);
        assert!((at(2.0) - top).abs() < 1e-12);
        assert!((at(9.0) - top).abs() < 1e-12);
        let level1 = chain.sample_bilinear(1, 0.125, 0.875)[0];
        assert!((at(0.25) - (0.75 + 0.25 * level1)).abs() < 1e-12);
        // λ from derivatives: one texel per pixel is level 0, four is level 2.
        assert!((chain.lod(0.25, 0.0, 0.0, 0.25)).abs() < 1e-12);
        assert!((chain.lod(1.0, 0.0, 0.0, 0.5) - 2.0).abs() < 1e-12);
    }
}
