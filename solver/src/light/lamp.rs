//! Point and spot lamps (issue 41): a position, an intensity per direction,
//! and an optional radius.
//!
//! A lamp's radiant intensity toward a unit direction ω (from the lamp) is
//!
//!   I(ω) = I₀ · cone(ω) · profile(ω)
//!
//! with I₀ in W·sr⁻¹ per channel, `cone` 1 for a point lamp and for a spot
//! the smoothstep-free falloff glTF's `KHR_lights_punctual` recommends,
//! saturate((cos θ − cos outer) / (cos inner − cos outer))², θ from the spot
//! axis; and `profile` an IES distribution's candela toward ω over its
//! maximum, when the lamp has one (its I₀ is then the profile's peak).
//!
//! A receiver at distance d (metres) whose normal makes angle θ_r with the
//! direction to the lamp gets E = I(ω) cos θ_r / d² (the inverse-square law).
//! A lamp with a radius r is a sphere of that intensity: it lights a point at
//! d > r exactly as the point does when wholly above the receiver's horizon,
//! and its shadows are soft; the solver clamps d to r, so a receiver touching
//! the sphere gets I/r², the sphere's own exitance, instead of a spike.

use super::ies::IesProfile;
use glam::DVec3;
use std::sync::Arc;

/// A lamp's definition is out of range.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LampError {
    #[error("{what} is {value}, which is not a finite number ≥ 0")]
    Negative { what: &'static str, value: f64 },
    #[error("the lamp position has a non-finite coordinate")]
    Position,
    #[error("the spot axis [{0}, {1}, {2}] has no direction: it must be finite and not zero")]
    Axis(f64, f64, f64),
    #[error(
        "the spot cone (inner {inner}°, outer {outer}°) must have 0 ≤ inner < outer ≤ 90 degrees"
    )]
    Cone { inner: f64, outer: f64 },
}

/// How a lamp's intensity varies with direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Beam {
    /// The same in every direction.
    Point,
    /// A cone about `axis` (unit, from the lamp): full inside `cos_inner`,
    /// zero outside `cos_outer`, the squared linear ramp between.
    Spot {
        axis: DVec3,
        cos_inner: f64,
        cos_outer: f64,
    },
}

/// A photometric profile placed in the scene: its type C frame's nadir
/// (−z) along `down` and its φ = 0 plane along `across`, both unit.
#[derive(Debug, Clone, PartialEq)]
pub struct Profile {
    pub ies: Arc<IesProfile>,
    /// The largest candela the profile returns, to normalise it.
    pub peak_candela: f64,
    pub down: DVec3,
    pub across: DVec3,
}

/// A point or spot lamp in scene coordinates.
#[derive(Debug, Clone, PartialEq)]
pub struct Lamp {
    /// Where the lamp is (scene units).
    pub position: DVec3,
    /// I₀: the intensity on the axis (a spot), everywhere (a point), or at
    /// the profile's peak, W·sr⁻¹ per channel.
    pub intensity: DVec3,
    /// The radius of the bulb (scene units); 0 is a point.
    pub radius: f64,
    pub beam: Beam,
    pub profile: Option<Profile>,
    /// A name for messages: the TOML table or glTF light it came from.
    pub name: String,
}

impl Lamp {
    /// A point lamp of intensity `intensity` (W·sr⁻¹ per channel, finite
    /// and ≥ 0) and bulb radius `radius` (scene units, ≥ 0).
    pub fn point(
        name: &str,
        position: DVec3,
        intensity: DVec3,
        radius: f64,
    ) -> Result<Self, LampError> {
        if !position.is_finite() {
            return Err(LampError::Position);
        }
        for value in intensity.to_array() {
            non_negative("the lamp intensity", value)?;
        }
        non_negative("the lamp radius", radius)?;
        Ok(Lamp {
            position,
            intensity,
            radius,
            beam: Beam::Point,
            profile: None,
            name: name.to_owned(),
        })
    }

    /// Makes the lamp a spot about `axis` (need not be unit length) whose
    /// full-strength cone is `inner_deg` and whose edge is `outer_deg`,
    /// both from the axis as glTF's `innerConeAngle` and `outerConeAngle`.
    pub fn with_spot(
        mut self,
        axis: DVec3,
        inner_deg: f64,
        outer_deg: f64,
    ) -> Result<Self, LampError> {
        let axis = unit(axis).ok_or(LampError::Axis(axis.x, axis.y, axis.z))?;
        let cone_ok = inner_deg.is_finite()
            && outer_deg.is_finite()
            && 0.0 <= inner_deg
            && inner_deg < outer_deg
            && outer_deg <= 90.0;
        if !cone_ok {
            return Err(LampError::Cone {
                inner: inner_deg,
                outer: outer_deg,
            });
        }
        self.beam = Beam::Spot {
            axis,
            cos_inner: inner_deg.to_radians().cos(),
            cos_outer: outer_deg.to_radians().cos(),
        };
        Ok(self)
    }

    /// Gives the lamp `ies`'s distribution, its nadir along `down` (the spot
    /// axis, or straight down) and its φ = 0 plane along any direction
    /// perpendicular to it. The lamp's intensity is then the profile's
    /// (candela × `color` / 683, `units.rs`) unless `intensity` overrides
    /// its peak.
    pub fn with_profile(mut self, ies: Arc<IesProfile>, down: DVec3) -> Result<Self, LampError> {
        let down = unit(down).ok_or(LampError::Axis(down.x, down.y, down.z))?;
        let across = down.any_orthonormal_vector();
        let peak_candela = peak_candela(&ies);
        self.profile = Some(Profile {
            ies,
            peak_candela,
            down,
            across,
        });
        Ok(self)
    }

    /// The radiant intensity toward unit `w` (from the lamp), W·sr⁻¹.
    pub fn intensity_toward(&self, w: DVec3) -> DVec3 {
        let cone = match self.beam {
            Beam::Point => 1.0,
            Beam::Spot {
                axis,
                cos_inner,
                cos_outer,
            } => spot_falloff(w.dot(axis), cos_inner, cos_outer),
        };
        let profile = self.profile.as_ref().map_or(1.0, |p| {
            if p.peak_candela <= 0.0 {
                return 0.0;
            }
            let side = p.down.cross(p.across);
            // The type C frame: z up (nadir −z), φ = 0 along +x.
            let local = [w.dot(p.across), w.dot(side), -w.dot(p.down)];
            p.ies.candela_toward(local) / p.peak_candela
        });
        self.intensity * (cone * profile)
    }

    /// The lamp's radiant flux, W per channel: ∫ I(ω) dω. Exact for a point
    /// (4π I₀) and a bare spot (2π I₀ ∫ falloff, by the midpoint rule with
    /// 4,096 steps in cos θ, relative error under 1e-6); with a profile, the
    /// profile's flux over its peak times I₀ (the cone then also applies,
    /// and is ignored here: an upper bound).
    pub fn power(&self) -> DVec3 {
        let solid = match (&self.profile, self.beam) {
            (Some(p), _) if p.peak_candela > 0.0 => p.ies.total_flux_lm() / p.peak_candela,
            (Some(_), _) => 0.0,
            (None, Beam::Point) => 4.0 * std::f64::consts::PI,
            (
                None,
                Beam::Spot {
                    cos_inner,
                    cos_outer,
                    ..
                },
            ) => {
                let steps = 4096;
                let h = (1.0 - cos_outer) / steps as f64;
                let sum: f64 = (0..steps)
                    .map(|k| spot_falloff(cos_outer + (k as f64 + 0.5) * h, cos_inner, cos_outer))
                    .sum();
                2.0 * std::f64::consts::PI * sum * h
            }
        };
        self.intensity * solid
    }
}

/// The spot falloff at cos θ from the axis: saturate((cos θ − cos outer) /
/// (cos inner − cos outer))², as `KHR_lights_punctual`'s specification
/// recommends ("Inner and Outer Cone Angles"); the path tracer uses the same.
pub fn spot_falloff(cos_theta: f64, cos_inner: f64, cos_outer: f64) -> f64 {
    let t = ((cos_theta - cos_outer) / (cos_inner - cos_outer)).clamp(0.0, 1.0);
    t * t
}

/// The largest candela over the profile's table (its scale applied).
fn peak_candela(ies: &IesProfile) -> f64 {
    let (nh, nv) = (ies.horizontal_angles().len(), ies.vertical_angles().len());
    let mut peak = 0.0f64;
    for h in 0..nh {
        for v in 0..nv {
            peak = peak.max(ies.raw_candela(h, v).unwrap_or(0.0));
        }
    }
    peak * ies.scale()
}

fn non_negative(what: &'static str, value: f64) -> Result<f64, LampError> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(LampError::Negative { what, value })
    }
}

fn unit(v: DVec3) -> Option<DVec3> {
    let n = v.normalize_or_zero();
    (v.is_finite() && n != DVec3::ZERO).then_some(n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spot_falloff_is_one_inside_zero_outside_and_squared_between() {
        let (ci, co) = (20f64.to_radians().cos(), 30f64.to_radians().cos());
        assert_eq!(spot_falloff(1.0, ci, co), 1.0);
        assert_eq!(spot_falloff(40f64.to_radians().cos(), ci, co), 0.0);
        // Halfway in cos θ the ramp is 1/2, squared 1/4 (exact up to rounding).
        let mid = 0.5 * (ci + co);
        assert!((spot_falloff(mid, ci, co) - 0.25).abs() < 1e-12);
    }

    #[test]
    fn point_power_is_four_pi_intensity() {
        let lamp = Lamp::point("p", DVec3::ZERO, DVec3::new(1.0, 2.0, 3.0), 0.0).unwrap();
        let p = lamp.power();
        assert!(
            (p - 4.0 * std::f64::consts::PI * DVec3::new(1.0, 2.0, 3.0))
                .abs()
                .max_element()
                < 1e-12
        );
    }

    #[test]
    fn spot_power_matches_the_closed_form() {
        // ∫ over the cone of ((c − c_o)/(c_i − c_o))² dω = 2π [(1 − c_i) +
        // (c_i − c_o)/3] for c from c_o to 1 (the ramp integrates to a third
        // of its width). The midpoint rule's error with 4,096 steps is far
        // below the 1e-6 tolerance.
        let lamp = Lamp::point("s", DVec3::ZERO, DVec3::ONE, 0.0)
            .unwrap()
            .with_spot(DVec3::NEG_Z, 20.0, 30.0)
            .unwrap();
        let (ci, co) = (20f64.to_radians().cos(), 30f64.to_radians().cos());
        let exact = 2.0 * std::f64::consts::PI * ((1.0 - ci) + (ci - co) / 3.0);
        assert!(
            (lamp.power().x / exact - 1.0).abs() < 1e-6,
            "{}",
            lamp.power().x
        );
    }

    #[test]
    fn bad_lamps_are_refused_with_the_value() {
        let e = Lamp::point("p", DVec3::ZERO, DVec3::new(1.0, f64::NAN, 0.0), 0.0).unwrap_err();
        assert!(e.to_string().contains("NaN"), "{e}");
        let e = Lamp::point("p", DVec3::ZERO, DVec3::new(-1.0, 0.0, 0.0), 0.0).unwrap_err();
        assert!(e.to_string().contains("-1"), "{e}");
        let lamp = Lamp::point("p", DVec3::ZERO, DVec3::ONE, 0.0).unwrap();
        let e = lamp.clone().with_spot(DVec3::Z, 30.0, 20.0).unwrap_err();
        assert!(e.to_string().contains("inner 30"), "{e}");
        assert!(lamp.clone().with_spot(DVec3::Z, 10.0, 95.0).is_err());
        assert!(lamp.with_spot(DVec3::ZERO, 10.0, 20.0).is_err());
    }
}
