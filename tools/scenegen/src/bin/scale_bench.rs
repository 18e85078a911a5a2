//! `scale-bench`: solves the scale scenes (families × sizes × presets) with
//! the release solver and records cost and growth (issue 13).

// Shipped code: Clippy checks clippy.toml's lists here (ARCHITECTURE.md's invariants).
#![cfg_attr(not(test), warn(clippy::disallowed_methods, clippy::disallowed_macros))]
#![cfg_attr(not(test), warn(clippy::too_many_lines))]

use anyhow::{bail, Context};
use clap::Parser;
use scenegen::bench::{report, run, write_reports, Config};
use scenegen::Family;
use std::path::PathBuf;
use std::time::Duration;

/// Generates each family at each size, runs `solver solve --preset P` on it
/// under a wall-clock limit, and writes OUT/scale.csv, OUT/scale.md (the table
/// and the log–log growth slopes from 10k triangles up) and OUT/scale-cpu.svg,
/// OUT/scale-rss.svg. Runs at the limit get Ctrl-C (SIGINT): the solver saves
/// its progress, which is recorded as "> limit".
#[derive(Parser)]
#[command(name = "scale-bench", version)]
struct Args {
    /// The solver binary to measure (build it with `cargo build --release -p solver`).
    #[arg(long, default_value = "target/release/solver")]
    solver: PathBuf,
    /// Families, comma-separated (default all three).
    #[arg(long, value_enum, value_delimiter = ',', default_values_t = Family::ALL.to_vec())]
    families: Vec<Family>,
    /// Triangle counts, comma-separated. Larger scenes take much longer (the
    /// current solver's cost grows faster than linearly) and more disk.
    #[arg(long, value_delimiter = ',', default_values_t = vec![1_000, 10_000, 100_000, 1_000_000])]
    sizes: Vec<usize>,
    /// Presets, comma-separated: draft, medium, final.
    #[arg(long, value_delimiter = ',', default_values_t = vec!["draft".to_owned(), "medium".to_owned(), "final".to_owned()])]
    presets: Vec<String>,
    /// Wall-clock limit per run, seconds: the runs beyond it are recorded with
    /// the progress they reached. Lower it for a quick look; the issue's
    /// figures use 1800.
    #[arg(long, default_value_t = 1800)]
    limit_s: u64,
    /// Seconds a stopped solver may take to finish its shot and save before
    /// it is killed (its stats are then missing).
    #[arg(long, default_value_t = 120)]
    grace_s: u64,
    /// Solver threads (default: the solver's, every core).
    #[arg(long)]
    threads: Option<u32>,
    /// Seed of the Cornell boxes' layout.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Folder for the reports.
    #[arg(long, default_value = "target/scale")]
    out: PathBuf,
    /// Scratch folder for scenes and solutions (one subfolder per run, removed
    /// after it unless --keep). A 1M-triangle scene and its solution take
    /// a few hundred MB.
    #[arg(long)]
    work: Option<PathBuf>,
    /// Keep each run's scene, solution and solver log.
    #[arg(long)]
    keep: bool,
    /// One more argument for every `solver solve`, repeatable and passed in
    /// order after the preset: `--solver-arg=--shooters --solver-arg=patch`
    /// compares the shooting methods, `--solver-arg=--max-shots
    /// --solver-arg=200` measures the cost per shot of scenes too large to
    /// solve in full. Record them with the figures: the table does not show
    /// them.
    #[arg(long = "solver-arg", allow_hyphen_values = true)]
    solver_args: Vec<String>,
    /// Run nothing: merge these scale.csv files (comma-separated, in order)
    /// into one set of reports in --out.
    #[arg(long, value_delimiter = ',')]
    merge: Vec<PathBuf>,
}

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    if !args.merge.is_empty() {
        let mut rows = Vec::new();
        for path in &args.merge {
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("reading {}", path.display()))?;
            rows.extend(
                report::parse_csv(&text).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?,
            );
        }
        write_reports(&args.out, &rows)?;
        println!("{}", report::markdown(&rows));
        return Ok(());
    }
    if !args.solver.exists() {
        bail!(
            "{} does not exist: build it with `cargo build --release -p solver` or pass --solver",
            args.solver.display()
        );
    }
    for p in &args.presets {
        if !["draft", "medium", "final"].contains(&p.as_str()) {
            bail!("--presets: unknown preset `{p}` (draft, medium, final)");
        }
    }
    let work_dir = args.work.unwrap_or_else(|| {
        std::env::temp_dir().join(format!("scale-bench-{}", std::process::id()))
    });
    let config = Config {
        solver: args.solver,
        families: args.families,
        sizes: args.sizes,
        presets: args.presets,
        limit: Duration::from_secs(args.limit_s),
        grace: Duration::from_secs(args.grace_s),
        threads: args.threads,
        seed: args.seed,
        out_dir: args.out.clone(),
        work_dir: work_dir.clone(),
        keep: args.keep,
        solver_args: args.solver_args,
    };
    let rows = run(&config).context("running the scale benchmark")?;
    if !args.keep {
        std::fs::remove_dir_all(&work_dir).ok();
    }
    println!("{}", report::markdown(&rows));
    eprintln!("scale-bench: reports in {}", args.out.display());
    Ok(())
}
