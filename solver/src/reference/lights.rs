//! The lights that are not polygons (issue 41, `crate::light`) as the path
//! tracer sees them: the sun, the sky and the lamps, in the render's
//! re-centred frame.
//!
//! What a ray sees and how each light is sampled for next-event estimation:
//!
//! * **The sky** is what a ray that leaves the scene sees ([`Sky::radiance`],
//!   with its below-horizon rule). Next-event estimation draws a
//!   cosine-distributed direction about the shading normal (Malley's method,
//!   as the solver's sky shot); a BSDF-sampled ray that escapes also finds
//!   it. The two are combined by multiple importance sampling with the power
//!   heuristic (Veach 1997, §9.2), so neither double counts: for a purely
//!   diffuse surface the densities are equal and each strategy carries half.
//! * **The sun** is its disc of uniform radiance E⊥ / Ω
//!   ([`Sun::disc_radiance`]), seen by escaping rays inside the disc's cone
//!   and sampled uniformly over that cone ([`Sun::sample_disc`], density
//!   1 / Ω); combined with BSDF sampling by the same heuristic.
//! * **A lamp** is a point of intensity I(ω) ([`Lamp::intensity_toward`]:
//!   spot cone and IES profile included), invisible to every ray. Next-event
//!   estimation picks one lamp with probability proportional to its power
//!   and gives the irradiance E = I(ω) cos θ / max(d², r²), d the distance to
//!   its centre in metres (scene units over `units_per_metre`), r its radius:
//!   exactly the solver's (`solve/lights.rs`). A point lamp's shadow ray goes
//!   to its centre; a bulb of radius r > 0 sends it to a point drawn
//!   uniformly on the disc of radius r that faces the shading point, whose
//!   visible fraction the solver estimates too: soft shadows. Delta lights
//!   have no BSDF strategy, hence no MIS weight.

use super::integrator::power_heuristic;
use crate::light::lamp::Lamp;
use crate::light::sky::Sky;
use crate::light::sun::Sun;
use crate::light::Lights;
use glam::DVec3;
use std::f64::consts::PI;

/// One light sample for next-event estimation.
#[derive(Clone, Copy, Debug)]
pub struct DirectSample {
    /// Unit direction from the shading point toward the light.
    pub wi: DVec3,
    /// Where the shadow ray ends: a point (a lamp), or `None` for a light at
    /// infinity (the sun, the sky), whose shadow ray must escape the scene
    /// ([`SceneLights::beyond_the_scene`]).
    pub target: Option<DVec3>,
    /// The incident radiance over the sample's density (W·sr⁻¹·m⁻² · sr), or
    /// for a lamp its irradiance on a plane facing it over the selection
    /// probability (W·m⁻²): what multiplies f · cos θ_i.
    pub weight: DVec3,
    /// The density per steradian for MIS against BSDF sampling; `None` for
    /// a delta light, which BSDF sampling never finds.
    pub pdf: Option<f64>,
}

/// The sun, the sky and the lamps of a render, with the lamp selection
/// distribution.
#[derive(Clone, Debug, Default)]
pub struct SceneLights {
    sun: Option<Sun>,
    sky: Option<Sky>,
    lamps: Vec<Lamp>,
    /// Cumulative lamp selection weights (the channel sum of each lamp's
    /// power), ending at the total.
    lamp_cumulative: Vec<f64>,
    /// Scene units per metre: lamp distances are divided by it.
    units_per_metre: f64,
    /// The centre and the diagonal of the scene's bounding box: a shadow
    /// ray toward the sun or the sky ends past every surface.
    centre: DVec3,
    diagonal: f64,
}

impl SceneLights {
    /// `lights` (in the polygons' frame, as `Scene::lights`), with
    /// distances in scene units of which `units_per_metre` make a metre, for
    /// a scene whose surfaces span `bounds`. Lamps of zero power are never
    /// sampled.
    pub fn new(lights: &Lights, units_per_metre: f64, bounds: (DVec3, DVec3)) -> SceneLights {
        let lights = lights.clone();
        let mut lamps = Vec::new();
        let mut lamp_cumulative = Vec::new();
        let mut total = 0.0;
        for lamp in lights.lamps {
            let power = lamp.power().element_sum();
            if power > 0.0 && power.is_finite() {
                total += power;
                lamp_cumulative.push(total);
                lamps.push(lamp);
            }
        }
        SceneLights {
            sun: lights.sun,
            sky: lights.sky,
            lamps,
            lamp_cumulative,
            units_per_metre,
            centre: 0.5 * (bounds.0 + bounds.1),
            diagonal: (bounds.1 - bounds.0).length(),
        }
    }

    /// Where a shadow ray from `x` along unit `wi` toward a light at
    /// infinity ends: past every surface, since any surface point is within
    /// half the diagonal of the box's centre. A segment test there is the
    /// any-hit query, cheaper than finding the nearest hit.
    pub fn beyond_the_scene(&self, x: DVec3, wi: DVec3) -> DVec3 {
        x + wi * ((x - self.centre).length() + self.diagonal)
    }

    /// Whether there is no sun, no sky and no lamp to sample.
    pub fn is_empty(&self) -> bool {
        self.sun.is_none() && self.sky.is_none() && self.lamps.is_empty()
    }

    /// The radiance a camera ray that leaves the scene along unit `dir` sees:
    /// the sky, plus the sun's disc where `dir` lies in it.
    pub fn background(&self, dir: DVec3) -> DVec3 {
        let sky = self.sky.as_ref().map_or(DVec3::ZERO, |s| s.radiance(dir));
        let sun = match &self.sun {
            Some(sun) if sun.disc_contains(dir) => sun.disc_radiance(),
            _ => DVec3::ZERO,
        };
        sky + sun
    }

    /// The radiance a BSDF-sampled ray that leaves the scene along unit `dir`
    /// brings, weighted against next-event estimation: `bsdf_pdf` is the
    /// density the BSDF drew `dir` with, `n` the shading normal at the point
    /// it left (the sky's sampling density is about it).
    pub fn escaped(&self, dir: DVec3, bsdf_pdf: f64, n: DVec3) -> DVec3 {
        let sky = self.sky.as_ref().map_or(DVec3::ZERO, |s| {
            let pdf_sky = sky_pdf(dir, n);
            s.radiance(dir) * power_heuristic(bsdf_pdf, pdf_sky)
        });
        let sun = match &self.sun {
            Some(sun) if sun.disc_contains(dir) => {
                sun.disc_radiance() * power_heuristic(bsdf_pdf, 1.0 / sun.solid_angle())
            }
            _ => DVec3::ZERO,
        };
        sky + sun
    }

    pub fn has_sun(&self) -> bool {
        self.sun.is_some()
    }

    pub fn has_sky(&self) -> bool {
        self.sky.is_some()
    }

    pub fn has_lamps(&self) -> bool {
        !self.lamps.is_empty()
    }

    /// A direction in the sun's disc from two uniforms; `None` without a sun.
    pub fn sample_sun(&self, u1: f64, u2: f64) -> Option<DirectSample> {
        let sun = self.sun.as_ref()?;
        let s = sun.sample_disc(u1, u2);
        Some(DirectSample {
            wi: s.direction,
            target: None,
            weight: sun.disc_radiance() / s.pdf,
            pdf: Some(s.pdf),
        })
    }

    /// A cosine-distributed direction about the shading normal `n` from two
    /// uniforms, with the sky's radiance there; `None` without a sky.
    pub fn sample_sky(&self, n: DVec3, u1: f64, u2: f64) -> Option<DirectSample> {
        let sky = self.sky.as_ref()?;
        let wi = super::bsdf::cosine_hemisphere(n, u1, u2);
        let pdf = sky_pdf(wi, n);
        (pdf > 0.0).then(|| DirectSample {
            wi,
            target: None,
            weight: sky.radiance(wi) / pdf,
            pdf: Some(pdf),
        })
    }

    /// One lamp, picked by power with `u0`, seen from `x`: its irradiance on
    /// a plane facing it over the selection probability, and a shadow-ray
    /// end on its bulb from `u1`, `u2`. `None` without lamps, or when `x` is
    /// at the lamp's centre.
    pub fn sample_lamp(&self, x: DVec3, u0: f64, u1: f64, u2: f64) -> Option<DirectSample> {
        let total = *self.lamp_cumulative.last()?;
        let i = self
            .lamp_cumulative
            .partition_point(|&c| c <= u0 * total)
            .min(self.lamps.len() - 1);
        let lo = if i > 0 {
            self.lamp_cumulative[i - 1]
        } else {
            0.0
        };
        let selection = (self.lamp_cumulative[i] - lo) / total;
        let lamp = &self.lamps[i];
        let to_lamp = lamp.position - x;
        let distance = to_lamp.length();
        if !(distance > 0.0 && distance.is_finite()) {
            return None;
        }
        let wi = to_lamp / distance;
        let metres = distance.max(lamp.radius) / self.units_per_metre;
        let irradiance = lamp.intensity_toward(-wi) / (metres * metres);
        let target = if lamp.radius > 0.0 {
            // Uniform on the disc of radius r facing x (√u for the radius).
            let (t, b) = wi.any_orthonormal_pair();
            let (r, (s, c)) = (lamp.radius * u1.sqrt(), (2.0 * PI * u2).sin_cos());
            lamp.position + r * (c * t + s * b)
        } else {
            lamp.position
        };
        Some(DirectSample {
            wi,
            target: Some(target),
            weight: irradiance / selection,
            pdf: None,
        })
    }
}

/// The sky's next-event density at unit `wi` about the shading normal `n`:
/// the cosine hemisphere's, cos θ / π.
fn sky_pdf(wi: DVec3, n: DVec3) -> f64 {
    wi.dot(n).max(0.0) / PI
}
