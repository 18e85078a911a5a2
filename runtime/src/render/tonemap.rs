//! Exposure and tone-map curve: linear radiance → display value in 0..1, then the
//! sRGB transfer function (applied by the sRGB colour attachment on the GPU).
//!
//! The formulas are the shared ones of `solution::raster::tonemap` (the solver's
//! `--preview` and the CPU reference use them), in this order per channel:
//! `x = radiance · 2^exposure_stops`, `y = curve(max(x, 0))`, sRGB-encode `y`.
//! `shaders/tonemap.frag` implements them in f32; [`ToneSettings::srgb8`] is the
//! CPU twin the tests compare with.

use serde::{Deserialize, Serialize};
use solution::raster::tonemap as shared;

/// The curve applied after exposure (see `solution::raster::ToneCurve`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum ToneCurve {
    /// `min(x, 1)`: exact below 1, brighter saturates.
    #[default]
    Clamp,
    /// `x / (1 + x)`: never saturates, compresses highlights.
    Reinhard,
    /// Narkowicz's (2015) fit of the ACES filmic curve.
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

    /// The shared CPU definition.
    pub fn shared(self) -> shared::ToneCurve {
        match self {
            ToneCurve::Clamp => shared::ToneCurve::Clamp,
            ToneCurve::Reinhard => shared::ToneCurve::Reinhard,
            ToneCurve::Aces => shared::ToneCurve::AcesFit,
        }
    }
}

/// Exposure (in stops: radiance is multiplied by `2^exposure_stops`) and curve.
#[derive(Clone, Copy, Debug, PartialEq, Default, Serialize, Deserialize)]
pub struct ToneSettings {
    pub exposure_stops: f32,
    pub curve: ToneCurve,
}

impl ToneSettings {
    /// The linear multiplier `2^exposure_stops`.
    pub fn gain(&self) -> f32 {
        self.exposure_stops.exp2()
    }

    /// Linear radiance → display value in 0..1 (before sRGB encoding).
    pub fn display_value(&self, radiance: f32) -> f32 {
        shared::tone_map(radiance * self.gain(), self.curve.shared())
    }

    /// Radiance → the 8-bit sRGB value an `R8G8B8A8_SRGB` attachment stores
    /// (Vulkan allows the hardware conversion some error: compare with ±1).
    pub fn srgb8(&self, radiance: f32) -> u8 {
        shared::encode_srgb8(self.display_value(radiance))
    }
}

/// The automatic exposure of a file, in stops: the one that shows its
/// stored log-average radiance (the header's exposure key, format x.1) at
/// the key value 0.18, log₂(0.18 / L̄); 0 for a file without a key (x.0),
/// which is drawn as before.
pub fn file_exposure_stops(lighting: Option<&solution::format::Lighting>) -> f32 {
    lighting
        .and_then(|l| shared::key_exposure_stops(l.exposure_key, shared::DEFAULT_KEY_VALUE))
        .unwrap_or(0.0)
}

/// The tone curve a file is shown with unless the user names one: ACES for
/// a physically lit file (one with lights, format x.1), whose sun patches
/// and sky are far above the key value and would clip; clamp for every
/// other file, so the images of files without lights keep their bytes.
pub fn default_curve(lighting: Option<&solution::format::Lighting>) -> ToneCurve {
    if lighting.is_some() {
        ToneCurve::Aces
    } else {
        ToneCurve::Clamp
    }
}

/// The tone of a file: its automatic exposure plus the user's EV offset
/// `offset_stops`, through `curve` or else [`default_curve`].
pub fn file_tone(
    lighting: Option<&solution::format::Lighting>,
    offset_stops: f32,
    curve: Option<ToneCurve>,
) -> ToneSettings {
    ToneSettings {
        exposure_stops: file_exposure_stops(lighting) + offset_stops,
        curve: curve.unwrap_or_else(|| default_curve(lighting)),
    }
}

/// The sRGB transfer function for a linear value in 0..1.
pub fn srgb_encode(linear: f32) -> f32 {
    shared::linear_to_srgb(linear)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_lit_file_is_exposed_from_its_key_with_aces_and_others_as_before() {
        let lit = solution::format::Lighting {
            exposure_key: 0.72,
            ..Default::default()
        };
        // 0.18 / 0.72 = 2⁻²: two stops down, plus the user's offset.
        let tone = file_tone(Some(&lit), 0.5, None);
        assert!((tone.exposure_stops + 1.5).abs() < 1e-6);
        assert_eq!(tone.curve, ToneCurve::Aces);
        assert_eq!(
            file_tone(Some(&lit), 0.0, Some(ToneCurve::Clamp)).curve,
            ToneCurve::Clamp
        );
        // No key (0: not computed) or no lighting: the offset alone, clamp.
        let unkeyed = solution::format::Lighting::default();
        assert_eq!(file_tone(Some(&unkeyed), 0.5, None).exposure_stops, 0.5);
        let plain = file_tone(None, 1.0, None);
        assert_eq!((plain.exposure_stops, plain.curve), (1.0, ToneCurve::Clamp));
    }

    #[test]
    fn exposure_is_in_stops_and_codes_match_the_shader() {
        let t = ToneSettings {
            exposure_stops: 2.0,
            curve: ToneCurve::Reinhard,
        };
        // 0.25 · 2² = 1, Reinhard(1) = 1/2.
        assert!((t.display_value(0.25) - 0.5).abs() < 1e-7);
        assert_eq!(t.display_value(-3.0), 0.0);
        // tonemap.frag switches on 0 = clamp, 1 = reinhard, 2 = aces.
        assert_eq!(
            [ToneCurve::Clamp, ToneCurve::Reinhard, ToneCurve::Aces].map(|c| c.code()),
            [0, 1, 2]
        );
        // 18% grey encodes to 0.4614 (IEC 61966-2-1).
        assert!((srgb_encode(0.18) - 0.461_356).abs() < 1e-5);
    }
}
