//! The sky: radiance arriving from every direction that reaches no geometry
//! (issue 41, "Sky").
//!
//! A [`SkyModel`] is the sky as a scene describes it (its kind and
//! parameters); a [`Sky`] evaluates it in the scene frame, about the scene's
//! up axis, with a rule for directions below the horizon ([`BelowHorizon`]).
//! Radiance is RGB W·sr⁻¹·m⁻² per channel; photometric inputs (cd·m⁻², lux)
//! go through `units.rs` (c · X / 683).
//!
//! The kinds:
//! - **uniform**: the same radiance L everywhere above the horizon; a
//!   horizontal plane open to it receives πL.
//! - **CIE standard overcast** (Moon and Spencer 1942, adopted by the CIE in
//!   1955; CIE S 011/E:2003 sky type 1): L(θ) = L_z (1 + 2 cos θ) / 3 with θ
//!   the zenith angle, so the zenith is three times as bright as the horizon.
//!   A horizontal plane receives 7πL_z/9 (derived at
//!   [`CIE_OVERCAST_HORIZONTAL_FACTOR`]).
//! - **clear**: Preetham, Shirley and Smits (1999), "A Practical Analytic
//!   Model for Daylight", SIGGRAPH 99: the Perez et al. (1993) all-weather
//!   distribution fitted per turbidity for the luminance Y and the
//!   chromaticities x, y, converted to linear Rec. 709 RGB through CIE XYZ.

use super::envmap::EnvMap;
use super::sun::{unit_direction, Sun};
use super::units;
use glam::DVec3;
use std::f64::consts::PI;
use std::sync::Arc;

/// E_h / L_z for the CIE overcast sky:
/// E_h = ∫₀^{2π} ∫₀^{π/2} L_z (1 + 2 cos θ)/3 · cos θ sin θ dθ dφ
///     = (2π L_z / 3) (∫ cos θ sin θ dθ + 2 ∫ cos² θ sin θ dθ)
///     = (2π L_z / 3) (1/2 + 2/3) = 7π L_z / 9.
pub const CIE_OVERCAST_HORIZONTAL_FACTOR: f64 = 7.0 * PI / 9.0;

/// The midpoint rule's zenith-angle steps for skies without a closed-form
/// horizontal irradiance (the clear sky): 256 steps in θ and 512 in φ give a
/// relative error under 1e-4 (the test `clear_sky_irradiance_converges`).
pub const NUMERIC_THETA_STEPS: u32 = 256;

/// Why a sky could not be built: each names the value it refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SkyError {
    #[error("{what} is {value}; it must be a finite number ≥ 0")]
    Negative { what: &'static str, value: f64 },
    #[error("the clear sky's turbidity is {0}; Preetham et al.'s fit covers 2 to 10")]
    Turbidity(f64),
    #[error("the clear sky needs the sun above the horizon; its elevation is {0:.3}°")]
    SunBelowHorizon(f64),
    #[error("the direction [{0}, {1}, {2}] must be finite and not zero")]
    BadDirection(f64, f64, f64),
    #[error("the ground albedo has {0} in a channel; each must be in [0, 1]")]
    Albedo(f64),
}

fn non_negative(what: &'static str, value: f64) -> Result<f64, SkyError> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(SkyError::Negative { what, value })
    }
}

fn non_negative_rgb(what: &'static str, rgb: DVec3) -> Result<DVec3, SkyError> {
    for value in rgb.to_array() {
        non_negative(what, value)?;
    }
    Ok(rgb)
}

fn unit(v: DVec3) -> Result<DVec3, SkyError> {
    unit_direction(v).ok_or(SkyError::BadDirection(v.x, v.y, v.z))
}

/// The sky as a scene describes it.
#[derive(Debug, Clone, PartialEq)]
pub enum SkyModel {
    /// The same radiance in every direction above the horizon.
    Uniform { radiance: DVec3 },
    /// The CIE standard overcast sky with radiance `zenith_radiance` at the
    /// zenith.
    CieOvercast { zenith_radiance: DVec3 },
    /// Preetham et al.'s clear sky for `turbidity` (2 to 10: 2 is a very
    /// clear day, 10 a hazy one) with the sun toward `sun_direction`.
    Clear {
        turbidity: f64,
        sun_direction: DVec3,
    },
    /// An equirectangular environment map (`envmap.rs`), its columns
    /// starting at `north` (made horizontal about the sky's up).
    Map { map: Arc<EnvMap>, north: DVec3 },
}

impl SkyModel {
    /// A uniform sky of radiance `radiance`, W·sr⁻¹·m⁻² per channel.
    pub fn uniform(radiance: DVec3) -> Result<Self, SkyError> {
        Ok(SkyModel::Uniform {
            radiance: non_negative_rgb("the sky's radiance", radiance)?,
        })
    }

    /// A uniform sky of luminance `nits` (cd·m⁻²) through the colour filter
    /// `color`.
    pub fn uniform_luminance(nits: f64, color: DVec3) -> Result<Self, SkyError> {
        non_negative("the sky's luminance", nits)?;
        Self::uniform(units::nits_to_radiance(nits, color))
    }

    /// A CIE overcast sky of zenith radiance `zenith_radiance`.
    pub fn cie_overcast(zenith_radiance: DVec3) -> Result<Self, SkyError> {
        Ok(SkyModel::CieOvercast {
            zenith_radiance: non_negative_rgb("the sky's zenith radiance", zenith_radiance)?,
        })
    }

    /// A CIE overcast sky of zenith luminance `nits` (cd·m⁻²) through
    /// `color`.
    pub fn cie_overcast_luminance(nits: f64, color: DVec3) -> Result<Self, SkyError> {
        non_negative("the sky's zenith luminance", nits)?;
        Self::cie_overcast(units::nits_to_radiance(nits, color))
    }

    /// A CIE overcast sky that gives a horizontal plane the illuminance
    /// `lux` through `color`: L_z = 9 E_h / (7π).
    pub fn cie_overcast_illuminance(lux: f64, color: DVec3) -> Result<Self, SkyError> {
        non_negative("the sky's horizontal illuminance", lux)?;
        Self::cie_overcast_luminance(lux / CIE_OVERCAST_HORIZONTAL_FACTOR, color)
    }

    /// Preetham et al.'s clear sky for `turbidity` in [2, 10] with the sun
    /// toward `sun_direction` (need not be unit length).
    pub fn clear(turbidity: f64, sun_direction: DVec3) -> Result<Self, SkyError> {
        if !(2.0..=10.0).contains(&turbidity) {
            return Err(SkyError::Turbidity(turbidity));
        }
        Ok(SkyModel::Clear {
            turbidity,
            sun_direction: unit(sun_direction)?,
        })
    }
}

impl SkyModel {
    /// The model after its constructor's checks, for one built directly
    /// from its public fields.
    fn checked(self) -> Result<Self, SkyError> {
        match self {
            SkyModel::Map { map, north } => Ok(SkyModel::Map {
                map,
                north: unit(north)?,
            }),
            SkyModel::Uniform { radiance } => Self::uniform(radiance),
            SkyModel::CieOvercast { zenith_radiance } => Self::cie_overcast(zenith_radiance),
            SkyModel::Clear {
                turbidity,
                sun_direction,
            } => Self::clear(turbidity, sun_direction),
        }
    }
}

/// What a sky shows below the horizon.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum BelowHorizon {
    /// Nothing: no light from below (the default).
    #[default]
    Black,
    /// The sky continues, mirrored in the horizon: a direction at zenith
    /// angle θ > 90° sees what 180° − θ sees. A uniform sky is then the same
    /// everywhere, as a path tracer's constant environment is; a CIE or
    /// clear sky stays positive (its formula continued past the horizon
    /// would turn negative or blow up).
    Same,
    /// A diffuse ground of albedo ρ (per channel, in [0, 1]) lit by the sky
    /// and, when given, the sun: L = ρ · E_h / π, with E_h the horizontal
    /// irradiance from the sky above the horizon plus the sun's E⊥ sin(h)
    /// at elevation h > 0. The ground is unshadowed and infinite.
    Ground { albedo: DVec3 },
}

/// A sky evaluated in the scene frame about its up axis.
#[derive(Debug, Clone, PartialEq)]
pub struct Sky {
    model: SkyModel,
    up: DVec3,
    below: BelowHorizon,
    clear: Option<Preetham>,
    horizontal_irradiance: DVec3,
    ground_radiance: DVec3,
}

impl Sky {
    /// `model` about the unit `up` (need not be unit length), showing
    /// `below` under the horizon. `sun` lights the ground of
    /// [`BelowHorizon::Ground`]; the other rules ignore it.
    pub fn new(
        model: SkyModel,
        up: DVec3,
        below: BelowHorizon,
        sun: Option<&Sun>,
    ) -> Result<Self, SkyError> {
        let up = unit(up)?;
        let model = match model.checked()? {
            // The map's north made horizontal about this sky's up.
            SkyModel::Map { map, north } => {
                let horizontal = north - up * north.dot(up);
                SkyModel::Map {
                    map,
                    north: unit(horizontal)?,
                }
            }
            other => other,
        };
        let clear = match model {
            SkyModel::Clear {
                turbidity,
                sun_direction,
            } => Some(Preetham::new(turbidity, sun_direction, up)?),
            _ => None,
        };
        let mut sky = Sky {
            model,
            up,
            below,
            clear,
            horizontal_irradiance: DVec3::ZERO,
            ground_radiance: DVec3::ZERO,
        };
        sky.horizontal_irradiance = match &sky.model {
            SkyModel::Map { map, .. } => map.horizontal_irradiance(),
            SkyModel::Uniform { radiance } => PI * *radiance,
            SkyModel::CieOvercast { zenith_radiance } => {
                CIE_OVERCAST_HORIZONTAL_FACTOR * *zenith_radiance
            }
            SkyModel::Clear { .. } => {
                hemisphere_irradiance(|w| sky.above(w), up, NUMERIC_THETA_STEPS)
            }
        };
        if let BelowHorizon::Ground { albedo } = below {
            if let Some(&value) = albedo.to_array().iter().find(|v| !(0.0..=1.0).contains(*v)) {
                return Err(SkyError::Albedo(value));
            }
            let from_sun = sun.map_or(DVec3::ZERO, |s| {
                s.irradiance() * s.direction().dot(up).max(0.0)
            });
            sky.ground_radiance = albedo * (sky.horizontal_irradiance + from_sun) / PI;
        }
        Ok(sky)
    }

    pub fn model(&self) -> SkyModel {
        self.model.clone()
    }

    pub fn up(&self) -> DVec3 {
        self.up
    }

    pub fn below_horizon(&self) -> BelowHorizon {
        self.below
    }

    /// The radiance arriving from `direction` (toward the sky, need not be
    /// unit length), RGB W·sr⁻¹·m⁻². The horizon itself (cos θ = 0) belongs
    /// to the sky above it.
    pub fn radiance(&self, direction: DVec3) -> DVec3 {
        let w = direction.normalize_or_zero();
        let cos_theta = w.dot(self.up);
        if cos_theta >= 0.0 {
            return self.above(w);
        }
        if let (SkyModel::Map { .. }, BelowHorizon::Same) = (&self.model, self.below) {
            // A map holds its own lower half: "same" shows it.
            return self.above(w);
        }
        match self.below {
            BelowHorizon::Black => DVec3::ZERO,
            BelowHorizon::Same => self.above(w - 2.0 * cos_theta * self.up),
            BelowHorizon::Ground { .. } => self.ground_radiance,
        }
    }

    /// The irradiance from the sky above the horizon on a horizontal plane
    /// facing up, W·m⁻² per channel: πL (uniform) and 7πL_z/9 (CIE
    /// overcast) exactly; for the clear sky, the midpoint rule with
    /// [`NUMERIC_THETA_STEPS`] (relative error under 1e-4).
    pub fn horizontal_irradiance(&self) -> DVec3 {
        self.horizontal_irradiance
    }

    /// The ground's radiance under [`BelowHorizon::Ground`], else zero.
    pub fn ground_radiance(&self) -> DVec3 {
        self.ground_radiance
    }

    /// The irradiance on a plane facing `normal` open to the whole sky (both
    /// hemispheres, with the below-horizon rule), by the midpoint rule with
    /// `theta_steps` zenith steps about the normal and twice as many in
    /// azimuth. Where the radiance is smooth the error falls as the steps'
    /// square; a horizon crossing the hemisphere makes it fall only as the
    /// steps (about 1e-3 relative at 256 steps).
    /// A zero or non-finite normal gets zero.
    pub fn irradiance(&self, normal: DVec3, theta_steps: u32) -> DVec3 {
        unit_direction(normal).map_or(DVec3::ZERO, |n| {
            hemisphere_irradiance(|w| self.radiance(w), n, theta_steps)
        })
    }

    /// The radiance of the model at unit `w` with w · up ≥ 0.
    fn above(&self, w: DVec3) -> DVec3 {
        match &self.model {
            SkyModel::Map { map, north } => {
                let east = north.cross(self.up);
                map.radiance(DVec3::new(w.dot(*north), w.dot(east), w.dot(self.up)))
            }
            SkyModel::Uniform { radiance } => *radiance,
            SkyModel::CieOvercast { zenith_radiance } => {
                *zenith_radiance * (1.0 + 2.0 * w.dot(self.up)) / 3.0
            }
            SkyModel::Clear { .. } => self
                .clear
                .as_ref()
                .map_or(DVec3::ZERO, |p| p.radiance(w, self.up)),
        }
    }
}

/// ∫ L(ω) (ω · axis) dω over the hemisphere about the unit `axis`, by the
/// midpoint rule in θ (`theta_steps`) and φ (2 × `theta_steps`).
fn hemisphere_irradiance(
    radiance: impl Fn(DVec3) -> DVec3,
    axis: DVec3,
    theta_steps: u32,
) -> DVec3 {
    let n_theta = theta_steps.max(1);
    let n_phi = 2 * n_theta;
    let d_theta = 0.5 * PI / f64::from(n_theta);
    let d_phi = 2.0 * PI / f64::from(n_phi);
    let (t, b) = axis.any_orthonormal_pair();
    let mut sum = DVec3::ZERO;
    for i in 0..n_theta {
        let theta = (f64::from(i) + 0.5) * d_theta;
        let (s, c) = theta.sin_cos();
        let mut ring = DVec3::ZERO;
        for j in 0..n_phi {
            let (sp, cp) = ((f64::from(j) + 0.5) * d_phi).sin_cos();
            ring += radiance(axis * c + s * (cp * t + sp * b));
        }
        sum += ring * (c * s);
    }
    sum * d_theta * d_phi
}

/// Preetham et al.'s (1999) clear sky, its sun-dependent parts precomputed.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Preetham {
    sun: DVec3,
    /// The Perez coefficients A–E for Y, x and y (Preetham et al. 1999,
    /// Appendix A.2, linear in the turbidity).
    perez: [[f64; 5]; 3],
    /// Y_z (cd·m⁻²), x_z, y_z divided by F(0, θ_s): the zenith values over
    /// the distribution's zenith value, so that value × F(θ, γ) is the sky.
    scale: [f64; 3],
}

impl Preetham {
    fn new(turbidity: f64, sun: DVec3, up: DVec3) -> Result<Self, SkyError> {
        let cos_s = sun.dot(up);
        if cos_s <= 0.0 {
            return Err(SkyError::SunBelowHorizon(
                cos_s.clamp(-1.0, 1.0).asin().to_degrees(),
            ));
        }
        let t = turbidity;
        let theta_s = cos_s.clamp(-1.0, 1.0).acos();
        let perez = [
            [
                0.1787 * t - 1.4630,
                -0.3554 * t + 0.4275,
                -0.0227 * t + 5.3251,
                0.1206 * t - 2.5771,
                -0.0670 * t + 0.3703,
            ],
            [
                -0.0193 * t - 0.2592,
                -0.0665 * t + 0.0008,
                -0.0004 * t + 0.2125,
                -0.0641 * t - 0.8989,
                -0.0033 * t + 0.0452,
            ],
            [
                -0.0167 * t - 0.2608,
                -0.0950 * t + 0.0092,
                -0.0079 * t + 0.2102,
                -0.0441 * t - 1.6537,
                -0.0109 * t + 0.0529,
            ],
        ];
        // Zenith luminance in kcd·m⁻² (Appendix A.2), here in cd·m⁻².
        let chi = (4.0 / 9.0 - t / 120.0) * (PI - 2.0 * theta_s);
        let y_zenith = 1000.0 * ((4.0453 * t - 4.9710) * chi.tan() - 0.2155 * t + 2.4192);
        // Zenith chromaticity: [T², T, 1] · M · [θ_s³, θ_s², θ_s, 1].
        let chroma = |m: [[f64; 4]; 3]| {
            let th = [theta_s.powi(3), theta_s.powi(2), theta_s, 1.0];
            let row = |r: [f64; 4]| r.iter().zip(th).map(|(a, b)| a * b).sum::<f64>();
            t * t * row(m[0]) + t * row(m[1]) + row(m[2])
        };
        let x_zenith = chroma([
            [0.00166, -0.00375, 0.00209, 0.0],
            [-0.02903, 0.06377, -0.03202, 0.00394],
            [0.11693, -0.21196, 0.06052, 0.25886],
        ]);
        let y_chroma_zenith = chroma([
            [0.00275, -0.00610, 0.00317, 0.0],
            [-0.04214, 0.08970, -0.04153, 0.00516],
            [0.15346, -0.26756, 0.06670, 0.26688],
        ]);
        let zenith = [y_zenith.max(0.0), x_zenith, y_chroma_zenith];
        let mut scale = [0.0; 3];
        for k in 0..3 {
            scale[k] = zenith[k] / perez_f(perez[k], 1.0, cos_s);
        }
        Ok(Preetham { sun, perez, scale })
    }

    /// Linear Rec. 709 radiance toward unit `w` above the horizon.
    fn radiance(&self, w: DVec3, up: DVec3) -> DVec3 {
        let cos_theta = w.dot(up);
        let cos_gamma = w.dot(self.sun).clamp(-1.0, 1.0);
        let v: [f64; 3] =
            std::array::from_fn(|k| self.scale[k] * perez_f(self.perez[k], cos_theta, cos_gamma));
        xyy_to_radiance(v[1], v[2], v[0])
    }
}

/// The Perez et al. (1993) distribution F(θ, γ) = (1 + A e^{B / cos θ}) ·
/// (1 + C e^{D γ} + E cos² γ), θ the zenith angle and γ the angle to the
/// sun. At the horizon B / cos θ → −∞ (B < 0 for every turbidity ≥ 2), so
/// the first factor tends to 1; the division is guarded there.
fn perez_f(c: [f64; 5], cos_theta: f64, cos_gamma: f64) -> f64 {
    let [a, b, cc, d, e] = c;
    let gamma = cos_gamma.acos();
    let first = if cos_theta > 1e-9 {
        1.0 + a * (b / cos_theta).exp()
    } else {
        1.0
    };
    first * (1.0 + cc * (d * gamma).exp() + e * cos_gamma * cos_gamma)
}

/// CIE xyY (Y in cd·m⁻²) → linear Rec. 709 RGB radiance (W·sr⁻¹·m⁻²): XYZ,
/// then the sRGB/Rec. 709 matrix for the D65 white (IEC 61966-2-1), then the
/// 1/683 rule of `units.rs`, so that the D65 white of luminance Y gives Y/683
/// in every channel. Negative channels (colours outside the Rec. 709 gamut)
/// are clipped to 0.
fn xyy_to_radiance(x: f64, y: f64, luminance: f64) -> DVec3 {
    if y <= 0.0 || luminance <= 0.0 {
        return DVec3::ZERO;
    }
    let xyz = DVec3::new(x * luminance / y, luminance, (1.0 - x - y) * luminance / y);
    let rgb = DVec3::new(
        3.240_454_2 * xyz.x - 1.537_138_5 * xyz.y - 0.498_531_4 * xyz.z,
        -0.969_266_0 * xyz.x + 1.876_010_8 * xyz.y + 0.041_556_0 * xyz.z,
        0.055_643_4 * xyz.x - 0.204_025_9 * xyz.y + 1.057_225_2 * xyz.z,
    );
    units::nits_to_radiance(1.0, rgb.max(DVec3::ZERO))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::sun::SunPosition;

    fn rel(a: DVec3, b: DVec3) -> f64 {
        (a - b).abs().max_element() / b.abs().max_element()
    }

    fn upper(sky: &Sky, steps: u32) -> DVec3 {
        hemisphere_irradiance(|w| sky.radiance(w), sky.up(), steps)
    }

    #[test]
    fn uniform_sky_gives_pi_l_on_a_horizontal_plane() {
        let l = DVec3::new(1.0, 2.0, 3.0);
        let up = DVec3::new(0.2, 1.0, -0.1);
        let sky = Sky::new(SkyModel::uniform(l).unwrap(), up, BelowHorizon::Black, None).unwrap();
        assert!(rel(sky.horizontal_irradiance(), PI * l) < 1e-15);
        // The midpoint rule on ∫ cos θ sin θ: error (Δθ)²/24 · … ≈ 1e-5 at
        // 256 steps (here 4e-6).
        assert!(rel(upper(&sky, 256), PI * l) < 1e-5);
        // As luminance: 683 cd/m² of white is 1 W·sr⁻¹·m⁻² per channel.
        let nits = SkyModel::uniform_luminance(683.0, DVec3::ONE).unwrap();
        assert_eq!(
            nits,
            SkyModel::Uniform {
                radiance: DVec3::ONE
            }
        );
    }

    #[test]
    fn uniform_sky_on_a_tilted_plane_gives_one_plus_cos_over_two() {
        // A plane tilted by β sees the sky over (1 + cos β)/2 of its πL;
        // black below. The horizon cuts the hemisphere, so the midpoint rule
        // converges only as the step: 2e-3 at 256 steps.
        let sky = Sky::new(
            SkyModel::uniform(DVec3::ONE).unwrap(),
            DVec3::Y,
            BelowHorizon::Black,
            None,
        )
        .unwrap();
        for beta in [0.0f64, 30.0, 60.0, 90.0, 135.0] {
            let n = DVec3::new(beta.to_radians().sin(), beta.to_radians().cos(), 0.0);
            let e = sky.irradiance(n, 256).x;
            let expected = (1.0 + beta.to_radians().cos()) / 2.0 * PI;
            assert!(
                (e - expected).abs() < 2e-3 * PI,
                "{beta}: {e} vs {expected}"
            );
        }
    }

    #[test]
    fn cie_overcast_horizontal_illuminance_is_seven_pi_over_nine() {
        let lz = DVec3::new(3.0, 2.0, 1.0);
        let sky = Sky::new(
            SkyModel::cie_overcast(lz).unwrap(),
            DVec3::Z,
            BelowHorizon::Black,
            None,
        )
        .unwrap();
        assert!(rel(sky.horizontal_irradiance(), 7.0 * PI / 9.0 * lz) < 1e-15);
        // The integrand is smooth: the midpoint rule's error is under 1e-5
        // at 256 steps.
        assert!(rel(upper(&sky, 256), 7.0 * PI / 9.0 * lz) < 1e-5);
        // Zenith three times the horizon.
        let zenith = sky.radiance(DVec3::Z * 2.0);
        let horizon = sky.radiance(DVec3::X);
        assert!(rel(zenith, lz) < 1e-15 && rel(horizon, lz / 3.0) < 1e-15);
        assert!(rel(zenith, 3.0 * horizon) < 1e-15);
    }

    #[test]
    fn cie_overcast_from_illuminance_gives_that_illuminance() {
        // 10 klux of white: L_z = 9·10⁴/(7π) cd/m², and the plane gets back
        // 10⁴/683 W/m² per channel.
        let model = SkyModel::cie_overcast_illuminance(10_000.0, DVec3::ONE).unwrap();
        let sky = Sky::new(model.clone(), DVec3::Y, BelowHorizon::Black, None).unwrap();
        let lux = units::irradiance_to_lux(sky.horizontal_irradiance().y);
        assert!((lux - 10_000.0).abs() < 1e-9, "{lux}");
        let SkyModel::CieOvercast { zenith_radiance } = model else {
            panic!("not CIE")
        };
        let nits = units::radiance_to_nits(zenith_radiance.x);
        assert!((nits - 90_000.0 / (7.0 * PI)).abs() < 1e-9);
    }

    #[test]
    fn below_the_horizon_rules() {
        let l = DVec3::new(1.0, 0.5, 0.25);
        let down = DVec3::new(0.3, -1.0, 0.2);
        let mirrored = DVec3::new(0.3, 1.0, 0.2);
        let uniform = SkyModel::uniform(l).unwrap();
        let cie = SkyModel::cie_overcast(l).unwrap();
        let make = |m: &SkyModel, b, sun| Sky::new(m.clone(), DVec3::Y, b, sun).unwrap();
        assert_eq!(
            make(&uniform, BelowHorizon::default(), None).radiance(down),
            DVec3::ZERO
        );
        assert_eq!(make(&uniform, BelowHorizon::Same, None).radiance(down), l);
        let same = make(&cie, BelowHorizon::Same, None);
        assert!(rel(same.radiance(down), same.radiance(mirrored)) < 1e-15);
        assert!(same.radiance(-DVec3::Y).min_element() > 0.0);
        // Ground: ρ E_h / π with E_h = πL from the uniform sky, so ρL; and
        // a sun of E⊥ at elevation 30° adds ρ E⊥ sin 30° / π.
        let albedo = DVec3::new(0.2, 0.4, 0.6);
        let ground = BelowHorizon::Ground { albedo };
        assert!(rel(make(&uniform, ground, None).radiance(down), albedo * l) < 1e-15);
        let position = SunPosition::from_direction(DVec3::new(3f64.sqrt(), 1.0, 0.0)).unwrap();
        let sun = Sun::new(position, DVec3::splat(100.0), 0.53).unwrap();
        let lit = make(&uniform, ground, Some(&sun));
        let expected = albedo * (PI * l + DVec3::splat(50.0)) / PI;
        assert!(rel(lit.radiance(down), expected) < 1e-12);
        assert!(rel(lit.ground_radiance(), expected) < 1e-12);
        // Above the horizon the rule changes nothing.
        assert_eq!(lit.radiance(mirrored), l);
        let bad = BelowHorizon::Ground {
            albedo: DVec3::new(0.5, 1.5, 0.5),
        };
        assert!(Sky::new(uniform, DVec3::Y, bad, None).is_err());
    }

    #[test]
    fn bad_sky_inputs_are_refused() {
        assert!(SkyModel::uniform(DVec3::new(1.0, -1.0, 1.0)).is_err());
        assert!(SkyModel::uniform(DVec3::new(1.0, f64::NAN, 1.0)).is_err());
        assert!(SkyModel::cie_overcast_illuminance(f64::INFINITY, DVec3::ONE).is_err());
        let err = SkyModel::uniform_luminance(-5.0, DVec3::ONE).unwrap_err();
        assert!(err.to_string().contains("-5"), "{err}");
        assert!(SkyModel::clear(1.0, DVec3::Y).is_err());
        assert!(SkyModel::clear(3.0, DVec3::ZERO).is_err());
        let below = SkyModel::clear(3.0, DVec3::new(1.0, -0.1, 0.0)).unwrap();
        let err = Sky::new(below, DVec3::Y, BelowHorizon::Black, None).unwrap_err();
        assert!(
            matches!(err, SkyError::SunBelowHorizon(e) if e < 0.0),
            "{err}"
        );
        let uniform = SkyModel::uniform(DVec3::ONE).unwrap();
        assert!(Sky::new(uniform.clone(), DVec3::ZERO, BelowHorizon::Black, None).is_err());
        // A model built from its fields is checked too.
        let direct = SkyModel::Uniform {
            radiance: DVec3::new(1.0, -2.0, 1.0),
        };
        assert!(Sky::new(direct, DVec3::Y, BelowHorizon::Black, None).is_err());
        let nan_albedo = BelowHorizon::Ground {
            albedo: DVec3::new(0.5, f64::NAN, 0.5),
        };
        assert!(Sky::new(uniform.clone(), DVec3::Y, nan_albedo, None).is_err());
        let sky = Sky::new(uniform, DVec3::Y, BelowHorizon::Black, None).unwrap();
        assert_eq!(sky.irradiance(DVec3::ZERO, 8), DVec3::ZERO);
    }

    #[test]
    fn d65_white_becomes_equal_channels() {
        // The sRGB matrix maps the D65 white (x, y) = (0.3127, 0.3290) to
        // R = G = B = Y to 4 digits (the chromaticities' rounding).
        let l = xyy_to_radiance(0.3127, 0.3290, 683.0);
        assert!((l - DVec3::ONE).abs().max_element() < 1e-3, "{l}");
    }

    fn clear(turbidity: f64, elevation_deg: f64) -> Sky {
        let e = elevation_deg.to_radians();
        let sun = DVec3::new(e.cos(), e.sin(), 0.0);
        Sky::new(
            SkyModel::clear(turbidity, sun).unwrap(),
            DVec3::Y,
            BelowHorizon::Black,
            None,
        )
        .unwrap()
    }

    #[test]
    fn clear_sky_zenith_matches_preetham_zenith_luminance() {
        // At the zenith F(0, θ_s)/F(0, θ_s) = 1, so the luminance there is
        // Preetham's Y_z: for T = 2.5 and θ_s = 45°,
        // χ = (4/9 − 2.5/120)(π − π/2), Y_z = (4.0453·2.5 − 4.9710) tan χ
        // − 0.2155·2.5 + 2.4192 kcd/m². The luminance of linear Rec. 709 is
        // 0.2126 R + 0.7152 G + 0.0722 B (IEC 61966-2-1), × 683; the gamut
        // clip could lower it, which a zenith blue stays clear of (1e-6).
        let sky = clear(2.5, 45.0);
        let l = sky.radiance(DVec3::Y);
        let y = 683.0 * (0.2126 * l.x + 0.7152 * l.y + 0.0722 * l.z);
        let chi = (4.0 / 9.0 - 2.5 / 120.0) * (PI / 2.0);
        let yz = 1000.0 * ((4.0453 * 2.5 - 4.9710) * chi.tan() - 0.2155 * 2.5 + 2.4192);
        assert!((y - yz).abs() < 1e-3 * yz, "{y} vs {yz}");
        // A clear zenith is blue.
        assert!(l.z > l.x, "{l}");
    }

    #[test]
    fn clear_sky_is_brightest_around_the_sun() {
        // At the sun's elevation, toward the sun is brighter than away from
        // it (the Perez circumsolar term C e^{Dγ}).
        let sky = clear(3.0, 30.0);
        let e = 30f64.to_radians();
        let toward = sky.radiance(DVec3::new(e.cos(), e.sin(), 0.0) + DVec3::Z * 0.05);
        let away = sky.radiance(DVec3::new(-e.cos(), e.sin(), 0.0));
        assert!(toward.y > 3.0 * away.y, "{toward} {away}");
        assert!(sky.radiance(DVec3::new(0.0, -1.0, 0.0)) == DVec3::ZERO);
    }

    #[test]
    fn clear_sky_irradiance_converges() {
        // The stored value (256 steps) against 512 steps: the midpoint
        // rule's error falls 4× per doubling, so their difference bounds
        // the error at 256 steps; we require it under 1e-4.
        for (t, elevation) in [(2.0, 60.0), (3.0, 30.0), (6.0, 10.0), (10.0, 80.0)] {
            let sky = clear(t, elevation);
            let stored = sky.horizontal_irradiance();
            let fine = upper(&sky, 512);
            assert!(rel(stored, fine) < 1e-4, "{t} {elevation}: {stored} {fine}");
            assert!(stored.min_element() > 0.0);
        }
    }
}
