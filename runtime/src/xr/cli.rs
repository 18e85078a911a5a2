//! `runtime xr SOLUTION [--frames N]`: walk through a solution in a headset.
//!
//! Without an OpenXR runtime (or without a headset) the command says so in one
//! line, suggests `runtime mirror`, and exits non-zero. With `--frames N` the
//! session ends cleanly (the runtime is asked to exit, and the frame loop runs
//! until it agrees) after N frames submitted with rendered views; the command
//! then prints the count and the median and 99th-percentile frame times, so
//! scripts can check the real path against any conformant runtime.

use super::config::XrConfig;
use super::lifecycle::ExitReason;
use super::session::XrSession;
use super::system::{quiet_loader_log, XrSystem};
use super::vulkan::create_gpu;
use crate::cli::{open_solution, report_truncation_mapped, RenderOptions};
use crate::gpu::Gpu;
use crate::render::{RendererDesc, StereoRenderer};
use crate::session::{run_frame, Session};
use anyhow::{bail, Context, Result};
use solution::format::MappedSolution;
use std::path::PathBuf;
use std::time::Instant;

#[derive(clap::Args, Debug, Clone)]
pub struct XrArgs {
    /// The solution file.
    pub solution: PathBuf,
    /// End the session cleanly after N frames submitted with rendered views,
    /// and print the frame-time figures.
    #[arg(long, value_name = "N")]
    pub frames: Option<u64>,
    /// Comfort settings (default: config/xr.toml when it exists, else the
    /// built-in values that file states).
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    #[command(flatten)]
    pub render: RenderOptions,
}

/// Everything a headset walkthrough holds, in teardown order: fields drop in
/// declaration order, so the OpenXR session's handles go first, then the
/// renderer (which waits on its fence, then destroys its Vulkan objects newest
/// first), then the GPU context (device, then instance; the session's and
/// renderer's references to it are gone by then), and the OpenXR instance
/// last.
pub struct XrApp {
    pub session: XrSession,
    pub renderer: StereoRenderer,
    pub gpu: Gpu,
    pub system: XrSystem,
}

/// Frame-time figures of a run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameStats {
    pub frames: u64,
    pub median_ms: f64,
    pub p99_ms: f64,
}

/// The `p`-th percentile of sorted samples (nearest rank).
pub fn percentile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return 0.0;
    }
    let rank = (p / 100.0 * (sorted.len() - 1) as f64).round() as usize;
    sorted[rank.min(sorted.len() - 1)]
}

/// Median and 99th percentile of frame times in milliseconds.
pub fn frame_stats(times_ms: &[f64]) -> FrameStats {
    let mut sorted = times_ms.to_vec();
    sorted.sort_by(f64::total_cmp);
    FrameStats {
        frames: sorted.len() as u64,
        median_ms: percentile(&sorted, 50.0),
        p99_ms: percentile(&sorted, 99.0),
    }
}

fn renderer_desc(args: &XrArgs, file: &MappedSolution, width: u32, height: u32) -> RendererDesc {
    RendererDesc {
        width,
        height,
        max_samples: args.render.samples,
        // Auto: the per-view path on lavapipe (its multiview clipping bug
        // spoils XR swapchain images too), a single pass elsewhere.
        multiview: args.render.multiview,
        max_order: args.render.max_order,
        tone: args.render.tone(file.lighting()),
        culling: args.render.culling(),
    }
}

fn new_renderer(
    args: &XrArgs,
    gpu: &Gpu,
    file: &MappedSolution,
    session: &XrSession,
) -> Result<StereoRenderer> {
    let swapchain = session.swapchain();
    let desc = renderer_desc(args, file, swapchain.width, swapchain.height);
    StereoRenderer::from_mapped(gpu, file, desc, &swapchain).context("cannot prepare the renderer")
}

/// Runs `runtime xr`.
pub fn run(args: XrArgs) -> Result<()> {
    args.render.check()?;
    if args.frames == Some(0) {
        bail!("--frames must be at least 1");
    }
    let config = XrConfig::load_or_default(args.config.as_deref())?;
    // Mapped, not read: the upload streams it as stored. It stays mapped for
    // the session, since a lost session's new swapchain needs a new renderer.
    let file = open_solution(&args.solution, args.render.max_frame_cost)?;
    report_truncation_mapped(&file, args.render.max_order);

    quiet_loader_log();
    let system = XrSystem::new()?;
    eprintln!(
        "runtime xr: {} (OpenXR {}), {}x{} per eye",
        system.runtime, system.api_version, system.width, system.height
    );
    let gpu = create_gpu(&system, args.render.validation)?;
    let mut session = XrSession::new(&system, &gpu, file.header(), config)?;
    session.prepare_overlay(&gpu);
    let renderer = new_renderer(&args, &gpu, &file, &session)?;
    let mut app = XrApp {
        session,
        renderer,
        gpu,
        system,
    };

    let mut generation = app.session.swapchain_generation();
    let mut times_ms = Vec::new();
    let mut exit_asked = false;
    while !app.session.should_exit() {
        if app.session.swapchain_generation() != generation {
            // A lost session was recreated with a new swapchain.
            app.renderer = new_renderer(&args, &app.gpu, &file, &app.session)?;
            app.session.prepare_overlay(&app.gpu);
            generation = app.session.swapchain_generation();
        }
        // The file's automatic exposure, `--exposure` and the stick's steps.
        let offset = args.render.exposure + app.session.exposure_offset_stops();
        app.renderer.set_tone(crate::render::file_tone(
            file.lighting(),
            offset,
            args.render.tonemap,
        ));
        let start = Instant::now();
        let report = run_frame(&mut app.session, &mut app.renderer)?;
        if report.image.is_some() {
            times_ms.push(start.elapsed().as_secs_f64() * 1e3);
        }
        if let Some(n) = args.frames {
            if !exit_asked && app.session.counts().with_layers >= n {
                app.session.request_exit()?;
                exit_asked = true;
            }
        }
    }

    let stats = frame_stats(&times_ms);
    let counts = app.session.counts();
    println!(
        "frames submitted: {} (plus {} without views); frame time median {:.2} ms, p99 {:.2} ms",
        counts.with_layers, counts.empty, stats.median_ms, stats.p99_ms
    );
    // A handle that outlives the device: teardown messages count too.
    let log = app.gpu.validation_log_handle();
    let reason = app.session.exit_reason();
    drop(app);
    let log = log.count();
    match reason {
        Some(ExitReason::Requested) | Some(ExitReason::RuntimeExiting) | None => {}
        Some(ExitReason::InstanceLost) => bail!("the OpenXR runtime went away (instance lost)"),
        Some(ExitReason::SessionLost) => {
            bail!("the OpenXR session was lost and could not be created again")
        }
    }
    anyhow::ensure!(log == 0, "{log} Vulkan validation messages (printed above)");
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_by_nearest_rank() {
        let times: Vec<f64> = (1..=100).map(f64::from).rev().collect();
        let s = frame_stats(&times);
        // Ranks round((p/100)·99): the 50th is index 50 (value 51), the 99th
        // index 98 (value 99).
        assert_eq!(s.frames, 100);
        assert_eq!(s.median_ms, 51.0);
        assert_eq!(s.p99_ms, 99.0);
        assert_eq!(frame_stats(&[]).median_ms, 0.0);
        assert_eq!(frame_stats(&[7.0]).p99_ms, 7.0);
    }
}
