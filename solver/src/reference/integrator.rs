//! The unbiased estimator of radiance: a path traced from the eye, with
//! next-event estimation on the emitters and BSDF sampling combined by
//! multiple importance sampling with the power heuristic (Veach 1997, §9.2),
//! and Russian roulette (unbiased) after a few bounces.
//!
//! Physics (the solver's): surfaces are one-sided. A ray that meets a polygon's
//! back face finds it black (no emission, no reflection), yet the polygon blocks
//! light from either side, as the solver's visibility rays do. Emitters are
//! Lambertian with radiance `emission` toward their front. A ray that leaves
//! the scene sees the sky and the sun's disc, if the scene has them; lamps
//! are points that no ray meets ([`super::lights`]).

use super::scene::RenderScene;
use crate::geometry::sampling::Rng;
use glam::DVec3;

/// Russian roulette starts after this many bounces (the first few carry most of
/// the image; killing them early only adds noise).
const ROULETTE_AFTER: u32 = 3;

/// A guard against a path that never ends (a closed scene of albedo exactly 1
/// survives roulette forever). Light after this many bounces is lost; with any
/// albedo below 1 it is below f64 rounding.
pub const MAX_BOUNCES: u32 = 100_000;

/// A ray's nearest hit, in f64.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceHit {
    pub polygon: usize,
    pub point: DVec3,
    /// Distance along the (unit) ray.
    pub distance: f64,
    /// Whether the ray met the front (the side the normal points to).
    pub front: bool,
}

/// The estimator: a scene and a bounce limit.
pub struct Integrator<'a> {
    pub scene: &'a RenderScene,
    /// Most bounces a path may take (`None`: unlimited, ended by roulette). 0
    /// gives emitted light only, 1 direct lighting.
    pub max_depth: Option<u32>,
}

/// The power heuristic (β = 2) weight of a strategy of density `a` against one
/// of density `b` (Veach 1997, §9.2.4).
#[inline]
pub(super) fn power_heuristic(a: f64, b: f64) -> f64 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 {
        a2 / (a2 + b2)
    } else {
        0.0
    }
}

impl Integrator<'_> {
    /// The nearest surface along the unit direction `dir` from `origin`, with the
    /// hit point recomputed in f64 on the polygon's plane. Hits nearer than the
    /// occluder's scene epsilon along the ray are skipped (`closest_hit`), so
    /// that a ray leaving a surface does not meet that surface again.
    pub fn intersect(&self, origin: DVec3, dir: DVec3) -> Option<SurfaceHit> {
        let hit = self
            .scene
            .occluder
            .closest_hit(origin, dir, f64::INFINITY)?;
        let s = &self.scene.surfaces[hit.polygon];
        let denom = s.normal.dot(dir);
        // The hit is refined in f64 on the plane of the triangle that was hit, not
        // on the polygon's Newell plane: on a slightly non-planar polygon the two
        // differ by more than the ray offset, and a point placed behind the real
        // surface would see that surface's back (a black band across the Cornell
        // box's red wall, found by the comparison with Mitsuba 3).
        let t = match self.scene.occluder.triangle_plane(hit.triangle) {
            Some((point, n)) if n.dot(dir) != 0.0 => {
                let exact = n.dot(point - origin) / n.dot(dir);
                // Keep the f32 answer if the plane's is far from it (a sliver
                // triangle whose normal is unreliable).
                let window = 1e-3 * hit.t.max(self.scene.occluder.scene_epsilon());
                if (exact - hit.t).abs() <= window {
                    exact
                } else {
                    hit.t
                }
            }
            _ => hit.t,
        };
        Some(SurfaceHit {
            polygon: hit.polygon,
            point: origin + dir * t,
            distance: t,
            front: denom < 0.0,
        })
    }

    /// One sample of the radiance arriving at `origin` from direction `-dir`
    /// (i.e. along the ray `origin + t · dir`, `dir` unit).
    pub fn radiance(&self, origin: DVec3, dir: DVec3, rng: &mut Rng) -> DVec3 {
        match self.intersect(origin, dir) {
            Some(hit) => self.path(hit, dir, rng),
            None => self.scene.lights.background(dir),
        }
    }

    /// One sample of the radiance leaving `point` on polygon `polygon` toward
    /// unit `wo` (above its front side): emission plus reflection.
    ///
    /// Rays leaving `point` skip hits nearer than the scene epsilon along
    /// them ([`Integrator::intersect`]), so a point within about that
    /// distance of another surface (a corner) does not see that surface's
    /// nearest band: probe a solver's vertex a millimetre into its element,
    /// not at its receiving point (docs/lab/glossy-edges-and-corners.md, "edges and corners").
    pub fn outgoing(&self, polygon: usize, point: DVec3, wo: DVec3, rng: &mut Rng) -> DVec3 {
        let hit = SurfaceHit {
            polygon,
            point,
            distance: 0.0,
            front: wo.dot(self.scene.surfaces[polygon].normal) > 0.0,
        };
        self.path(hit, -wo, rng)
    }

    fn path(&self, mut hit: SurfaceHit, mut dir: DVec3, rng: &mut Rng) -> DVec3 {
        let scene = self.scene;
        let max_depth = self.max_depth.unwrap_or(MAX_BOUNCES).min(MAX_BOUNCES);
        let mut radiance = DVec3::ZERO;
        let mut throughput = DVec3::ONE;
        // Density of the BSDF sample that found this hit; None for the eye ray.
        let mut bsdf_pdf: Option<f64> = None;
        let lights = &scene.lights;
        let mut depth = 0;
        loop {
            if !hit.front {
                break;
            }
            let surface = &scene.surfaces[hit.polygon];
            let bsdf = scene.bsdf_at(hit.polygon, hit.point);
            // Emission and one-sidedness follow the polygon; reflection its
            // shading normal (`shading.rs`), as the solver's receivers do.
            let geometric = surface.normal;
            let n = surface.shading_normal(hit.point);
            if bsdf.emission.max_element() > 0.0 {
                let weight = match bsdf_pdf {
                    None => 1.0,
                    Some(pdf_b) => {
                        let cos_l = -dir.dot(geometric);
                        let pdf_l =
                            scene.emitters.pdf_area(hit.polygon) * hit.distance * hit.distance
                                / cos_l;
                        power_heuristic(pdf_b, pdf_l)
                    }
                };
                radiance += throughput * bsdf.emission * weight;
            }
            if depth >= max_depth || !bsdf.reflects() {
                break;
            }
            let wo = -dir;
            radiance += throughput * self.direct_light(hit, wo, rng);
            if !lights.is_empty() {
                radiance += throughput * self.direct_lights(hit, wo, rng);
            }
            let Some(sample) = bsdf.sample(wo, n, rng) else {
                break;
            };
            // A direction above the shading horizon but below the polygon
            // enters the surface: the surface itself blocks it, as it blocks
            // the solver's rays there.
            if sample.wi.dot(geometric) <= 0.0 {
                break;
            }
            throughput *= sample.f * (sample.wi.dot(n) / sample.pdf);
            if depth >= ROULETTE_AFTER {
                let survive = throughput.max_element().min(1.0);
                if survive.is_nan() || survive <= 0.0 || rng.next_f64() >= survive {
                    break;
                }
                throughput /= survive;
            }
            let largest = throughput.max_element();
            if largest.is_nan() || largest <= 0.0 {
                break;
            }
            let Some(next) = self.intersect(hit.point, sample.wi) else {
                // The ray leaves the scene: the sky and the sun, weighted
                // against their next-event samples at this point.
                if !lights.is_empty() {
                    radiance += throughput * lights.escaped(sample.wi, sample.pdf, n);
                }
                break;
            };
            bsdf_pdf = Some(sample.pdf);
            dir = sample.wi;
            hit = next;
            depth += 1;
        }
        radiance
    }

    /// Next-event estimation at `hit` toward `wo`: one point on an emitter,
    /// weighted against BSDF sampling by the power heuristic.
    fn direct_light(&self, hit: SurfaceHit, wo: DVec3, rng: &mut Rng) -> DVec3 {
        let scene = self.scene;
        let (u0, u1, u2) = (rng.next_f64(), rng.next_f64(), rng.next_f64());
        let Some(light) = scene.emitters.sample(u0, u1, u2) else {
            return DVec3::ZERO;
        };
        let surface = &scene.surfaces[hit.polygon];
        let emitter = &scene.surfaces[light.polygon];
        let to_light = light.point - hit.point;
        let distance_sq = to_light.length_squared();
        if distance_sq.is_nan() || distance_sq <= 0.0 {
            return DVec3::ZERO;
        }
        let wi = to_light / distance_sq.sqrt();
        let n = surface.shading_normal(hit.point);
        let cos_i = wi.dot(n);
        let cos_l = -wi.dot(emitter.normal);
        if cos_i <= 0.0 || cos_l <= 0.0 || wi.dot(surface.normal) <= 0.0 {
            return DVec3::ZERO;
        }
        let bsdf = scene.bsdf_at(hit.polygon, hit.point);
        let f = bsdf.eval(wi, wo, n);
        let largest = f.max_element();
        if largest.is_nan() || largest <= 0.0 || !scene.occluder.visible(hit.point, light.point) {
            return DVec3::ZERO;
        }
        let pdf_l = light.pdf_area * distance_sq / cos_l;
        let weight = power_heuristic(pdf_l, bsdf.pdf(wi, wo, n));
        let le = scene.emission_at(light.polygon, light.point);
        f * le * (cos_i * weight / pdf_l)
    }

    /// Next-event estimation of the sun, the sky and the lamps at `hit`
    /// toward `wo`: one sample of each that the scene has (random numbers
    /// are drawn only for those, so a scene without them renders as before).
    fn direct_lights(&self, hit: SurfaceHit, wo: DVec3, rng: &mut Rng) -> DVec3 {
        let lights = &self.scene.lights;
        let surface = &self.scene.surfaces[hit.polygon];
        let n = surface.shading_normal(hit.point);
        let mut sum = DVec3::ZERO;
        if lights.has_sun() {
            let (u1, u2) = (rng.next_f64(), rng.next_f64());
            if let Some(s) = lights.sample_sun(u1, u2) {
                sum += self.light_sample(hit, wo, n, &s);
            }
        }
        if lights.has_sky() {
            let (u1, u2) = (rng.next_f64(), rng.next_f64());
            if let Some(s) = lights.sample_sky(n, u1, u2) {
                sum += self.light_sample(hit, wo, n, &s);
            }
        }
        if lights.has_lamps() {
            let (u0, u1, u2) = (rng.next_f64(), rng.next_f64(), rng.next_f64());
            if let Some(s) = lights.sample_lamp(hit.point, u0, u1, u2) {
                sum += self.light_sample(hit, wo, n, &s);
            }
        }
        sum
    }

    /// One light sample's contribution at `hit` (shading normal `n`) toward
    /// `wo`: f · cos θ_i · weight, times its MIS weight against BSDF
    /// sampling, if the shadow ray reaches the light.
    fn light_sample(
        &self,
        hit: SurfaceHit,
        wo: DVec3,
        n: DVec3,
        s: &super::lights::DirectSample,
    ) -> DVec3 {
        let scene = self.scene;
        let geometric = scene.surfaces[hit.polygon].normal;
        let cos_i = s.wi.dot(n);
        if cos_i <= 0.0 || s.wi.dot(geometric) <= 0.0 || s.weight.max_element() <= 0.0 {
            return DVec3::ZERO;
        }
        let bsdf = scene.bsdf_at(hit.polygon, hit.point);
        let f = bsdf.eval(s.wi, wo, n);
        let largest = f.max_element();
        if largest.is_nan() || largest <= 0.0 {
            return DVec3::ZERO;
        }
        let target = s
            .target
            .unwrap_or_else(|| scene.lights.beyond_the_scene(hit.point, s.wi));
        if !scene.occluder.visible(hit.point, target) {
            return DVec3::ZERO;
        }
        let weight = s
            .pdf
            .map_or(1.0, |pdf| power_heuristic(pdf, bsdf.pdf(s.wi, wo, n)));
        f * s.weight * (cos_i * weight)
    }
}
