//! A scene material as the reference path tracer reflects it: Lambertian Kd
//! plus, in directional mode, Ks times the exact glossy lobe ([`ExactLobe`]);
//! in diffuse mode Kd with Ks folded in, as the solver does
//! (`scene::Material::diffuse_equivalent_kd`, applied by `RenderScene::new`);
//! one-sided (nothing is reflected or emitted below the surface).
//!
//! Sampling is a one-sample mixture of the cosine-weighted hemisphere (for Kd)
//! and the lobe sampler (for Ks), chosen with probabilities proportional to the
//! mean of Kd and of Ks over the channels; [`Bsdf::pdf`] is the mixture's
//! density, which multiple importance sampling needs (Veach 1997, §9.2).

use super::lobe::ExactLobe;
use crate::geometry::sampling::Rng;
use glam::DVec3;
use std::f64::consts::PI;
use std::sync::Arc;

/// One material's reflection and emission.
#[derive(Clone, Debug)]
pub struct Bsdf {
    pub kd: DVec3,
    /// Glossy reflectance; zero in diffuse mode (Ks is folded into Kd there, as by the solver).
    pub ks: DVec3,
    pub lobe: Option<Arc<ExactLobe>>,
    /// Emitted radiance toward the front side.
    pub emission: DVec3,
    /// Probability of sampling the lobe rather than the cosine hemisphere.
    glossy_probability: f64,
}

/// A sampled incident direction with `f(ω_i, ω_o)` and the mixture density.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    pub wi: DVec3,
    pub f: DVec3,
    pub pdf: f64,
}

impl Bsdf {
    pub fn new(kd: DVec3, ks: DVec3, lobe: Option<Arc<ExactLobe>>, emission: DVec3) -> Bsdf {
        let ks = if lobe.is_some() { ks } else { DVec3::ZERO };
        let (d, g) = (kd.element_sum(), ks.element_sum());
        let glossy_probability = if d + g > 0.0 { g / (d + g) } else { 0.0 };
        Bsdf {
            kd,
            ks,
            lobe,
            emission,
            glossy_probability,
        }
    }

    /// The same material with diffuse reflectance `kd` (a textured point's
    /// Kd ⊙ ρ(uv)).
    pub fn with_kd(&self, kd: DVec3) -> Bsdf {
        Bsdf::new(kd, self.ks, self.lobe.clone(), self.emission)
    }

    /// Whether the material reflects anything.
    pub fn reflects(&self) -> bool {
        self.kd.max_element() > 0.0 || self.ks.max_element() > 0.0
    }

    /// `f(ω_i, ω_o)` for unit directions, ω_i toward the light and ω_o toward the
    /// eye; zero unless both are above the surface of normal `n`.
    pub fn eval(&self, wi: DVec3, wo: DVec3, n: DVec3) -> DVec3 {
        if wi.dot(n) <= 0.0 || wo.dot(n) <= 0.0 {
            return DVec3::ZERO;
        }
        let mut f = self.kd / PI;
        if let Some(lobe) = &self.lobe {
            if self.ks.max_element() > 0.0 {
                f += self.ks * lobe.eval(wi, wo, n);
            }
        }
        f
    }

    /// Density per steradian with which [`Bsdf::sample`] picks `wi` given `wo`.
    pub fn pdf(&self, wi: DVec3, wo: DVec3, n: DVec3) -> f64 {
        let cos = wi.dot(n);
        let diffuse = if cos > 0.0 { cos / PI } else { 0.0 };
        let glossy = match &self.lobe {
            Some(lobe) if self.glossy_probability > 0.0 => lobe.pdf(wi, wo, n),
            _ => 0.0,
        };
        (1.0 - self.glossy_probability) * diffuse + self.glossy_probability * glossy
    }

    /// Samples an incident direction for outgoing `wo`; `None` when the material
    /// reflects nothing or the sample falls below the surface (absorbed).
    pub fn sample(&self, wo: DVec3, n: DVec3, rng: &mut Rng) -> Option<BsdfSample> {
        if !self.reflects() {
            return None;
        }
        let (pick, u1, u2) = (rng.next_f64(), rng.next_f64(), rng.next_f64());
        let wi = match &self.lobe {
            Some(lobe) if pick < self.glossy_probability => lobe.sample(wo, n, u1, u2),
            _ => cosine_hemisphere(n, u1, u2),
        };
        if wi.dot(n) <= 0.0 {
            return None;
        }
        let pdf = self.pdf(wi, wo, n);
        (pdf > 0.0).then(|| BsdfSample {
            wi,
            f: self.eval(wi, wo, n),
            pdf,
        })
    }
}

/// A cosine-distributed direction about unit `n` (Malley's method: a uniform
/// point on the unit disc lifted to the hemisphere), density `cos θ / π`.
pub fn cosine_hemisphere(n: DVec3, u1: f64, u2: f64) -> DVec3 {
    let r = u1.sqrt();
    let (s, c) = (2.0 * PI * u2).sin_cos();
    let (t, b) = n.any_orthonormal_pair();
    let z = (1.0 - u1).max(0.0).sqrt();
    (t * (r * c) + b * (r * s) + n * z).normalize()
}
