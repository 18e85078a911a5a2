//! Diffuse textures as the solve and the path tracer use them: linear-RGB
//! texel pyramids, the integral of the albedo over a UV triangle, and bilinear
//! point samples. Pure: decoding files is `scene::texture_file`'s job.
//!
//! * **Colour space.** Texels arrive sRGB-encoded (8 bits) and are decoded to
//!   linear reflectance with the sRGB transfer function (IEC 61966-2-1), so
//!   grey 128 is 0.2159, not 0.502: every average below is of linear values.
//! * **Pyramid.** Level 0 is the decoded image; each next level halves both
//!   sizes (rounding down, at least 1) and is a box filter of the previous
//!   one with fractional overlaps, so every level keeps the exact mean.
//! * **Integration.** A texture is a function constant on each texel (box
//!   reconstruction). The integral of ρ times a corner's barycentric weight
//!   over a UV triangle is computed exactly at one pyramid level: the
//!   triangle is clipped to every texel cell it touches (Sutherland and
//!   Hodgman 1974) and, since the barycentric weight is linear, its integral
//!   over a clipped piece is the piece's area times its value at the piece's
//!   centroid. The level is the finest at which the triangle's UV bounding box
//!   spans at most [`MAX_CELLS`] cells: an element covering many texels is
//!   integrated from a coarser, pre-averaged level (the mip level), never
//!   from the texel at its centre.
//! * **Wrapping.** UVs repeat (OBJ's and glTF's default): cell (i, j) reads
//!   texel (i mod w, j mod h).
//! * **Orientation.** `v` grows upwards (OBJ, Wavefront 1992): v = 1 is the
//!   image's first row.

use glam::{DVec2, DVec3};

mod integrate;
#[cfg(test)]
mod tests;

pub use integrate::Integral;

/// The most texel cells one triangle's UV bounding box may span at the level
/// it is integrated from: 4096 bounds the clipping work per element (a few
/// tens of microseconds) while an element smaller than 64 × 64 texels is
/// integrated from full resolution.
pub const MAX_CELLS: f64 = 4096.0;

/// One pyramid level: linear RGB, rows top to bottom.
#[derive(Clone, Debug, PartialEq)]
struct Level {
    width: usize,
    height: usize,
    texels: Vec<[f32; 3]>,
}

impl Level {
    /// The texel of cell (i, j), wrapped (repeat).
    fn texel(&self, i: i64, j: i64) -> DVec3 {
        let x = i.rem_euclid(self.width as i64) as usize;
        let y = j.rem_euclid(self.height as i64) as usize;
        DVec3::from_array(self.texels[y * self.width + x].map(f64::from))
    }

    /// The next coarser level: both sizes halved (at least 1), each texel the
    /// box average of the source texels it overlaps, fractionally weighted.
    fn halved(&self) -> Level {
        let width = (self.width / 2).max(1);
        let height = (self.height / 2).max(1);
        let wx = box_weights(self.width, width);
        let wy = box_weights(self.height, height);
        let mut texels = Vec::with_capacity(width * height);
        for row in &wy {
            for column in &wx {
                let mut sum = DVec3::ZERO;
                for &(y, a) in row {
                    for &(x, b) in column {
                        let t = self.texels[y * self.width + x].map(f64::from);
                        sum += DVec3::from_array(t) * (a * b);
                    }
                }
                texels.push(sum.as_vec3().to_array());
            }
        }
        Level {
            width,
            height,
            texels,
        }
    }
}

/// Per destination texel of a 1-D box resampling from `from` to `to` texels,
/// the source texels and their weights (overlap length / destination length,
/// summing to 1).
fn box_weights(from: usize, to: usize) -> Vec<Vec<(usize, f64)>> {
    let scale = from as f64 / to as f64;
    (0..to)
        .map(|d| {
            let (lo, hi) = (d as f64 * scale, (d + 1) as f64 * scale);
            let mut weights = Vec::new();
            let mut s = lo.floor() as usize;
            while (s as f64) < hi && s < from {
                let overlap = (hi.min(s as f64 + 1.0) - lo.max(s as f64)).max(0.0);
                if overlap > 0.0 {
                    weights.push((s, overlap / scale));
                }
                s += 1;
            }
            weights
        })
        .collect()
}

/// sRGB 8-bit code to linear value (IEC 61966-2-1).
pub fn srgb_to_linear(code: u8) -> f32 {
    let c = f64::from(code) / 255.0;
    let linear = if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    };
    linear as f32
}

/// The 8-bit sRGB code whose linear value ([`srgb_to_linear`]) is nearest
/// `linear` (clamped to [0, 1]): the error is at most half the step between
/// neighbouring codes' linear values, under 0.0045 everywhere and under
/// 0.0023 below 0.2. Used to store a reflectance computed at import (glTF's
/// metallic-roughness fold, `scene::metal_texture`) as the solution file's
/// RGBA8 texels, so that the solve and the display read the same value.
pub fn linear_to_srgb8(linear: f64) -> u8 {
    let linear = linear.clamp(0.0, 1.0);
    let c = if linear <= 0.0031308 {
        12.92 * linear
    } else {
        1.055 * linear.powf(1.0 / 2.4) - 0.055
    };
    let guess = (c * 255.0).round().clamp(0.0, 255.0) as u8;
    let error = |code: u8| (f64::from(srgb_to_linear(code)) - linear).abs();
    [guess.saturating_sub(1), guess, guess.saturating_add(1)]
        .into_iter()
        .min_by(|a, b| error(*a).total_cmp(&error(*b)))
        .unwrap_or(guess)
}

/// A diffuse texture: its linear-RGB pyramid.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    levels: Vec<Level>,
}

impl Texture {
    /// A texture from sRGB-encoded 8-bit texels of `channels` (3 or 4: RGB
    /// or RGBA, alpha ignored) each, rows top to bottom. `None` when a size is
    /// zero or `pixels` is not `channels · width · height` long.
    pub fn from_srgb(
        width: usize,
        height: usize,
        pixels: &[u8],
        channels: usize,
    ) -> Option<Texture> {
        let count = width.checked_mul(height)?;
        if count == 0 || channels < 3 || pixels.len() != count.checked_mul(channels)? {
            return None;
        }
        let table: Vec<f32> = (0..=255u8).map(srgb_to_linear).collect();
        let texels = pixels
            .chunks_exact(channels)
            .map(|c| {
                [
                    table[c[0] as usize],
                    table[c[1] as usize],
                    table[c[2] as usize],
                ]
            })
            .collect();
        Some(Texture::from_linear(width, height, texels))
    }

    /// A texture from linear RGB texels, rows top to bottom (sizes checked by
    /// the caller: `texels.len() == width · height > 0`).
    fn from_linear(width: usize, height: usize, texels: Vec<[f32; 3]>) -> Texture {
        let mut levels = vec![Level {
            width,
            height,
            texels,
        }];
        while let Some(last) = levels.last().filter(|l| l.width > 1 || l.height > 1) {
            let next = last.halved();
            levels.push(next);
        }
        Texture { levels }
    }

    /// Level 0's size in texels.
    pub fn size(&self) -> (usize, usize) {
        (self.levels[0].width, self.levels[0].height)
    }

    /// Bytes held: every level's texels.
    pub fn bytes(&self) -> u64 {
        self.levels
            .iter()
            .map(|l| (l.texels.len() * std::mem::size_of::<[f32; 3]>()) as u64)
            .sum()
    }

    /// Bytes a `width` × `height` texture will hold, before decoding it: 12
    /// bytes per texel and at most 4/3 of that for the pyramid (plus one row
    /// and column per level for odd sizes, bounded by the 1.5 used here).
    pub fn bytes_for(width: u64, height: u64) -> u64 {
        width
            .saturating_mul(height)
            .saturating_mul(12)
            .saturating_mul(3)
            / 2
    }

    /// The mean albedo over the whole texture (the coarsest level's texel).
    pub fn mean(&self) -> DVec3 {
        let last = self
            .levels
            .last()
            .expect("a texture has at least one level");
        last.texel(0, 0)
    }

    /// Bilinear sample of level 0 at `uv` (repeat wrap), the path tracer's
    /// reconstruction.
    pub fn bilinear(&self, uv: DVec2) -> DVec3 {
        let level = &self.levels[0];
        let x = uv.x * level.width as f64 - 0.5;
        let y = (1.0 - uv.y) * level.height as f64 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (i, j) = (x0 as i64, y0 as i64);
        let top = level.texel(i, j) * (1.0 - fx) + level.texel(i + 1, j) * fx;
        let bottom = level.texel(i, j + 1) * (1.0 - fx) + level.texel(i + 1, j + 1) * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// The integral of the albedo over the UV triangle `uv`, and of the albedo
    /// times each corner's barycentric weight, both divided by the triangle's
    /// UV area (see the module notes).
    pub fn integrate(&self, uv: [DVec2; 3]) -> Integral {
        integrate::integrate(self, uv)
    }
}
