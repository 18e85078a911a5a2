//! Image comparison for GPU-versus-CPU tests: differences measured relative to the
//! reference image's mean radiance, so that thresholds do not depend on the
//! scene's units or emitter strength.

use super::{Image, RenderError};

/// Per-pixel difference (relative) above which [`compare`] counts a pixel as
/// differing: 1% of the mean radiance, well above f32 SH evaluation error
/// (`sh::f32_basis_tolerance`, ~1e-6 relative) and well below a wrong edge pixel.
pub const DEFAULT_DIFF_THRESHOLD: f64 = 1e-2;

/// How two images differ. Each pixel's difference is the largest of its three
/// channels' absolute differences, divided by `scale`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageDiff {
    /// The mean radiance (over pixels and channels) of the reference image; the
    /// test image's when the reference is black; 1 when both are.
    pub scale: f64,
    pub mean_abs: f64,
    /// 99th percentile of the per-pixel differences.
    pub p99_abs: f64,
    pub max_abs: f64,
    /// Fraction of pixels whose difference exceeds the threshold.
    pub differing_fraction: f64,
    /// Column and row of the largest difference.
    pub worst_pixel: (u32, u32),
}

/// [`compare_with`] at [`DEFAULT_DIFF_THRESHOLD`].
pub fn compare(reference: &Image, test: &Image) -> Result<ImageDiff, RenderError> {
    compare_with(reference, test, DEFAULT_DIFF_THRESHOLD)
}

/// Compares `test` with `reference`; `threshold` is relative to the scale (see
/// [`ImageDiff`]). A NaN or infinite channel in either image is an infinite
/// difference.
pub fn compare_with(
    reference: &Image,
    test: &Image,
    threshold: f64,
) -> Result<ImageDiff, RenderError> {
    check_sizes(reference, test)?;
    let mut scale = reference.mean_radiance().abs();
    if !(scale > 0.0 && scale.is_finite()) {
        scale = test.mean_radiance().abs();
    }
    if !(scale > 0.0 && scale.is_finite()) {
        scale = 1.0;
    }
    let mut differences: Vec<f64> = reference
        .pixels
        .iter()
        .zip(&test.pixels)
        .map(|(a, b)| {
            (0..3)
                .map(|c| {
                    let d = (a[c] as f64 - b[c] as f64).abs();
                    if d.is_finite() {
                        d / scale
                    } else {
                        f64::INFINITY
                    }
                })
                .fold(0.0, f64::max)
        })
        .collect();
    let n = differences.len();
    if n == 0 {
        return Ok(ImageDiff {
            scale,
            mean_abs: 0.0,
            p99_abs: 0.0,
            max_abs: 0.0,
            differing_fraction: 0.0,
            worst_pixel: (0, 0),
        });
    }
    // The first pixel with the largest difference.
    let (worst, max_abs) =
        differences.iter().enumerate().fold(
            (0, 0.0),
            |best, (k, &d)| if d > best.1 { (k, d) } else { best },
        );
    let mean_abs = differences.iter().sum::<f64>() / n as f64;
    let differing = differences.iter().filter(|&&d| d > threshold).count();
    // Nearest-rank percentile.
    let rank = ((0.99 * n as f64).ceil() as usize).clamp(1, n) - 1;
    let (_, &mut p99_abs, _) = differences.select_nth_unstable_by(rank, f64::total_cmp);
    let width = reference.width as usize;
    Ok(ImageDiff {
        scale,
        mean_abs,
        p99_abs,
        max_abs,
        differing_fraction: differing as f64 / n as f64,
        worst_pixel: ((worst % width) as u32, (worst / width) as u32),
    })
}

/// `|a − b|` per pixel and channel (depth: `|a − b|` too), for looking at where
/// two renders differ.
pub fn difference_image(a: &Image, b: &Image) -> Result<Image, RenderError> {
    check_sizes(a, b)?;
    Ok(Image {
        width: a.width,
        height: a.height,
        pixels: a
            .pixels
            .iter()
            .zip(&b.pixels)
            .map(|(p, q)| [0, 1, 2].map(|c| (p[c] - q[c]).abs()))
            .collect(),
        depth: a
            .depth
            .iter()
            .zip(&b.depth)
            .map(|(p, q)| (p - q).abs())
            .collect(),
    })
}

fn check_sizes(a: &Image, b: &Image) -> Result<(), RenderError> {
    let consistent = |i: &Image| {
        i.pixels.len() == i.width as usize * i.height as usize && i.depth.len() == i.pixels.len()
    };
    if a.width != b.width || a.height != b.height || !consistent(a) || !consistent(b) {
        return Err(RenderError::SizeMismatch(
            a.width, a.height, b.width, b.height,
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_images_do_not_differ() {
        let mut a = Image::new(10, 10);
        a.pixels
            .iter_mut()
            .enumerate()
            .for_each(|(k, p)| *p = [k as f32, 1.0, 2.0]);
        let d = compare(&a, &a).unwrap();
        assert_eq!(
            (d.mean_abs, d.p99_abs, d.max_abs, d.differing_fraction),
            (0.0, 0.0, 0.0, 0.0)
        );
    }

    #[test]
    fn metrics_match_a_known_perturbation() {
        // 100 pixels of radiance 2 (scale 2); 3 pixels off by 1 (relative 0.5),
        // one by 0.01 (relative 0.005, under the 1% threshold).
        let mut a = Image::new(10, 10);
        a.pixels.fill([2.0; 3]);
        let mut b = a.clone();
        for k in [5, 17, 99] {
            b.pixels[k][1] = 3.0;
        }
        b.pixels[40][0] = 2.01;
        let d = compare(&a, &b).unwrap();
        assert_eq!(d.scale, 2.0);
        assert!((d.max_abs - 0.5).abs() < 1e-12);
        assert!((d.mean_abs - (3.0 * 0.5 + 0.005) / 100.0).abs() < 1e-6);
        assert!((d.differing_fraction - 0.03).abs() < 1e-12);
        // The 99th of 100 sorted values is the second-largest: 0.5.
        assert!((d.p99_abs - 0.5).abs() < 1e-12);
        assert_eq!(d.worst_pixel.1 * 10 + d.worst_pixel.0, 5);
        let diff = difference_image(&a, &b).unwrap();
        assert_eq!(diff.pixels[17], [0.0, 1.0, 0.0]);
        // NaN counts as an infinite difference; size mismatches are errors.
        b.pixels[0][2] = f32::NAN;
        assert_eq!(compare(&a, &b).unwrap().max_abs, f64::INFINITY);
        assert!(matches!(
            compare(&a, &Image::new(9, 10)),
            Err(RenderError::SizeMismatch(..))
        ));
    }
}
