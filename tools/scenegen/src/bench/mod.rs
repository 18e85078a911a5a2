//! The scale benchmark: for each family × size × preset, generate the scene
//! into a scratch folder, run the release `solver solve` on it under a
//! wall-clock limit, and record its cost (wall and CPU seconds and peak RSS by
//! wait4, the solver's own --stats-json counts, file sizes), then the growth
//! slopes and log–log plots ([`report`], [`svg`]).

pub mod child;
pub mod report;
pub mod svg;

use crate::scene::write_scene;
use crate::{generate, Family};
use anyhow::Context;
use child::{run_limited, Ending};
use report::{Row, Status};
use solution::atomic::write_atomically;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

/// The solver's exit code after Ctrl-C (SIGINT): progress saved.
const EXIT_INTERRUPTED: i32 = 130;
/// `solver solve`'s status when it stopped at its shot cap above the threshold.
const EXIT_SHOT_CAP: i32 = 4;

#[derive(Clone, Debug)]
pub struct Config {
    pub solver: PathBuf,
    pub families: Vec<Family>,
    pub sizes: Vec<usize>,
    pub presets: Vec<String>,
    pub limit: Duration,
    pub grace: Duration,
    pub threads: Option<u32>,
    pub seed: u64,
    /// Where scale.csv, scale.md and the plots go.
    pub out_dir: PathBuf,
    /// Scratch space for scenes and solutions (one folder per run).
    pub work_dir: PathBuf,
    /// Keep each run's folder (scene, solution, log) instead of deleting it.
    pub keep: bool,
    /// More arguments for every `solver solve` (after the preset, so they
    /// override it): `--shooters patch`, `--max-shots 200`.
    pub solver_args: Vec<String>,
}

/// Runs every point, rewriting the reports after each so that a long
/// benchmark stopped half-way keeps what it measured.
pub fn run(config: &Config) -> anyhow::Result<Vec<Row>> {
    let mut rows = Vec::new();
    for &family in &config.families {
        for &size in &config.sizes {
            for preset in &config.presets {
                eprintln!("scale-bench: {} {size} {preset} …", family.name());
                let row = run_point(config, family, size, preset)?;
                eprintln!(
                    "scale-bench: {} {} triangles {preset}: {}, {:.1} s wall, {:.1} s CPU, {:.0} MiB peak",
                    row.family,
                    row.triangles,
                    row.status.label(),
                    row.wall_seconds,
                    row.cpu_seconds,
                    row.peak_rss_bytes as f64 / (1024.0 * 1024.0)
                );
                rows.push(row);
                write_reports(&config.out_dir, &rows)?;
            }
        }
    }
    Ok(rows)
}

fn run_point(config: &Config, family: Family, size: usize, preset: &str) -> anyhow::Result<Row> {
    let dir = config
        .work_dir
        .join(format!("{}-{size}-{preset}", family.name()));
    if dir.exists() {
        std::fs::remove_dir_all(&dir).with_context(|| format!("clearing {}", dir.display()))?;
    }
    let scene = generate(family, size, config.seed)?;
    let paths = write_scene(&scene, &dir, family.name())?;
    let out = dir.join("scene.sol");
    let checkpoint = dir.join("scene.sol.checkpoint");
    let stats_path = dir.join("stats.json");
    let log = dir.join("solver.log");
    let mut command = Command::new(&config.solver);
    command
        .arg("solve")
        .arg(&paths.toml)
        .arg("--out")
        .arg(&out)
        .args(["--preset", preset])
        .arg("--stats-json")
        .arg(&stats_path);
    if let Some(t) = config.threads {
        command.args(["--threads", &t.to_string()]);
    }
    command.args(&config.solver_args);
    let measured = run_limited(&mut command, &log, config.limit, config.grace, &checkpoint)?;
    let log_text = std::fs::read_to_string(&log).unwrap_or_default();
    let status = match (measured.ending, measured.hit_limit) {
        (Ending::Exited(EXIT_SHOT_CAP), _) => Status::ShotBudget,
        // A solver from before that status said so with status 0.
        (Ending::Exited(0), _) if log_text.contains("stopped after") => Status::ShotBudget,
        (Ending::Exited(0), _) => Status::Converged,
        (Ending::Exited(EXIT_INTERRUPTED), true) | (Ending::Signalled(_), true) => {
            Status::OverLimit(config.limit.as_secs_f64())
        }
        (ending, _) => {
            let last = log_text.lines().last().unwrap_or("").to_owned();
            Status::Failed(format!("{ending:?}: {last}"))
        }
    };
    let stats: Option<serde_json::Value> = std::fs::read(&stats_path)
        .ok()
        .and_then(|b| serde_json::from_slice(&b).ok());
    let count = |key: &str| stats.as_ref().and_then(|s| s[key].as_u64());
    let row = Row {
        family: family.name().to_owned(),
        target: size,
        triangles: scene.mesh.triangle_count(),
        preset: preset.to_owned(),
        status,
        wall_seconds: measured.wall_seconds,
        cpu_seconds: measured.cpu_seconds,
        peak_rss_bytes: measured.peak_rss_bytes,
        elements: count("elements"),
        vertices: count("vertices"),
        shots: count("shots"),
        rays: count("rays"),
        unshot_fraction: stats.as_ref().and_then(|s| s["unshot_fraction"].as_f64()),
        solution_bytes: std::fs::metadata(&out).ok().map(|m| m.len()),
        checkpoint_bytes: measured.watched_peak_bytes,
    };
    if !config.keep {
        std::fs::remove_dir_all(&dir).with_context(|| format!("removing {}", dir.display()))?;
    }
    Ok(row)
}

/// scale.csv, scale.md (the table and the growth slopes) and the two plots.
pub fn write_reports(out_dir: &Path, rows: &[Row]) -> anyhow::Result<()> {
    std::fs::create_dir_all(out_dir).with_context(|| format!("creating {}", out_dir.display()))?;
    let series = |value: &dyn Fn(&Row) -> f64| -> Vec<svg::Series> {
        let mut out: Vec<svg::Series> = Vec::new();
        for r in rows
            .iter()
            .filter(|r| !matches!(r.status, Status::Failed(_)))
        {
            let name = format!("{} {}", r.family, r.preset);
            let point = svg::Point {
                x: r.triangles as f64,
                y: value(r),
                finished: r.status.finished(),
            };
            match out.iter_mut().find(|s| s.name == name) {
                Some(s) => s.points.push(point),
                None => out.push(svg::Series {
                    name,
                    points: vec![point],
                }),
            }
        }
        out
    };
    let cpu = svg::plot(
        "CPU seconds of solver solve",
        "triangles",
        "CPU s",
        &series(&|r| r.cpu_seconds),
    );
    let rss = svg::plot(
        "Peak resident set of solver solve",
        "triangles",
        "peak RSS, MiB",
        &series(&|r| r.peak_rss_bytes as f64 / (1024.0 * 1024.0)),
    );
    for (name, text) in [
        ("scale.csv", report::csv(rows)),
        ("scale.md", report::markdown(rows)),
        ("scale-cpu.svg", cpu),
        ("scale-rss.svg", rss),
    ] {
        let path = out_dir.join(name);
        write_atomically(&path, |f| f.write_all(text.as_bytes()))
            .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}
