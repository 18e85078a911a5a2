//! `solver reference SCENE -o IMAGE.exr`: the unbiased path-traced reference
//! image of a scene (the project's ground truth), around the pure core in
//! `crate::reference`: loading and settings (as `solver solve` does), the
//! camera, passes until a sample budget or a target noise, progress, and the
//! atomic EXR write.
//!
//! The EXR contract (read by `solver compare`): one layer, f32 channels `R`,
//! `G`, `B` (mean radiance over each pixel's square, W·sr⁻¹·m⁻², linear),
//! `se.R`, `se.G`, `se.B` (standard error of that mean, from the per-sample
//! variance), `material_id` and `object_id` (integer indices, as f32, of the
//! surface the ray through the pixel centre meets, −1 for none); text
//! attributes `materials` and `objects` (JSON arrays of names, indexed by those
//! ids; non-ASCII escaped as \uXXXX) and `reference` (JSON: spp, passes, seed,
//! mean relative error, mode, normalization, max depth).

use crate::reference::{id_buffers, Accumulator, Integrator, Physics, RenderScene};
use crate::scene::ImportOptions;
use crate::settings::{Preset, SettingsPatch, SolverSettings};
use anyhow::{bail, Context};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use solution::camera::Camera;
use solution::format::SolveMode;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};

const AFTER_LONG_HELP: &str = "\
The image is the ground truth that `solver solve` results are measured against:
every pixel is an unbiased estimate of the mean radiance over its square, with
its standard error alongside (EXR channels R G B, se.R se.G se.B, material_id,
object_id; attributes materials, objects, reference).

Cost and noise: the standard error falls like 1/sqrt(samples), so halving the
noise costs four times the samples. --target-error stops as soon as the mean
relative standard error over lit pixels reaches E; --spp caps the samples either
way. The result depends only on --seed, never on --threads.";

/// `solver reference SCENE -o IMAGE.exr …`
#[derive(clap::Args, Debug, Clone)]
#[command(after_long_help = AFTER_LONG_HELP)]
pub struct ReferenceArgs {
    /// The scene: `.obj` (+ `.mtl`), `.gltf` / `.glb` (glTF 2.0, metres; docs/gltf.md), `.toml` scene config or a legacy geometry file.
    #[arg(value_name = "SCENE")]
    pub scene: PathBuf,

    /// Where to write the image (linear OpenEXR, written atomically).
    #[arg(short, long, value_name = "IMAGE.exr")]
    pub out: PathBuf,

    /// Eye position, scene coordinates (default: the scene's camera).
    #[arg(long, num_args = 3, value_names = ["X", "Y", "Z"], allow_negative_numbers = true)]
    pub eye: Option<Vec<f64>>,
    /// Point looked at, scene coordinates (default: the scene's camera).
    #[arg(long, num_args = 3, value_names = ["X", "Y", "Z"], allow_negative_numbers = true)]
    pub target: Option<Vec<f64>>,
    /// Up direction (default: the scene's camera).
    #[arg(long, num_args = 3, value_names = ["X", "Y", "Z"], allow_negative_numbers = true)]
    pub up: Option<Vec<f64>>,
    /// Vertical field of view, degrees (default: the scene's camera).
    #[arg(long, value_name = "DEG")]
    pub fov_y: Option<f64>,
    /// Image size, WIDTHxHEIGHT (default: the scene's camera).
    #[arg(
        long,
        value_name = "WxH",
        value_parser = solution::camera::parse_image_size,
        long_help = "Image size, WIDTHxHEIGHT (default: the scene's camera). Time grows \
            with the pixel count at a given noise."
    )]
    pub size: Option<(u32, u32)>,

    /// Samples per pixel in all (the budget; default 256).
    #[arg(
        long,
        value_name = "N",
        long_help = "Samples per pixel in all (2 to 2^24; default 256, or 65536 with \
            --target-error, as a cap). Noise falls like 1/sqrt(N) and time grows like N."
    )]
    pub spp: Option<u64>,

    /// Samples per pixel per pass (default 16).
    #[arg(
        long,
        value_name = "K",
        default_value_t = 16,
        long_help = "Samples per pixel per pass (2 to 65536; default 16). The noise is \
            measured and progress reported after each pass; smaller passes stop closer \
            to --target-error, at a small cost in overhead."
    )]
    pub pass_spp: u32,

    /// Render passes until the mean relative standard error over lit pixels is ≤ E.
    #[arg(
        long,
        value_name = "E",
        long_help = "Render passes until the mean, over lit pixels, of the luminance's \
            relative standard error se(Y)/Y is at most E (0 < E < 1; e.g. 0.01), or \
            until --spp samples. Each halving of E costs four times the time."
    )]
    pub target_error: Option<f64>,

    /// Seed of the random sample streams.
    #[arg(
        long,
        value_name = "S",
        default_value_t = 1,
        long_help = "Seed of the random streams (one per pixel and pass). The same seed \
            gives the same image bit for bit with any --threads; another seed gives \
            independent noise (two seeds' images can be averaged)."
    )]
    pub seed: u64,

    /// Worker threads (default: every core).
    #[arg(
        long,
        value_name = "N",
        long_help = "Worker threads (1 to 1024; default every core). Speed only: the \
            image does not depend on it."
    )]
    pub threads: Option<usize>,

    /// Most bounces per path (default unlimited, ended by Russian roulette).
    #[arg(
        long,
        value_name = "D",
        long_help = "Most bounces per path: 0 emitters only, 1 direct lighting, ... \
            Default unlimited (paths end by Russian roulette, which is unbiased). A \
            limit is faster but biased dark: the light it drops is at most \
            ρ^(D+1)/(1−ρ) of the emitted power, ρ the largest Kd + Ks of the scene \
            (printed)."
    )]
    pub max_depth: Option<u32>,

    /// diffuse or directional (glossy); default the scene config's, else diffuse.
    #[arg(
        long,
        value_parser = crate::settings::solve_mode_parser(),
        value_name = "MODE",
        long_help = "As `solver solve --mode`: diffuse folds Ks into Kd (per channel, capped at \
            1, as the solver does); \
            directional reflects Ks through the exact glossy lobe of Remington 1992 \
            eq. 4.2 (no spherical-harmonic truncation). Default: the scene config's \
            mode, else diffuse."
    )]
    pub mode: Option<SolveMode>,

    /// Scene units per metre (does not change the lighting).
    #[arg(long, value_name = "U")]
    pub units_per_metre: Option<f64>,

    /// Make import warnings errors.
    #[arg(long)]
    pub strict: bool,

    /// Legacy display parameter file (Remington 1992, app. A): its camera when the scene names none.
    #[arg(long, value_name = "FILE")]
    pub display: Option<PathBuf>,
}

fn vec3(v: &Option<Vec<f64>>, default: [f64; 3]) -> [f64; 3] {
    match v {
        Some(v) if v.len() == 3 => [v[0], v[1], v[2]],
        _ => default,
    }
}

/// The largest total sample count accepted per pixel.
const MAX_SPP: u64 = 1 << 24;

impl ReferenceArgs {
    fn check(&self) -> anyhow::Result<()> {
        if let Some(e) = self.target_error {
            if !(e > 0.0 && e < 1.0) {
                bail!("--target-error {e} must be in (0, 1), e.g. 0.01");
            }
        }
        if let Some(n) = self.spp {
            if !(2..=MAX_SPP).contains(&n) {
                bail!("--spp {n} must be in 2..={MAX_SPP}");
            }
        }
        if !(2..=65536).contains(&self.pass_spp) {
            bail!("--pass-spp {} must be in 2..=65536", self.pass_spp);
        }
        if let Some(t) = self.threads {
            if !(1..=1024).contains(&t) {
                bail!("--threads {t} must be in 1..=1024");
            }
        }
        Ok(())
    }

    /// The total budget of samples per pixel.
    fn budget(&self) -> u64 {
        self.spp.unwrap_or(if self.target_error.is_some() {
            65536
        } else {
            256
        })
    }
}

/// Runs the command.
pub fn run(args: ReferenceArgs) -> anyhow::Result<ExitCode> {
    args.check()?;
    check_writable(&args.out)?;
    let display_flag = match &args.display {
        Some(path) => Some(
            crate::scene::load_display_file(path)
                .map_err(super::solve::plain)
                .with_context(|| format!("reading display file {}", path.display()))?,
        ),
        None => None,
    };
    let options = ImportOptions {
        strict: args.strict,
        units_per_metre: args.units_per_metre,
        ..Default::default()
    };
    let loaded = crate::scene::load_scene(&args.scene, &options)
        .map_err(super::solve::plain)
        .with_context(|| format!("loading scene {}", args.scene.display()))?;
    let mut scene = loaded.scene;
    super::solve::print_warnings(&scene.warnings);
    super::solve::adopt_display_camera(&mut scene, display_flag.as_ref(), loaded.display.as_ref());
    let display = display_flag.or(loaded.display);
    // The same precedence as `solver solve`: flags > TOML config > display file.
    let display_patch = display.map(|d| d.settings).unwrap_or_default();
    let flags = SettingsPatch {
        mode: args.mode,
        ..SettingsPatch::default()
    };
    let settings = SolverSettings::resolve(
        Preset::default(),
        &[&display_patch, &loaded.settings, &flags],
    )
    .context("resolving the mode")?;
    // The same smooth surfaces as `solver solve` at the same crease angle, so
    // truth and solver agree on the shading normals.
    super::solve::apply_smoothing(&mut scene, settings.crease_angle);
    let physics = Physics {
        mode: settings.mode,
    };

    let threads = args.threads.unwrap_or_else(|| {
        std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1)
    });
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .context("starting the worker threads")?;
    let render = pool.install(|| RenderScene::new(&scene, physics));
    report_scene(&render, &args);

    let (lo, hi) = render.bounds();
    let default = scene.camera.unwrap_or_else(|| {
        crate::solve::default_camera(
            lo + scene.recentre_offset,
            hi + scene.recentre_offset,
            scene.up_axis,
        )
    });
    let (width, height) = args.size.unwrap_or((default.width, default.height));
    let camera = Camera {
        eye: vec3(&args.eye, default.eye),
        target: vec3(&args.target, default.target),
        up: vec3(&args.up, default.up),
        fov_y_deg: args.fov_y.unwrap_or(default.fov_y_deg),
        width,
        height,
    };
    camera.validate().context("invalid camera")?;
    let view = camera.mono_view(scene.recentre_offset);
    let integrator = Integrator {
        scene: &render,
        max_depth: args.max_depth,
    };

    let start = Instant::now();
    let image = pool.install(|| render_passes(&integrator, &view, &args));
    let (materials, objects) = pool.install(|| id_buffers(&integrator, &view));
    let seconds = start.elapsed().as_secs_f64();
    let error = image.mean_relative_error();
    write_reference_exr(
        &args.out, &image, &materials, &objects, &render, &args, physics, error,
    )?;
    let error_text = error.map_or("no lit pixel".to_string(), |e| format!("{e:.4}"));
    eprintln!(
        "solver: {} spp in {} passes, {:.1} s; mean relative standard error over lit pixels {}",
        image.samples_per_pixel(),
        image.passes,
        seconds,
        error_text
    );
    if let (Some(target), Some(e)) = (args.target_error, error) {
        if e > target {
            eprintln!(
                "solver: note: the --spp budget of {} ran out before --target-error {target}",
                args.budget()
            );
        }
    }
    eprintln!("solver: reference image written to {}", args.out.display());
    Ok(ExitCode::SUCCESS)
}

/// Says what was built and, for a bounce limit, the bound on the missing light.
fn report_scene(render: &RenderScene, args: &ReferenceArgs) {
    if !render.is_lit() {
        eprintln!(
            "solver: warning: the scene has no emitter, sun, sky or lamp: the image will be black"
        );
    }
    for lobe in &render.lobes {
        eprintln!(
            "solver: glossy lobe α = {}: C_R tabulated from the exact lobe to {:.1e} relative",
            lobe.alpha, lobe.interpolation_error
        );
    }
    if let Some(d) = args.max_depth {
        let rho = render.max_albedo;
        let bound = if rho < 1.0 {
            format!("{:.3e}", rho.powi(d as i32 + 1) / (1.0 - rho))
        } else {
            "unbounded (ρ = 1)".into()
        };
        eprintln!(
            "solver: --max-depth {d}: light after more than {d} bounces is dropped, at most \
             ρ^(D+1)/(1−ρ) = {bound} of the emitted power (ρ = {rho:.3}, the largest Kd + Ks)"
        );
    }
}

/// Passes of `--pass-spp` samples until the budget or the target error.
fn render_passes(
    integrator: &Integrator,
    view: &solution::camera::EyeView,
    args: &ReferenceArgs,
) -> Accumulator {
    let pixels = view.width as u64 * view.height as u64;
    let budget = args.budget();
    let bar = progress_bar(pixels * budget);
    #[allow(clippy::disallowed_methods)] // An edge: the terminal belongs to cli/.
    let plain = !std::io::stderr().is_terminal();
    let mut image = Accumulator::new(view.width, view.height);
    let mut last_line = Instant::now();
    while image.samples_per_pixel() < budget {
        let spp = (args.pass_spp as u64).min(budget - image.samples_per_pixel()) as u32;
        let spp = spp.max(2);
        image.render_pass(integrator, view, args.seed, spp, &|n| bar.inc(n));
        let error = image.mean_relative_error();
        let done = image.samples_per_pixel();
        if let (Some(target), Some(e)) = (args.target_error, error) {
            // Noise ∝ 1/√n: the samples that should reach the target.
            let needed = ((done as f64) * (e / target).powi(2)).ceil() as u64;
            bar.set_length(pixels * needed.clamp(done, budget));
            if e <= target {
                break;
            }
        }
        let e_text = error.map_or("-".into(), |e| format!("{e:.4}"));
        bar.set_message(format!("{done} spp, mean relative error {e_text}"));
        if plain && last_line.elapsed() >= Duration::from_secs(2) {
            eprintln!("solver: {done} spp, mean relative error {e_text}");
            last_line = Instant::now();
        }
    }
    bar.finish_and_clear();
    image
}

fn progress_bar(length: u64) -> ProgressBar {
    let bar = ProgressBar::with_draw_target(Some(length), ProgressDrawTarget::stderr());
    let style = ProgressStyle::with_template(
        "{spinner} [{elapsed}] {wide_bar} {percent:>3}% ETA {eta}\n  {wide_msg}",
    )
    .unwrap_or_else(|_| ProgressStyle::default_bar());
    bar.set_style(style);
    bar.enable_steady_tick(Duration::from_millis(200));
    bar
}

/// Fails early, before rendering, when the output's folder is missing or the
/// name is not an .exr.
fn check_writable(path: &Path) -> anyhow::Result<()> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if ext.as_deref() != Some("exr") {
        bail!(
            "{}: the reference image is written as OpenEXR: name it *.exr",
            path.display()
        );
    }
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        bail!(
            "{}: folder {} does not exist",
            path.display(),
            dir.display()
        );
    }
    Ok(())
}

/// JSON with every non-ASCII character escaped (`\uXXXX`, UTF-16), which OpenEXR
/// text attributes (bytes) carry unchanged.
fn ascii_json<T: serde::Serialize>(value: &T) -> String {
    let json = serde_json::to_string(value).unwrap_or_else(|_| "[]".into());
    let mut out = String::with_capacity(json.len());
    for ch in json.chars() {
        if ch.is_ascii() {
            out.push(ch);
        } else {
            let mut buf = [0u16; 2];
            for unit in ch.encode_utf16(&mut buf) {
                out.push_str(&format!("\\u{unit:04x}"));
            }
        }
    }
    out
}

/// Writes the EXR of the contract above atomically (`solution::atomic`:
/// temporary file beside `path`, fsync, rename).
#[allow(clippy::too_many_arguments)]
fn write_reference_exr(
    path: &Path,
    image: &Accumulator,
    materials: &[i32],
    objects: &[i32],
    render: &RenderScene,
    args: &ReferenceArgs,
    physics: Physics,
    error: Option<f64>,
) -> anyhow::Result<()> {
    use exr::prelude::*;
    let channel = |name: &str, values: Vec<f32>| AnyChannel::new(name, FlatSamples::F32(values));
    let mean = |c: usize| {
        image
            .pixels
            .iter()
            .map(|p| p.mean(c) as f32)
            .collect::<Vec<_>>()
    };
    let se = |c: usize| {
        image
            .pixels
            .iter()
            .map(|p| p.standard_error(c) as f32)
            .collect::<Vec<_>>()
    };
    let ids = |v: &[i32]| v.iter().map(|&i| i as f32).collect::<Vec<_>>();
    let channels = vec![
        channel("R", mean(0)),
        channel("G", mean(1)),
        channel("B", mean(2)),
        channel("se.R", se(0)),
        channel("se.G", se(1)),
        channel("se.B", se(2)),
        channel("material_id", ids(materials)),
        channel("object_id", ids(objects)),
    ];
    let mut attributes = LayerAttributes::default();
    let text = |s: String| AttributeValue::Text(Text::new_or_panic(s));
    attributes.other.insert(
        Text::from("materials"),
        text(ascii_json(&render.material_names)),
    );
    attributes.other.insert(
        Text::from("objects"),
        text(ascii_json(&render.object_names)),
    );
    let info = serde_json::json!({
        "spp": image.samples_per_pixel(),
        "passes": image.passes,
        "seed": args.seed,
        "mean_relative_error": error,
        "mode": physics.mode,
        "max_depth": args.max_depth,
    });
    attributes
        .other
        .insert(Text::from("reference"), text(ascii_json(&info)));
    let layer = Layer::new(
        (image.width as usize, image.height as usize),
        attributes,
        Encoding::FAST_LOSSLESS,
        AnyChannels::sort(SmallVec::from_vec(channels)),
    );
    // `to_unbuffered` is what exr's own `to_file` does with the file it creates.
    #[allow(clippy::disallowed_methods)] // An edge: `solver reference` writes its image.
    solution::atomic::write_atomically(path, |file| {
        Image::from_layer(layer)
            .write()
            .to_unbuffered(file)
            .map_err(std::io::Error::other)
    })
    .with_context(|| format!("writing {}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn non_ascii_names_are_escaped_json() {
        let names = vec!["wall".to_string(), "béton 🧱".to_string()];
        let text = ascii_json(&names);
        assert!(text.is_ascii());
        let back: Vec<String> = serde_json::from_str(&text).unwrap();
        assert_eq!(back, names);
    }

    #[test]
    fn sizes_and_outputs_are_checked() {
        use solution::camera::parse_image_size as parse_size;
        assert_eq!(parse_size("64x48"), Ok((64, 48)));
        assert!(parse_size("64").is_err() && parse_size("0x4").is_err());
        assert!(check_writable(Path::new("out.png")).is_err());
        assert!(check_writable(Path::new("/no/such/folder/out.exr")).is_err());
        assert!(check_writable(Path::new("out.exr")).is_ok());
    }
}
