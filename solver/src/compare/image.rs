//! The images `solver compare` works on: linear RGB radiance, row 0 at the top,
//! and the optional per-pixel channels a reference render carries beside it.

/// Linear RGB radiance, interleaved, row-major with row 0 at the top.
#[derive(Debug, Clone, PartialEq)]
pub struct Image {
    pub width: usize,
    pub height: usize,
    /// `width × height × 3` values.
    pub rgb: Vec<f32>,
}

/// Rec. 709 / sRGB-primaries luminance weights (ITU-R BT.709-6, item 3.3).
pub const LUMINANCE_WEIGHTS: [f32; 3] = [0.2126, 0.7152, 0.0722];

/// Luminance Y of one linear RGB triple.
pub fn luminance(rgb: &[f32]) -> f32 {
    LUMINANCE_WEIGHTS[0] * rgb[0] + LUMINANCE_WEIGHTS[1] * rgb[1] + LUMINANCE_WEIGHTS[2] * rgb[2]
}

impl Image {
    /// An image of one colour.
    pub fn filled(width: usize, height: usize, rgb: [f32; 3]) -> Image {
        Image {
            width,
            height,
            rgb: rgb
                .iter()
                .copied()
                .cycle()
                .take(width * height * 3)
                .collect(),
        }
    }

    /// The mean of each `factor × factor` block of pixels: a supersampled render
    /// brought to a reference's pixel footprints, since a reference pixel is the
    /// mean radiance over its square (design notes, "Truth, not self-consistency").
    /// `factor` must divide both sides; the caller checks it.
    pub fn box_downsample(&self, factor: usize) -> Image {
        let (width, height) = (self.width / factor, self.height / factor);
        let mut rgb = vec![0f32; width * height * 3];
        let weight = 1.0 / (factor * factor) as f64;
        for y in 0..height {
            for x in 0..width {
                for c in 0..3 {
                    let mut sum = 0f64;
                    for j in 0..factor {
                        let row = (y * factor + j) * self.width;
                        for i in 0..factor {
                            sum += self.rgb[(row + x * factor + i) * 3 + c] as f64;
                        }
                    }
                    rgb[(y * width + x) * 3 + c] = (sum * weight) as f32;
                }
            }
        }
        Image { width, height, rgb }
    }

    /// The integer factor by which this image is a supersampled version of one of
    /// `width × height` (the same factor on both sides), if it is one.
    pub fn supersampling_factor(&self, width: usize, height: usize) -> Option<usize> {
        if width == 0 || height == 0 || !self.width.is_multiple_of(width) {
            return None;
        }
        let factor = self.width / width;
        (factor > 1 && self.height == height * factor).then_some(factor)
    }

    pub fn pixel_count(&self) -> usize {
        self.width * self.height
    }

    /// The RGB triples, one per pixel.
    pub fn pixels(&self) -> std::slice::ChunksExact<'_, f32> {
        self.rgb.chunks_exact(3)
    }

    /// Luminance of every pixel.
    pub fn luminances(&self) -> Vec<f32> {
        self.pixels().map(luminance).collect()
    }

    /// The first non-finite value, as (pixel x, pixel y, channel), with the number
    /// of non-finite values.
    pub fn first_non_finite(&self) -> Option<((usize, usize, usize), usize)> {
        let count = self.rgb.iter().filter(|v| !v.is_finite()).count();
        let first = self.rgb.iter().position(|v| !v.is_finite())?;
        let pixel = first / 3;
        Some(((pixel % self.width, pixel / self.width, first % 3), count))
    }
}

/// Per-pixel identifiers from a reference render: which material or object each
/// pixel shows, and the names the indices stand for.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct IdChannel {
    /// One index per pixel; −1 where the primary ray hit nothing.
    pub ids: Vec<i32>,
    /// Names by index, from the header's JSON array (may be empty).
    pub names: Vec<String>,
}

impl IdChannel {
    /// The display name of an index: its name, "(no hit)" for −1, or `#i` when the
    /// header names fewer entries.
    pub fn name(&self, id: i32) -> String {
        if id < 0 {
            return "(no hit)".into();
        }
        match self.names.get(id as usize) {
            Some(name) => name.clone(),
            None => format!("#{id}"),
        }
    }
}

/// An image as read from a file, with whatever extra channels it carried.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadedImage {
    pub image: Image,
    /// Standard error of each pixel's RGB estimate (`se.R`, `se.G`, `se.B`).
    pub standard_error: Option<Vec<f32>>,
    pub material_id: Option<IdChannel>,
    pub object_id: Option<IdChannel>,
}

impl LoadedImage {
    pub fn plain(image: Image) -> LoadedImage {
        LoadedImage {
            image,
            standard_error: None,
            material_id: None,
            object_id: None,
        }
    }
}

#[cfg(test)]
mod downsample_tests {
    use super::*;

    #[test]
    fn box_downsample_averages_each_block() {
        // A 4×2 image with pixel values 0..8 (all channels alike) at factor 2:
        // blocks {0,1,4,5} and {2,3,6,7} average to 2.5 and 4.5 exactly.
        let rgb = (0..8).flat_map(|v| [v as f32; 3]).collect();
        let image = Image {
            width: 4,
            height: 2,
            rgb,
        };
        let small = image.box_downsample(2);
        assert_eq!((small.width, small.height), (2, 1));
        assert_eq!(small.rgb, vec![2.5, 2.5, 2.5, 4.5, 4.5, 4.5]);
        assert_eq!(image.supersampling_factor(2, 1), Some(2));
        assert_eq!(image.supersampling_factor(4, 2), None);
        assert_eq!(image.supersampling_factor(3, 1), None);
        assert_eq!(image.supersampling_factor(2, 2), None);
    }
}
