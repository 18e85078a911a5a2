//! `sweep`: the speed/accuracy sweep of issue 7.
//!
//! For each scene (the Cornell box and the bundled glossy room) it solves one
//! converged reference, then one solve per sweep point, each through the real
//! `solver solve` binary, and measures what the point cost (CPU and wall
//! seconds, rays, peak resident memory, file size) and what it bought (error
//! per vertex and in images rendered by `runtime screenshot` from fixed
//! cameras, both against the reference), and beside that the image error against
//! a path-traced truth per camera (`solver reference`, see [`truth`]). It writes
//! `docs/tradeoffs.md` and one
//! SVG plot per scene. Run it from the repository root after
//! `cargo build --release -p solver -p runtime`:
//!
//! ```text
//! cargo run --release -p sweep -- --quick      # a few points, under 3 minutes
//! cargo run --release -p sweep                 # the full sweep
//! ```
//!
//! Results are cached per point in the work folder (keyed by the exact scene
//! config and flags), so a second run only re-renders the report; `--fresh`
//! re-measures everything.

// Shipped code: Clippy checks clippy.toml's lists here (ARCHITECTURE.md's invariants).
#![cfg_attr(not(test), warn(clippy::disallowed_methods, clippy::disallowed_macros))]
#![cfg_attr(not(test), warn(clippy::too_many_lines))]

mod points;
mod report;
mod truth;

use anyhow::{bail, Context};
use bench_support::host::cpu_model;
use clap::Parser;
use glam::DVec3;
use points::{Camera, Point, SceneSpec};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::process::Command;
use sweep::child::run_measured;
use sweep::image::{read_exr, RgbImage};
use sweep::lookup::ReferenceLookup;
use sweep::metrics::{relative_error, ErrorStats, MetricError};

#[derive(Parser, Debug)]
#[command(about = "Speed/accuracy sweep of the solver; writes docs/tradeoffs.md")]
struct Args {
    /// A few points per scene (under 3 minutes); the report goes to the work folder
    /// unless --docs is given.
    #[arg(long)]
    quick: bool,
    /// Work folder: references, per-point solutions, images and cached results.
    #[arg(long, default_value = "target/sweep")]
    work: PathBuf,
    /// The solver binary.
    #[arg(long, default_value = "target/release/solver")]
    solver: PathBuf,
    /// The runtime binary (offscreen screenshots).
    #[arg(long, default_value = "target/release/runtime")]
    runtime: PathBuf,
    /// Where tradeoffs.md and the SVG plots go (default: docs/, or the work
    /// folder with --quick).
    #[arg(long)]
    docs: Option<PathBuf>,
    /// Only these scenes (cornell, glossy).
    #[arg(long, value_delimiter = ',')]
    scenes: Option<Vec<String>>,
    /// Only these axes (see the report's tables), e.g. samples,presets.
    #[arg(long, value_delimiter = ',')]
    axes: Option<Vec<String>>,
    /// Leave out the points whose label starts with one of these, or with the
    /// part after `SCENE/` in that scene only (e.g. `--skip C7,reference` drops
    /// the dearest combination and the floor rows, `--skip "glossy/--preset
    /// medium"` one preset of one scene): for a reduced sweep on a loaded
    /// machine; the report's command line says which.
    #[arg(long, value_delimiter = ',', value_name = "LABEL")]
    skip: Vec<String>,
    /// Re-measure points whose results are cached.
    #[arg(long)]
    fresh: bool,
    /// Notes (markdown) inserted into the report after the generated summary.
    #[arg(long, default_value = "tools/sweep/notes.md")]
    notes: PathBuf,
    /// Noise of the truths the sweep renders itself: `solver reference
    /// --target-error E` (mean relative standard error over lit pixels). Each
    /// halving costs four times the time.
    #[arg(long, value_name = "E", default_value_t = 0.005)]
    truth_error: f64,
    /// Truth size: each camera's screenshot divided by K per side (default per
    /// camera: 4 or 8, i.e. 64² or 32² for the Cornell box's 256² views). A
    /// smaller K is a finer truth, K² times dearer.
    #[arg(long, value_name = "K")]
    truth_divisor: Option<u32>,
    /// Use this EXR as the truth of one camera (repeatable), e.g.
    /// `--truth cornell/corner=corner32.exr`; it must be the camera's screenshot
    /// size divided by a whole number.
    #[arg(long, value_name = "SCENE/CAMERA=EXR", value_parser = truth::parse_given)]
    truth: Vec<(String, PathBuf)>,
    /// Only these cameras get a truth (e.g. `--truth-cameras cornell/front`,
    /// whose truth is the committed fixture): the truth columns are then the
    /// mean over these cameras alone, and a scene with none has no truth
    /// columns. Default: every camera.
    #[arg(long, value_delimiter = ',', value_name = "SCENE/CAMERA")]
    truth_cameras: Option<Vec<String>>,
    /// Skip the truths: only the error against the converged solution.
    #[arg(long)]
    no_truth: bool,
}

/// Everything measured for one point.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PointResult {
    pub scene: String,
    pub axis: String,
    pub label: String,
    /// The settings that differ from the scene config, as `key=value` text.
    pub settings: String,
    pub cpu_seconds: f64,
    pub wall_seconds: f64,
    pub peak_rss_bytes: u64,
    pub file_bytes: u64,
    pub elements: u64,
    pub vertices: u64,
    pub shots: u64,
    pub rays: u64,
    pub unshot_fraction: f64,
    /// Relative L1 error of the vertices' radiance toward the scene's fixed eye.
    pub vertex_error: Option<f64>,
    /// Fraction of vertices that could not be located on the reference mesh.
    pub vertex_unmatched: Option<f64>,
    /// Relative L1 and RMSE errors over every camera's pixels.
    pub image_error: Option<f64>,
    pub image_rmse: Option<f64>,
    /// What went wrong in a stage that did not stop the point.
    pub note: Option<String>,
    /// The solution's batches, e.g. `SH 0, 18` or `SH 0, cube 384`.
    #[serde(default)]
    pub representation: Option<String>,
    /// Error against the path-traced truth, mean over the cameras (bias plus
    /// the truth's noise); filled after the point is measured or loaded.
    #[serde(default)]
    pub truth: Option<truth::TruthError>,
}

impl PointResult {
    /// The row of `point` before anything is measured: costs NaN or zero, no
    /// errors, no note.
    fn unmeasured(scene: &SceneSpec, point: &Point) -> PointResult {
        PointResult {
            scene: scene.key.to_string(),
            axis: point.axis.clone(),
            label: point.label.clone(),
            settings: point.settings_text(),
            cpu_seconds: f64::NAN,
            wall_seconds: f64::NAN,
            peak_rss_bytes: 0,
            file_bytes: 0,
            elements: 0,
            vertices: 0,
            shots: 0,
            rays: 0,
            unshot_fraction: f64::NAN,
            vertex_error: None,
            vertex_unmatched: None,
            image_error: None,
            image_rmse: None,
            note: None,
            representation: None,
            truth: None,
        }
    }
}

/// The distinct representations of a solution's batches, in file order.
fn representation_text(solution: &solution::format::Solution) -> String {
    let mut parts: Vec<String> = Vec::new();
    for batch in &solution.batches {
        let text = match batch.representation {
            solution::format::Representation::Sh { order } => format!("L={order}"),
            solution::format::Representation::Cube { directions } => format!("D={directions}"),
        };
        if !parts.contains(&text) {
            parts.push(text);
        }
    }
    parts.join(", ")
}

#[derive(Serialize, Deserialize)]
struct StatsJson {
    elements: u64,
    vertices: u64,
    shots: u64,
    rays: u64,
    #[allow(dead_code)]
    seconds: f64,
    unshot_fraction: f64,
}

/// The per-scene state the points are measured against.
struct Reference {
    lookup: ReferenceLookup,
    /// The vertex-error eye in file (re-centred) coordinates.
    eye_file: DVec3,
    images: Vec<RgbImage>,
    result: PointResult,
}

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    if !args.solver.is_file() || !args.runtime.is_file() {
        bail!(
            "{} or {} is missing: run `cargo build --release -p solver -p runtime` first \
             (from the repository root)",
            args.solver.display(),
            args.runtime.display()
        );
    }
    // Other people rebuild target/release while a sweep runs; every point must
    // use the same programs, so the sweep runs private copies.
    let mut args = args;
    let bin = args.work.join("bin");
    std::fs::create_dir_all(&bin).with_context(|| format!("creating {}", bin.display()))?;
    let mut built = Vec::new();
    for (name, path) in [("solver", &mut args.solver), ("runtime", &mut args.runtime)] {
        let copy = bin.join(name);
        #[allow(clippy::disallowed_methods)]
        // A private working copy of a program (keeps its mode), not an output.
        std::fs::copy(&*path, &copy)
            .with_context(|| format!("copying {} to {}", path.display(), copy.display()))?;
        let modified = std::fs::metadata(&*path)
            .and_then(|m| m.modified())
            .ok()
            .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
            .map_or(0, |d| d.as_secs());
        built.push(format!("{name} built at Unix time {modified}"));
        *path = copy;
    }
    if std::env::var_os("VK_ICD_FILENAMES").is_none() {
        // lavapipe, as scripts/test.sh picks it, unless the caller chose a device.
        if let Some(icd) = lavapipe_icd() {
            std::env::set_var("VK_ICD_FILENAMES", icd);
        }
    }
    let help = Command::new(&args.solver)
        .args(["solve", "--help"])
        .output()
        .context("running solver solve --help")?;
    let help = String::from_utf8_lossy(&help.stdout).into_owned();
    let has_cube = help.contains("--cube-resolution");
    if !has_cube {
        println!(
            "note: `solver solve --help` lists no cube method: the global-cube (D) points are skipped"
        );
    }
    let load_before = load_average();
    let started = std::time::Instant::now();
    let mut all: Vec<report::SceneResults> = Vec::new();
    for scene in points::scenes() {
        if let Some(only) = &args.scenes {
            if !only.iter().any(|s| s == scene.key) {
                continue;
            }
        }
        let dir = args.work.join(scene.key);
        std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
        let truths = if args.no_truth {
            Vec::new()
        } else {
            let options = truth::TruthOptions {
                solver: &args.solver,
                target_error: args.truth_error,
                divisor: args.truth_divisor,
                given: &args.truth,
            };
            let mut truths = Vec::new();
            let wanted = |camera: &points::Camera| {
                let name = format!("{}/{}", scene.key, camera.name);
                args.truth_cameras
                    .as_ref()
                    .is_none_or(|only| only.contains(&name))
            };
            for camera in scene.cameras.iter().filter(|c| wanted(c)) {
                let t = truth::truth(&options, &scene, camera, &dir)?;
                println!(
                    "   truth {}: {}×{}, noise {}",
                    camera.name,
                    t.width,
                    t.height,
                    t.noise
                        .map_or("unknown".into(), |n| format!("{:.2}%", 100.0 * n))
                );
                truths.push(t);
            }
            truths
        };
        println!("== {}: reference", scene.title);
        let mut reference = reference(&args, &scene, &dir)?;
        let point_dir = dir.join(points::reference_point(&scene).id());
        attach_truth(&args, &mut reference.result, &point_dir, &truths);
        let mut results = Vec::new();
        for point in points::points(&scene, args.quick, has_cube, &help) {
            if let Some(only) = &args.axes {
                if !only.contains(&point.axis) {
                    continue;
                }
            }
            if skipped(&args.skip, scene.key, &point.label) {
                continue;
            }
            let mut result = measure(&args, &scene, &dir, &point, Some(&reference))?;
            attach_truth(&args, &mut result, &dir.join(point.id()), &truths);
            println!(
                "   {:<14} {:<34} cpu {:>7.2} s  wall {:>7.2} s  vertex err {}  image err {}  truth MARE {}{}",
                result.axis,
                result.label,
                result.cpu_seconds,
                result.wall_seconds,
                report::fmt_err(result.vertex_error),
                report::fmt_err(result.image_error),
                report::fmt_err(result.truth.as_ref().map(|t| t.mare)),
                result
                    .note
                    .as_deref()
                    .map(|n| format!("  ({n})"))
                    .unwrap_or_default()
            );
            results.push(result);
        }
        all.push(report::SceneResults {
            scene,
            results,
            reference: reference.result,
            truths,
        });
    }
    let load_after = load_average();
    let docs = args.docs.clone().unwrap_or_else(|| {
        if args.quick {
            args.work.clone()
        } else {
            PathBuf::from("docs")
        }
    });
    let notes = std::fs::read_to_string(&args.notes).unwrap_or_default();
    let machine = report::Machine {
        cpu: cpu_model(),
        cores: std::thread::available_parallelism().map_or(1, |n| n.get()),
        load_before,
        load_after,
        sweep_seconds: started.elapsed().as_secs_f64(),
        binaries: format!("{} (git HEAD {})", built.join(", "), git_head()),
        command: std::env::args().skip(1).collect::<Vec<_>>().join(" "),
    };
    report::write(&docs, &all, &machine, &notes)?;
    println!("report written to {}", docs.join("tradeoffs.md").display());
    Ok(())
}

/// Whether `--skip` leaves out the point `label` of scene `scene`.
fn skipped(skip: &[String], scene: &str, label: &str) -> bool {
    skip.iter().any(|s| match s.split_once('/') {
        Some((only, prefix)) if only == scene => label.starts_with(prefix),
        Some(_) => false,
        None => label.starts_with(s.as_str()),
    })
}

/// Compares the point's screenshots (in `point_dir`, one per camera) with the
/// truths; a point without images (a failed solve) gets none, and a failed
/// comparison is a note on the row, not the end of the sweep.
fn attach_truth(args: &Args, result: &mut PointResult, point_dir: &Path, truths: &[truth::Truth]) {
    if truths.is_empty() || result.image_error.is_none() && result.axis != "reference" {
        return;
    }
    let mut errors = Vec::new();
    for t in truths {
        let image = point_dir.join(format!("{}.exr", t.camera));
        match truth::error_against(&args.solver, &image, t) {
            Ok(e) => errors.push(e),
            Err(e) => {
                let note = format!("no truth error: {}", first_line(&e));
                result.note = Some(match result.note.take() {
                    Some(n) => format!("{n}; {note}"),
                    None => note,
                });
                return;
            }
        }
    }
    result.truth = truth::mean_error(&errors);
}

/// Solves (or loads) the scene's reference and renders its images.
fn reference(args: &Args, scene: &SceneSpec, dir: &Path) -> anyhow::Result<Reference> {
    let point = points::reference_point(scene);
    let result = measure(args, scene, dir, &point, None)?;
    let point_dir = dir.join(point.id());
    let solution = solution::format::read_solution(&point_dir.join("solution.sol"))
        .with_context(|| format!("reading the {} reference", scene.key))?;
    let offset = DVec3::from(solution.header.recentre_offset);
    let eye_file = DVec3::from(scene.vertex_eye) - offset;
    let lookup = ReferenceLookup::new(&solution, eye_file)?;
    let mut result = result;
    result.representation = Some(representation_text(&solution));
    let mut images = Vec::new();
    for camera in &scene.cameras {
        images.push(read_exr(&point_dir.join(format!("{}.exr", camera.name)))?);
    }
    if images.len() != scene.cameras.len() {
        bail!(
            "the {} reference has no images: {:?}",
            scene.key,
            result.note
        );
    }
    println!(
        "   reference: {} elements, cpu {:.1} s, wall {:.1} s",
        result.elements, result.cpu_seconds, result.wall_seconds
    );
    Ok(Reference {
        lookup,
        eye_file,
        images,
        result,
    })
}

/// Measures one point (cached by its key), comparing with `reference` when given.
fn measure(
    args: &Args,
    scene: &SceneSpec,
    dir: &Path,
    point: &Point,
    reference: Option<&Reference>,
) -> anyhow::Result<PointResult> {
    let point_dir = dir.join(point.id());
    std::fs::create_dir_all(&point_dir)?;
    if let (Some(order), Some(reference)) = (point.render_max_order, reference) {
        return truncated(args, scene, dir, &point_dir, point, order, reference);
    }
    let config = points::scene_config(scene, point)?;
    // The cameras' views, not their truths: a new truth re-compares a point's
    // images but does not re-solve it.
    let views: Vec<String> = scene.cameras.iter().map(|c| c.view_key()).collect();
    let key = format!(
        "{config}\n# flags: {:?}\n# cameras: {:?}\n",
        point.flags, views
    );
    let key_path = point_dir.join("key.txt");
    let result_path = point_dir.join("result.json");
    if !args.fresh && std::fs::read_to_string(&key_path).ok().as_deref() == Some(key.as_str()) {
        if let Ok(text) = std::fs::read_to_string(&result_path) {
            if let Ok(result) = serde_json::from_str::<PointResult>(&text) {
                return Ok(result);
            }
        }
    }
    // The config's relative paths are made absolute, so it may live anywhere.
    let config_path = point_dir.join("scene.toml");
    report::write_atomic(&config_path, &config)?;
    let solution_path = point_dir.join("solution.sol");
    let stats_path = point_dir.join("stats.json");
    let mut command = Command::new(&args.solver);
    command
        .arg("solve")
        .arg(&config_path)
        .arg("-o")
        .arg(&solution_path)
        .arg("--stats-json")
        .arg(&stats_path)
        .args(&point.flags);
    let measured = match run_measured(&mut command, &point_dir.join("solve.log")) {
        Ok(m) => m,
        // A refused point (e.g. a memory bound) is a row that says so, not the
        // end of the sweep; the reference must solve.
        Err(e) if reference.is_some() => {
            return Ok(PointResult {
                note: Some(format!("solve failed: {}", last_line(&e))),
                ..PointResult::unmeasured(scene, point)
            });
        }
        Err(e) => return Err(e),
    };
    let stats: StatsJson = serde_json::from_str(
        &std::fs::read_to_string(&stats_path)
            .with_context(|| format!("reading {}", stats_path.display()))?,
    )
    .with_context(|| format!("parsing {}", stats_path.display()))?;
    let file_bytes = std::fs::metadata(&solution_path)?.len();
    let mut result = PointResult {
        cpu_seconds: measured.cpu_seconds,
        wall_seconds: measured.wall_seconds,
        peak_rss_bytes: measured.peak_rss_bytes,
        file_bytes,
        elements: stats.elements,
        vertices: stats.vertices,
        shots: stats.shots,
        rays: stats.rays,
        unshot_fraction: stats.unshot_fraction,
        ..PointResult::unmeasured(scene, point)
    };
    let mut notes = Vec::new();
    // Images from the fixed cameras.
    let mut images = Vec::new();
    for camera in &scene.cameras {
        match screenshot(args, &solution_path, &point_dir, camera, None) {
            Ok(image) => images.push(image),
            Err(e) => {
                notes.push(format!("no image: {}", first_line(&e)));
                break;
            }
        }
    }
    if let Some(reference) = reference {
        if images.len() == reference.images.len() {
            match image_error(reference, &images) {
                Ok(e) => {
                    result.image_error = Some(e.rel_l1);
                    result.image_rmse = Some(e.rel_rmse);
                }
                Err(e) => notes.push(format!("image comparison: {e}")),
            }
        }
        let vertex = solution::format::read_solution(&solution_path)
            .map_err(anyhow::Error::from)
            .and_then(|s| {
                result.representation = Some(representation_text(&s));
                reference.lookup.vertex_error(&s, reference.eye_file)
            });
        match vertex {
            Ok(v) => {
                result.vertex_error = Some(v.stats.rel_l1);
                result.vertex_unmatched = Some(v.unmatched as f64 / v.vertices.max(1) as f64);
            }
            Err(e) => notes.push(format!("no vertex error: {}", first_line(&e))),
        }
    }
    if !notes.is_empty() {
        result.note = Some(notes.join("; "));
    }
    // The solution itself is only needed again for the reference.
    if reference.is_some() {
        std::fs::remove_file(&solution_path).ok();
    }
    // The result before its key: a point counts as done only when both exist.
    report::write_atomic(&result_path, &serde_json::to_string_pretty(&result)?)?;
    report::write_atomic(&key_path, &key)?;
    Ok(result)
}

/// A `truncation` point: the reference's solution drawn with its SH expansion
/// cut at `order`. Its cost columns are the reference's (it solves nothing);
/// its errors are what the cut alone loses.
fn truncated(
    args: &Args,
    scene: &SceneSpec,
    dir: &Path,
    point_dir: &Path,
    point: &Point,
    order: u32,
    reference: &Reference,
) -> anyhow::Result<PointResult> {
    let solution_path = dir
        .join(points::reference_point(scene).id())
        .join("solution.sol");
    let mut result = reference.result.clone();
    result.axis = point.axis.clone();
    result.label = point.label.clone();
    result.settings = format!("runtime screenshot --max-order {order}");
    let mut images = Vec::new();
    for camera in &scene.cameras {
        images.push(screenshot(
            args,
            &solution_path,
            point_dir,
            camera,
            Some(order),
        )?);
    }
    let e = image_error(reference, &images)?;
    result.image_error = Some(e.rel_l1);
    result.image_rmse = Some(e.rel_rmse);
    let solution = solution::format::read_solution(&solution_path)?;
    result.representation = Some(format!(
        "{} (drawn to L={order})",
        representation_text(&solution)
    ));
    let v = reference
        .lookup
        .vertex_error_capped(&solution, reference.eye_file, order)?;
    result.vertex_error = Some(v.stats.rel_l1);
    result.vertex_unmatched = Some(v.unmatched as f64 / v.vertices.max(1) as f64);
    result.note = None;
    Ok(result)
}

/// The relative error of `images` against the reference's, over every pixel
/// and channel of every camera in order.
fn image_error(reference: &Reference, images: &[RgbImage]) -> Result<ErrorStats, MetricError> {
    let flat = |images: &[RgbImage]| -> Vec<f64> {
        images
            .iter()
            .flat_map(|i| i.values.iter().copied())
            .collect()
    };
    relative_error(&flat(&reference.images), &flat(images))
}

fn last_line(e: &anyhow::Error) -> String {
    format!("{e:#}")
        .lines()
        .last()
        .unwrap_or_default()
        .to_string()
}

fn first_line(e: &anyhow::Error) -> String {
    format!("{e:#}")
        .lines()
        .next()
        .unwrap_or_default()
        .to_string()
}

/// Renders `solution` from `camera` with the runtime; returns the linear image.
fn screenshot(
    args: &Args,
    solution: &Path,
    dir: &Path,
    camera: &Camera,
    max_order: Option<u32>,
) -> anyhow::Result<RgbImage> {
    let prefix = dir.join(camera.name);
    let v = |a: [f64; 3]| a.map(|x| x.to_string());
    let mut command = Command::new(&args.runtime);
    command
        .arg("screenshot")
        .arg(solution)
        .arg("--mono")
        .arg("--out")
        .arg(&prefix)
        .arg("--eye")
        .args(v(camera.eye))
        .arg("--target")
        .args(v(camera.target))
        .arg("--up")
        .args(v(camera.up))
        .arg("--fov-y")
        .arg(camera.fov_y_deg.to_string())
        .arg("--size")
        .arg(format!("{}x{}", camera.width, camera.height));
    if let Some(order) = max_order {
        command.arg("--max-order").arg(order.to_string());
    }
    run_measured(&mut command, &dir.join(format!("{}.log", camera.name)))?;
    read_exr(&prefix.with_extension("exr"))
}

fn lavapipe_icd() -> Option<PathBuf> {
    let mut found: Vec<PathBuf> = std::fs::read_dir("/usr/share/vulkan/icd.d")
        .ok()?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with("lvp_icd") && n.ends_with(".json"))
        })
        .collect();
    found.sort();
    found.into_iter().next()
}

fn git_head() -> String {
    Command::new("git")
        .args(["rev-parse", "--short", "HEAD"])
        .output()
        .ok()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .filter(|s| !s.is_empty())
        .unwrap_or_else(|| "unknown".into())
}

fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|_| "unknown".into())
}

#[cfg(test)]
mod tests {
    #[test]
    fn skip_matches_label_prefixes_in_all_or_one_scene() {
        let skip = ["C7".to_string(), "glossy/--preset medium".to_string()];
        assert!(super::skipped(&skip, "cornell", "C7: n=16"));
        assert!(super::skipped(&skip, "glossy", "--preset medium"));
        assert!(!super::skipped(&skip, "cornell", "--preset medium"));
        assert!(!super::skipped(&skip, "cornell", "C6: n=16"));
        assert!(!super::skipped(&[], "cornell", "C7"));
    }
}
