//! Directional mode's part of a checkpoint: the arrays written (borrowed, for
//! streaming), and the per-coefficient recorded-shot part (`direct`), which is
//! not written but recomputed on resume.
//!
//! Why the recomputation is exact: `direct` at a vertex changes in two places
//! only. A vertex that exists when a recorded shot is shot receives it from
//! the shot's own sample pool (`d.direct += c`, in shot order); a vertex that a
//! split creates receives all the recorded shots so far from their replay pools,
//! summed from zero in order (`DirField::receive`). A recorded shot's
//! `receivers` is the vertex count when it was shot, and vertex ids only grow,
//! so vertex v got the shots with `v >= receivers` (a prefix) by replay at its
//! creation and the rest directly, later. Both receives are pure functions of
//! (shot, pool, vertex) — the samples come from stateless streams — so doing
//! the same additions in the same order gives the same bits.

use super::lights::DirLights;
use super::receive::{DirScratch, DirShot, Receiving, Tables};
use super::{Directional, DirectionalCheckpoint};
use crate::solve::checkpoint::precision::kept_bits;
use crate::solve::lights::LightShot;
use crate::solve::shoot::{RecordedShot, SamplePool};
use crate::solve::Solver;
use rayon::prelude::*;
use solution::sh::coefficient_count;

/// The directional arrays a checkpoint stores, borrowed (`direct` is not
/// stored: it masks `radiance`, see `checkpoint.rs`).
pub(in crate::solve) struct CheckpointSections<'a> {
    pub surface_order: &'a [u32],
    pub radiance: &'a [f64],
    pub direct: &'a [f64],
    pub patch_unshot: &'a [f64],
    pub recorded_unshot: &'a [Vec<f64>],
    pub shot_sum: &'a [f64],
}

impl Directional {
    pub(in crate::solve) fn checkpoint_sections(&self) -> CheckpointSections<'_> {
        CheckpointSections {
            surface_order: &self.surface_order,
            radiance: &self.radiance,
            direct: &self.direct,
            patch_unshot: &self.patch_unshot,
            recorded_unshot: &self.recorded_unshot,
            shot_sum: &self.shot_sum,
        }
    }
}

impl Solver {
    /// Recomputes the diffuse proxies of a directional solve from its
    /// coefficients, exactly as the end of every directional step does (radiance
    /// c₀₀ Y₀₀ per vertex, the hemisphere-equivalent unshot per patch); before
    /// the first shot they are still what `Solver::new` set.
    pub(in crate::solve) fn restore_diffuse_proxies(&mut self) {
        let Some(d) = self.directional.as_deref() else {
            return;
        };
        if self.stats.shots == 0 {
            return;
        }
        for v in 0..self.mesh.vertices.len() {
            let o = d.vertex_offset[v];
            let surface = self.mesh.vertices[v].surface as usize;
            self.field.radiance[v] = d.diffuse_proxy(surface, &d.radiance[o..]);
        }
        for p in 0..self.mesh.patches.len() {
            let order = d.surface_order[self.mesh.patches[p].surface as usize];
            let range = d.patch_range(&self.mesh, p);
            self.patches.unshot[p] = d.hemisphere_equivalent(order, &d.patch_unshot[range]);
        }
    }
}

/// Vertices recomputed per parallel block: bounds the temporary copies.
const BLOCK: usize = 4096;

impl Solver {
    /// Recomputes `direct` of every vertex from the recorded shots (see the
    /// module documentation); called by `Solver::resume` after the mesh was
    /// replayed and the directional state restored. Nothing else changes.
    pub(in crate::solve) fn recompute_directional_direct(&mut self) {
        let Some(mut d) = self.directional.take() else {
            return;
        };
        let tables = Tables::new(&d, &self.mesh);
        let shots = RecordedShot::rebuild_all(
            &self.record.shots,
            &self.mesh,
            &self.settings,
            &self.occluder,
            &self.materials.kd,
        );
        // The pool each recorded shot was shot with (the replay pools are the
        // solver's `recorded_pools`, already rebuilt).
        let own_pools: Vec<SamplePool> = shots.iter().map(SamplePool::new).collect();
        let recorded_unshot = std::mem::take(&mut d.recorded_unshot);
        let dir_shot =
            |i: usize, pool| DirShot::replay(&shots[i], pool, &recorded_unshot[i], &tables);
        let direct: Vec<DirShot> = (0..shots.len())
            .map(|i| dir_shot(i, &own_pools[i]))
            .collect();
        let replay: Vec<DirShot> = (0..shots.len())
            .map(|i| dir_shot(i, &self.record.pools[i]))
            .collect();
        // The lights shot first, to every vertex alike (a pure function of
        // the vertex): their part comes first in each sum.
        let upm = self.units_per_metre();
        let (kd, settings) = (&self.materials.kd, &self.settings);
        let light_shot = LightShot::replay(&self.lights, &self.occluder, kd, settings, upm);
        let lights = light_shot.as_ref().map(|lights| DirLights {
            lights,
            tables: &tables,
        });
        let (mesh, recorded) = (&self.mesh, &self.record.shots);
        // A small surface's vertices received at its one point (`small.rs`).
        let small = &self.sharing.small;
        let who = |v: u32| match small.of(mesh.vertices[v as usize].surface) {
            Some(k) => Receiving::Small(&small.points()[k]),
            None => Receiving::Vertex(v),
        };
        let mut sums: Vec<Vec<f64>> = Vec::new();
        for start in (0..mesh.vertices.len()).step_by(BLOCK) {
            let end = (start + BLOCK).min(mesh.vertices.len());
            (start as u32..end as u32)
                .into_par_iter()
                .map_init(
                    || (DirScratch::default(), Vec::new()),
                    |(scratch, got), v| {
                        let mut sum = vec![0.0; d.vertex_slot(mesh, v as usize).len()];
                        got.resize(sum.len(), 0.0);
                        if let Some(lights) = &lights {
                            lights.receive_into(mesh, kd, who(v), scratch, got);
                            for (s, c) in sum.iter_mut().zip(got.iter()) {
                                *s += c;
                            }
                        }
                        for (i, r) in recorded.iter().enumerate() {
                            let shot = if v >= r.receivers {
                                &replay[i]
                            } else {
                                &direct[i]
                            };
                            shot.receive_into(mesh, kd, who(v), scratch, got);
                            for (s, c) in sum.iter_mut().zip(got.iter()) {
                                *s += c;
                            }
                        }
                        sum
                    },
                )
                .collect_into_vec(&mut sums);
            for (v, sum) in (start..end).zip(&sums) {
                let o = d.vertex_offset[v];
                d.direct[o..o + sum.len()].copy_from_slice(sum);
            }
        }
        drop((direct, replay));
        d.recorded_unshot = recorded_unshot;
        self.directional = Some(d);
    }
}

impl Solver {
    /// Unmasks the radiance coefficients read from a checkpoint (stored as
    /// their bits XOR the recorded-shot part's, see `checkpoint.rs`), once
    /// `direct` has been recomputed; then every one must be finite.
    pub(in crate::solve) fn unmask_directional_radiance(&mut self) -> Result<(), String> {
        let Some(d) = self.directional.as_deref_mut() else {
            return Ok(());
        };
        for (r, m) in d.radiance.iter_mut().zip(&d.direct) {
            *r = f64::from_bits(r.to_bits() ^ kept_bits(*m));
        }
        if d.radiance.iter().all(|x| x.is_finite()) {
            Ok(())
        } else {
            Err("it holds non-finite radiance coefficients".into())
        }
    }
}

/// A patch's unshot SH is masked by its prediction when the prediction's
/// red c₀₀ is within this fraction of the unshot's: then they share sign,
/// exponent and leading mantissa bits in most coefficients. (A patch that has
/// shot holds only what arrived since, far below its vertices' radiance: its
/// prediction would only add noise, so it is stored as it is.)
const MASK_WITHIN: f64 = 0.25;

impl Solver {
    /// The prediction of patch `p`'s unshot SH from state a resume has before
    /// it: the gather-weighted mean of its vertices' radiance coefficients.
    /// A patch that never shot holds, up to the weights' changes as the mesh
    /// refined, exactly that (every shot's ΔL was gathered into it with these
    /// weights); the light of an emitter's own surface is not in it, but an
    /// emitter shoots first.
    fn unshot_prediction(&self, d: &Directional, p: usize, out: &mut Vec<f64>) {
        out.clear();
        out.resize(d.patch_range(&self.mesh, p).len(), 0.0);
        let weights = &self.patches.weights[p];
        let total: f64 = weights.iter().map(|w| w.1).sum();
        if total <= 0.0 {
            return;
        }
        for &(v, w) in weights {
            let share = w / total;
            for (o, c) in out
                .iter_mut()
                .zip(&d.radiance[d.vertex_range(&self.mesh, v as usize)])
            {
                *o += share * c;
            }
        }
    }

    /// Patch `p`'s unshot SH as a checkpoint stores it, into `out`: masked
    /// (bits XOR those of [`Solver::unshot_prediction`]) when that is worth it;
    /// returns whether it was masked.
    pub(in crate::solve) fn masked_unshot(
        &self,
        p: usize,
        prediction: &mut Vec<f64>,
        out: &mut Vec<f64>,
    ) -> bool {
        let Some(d) = self.directional.as_deref() else {
            return false;
        };
        let unshot = &d.patch_unshot[d.patch_range(&self.mesh, p)];
        self.unshot_prediction(d, p, prediction);
        let (u, q) = (unshot[0], prediction[0]);
        let mask = u != 0.0 && (q - u).abs() <= MASK_WITHIN * u.abs();
        out.clear();
        out.extend(unshot.iter().zip(prediction.iter()).map(|(x, q)| {
            if mask {
                f64::from_bits(x.to_bits() ^ kept_bits(*q))
            } else {
                *x
            }
        }));
        mask
    }

    /// Unmasks the patches' unshot SH read from a checkpoint (`masked`: one
    /// flag per patch, as [`Solver::masked_unshot`] returned them), once the
    /// radiance is unmasked and the weights rebuilt; then every coefficient
    /// must be finite.
    pub(in crate::solve) fn unmask_unshot(&mut self, masked: &[u32]) -> Result<(), String> {
        let Some(mut d) = self.directional.take() else {
            return Ok(());
        };
        let result = if masked.len() != self.mesh.patches.len() {
            Err(format!(
                "it has {} unshot flags for {} patches",
                masked.len(),
                self.mesh.patches.len()
            ))
        } else {
            let mut prediction = Vec::new();
            for (p, &flag) in masked.iter().enumerate() {
                if flag != 0 {
                    self.unshot_prediction(&d, p, &mut prediction);
                    let range = d.patch_range(&self.mesh, p);
                    for (x, q) in d.patch_unshot[range].iter_mut().zip(&prediction) {
                        *x = f64::from_bits(x.to_bits() ^ kept_bits(*q));
                    }
                }
            }
            if d.patch_unshot.iter().all(|x| x.is_finite()) {
                Ok(())
            } else {
                Err("it holds non-finite unshot coefficients".into())
            }
        };
        self.directional = Some(d);
        result
    }
}

#[cfg(test)]
impl Solver {
    /// The per-coefficient recorded-shot part, as bits (for the resume tests).
    pub(in crate::solve) fn directional_direct_bits(&self) -> Vec<u64> {
        self.directional
            .as_deref()
            .map(|d| d.direct.iter().map(|x| x.to_bits()).collect())
            .unwrap_or_default()
    }
}

impl Solver {
    /// Restores the directional state after the mesh was replayed; an error
    /// string when the checkpoint does not fit.
    pub(in crate::solve) fn restore_directional(
        &mut self,
        state: Option<DirectionalCheckpoint>,
    ) -> Result<(), String> {
        let d = match (self.directional.as_deref_mut(), state) {
            (None, None) => return Ok(()),
            (Some(_), None) => {
                return Err("it was written by a diffuse solve, this one is directional".into())
            }
            (None, Some(_)) => {
                return Err("it was written by a directional solve, this one is diffuse".into())
            }
            (Some(d), Some(s)) => {
                d.extend_vertices(&self.mesh);
                if s.surface_order != d.surface_order {
                    return Err(format!(
                        "its SH orders per surface {:?} differ from this solve's {:?} (another \
                         α, Ks, sh_error_target or max_sh_order)",
                        s.surface_order, d.surface_order
                    ));
                }
                if s.radiance.len() != d.radiance.len()
                    || s.patch_unshot.len() != d.patch_unshot.len()
                {
                    return Err(format!(
                        "it has {} radiance and {} unshot coefficients, this mesh needs {} and {}",
                        s.radiance.len(),
                        s.patch_unshot.len(),
                        d.radiance.len(),
                        d.patch_unshot.len()
                    ));
                }
                if s.shot_sum.len() != d.shot_sum.len() {
                    return Err(format!(
                        "it has {} shot-sum coefficients, this mesh needs {}",
                        s.shot_sum.len(),
                        d.shot_sum.len()
                    ));
                }
                if !(s.direct.is_empty() || s.direct.len() == d.radiance.len()) {
                    return Err(format!(
                        "it has {} recorded-shot coefficients, this mesh needs {}",
                        s.direct.len(),
                        d.radiance.len()
                    ));
                }
                // One unshot SH per recorded shot, of its source surface's order.
                let recorded_fits = s.recorded_unshot.len() == self.record.shots.len()
                    && s.recorded_unshot
                        .iter()
                        .zip(&self.record.shots)
                        .all(|(u, r)| {
                            let surface = self.mesh.patches[r.patch as usize].surface as usize;
                            u.len() == 3 * coefficient_count(d.surface_order[surface])
                        });
                if !recorded_fits {
                    return Err(format!(
                        "its {} recorded directional shots do not match its {} recorded shots",
                        s.recorded_unshot.len(),
                        self.record.shots.len()
                    ));
                }
                d.radiance = s.radiance.into_iter().map(f64::from_bits).collect();
                d.patch_unshot = s.patch_unshot.into_iter().map(f64::from_bits).collect();
                d.direct = if s.direct.is_empty() {
                    vec![0.0; d.radiance.len()]
                } else {
                    s.direct.into_iter().map(f64::from_bits).collect()
                };
                d.shot_sum = s.shot_sum.into_iter().map(f64::from_bits).collect();
                d.recorded_unshot = s
                    .recorded_unshot
                    .into_iter()
                    .map(|u| u.into_iter().map(f64::from_bits).collect())
                    .collect();
                // The radiance and the unshot arrive masked (see
                // `checkpoint.rs`), so they are checked once unmasked, by `resume`.
                if !d
                    .direct
                    .iter()
                    .chain(d.recorded_unshot.iter().flatten())
                    .chain(&d.shot_sum)
                    .all(|x| x.is_finite())
                {
                    return Err("it holds non-finite coefficients".into());
                }
                d
            }
        };
        d.received.fill(0.0);
        Ok(())
    }
}
