//! One directional shot's transport to a receiving vertex (module
//! documentation of [`super`], "Transport"): the visible source samples, the
//! source's unshot SH evaluated toward the receiver, and the diffuse and
//! glossy parts of what the receiver reflects.

use super::Directional;
use crate::brdf::GlossyLobe;
use crate::mesh::Mesh;
use crate::solve::regions::QuadrantScale;
use crate::solve::shoot::{visible_samples, SampleBy, SamplePool, SampleScratch, Shot};
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
    basis: Vec<f64>,
    unit: Vec<f64>,
    lobe_scratch: Vec<f64>,
    /// Per visible sample, its scale of the unshot radiance when the source
    /// shoots by quadrants ([`QuadrantScale::sample_scales`]); empty otherwise.
    scales: Vec<DVec3>,
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

    /// ΔL of vertex `v` as SH coefficients of its surface's order.
    pub(super) fn receive(
        &self,
        mesh: &Mesh,
        kd: &[DVec3],
        v: u32,
        scratch: &mut DirScratch,
    ) -> ReceivedSh {
        let surface = mesh.vertices[v as usize].surface as usize;
        let order = self.tables.surface_order[surface];
        let count = coefficient_count(order);
        // A textured surface keeps E/π after its coefficients.
        let textured = self.tables.textured[surface];
        let mut out = vec![0.0; 3 * count + if textured { 3 } else { 0 }];
        let kd = kd[surface];
        let ks = self.tables.ks[surface];
        let lobe = self.tables.lobes[surface].as_deref();
        if surface as u32 == self.shot.source_surface || (kd == DVec3::ZERO && lobe.is_none()) {
            return ReceivedSh {
                coefficients: out,
                visible: 0,
                rays: 0,
            };
        }
        // Where the light's direction matters (a glossy receiver, or a
        // source whose radiance depends on direction), samples by solid
        // angle; so too where it matters which part of the source a sample
        // comes from (a source shooting by quadrants: equal shares of area
        // samples would average the quadrants out). Between two diffuse ends
        // of a uniform shot, the diffuse solver's own samples.
        let by = if order > 0 || self.source_order > 0 || self.quadrants.is_some() {
            SampleBy::SolidAngle
        } else {
            SampleBy::Area
        };
        let (q, visible, rays) =
            visible_samples(self.shot, mesh, v, self.pool, &mut scratch.sampling, by);
        let shading = mesh.vertices[v as usize].normal;
        // A source shooting by quadrants: each sample's scale is its
        // quadrant's, times the ratio that makes their unoccluded sum exact.
        scratch.scales.clear();
        if let Some(quadrants) = self.quadrants {
            let sampling = &scratch.sampling;
            quadrants.sample_scales(
                q,
                shading,
                &sampling.samples,
                &sampling.occluded,
                &mut scratch.scales,
            );
        }
        let s = &mesh.surfaces[surface];
        let source_count = coefficient_count(self.source_order);
        scratch.basis.resize(source_count, 0.0);
        scratch.unit.resize(count, 0.0);
        scratch.lobe_scratch.resize(count, 0.0);
        let samples = std::mem::take(&mut scratch.sampling.samples);
        let sqrt_4pi = (4.0 * PI).sqrt();
        for (i, &(p, share)) in samples.iter().enumerate() {
            let Some(toward_source) = (p - q).try_normalize() else {
                continue;
            };
            // U_s toward the receiver, from the source's SH in its frame.
            let unshot = if self.source_order == 0 {
                DVec3::from_slice(&self.unshot[..3]) * Y00
            } else {
                let local = sh::to_local(-toward_source, self.shot.normal, self.source_tangent);
                sh::eval_basis(self.source_order, local, &mut scratch.basis);
                let mut u = DVec3::ZERO;
                for (c, y) in self.unshot.chunks_exact(3).zip(&scratch.basis) {
                    u += DVec3::from_slice(c) * *y;
                }
                u
            };
            let unshot = scratch
                .scales
                .get(i)
                .map_or(unshot, |&scale| unshot * scale);
            // Ringing of a truncated lobe below zero is not light to shoot.
            let irradiance = unshot.max(DVec3::ZERO) * PI * share;
            if textured {
                // Textured: ΔE/π, which the texture multiplies at display
                // and in the gather (`directional/textured.rs`; kd is 1).
                let e = kd * irradiance / PI;
                let at = 3 * count;
                out[at] += e.x;
                out[at + 1] += e.y;
                out[at + 2] += e.z;
            } else {
                // Diffuse part: radiance Kd·ΔE/π as c₀₀.
                let diffuse = kd * irradiance / PI * sqrt_4pi;
                out[0] += diffuse.x;
                out[1] += diffuse.y;
                out[2] += diffuse.z;
            }
            if let Some(lobe) = lobe {
                scratch.unit.fill(0.0);
                if shading == s.normal {
                    let omega_i = sh::to_local(toward_source, s.normal, s.tangent);
                    lobe.add_lobe_sh(omega_i, 1.0, &mut scratch.unit, &mut scratch.lobe_scratch);
                } else {
                    // A smooth surface reflects about its shading normal; the
                    // lobe is expressed in the polygon's frame, like every
                    // coefficient of this surface (module documentation, "Frames").
                    let mu_i = shading.dot(toward_source);
                    let mirror = 2.0 * mu_i * shading - toward_source;
                    lobe.add_lobe_sh_about(
                        mu_i,
                        sh::to_local(mirror, s.normal, s.tangent),
                        1.0,
                        &mut scratch.unit,
                        &mut scratch.lobe_scratch,
                    );
                }
                let e = irradiance * ks;
                for (o, u) in out.chunks_exact_mut(3).zip(&scratch.unit) {
                    o[0] += u * e.x;
                    o[1] += u * e.y;
                    o[2] += u * e.z;
                }
            }
        }
        scratch.sampling.samples = samples;
        ReceivedSh {
            coefficients: out,
            visible,
            rays,
        }
    }
}
