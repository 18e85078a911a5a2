//! One directional shot's transport to a receiving vertex (module
//! documentation of [`super`], "Transport"): the visible source samples, the
//! source's unshot SH evaluated toward the receiver, and the diffuse and
//! glossy parts of what the receiver reflects.

use super::lights::SKY_RAYS_PER_COEFFICIENT;
use super::Directional;
use crate::brdf::GlossyLobe;
use crate::mesh::Mesh;
use crate::solve::regions::QuadrantScale;
use crate::solve::shoot::{
    visible_samples_at, ReceivingPoint, SampleBy, SamplePool, SampleScratch, Scratch, Shot,
};
use glam::DVec3;
use solution::sh::{self, coefficient_count, Y00};
use std::f64::consts::PI;
use std::sync::Arc;

/// What one receiving vertex gets from one directional shot.
pub(super) struct ReceivedSh {
    pub(super) coefficients: Vec<f64>,
    pub(super) visible: u32,
    pub(super) rays: u32,
}

/// Per-worker buffers.
#[derive(Default)]
pub(super) struct DirScratch {
    /// The visible source samples and the buffers that find them.
    sampling: SampleScratch,
    pub(super) basis: Vec<f64>,
    pub(super) lobe: LobeScratch,
    /// Per visible sample, its scale of the unshot radiance when the source
    /// shoots by quadrants ([`QuadrantScale::sample_scales`]); empty otherwise.
    scales: Vec<DVec3>,
    /// A grouped shot's cut, rays and flags (`directional/group.rs`).
    pub(super) group: Scratch,
}

/// The buffers of [`Reflector::add`].
#[derive(Default)]
pub(super) struct LobeScratch {
    unit: Vec<f64>,
    scratch: Vec<f64>,
}

/// How one receiving vertex reflects light arriving from a direction
/// (module documentation of [`super`], "Transport"): its diffuse part as
/// c₀₀ (or, textured, E/π after its coefficients) and its glossy lobe.
pub(super) struct Reflector<'t> {
    /// Its coefficients per channel, (L+1)².
    count: usize,
    textured: bool,
    kd: DVec3,
    ks: DVec3,
    lobe: Option<&'t GlossyLobe>,
    /// The vertex's shading normal, and its polygon's SH frame.
    shading: DVec3,
    normal: DVec3,
    tangent: DVec3,
}

impl ReceivedSh {
    /// Nothing received: `coefficients` (zeroed), no ray traced.
    pub(super) fn nothing(coefficients: Vec<f64>) -> Self {
        ReceivedSh {
            coefficients,
            visible: 0,
            rays: 0,
        }
    }
}

/// Who receives a shot: a vertex, or a small flat surface once, at its
/// centroid, for every vertex of it (`solve/small.rs`: one element that
/// refinement never splits, so per-vertex samples would buy only noise).
#[derive(Clone, Copy)]
pub(super) enum Receiving<'a> {
    Vertex(u32),
    Small(&'a ReceivingPoint),
}

impl Receiving<'_> {
    /// The surface it lies on.
    pub(super) fn surface(&self, mesh: &Mesh) -> u32 {
        match self {
            Receiving::Vertex(v) => mesh.vertices[*v as usize].surface,
            Receiving::Small(at) => at.surface,
        }
    }

    /// Its receiving point, for an occluder of scene epsilon `epsilon`.
    pub(super) fn point(&self, mesh: &Mesh, epsilon: f64) -> ReceivingPoint {
        match self {
            Receiving::Vertex(v) => ReceivingPoint::of_vertex(mesh, *v, epsilon),
            Receiving::Small(at) => **at,
        }
    }
}

impl<'t> Reflector<'t> {
    pub(super) fn of_vertex(mesh: &Mesh, tables: &'t Tables, kd: &[DVec3], v: u32) -> Self {
        Reflector::of(mesh, tables, kd, Receiving::Vertex(v))
    }

    /// How `who` reflects: its surface's tables, and its shading normal (a
    /// small surface's is its facet normal).
    pub(super) fn of(mesh: &Mesh, tables: &'t Tables, kd: &[DVec3], who: Receiving) -> Self {
        let surface = who.surface(mesh) as usize;
        let s = &mesh.surfaces[surface];
        let shading = match who {
            Receiving::Vertex(v) => mesh.vertices[v as usize].normal,
            Receiving::Small(at) => at.n,
        };
        Reflector {
            count: coefficient_count(tables.surface_order[surface]),
            textured: tables.textured[surface],
            kd: kd[surface],
            ks: tables.ks[surface],
            lobe: tables.lobes[surface].as_deref(),
            shading,
            normal: s.normal,
            tangent: s.tangent,
        }
    }

    /// Whether it has a glossy lobe.
    pub(super) fn glossy(&self) -> bool {
        self.lobe.is_some()
    }

    /// Whether it reflects anything (Kd or a lobe).
    pub(super) fn reflects(&self) -> bool {
        self.kd != DVec3::ZERO || self.lobe.is_some()
    }

    /// The sky rays it wants at least: [`SKY_RAYS_PER_COEFFICIENT`] per
    /// SH coefficient when glossy, none more otherwise.
    pub(super) fn sky_rays(&self) -> u32 {
        if self.lobe.is_some() {
            SKY_RAYS_PER_COEFFICIENT * self.count as u32
        } else {
            0
        }
    }

    /// Zeroed coefficients for it: a textured surface keeps E/π after them.
    pub(super) fn zeroed(&self) -> Vec<f64> {
        vec![0.0; 3 * self.count + if self.textured { 3 } else { 0 }]
    }

    /// Adds to `out` what it reflects of `irradiance` (ΔE, per channel)
    /// arriving from the unit direction `toward` (scene frame).
    pub(super) fn add(
        &self,
        out: &mut [f64],
        toward: DVec3,
        irradiance: DVec3,
        scratch: &mut LobeScratch,
    ) {
        if self.textured {
            // Textured: ΔE/π, which the texture multiplies at display
            // and in the gather (`directional/textured.rs`; kd is 1).
            let e = self.kd * irradiance / PI;
            let at = 3 * self.count;
            out[at] += e.x;
            out[at + 1] += e.y;
            out[at + 2] += e.z;
        } else {
            // Diffuse part: radiance Kd·ΔE/π as c₀₀.
            let diffuse = self.kd * irradiance / PI * (4.0 * PI).sqrt();
            out[0] += diffuse.x;
            out[1] += diffuse.y;
            out[2] += diffuse.z;
        }
        let Some(lobe) = self.lobe else {
            return;
        };
        scratch.unit.resize(self.count, 0.0);
        scratch.scratch.resize(self.count, 0.0);
        scratch.unit.fill(0.0);
        if self.shading == self.normal {
            let omega_i = sh::to_local(toward, self.normal, self.tangent);
            lobe.add_lobe_sh(omega_i, 1.0, &mut scratch.unit, &mut scratch.scratch);
        } else {
            // A smooth surface reflects about its shading normal; the lobe is
            // expressed in the polygon's frame, like every coefficient of
            // this surface (module documentation, "Frames").
            let mu_i = self.shading.dot(toward);
            let mirror = 2.0 * mu_i * self.shading - toward;
            lobe.add_lobe_sh_about(
                mu_i,
                sh::to_local(mirror, self.normal, self.tangent),
                1.0,
                &mut scratch.unit,
                &mut scratch.scratch,
            );
        }
        let e = irradiance * self.ks;
        for (o, u) in out.chunks_exact_mut(3).zip(&scratch.unit) {
            o[0] += u * e.x;
            o[1] += u * e.y;
            o[2] += u * e.z;
        }
    }
}

/// What `who` reflects of the light that `arrive` hands it ray by ray at
/// its receiving point (for an occluder of scene epsilon `epsilon`):
/// `arrive(at, reflector, sink)` calls `sink(toward, ΔE)` for each arrival,
/// the unit direction toward the light and its irradiance, RGB, and returns
/// its visible count and rays traced. Into `out`, its slot, which it
/// overwrites; a receiver that reflects nothing receives nothing.
#[allow(clippy::too_many_arguments)]
pub(super) fn receive_arrivals(
    mesh: &Mesh,
    tables: &Tables,
    kd: &[DVec3],
    who: Receiving,
    epsilon: f64,
    out: &mut [f64],
    lobe: &mut LobeScratch,
    arrive: impl FnOnce(&ReceivingPoint, &Reflector, &mut dyn FnMut(DVec3, DVec3)) -> (u32, u32),
) -> (u32, u32) {
    let reflector = Reflector::of(mesh, tables, kd, who);
    out.fill(0.0);
    if !reflector.reflects() {
        return (0, 0);
    }
    let at = who.point(mesh, epsilon);
    arrive(&at, &reflector, &mut |toward, irradiance| {
        reflector.add(out, toward, irradiance, lobe);
    })
}

/// The radiance RGB of `coefficients` (order `order`, three per
/// coefficient) toward `local`, a unit direction in their frame; `basis` is
/// scratch.
pub(super) fn sh_toward(
    order: u32,
    local: DVec3,
    coefficients: &[f64],
    basis: &mut Vec<f64>,
) -> DVec3 {
    basis.resize(coefficient_count(order), 0.0);
    sh::eval_basis(order, local, basis);
    let mut u = DVec3::ZERO;
    for (c, y) in coefficients.chunks_exact(3).zip(basis.iter()) {
        u += DVec3::from_slice(c) * *y;
    }
    u
}

/// One directional shot: the diffuse [`Shot`] (geometry, samples,
/// visibility) and the source's unshot SH.
pub(super) struct DirShot<'a> {
    pub(super) shot: &'a Shot<'a>,
    /// The shot's jittered sample sets, shared with the diffuse path.
    pub(super) pool: &'a SamplePool,
    pub(super) unshot: &'a [f64],
    pub(super) source_order: u32,
    pub(super) source_tangent: DVec3,
    pub(super) tables: &'a Tables,
    /// A quad source lit unevenly: its quadrants' scales of `unshot`
    /// ([`QuadrantScale`]); `None` shoots `unshot` uniformly.
    pub(super) quadrants: Option<&'a QuadrantScale>,
}

/// Per-surface tables a shot reads (a copy, so the state can grow meanwhile).
#[derive(Clone)]
pub(super) struct Tables {
    pub(super) surface_order: Vec<u32>,
    pub(super) ks: Vec<DVec3>,
    pub(super) lobes: Vec<Option<Arc<GlossyLobe>>>,
    /// Per surface: the tangent of its SH frame.
    pub(super) tangent: Vec<DVec3>,
    /// Per surface: whether it is textured (its diffuse part goes to E/π).
    pub(super) textured: Vec<bool>,
}

impl Tables {
    pub(super) fn new(d: &Directional, mesh: &Mesh) -> Tables {
        Tables {
            surface_order: d.surface_order.clone(),
            ks: d.ks.clone(),
            lobes: d.lobes.clone(),
            tangent: mesh.surfaces.iter().map(|s| s.tangent).collect(),
            textured: d.textured.clone(),
        }
    }
}

impl<'a> DirShot<'a> {
    /// A recorded (emitter) shot replayed with its unshot SH, shooting
    /// uniformly as recorded shots do.
    pub(super) fn replay(
        shot: &'a Shot<'a>,
        pool: &'a SamplePool,
        unshot: &'a [f64],
        tables: &'a Tables,
    ) -> DirShot<'a> {
        let surface = shot.source_surface as usize;
        DirShot {
            shot,
            pool,
            unshot,
            source_order: tables.surface_order[surface],
            source_tangent: tables.tangent[surface],
            tables,
            quadrants: None,
        }
    }

    /// ΔL of vertex `v` as SH coefficients of its surface's order, into
    /// `out`, the vertex's slot (its coefficients, then E/π on a textured
    /// surface), which it overwrites; the visible samples and the rays traced.
    pub(super) fn receive_into(
        &self,
        mesh: &Mesh,
        kd: &[DVec3],
        who: Receiving,
        scratch: &mut DirScratch,
        out: &mut [f64],
    ) -> (u32, u32) {
        let surface = who.surface(mesh);
        let reflector = Reflector::of(mesh, self.tables, kd, who);
        out.fill(0.0);
        if surface == self.shot.source_surface || !reflector.reflects() {
            return (0, 0);
        }
        // Where the light's direction matters (a glossy receiver, or a
        // source whose radiance depends on direction), samples by solid
        // angle; so too where it matters which part of the source a sample
        // comes from (a source shooting by quadrants: equal shares of area
        // samples would average the quadrants out). Between two diffuse ends
        // of a uniform shot, the diffuse solver's own samples.
        let by = if reflector.count > 1 || self.source_order > 0 || self.quadrants.is_some() {
            SampleBy::SolidAngle
        } else {
            SampleBy::Area
        };
        let at = who.point(mesh, self.shot.occluder.scene_epsilon());
        let (q, visible, rays) =
            visible_samples_at(self.shot, &at, self.pool, &mut scratch.sampling, by);
        // A source shooting by quadrants: each sample's scale is its
        // quadrant's, times the ratio that makes their unoccluded sum exact.
        scratch.scales.clear();
        if let Some(quadrants) = self.quadrants {
            let sampling = &scratch.sampling;
            quadrants.sample_scales(
                q,
                reflector.shading,
                &sampling.samples,
                &sampling.occluded,
                &mut scratch.scales,
            );
        }
        let samples = std::mem::take(&mut scratch.sampling.samples);
        for (i, &(p, share)) in samples.iter().enumerate() {
            let Some(toward_source) = (p - q).try_normalize() else {
                continue;
            };
            // U_s toward the receiver, from the source's SH in its frame.
            let unshot = if self.source_order == 0 {
                DVec3::from_slice(&self.unshot[..3]) * Y00
            } else {
                let local = sh::to_local(-toward_source, self.shot.normal, self.source_tangent);
                sh_toward(self.source_order, local, self.unshot, &mut scratch.basis)
            };
            let unshot = scratch
                .scales
                .get(i)
                .map_or(unshot, |&scale| unshot * scale);
            // Ringing of a truncated lobe below zero is not light to shoot.
            let irradiance = unshot.max(DVec3::ZERO) * PI * share;
            reflector.add(out, toward_source, irradiance, &mut scratch.lobe);
        }
        scratch.sampling.samples = samples;
        (visible, rays)
    }
}
