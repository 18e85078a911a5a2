//! Photometric values as the solver's radiometric RGB (issue 41, "Units").
//!
//! The solver's radiance is radiometric, RGB W·sr⁻¹·m⁻² per channel, as a
//! material's `Ke`. A photometric value X (candela, lux, or cd·m⁻²) given with
//! a colour c becomes c · X / 683 per channel: the colour is a filter on a
//! white light, and a white light (c = (1, 1, 1)) has X / 683 in each channel.
//! This is the rule of glTF's `KHR_lights_punctual` ("the luminous intensity
//! … in candela … (lm/sr)", divided by 683 lm/W for watts) and so it keeps
//! lights imported from glTF and those given in TOML on one scale.
//!
//! The rule treats each RGB channel as if all its power were at 555 nm, the
//! wavelength at which the candela is defined, so it is a convention and not a
//! spectral conversion: 100 klux of sunlight is about 146 W·m⁻² per channel
//! here, not the 1,000 W·m⁻² a pyranometer reads. What matters for the solve
//! is that every light, and the sky, uses the same convention.

use glam::DVec3;

/// Lumens per watt at 540 THz (about 555 nm): the SI definition of the
/// candela (BIPM, SI Brochure 9th edition 2019, §2.3.1: "the luminous
/// efficacy of monochromatic radiation of frequency 540 × 10¹² Hz, K_cd, is
/// 683 lm W⁻¹"), and the factor glTF's `KHR_lights_punctual` specification
/// names for converting its photometric units to watts.
pub const LUMENS_PER_WATT: f64 = 683.0;

/// The radiometric RGB of a photometric `value` seen through `color`:
/// `color · value / 683` per channel. The unit follows the input: cd gives
/// W·sr⁻¹, lx gives W·m⁻², cd·m⁻² gives W·sr⁻¹·m⁻².
fn photometric_to_radiometric(value: f64, color: DVec3) -> DVec3 {
    color * (value / LUMENS_PER_WATT)
}

/// The inverse of [`photometric_to_radiometric`] for a white light: the
/// photometric value whose radiometric RGB has `radiometric` in a channel.
fn radiometric_to_photometric(radiometric: f64) -> f64 {
    radiometric * LUMENS_PER_WATT
}

/// Luminous intensity in candela with a colour filter → radiant intensity,
/// W·sr⁻¹ per channel.
pub fn candela_to_intensity(candela: f64, color: DVec3) -> DVec3 {
    photometric_to_radiometric(candela, color)
}

/// Illuminance in lux with a colour filter → irradiance, W·m⁻² per channel.
pub fn lux_to_irradiance(lux: f64, color: DVec3) -> DVec3 {
    photometric_to_radiometric(lux, color)
}

/// Luminance in cd·m⁻² (nits) with a colour filter → radiance,
/// W·sr⁻¹·m⁻² per channel.
pub fn nits_to_radiance(nits: f64, color: DVec3) -> DVec3 {
    photometric_to_radiometric(nits, color)
}

/// One channel's radiant intensity (W·sr⁻¹) → the candela of a white light
/// that has it.
pub fn intensity_to_candela(intensity: f64) -> f64 {
    radiometric_to_photometric(intensity)
}

/// One channel's irradiance (W·m⁻²) → the lux of a white light that has it.
pub fn irradiance_to_lux(irradiance: f64) -> f64 {
    radiometric_to_photometric(irradiance)
}

/// One channel's radiance (W·sr⁻¹·m⁻²) → the cd·m⁻² of a white light that
/// has it.
pub fn radiance_to_nits(radiance: f64) -> f64 {
    radiometric_to_photometric(radiance)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_hundred_kilolux_of_white_sun_is_146_watts_per_square_metre() {
        // The figure: 100,000 / 683 = 146.41… W·m⁻² per channel.
        let e = lux_to_irradiance(100_000.0, DVec3::ONE);
        for c in e.to_array() {
            assert!((c - 146.412_884_333_821_4).abs() < 1e-9, "{c}");
            assert!((c - 146.4).abs() < 0.05);
        }
    }

    #[test]
    fn the_colour_is_a_filter_per_channel() {
        let color = DVec3::new(1.0, 0.5, 0.25);
        let i = candela_to_intensity(683.0, color);
        assert_eq!(i, color);
        let l = nits_to_radiance(1366.0, color);
        assert_eq!(l, 2.0 * color);
    }

    #[test]
    fn every_conversion_round_trips() {
        // Multiplying by 683 and dividing by it is exact to a few ulps; 1e-12
        // relative leaves room for two roundings.
        for x in [1e-6, 0.3, 1.0, 683.0, 1234.5, 1e5, 3.2e9] {
            let back = [
                intensity_to_candela(candela_to_intensity(x, DVec3::ONE).x),
                irradiance_to_lux(lux_to_irradiance(x, DVec3::ONE).y),
                radiance_to_nits(nits_to_radiance(x, DVec3::ONE).z),
            ];
            for b in back {
                assert!((b - x).abs() <= 1e-12 * x, "{x} -> {b}");
            }
        }
    }
}
