//! Exposure, tone curves and sRGB encoding for displayed images (`.png` renders,
//! the desktop mirror). The runtime's display shader mirrors these formulas in f32,
//! in this order, per channel:
//!
//! ```text
//! x   = radiance · 2^exposure_stops        (exposure in stops, 0 = unchanged)
//! y   = curve(max(x, 0))                   (ToneCurve)
//! s   = linear_to_srgb(clamp(y, 0, 1))     (IEC 61966-2-1 piecewise curve)
//! u8  = floor(s · 255 + 0.5)
//! ```
//!
//! A shader that writes to an `*_SRGB` image lets the hardware do the last two
//! steps; Vulkan allows that conversion some error, so GPU and CPU bytes can
//! differ by one step.

use super::Image;

/// The curve applied to exposed linear radiance.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ToneCurve {
    /// `min(x, 1)`: exact below 1, everything brighter saturates.
    #[default]
    Clamp,
    /// Reinhard's `x / (1 + x)` per channel: never saturates, compresses highlights.
    Reinhard,
    /// Narkowicz's (2015) rational fit of the ACES filmic curve,
    /// `x(2.51x + 0.03) / (x(2.43x + 0.59) + 0.14)`, clamped to 1.
    AcesFit,
}

impl ToneCurve {
    /// Parses `clamp`, `reinhard`, `aces` (case-insensitive).
    pub fn parse(text: &str) -> Option<ToneCurve> {
        Some(match text.trim().to_ascii_lowercase().as_str() {
            "clamp" => ToneCurve::Clamp,
            "reinhard" => ToneCurve::Reinhard,
            "aces" | "acesfit" | "aces-fit" => ToneCurve::AcesFit,
            _ => return None,
        })
    }
}

/// The tone curve at exposed radiance `x`; negative and NaN inputs give 0, the
/// result lies in 0..=1.
pub fn tone_map(x: f32, curve: ToneCurve) -> f32 {
    // `f32::max` returns the other operand for NaN, so NaN maps to 0.
    let x = x.max(0.0);
    let y = match curve {
        ToneCurve::Clamp => x,
        ToneCurve::Reinhard => x / (1.0 + x),
        ToneCurve::AcesFit => {
            let (a, b, c, d, e) = (2.51f32, 0.03f32, 2.43f32, 0.59f32, 0.14f32);
            (x * (a * x + b)) / (x * (c * x + d) + e)
        }
    };
    // Reinhard of +inf is NaN (inf/inf); the limit is 1, as for the others.
    if y.is_nan() {
        1.0
    } else {
        y.min(1.0)
    }
}

/// The sRGB transfer function (IEC 61966-2-1): linear 0..1 to encoded 0..1.
/// Inputs outside 0..1 are clamped.
pub fn linear_to_srgb(linear: f32) -> f32 {
    let x = linear.clamp(0.0, 1.0);
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// Inverse of [`linear_to_srgb`].
pub fn srgb_to_linear(encoded: f32) -> f32 {
    let s = encoded.clamp(0.0, 1.0);
    if s <= 0.040_45 {
        s / 12.92
    } else {
        ((s + 0.055) / 1.055).powf(2.4)
    }
}

/// Tone-mapped value `y` (0..1; anything else is clamped, NaN gives 0) to an
/// sRGB byte: `floor(linear_to_srgb(y) · 255 + 0.5)`.
pub fn encode_srgb8(y: f32) -> u8 {
    // Written so that NaN also takes the early return.
    if y.is_nan() || y <= 0.0 {
        return 0;
    }
    (linear_to_srgb(y) * 255.0 + 0.5).floor() as u8
}

/// The displayed RGB8 bytes of `image` (row-major, row 0 at the top, 3 bytes per
/// pixel): radiance times `2^exposure_stops`, through `curve`, sRGB-encoded.
pub fn tonemap_srgb8(image: &Image, exposure_stops: f32, curve: ToneCurve) -> Vec<u8> {
    let scale = exposure_stops.exp2();
    image
        .pixels
        .iter()
        .flat_map(|p| p.map(|c| encode_srgb8(tone_map(c * scale, curve))))
        .collect()
}

/// Rec. 709 luminance of linear RGB.
pub fn luminance(rgb: [f32; 3]) -> f32 {
    0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]
}

/// The exposure (stops) that maps the log-average luminance of the lit pixels
/// (Reinhard et al. 2002's "key") to `key`, e.g. 0.18 for a mid-grey scene; 0 for
/// an image with no lit pixel. Radiance levels depend on the scene's emitters and
/// units, so previews and screenshots default to this rather than to a fixed value.
pub fn auto_exposure_stops(image: &Image, key: f32) -> f32 {
    let (sum, count) = image
        .pixels
        .iter()
        .map(|&p| luminance(p))
        .filter(|y| *y > 0.0 && y.is_finite())
        .fold((0.0f64, 0usize), |(s, n), y| (s + (y as f64).ln(), n + 1));
    if count == 0 || key.is_nan() || key <= 0.0 {
        return 0.0;
    }
    let log_average = (sum / count as f64).exp();
    (key as f64 / log_average).log2() as f32
}

/// The key value a scene's log-average radiance is shown at: middle grey,
/// Reinhard et al.'s (2002) "normal-key" value.
pub const DEFAULT_KEY_VALUE: f32 = 0.18;

/// δ in [`log_average_luminance`], relative to the weighted mean luminance:
/// it keeps black samples from sending the log-average to 0 while leaving the
/// key proportional to the radiance (scaling every radiance by k scales the
/// result by k).
pub const LOG_AVERAGE_DELTA: f64 = 1e-4;

/// The log-average luminance of weighted RGB radiance samples, Reinhard et
/// al. 2002 ("Photographic tone reproduction for digital images"), eq. 1:
/// exp(Σ w log(δ + Y) / Σ w), with Y the Rec. 709 luminance, w a sample's
/// weight (the solver passes each vertex's share of its triangles' area) and
/// δ = [`LOG_AVERAGE_DELTA`] × the weighted mean of Y. 0 when there is no
/// positive weight or no light; non-finite samples and weights are skipped.
pub fn log_average_luminance(samples: impl IntoIterator<Item = ([f32; 3], f64)> + Clone) -> f32 {
    let usable =
        |(rgb, w): &([f32; 3], f64)| w.is_finite() && *w > 0.0 && rgb.iter().all(|c| c.is_finite());
    let (mut weight, mut mean) = (0.0f64, 0.0f64);
    for (rgb, w) in samples.clone().into_iter().filter(usable) {
        weight += w;
        mean += w * f64::from(luminance(rgb).max(0.0));
    }
    if weight <= 0.0 || mean <= 0.0 {
        return 0.0;
    }
    let delta = LOG_AVERAGE_DELTA * mean / weight;
    let log_sum: f64 = samples
        .into_iter()
        .filter(usable)
        .map(|(rgb, w)| w * (delta + f64::from(luminance(rgb).max(0.0))).ln())
        .sum();
    (log_sum / weight).exp() as f32
}

/// The exposure in stops that shows a stored log-average radiance
/// `exposure_key` at `key_value`: log₂(key_value / exposure_key); `None` for a
/// key that is 0 (not computed), negative or not finite.
pub fn key_exposure_stops(exposure_key: f32, key_value: f32) -> Option<f32> {
    (exposure_key.is_finite() && exposure_key > 0.0 && key_value > 0.0)
        .then(|| (f64::from(key_value) / f64::from(exposure_key)).log2() as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_average_is_the_geometric_mean_weighted_by_area() {
        // Two grey samples 1 and 100 of equal weight: geometric mean 10 (δ
        // adds at most 1e-4 × 50.5 inside each log: relative 5e-3 on the
        // sample of 1, so 2.5e-3 on the mean).
        let two = [([1.0f32; 3], 1.0f64), ([100.0; 3], 1.0)];
        let got = log_average_luminance(two);
        assert!((got - 10.0).abs() < 10.0 * 3e-3, "{got}");
        // Weight 3:1 toward 100: 100^0.75 = 31.6.
        let weighted = [([1.0f32; 3], 1.0f64), ([100.0; 3], 3.0)];
        let got = log_average_luminance(weighted);
        assert!((got - 31.62).abs() < 31.62 * 3e-3, "{got}");
        // Scaling the radiance scales the key: δ is relative.
        let scaled = [([1000.0f32; 3], 1.0f64), ([100_000.0; 3], 1.0)];
        assert!((log_average_luminance(scaled) / got.max(1.0) - 10_000.0 / 31.62).abs() < 1.0);
        assert_eq!(log_average_luminance([([0.0f32; 3], 1.0f64)]), 0.0);
        assert_eq!(log_average_luminance(Vec::<([f32; 3], f64)>::new()), 0.0);
        // The stops show the key at 0.18.
        let stops = key_exposure_stops(0.72, 0.18).unwrap();
        assert!((stops + 2.0).abs() < 1e-6);
        assert_eq!(key_exposure_stops(0.0, 0.18), None);
    }

    const CURVES: [ToneCurve; 3] = [ToneCurve::Clamp, ToneCurve::Reinhard, ToneCurve::AcesFit];

    #[test]
    fn zero_is_black_and_curves_are_monotone() {
        for curve in CURVES {
            assert_eq!(tone_map(0.0, curve), 0.0);
            assert_eq!(encode_srgb8(tone_map(0.0, curve)), 0);
            assert_eq!(tone_map(-3.0, curve), 0.0);
            assert_eq!(tone_map(f32::NAN, curve), 0.0);
            assert_eq!(tone_map(f32::INFINITY, curve), 1.0);
            // Non-decreasing over 1e-6..1e6 on a fine logarithmic grid, in value
            // and in the encoded byte.
            let mut last = (0.0f32, 0u8);
            for k in 0..=12_000 {
                let x = 10f32.powf(-6.0 + k as f32 * 1e-3);
                let y = tone_map(x, curve);
                let byte = encode_srgb8(y);
                assert!(
                    y >= last.0 && byte >= last.1,
                    "{curve:?} at {x}: {y} < {}",
                    last.0
                );
                assert!((0.0..=1.0).contains(&y));
                last = (y, byte);
            }
        }
    }

    #[test]
    fn clamp_curve_encodes_one_as_255_and_matches_srgb() {
        assert_eq!(encode_srgb8(tone_map(1.0, ToneCurve::Clamp)), 255);
        assert_eq!(encode_srgb8(tone_map(7.0, ToneCurve::Clamp)), 255);
        // Linear 0.5 is sRGB 0.735357 (IEC 61966-2-1) → byte round(187.5...) = 188.
        assert!((linear_to_srgb(0.5) - 0.735_356_7).abs() < 1e-6);
        assert_eq!(encode_srgb8(0.5), 188);
        // The two branches meet at 0.0031308 (continuity to f32 rounding).
        let t = 0.003_130_8f32;
        assert!((12.92 * t - (1.055 * t.powf(1.0 / 2.4) - 0.055)).abs() < 1e-6);
        // Round trip.
        for k in 0..=100 {
            let x = k as f32 / 100.0;
            assert!((srgb_to_linear(linear_to_srgb(x)) - x).abs() < 1e-6);
        }
    }

    #[test]
    fn exposure_is_in_stops() {
        let mut image = Image::new(2, 1);
        image.pixels = vec![[0.25, 0.25, 0.25], [0.5, 0.5, 0.5]];
        // +1 stop doubles: the first pixel at +1 stop equals the second at 0.
        let up = tonemap_srgb8(&image, 1.0, ToneCurve::Clamp);
        let plain = tonemap_srgb8(&image, 0.0, ToneCurve::Clamp);
        assert_eq!(up[0..3], plain[3..6]);
        // Auto exposure sends the log-average luminance (√(0.25·0.5)) to the key.
        let stops = auto_exposure_stops(&image, 0.18);
        let expected = (0.18f64 / (0.25f64 * 0.5).sqrt()).log2();
        assert!((stops as f64 - expected).abs() < 1e-5);
        assert_eq!(auto_exposure_stops(&Image::new(3, 3), 0.18), 0.0);
    }
}
