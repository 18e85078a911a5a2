//! Exposure and tone-map curve: linear radiance → display value in 0..1, then the
//! sRGB transfer function (applied by the sRGB colour attachment on the GPU).
//!
//! `shaders/tonemap.frag` implements [`ToneSettings::display_value`]; the CPU twin
//! here is what the tests and the reference images use.

use serde::{Deserialize, Serialize};

/// The curve applied after exposure.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
#[derive(clap::ValueEnum)]
pub enum ToneCurve {
    /// `min(v, 1)`: exact for scenes exposed into range.
    Clamp,
    /// `v / (1 + v)` (Reinhard et al. 2002, global operator without white point).
    #[default]
    Reinhard,
    /// Narkowicz's fit of the ACES filmic curve.
    Aces,
}

impl ToneCurve {
    /// The code `tonemap.frag` switches on.
    pub fn code(self) -> u32 {
        match self {
            ToneCurve::Clamp => 0,
            ToneCurve::Reinhard => 1,
            ToneCurve::Aces => 2,
        }
    }
}

/// Exposure (a linear multiplier of radiance) and curve.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ToneSettings {
    /// Multiplies radiance (W·sr⁻¹·m⁻²) before the curve: display value 1 (before
    /// the curve) is radiance `1 / exposure`.
    pub exposure: f32,
    pub curve: ToneCurve,
}

impl Default for ToneSettings {
    fn default() -> Self {
        ToneSettings {
            exposure: 1.0,
            curve: ToneCurve::default(),
        }
    }
}

impl ToneSettings {
    /// Linear radiance → display value in 0..1 (before sRGB encoding). Negative
    /// radiance (ringing of a truncated SH lobe) shows as black.
    pub fn display_value(&self, radiance: f32) -> f32 {
        let v = (radiance * self.exposure).max(0.0);
        let v = match self.curve {
            ToneCurve::Clamp => v,
            ToneCurve::Reinhard => v / (1.0 + v),
            ToneCurve::Aces => (v * (2.51 * v + 0.03)) / (v * (2.43 * v + 0.59) + 0.14),
        };
        v.clamp(0.0, 1.0)
    }

    /// Display value → 8-bit sRGB, as an `R8G8B8A8_SRGB` attachment stores it.
    pub fn srgb8(&self, radiance: f32) -> u8 {
        (srgb_encode(self.display_value(radiance)) * 255.0).round() as u8
    }
}

/// The sRGB transfer function (IEC 61966-2-1) for a linear value in 0..1.
pub fn srgb_encode(linear: f32) -> f32 {
    let v = linear.clamp(0.0, 1.0);
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn curves_are_monotone_and_bounded() {
        for curve in [ToneCurve::Clamp, ToneCurve::Reinhard, ToneCurve::Aces] {
            let t = ToneSettings {
                exposure: 2.0,
                curve,
            };
            assert_eq!(t.display_value(-1.0), 0.0);
            assert_eq!(t.display_value(0.0), 0.0);
            let mut last = 0.0;
            for i in 1..2000 {
                let v = t.display_value(i as f32 * 0.01);
                assert!(v >= last && v <= 1.0, "{curve:?} not monotone at {i}");
                last = v;
            }
        }
        // Reinhard at exposed value 1 is exactly 1/2.
        let t = ToneSettings {
            exposure: 4.0,
            curve: ToneCurve::Reinhard,
        };
        assert!((t.display_value(0.25) - 0.5).abs() < 1e-7);
    }

    #[test]
    fn srgb_matches_the_standard_at_known_points() {
        // 18% grey encodes to 0.4614 (IEC 61966-2-1); the linear segment's end.
        assert!((srgb_encode(0.18) - 0.461_356).abs() < 1e-5);
        assert!((srgb_encode(0.003_130_8) - 0.040_449_9).abs() < 1e-6);
        assert_eq!(srgb_encode(1.0), 1.0);
    }
}
