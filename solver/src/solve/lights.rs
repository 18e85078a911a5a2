//! The lights' shot (issue 41): the sun, the sky and the lamps light every
//! receiving vertex directly, once, as the solve's first shot; the light
//! they reflect then propagates from the patches as an emitter's does.
//!
//! Each receiving point q with normal n and diffuse reflectance ρ gets
//! ΔL = ρ E(q) / π, with E the irradiance:
//!
//! - a lamp of intensity I(ω) at distance d (metres): E = I(ω) cos θ / d²,
//!   the inverse-square law, with visibility by one ray to a point lamp, or
//!   the visible fraction of `samples` stratified points on the disc a bulb
//!   of radius r shows the receiver (d clamped to r, `light/lamp.rs`);
//! - the sun: E = E⊥ ⟨cos θ_i V_i⟩ over `samples` stratified directions
//!   of its disc (`light/sun.rs`), V_i a ray to infinity;
//! - the sky: E = (π / N) Σ L(ω_i) V_i over N = [`SKY_RAYS_PER_SAMPLE`] ×
//!   `samples` cosine-distributed directions (Malley's method on stratified
//!   points), unbiased for any sky; exact for an open receiver under a
//!   uniform sky. With portals (`light/portal.rs`) half of the rays go
//!   through the portals the receiver faces, and for a sky with a bright
//!   spot half of the rest are drawn by its radiance from a table
//!   (`light/sky_sampling.rs`); all are combined by the balance heuristic.
//!
//! The lights' shot is recorded like an emitter's: vertices that later
//! splits create receive it exactly ([`super::refine::Replay::lights`]), so
//! shadow boundaries of the sun and the lamps refine as an area light's do.
//! Its visible count, for the meshing's noise allowance, is the visible
//! fraction of the light weighted by each light's share, out of `samples`.

use super::group_shot::Shooter;
use super::pipeline::{Shooting, Source, Transport};
use super::refine::{self, Criteria, Refined, DARK_FLOOR};
use super::shoot::{Received, ReceivingPoint, RecordedShot};
use super::{footprint, Solver};
use crate::geometry::sampling::{stratified_points, stratified_square, stream_id, Rng};
use crate::geometry::visibility::Occluder;
use crate::light::lamp::Lamp;
use crate::light::sky::Sky;
use crate::light::sky_sampling::SkyDistribution;
use crate::light::sun::Sun;
use crate::light::Lights;
use crate::mesh::Mesh;
use crate::settings::SolverSettings;
use glam::DVec3;
use std::f64::consts::PI;
use std::time::Instant;

/// How close geometry must enclose a lamp in every direction for
/// [`Solver::enclosed_lamp_warnings`] to warn: 10 cm, a bulb or a shade.
pub const ENCLOSED_WITHIN_M: f64 = 0.1;

/// Sky rays per receiver over the base `samples` (the sky spans a
/// hemisphere, an area light a small solid angle): 64 at draft, 256 at
/// medium, 1,024 at final.
pub const SKY_RAYS_PER_SAMPLE: u32 = 8;

/// The lights' state in a solve: the lights in the solver's frame, and
/// whether they have shot.
#[derive(Default)]
pub(super) struct LightsState {
    pub lights: Lights,
    pub shot: bool,
    /// The power the lights put into the scene's patches (π Σ ρE/π · A,
    /// scene units, summed over the channels): their part of the emitted
    /// power the solve converges against. Checkpointed.
    pub power: f64,
    /// The sky tabulated for sampling by its radiance, where that pays
    /// (`light/sky_sampling.rs`).
    pub sky_table: Option<SkyDistribution>,
}

impl LightsState {
    /// The lights (in the solver's frame), not yet shot.
    pub fn new(lights: Lights) -> Self {
        let sky_table = lights.sky.as_ref().and_then(SkyDistribution::worth_it);
        LightsState {
            lights,
            shot: false,
            power: 0.0,
            sky_table,
        }
    }

    /// Whether the lights still have to shoot.
    pub fn pending(&self) -> bool {
        !self.shot && !self.lights.is_empty()
    }
}

/// One evaluation of the lights at receivers: the lights, the occluder and
/// the reflectances, and the sampling.
pub(super) struct LightShot<'a> {
    pub lights: &'a Lights,
    pub sky_table: Option<&'a SkyDistribution>,
    pub occluder: &'a Occluder,
    pub kd: &'a [DVec3],
    /// Rays per lamp with a radius and per sun; the sky takes
    /// [`SKY_RAYS_PER_SAMPLE`] times as many.
    pub samples: u32,
    pub seed: u64,
    /// Scene units per metre, for the inverse-square law.
    pub units_per_metre: f64,
}

/// Where the lights' visible samples go ([`LightShot::visit`]): the unit
/// direction toward the light and the irradiance the sample brings.
pub(super) type Sink<'s> = &'s mut dyn FnMut(DVec3, DVec3);

/// What the lights bring to one receiving point: their irradiance, and the
/// visible count and the rays of [`Received`].
#[derive(Clone, Copy, Default)]
pub(super) struct Arrival {
    pub irradiance: DVec3,
    pub visible: u32,
    pub rays: u32,
}

/// One light's irradiance at a point and the fraction of it that arrived.
#[derive(Clone, Copy, Default)]
struct Part {
    irradiance: DVec3,
    /// The unoccluded irradiance's brightest channel, the light's weight in
    /// the visible count.
    weight: f64,
    visible: f64,
    rays: u32,
}

/// The RNG stream of the lights' shot (shot 0 in the shots' numbering is an
/// emitter's; the lights take a stream no patch shot uses).
const LIGHTS_STREAM: u64 = u64::MAX;

impl<'a> LightShot<'a> {
    pub fn new(
        state: &'a LightsState,
        occluder: &'a Occluder,
        kd: &'a [DVec3],
        settings: &SolverSettings,
        units_per_metre: f64,
    ) -> Self {
        LightShot {
            lights: &state.lights,
            sky_table: state.sky_table.as_ref(),
            occluder,
            kd,
            samples: settings.samples,
            seed: settings.seed,
            units_per_metre,
        }
    }

    /// The lights' replay for later shots: `None` before they shot (or
    /// without lights).
    pub fn replay(
        state: &'a LightsState,
        occluder: &'a Occluder,
        kd: &'a [DVec3],
        settings: &SolverSettings,
        units_per_metre: f64,
    ) -> Option<Self> {
        (state.shot && !state.lights.is_empty())
            .then(|| Self::new(state, occluder, kd, settings, units_per_metre))
    }

    /// ΔL at vertex `v`.
    pub fn receive(&self, mesh: &Mesh, v: u32) -> Received {
        let at = ReceivingPoint::of_vertex(mesh, v, self.occluder.scene_epsilon());
        self.receive_at(&at)
    }

    /// ΔL at a receiving point: ρ E / π summed over the lights.
    pub fn receive_at(&self, at: &ReceivingPoint) -> Received {
        let kd = self.kd[at.surface as usize];
        if kd == DVec3::ZERO {
            return Received::default();
        }
        let arrival = self.visit(at, 0, &mut |_, _| {});
        Received {
            radiance: kd * arrival.irradiance / PI,
            visible: arrival.visible,
            rays: arrival.rays,
        }
    }

    /// The lights at a receiving point: each visible sample goes to `sink`
    /// as the unit direction toward its light and the irradiance it brings
    /// (a glossy receiver reflects each by its lobe,
    /// `directional/lights.rs`); returns their sum, and the visible count
    /// and the rays for the meshing. The sky takes at least `sky_rays`
    /// (a glossy receiver estimates a coefficient per SH function from
    /// them, `directional/lights.rs`).
    pub fn visit(&self, at: &ReceivingPoint, sky_rays: u32, sink: Sink) -> Arrival {
        let mut rng = Rng::new(self.seed, stream_id(LIGHTS_STREAM, at.stream as u64));
        let origin = at.q + at.n * self.occluder.scene_epsilon();
        let mut parts: Vec<Part> = self
            .lights
            .lamps
            .iter()
            .map(|lamp| self.lamp(lamp, origin, at.n, &mut rng, &mut *sink))
            .collect();
        if let Some(sun) = &self.lights.sun {
            parts.push(self.sun(sun, origin, at.n, &mut rng, &mut *sink));
        }
        if let Some(sky) = &self.lights.sky {
            let count = sky_rays.max(self.samples * SKY_RAYS_PER_SAMPLE);
            parts.push(self.sky(sky, origin, at.n, count, &mut rng, sink));
        }
        let irradiance: DVec3 = parts.iter().map(|p| p.irradiance).sum();
        let weight: f64 = parts.iter().map(|p| p.weight).sum();
        let seen: f64 = parts.iter().map(|p| p.weight * p.visible).sum();
        let fraction = if weight > 0.0 { seen / weight } else { 0.0 };
        Arrival {
            irradiance,
            visible: (fraction * self.samples as f64).round() as u32,
            rays: parts.iter().map(|p| p.rays).sum(),
        }
    }

    /// A lamp's irradiance at `origin` (lifted off its surface) facing `n`.
    fn lamp(&self, lamp: &Lamp, origin: DVec3, n: DVec3, rng: &mut Rng, sink: Sink) -> Part {
        let to_lamp = lamp.position - origin;
        let distance = to_lamp.length();
        let w = to_lamp / distance;
        let cos = w.dot(n);
        if cos.is_nan() || cos <= 0.0 {
            return Part::default();
        }
        let metres = (distance.max(lamp.radius) / self.units_per_metre).max(f64::MIN_POSITIVE);
        let unoccluded = lamp.intensity_toward(-w) * cos / (metres * metres);
        if unoccluded == DVec3::ZERO {
            return Part::default();
        }
        let (visible, rays) = if lamp.radius > 0.0 {
            // Points on the disc the bulb shows the receiver.
            let (t, b) = w.any_orthonormal_pair();
            let mut seen = 0u32;
            let share = unoccluded / self.samples as f64;
            stratified_square(self.samples, rng, |u, v| {
                let (r, phi) = (lamp.radius * u.sqrt(), 2.0 * PI * v);
                let point = lamp.position + r * (phi.cos() * t + phi.sin() * b);
                if self.occluder.visible(origin, point) {
                    seen += 1;
                    sink((point - origin).normalize_or(w), share);
                }
            });
            (seen as f64 / self.samples as f64, self.samples)
        } else if self.occluder.visible(origin, lamp.position) {
            sink(w, unoccluded);
            (1.0, 1)
        } else {
            (0.0, 1)
        };
        Part {
            irradiance: unoccluded * visible,
            weight: unoccluded.max_element(),
            visible,
            rays,
        }
    }

    /// The sun's irradiance: E⊥ times the mean of cos θ_i over its visible
    /// disc directions.
    fn sun(&self, sun: &Sun, origin: DVec3, n: DVec3, rng: &mut Rng, sink: Sink) -> Part {
        if sun.direction().dot(n) <= -(0.5 * sun.angular_diameter_deg()).to_radians().sin() {
            return Part::default();
        }
        let far = self.far(origin);
        let (mut lit, mut open) = (0.0, 0.0);
        let mut rays = 0;
        let count = self.samples as f64;
        stratified_square(self.samples, rng, |u, v| {
            let w = sun.sample_disc(u, v).direction;
            let cos = w.dot(n);
            if cos > 0.0 {
                open += cos;
                rays += 1;
                if self.occluder.visible(origin, origin + w * far) {
                    lit += cos;
                    sink(w, sun.irradiance() * (cos / count));
                }
            }
        });
        Part {
            irradiance: sun.irradiance() * (lit / count),
            weight: sun.irradiance().max_element() * open / count,
            visible: if open > 0.0 { lit / open } else { 0.0 },
            rays,
        }
    }

    /// The sky's irradiance: cosine-distributed directions about `n`, and
    /// with portals, points drawn on the portals the receiver faces, the
    /// two combined by Veach's (1997, §9.2) multi-sample balance heuristic:
    /// each direction ω counts f(ω) / Σ_j n_j p_j(ω), with f = L cos θ V and
    /// n_j samples from density p_j (`light/portal.rs`).
    fn sky(
        &self,
        sky: &Sky,
        origin: DVec3,
        n: DVec3,
        count: u32,
        rng: &mut Rng,
        sink: Sink,
    ) -> Part {
        let far = self.far(origin);
        let portals = self.portal_shares(origin, n, count / 2);
        let rest = count - portals.iter().map(|&(_, k)| k).sum::<u32>();
        let tabled = if self.sky_table.is_some() {
            rest / 2
        } else {
            0
        };
        let cosine = rest - tabled;
        // The balance heuristic's denominator at unit direction w.
        let density = |w: DVec3| {
            let cos = w.dot(n).max(0.0);
            cosine as f64 * cos / PI
                + self.sky_table.map_or(0.0, |t| tabled as f64 * t.pdf(w))
                + portals
                    .iter()
                    .map(|&(p, k)| k as f64 * self.lights.portals[p].direction_pdf(origin, w))
                    .sum::<f64>()
        };
        let (mut lit, mut open) = (DVec3::ZERO, DVec3::ZERO);
        let mut rays = 0;
        let mut add = |w: DVec3| {
            let cos = w.dot(n);
            let radiance = sky.radiance(w);
            if cos <= 0.0 || radiance == DVec3::ZERO {
                return;
            }
            let f = radiance * cos / density(w);
            open += f;
            rays += 1;
            if self.occluder.visible(origin, origin + w * far) {
                lit += f;
                sink(w, f);
            }
        };
        let (t, b) = n.any_orthonormal_pair();
        stratified_square(cosine, rng, |u, v| {
            // Malley's method: a uniform point on the disc lifted to the
            // hemisphere has density cos θ / π.
            let (r, phi) = (u.sqrt(), 2.0 * PI * v);
            add(r * (phi.cos() * t + phi.sin() * b) + (1.0 - u).max(0.0).sqrt() * n);
        });
        if let Some(table) = self.sky_table {
            stratified_square(tabled, rng, |u, v| add(table.sample(u, v).0));
        }
        let mut points = Vec::new();
        for &(p, k) in &portals {
            points.clear();
            stratified_points(self.lights.portals[p].corners(), k, rng, &mut points);
            for q in &points {
                add((*q - origin).normalize());
            }
        }
        let weight = open.max_element();
        Part {
            irradiance: lit,
            weight,
            visible: if weight > 0.0 {
                lit.max_element() / weight
            } else {
                0.0
            },
            rays,
        }
    }

    /// How `total` portal samples are shared among the portals in front of
    /// the receiver at `origin` facing `n`: by each one's approximate solid
    /// angle times the cosine toward it, at least one each; none without
    /// portals in front.
    fn portal_shares(&self, origin: DVec3, n: DVec3, total: u32) -> Vec<(usize, u32)> {
        let weights: Vec<(usize, f64)> = self
            .lights
            .portals
            .iter()
            .enumerate()
            .filter_map(|(i, p)| {
                let cos = (p.centre() - origin).normalize_or_zero().dot(n);
                let w = p.approximate_solid_angle(origin) * cos;
                (w > 0.0).then_some((i, w))
            })
            .collect();
        let sum: f64 = weights.iter().map(|&(_, w)| w).sum();
        weights
            .into_iter()
            .map(|(i, w)| (i, ((total as f64 * w / sum).round() as u32).max(1)))
            .collect()
    }

    /// A distance from `origin` past every surface: twice the scene's
    /// diagonal (the occluder's epsilon is 1e-5 of it) beyond the origin's
    /// own distance from the centre.
    fn far(&self, origin: DVec3) -> f64 {
        2e5 * self.occluder.scene_epsilon() + origin.length()
    }
}

/// The lights' shot as a [`Transport`]: every vertex receives the lights,
/// the mesh refines at their shadows, and the reflected light is gathered
/// into the patches, which then shoot it on.
pub(super) struct LightsTransport;

impl Transport for LightsTransport {
    fn take_source(&mut self, s: &mut Solver) -> Source {
        s.lights.shot = true;
        Source {
            patch: None,
            ambient: s.ambient_from_index(),
            unshot: DVec3::ZERO,
        }
    }

    fn shoot(&mut self, s: &mut Solver, source: &Source) -> Shooting {
        let lights = std::mem::take(&mut s.lights);
        let upm = s.units_per_metre();
        let shot = LightShot::new(&lights, &s.occluder, &s.materials.kd, &s.settings, upm);
        let shooter = Shooter::Lights(&shot);
        let rays = footprint::shoot_receivers(
            &s.mesh,
            &mut s.sharing.footprint,
            footprint::SampleSharing {
                small: &s.sharing.small,
                twins: &s.sharing.twins,
                sites: &s.sharing.sites,
            },
            s.field.state(),
            &shooter,
            true,
        );
        let shot_done = Instant::now();
        // The level of the light the lights put in, before refinement adds
        // to it: this shot's dark floor and the ambient it is heading for.
        // (The gather measures their power exactly, `unshot_power`.)
        let level = s.lights_level(s.received_power());
        let ambient = source.ambient + DVec3::splat(level);
        let floor = s.stats.radiance_level.max(level);
        let criteria = Criteria {
            dark_floor: DARK_FLOOR * floor,
            ..s.refine_criteria(ambient)
        };
        let mut refined = Refined::default();
        if s.refines() {
            // New vertices receive the lights and every recorded shot
            // exactly (`refine.rs`).
            let mut split_budget = s.split_budget(None);
            let replay_shots = RecordedShot::rebuild_all(
                &s.record.shots,
                &s.mesh,
                &s.settings,
                &s.occluder,
                &s.materials.kd,
            );
            let scan = s.touched_patches();
            let replay_groups = s
                .record
                .group_replays(&s.settings, &s.occluder, &s.materials.kd);
            let replay = refine::Replay {
                recorded: &replay_shots,
                pools: &s.record.pools,
                groups: &replay_groups,
                lights: Some(&shot),
                current_recorded: true,
            };
            refined = refine::refine_field(
                &mut s.mesh,
                &mut refine::DiffuseField {
                    state: s.field.state(),
                    replay: &replay,
                    shooter: &shooter,
                    scan: scan.as_deref(),
                },
                &criteria,
                &mut split_budget,
            );
            drop(replay_shots);
            s.after_refinement(&split_budget, None);
        }
        s.lights = lights;
        Shooting {
            rays: rays + refined.rays,
            refined,
            shot_done,
        }
    }

    fn gather(&mut self, s: &mut Solver, _source: &Source, dirty: &[u32]) {
        s.unshot_changed(dirty);
        s.gather();
    }

    /// The unshot power once gathered. What the lights added to it is
    /// their power: it joins the emitted power the solve converges against.
    fn unshot_power(&mut self, s: &mut Solver) -> f64 {
        let total = s.unshot_power_from_index();
        s.measure_lights_power(total)
    }
}

impl Solver {
    /// The scene's sun, sky and lamps in the solver's (and the solution's)
    /// frame: lamps moved by [`Solver::offset`].
    pub fn lights(&self) -> &Lights {
        &self.lights.lights
    }

    /// A warning for each lamp that geometry encloses within
    /// [`ENCLOSED_WITHIN_M`] (or twice its radius) in every one of 26
    /// directions, as a bulb or a closed shade modelled around it does: its
    /// light cannot get out, and the scene stays dark around it.
    pub(super) fn enclosed_lamp_warnings(&self) -> Vec<String> {
        let dirs: Vec<DVec3> = (-1..=1)
            .flat_map(|x| (-1..=1).flat_map(move |y| (-1..=1).map(move |z| (x, y, z))))
            .filter(|&d| d != (0, 0, 0))
            .map(|(x, y, z)| DVec3::new(x as f64, y as f64, z as f64).normalize())
            .collect();
        let upm = self.units_per_metre();
        self.lights
            .lights
            .lamps
            .iter()
            .filter(|lamp| {
                let reach = (ENCLOSED_WITHIN_M * upm).max(2.0 * lamp.radius);
                dirs.iter().all(|d| {
                    !self
                        .occluder
                        .visible(lamp.position, lamp.position + *d * reach)
                })
            })
            .map(|lamp| {
                format!(
                    "lamp {} is enclosed by geometry within {ENCLOSED_WITHIN_M} m in every \
                     direction (a bulb or shade mesh around it?): its light cannot get out; \
                     move it, or remove the mesh that encloses it",
                    lamp.name
                )
            })
            .collect()
    }

    /// π Σ_v w_v ρE_v/π over the patches' gather weights, summed over the
    /// channels: the power the current shot's `received` puts into the
    /// patches once gathered (`footprint.rs`, the gather).
    pub(super) fn received_power(&self) -> f64 {
        let mut power = DVec3::ZERO;
        for weights in &self.patches.weights {
            for &(v, w) in weights {
                power += self.field.received[v as usize] * w;
            }
        }
        PI * power.element_sum()
    }

    /// The lights' power, measured once their shot is gathered: what they
    /// added to the unshot power, which is now `total` (returned).
    pub(super) fn measure_lights_power(&mut self, total: f64) -> f64 {
        self.lights.power = (total - self.stats.unshot_power).max(0.0);
        self.include_lights_power();
        total
    }

    /// Adds the lights' power to the emitted power the solve converges
    /// against, and raises the scene's radiance level (the meshing's dark
    /// floor) to the lights', as their shot did (on resume).
    pub(super) fn include_lights_power(&mut self) {
        self.stats.emitted_power += self.lights.power;
        let level = self.lights_level(self.lights.power);
        self.stats.radiance_level = self.stats.radiance_level.max(level);
    }

    /// Cohen et al.'s (1988) ambient radiance of the lights' `power`, as
    /// [`Solver::ambient`] has it for unshot light: power / (π · area),
    /// over 1 − the mean reflectance (its brightest channel), the channels'
    /// mean.
    pub(super) fn lights_level(&self, power: f64) -> f64 {
        let (mut area, mut reflect) = (0.0, DVec3::ZERO);
        for p in &self.mesh.patches {
            area += p.area;
            reflect += self.materials.albedo[p.surface as usize] * p.area;
        }
        if area.is_nan() || area <= 0.0 {
            return 0.0;
        }
        let r = (DVec3::ONE - reflect / area)
            .max(DVec3::splat(1e-6))
            .recip();
        r.max_element() * power / (3.0 * PI * area)
    }
}
