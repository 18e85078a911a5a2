//! `runtime bench`: offscreen stereo frames through the mock session.

use super::{
    open_gpu, open_solution, parse_size, report_truncation_mapped, RenderOptions, Timings,
};
use crate::render::{CullStats, DrawKind, GpuScene, RendererDesc, StereoRenderer};
use crate::session::{run_frame, HeadPath, MockDesc, MockSession, Session};
use anyhow::Result;
use glam::DVec3;
use serde::Serialize;
use std::path::PathBuf;
use std::time::Instant;

#[derive(clap::Args, Debug, Clone)]
pub struct BenchArgs {
    /// The solution file.
    pub solution: PathBuf,
    /// Stereo frames to time (after the warm-up frames).
    #[arg(long, value_name = "N", default_value_t = 60)]
    pub frames: u32,
    /// Untimed frames first (pipeline and cache warm-up).
    #[arg(long, value_name = "N", default_value_t = 3)]
    pub warmup: u32,
    /// Image size per eye, WIDTHxHEIGHT.
    #[arg(long, value_name = "WxH", value_parser = parse_size, default_value = "1024x1024")]
    pub size: (u32, u32),
    /// Head path (`t x y z yaw pitch` per line, scene coordinates, degrees);
    /// default: an orbit around the scene at the header camera's eye height.
    #[arg(long, value_name = "FILE")]
    pub walk: Option<PathBuf>,
    /// Interpupillary distance, metres.
    #[arg(long, value_name = "METRES", default_value_t = 0.064)]
    pub ipd: f64,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub render: RenderOptions,
}

/// What `runtime bench` measures.
#[derive(Clone, Debug, Serialize)]
pub struct BenchReport {
    /// Median and 99th-percentile wall time per stereo frame (record, submit and
    /// wait for the GPU), milliseconds.
    pub median_ms: f64,
    pub p95_ms: f64,
    pub p99_ms: f64,
    pub frames: u32,
    pub width: u32,
    pub height: u32,
    pub vertices: u64,
    pub triangles: u64,
    /// Vertex SH evaluations (one per vertex per eye, any order) per second at
    /// the median frame time.
    pub sh_evals_per_second: f64,
    /// Basis-function terms summed over vertices and eyes, per second: `(L+1)²`
    /// for an SH vertex, the 4 bilinear taps for a global-cube vertex.
    pub sh_terms_per_second: f64,
    pub device: String,
    pub multiview: String,
    pub samples: u32,
    pub coefficients: String,
    pub max_order: Option<u32>,
    /// Whether chunks were culled against the eyes' frusta (`--no-cull`), and
    /// the chunk size.
    pub culling: bool,
    pub chunk_triangles: u32,
    /// Chunks and triangles drawn per stereo frame (summed over its passes:
    /// the per-view path counts each eye's pass), averaged over the timed
    /// frames, against the totals of those passes.
    pub chunks_drawn: f64,
    pub chunks: u64,
    pub triangles_drawn: f64,
    pub triangles_per_frame: u64,
    /// Draw calls per stereo frame, averaged (neighbouring visible chunks merge).
    pub draws: f64,
}

fn percentile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return 0.0;
    }
    let rank = (p / 100.0 * (sorted.len() - 1) as f64).round() as usize;
    sorted[rank.min(sorted.len() - 1)]
}

pub fn run(args: &BenchArgs) -> Result<BenchReport> {
    let mut timings = Timings::start();
    args.render.check()?;
    anyhow::ensure!(args.frames > 0, "--frames must be at least 1");
    let file = open_solution(&args.solution, args.render.max_frame_cost)?;
    timings.stage("open and validate");
    report_truncation_mapped(&file, args.render.max_order);
    let header = file.header();
    let offset = DVec3::from(header.recentre_offset);
    let path = head_path(args, header)?;
    let (width, height) = args.size;
    let gpu = open_gpu(args.render.validation)?;
    let total = u64::from(args.warmup + args.frames);
    let mut session = MockSession::new(
        &gpu,
        MockDesc {
            width,
            height,
            images: 3,
            path,
            ipd_m: args.ipd,
            units_per_metre: header.units_per_metre,
            up_axis: header.up_axis,
            recentre_offset: offset,
            fov_y_deg: header.camera.fov_y_deg,
            frame_rate: 90.0,
            frames: Some(total),
        },
    )?;
    let desc = RendererDesc {
        width,
        height,
        max_samples: args.render.samples,
        multiview: args.render.multiview,
        max_order: args.render.max_order,
        tone: args.render.tone(file.lighting()),
        culling: args.render.culling(),
    };
    let mut renderer = StereoRenderer::from_mapped(&gpu, &file, desc, &session.swapchain())?;
    timings.stage("vulkan and renderer");
    timings.upload(renderer.upload_time(), renderer.upload_stats());
    let (mut times, kept) = time_frames(&mut session, &mut renderer, args.warmup)?;
    let timed = times.len().max(1) as f64;
    if args.render.timings {
        eprintln!("{}", timings.line(renderer.first_submit()));
    }
    times.sort_by(f64::total_cmp);
    let median_ms = percentile(&times, 50.0);
    let p95_ms = percentile(&times, 95.0);
    let p99_ms = percentile(&times, 99.0);
    let scene = renderer.scene();
    let (evals, terms) = evaluations_per_frame(scene);
    let per_second = |count: u64| {
        if median_ms > 0.0 {
            count as f64 / (median_ms / 1e3)
        } else {
            0.0
        }
    };
    let report = BenchReport {
        median_ms,
        p95_ms,
        p99_ms,
        frames: args.frames,
        width,
        height,
        vertices: scene.vertex_count,
        triangles: scene.triangle_count,
        sh_evals_per_second: per_second(evals),
        sh_terms_per_second: per_second(terms),
        device: gpu.info.describe(),
        multiview: format!("{:?}", renderer.multiview_path()),
        samples: renderer.samples(),
        coefficients: format!("{:?}", scene.storage),
        max_order: args.render.max_order,
        culling: !args.render.no_cull,
        chunk_triangles: args.render.chunk_triangles,
        chunks_drawn: kept.chunks_drawn as f64 / timed,
        chunks: kept.chunks,
        triangles_drawn: kept.triangles_drawn as f64 / timed,
        triangles_per_frame: kept.triangles,
        draws: kept.draws as f64 / timed,
    };
    if args.json {
        println!("{}", serde_json::to_string(&report)?);
    } else {
        print_report(&report);
    }
    let log = gpu.validation_log();
    anyhow::ensure!(
        log.count() == 0,
        "{} Vulkan validation messages (printed above)",
        log.count()
    );
    Ok(report)
}

/// The head path: `--walk`'s file, or an orbit around the scene's centre at the
/// header camera's eye height and horizontal distance (half the bounds'
/// diagonal when the eye stands at the centre).
fn head_path(args: &BenchArgs, header: &solution::format::Header) -> Result<HeadPath> {
    if let Some(file) = &args.walk {
        return Ok(HeadPath::load(file)?);
    }
    let offset = DVec3::from(header.recentre_offset);
    let lo = DVec3::from(header.bounds_min.map(f64::from)) + offset;
    let hi = DVec3::from(header.bounds_max.map(f64::from)) + offset;
    let centre = 0.5 * (lo + hi);
    let eye = DVec3::from(header.camera.eye);
    let up = DVec3::from(header.up_axis.vector());
    let flat = |v: DVec3| v - up * v.dot(up);
    let mut radius = flat(eye - centre).length();
    if !(radius > 0.0 && radius.is_finite()) {
        radius = 0.5 * (hi - lo).length().max(1e-3);
    }
    Ok(HeadPath::orbit(centre, eye, radius, 10.0, header.up_axis))
}

/// Runs the session's frames: the wall time of each frame after the first
/// `warmup` (milliseconds), and what culling kept over those frames (chunk and
/// triangle totals of the last, drawn counts summed).
fn time_frames(
    session: &mut MockSession,
    renderer: &mut StereoRenderer,
    warmup: u32,
) -> Result<(Vec<f64>, CullStats)> {
    let mut times = Vec::new();
    let mut kept = CullStats::default();
    while !session.should_exit() {
        let start = Instant::now();
        let report = run_frame(session, renderer)?;
        let ms = start.elapsed().as_secs_f64() * 1e3;
        if report.timing.index >= u64::from(warmup) {
            times.push(ms);
            let frame = renderer.cull_stats();
            kept.chunks = frame.chunks;
            kept.triangles = frame.triangles;
            kept.chunks_drawn += frame.chunks_drawn;
            kept.triangles_drawn += frame.triangles_drawn;
            kept.draws += frame.draws;
        }
    }
    Ok((times, kept))
}

/// Vertex evaluations and basis terms per stereo frame: each vertex once per
/// eye, with `(L+1)²` terms for SH and the 4 bilinear taps for a global cube.
fn evaluations_per_frame(scene: &GpuScene) -> (u64, u64) {
    let evals: u64 = scene
        .draws
        .iter()
        .map(|d| u64::from(d.vertex_count) * 2)
        .sum();
    let terms: u64 = scene
        .draws
        .iter()
        .map(|d| {
            let per_vertex = match d.kind {
                DrawKind::Sh => (u64::from(d.order) + 1).pow(2),
                DrawKind::Cube { .. } => 4,
            };
            u64::from(d.vertex_count) * 2 * per_vertex
        })
        .sum();
    (evals, terms)
}

/// The report as text: frames and device, frame times and throughput, culling.
fn print_report(report: &BenchReport) {
    println!(
        "{} stereo frames of {}x{} per eye on {} ({} multiview, {}x MSAA, {} coefficients)",
        report.frames,
        report.width,
        report.height,
        report.device,
        report.multiview,
        report.samples,
        report.coefficients
    );
    println!(
        "median {:.2} ms, p95 {:.2} ms, p99 {:.2} ms per stereo frame; {} vertices, {} triangles; {:.3e} SH evaluations/s ({:.3e} basis terms/s)",
        report.median_ms, report.p95_ms, report.p99_ms, report.vertices, report.triangles, report.sh_evals_per_second,
        report.sh_terms_per_second
    );
    println!(
        "culling {} (chunks of ≤ {} triangles): {:.1} of {} chunks, {:.0} of {} triangles ({:.1}%) and {:.1} draws per stereo frame",
        if report.culling { "on" } else { "off" },
        report.chunk_triangles,
        report.chunks_drawn,
        report.chunks,
        report.triangles_drawn,
        report.triangles_per_frame,
        100.0 * report.triangles_drawn / (report.triangles_per_frame.max(1) as f64),
        report.draws
    );
}
