//! The lights' shot in directional mode (issue 41): the sun, the sky and the
//! lamps light every vertex's SH, so a polished floor shows the sun's
//! highlight and glossy surfaces reflect the sky.
//!
//! Each visible light sample arriving from ω_i with irradiance ΔE_i
//! ([`LightShot::visit`], the same samples, rays and random streams as the
//! diffuse solve's lights) is reflected as a patch's sample is
//! ([`Reflector::add`]): Kd·ΔE_i/π as c₀₀, and Ks·ΔE_i·C_R(μ_i) times the
//! lobe about the mirror of ω_i. The sky's samples are cosine-, portal- and
//! radiance-distributed (`solve/lights.rs`); their sum over a glossy lobe is
//! the Monte Carlo estimate of ∫ f_s L cos θ dω, unbiased like the
//! irradiance, and band-limited by the lobe's order.
//!
//! A glossy receiver estimates (L+1)² coefficients per channel from the
//! sky's samples, so it takes at least [`SKY_RAYS_PER_COEFFICIENT`] per
//! coefficient. Measured on an open floor under a uniform sky, seen from
//! 30–90° above it: α = 0.1 (L = 21) reflects it with a per-vertex noise
//! of 17–29% from draft's 64 rays, 5–12% from 256 and 1.3–2.7% from 1,024
//! (stratified, it falls about as 1/N); with the rule, draft's 968 rays
//! give 1.3–2.5%.
//!
//! The shot is recorded like an emitter's: its coefficients join each
//! vertex's `direct` part, and vertices created later receive it exactly,
//! first of the replayed shots ([`DirSource::Lights`]).

use super::field::{DirField, SolverParts};
use super::group::DirGroup;
use super::receive::{
    receive_arrivals, DirScratch, DirShot, ReceivedSh, Receiving, Reflector, Tables,
};
use super::shot::{finish_shot, receive_all};
use super::Directional;
use crate::mesh::Mesh;
use crate::solve::lights::LightShot;
use crate::solve::pipeline::{Shooting, Source, Transport};
use crate::solve::refine::{self, Criteria, Refined, DARK_FLOOR};
use crate::solve::Solver;
use glam::DVec3;
use std::time::Instant;

/// Sky rays per SH coefficient, at least, for a glossy receiver.
pub(in crate::solve) const SKY_RAYS_PER_COEFFICIENT: u32 = 2;

/// The lights evaluated into a receiving vertex's SH.
pub(in crate::solve) struct DirLights<'a> {
    pub(super) lights: &'a LightShot<'a>,
    pub(super) tables: &'a Tables,
}

impl DirLights<'_> {
    /// What `who` receives of the lights, as SH coefficients of its
    /// surface's order, into `out`, its slot, which it overwrites; the
    /// visible samples and the rays traced.
    pub(super) fn receive_into(
        &self,
        mesh: &Mesh,
        kd: &[DVec3],
        who: Receiving,
        scratch: &mut DirScratch,
        out: &mut [f64],
    ) -> (u32, u32) {
        let epsilon = self.lights.occluder.scene_epsilon();
        let lobe = &mut scratch.lobe;
        receive_arrivals(
            mesh,
            self.tables,
            kd,
            who,
            epsilon,
            out,
            lobe,
            |at, reflector, sink| {
                let arrival = self.lights.visit(at, reflector.sky_rays(), sink);
                (arrival.visible, arrival.rays)
            },
        )
    }
}

/// What a vertex receives in directional mode: a patch's shot, or the
/// lights'.
pub(in crate::solve) enum DirSource<'a> {
    Patch(DirShot<'a>),
    /// A group of patches (`directional/group.rs`).
    Group(DirGroup<'a>),
    Lights(DirLights<'a>),
}

impl DirSource<'_> {
    /// ΔL of vertex `v` as SH coefficients of its surface's order.
    pub(super) fn receive(
        &self,
        mesh: &Mesh,
        kd: &[DVec3],
        v: u32,
        scratch: &mut DirScratch,
    ) -> ReceivedSh {
        let mut coefficients = Reflector::of_vertex(mesh, self.tables(), kd, v).zeroed();
        let (visible, rays) = self.receive_into(mesh, kd, v, scratch, &mut coefficients);
        ReceivedSh {
            coefficients,
            visible,
            rays,
        }
    }

    /// [`Self::receive`] into `out`, the vertex's slot, which it overwrites;
    /// the visible samples and the rays traced.
    pub(super) fn receive_into(
        &self,
        mesh: &Mesh,
        kd: &[DVec3],
        v: u32,
        scratch: &mut DirScratch,
        out: &mut [f64],
    ) -> (u32, u32) {
        self.receive_as(mesh, kd, Receiving::Vertex(v), scratch, out)
    }

    /// What `who` receives, into `out`, its slot, which it overwrites; the
    /// visible samples and the rays traced.
    pub(super) fn receive_as(
        &self,
        mesh: &Mesh,
        kd: &[DVec3],
        who: Receiving,
        scratch: &mut DirScratch,
        out: &mut [f64],
    ) -> (u32, u32) {
        match self {
            DirSource::Patch(shot) => shot.receive_into(mesh, kd, who, scratch, out),
            DirSource::Group(group) => group.receive_into(mesh, kd, who, scratch, out),
            DirSource::Lights(lights) => lights.receive_into(mesh, kd, who, scratch, out),
        }
    }

    pub(super) fn tables(&self) -> &Tables {
        match self {
            DirSource::Patch(shot) => shot.tables,
            DirSource::Group(group) => group.tables,
            DirSource::Lights(lights) => lights.tables,
        }
    }
}

/// The lights' shot as directional mode's [`Transport`]: every vertex
/// receives them in SH, the mesh refines at their shadows, and the reflected
/// light is gathered into the patches' unshot SH.
pub(in crate::solve) struct DirLightsShot<'d> {
    d: &'d mut Directional,
    /// Where the coefficients of the vertices refinement creates begin.
    created_from: usize,
}

impl<'d> DirLightsShot<'d> {
    pub(in crate::solve) fn new(d: &'d mut Directional) -> DirLightsShot<'d> {
        DirLightsShot { d, created_from: 0 }
    }
}

impl Transport for DirLightsShot<'_> {
    fn take_source(&mut self, s: &mut Solver) -> Source {
        s.lights.shot = true;
        Source {
            patch: None,
            ambient: s.ambient(),
            unshot: DVec3::ZERO,
        }
    }

    fn shoot(&mut self, s: &mut Solver, source: &Source) -> Shooting {
        let d = &mut *self.d;
        let upm = s.units_per_metre();
        let lights = std::mem::take(&mut s.lights);
        let shot = LightShot::new(&lights, &s.occluder, &s.materials.kd, &s.settings, upm);
        let tables = Tables::new(d, &s.mesh);
        let replay = [DirSource::Lights(DirLights {
            lights: &shot,
            tables: &tables,
        })];
        let kd = &s.materials.kd;
        let field = (&mut s.field, &s.sharing.small);
        let rays = receive_all(&s.mesh, kd, field, d, &replay[0], true);
        let shot_done = Instant::now();
        self.created_from = d.radiance.len();
        // As the diffuse lights' shot (`solve/lights.rs`): the level of the
        // light they put in sets this shot's dark floor and ambient.
        let level = s.lights_level(s.received_power());
        let criteria = Criteria {
            dark_floor: DARK_FLOOR * s.stats.radiance_level.max(level),
            ..s.refine_criteria(source.ambient + DVec3::splat(level))
        };
        if !s.refines() {
            s.lights = lights;
            return Shooting {
                rays,
                refined: Refined::default(),
                shot_done,
            };
        }
        let mut split_budget = s.split_budget(Some(d));
        let refined = refine::refine_field(
            &mut s.mesh,
            &mut DirField::of_shot(
                d,
                &mut s.field,
                SolverParts {
                    patches: &s.patches,
                    materials: &s.materials,
                    settings: &s.settings,
                    occluder: &s.occluder,
                },
                &replay[0],
                &replay,
                (true, true),
            ),
            &criteria,
            &mut split_budget,
        );
        s.lights = lights;
        s.after_refinement(&split_budget, Some(d));
        Shooting {
            rays: rays + refined.rays,
            refined,
            shot_done,
        }
    }

    fn gather(&mut self, s: &mut Solver, _source: &Source, _dirty: &[u32]) {
        finish_shot(s, self.d, self.created_from);
    }

    /// The unshot power once gathered; what the lights added to it is their
    /// power (`solve/lights.rs`).
    fn unshot_power(&mut self, s: &mut Solver) -> f64 {
        let total = s.total_unshot_power();
        s.measure_lights_power(total)
    }
}
