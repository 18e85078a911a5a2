//! The shooting loop of `solver solve`, with its duties toward the files: a
//! checkpoint and a partial solution every K shots, a clean stop on Ctrl-C, and a
//! kept checkpoint whenever the solve ends before converging.
//!
//! The loop is written against [`Shooter`], the few operations it needs from the
//! solver core, so that its bookkeeping (when to save, what to keep, what to say)
//! is tested on its own; `solve::Solver` implements it in `cli/solve.rs`.

use super::checkpoint::{self, Meta};
use super::progress::{Reporter, Snapshot};
use super::stats::RunStats;
use solution::format::Solution;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

/// What the loop needs from a solver.
pub trait Shooter {
    /// The resumable state, as read back from checkpoints.
    type State: checkpoint::Payload;
    /// Shoots the source with the most unshot power; `false` when there was none.
    fn step(&mut self) -> bool;
    /// Below the threshold or at the shot budget.
    fn is_done(&self) -> bool;
    fn snapshot(&self) -> Snapshot;
    /// The solution as it stands; `partial` marks files written mid-solve.
    fn solution(&self, partial: bool) -> Solution;
    /// Streams the resumable state into a checkpoint (no copy of it is made).
    fn write_state(&self, w: &mut dyn Write) -> std::io::Result<()>;
    /// The memory figures for the closing summary (the estimated peak and the
    /// budget), when the solver keeps them.
    fn memory_note(&self) -> Option<String> {
        None
    }
}

/// Where the loop writes and what it stamps on its checkpoints.
pub struct Session<'a> {
    pub out: &'a Path,
    pub checkpoint_path: PathBuf,
    /// Scene fingerprint, scene path and result settings; `seconds` and `shots` are
    /// filled in at each save.
    pub meta: Meta,
    pub threshold: f64,
    pub max_shots: u64,
    pub checkpoint_every: u64,
    pub threads: usize,
    /// Set by the Ctrl-C handler.
    pub interrupted: &'a AtomicBool,
}

/// How the loop ended.
pub struct Outcome {
    pub solution: Solution,
    pub stats: RunStats,
    /// Stopped by Ctrl-C; the checkpoint and the partial solution are on disk.
    pub interrupted: bool,
    /// The unshot fraction reached the threshold. When not (a shot budget, or no
    /// source left with power), the checkpoint is kept for `--resume`.
    pub converged: bool,
}

impl Session<'_> {
    /// Reads the checkpoint for `--resume`; refuses another scene's or settings'.
    pub fn load<S: checkpoint::Payload>(&self) -> anyhow::Result<(Meta, S)> {
        Ok(checkpoint::read(
            &self.checkpoint_path,
            &self.meta.scene_fingerprint,
            &self.meta.scene_path,
            &self.meta.settings,
        )?)
    }

    /// Saves the checkpoint alone, atomically: the one written as soon as the
    /// set-up ends, so that no interrupt after it loses the set-up.
    pub fn save_checkpoint<S: Shooter>(&self, shooter: &S, seconds: f64) -> anyhow::Result<()> {
        let meta = Meta {
            seconds,
            shots: shooter.snapshot().shots,
            ..self.meta.clone()
        };
        checkpoint::write(&self.checkpoint_path, &meta, |w| shooter.write_state(w))
    }

    /// Saves the checkpoint, then the partial solution a viewer can watch; both
    /// atomically.
    fn save<S: Shooter>(&self, shooter: &S, seconds: f64) -> anyhow::Result<()> {
        self.save_checkpoint(shooter, seconds)?;
        let mut partial = shooter.solution(true);
        partial.header.stats.seconds = seconds;
        super::files::write_solution(self.out, &mut partial, "partial solution")
    }

    /// Shoots until done or interrupted. `seconds_before` is the time spent by the
    /// sessions before a resume.
    pub fn run<S: Shooter>(&self, mut shooter: S, seconds_before: f64) -> anyhow::Result<Outcome> {
        let mut reporter = Reporter::new(
            self.threshold,
            self.max_shots,
            seconds_before,
            shooter.snapshot(),
        );
        let mut stopped_by_user = false;
        while !shooter.is_done() {
            if self.interrupted.load(Ordering::SeqCst) {
                stopped_by_user = true;
                break;
            }
            if !shooter.step() {
                break;
            }
            let now = shooter.snapshot();
            reporter.update(&now);
            if now.shots.is_multiple_of(self.checkpoint_every) {
                self.save(&shooter, reporter.total_seconds())?;
            }
        }
        reporter.finish();

        let now = shooter.snapshot();
        let converged = now.unshot_fraction < self.threshold;
        // A Ctrl-C during the last shot, after which the solve converged, lost
        // nothing: finish normally.
        stopped_by_user &= !converged;
        let seconds = reporter.total_seconds();
        if stopped_by_user || !converged {
            // Keep what was done: a resumable checkpoint, and the partial solution
            // (rewritten below with the final figures when not interrupted).
            self.save(&shooter, seconds)?;
        }
        // A solve that stopped short of its threshold (Ctrl-C, or the shot cap) is
        // marked partial, so that no reader takes it for a finished one.
        let mut solution = shooter.solution(!converged);
        solution.header.stats.seconds = seconds;
        if let Some(note) = shooter.memory_note() {
            eprintln!("solver: {note}");
        }
        let stats = RunStats {
            elements: now.elements,
            vertices: now.vertices,
            shots: now.shots,
            rays: now.rays,
            seconds,
            rays_per_second: if seconds > 0.0 {
                now.rays as f64 / seconds
            } else {
                0.0
            },
            threads: self.threads,
            unshot_fraction: now.unshot_fraction,
        };
        Ok(Outcome {
            solution,
            stats,
            interrupted: stopped_by_user,
            converged,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::{Deserialize, Serialize};
    use solution::format::{
        Batch, Header, Representation, ScalarType, SolveMode, SolveStats, Vertex,
    };

    /// A stand-in solver: each shot multiplies the unshot fraction by `decay`, and
    /// the "radiance" of its one triangle is the number of shots, so a solution
    /// shows exactly how far it got.
    struct Toy {
        state: ToyState,
        threshold: f64,
        max_shots: u64,
        /// Raise this flag after this many shots (a Ctrl-C mid-solve).
        interrupt_at: Option<(u64, &'static AtomicBool)>,
    }

    #[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
    struct ToyState {
        shots: u64,
        unshot: f64,
    }

    impl Shooter for Toy {
        type State = ToyState;
        fn step(&mut self) -> bool {
            self.state.shots += 1;
            self.state.unshot *= 0.5;
            if let Some((at, flag)) = self.interrupt_at {
                if self.state.shots == at {
                    flag.store(true, Ordering::SeqCst);
                }
            }
            true
        }
        fn is_done(&self) -> bool {
            self.state.unshot < self.threshold || self.state.shots >= self.max_shots
        }
        fn snapshot(&self) -> Snapshot {
            Snapshot {
                shots: self.state.shots,
                rays: 10 * self.state.shots,
                unshot_fraction: self.state.unshot,
                elements: 1,
                vertices: 3,
            }
        }
        fn solution(&self, partial: bool) -> Solution {
            let vertex = |x: f32, y: f32| Vertex {
                position: [x, y, 0.0],
                normal: [0.0, 0.0, 1.0],
                tangent: [1.0, 0.0, 0.0],
            };
            Solution {
                lighting: None,
                header: Header {
                    units_per_metre: 1.0,
                    up_axis: Default::default(),
                    recentre_offset: [0.0; 3],
                    camera: Default::default(),
                    bounds_min: [0.0; 3],
                    bounds_max: [1.0, 1.0, 0.0],
                    partial,
                    mode: SolveMode::Diffuse,
                    stats: SolveStats {
                        shots: self.state.shots,
                        unshot_fraction: self.state.unshot,
                        ..Default::default()
                    },
                    settings_json: "{}".into(),
                },
                batches: vec![Batch {
                    representation: Representation::Sh { order: 0 },
                    scalar: ScalarType::F32,
                    vertices: vec![vertex(0.0, 0.0), vertex(1.0, 0.0), vertex(0.0, 1.0)],
                    coefficients: vec![self.state.shots as f32; 9],
                    indices: vec![0, 1, 2],
                    texturing: None,
                }],
                textures: Vec::new(),
            }
        }
        fn write_state(&self, w: &mut dyn Write) -> std::io::Result<()> {
            serde_json::to_writer(w, &self.state).map_err(std::io::Error::other)
        }
    }

    impl checkpoint::Payload for ToyState {
        fn read_payload(reader: &mut dyn std::io::Read, length: u64) -> Result<Self, String> {
            serde_json::from_reader(std::io::Read::take(reader, length)).map_err(|e| e.to_string())
        }
    }

    fn toy(max_shots: u64) -> Toy {
        Toy {
            state: ToyState {
                shots: 0,
                unshot: 1.0,
            },
            threshold: 0.01, // 2^-7 < 0.01 < 2^-6: converges at shot 7
            max_shots,
            interrupt_at: None,
        }
    }

    fn session<'a>(dir: &Path, flag: &'a AtomicBool, every: u64) -> Session<'a> {
        let out: &'static Path = Box::leak(dir.join("out.sol").into_boxed_path());
        Session {
            out,
            checkpoint_path: super::super::files::checkpoint_path(out),
            meta: Meta {
                scene_fingerprint: "0123456789abcdef".into(),
                scene_path: "toy.obj".into(),
                settings: serde_json::json!({"samples": 4}),
                seconds: 0.0,
                shots: 0,
            },
            threshold: 0.01,
            max_shots: 100,
            checkpoint_every: every,
            threads: 1,
            interrupted: flag,
        }
    }

    #[test]
    fn converged_solve_writes_no_checkpoint_of_its_own_end() {
        let dir = tempfile::tempdir().unwrap();
        let flag = AtomicBool::new(false);
        let s = session(dir.path(), &flag, 1000);
        let outcome = s.run(toy(100), 0.0).unwrap();
        assert!(outcome.converged && !outcome.interrupted);
        assert_eq!(outcome.stats.shots, 7);
        assert!(!outcome.solution.header.partial);
        assert!(!s.checkpoint_path.exists(), "no save was due");
    }

    #[test]
    fn checkpoints_come_every_k_shots_with_a_partial_solution() {
        let dir = tempfile::tempdir().unwrap();
        let flag = AtomicBool::new(false);
        let s = session(dir.path(), &flag, 3);
        s.run(toy(100), 0.0).unwrap();
        // The last save was at shot 6 (a multiple of 3, before convergence at 7).
        let (meta, state): (Meta, ToyState) = s.load().unwrap();
        assert_eq!((meta.shots, state.shots), (6, 6));
        let partial = solution::format::read_solution(s.out).unwrap();
        assert!(partial.header.partial);
        assert_eq!(partial.batches[0].coefficients[0], 6.0);
    }

    #[test]
    fn ctrl_c_saves_and_resume_finishes_like_an_uninterrupted_run() {
        static FLAG: AtomicBool = AtomicBool::new(false);
        let dir = tempfile::tempdir().unwrap();
        let s = session(dir.path(), &FLAG, 1000);
        let mut interrupted = toy(100);
        interrupted.interrupt_at = Some((4, &FLAG));
        let outcome = s.run(interrupted, 0.0).unwrap();
        assert!(outcome.interrupted && !outcome.converged);
        assert_eq!(outcome.stats.shots, 4, "stops after the current shot");
        assert!(
            solution::format::read_solution(s.out)
                .unwrap()
                .header
                .partial
        );

        FLAG.store(false, Ordering::SeqCst);
        let (meta, state): (Meta, ToyState) = s.load().unwrap();
        assert_eq!(meta.shots, 4);
        let mut resumed = toy(100);
        resumed.state = state;
        let outcome = s.run(resumed, meta.seconds).unwrap();
        assert!(outcome.converged);
        assert_eq!(outcome.stats.shots, 7);
        assert_eq!(outcome.stats.rays, 70, "rays count over both sessions");
        assert_eq!(
            outcome.solution.batches,
            toy_solution_after(7).batches,
            "same result as an uninterrupted run"
        );
    }

    fn toy_solution_after(shots: u64) -> Solution {
        let mut t = toy(100);
        t.state.shots = shots;
        t.solution(false)
    }

    #[test]
    fn shot_budget_keeps_the_checkpoint() {
        let dir = tempfile::tempdir().unwrap();
        let flag = AtomicBool::new(false);
        let s = session(dir.path(), &flag, 1000);
        let outcome = s.run(toy(3), 0.0).unwrap();
        assert!(!outcome.converged && !outcome.interrupted);
        assert!(
            outcome.solution.header.partial,
            "an unconverged end is partial"
        );
        let (meta, _): (Meta, ToyState) = s.load().unwrap();
        assert_eq!(meta.shots, 3);
    }
}
