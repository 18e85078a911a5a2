//! Error metrics between a test image and a reference (ground-truth) image.
//! All sums are taken in f64 so that large images lose no precision.

use super::image::{luminance, IdChannel, Image};

/// Pixels whose reference luminance is at most this fraction of the mean reference
/// luminance are "unlit": relative errors there divide by almost nothing and would
/// swamp every mean, so MARE, the signed error and the heatmap skip them.
pub const LIT_FRACTION: f64 = 1e-3;

/// The whole-image figures `solver compare` prints.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Summary {
    /// Mean over all pixels and channels.
    pub test_mean: f64,
    pub reference_mean: f64,
    /// RMSE over all pixels and channels divided by the reference's mean.
    pub relative_rmse: f64,
    /// Mean |Y_test − Y_ref| / Y_ref over lit pixels.
    pub mare: f64,
    /// Mean (Y_test − Y_ref) / Y_ref over lit pixels: the bias, with its sign.
    pub mean_signed_relative_error: f64,
    /// Largest |test − reference| over all pixels and channels.
    pub max_abs_error: f64,
    /// Where the largest error is: (x, y, channel).
    pub max_abs_error_at: (usize, usize, usize),
    /// The luminance below which a pixel is unlit (`LIT_FRACTION` × mean Y_ref).
    pub lit_threshold: f64,
    pub lit_pixels: usize,
    pub pixels: usize,
}

fn mean(values: &[f32]) -> f64 {
    values.iter().map(|&v| v as f64).sum::<f64>() / values.len().max(1) as f64
}

/// The lit-pixel threshold for a reference's luminances.
pub fn lit_threshold(reference_luminance: &[f32]) -> f64 {
    LIT_FRACTION * mean(reference_luminance)
}

/// Computes the whole-image metrics. The images must have the same size.
pub fn summarize(test: &Image, reference: &Image) -> Summary {
    assert_eq!(test.rgb.len(), reference.rgb.len(), "images differ in size");
    let test_mean = mean(&test.rgb);
    let reference_mean = mean(&reference.rgb);
    let mut squared = 0.0f64;
    let mut max_abs = 0.0f64;
    let mut max_at = 0usize;
    for (i, (&t, &r)) in test.rgb.iter().zip(&reference.rgb).enumerate() {
        let d = (t as f64 - r as f64).abs();
        squared += d * d;
        if d > max_abs {
            max_abs = d;
            max_at = i;
        }
    }
    let rmse = (squared / test.rgb.len().max(1) as f64).sqrt();
    let relative = signed_relative_luminance_error(test, reference);
    let lit: Vec<f64> = relative.errors.iter().flatten().copied().collect();
    let lit_count = lit.len().max(1) as f64;
    let pixel = max_at / 3;
    Summary {
        test_mean,
        reference_mean,
        relative_rmse: rmse / reference_mean,
        mare: lit.iter().map(|e| e.abs()).sum::<f64>() / lit_count,
        mean_signed_relative_error: lit.iter().sum::<f64>() / lit_count,
        max_abs_error: max_abs,
        max_abs_error_at: (pixel % test.width, pixel / test.width, max_at % 3),
        lit_threshold: relative.threshold,
        lit_pixels: lit.len(),
        pixels: test.pixel_count(),
    }
}

/// Per-pixel signed relative luminance error, `None` where the reference is unlit.
#[derive(Debug, Clone, PartialEq)]
pub struct RelativeError {
    pub errors: Vec<Option<f64>>,
    pub threshold: f64,
}

/// (Y_test − Y_ref) / Y_ref per pixel where Y_ref exceeds the lit threshold.
pub fn signed_relative_luminance_error(test: &Image, reference: &Image) -> RelativeError {
    let y_ref = reference.luminances();
    let threshold = lit_threshold(&y_ref);
    let errors = test
        .pixels()
        .zip(&y_ref)
        .map(|(t, &r)| {
            let r = r as f64;
            (r > threshold).then(|| (luminance(t) as f64 - r) / r)
        })
        .collect();
    RelativeError { errors, threshold }
}

/// The error of the pixels that show one material or object.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct GroupError {
    pub id: i32,
    pub name: String,
    /// Pixels showing this id (lit or not).
    pub pixels: usize,
    /// Of those, the lit ones, over which `mare` and `mean_signed` are taken.
    pub lit_pixels: usize,
    pub mare: f64,
    pub mean_signed: f64,
    /// This group's share of Σ |Y_test − Y_ref| over the whole image, in [0, 1].
    pub share_of_abs_error: f64,
}

/// Breaks the luminance error down by id, largest share of absolute error first.
pub fn error_by_id(test: &Image, reference: &Image, ids: &IdChannel) -> Vec<GroupError> {
    use std::collections::BTreeMap;
    let relative = signed_relative_luminance_error(test, reference);
    #[derive(Default)]
    struct Acc {
        pixels: usize,
        lit: usize,
        abs_rel: f64,
        signed_rel: f64,
        abs: f64,
    }
    let mut groups: BTreeMap<i32, Acc> = BTreeMap::new();
    let mut total_abs = 0.0;
    for (((t, r), &id), rel) in test
        .pixels()
        .zip(reference.pixels())
        .zip(&ids.ids)
        .zip(&relative.errors)
    {
        let acc = groups.entry(id).or_default();
        let abs = (luminance(t) as f64 - luminance(r) as f64).abs();
        acc.pixels += 1;
        acc.abs += abs;
        total_abs += abs;
        if let Some(e) = rel {
            acc.lit += 1;
            acc.abs_rel += e.abs();
            acc.signed_rel += e;
        }
    }
    let mut rows: Vec<GroupError> = groups
        .into_iter()
        .map(|(id, a)| GroupError {
            id,
            name: ids.name(id),
            pixels: a.pixels,
            lit_pixels: a.lit,
            mare: a.abs_rel / a.lit.max(1) as f64,
            mean_signed: a.signed_rel / a.lit.max(1) as f64,
            share_of_abs_error: if total_abs > 0.0 {
                a.abs / total_abs
            } else {
                0.0
            },
        })
        .collect();
    rows.sort_by(|a, b| {
        b.share_of_abs_error
            .total_cmp(&a.share_of_abs_error)
            .then(b.mare.total_cmp(&a.mare))
            .then(a.id.cmp(&b.id))
    });
    rows
}

/// Mean relative standard error of the reference's luminance over its lit pixels:
/// the noise of the ground truth itself, to read beside the test's error.
///
/// The three channels of a path-traced pixel come from the same paths, so their
/// errors are strongly correlated; the luminance's standard error is bounded by
/// the fully correlated sum Σ w_c·se_c, which is what is used (an upper bound).
pub fn reference_noise(reference: &Image, standard_error: &[f32]) -> f64 {
    let y_ref = reference.luminances();
    let threshold = lit_threshold(&y_ref);
    let (sum, count) = standard_error
        .chunks_exact(3)
        .zip(&y_ref)
        .filter(|(_, &y)| y as f64 > threshold)
        .fold((0.0f64, 0usize), |(s, n), (se, &y)| {
            let se_y: f64 = se
                .iter()
                .zip(super::image::LUMINANCE_WEIGHTS)
                .map(|(&e, w)| (w * e.abs()) as f64)
                .sum();
            (s + se_y / y as f64, n + 1)
        });
    sum / count.max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    fn varied(width: usize, height: usize) -> Image {
        let rgb = (0..width * height * 3)
            .map(|i| 0.05 + ((i * 37 % 101) as f32) / 50.0)
            .collect();
        Image { width, height, rgb }
    }

    fn scaled(image: &Image, k: f32) -> Image {
        Image {
            rgb: image.rgb.iter().map(|v| v * k).collect(),
            ..image.clone()
        }
    }

    #[test]
    fn identical_images_have_zero_error() {
        let image = varied(7, 5);
        let s = summarize(&image, &image);
        assert_eq!(s.relative_rmse, 0.0);
        assert_eq!(s.mare, 0.0);
        assert_eq!(s.mean_signed_relative_error, 0.0);
        assert_eq!(s.max_abs_error, 0.0);
        assert_eq!(s.lit_pixels, 35);
        assert_eq!(s.test_mean, s.reference_mean);
    }

    #[test]
    fn constant_scale_gives_k_minus_one() {
        // For test = k · reference, every lit pixel's relative luminance error is
        // exactly k − 1, so MARE = |k − 1| on any image; relative RMSE equals |k − 1|
        // when the reference is uniform (RMSE = |k − 1|·rms(ref) and rms = mean).
        // Tolerance 1e-6: f32 products k·v carry a relative rounding of 6e-8.
        for k in [0.5f32, 0.9, 1.25, 3.0] {
            let image = varied(9, 4);
            let s = summarize(&scaled(&image, k), &image);
            assert!(
                (s.mare - (k as f64 - 1.0).abs()).abs() < 1e-6,
                "k={k}: {}",
                s.mare
            );
            assert!((s.mean_signed_relative_error - (k as f64 - 1.0)).abs() < 1e-6);
            let uniform = Image::filled(6, 3, [0.3, 0.3, 0.3]);
            let s = summarize(&scaled(&uniform, k), &uniform);
            assert!(
                (s.relative_rmse - (k as f64 - 1.0).abs()).abs() < 1e-6,
                "k={k}"
            );
            assert!((s.mare - (k as f64 - 1.0).abs()).abs() < 1e-6);
        }
    }

    #[test]
    fn one_bright_pixel_has_known_errors() {
        // A uniform grey reference 0.5 over N = 10×10 pixels; the test adds d = 4.0
        // to all three channels of pixel (3, 2). Then RMSE = sqrt(3·d² / 3N) = d/√N,
        // relative RMSE = d / (√N · 0.5) = 0.8, the maximum absolute error is d,
        // and MARE = (d / 0.5) / N = 0.08 (one pixel off by a factor 1 + 8).
        let reference = Image::filled(10, 10, [0.5; 3]);
        let mut test = reference.clone();
        let i = (2 * 10 + 3) * 3;
        for c in 0..3 {
            test.rgb[i + c] += 4.0;
        }
        let s = summarize(&test, &reference);
        assert!((s.relative_rmse - 0.8).abs() < 1e-6, "{}", s.relative_rmse);
        assert!((s.max_abs_error - 4.0).abs() < 1e-6);
        assert_eq!(s.max_abs_error_at, (3, 2, 0));
        assert!((s.mare - 0.08).abs() < 1e-6, "{}", s.mare);
        assert!((s.test_mean - (0.5 + 4.0 / 100.0)).abs() < 1e-6);
    }

    #[test]
    fn mare_skips_pixels_at_or_below_the_lit_threshold() {
        // Reference: 99 pixels at Y = 1 and one at Y = y_dark. The mean is ~0.99, so
        // the threshold is ~9.9e-4. A dark pixel at 5e-4 is excluded (its 100 %
        // error must not count); at 2e-3 it is included.
        for (y_dark, included) in [(5e-4f32, false), (2e-3, true)] {
            let mut reference = Image::filled(10, 10, [1.0; 3]);
            for c in 0..3 {
                reference.rgb[c] = y_dark;
            }
            let mut test = reference.clone();
            for c in 0..3 {
                test.rgb[c] = 2.0 * y_dark; // 100 % too bright
            }
            let s = summarize(&test, &reference);
            assert_eq!(s.lit_pixels, if included { 100 } else { 99 });
            let expected = if included { 1.0 / 100.0 } else { 0.0 };
            assert!((s.mare - expected).abs() < 1e-6, "{y_dark}: {}", s.mare);
        }
        // A black reference pixel is never lit, even when the test is not black.
        let mut reference = Image::filled(4, 1, [1.0; 3]);
        reference.rgb[..3].copy_from_slice(&[0.0; 3]);
        let test = Image::filled(4, 1, [1.0; 3]);
        let s = summarize(&test, &reference);
        assert_eq!(s.lit_pixels, 3);
        assert_eq!(s.mare, 0.0);
        assert!(s.max_abs_error == 1.0);
    }

    #[test]
    fn error_by_id_splits_and_ranks_groups() {
        // Pixels 0..4 are material 0 (exact), 4..8 material 1 (20 % too bright),
        // 8..10 no hit (black in both): material 1 holds all the absolute error.
        let reference = Image::filled(10, 1, [1.0; 3]);
        let mut test = reference.clone();
        for v in &mut test.rgb[12..24] {
            *v = 1.2;
        }
        let mut ids = IdChannel {
            ids: vec![0, 0, 0, 0, 1, 1, 1, 1, -1, -1],
            names: vec!["floor".into(), "lamp".into()],
        };
        let rows = error_by_id(&test, &reference, &ids);
        assert_eq!(rows.len(), 3);
        assert_eq!(rows[0].name, "lamp");
        assert_eq!(rows[0].pixels, 4);
        assert!((rows[0].mare - 0.2).abs() < 1e-6);
        assert!((rows[0].mean_signed - 0.2).abs() < 1e-6);
        assert!((rows[0].share_of_abs_error - 1.0).abs() < 1e-12);
        assert!(rows[1..].iter().all(|r| r.share_of_abs_error == 0.0));
        ids.names.clear();
        assert_eq!(error_by_id(&test, &reference, &ids)[0].name, "#1");
    }

    #[test]
    fn reference_noise_is_the_mean_relative_standard_error() {
        // se = 5 % of the value in every channel gives se_Y = Σ w_c·0.05·v_c =
        // 0.05·Y, a relative luminance standard error of exactly 5 % per pixel.
        let reference = varied(5, 5);
        let se: Vec<f32> = reference.rgb.iter().map(|v| 0.05 * v).collect();
        let noise = reference_noise(&Image::filled(5, 5, [1.0; 3]), &vec![0.05; 75]);
        assert!((noise - 0.05).abs() < 1e-6);
        let noise = reference_noise(&reference, &se);
        assert!((noise - 0.05).abs() < 1e-6, "{noise}");
    }
}
