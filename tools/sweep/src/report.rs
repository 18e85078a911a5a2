//! Writing `docs/tradeoffs.md` and its SVG plots from the measured points.

use crate::points::SceneSpec;
use crate::truth::Truth;
use crate::PointResult;
use anyhow::Context;
use std::fmt::Write;
use std::path::Path;
use sweep::metrics::pareto_front;
use sweep::svg::{plot, PlotPoint};

/// The machine and the sweep's own running time, for the report's header.
pub struct Machine {
    pub cpu: String,
    pub cores: usize,
    pub load_before: String,
    pub load_after: String,
    pub sweep_seconds: f64,
    /// Which solver and runtime builds this run used.
    pub binaries: String,
    /// The sweep's own arguments (empty for the full sweep).
    pub command: String,
}

/// One scene's measurements: its points, its converged reference and the
/// path-traced truth of each camera (none with `--no-truth`).
pub struct SceneResults {
    pub scene: SceneSpec,
    pub results: Vec<PointResult>,
    pub reference: PointResult,
    pub truths: Vec<Truth>,
}

/// Image-error targets of the presets, chosen on the Cornell box's front: the
/// cheapest front point at or below each target becomes that preset. draft:
/// the light's layout and colour bleeding right, shading errors visible (5%).
/// medium: about the Weber fraction of luminance discrimination (1–2%), below
/// which smooth-gradient differences are hard to see (1.5%). final: half of
/// that, within 5× of the reference's own seed-to-seed noise (0.7%).
pub const PRESET_TARGETS: [(&str, f64); 3] = [("draft", 0.05), ("medium", 0.015), ("final", 0.007)];

pub fn fmt_err(e: Option<f64>) -> String {
    match e {
        Some(e) if e.is_finite() => format!("{:.2}%", 100.0 * e),
        Some(_) => "inf".into(),
        None => "n/a".into(),
    }
}

fn mb(bytes: u64) -> String {
    format!("{:.0}", bytes as f64 / (1024.0 * 1024.0))
}

fn kb(bytes: u64) -> String {
    format!("{:.0}", bytes as f64 / 1024.0)
}

fn mrays(rays: u64) -> String {
    format!("{:.1}", rays as f64 / 1e6)
}

/// The axis whose rows re-draw the reference instead of solving; they are in
/// the tables but not on the plots or fronts (the reference's cost is not
/// theirs).
const TRUNCATION_AXIS: &str = "truncation";

/// Which error a plot or a front is of.
#[derive(Clone, Copy, PartialEq, Eq)]
enum ErrorKind {
    /// Image error against the converged solution (convergence).
    Image,
    /// Vertex error against the converged solution.
    Vertex,
    /// MARE of the images against the path-traced truth (bias plus noise).
    Truth,
}

impl ErrorKind {
    fn of(self, r: &PointResult) -> Option<f64> {
        match self {
            ErrorKind::Image => r.image_error,
            ErrorKind::Vertex => r.vertex_error,
            ErrorKind::Truth => r.truth.as_ref().map(|t| t.mare),
        }
    }
}

/// Index of the (cost, error) front of `results` by the given error.
fn front(results: &[PointResult], kind: ErrorKind) -> Vec<usize> {
    let points: Vec<(f64, f64)> = results
        .iter()
        .map(|r| {
            if r.axis == TRUNCATION_AXIS {
                return (f64::NAN, f64::NAN);
            }
            (r.cpu_seconds, kind.of(r).unwrap_or(f64::NAN))
        })
        .collect();
    pareto_front(&points)
}

fn fmt_flip(f: Option<f64>) -> String {
    f.map_or("n/a".into(), |f| format!("{f:.3}"))
}

/// The truths' paragraph of a scene's section: where each came from and its noise.
fn truth_paragraph(md: &mut String, truths: &[Truth], reference: &PointResult) {
    if truths.is_empty() {
        let _ = writeln!(
            md,
            "No path-traced truth for this scene in this run (`--no-truth`, or none of its \
             cameras in `--truth-cameras`): the truth columns are empty.\n"
        );
        return;
    }
    let _ = writeln!(
        md,
        "Path-traced truths (`solver reference`; the truth columns are the mean over these cameras, each camera alike):\n"
    );
    for t in truths {
        let _ = writeln!(
            md,
            "- `{}`: {}×{}, **own noise {}** (mean relative standard error of luminance over lit pixels); {}.",
            t.camera,
            t.width,
            t.height,
            t.noise
                .map_or("unknown".into(), |n| format!("{:.2}%", 100.0 * n)),
            t.source
        );
    }
    if let Some(e) = &reference.truth {
        let _ = writeln!(
            md,
            "\nThe converged reference itself measures MARE {} against the truths (HDR-FLIP {}, \
             mean signed error {:+.2}%): that is its own bias, which the `image err` column, \
             measured against it, cannot see.",
            fmt_err(Some(e.mare)),
            fmt_flip(e.flip),
            100.0 * e.mean_signed
        );
    }
    md.push('\n');
}

pub fn write(
    docs: &Path,
    all: &[SceneResults],
    machine: &Machine,
    notes: &str,
) -> anyhow::Result<()> {
    std::fs::create_dir_all(docs).with_context(|| format!("creating {}", docs.display()))?;
    let mut md = String::new();
    header(&mut md, all, machine);
    if !notes.trim().is_empty() {
        md.push_str(notes.trim_end());
        md.push_str("\n\n");
    }
    for SceneResults {
        scene,
        results,
        reference,
        truths,
    } in all
    {
        scene_intro(&mut md, scene, reference, truths);
        let plots = [
            (
                ErrorKind::Truth,
                "truth",
                "MARE against the path-traced truth (log)",
            ),
            (
                ErrorKind::Image,
                "image",
                "relative L1 image error against the converged solution (log)",
            ),
            (
                ErrorKind::Vertex,
                "vertex",
                "relative L1 vertex error against the converged solution (log)",
            ),
        ];
        for (error, kind, y_label) in plots {
            if error == ErrorKind::Truth && truths.is_empty() {
                continue;
            }
            let front_idx = front(results, error);
            let points: Vec<PlotPoint> = results
                .iter()
                .map(|r| PlotPoint {
                    // NaN leaves a truncation row off the plot, keeping the
                    // indices of `front_idx` valid.
                    x: if r.axis == TRUNCATION_AXIS {
                        f64::NAN
                    } else {
                        r.cpu_seconds
                    },
                    y: error.of(r).unwrap_or(f64::NAN),
                    group: r.axis.clone(),
                    label: format!("{}: {}", r.axis, r.label),
                })
                .collect();
            let name = format!("tradeoffs-{}-{kind}.svg", scene.key);
            let svg = plot(
                &format!("{}: {kind} error against CPU seconds", scene.title),
                "solver CPU seconds (log)",
                y_label,
                &points,
                &front_idx,
            );
            write_atomic(&docs.join(&name), &svg)?;
            let _ = writeln!(md, "![{kind} error against CPU seconds]({name})\n");
        }
        axis_tables(&mut md, scene, results);
        if scene.key == "cornell" {
            preset_section(&mut md, results);
        }
    }
    write_atomic(&docs.join("tradeoffs.md"), &md)
}

/// The page's title and the run's paragraphs: how it was generated, the
/// machine and its load, the programs, the truths and what each column means.
fn header(md: &mut String, all: &[SceneResults], machine: &Machine) {
    let _ = writeln!(md, "# Speed/accuracy trade-offs\n");
    let _ = writeln!(
        md,
        "Generated by `cargo run --release -p sweep{}` (tools/sweep, issue 7); the tables and \
         plots are rewritten on each run, the prose comes from `tools/sweep/notes.md`. Do not \
         edit this file by hand.\n",
        if machine.command.is_empty() {
            String::new()
        } else {
            format!(" -- {}", machine.command)
        }
    );
    let _ = writeln!(
        md,
        "Machine: {} ({} cores). Load average (1, 5, 15 min) {} before this run and {} \
         after; this run took {:.0} s (rows cached from earlier runs are not re-measured), \
         and the solves of all rows took {:.0} s of wall time when measured. Other engineers were compiling on the same cores, so \
         **wall seconds are inflated and noisy; the plots, the front and the preset choice \
         use CPU seconds** (user + system of the solver process, from `wait4`), which \
         contention changes much less.\n",
        machine.cpu,
        machine.cores,
        machine.load_before,
        machine.load_after,
        machine.sweep_seconds,
        all.iter()
            .flat_map(|SceneResults { results: rows, reference, .. }| {
                rows.iter()
                    .filter(|r| r.axis != "truncation")
                    .chain(std::iter::once(reference))
            })
            .map(|r| r.wall_seconds)
            .filter(|s| s.is_finite())
            .sum::<f64>()
    );
    let _ = writeln!(
        md,
        "This run's programs: {}. Points cached from earlier runs keep the figures of \
         the build that measured them (see the notes).\n",
        machine.binaries
    );
    let truths: Vec<String> = all
        .iter()
        .flat_map(|r| {
            r.truths.iter().map(|t| {
                format!(
                    "`{}/{}` {}×{}, noise {}",
                    r.scene.key,
                    t.camera,
                    t.width,
                    t.height,
                    t.noise
                        .map_or("unknown".into(), |n| format!("{:.2}%", 100.0 * n))
                )
            })
        })
        .collect();
    let _ = writeln!(
        md,
        "Path-traced truths of this run (`solver reference`; noise = the truth's own mean \
         relative standard error of luminance over lit pixels, details per scene below): {}.\n",
        if truths.is_empty() {
            "none".to_string()
        } else {
            truths.join("; ")
        }
    );
    let _ = writeln!(
        md,
        "Columns: **CPU s** and **wall s** of the `solver solve` process; **Mrays** \
         visibility rays traced; **peak MB** its peak resident set (`wait4` ru_maxrss, \
         this child only); **file KB** the solution file; **stored as** the solution's \
         batches (SH order L per batch, or the global cube's D); **vertex err** the \
         area-weighted relative L1 error (Σ A|L − L_ref| / Σ A|L_ref| over vertices and \
         RGB, A = a third of the area of the triangles around the vertex) of each vertex's \
         radiance toward the scene's fixed eye, the reference interpolated \
         barycentrically at the vertex on the reference mesh; **image err** / **image RMSE** the relative L1 and \
         relative RMSE over every pixel of the fixed cameras' linear EXR screenshots \
         (`runtime screenshot`, lavapipe) against the reference's. **front** marks the \
         Pareto front of (CPU s, image err) over all of the scene's points. These are \
         errors against the converged radiosity solution: **convergence**, not accuracy. \
         **MARE vs truth** / **FLIP vs truth**: the same screenshots against a path-traced \
         truth from `solver reference` (bias plus the truth's noise), by `solver compare \
         --json` as docs/accuracy.md measures them: MARE (mean absolute relative luminance \
         error over the truth's lit pixels) and HDR-FLIP, each screenshot box-filtered to \
         the truth's pixel footprints, the mean over the scene's cameras; **truth front** \
         marks the Pareto front of (CPU s, MARE vs truth). No point can measure below \
         about 0.8 × the truth's own noise (stated per scene).\n"
    );
}

/// A scene's heading, its reference and cameras, its truths and the base
/// settings every point starts from.
fn scene_intro(md: &mut String, scene: &SceneSpec, reference: &PointResult, truths: &[Truth]) {
    let _ = writeln!(md, "## {}\n", scene.title);
    let _ = writeln!(
        md,
        "Scene `{}`. Reference (`{}`): {} elements, {} vertices, {} Mrays, {:.1} CPU s, \
         {:.1} wall s, peak {} MB, file {} KB. Fixed cameras: {}. Vertex-error eye: {:?}.\n",
        scene.config,
        reference.settings,
        reference.elements,
        reference.vertices,
        mrays(reference.rays),
        reference.cpu_seconds,
        reference.wall_seconds,
        mb(reference.peak_rss_bytes),
        kb(reference.file_bytes),
        scene
            .cameras
            .iter()
            .map(|c| format!(
                "`{}` eye {:?} → {:?}, {}° × {}×{}",
                c.name, c.eye, c.target, c.fov_y_deg, c.width, c.height
            ))
            .collect::<Vec<_>>()
            .join("; "),
        scene.vertex_eye
    );
    truth_paragraph(md, truths, reference);
    let base: Vec<String> = scene.base.iter().map(|(k, v)| format!("{k}={v}")).collect();
    let _ = writeln!(
        md,
        "Every point but the presets starts from `{}` and changes what its row says.\n",
        base.join(" ")
    );
}

/// One table per axis of a scene's points, in order of first appearance, with
/// the image-error and truth fronts marked.
fn axis_tables(md: &mut String, scene: &SceneSpec, results: &[PointResult]) {
    let front_idx = front(results, ErrorKind::Image);
    let truth_front = front(results, ErrorKind::Truth);
    let mut axes: Vec<&str> = Vec::new();
    for r in results {
        if !axes.contains(&r.axis.as_str()) {
            axes.push(&r.axis);
        }
    }
    for axis in axes {
        let _ = writeln!(md, "### {} — {axis}\n", scene.key);
        let _ = writeln!(
            md,
            "| point | CPU s | wall s | Mrays | elements | peak MB | file KB | stored as | vertex err | image err | image RMSE | front | MARE vs truth | FLIP vs truth | truth front |"
        );
        let _ = writeln!(
            md,
            "|---|--:|--:|--:|--:|--:|--:|---|--:|--:|--:|:-:|--:|--:|:-:|"
        );
        for (k, r) in results.iter().enumerate().filter(|(_, r)| r.axis == axis) {
            let _ = writeln!(
                md,
                "| {}{} | {:.2} | {:.2} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                r.label,
                r.note
                    .as_deref()
                    .map(|n| format!(" ({n})"))
                    .unwrap_or_default(),
                r.cpu_seconds,
                r.wall_seconds,
                mrays(r.rays),
                r.elements,
                mb(r.peak_rss_bytes),
                kb(r.file_bytes),
                r.representation.as_deref().unwrap_or(""),
                fmt_err(r.vertex_error),
                fmt_err(r.image_error),
                fmt_err(r.image_rmse),
                if front_idx.contains(&k) { "●" } else { "" },
                fmt_err(r.truth.as_ref().map(|t| t.mare)),
                fmt_flip(r.truth.as_ref().and_then(|t| t.flip)),
                if truth_front.contains(&k) { "●" } else { "" }
            );
        }
        md.push('\n');
    }
}

/// Axes whose points a preset can express: `config/presets.toml` keeps its keys
/// (samples, thresholds, mesh), so the other methods (wallace, hemicube,
/// Gauss–Seidel) and the reference-cost floor are not candidates.
/// The `presets` rows (the shipped presets themselves) are the check, not
/// candidates.
pub const PRESET_AXES: [&str; 7] = [
    "samples",
    "mesh",
    "min_area",
    "patches",
    "threshold",
    "ladder",
    "combo",
];

/// The rule that picks presets from the Cornell box's front, and what the
/// shipped presets measured.
fn preset_section(md: &mut String, results: &[PointResult]) {
    let points: Vec<(f64, f64)> = results
        .iter()
        .map(|r| {
            if PRESET_AXES.contains(&r.axis.as_str()) {
                (r.cpu_seconds, r.image_error.unwrap_or(f64::NAN))
            } else {
                (f64::NAN, f64::NAN)
            }
        })
        .collect();
    let front_idx = pareto_front(&points);
    let _ = writeln!(md, "### Preset choice (generated)\n");
    let _ = writeln!(
        md,
        "Rule: of the points a preset can express (axes {}; analytic form factors, \
         progressive refinement), take the Pareto front of CPU s against image error; each \
         preset is the cheapest front point whose image error is at most its target. The \
         `presets` rows above are `solver solve --preset NAME` as shipped in \
         `config/presets.toml`, measured in the same run.\n",
        PRESET_AXES.join(", ")
    );
    let front_labels: Vec<String> = front_idx
        .iter()
        .map(|&k| {
            format!(
                "{} ({:.2} s, {})",
                results[k].label,
                results[k].cpu_seconds,
                fmt_err(results[k].image_error)
            )
        })
        .collect();
    let _ = writeln!(md, "Front: {}.\n", front_labels.join(" → "));
    let _ = writeln!(
        md,
        "| preset | target | chosen point | CPU s | image err | vertex err | MARE vs truth | settings | shipped preset: CPU s, image err, vertex err, MARE vs truth |"
    );
    let _ = writeln!(md, "|---|--:|---|--:|--:|--:|--:|---|---|");
    for (name, target) in PRESET_TARGETS {
        let shipped = results
            .iter()
            .find(|r| r.axis == "presets" && r.label == format!("--preset {name}"))
            .map_or("not measured".to_string(), |r| {
                format!(
                    "{:.2} s, {}, {}, {}",
                    r.cpu_seconds,
                    fmt_err(r.image_error),
                    fmt_err(r.vertex_error),
                    fmt_err(r.truth.as_ref().map(|t| t.mare))
                )
            });
        let chosen = front_idx
            .iter()
            .map(|&k| &results[k])
            .find(|r| r.image_error.is_some_and(|e| e <= target));
        match chosen {
            Some(r) => {
                let _ = writeln!(
                    md,
                    "| {name} | {} | {}: {} | {:.2} | {} | {} | {} | `{}` | {shipped} |",
                    fmt_err(Some(target)),
                    r.axis,
                    r.label,
                    r.cpu_seconds,
                    fmt_err(r.image_error),
                    fmt_err(r.vertex_error),
                    fmt_err(r.truth.as_ref().map(|t| t.mare)),
                    r.settings
                );
            }
            None => {
                let _ = writeln!(
                    md,
                    "| {name} | {} | no front point reaches it | | | | | | {shipped} |",
                    fmt_err(Some(target))
                );
            }
        }
    }
    md.push('\n');
}

/// Writes `text` to `path` through the contract crate's one atomic writer.
pub(crate) fn write_atomic(path: &Path, text: &str) -> anyhow::Result<()> {
    solution::atomic::write_bytes_atomically(path, text.as_bytes())
        .with_context(|| format!("writing {}", path.display()))
}
