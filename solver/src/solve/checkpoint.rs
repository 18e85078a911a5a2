//! The solver's state between shots, for checkpoint files.
//!
//! Between shots the state is: the mesh (rebuilt exactly by replaying its split
//! log on a fresh mesh of the same scene), each vertex's radiance and the part
//! of it from recorded (emitter) shots, the list of those shots, each patch's
//! unshot radiance, and the counters. Vertex ΔL is always zero between shots
//! (it is gathered into the patches), and random samples are drawn from
//! stateless streams (seed, shot, vertex), so nothing else is needed for a
//! resumed solve to end bit-identical to an uninterrupted one. Floating-point
//! values are stored as their IEEE bit patterns, so any serde format (JSON
//! included, with or without exact float parsing) restores them exactly.

use super::{SolveError, Solver};
use crate::scene::Scene;
use crate::settings::SolverSettings;
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// Bump when the meaning of the fields changes.
pub const CHECKPOINT_VERSION: u32 = 1;

/// Everything [`Solver::resume`] needs. See the module documentation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Checkpoint {
    pub version: u32,
    /// FNV-1a of the meshed scene (surfaces, patch counts, materials), hex: a
    /// checkpoint of another scene is refused.
    pub fingerprint: String,
    pub shots: u64,
    pub rays: u64,
    pub seconds: f64,
    /// The elements split so far, in order.
    pub split_log: Vec<u32>,
    /// Per vertex: radiance as f64 bit patterns (RGB).
    pub radiance: Vec<[u64; 3]>,
    /// Per patch: unshot radiance as f64 bit patterns (RGB).
    pub patch_unshot: Vec<[u64; 3]>,
    /// Per vertex: the part of the radiance from recorded shots (bits); empty
    /// when the mode does not keep it (directional).
    #[serde(default)]
    pub direct: Vec<[u64; 3]>,
    /// The recorded (emitter) shots, in order.
    #[serde(default)]
    pub recorded: Vec<super::shoot::RecordedShot>,
    /// Directional mode's SH coefficients; absent for a diffuse solve.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub directional: Option<super::DirectionalCheckpoint>,
}

fn to_bits(v: DVec3) -> [u64; 3] {
    [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()]
}

fn from_bits(b: [u64; 3]) -> DVec3 {
    DVec3::new(
        f64::from_bits(b[0]),
        f64::from_bits(b[1]),
        f64::from_bits(b[2]),
    )
}

impl Solver {
    /// The state between shots.
    pub fn checkpoint(&self) -> Checkpoint {
        Checkpoint {
            version: CHECKPOINT_VERSION,
            fingerprint: self.fingerprint(),
            shots: self.shots,
            rays: self.rays,
            seconds: self.seconds,
            split_log: self.mesh.split_log.clone(),
            radiance: self.radiance.iter().map(|&v| to_bits(v)).collect(),
            patch_unshot: self.patch_unshot.iter().map(|&v| to_bits(v)).collect(),
            direct: if self.direct.len() == self.radiance.len() {
                self.direct.iter().map(|&v| to_bits(v)).collect()
            } else {
                Vec::new()
            },
            recorded: self.recorded.clone(),
            directional: self.directional_checkpoint(),
        }
    }

    /// Rebuilds a solver from `checkpoint` on the same scene. With the same
    /// settings, continuing it gives bit-identical results to a solve that was
    /// never interrupted. The thresholds and shot budget may differ (to continue
    /// a solve further); settings that change the mesh (patches) may not.
    pub fn resume(
        scene: &Scene,
        settings: &SolverSettings,
        checkpoint: Checkpoint,
    ) -> Result<Solver, SolveError> {
        let mismatch = |what: String| Err(SolveError::CheckpointMismatch(what));
        if checkpoint.version != CHECKPOINT_VERSION {
            return mismatch(format!(
                "it has state version {}, this solver reads version {CHECKPOINT_VERSION}",
                checkpoint.version
            ));
        }
        let mut solver = Solver::new(scene, settings)?;
        if checkpoint.fingerprint != solver.fingerprint() {
            return mismatch(format!(
                "its scene fingerprint is {}, this scene's is {} (another scene, or another \
                 patch count)",
                checkpoint.fingerprint,
                solver.fingerprint()
            ));
        }
        // Validate the log before replaying it: every entry must name an element
        // that exists by then (each split adds four).
        let mut elements = solver.mesh.elements.len() as u64;
        for &e in &checkpoint.split_log {
            if e as u64 >= elements {
                return mismatch(format!("its split log names element {e}, of {elements}"));
            }
            elements += 4;
        }
        solver
            .mesh
            .replay(&checkpoint.split_log)
            .map_err(|e| SolveError::CheckpointMismatch(e.to_string()))?;
        if checkpoint.radiance.len() != solver.mesh.vertices.len()
            || !(checkpoint.direct.is_empty()
                || checkpoint.direct.len() == solver.mesh.vertices.len())
            || checkpoint.patch_unshot.len() != solver.mesh.patches.len()
        {
            return mismatch(format!(
                "it has {} vertices and {} patches, the replayed mesh {} and {}",
                checkpoint.radiance.len(),
                checkpoint.patch_unshot.len(),
                solver.mesh.vertices.len(),
                solver.mesh.patches.len()
            ));
        }
        solver.radiance = checkpoint.radiance.into_iter().map(from_bits).collect();
        solver.patch_unshot = checkpoint.patch_unshot.into_iter().map(from_bits).collect();
        solver.direct = if checkpoint.direct.is_empty() {
            vec![DVec3::ZERO; solver.mesh.vertices.len()]
        } else {
            checkpoint.direct.into_iter().map(from_bits).collect()
        };
        let patches = solver.mesh.patches.len() as u32;
        if let Some(bad) = checkpoint
            .recorded
            .iter()
            .find(|r| r.patch >= patches || r.index >= checkpoint.shots)
        {
            return mismatch(format!("its recorded shot {bad:?} does not fit the solve"));
        }
        solver.recorded = checkpoint.recorded;
        solver.recorded_pools = solver
            .recorded
            .iter()
            .map(|r| {
                let shot = super::shoot::Shot::for_patch(
                    &solver.mesh,
                    r.patch,
                    r.index,
                    r.unshot(),
                    &solver.settings,
                    &solver.occluder,
                    &solver.kd,
                );
                super::shoot::SamplePool::with_sets(&shot, super::shoot::REPLAY_POOL_SETS)
            })
            .collect();
        if !solver
            .radiance
            .iter()
            .chain(&solver.patch_unshot)
            .chain(&solver.direct)
            .all(|v| v.is_finite())
        {
            return mismatch("it holds non-finite radiance".into());
        }
        let count = solver.mesh.vertices.len();
        solver.received = vec![DVec3::ZERO; count];
        solver.visible = vec![0; count];
        solver.leaf_count = solver.mesh.leaf_count();
        let all: Vec<u32> = (0..solver.mesh.surfaces.len() as u32).collect();
        solver.update_weights(&all);
        solver.shots = checkpoint.shots;
        solver.rays = checkpoint.rays;
        solver.seconds = checkpoint.seconds;
        solver
            .restore_directional(checkpoint.directional)
            .map_err(SolveError::CheckpointMismatch)?;
        solver.unshot_power = solver.total_unshot_power();
        Ok(solver)
    }

    /// FNV-1a over what the mesh and the transport are built from.
    fn fingerprint(&self) -> String {
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        let mut eat = |x: u64| {
            for b in x.to_le_bytes() {
                h ^= b as u64;
                h = h.wrapping_mul(0x0000_0100_0000_01b3);
            }
        };
        eat(self.mesh.surfaces.len() as u64);
        for (i, s) in self.mesh.surfaces.iter().enumerate() {
            eat(s.polygon as u64);
            eat(s.patches_per_side as u64);
            // The absolute smallest element decides later splits (a per-object
            // TOML size is not in the settings); nothing in the flat rule, so
            // its fingerprints are those of checkpoints written before sizes.
            if let Some(size) = s.min_element_size {
                eat(size.to_bits());
            }
            eat(s.vertices.len() as u64);
            for v in &s.vertices {
                v.to_array().iter().for_each(|c| eat(c.to_bits()));
            }
            for c in self.kd[i]
                .to_array()
                .iter()
                .chain(&self.emission[i].to_array())
            {
                eat(c.to_bits());
            }
        }
        eat(self.mesh.patches.len() as u64);
        format!("{h:016x}")
    }
}
