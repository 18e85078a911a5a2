//! The signed relative luminance error as a picture: a diverging colour map, white
//! where the test matches the reference, red where it is too bright, blue where it
//! is too dark, saturating at ±`range`. Pixels the metrics skip (unlit reference)
//! are drawn mid grey so that they are not mistaken for "no error".

/// The default saturation of the colour map: ±25 % relative error.
pub const DEFAULT_RANGE: f64 = 0.25;

const TOO_BRIGHT: [f64; 3] = [0.70, 0.09, 0.17];
const TOO_DARK: [f64; 3] = [0.13, 0.40, 0.67];
const MATCH: [f64; 3] = [1.0, 1.0, 1.0];
const SKIPPED: [u8; 3] = [128, 128, 128];

/// The 8-bit sRGB colour of one signed relative error (`None`: skipped pixel).
pub fn colour(error: Option<f64>, range: f64) -> [u8; 3] {
    let Some(e) = error else {
        return SKIPPED;
    };
    let t = (e / range).clamp(-1.0, 1.0);
    let end = if t >= 0.0 { TOO_BRIGHT } else { TOO_DARK };
    let t = t.abs();
    std::array::from_fn(|c| ((MATCH[c] + (end[c] - MATCH[c]) * t) * 255.0).round() as u8)
}

/// RGB8 pixels (row 0 at the top) for a map of signed relative errors.
pub fn render(errors: &[Option<f64>], range: f64) -> Vec<u8> {
    errors.iter().flat_map(|&e| colour(e, range)).collect()
}

/// Matplotlib's "magma" at nine evenly spaced values (0, 1/8, …, 1), the colour
/// map of the FLIP authors' error images (Andersson et al. 2020, Fig. 1):
/// black for no perceived difference, through purple and red, to pale
/// yellow for the largest.
const MAGMA: [[f64; 3]; 9] = [
    [0.0, 0.0, 4.0],
    [28.0, 16.0, 68.0],
    [79.0, 18.0, 123.0],
    [129.0, 37.0, 129.0],
    [181.0, 54.0, 122.0],
    [229.0, 80.0, 100.0],
    [251.0, 135.0, 97.0],
    [254.0, 194.0, 135.0],
    [252.0, 253.0, 191.0],
];

/// The 8-bit sRGB colour of one FLIP error in [0, 1]: magma, linearly
/// interpolated between its nine samples (values outside [0, 1] clamp).
pub fn flip_colour(error: f32) -> [u8; 3] {
    let x = f64::from(if error.is_nan() {
        0.0
    } else {
        error.clamp(0.0, 1.0)
    }) * 8.0;
    let i = (x.floor() as usize).min(7);
    let t = x - i as f64;
    std::array::from_fn(|c| (MAGMA[i][c] + (MAGMA[i + 1][c] - MAGMA[i][c]) * t).round() as u8)
}

/// RGB8 pixels (row 0 at the top) for a per-pixel FLIP map.
pub fn render_flip(map: &[f32]) -> Vec<u8> {
    map.iter().flat_map(|&e| flip_colour(e)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flip_colours_run_from_black_to_pale_yellow_and_clamp() {
        assert_eq!(flip_colour(0.0), [0, 0, 4]);
        assert_eq!(flip_colour(1.0), [252, 253, 191]);
        assert_eq!(flip_colour(2.0), flip_colour(1.0));
        assert_eq!(flip_colour(-1.0), flip_colour(0.0));
        assert_eq!(flip_colour(f32::NAN), flip_colour(0.0));
        // Halfway between the samples at 4/8 and 5/8.
        assert_eq!(flip_colour(0.5625), [205, 67, 111]);
        // Brightness (sum of channels) grows with the error.
        let sum = |c: [u8; 3]| c.iter().map(|&v| u32::from(v)).sum::<u32>();
        for k in 0..100 {
            let (a, b) = (k as f32 / 100.0, (k + 1) as f32 / 100.0);
            assert!(sum(flip_colour(b)) >= sum(flip_colour(a)), "{a} → {b}");
        }
    }

    #[test]
    fn colour_map_is_diverging_and_saturates() {
        assert_eq!(colour(Some(0.0), 0.25), [255, 255, 255]);
        assert_eq!(colour(None, 0.25), SKIPPED);
        let bright = colour(Some(0.25), 0.25);
        assert_eq!(bright, colour(Some(10.0), 0.25), "saturates at +range");
        assert!(bright[0] > bright[2]);
        let dark = colour(Some(-0.25), 0.25);
        assert_eq!(dark, colour(Some(-0.9), 0.25), "saturates at −range");
        assert!(dark[2] > dark[0]);
        // Half the range is half way to the end colour.
        let half = colour(Some(0.125), 0.25);
        assert!(half[1] < 255 && half[1] > bright[1]);
    }
}
