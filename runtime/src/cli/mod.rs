//! The `runtime` command line: `screenshot` and `bench`, and what all four
//! commands share (`mirror` and `xr` live in their own modules): every one
//! opens its file with [`open_solution`] (mapped, `--max-frame-cost` checked)
//! and uploads it with `StereoRenderer::from_mapped`.

mod bench;
mod output;
mod screenshot;
mod timings;

pub use bench::{BenchArgs, BenchReport};
pub use output::{write_exr, write_png};
pub use screenshot::ScreenshotArgs;
pub use timings::Timings;

use anyhow::{bail, Context, Result};
use clap::{Parser, Subcommand};
use std::path::Path;

#[derive(Parser, Debug)]
#[command(
    name = "runtime",
    version,
    about = "Renders a radiosity solution file in stereo with Vulkan (offscreen screenshots, benchmarks)."
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Renders one stereo pair (or one mono image) to PNG (exposed, sRGB) and EXR
    /// (linear radiance).
    #[command(after_help = DEFAULT_VIEW_HELP)]
    Screenshot(ScreenshotArgs),
    /// Renders offscreen stereo frames along a scripted walk and prints timings.
    Bench(BenchArgs),
    /// Walks through the solution in a headset (OpenXR); without a runtime it
    /// says so and suggests `runtime mirror`.
    #[command(after_help = DEFAULT_VIEW_HELP)]
    Xr(crate::xr::cli::XrArgs),
    /// Shows the solution in a desktop window, both eyes side by side (or one
    /// eye, or anaglyph), with radview's keys (F1 lists them).
    #[command(after_help = DEFAULT_VIEW_HELP)]
    Mirror(crate::mirror::MirrorArgs),
}

/// How the first view is chosen, for `--help` of `screenshot`, `mirror` and
/// `xr`. The figures are `solution::view`'s constants (checked by a test).
pub const DEFAULT_VIEW_HELP: &str = "\
The view: the solution header's camera (screenshot and mirror: unless --eye, --target,
--up or --fov-y are given).
When the scene named no camera, the solver chose that camera when it solved
(solver::view): 49 candidate eyes (a jittered 4x4x3 grid over the bounds and its
centre), each stood 1.6 m (x units_per_metre; at most 0.7 of the floor-to-ceiling
height) above the floor a downward ray meets; of those whose 128 survey rays meet
at least 75% front faces, at most 10% back faces and nothing within 0.3 m, the one
standing upright that sees the most light, looking level toward the brightest,
farthest-seen heading (60 degree field of view). If none passes, the camera frames
the bounds from outside. xr: LOCAL space puts the head at that eye; STAGE space
puts the floor camera_eye_height_m (default 1.6 m) below it, on the floor found.";

/// Runs a parsed command line.
pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Screenshot(args) => screenshot::run(&args),
        Command::Bench(args) => bench::run(&args).map(|_| ()),
        Command::Xr(args) => crate::xr::cli::run(args),
        Command::Mirror(args) => crate::mirror::run(&args),
    }
}

/// Options shared by the commands that render.
#[derive(clap::Args, Debug, Clone)]
pub struct RenderOptions {
    /// Cap on the SH order evaluated; bands above it are dropped and the error
    /// that costs (Parseval) is printed per batch.
    #[arg(long, value_name = "L")]
    pub max_order: Option<u32>,
    /// Exposure offset in stops (EV): radiance is multiplied by 2^E before
    /// the tone curve, on top of the file's automatic exposure (a file with
    /// lights stores its log-average radiance, shown at the key value 0.18;
    /// a file without is drawn at 0 EV) (PNG only; the EXR holds unexposed
    /// radiance).
    #[arg(
        long,
        value_name = "E",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    pub exposure: f32,
    /// Tone curve after exposure [default: aces for a file with lights (a
    /// physically lit scene), clamp for any other].
    #[arg(long, value_enum)]
    pub tonemap: Option<crate::render::ToneCurve>,
    /// Most samples per pixel (MSAA); the device may allow fewer; 1 turns it off.
    #[arg(long, value_name = "N", default_value_t = 4)]
    pub samples: u32,
    /// How the two eyes are drawn (auto: one pass per view on lavapipe, whose
    /// multiview clipping is broken; a single multiview pass elsewhere).
    #[arg(long, value_enum, default_value_t = crate::render::MultiviewMode::Auto)]
    pub multiview: crate::render::MultiviewMode,
    /// Enable the Vulkan validation layer (also: RUNTIME_VALIDATION=1).
    #[arg(long)]
    pub validation: bool,
    /// Refuse files whose per-view cost, Σ vertices × basis terms per vertex
    /// ((L+1)² for SH, 4 for a global cube), exceeds N. What it trades: the
    /// default (10⁸, seconds per frame on lavapipe) keeps a crafted or huge file
    /// from stalling the GPU for seconds or longer — a watchdog may reset the
    /// device — while a larger N lets big solutions load on fast GPUs.
    #[arg(long, value_name = "N", default_value_t = solution::format::DEFAULT_MAX_FRAME_COST)]
    pub max_frame_cost: u64,
    /// Print on stderr how long each stage took, from the command's start to
    /// the first frame submitted (open, validate, upload, ...).
    #[arg(long)]
    pub timings: bool,
    /// Draw every chunk of every batch, without testing it against the eyes'
    /// frusta (for measuring what culling saves; the image is the same).
    #[arg(long)]
    pub no_cull: bool,
    /// The most triangles per spatial chunk, the unit that culling keeps or
    /// drops. What it trades: smaller chunks fit the frusta closer (fewer
    /// triangles drawn) but cost one box test and up to one draw each and a
    /// longer partition at load; larger ones the reverse.
    #[arg(long, value_name = "N", default_value_t = crate::render::cull::DEFAULT_CHUNK_TRIANGLES,
          value_parser = clap::value_parser!(u32).range(1..))]
    pub chunk_triangles: u32,
}

impl RenderOptions {
    /// The renderer's culling settings from `--no-cull` and `--chunk-triangles`.
    pub fn culling(&self) -> crate::render::Culling {
        crate::render::Culling {
            enabled: !self.no_cull,
            chunk_triangles: self.chunk_triangles,
        }
    }

    /// The tone a file is shown with: its automatic exposure plus
    /// `--exposure`, through `--tonemap` or the file's default curve
    /// ([`crate::render::file_tone`]).
    pub fn tone(
        &self,
        lighting: Option<&solution::format::Lighting>,
    ) -> crate::render::ToneSettings {
        crate::render::file_tone(lighting, self.exposure, self.tonemap)
    }

    pub fn check(&self) -> Result<()> {
        if !(self.exposure.is_finite() && self.exposure.abs() <= 64.0) {
            bail!(
                "--exposure {} must be a finite number of stops in -64..=64",
                self.exposure
            );
        }
        Ok(())
    }
}

/// `--size WxH`: the contract crate's parser, shared with `solver reference`.
pub use solution::camera::parse_image_size as parse_size;

/// Maps and validates a solution file for [`StereoRenderer::from_mapped`]:
/// every check but the CRC-32 of the batches' sections, which the upload
/// computes as it streams them and refuses the file on (naming file, batch and
/// section). Coefficients are stored on the GPU as the file stores them.
///
/// [`StereoRenderer::from_mapped`]: crate::render::StereoRenderer::from_mapped
///
/// Files whose per-view cost (`solution::format::frame_cost`) exceeds
/// `max_frame_cost` are refused with the format's message naming the flag.
pub fn open_solution(path: &Path, max_frame_cost: u64) -> Result<solution::format::MappedSolution> {
    use solution::format::{check_frame_cost, frame_cost, MappedSolution};
    let file = MappedSolution::open_deferring_checksums(path).map_err(anyhow::Error::new)?;
    check_frame_cost(path, frame_cost(file.batches()), max_frame_cost)
        .map_err(anyhow::Error::new)?;
    Ok(file)
}

/// Creates the GPU context, reporting a missing device with the packages to
/// install.
pub fn open_gpu(validation: bool) -> Result<crate::gpu::Gpu> {
    crate::gpu::Gpu::new(&crate::gpu::GpuDesc { validation }).context("cannot start Vulkan")
}

/// [`report_truncation`] for a mapped file. Only with `--max-order`: the
/// Parseval error needs every coefficient, so the file is decoded in memory
/// for it (the upload itself never is).
pub fn report_truncation_mapped(file: &solution::format::MappedSolution, cap: Option<u32>) {
    if cap.is_some() {
        // Only a texture that does not decode can fail here; the upload
        // reports it with the file's name, so the report is simply skipped.
        if let Ok(solution) = file.to_solution() {
            report_truncation(&solution, cap);
        }
    }
}

/// Prints what a `--max-order` cap costs, per batch.
pub fn report_truncation(solution: &solution::format::Solution, cap: Option<u32>) {
    if let Some(cap) = cap {
        let lines = crate::render::truncation::truncation_report(&solution.batches, cap);
        if lines.is_empty() {
            eprintln!("--max-order {cap}: no batch has a higher order; nothing dropped");
        }
        for line in lines {
            eprintln!("--max-order {cap}: {line}");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::DEFAULT_VIEW_HELP;
    use solution::view as v;

    /// The help states the chooser's figures; if a constant changes, so must
    /// the text.
    #[test]
    fn the_default_view_help_states_the_choosers_figures() {
        let grid = format!("{}x{}x{}", v::GRID[0], v::GRID[1], v::GRID[2]);
        let candidates = format!("{} candidate", v::GRID.iter().product::<usize>() + 1);
        let figures = [
            grid,
            candidates,
            format!("{} m (x units_per_metre", v::EYE_HEIGHT_M),
            format!("at most {} of the floor", v::EYE_HEIGHT_FRACTION),
            format!("{} survey rays", v::RAYS),
            format!("{}% front", v::MIN_FRONT_FRACTION * 100.0),
            format!("{}% back", v::MAX_BACK_FRACTION * 100.0),
            format!("within {} m", v::MIN_CLEARANCE_M),
            format!("({} degree", v::FOV_Y_DEG),
        ];
        for figure in figures {
            assert!(DEFAULT_VIEW_HELP.contains(&figure), "{figure}");
        }
    }
}
