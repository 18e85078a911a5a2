//! Lights that are not glowing polygons: the sun, the sky, and photometric
//! lamps (issue 41). Pure, like the rest of the solver core: parsers take
//! text the importers read, and every function returns values or errors.
//!
//! Units: the solver's radiance is radiometric, RGB W·sr⁻¹·m⁻² per channel,
//! as a material's `Ke`. A photometric value X (cd, lx, cd·m⁻²) with colour c
//! becomes c · X / 683 per channel (`units.rs`): the colour is a filter, and
//! a white light's RGB luminance is X / 683, as glTF's specification has it.

pub mod envmap;
pub mod ies;
pub mod lamp;
pub mod portal;
pub mod portal_detect;
#[cfg(test)]
mod portal_detect_tests;
pub mod sky;
pub mod sky_sampling;
pub mod sun;
pub mod units;

/// Every light of a scene that is not a glowing polygon. Empty by default:
/// a scene lit only by emissive materials.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Lights {
    pub sun: Option<sun::Sun>,
    pub sky: Option<sky::Sky>,
    pub lamps: Vec<lamp::Lamp>,
    /// Openings the sky lights an interior through (`portal.rs`); they
    /// change how the sky is sampled, not what it gives.
    pub portals: Vec<portal::Portal>,
}

impl Lights {
    pub fn is_empty(&self) -> bool {
        self.sun.is_none() && self.sky.is_none() && self.lamps.is_empty()
    }

    /// The same lights with every lamp moved by `-offset` (the solver's
    /// recentred frame); the sun and the sky are directions and do not move.
    pub fn recentred(&self, offset: glam::DVec3) -> Lights {
        let mut lights = self.clone();
        for lamp in &mut lights.lamps {
            lamp.position -= offset;
        }
        for portal in &mut lights.portals {
            *portal = portal.moved(offset);
        }
        lights
    }

    /// One line per light and portal, for `solve` to print at import: what
    /// it is, where, and its strength (a lamp's power ∫ I dω in W per channel, the
    /// sun's and the sky's irradiance on a plane facing up; a portal's
    /// sides and area in scene units). Lamp and portal positions are
    /// printed plus `offset`: the scene's recentre offset gives them back
    /// in the input's own coordinates.
    pub fn describe(&self, offset: glam::DVec3) -> Vec<String> {
        let rgb = |v: glam::DVec3| format!("[{:.4}, {:.4}, {:.4}]", v.x, v.y, v.z);
        let mut lines = Vec::new();
        if let Some(sun) = &self.sun {
            let d = sun.direction();
            lines.push(format!(
                "sun toward [{:.3}, {:.3}, {:.3}], {} W/m² facing it, disc {}°",
                d.x,
                d.y,
                d.z,
                rgb(sun.irradiance()),
                sun.angular_diameter_deg()
            ));
        }
        if let Some(sky) = &self.sky {
            let kind = match sky.model() {
                sky::SkyModel::Uniform { .. } => "uniform",
                sky::SkyModel::CieOvercast { .. } => "CIE overcast",
                sky::SkyModel::Clear { .. } => "clear (Preetham)",
                sky::SkyModel::Map { .. } => "environment map",
            };
            lines.push(format!(
                "sky {kind}, {} W/m² on an open horizontal plane",
                rgb(sky.horizontal_irradiance())
            ));
        }
        for lamp in &self.lamps {
            let kind = match lamp.beam {
                lamp::Beam::Point => "point",
                lamp::Beam::Spot { .. } => "spot",
            };
            let p = lamp.position + offset;
            lines.push(format!(
                "lamp {} ({kind}{}) at [{:.3}, {:.3}, {:.3}], {} W",
                lamp.name,
                if lamp.profile.is_some() { ", IES" } else { "" },
                p.x,
                p.y,
                p.z,
                rgb(lamp.power())
            ));
        }
        for portal in &self.portals {
            let c = portal.centre() + offset;
            let k = portal.corners();
            let side = |i: usize| (k[(i + 1) % k.len()] - k[i]).length();
            let size = if k.len() == 4 {
                format!("{:.3} × {:.3}", side(0), side(1))
            } else {
                "a triangle".to_owned()
            };
            lines.push(format!(
                "portal ({}) at [{:.3}, {:.3}, {:.3}], {size}, area {:.4}",
                if portal.is_detected() {
                    "detected"
                } else {
                    "declared"
                },
                c.x,
                c.y,
                c.z,
                portal.area()
            ));
        }
        lines
    }
}
