//! `solver solve SCENE -o OUT …`: everything around the pure solver core — files,
//! flags, the terminal, checkpoints and Ctrl-C.
//!
//! The flow: load the scene (and display file), resolve the settings (flags > TOML
//! config > display file > preset), start or resume the solver inside a rayon pool
//! of `--threads` workers, shoot until done or interrupted while saving a
//! checkpoint and a partial solution every K shots ([`session`]), then write the
//! solution, the stats and the preview.

pub(crate) mod args;
mod checkpoint;
mod eta;
pub(crate) mod files;
pub mod memory;
mod preview;
mod progress;
mod session;
mod setup_progress;
mod stats;

pub use args::{SolveArgs, EXIT_INTERRUPTED, EXIT_SHOT_CAP};
pub use stats::RunStats;

use crate::method::Dispatch;
use crate::scene::{DisplayParams, ImportOptions, Scene};
use crate::settings::{SettingsPatch, SolverSettings};
use crate::solve::{Checkpoint, Solver};
use anyhow::{bail, Context};
use session::{Outcome, Session};
use solution::camera::Camera;
use std::path::Path;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// Runs the command; `Ok` carries the exit code (0; [`EXIT_SHOT_CAP`] when stopped
/// at the shot cap above the threshold; 130 when interrupted).
pub fn run(args: SolveArgs) -> anyhow::Result<ExitCode> {
    // From the start: a Ctrl-C during the import lets the set-up finish and
    // save, as one during the set-up does.
    let interrupt = install_ctrlc();
    let checkpoint_path = files::checkpoint_path(&args.out);
    check_checkpoint_state(&args, &checkpoint_path)?;
    // Find out now, not after an hour of solving, that an output cannot be written.
    for path in [
        Some(&args.out),
        args.stats_json.as_ref(),
        args.preview.as_ref(),
    ]
    .into_iter()
    .flatten()
    {
        files::check_writable(path)?;
    }

    // The display file named on the command line, then the scene.
    let display_flag = match &args.display {
        Some(path) => {
            let display = crate::scene::load_display_file(path)
                .map_err(plain)
                .with_context(|| format!("reading display file {}", path.display()))?;
            print_warnings(&display.warnings);
            Some(display)
        }
        None => None,
    };
    // Refuse out-of-range flags before importing or meshing anything: flags take
    // precedence over every other source, so an error now is an error in the
    // final settings. The scene config's own values are checked as it is read,
    // before its geometry; all are checked again once combined.
    let no_patch = SettingsPatch::default();
    let mut early = args.settings.clone();
    if early.mode.is_none() {
        // The mode may come from the scene config: the method is checked
        // against it once the config is read, before meshing.
        early.method = None;
    }
    resolve_settings(&args, &no_patch, &no_patch, &early)?;
    let options = ImportOptions {
        strict: args.settings.strict.unwrap_or(false),
        units_per_metre: args.settings.units_per_metre,
        lights: crate::scene::LightFlags {
            sun: args.sun,
            sky: args.sky,
        },
        ..Default::default()
    };
    let loaded = crate::scene::load_scene(&args.scene, &options)
        .map_err(plain)
        .with_context(|| format!("loading scene {}", args.scene.display()))?;
    let mut scene = loaded.scene;
    print_warnings(&scene.warnings);
    adopt_display_camera(&mut scene, display_flag.as_ref(), loaded.display.as_ref());
    // `--display` stands in for a display file that a TOML config names.
    let display = display_flag.or(loaded.display);

    let display_patch = display
        .as_ref()
        .map(|d| d.settings.clone())
        .unwrap_or_default();
    let mut settings = resolve_settings(&args, &display_patch, &loaded.settings, &args.settings)?;
    for line in scene.lights.describe(scene.recentre_offset) {
        eprintln!("solver: light: {line}");
    }
    warn_clamped_patches(&scene, &settings);
    apply_smoothing(&mut scene, settings.crease_angle);
    // The import's text and parse tables are freed; give their pages back
    // before meshing (`memory::return_freed_memory`).
    memory::return_freed_memory();
    // What import left resident, freed or not, is where the estimate starts.
    settings.resident_before_meshing = memory::resident_bytes();
    let budget_source = match settings.memory_budget {
        Some(_) => "as set".to_string(),
        None => {
            let (bytes, source) = memory::default_budget();
            settings.memory_budget = Some(bytes);
            source
        }
    };
    let resident = settings
        .resident_before_meshing
        .map(|r| {
            format!(
                "; {} resident after import",
                crate::solve::budget::human_bytes(r as u128)
            )
        })
        .unwrap_or_default();
    eprintln!(
        "solver: memory budget {} ({budget_source}){resident}",
        crate::solve::budget::human_bytes(settings.memory_budget.unwrap_or(0) as u128)
    );

    let threads = settings.threads.unwrap_or_else(|| {
        std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1)
    });
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .context("starting the worker threads")?;
    let session = Session {
        out: &args.out,
        checkpoint_path: checkpoint_path.clone(),
        meta: checkpoint::Meta {
            scene_fingerprint: checkpoint::scene_fingerprint(&scene),
            scene_path: args.scene.display().to_string(),
            settings: checkpoint::result_settings(&settings),
            seconds: 0.0,
            shots: 0,
        },
        threshold: settings.threshold,
        max_shots: settings.max_shots,
        checkpoint_every: settings.checkpoint_every,
        threads,
        interrupted: &interrupt.pressed,
    };
    // The method was checked against the mode when the settings resolved.
    let outcome = match settings.method.dispatch() {
        Dispatch::Progressive => {
            pool.install(|| solve(&args, &scene, &settings, &session, &interrupt.shooting))?
        }
        Dispatch::GaussSeidel => {
            pool.install(|| gauss_seidel(&args, &scene, &settings, threads))?
        }
        Dispatch::Cube => pool.install(|| cube_solve(&args, &scene, &settings, threads))?,
    };
    finish(&args, &settings, &checkpoint_path, outcome, scene.camera)
}

/// Refuses, before any work, a resume without a checkpoint and a fresh solve that
/// would overwrite one (the saved work would be lost).
fn check_checkpoint_state(args: &SolveArgs, checkpoint_path: &Path) -> anyhow::Result<()> {
    if args.resume && !checkpoint_path.exists() {
        bail!(
            "--resume: there is no checkpoint {} to continue (it is removed when a solve \
             converges); run without --resume to start a new solve",
            checkpoint_path.display()
        );
    }
    if !args.resume && checkpoint_path.exists() {
        bail!(
            "{} holds the checkpoint of an unfinished solve into {}; add --resume to \
             continue it, or delete the checkpoint to start over",
            checkpoint_path.display(),
            args.out.display()
        );
    }
    Ok(())
}

/// The display file's camera becomes the scene's when the scene names none. A
/// `--display` file also replaces the camera of a display file that the TOML
/// config names, but not the config's own `[camera]` (the config ranks above any
/// display file).
pub(crate) fn adopt_display_camera(
    scene: &mut Scene,
    flag: Option<&DisplayParams>,
    named_by_config: Option<&DisplayParams>,
) {
    let camera_from_named = named_by_config.is_some_and(|d| scene.camera == Some(d.camera));
    if let Some(display) = flag {
        if scene.camera.is_none() || camera_from_named {
            scene.camera = Some(display.camera);
        }
    } else if let (None, Some(display)) = (scene.camera, named_by_config) {
        scene.camera = Some(display.camera);
    }
}

/// Resolves settings and names the source of an out-of-range value.
fn resolve_settings(
    args: &SolveArgs,
    display: &SettingsPatch,
    config: &SettingsPatch,
    flags: &SettingsPatch,
) -> anyhow::Result<SolverSettings> {
    SolverSettings::resolve(args.preset(), &[display, config, flags]).map_err(|err| {
        let sets = |patch: &SettingsPatch| {
            serde_json::to_value(patch)
                .ok()
                .and_then(|v| v.get(err.name).cloned())
                .is_some_and(|v| !v.is_null())
        };
        let source = if sets(flags) {
            format!("flag {}", args::flag_name(err.name))
        } else if sets(config) {
            format!("scene config {}", args.scene.display())
        } else if sets(display) {
            let file = args
                .display
                .as_deref()
                .unwrap_or(Path::new("(named by the config)"));
            format!("display file {}", file.display())
        } else {
            format!("preset {}", args.preset().name())
        };
        anyhow::Error::new(err).context(format!("bad setting from {source}"))
    })
}

/// An error as one line: its message, then each source whose text the message
/// does not already contain (library errors often quote their source, and anyhow
/// would print it twice).
pub(crate) fn plain<E: std::error::Error>(err: E) -> anyhow::Error {
    let mut message = err.to_string();
    let mut source = err.source();
    while let Some(s) = source {
        let text = s.to_string();
        if !message.contains(&text) {
            message = format!("{message}: {text}");
        }
        source = s.source();
    }
    anyhow::anyhow!(message)
}

/// Finds the scene's smooth surfaces at `crease_angle` degrees
/// ([`crate::scene::smooth_scene`]) and says what it found.
pub(crate) fn apply_smoothing(scene: &mut crate::scene::Scene, crease_angle: f64) {
    let report = crate::scene::smooth_scene(scene, crease_angle);
    print_warnings(&report.warnings);
    if report.groups > 0 || report.with_input_normals > 0 {
        eprintln!(
            "solver: smooth surfaces (crease angle {crease_angle}°): {} polygons in {} groups, {} with the input's vertex normals",
            report.polygons, report.groups, report.with_input_normals
        );
    }
}

/// Prints each import warning once (`file:line (item): message`).
/// Warns about polygons whose size-driven patch count was clamped to
/// [`crate::mesh::MAX_PATCHES_PER_SIDE`]: their patches are larger than the target.
fn warn_clamped_patches(scene: &crate::scene::Scene, settings: &crate::settings::SolverSettings) {
    let sizing = crate::mesh::Sizing::from_settings(settings, scene);
    let clamped = crate::mesh::sizing::clamped_polygons(scene, &sizing);
    if let Some(&(first, asked)) = clamped.first() {
        eprintln!(
            "solver: warning: {}: the patch size asks for {asked} patches per side, clamped to {}; \
             {} polygon(s) in all have patches larger than the target",
            scene.polygons[first].source,
            crate::mesh::MAX_PATCHES_PER_SIDE,
            clamped.len()
        );
    }
}

pub(crate) fn print_warnings(warnings: &[crate::scene::Warning]) {
    let mut seen = std::collections::HashSet::new();
    for warning in warnings {
        let line = warning.to_string();
        if seen.insert(line.clone()) {
            eprintln!("solver: warning: {line}");
        }
    }
}

/// Ctrl-C's state: whether it was pressed, and whether the set-up has
/// ended (its checkpoint written), which decides what a second one loses.
pub struct Interrupt {
    pub pressed: AtomicBool,
    pub shooting: AtomicBool,
}

/// Sets a flag on Ctrl-C; the set-up runs to its end and saves its
/// checkpoint, the loop checks the flag between shots. A second Ctrl-C quits
/// at once (a long shot or pass need not be waited for), keeping the last
/// checkpoint, and says what that loses; every file is written atomically,
/// so none is left half-written. If the handler cannot be installed, Ctrl-C
/// kills the process as usual, which is said once.
fn install_ctrlc() -> Arc<Interrupt> {
    let state = Arc::new(Interrupt {
        pressed: AtomicBool::new(false),
        shooting: AtomicBool::new(false),
    });
    let handler_state = Arc::clone(&state);
    let installed = ctrlc::set_handler(move || {
        let shooting = handler_state.shooting.load(Ordering::SeqCst);
        if handler_state.pressed.swap(true, Ordering::SeqCst) {
            if shooting {
                eprintln!("\nsolver: second Ctrl-C: quitting now; --resume continues from the last checkpoint");
            } else {
                eprintln!(
                    "\nsolver: second Ctrl-C: quitting now; the set-up is lost (its checkpoint was \
                     not written yet) and the next run starts it over"
                );
            }
            #[allow(clippy::disallowed_methods)] // An edge: a second Ctrl-C quits at once.
            std::process::exit(EXIT_INTERRUPTED.into());
        }
        if shooting {
            eprintln!(
                "\nsolver: Ctrl-C: stopping after the current shot (press again to quit at once)"
            );
        } else {
            eprintln!(
                "\nsolver: Ctrl-C: finishing the set-up, then saving a checkpoint that --resume \
                 starts from (press again to quit at once and lose the set-up)"
            );
        }
    });
    if let Err(err) = installed {
        eprintln!("solver: note: Ctrl-C will stop without a final checkpoint ({err})");
    }
    state
}

/// Starts or resumes the solver core and runs the session.
fn solve(
    args: &SolveArgs,
    scene: &Scene,
    settings: &SolverSettings,
    session: &Session,
    shooting: &AtomicBool,
) -> anyhow::Result<Outcome> {
    let mut progress = setup_progress::SetupProgress::new();
    if args.resume {
        let (meta, state) = session.load::<Checkpoint>()?;
        let solver = Solver::resume_observed(scene, settings, state, &mut progress)
            .with_context(|| format!("resuming from {}", session.checkpoint_path.display()))?;
        memory::return_freed_memory();
        eprintln!("solver: {}", progress.summary());
        eprintln!(
            "solver: resuming {} at shot {} ({:.1} s spent before)",
            args.scene.display(),
            meta.shots,
            meta.seconds
        );
        shooting.store(true, Ordering::SeqCst);
        session.run(solver, meta.seconds)
    } else {
        let solver = Solver::new_observed(scene, settings, &mut progress)
            .map_err(plain)
            .with_context(|| format!("setting up the solve of {}", args.scene.display()))?;
        // Set-up's transients (contact cuts, grown vectors) are freed.
        memory::return_freed_memory();
        eprintln!("solver: {}", progress.summary());
        // Nothing done so far is lost from here on.
        session.save_checkpoint(&solver, progress.seconds())?;
        shooting.store(true, Ordering::SeqCst);
        report_setup(&solver);
        session.run(solver, progress.seconds())
    }
}

/// What the set-up decided that the user may want to know.
fn report_setup(solver: &Solver) {
    solver
        .warnings()
        .iter()
        .for_each(|w| eprintln!("solver: warning: {w}"));
    let estimate = solver.memory_estimate();
    eprintln!(
        "solver: memory: estimated peak {} at the start ({})",
        crate::solve::budget::human_bytes(estimate.peak() as u128),
        estimate.breakdown()
    );
    let small = solver.small_surface_count();
    if small > 0 {
        eprintln!(
            "solver: {small} small flat surfaces (one patch within the smallest element) \
             receive once per shot, at their centroid"
        );
    }
    let copies = solver.twin_copy_count();
    if copies > 0 {
        eprintln!(
            "solver: {copies} vertices copy a coincident vertex of their smooth surface \
             and take its sample"
        );
    }
    let (interpolated, sites) = solver.site_counts();
    if interpolated > 0 {
        eprintln!(
            "solver: {interpolated} points of finely tessellated smooth surfaces \
             interpolate {sites} sites (--site-angle {}°; 0: every point receives)",
            solver.settings().site_angle
        );
    }
}

/// The one-call solves (Gauss–Seidel, global cube) keep no checkpoints, so
/// there is nothing to resume.
fn refuse_resume(args: &SolveArgs, solve: &str) -> anyhow::Result<()> {
    if args.resume {
        bail!("--resume: the {solve} keeps no checkpoints; run without --resume");
    }
    Ok(())
}

/// A one-call solve's outcome. There is no checkpoint to keep or resume: an
/// unconverged result is said by the caller and marked partial in the file, so
/// the session's resume hint stays off.
fn one_call_outcome(solution: solution::format::Solution, stats: RunStats) -> Outcome {
    Outcome {
        converged: true,
        solution,
        stats,
        interrupted: false,
    }
}

/// `--method gauss-seidel`: one call, no checkpoints (nothing to resume).
fn gauss_seidel(
    args: &SolveArgs,
    scene: &Scene,
    settings: &SolverSettings,
    threads: usize,
) -> anyhow::Result<Outcome> {
    use crate::solve::gauss_seidel::{solve_gauss_seidel, GaussSeidelLimits};
    refuse_resume(args, "Gauss-Seidel solver")?;
    let result = solve_gauss_seidel(scene, settings, &GaussSeidelLimits::default())
        .map_err(plain)
        .with_context(|| format!("solving {} by Gauss-Seidel", args.scene.display()))?;
    eprintln!(
        "solver: gauss-seidel: {} patches, {:.1} MiB matrix, form factors {:.2} s, {} sweeps \
         {:.2} s, last change {:.1e}{}",
        result.patch_radiance.len(),
        result.matrix_bytes as f64 / (1u64 << 20) as f64,
        result.form_factor_seconds,
        result.sweeps,
        result.solve_seconds,
        result.change,
        if result.converged {
            ""
        } else {
            " (not converged: sweep budget)"
        }
    );
    let batch = result.solution.batches.first();
    let stats = RunStats {
        elements: result.patch_radiance.len() as u64,
        vertices: batch.map_or(0, |b| b.vertices.len() as u64),
        shots: result.sweeps as u64,
        rays: 0,
        seconds: result.form_factor_seconds + result.solve_seconds,
        rays_per_second: 0.0,
        threads,
        unshot_fraction: result.solution.header.stats.unshot_fraction,
    };
    Ok(one_call_outcome(result.solution, stats))
}

/// `--method cube`: Immel, Cohen and Greenberg's (1986) global cubes gathered by
/// Gauss-Seidel; one call, no checkpoints (nothing to resume).
fn cube_solve(
    args: &SolveArgs,
    scene: &Scene,
    settings: &SolverSettings,
    threads: usize,
) -> anyhow::Result<Outcome> {
    use crate::solve::cube_gather::{solve_cube, CubeLimits};
    refuse_resume(args, "global-cube solve")?;
    let result = solve_cube(scene, settings, &CubeLimits::default())
        .map_err(plain)
        .with_context(|| format!("solving {} on global cubes", args.scene.display()))?;
    eprintln!(
        "solver: global cube k = {} (D = {}): {:.1} MiB, transport {:.2} s, {} sweeps {:.2} s, \
         last change {:.1e}, γ = {:.3}, error bound {:.1e} (power {:.1e}){}",
        result.k,
        solution::cube::direction_count(result.k),
        result.memory_bytes as f64 / (1u64 << 20) as f64,
        result.form_factor_seconds,
        result.sweeps,
        result.solve_seconds,
        result.change,
        result.gamma,
        result.error_bound,
        result.power_bound,
        if result.converged {
            ""
        } else {
            " (not converged: sweep budget)"
        }
    );
    let stats = RunStats {
        elements: result.patches as u64,
        vertices: result.vertex_count() as u64,
        shots: result.sweeps as u64,
        rays: result.rays,
        seconds: result.form_factor_seconds + result.solve_seconds,
        rays_per_second: if result.form_factor_seconds > 0.0 {
            result.rays as f64 / result.form_factor_seconds
        } else {
            0.0
        },
        threads,
        unshot_fraction: result.solution.header.stats.unshot_fraction,
    };
    Ok(one_call_outcome(result.solution, stats))
}

impl session::Shooter for Solver {
    type State = Checkpoint;
    fn step(&mut self) -> bool {
        let stepped = Solver::step(self).is_some();
        for warning in self.take_warnings() {
            eprintln!("solver: warning: {warning}");
        }
        let t = self.timings();
        if stepped && Solver::is_done(self) && t.group_shots > 0 {
            eprintln!(
                "solver: grouped shooters: {} of {} shots grouped, {} patches shot in them",
                t.group_shots,
                self.progress().shots,
                t.grouped_patches
            );
        }
        stepped
    }
    fn memory_note(&self) -> Option<String> {
        let peak = self.peak_memory_estimate();
        let budget = self.settings().memory_budget?;
        Some(format!(
            "memory: estimated peak {peak} bytes ({}) within the budget {budget} bytes ({})",
            crate::solve::budget::human_bytes(peak as u128),
            crate::solve::budget::human_bytes(budget as u128)
        ))
    }
    fn is_done(&self) -> bool {
        Solver::is_done(self)
    }
    fn snapshot(&self) -> progress::Snapshot {
        let p = self.progress();
        progress::Snapshot {
            shots: p.shots,
            rays: p.rays,
            unshot_fraction: p.unshot_fraction,
            elements: p.elements as u64,
            vertices: p.vertices as u64,
        }
    }
    fn solution(&self, partial: bool) -> solution::format::Solution {
        self.to_solution(partial)
    }
    fn write_state(&self, mut w: &mut dyn std::io::Write) -> std::io::Result<()> {
        self.write_checkpoint(&mut w)
    }
}

/// Writes the final (or interrupted) outputs and says what happened.
fn finish(
    args: &SolveArgs,
    settings: &SolverSettings,
    checkpoint_path: &Path,
    outcome: Outcome,
    scene_camera: Option<Camera>,
) -> anyhow::Result<ExitCode> {
    let Outcome {
        mut solution,
        stats,
        interrupted,
        converged,
    } = outcome;
    if !interrupted {
        files::write_solution(&args.out, &mut solution, "solution")?;
        // The light that never reaches the viewer (`solve::enclosure`).
        if let Some(warning) = crate::solve::enclosure::dark_view_warning(&solution) {
            eprintln!("solver: warning: {warning}");
        }
    }
    eprintln!("solver: {}", stats.summary(settings.threshold));
    if let Some(path) = &args.stats_json {
        files::write_atomic(path, stats.to_json().as_bytes())
            .with_context(|| format!("writing stats {}", path.display()))?;
    }
    if interrupted {
        eprintln!(
            "solver: interrupted after shot {}; saved {} and the partial solution {}.\n\
             solver: to continue, run the same command again with --resume",
            stats.shots,
            checkpoint_path.display(),
            args.out.display()
        );
        return Ok(ExitCode::from(EXIT_INTERRUPTED));
    }
    eprintln!("solver: solution written to {}", args.out.display());
    if let Some(path) = &args.preview {
        let camera = preview::choose_camera(scene_camera, &solution);
        preview::write_preview(path, &solution, &camera)?;
        eprintln!("solver: preview written to {}", path.display());
    }
    if converged {
        if checkpoint_path.exists() {
            #[allow(clippy::disallowed_methods)] // An edge: a converged solve needs no checkpoint.
            std::fs::remove_file(checkpoint_path)
                .with_context(|| format!("removing {}", checkpoint_path.display()))?;
        }
        Ok(ExitCode::SUCCESS)
    } else {
        eprintln!(
            "solver: stopped after {} shots (budget {}) with {:.4}% of the emitted power \
             unshot, above the threshold {}%; {} is partial and {} is kept: run the same \
             command with --resume and a larger --max-shots to continue",
            stats.shots,
            settings.max_shots,
            100.0 * stats.unshot_fraction,
            100.0 * settings.threshold,
            args.out.display(),
            checkpoint_path.display()
        );
        Ok(ExitCode::from(EXIT_SHOT_CAP))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn display(width: u32) -> DisplayParams {
        DisplayParams {
            camera: Camera {
                width,
                ..Camera::default()
            },
            fov_x_deg: 45.0,
            near: 0.1,
            far: 10.0,
            diameter: 1.0,
            settings: SettingsPatch::default(),
            file: "d.display".into(),
            warnings: vec![],
        }
    }

    fn scene(camera: Option<Camera>) -> Scene {
        Scene {
            lights: Default::default(),
            polygons: vec![],
            materials: vec![],
            units_per_metre: 1.0,
            up_axis: Default::default(),
            camera,
            recentre_offset: glam::DVec3::ZERO,
            warnings: vec![],
        }
    }

    /// Precedence (design notes): the config's camera over any display file's;
    /// a `--display` file over one that the config names.
    #[test]
    fn display_cameras_follow_the_precedence() {
        let config_camera = Camera {
            width: 7,
            ..Camera::default()
        };
        let (flag, named) = (display(64), display(32));

        let mut s = scene(None);
        adopt_display_camera(&mut s, Some(&flag), None);
        assert_eq!(s.camera.unwrap().width, 64, "fills a missing camera");

        let mut s = scene(Some(config_camera));
        adopt_display_camera(&mut s, Some(&flag), None);
        assert_eq!(s.camera.unwrap().width, 7, "config [camera] wins");

        let mut s = scene(Some(named.camera));
        adopt_display_camera(&mut s, Some(&flag), Some(&named));
        assert_eq!(
            s.camera.unwrap().width,
            64,
            "--display replaces the named file"
        );

        let mut s = scene(None);
        adopt_display_camera(&mut s, None, Some(&named));
        assert_eq!(s.camera.unwrap().width, 32);
    }
}
