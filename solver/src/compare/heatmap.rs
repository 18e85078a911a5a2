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

#[cfg(test)]
mod tests {
    use super::*;

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
