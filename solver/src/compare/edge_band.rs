//! The error on a reference image's sharp luminance edges, apart from the rest.
//!
//! A mesh interpolates radiance linearly across each element, so a shadow edge
//! sharper than the elements (the sun's penumbra is millimetres wide) is drawn as
//! a ramp one element wide; the path tracer draws it sharp. Pixels along such an
//! edge can be off by a large factor while the smooth parts agree, and a whole-image
//! MARE mixes the two. This module splits the pixels in two classes by the
//! reference alone (the truth decides where the edges are, not the image under
//! test) and reports each class's error.

use super::image::Image;

/// The default max/min luminance ratio over a pixel's 3 × 3 neighbourhood above
/// which it is an edge pixel. Why 2: a path-traced reference at 2–5 % relative
/// noise per pixel has a 3 × 3 max/min from noise alone of about 1.1–1.3 (±2.5σ),
/// so 2 never calls noise an edge; a sun or lamp shadow on a surface in the
/// scenes this was chosen for (the window room: sunlit floor against floor lit by
/// sky and interreflection) has a ratio of 5 or more, so its whole band, including
/// the pixels the penumbra only partly covers, is caught. Material boundaries of
/// more than a factor 2 in luminance (a red wall beside a white one) and creases
/// are edges too: the band is "where the truth changes sharply", whatever the cause.
pub const DEFAULT_EDGE_RATIO: f64 = 2.0;

/// For each pixel, whether the reference's luminance over its 3 × 3
/// neighbourhood (clipped at the image's border) has max > `ratio` × min.
/// A neighbourhood with a black pixel beside a non-black one is an edge; an
/// all-black one is not.
pub fn edge_mask(reference: &Image, ratio: f64) -> Vec<bool> {
    let y = reference.luminances();
    let (w, h) = (reference.width, reference.height);
    let mut mask = vec![false; w * h];
    for row in 0..h {
        for col in 0..w {
            let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
            for r in row.saturating_sub(1)..(row + 2).min(h) {
                for c in col.saturating_sub(1)..(col + 2).min(w) {
                    let v = y[r * w + c] as f64;
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
            }
            mask[row * w + col] = hi > ratio * lo;
        }
    }
    mask
}

/// The mask drawn over the reference, RGB8 row 0 at the top: edge pixels orange,
/// the rest grey by Y / (Y + mean Y), so that one can see which edges the band holds.
pub fn render_mask(reference: &Image, mask: &[bool]) -> Vec<u8> {
    let y = reference.luminances();
    let mean = y.iter().map(|&v| v as f64).sum::<f64>() / y.len().max(1) as f64;
    y.iter()
        .zip(mask)
        .flat_map(|(&v, &edge)| {
            if edge {
                [255, 120, 0]
            } else {
                let g = (255.0 * v as f64 / (v as f64 + mean).max(f64::MIN_POSITIVE)) as u8;
                [g, g, g]
            }
        })
        .collect()
}

/// The error over one class of pixels (the edge band, or the rest).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct BandError {
    /// Pixels in the class.
    pub pixels: usize,
    /// Of those, the lit ones (the whole-image lit threshold), over which
    /// `mare` and `mean_signed` are taken.
    pub lit_pixels: usize,
    pub mare: f64,
    pub mean_signed: f64,
    /// RMSE over the class's pixels and channels over the class's reference mean.
    pub relative_rmse: f64,
    /// Mean of the per-pixel FLIP map over the class, when a FLIP was computed.
    pub flip: Option<f64>,
}

/// The edge band's error and the rest's.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct EdgeBand {
    pub ratio: f64,
    pub edge: BandError,
    pub rest: BandError,
}

/// Splits the error by `mask` (from [`edge_mask`] with `ratio`). `relative` is the per-pixel signed relative
/// luminance error (`None` where unlit), `flip_map` the per-pixel FLIP if any.
pub fn edge_band_error(
    test: &Image,
    reference: &Image,
    relative: &[Option<f64>],
    flip_map: Option<&[f32]>,
    mask: &[bool],
    ratio: f64,
) -> EdgeBand {
    let class = |want: bool| {
        let chosen: Vec<usize> = (0..mask.len()).filter(|&i| mask[i] == want).collect();
        if chosen.is_empty() {
            // No means to take (a uniform reference has no edge pixels).
            return BandError {
                pixels: 0,
                lit_pixels: 0,
                mare: 0.0,
                mean_signed: 0.0,
                relative_rmse: 0.0,
                flip: None,
            };
        }
        let lit: Vec<f64> = chosen.iter().filter_map(|&i| relative[i]).collect();
        let (mut squared, mut reference_sum) = (0.0f64, 0.0f64);
        for &i in &chosen {
            let (t, r) = (
                &test.rgb[3 * i..3 * i + 3],
                &reference.rgb[3 * i..3 * i + 3],
            );
            for c in 0..3 {
                squared += (t[c] as f64 - r[c] as f64).powi(2);
                reference_sum += r[c] as f64;
            }
        }
        let values = (3 * chosen.len()) as f64;
        let lit_count = lit.len().max(1) as f64;
        BandError {
            pixels: chosen.len(),
            lit_pixels: lit.len(),
            mare: lit.iter().map(|e| e.abs()).sum::<f64>() / lit_count,
            mean_signed: lit.iter().sum::<f64>() / lit_count,
            relative_rmse: (squared / values).sqrt() / (reference_sum / values),
            flip: flip_map
                .map(|m| chosen.iter().map(|&i| m[i] as f64).sum::<f64>() / chosen.len() as f64),
        }
    };
    EdgeBand {
        ratio,
        edge: class(true),
        rest: class(false),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `width × height` grey image whose columns left of `step` have value
    /// `low` and the others `high`.
    fn step(width: usize, height: usize, step: usize, low: f32, high: f32) -> Image {
        let mut rgb = Vec::with_capacity(width * height * 3);
        for _ in 0..height {
            for col in 0..width {
                let v = if col < step { low } else { high };
                rgb.extend([v, v, v]);
            }
        }
        Image { width, height, rgb }
    }

    #[test]
    fn a_step_edge_marks_exactly_the_pixels_within_one_of_the_step() {
        // Columns 0..4 at 1, columns 4..9 at 10: a ratio of 10 across the step
        // between columns 3 and 4. Exactly columns 3 and 4 (one pixel either side)
        // see both values in their 3 × 3 neighbourhood, on every row.
        let image = step(9, 5, 4, 1.0, 10.0);
        let mask = edge_mask(&image, DEFAULT_EDGE_RATIO);
        for (i, &edge) in mask.iter().enumerate() {
            let col = i % 9;
            assert_eq!(edge, col == 3 || col == 4, "pixel {i} (column {col})");
        }
        // A step below the ratio (1.9 < 2) is no edge anywhere.
        let image = step(9, 5, 4, 1.0, 1.9);
        assert!(edge_mask(&image, DEFAULT_EDGE_RATIO).iter().all(|&e| !e));
        // Black beside lit is an edge; all black is not.
        let image = step(4, 2, 2, 0.0, 1.0);
        let mask = edge_mask(&image, DEFAULT_EDGE_RATIO);
        assert_eq!(mask, [false, true, true, false, false, true, true, false]);
    }

    #[test]
    fn the_error_is_split_between_the_band_and_the_rest() {
        // The test is exact off the band and 50 % too bright on it (columns 3 and
        // 4 of the step): the band's MARE and signed error are 0.5, the rest's 0.
        // The FLIP map is 1 on the band and 0 elsewhere, so its means are 1 and 0.
        let reference = step(9, 5, 4, 1.0, 10.0);
        let mut test = reference.clone();
        let mut flip = vec![0.0f32; 45];
        for i in (0..45).filter(|i| i % 9 == 3 || i % 9 == 4) {
            for v in &mut test.rgb[3 * i..3 * i + 3] {
                *v *= 1.5;
            }
            flip[i] = 1.0;
        }
        let relative = super::super::metrics::signed_relative_luminance_error(&test, &reference);
        let mask = edge_mask(&reference, 2.0);
        let band = edge_band_error(&test, &reference, &relative.errors, Some(&flip), &mask, 2.0);
        assert_eq!((band.edge.pixels, band.rest.pixels), (10, 35));
        assert_eq!((band.edge.lit_pixels, band.rest.lit_pixels), (10, 35));
        assert!((band.edge.mare - 0.5).abs() < 1e-6, "{}", band.edge.mare);
        assert!((band.edge.mean_signed - 0.5).abs() < 1e-6);
        // RMSE = sqrt(mean((0.5 v)²)) over v ∈ {1, 10} equally: 0.5·sqrt(50.5);
        // the band's reference mean is 5.5.
        let expected = 0.5 * 50.5f64.sqrt() / 5.5;
        assert!((band.edge.relative_rmse - expected).abs() < 1e-6);
        assert_eq!(band.rest.mare, 0.0);
        assert_eq!(band.rest.relative_rmse, 0.0);
        assert_eq!((band.edge.flip, band.rest.flip), (Some(1.0), Some(0.0)));
        // A uniform reference has no edge: the empty class reports zeros, not NaN.
        let flat = Image::filled(5, 4, [0.5; 3]);
        let mask = edge_mask(&flat, 2.0);
        let band = edge_band_error(&flat, &flat, &[Some(0.0); 20], None, &mask, 2.0);
        assert_eq!((band.edge.pixels, band.rest.pixels), (0, 20));
        assert_eq!((band.edge.mare, band.edge.relative_rmse), (0.0, 0.0));
        assert_eq!(band.rest.relative_rmse, 0.0);
    }
}
