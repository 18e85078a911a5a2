//! `runtime screenshot`: one stereo pair (or a mono image) to PNG and EXR.

use super::{
    open_gpu, open_solution, parse_size, report_truncation_mapped, write_exr, write_png,
    RenderOptions, Timings,
};
use crate::render::{RendererDesc, StereoRenderer};
use crate::session::OffscreenSwapchain;
use anyhow::{Context, Result};
use glam::DVec3;
use solution::camera::Camera;
use std::path::PathBuf;

#[derive(clap::Args, Debug, Clone)]
pub struct ScreenshotArgs {
    /// The solution file.
    pub solution: PathBuf,
    /// Eye position, scene coordinates (default: the header's camera).
    #[arg(long, num_args = 3, value_names = ["X", "Y", "Z"], allow_negative_numbers = true)]
    pub eye: Option<Vec<f64>>,
    /// Point looked at, scene coordinates (default: the header's camera).
    #[arg(long, num_args = 3, value_names = ["X", "Y", "Z"], allow_negative_numbers = true)]
    pub target: Option<Vec<f64>>,
    /// Up direction (default: the header's camera).
    #[arg(long, num_args = 3, value_names = ["X", "Y", "Z"], allow_negative_numbers = true)]
    pub up: Option<Vec<f64>>,
    /// Vertical field of view, degrees (default: the header's camera).
    #[arg(long, value_name = "DEG")]
    pub fov_y: Option<f64>,
    /// Image size per eye, WIDTHxHEIGHT (default: the header's camera).
    #[arg(long, value_name = "WxH", value_parser = parse_size)]
    pub size: Option<(u32, u32)>,
    /// Interpupillary distance in metres (scaled by the header's units_per_metre).
    #[arg(long, value_name = "METRES", default_value_t = 0.064)]
    pub ipd: f64,
    /// One image from the eye itself instead of a stereo pair.
    #[arg(long)]
    pub mono: bool,
    /// Output prefix: PREFIX-left/-right .png and .exr, or PREFIX.png/.exr with --mono.
    #[arg(long, value_name = "PREFIX")]
    pub out: PathBuf,
    #[command(flatten)]
    pub render: RenderOptions,
}

fn vec3(v: &Option<Vec<f64>>, default: [f64; 3]) -> [f64; 3] {
    match v {
        Some(v) if v.len() == 3 => [v[0], v[1], v[2]],
        _ => default,
    }
}

pub fn run(args: &ScreenshotArgs) -> Result<()> {
    let mut timings = Timings::start();
    args.render.check()?;
    if !(args.ipd.is_finite() && args.ipd >= 0.0) {
        anyhow::bail!(
            "--ipd {} must be a finite, non-negative distance in metres",
            args.ipd
        );
    }
    let file = open_solution(&args.solution, args.render.max_frame_cost)?;
    timings.stage("open and validate");
    let header = file.header();
    let (width, height) = args
        .size
        .unwrap_or((header.camera.width, header.camera.height));
    let camera = Camera {
        eye: vec3(&args.eye, header.camera.eye),
        target: vec3(&args.target, header.camera.target),
        up: vec3(&args.up, header.camera.up),
        fov_y_deg: args.fov_y.unwrap_or(header.camera.fov_y_deg),
        width,
        height,
    };
    camera.validate().context("invalid camera")?;
    report_truncation_mapped(&file, args.render.max_order);
    let offset = DVec3::from(header.recentre_offset);
    let views = if args.mono {
        vec![camera.mono_view(offset)]
    } else {
        camera
            .stereo_views(args.ipd * header.units_per_metre, offset)
            .to_vec()
    };

    let gpu = open_gpu(args.render.validation)?;
    let swapchain = OffscreenSwapchain::new(&gpu, width, height, 1)?;
    timings.stage("vulkan");
    let desc = RendererDesc {
        width,
        height,
        max_samples: args.render.samples,
        multiview: args.render.multiview,
        max_order: args.render.max_order,
        tone: args.render.tone(file.lighting()),
        culling: args.render.culling(),
    };
    let mut renderer = StereoRenderer::from_mapped(&gpu, &file, desc, &swapchain.desc())?;
    timings.stage("renderer");
    timings.upload(renderer.upload_time(), renderer.upload_stats());
    renderer.render(&views, 0)?;
    timings.stage("first frame");
    if args.render.timings {
        eprintln!("{}", timings.line(renderer.first_submit()));
    }
    let eyes = renderer.read_back(&gpu, 0, views.len())?;
    let names: Vec<String> = if args.mono {
        vec![String::new()]
    } else {
        vec!["-left".into(), "-right".into()]
    };
    for (eye, suffix) in eyes.iter().zip(names) {
        let base = args.out.as_os_str().to_string_lossy().into_owned() + &suffix;
        let png = PathBuf::from(format!("{base}.png"));
        let exr = PathBuf::from(format!("{base}.exr"));
        write_png(&png, eye.width, eye.height, &eye.srgb)?;
        write_exr(&exr, eye.width, eye.height, &eye.radiance)?;
        println!("wrote {} and {}", png.display(), exr.display());
    }
    let log = gpu.validation_log();
    if log.count() > 0 {
        anyhow::bail!("{} Vulkan validation messages (printed above)", log.count());
    }
    Ok(())
}
