//! Light transport into one receiving vertex from every source patch: the
//! form factors and the incoming directions the gather needs, computed once
//! (the mesh is fixed) before the Gauss–Seidel sweeps.
//!
//! For receiver v and source patch s the factor is the progressive solver's
//! (design notes, "Form factors"; [`Shot::form_factor`]): the exact unoccluded
//! point-to-polygon factor at v's receiving point times the visible fraction of
//! `samples` stratified, jittered rays, from the same pooled or clipped sample
//! sets (shot index = the source's patch index, so the streams depend only on
//! the seed, the source and the receiver). The `wallace` method uses Remington 1992, eq.
//! 3.1's per-sample terms and `hemicube` is treated as analytic, as the SH
//! directional mode does: a direction per visible sample is needed.
//!
//! A glossy receiver also needs where the light comes from: each visible
//! sample's share of the factor is splatted onto the receiver's
//! upper-hemisphere cube cells with the bilinear weights of its direction
//! (the adjoint of the lookup, renormalized over cells above the horizon), so
//! the reflection sees the source's extent, not only its centre.

use super::UpperCells;
use crate::mesh::Mesh;
use crate::solve::shoot::{visible_samples, SampleBy, SamplePool, SampleScratch, Shot};
use glam::DVec3;
use solution::sh;

/// Transport from one source patch into one receiver.
#[derive(Clone, Copy, Debug)]
pub(super) struct Pair {
    pub source: u32,
    /// F(v←s) with visibility.
    pub factor: f64,
    /// End of this pair's incoming-cell entries in [`Receiver::entries`]
    /// (they start where the previous pair's end).
    pub entries_end: u32,
    /// Where a glossy source is looked up: the upper cells of the source's
    /// cube nearest the direction from its centre toward the receiver, with
    /// bilinear weights summing to 1 (unused for diffuse sources), in the
    /// source polygon's frame.
    pub taps: [(u32, f32); 4],
}

/// Everything one receiving vertex gathers from.
#[derive(Clone, Debug, Default)]
pub(super) struct Receiver {
    pub pairs: Vec<Pair>,
    /// (upper-cell slot, share of the factor) per pair, glossy receivers only.
    pub entries: Vec<(u32, f64)>,
    /// Rays traced for this receiver.
    pub rays: u64,
}

/// Per-worker buffers.
#[derive(Default)]
pub(super) struct Scratch {
    /// The visible samples and the buffers that find them.
    pub(super) sampling: SampleScratch,
    cells: Vec<(u32, f64)>,
}

/// A pair, its incoming-cell entries and the rays traced for it.
pub(super) type PairResult = (Pair, Vec<(u32, f64)>, u32);

/// What receiver v gets from the shot's source: the pair (when the factor is
/// positive), its incoming entries appended to `entries`, and the rays traced.
pub(super) struct PairInput<'a> {
    pub mesh: &'a Mesh,
    pub shot: &'a Shot<'a>,
    pub pool: &'a SamplePool,
    /// The receiver's cube cells (None: a diffuse receiver).
    pub receiver_cells: Option<&'a UpperCells>,
    /// The frame (n, t) the receiver's cube is written in
    /// ([`super::vertex_frame`]).
    pub receiver_frame: (DVec3, DVec3),
    /// The source's cube cells (None: a diffuse source).
    pub source_cells: Option<&'a UpperCells>,
}

impl PairInput<'_> {
    pub fn pair(&self, v: u32, source: u32, scratch: &mut Scratch) -> Option<PairResult> {
        let mesh = self.mesh;
        let shot = self.shot;
        let surface = mesh.vertices[v as usize].surface;
        if surface == shot.source_surface {
            return None;
        }
        let (q, _, rays) = visible_samples(
            shot,
            mesh,
            v,
            self.pool,
            &mut scratch.sampling,
            SampleBy::Area,
        );
        let factor: f64 = scratch.sampling.samples.iter().map(|s| s.1).sum();
        if !(factor > 0.0 && factor.is_finite()) {
            return None;
        }
        let (normal, tangent) = self.receiver_frame;
        let mut entries = Vec::new();
        if let Some(cells) = self.receiver_cells {
            scratch.cells.clear();
            for &(p, share) in &scratch.sampling.samples {
                let Some(dir) = (p - q).try_normalize() else {
                    continue;
                };
                let local = sh::to_local(dir, normal, tangent);
                if let Some(taps) = cells.taps(local) {
                    for (slot, w) in taps {
                        if w > 0.0 {
                            scratch.cells.push((slot, share * w));
                        }
                    }
                }
            }
            // Merge per cell in a fixed order.
            scratch.cells.sort_unstable_by_key(|c| c.0);
            for &(slot, w) in &scratch.cells {
                match entries.last_mut() {
                    Some((last, sum)) if *last == slot => *sum += w,
                    _ => entries.push((slot, w)),
                }
            }
            if entries.is_empty() {
                return None;
            }
        }
        let mut taps = [(0u32, 0f32); 4];
        if let Some(cells) = self.source_cells {
            let source_surface = &mesh.surfaces[shot.source_surface as usize];
            let toward = toward_receiver(shot.centre, shot.normal, q);
            let local = sh::to_local(toward, source_surface.normal, source_surface.tangent);
            match cells.taps(local) {
                Some(t) => {
                    for (slot, (cell, w)) in taps.iter_mut().zip(t) {
                        *slot = (cell, w as f32);
                    }
                }
                // The receiver is on the source's horizon: it sees none of it.
                None => return None,
            }
        }
        Some((
            Pair {
                source,
                factor,
                entries_end: 0,
                taps,
            },
            entries,
            rays,
        ))
    }
}

/// The direction a source patch (centre, normal) is looked up in toward a
/// receiving point `q`: from its centre to `q`, or its normal when they meet.
pub(super) fn toward_receiver(centre: DVec3, normal: DVec3, q: DVec3) -> DVec3 {
    (q - centre).try_normalize().unwrap_or(normal)
}
