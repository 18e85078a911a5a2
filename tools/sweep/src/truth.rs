//! The path-traced truth of each fixed camera, and each point's error against it.
//!
//! The sweep's `image err` is against the converged radiosity solution: it
//! measures convergence, and it cannot see the bias that the converged solution
//! itself carries (meshing, interpolation, the ambient term). Beside it each
//! point gets its error against an unbiased truth from `solver reference`
//! (bias plus noise), computed by `solver compare --json` as docs/accuracy.md
//! computes it: MARE over lit pixels and HDR-FLIP, the screenshot box-filtered
//! to the truth's pixel footprints.
//!
//! A truth is read from a given EXR (`--truth`, or the camera's committed
//! fixture) or rendered once with `solver reference --target-error E` and cached
//! in the work folder, keyed by its command and the scene's files.

use anyhow::{bail, Context};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::process::Command;
use sweep::child::run_measured;

use crate::points::{Camera, SceneSpec};

/// Where a camera's truth comes from and what it is.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Truth {
    pub camera: String,
    pub path: PathBuf,
    pub width: usize,
    pub height: usize,
    /// Mean relative standard error of the truth's luminance over its lit
    /// pixels, from its own `se.*` channels (`solver compare`'s
    /// `reference_noise`); None when the file carries none.
    pub noise: Option<f64>,
    /// How it was made, for the report (a fixture, a given file, or the
    /// command's samples and seconds).
    pub source: String,
    /// Identifies this truth in the per-point comparison caches.
    pub key: String,
}

/// Settings of the truths the sweep renders itself.
pub struct TruthOptions<'a> {
    pub solver: &'a Path,
    /// Target noise: mean relative standard error over lit pixels.
    pub target_error: f64,
    /// Overrides the cameras' divisors (truth = screenshot / divisor per side).
    pub divisor: Option<u32>,
    /// Given truths: (`scene/camera`, path).
    pub given: &'a [(String, PathBuf)],
}

/// Parses a `--truth SCENE/CAMERA=PATH` value.
pub fn parse_given(text: &str) -> Result<(String, PathBuf), String> {
    match text.split_once('=') {
        Some((key, path)) if key.contains('/') && !path.is_empty() => {
            Ok((key.to_string(), PathBuf::from(path)))
        }
        _ => Err(format!(
            "'{text}' is not SCENE/CAMERA=PATH (e.g. cornell/front=truth.exr)"
        )),
    }
}

/// The truth's size for `camera`: the screenshot's divided by the divisor, which
/// must divide both sides.
pub fn truth_size(camera: &Camera, divisor: Option<u32>) -> anyhow::Result<(u32, u32)> {
    let k = divisor.unwrap_or(camera.truth_divisor);
    if k == 0 || !camera.width.is_multiple_of(k) || !camera.height.is_multiple_of(k) {
        bail!(
            "truth divisor {k} does not divide camera {}'s {}×{}",
            camera.name,
            camera.width,
            camera.height
        );
    }
    Ok((camera.width / k, camera.height / k))
}

/// The truth of `camera`: given, the committed fixture when its size fits, or
/// rendered (cached in `dir`).
pub fn truth(
    options: &TruthOptions,
    scene: &SceneSpec,
    camera: &Camera,
    dir: &Path,
) -> anyhow::Result<Truth> {
    let name = format!("{}/{}", scene.key, camera.name);
    if let Some((_, path)) = options.given.iter().find(|(k, _)| *k == name) {
        return read_truth(
            options.solver,
            camera,
            path,
            format!("given: `{}`", path.display()),
        );
    }
    let (width, height) = truth_size(camera, options.divisor)?;
    if let Some(fixture) = camera.truth_fixture {
        let path = PathBuf::from(fixture);
        let t = read_truth(
            options.solver,
            camera,
            &path,
            format!("committed fixture `{fixture}`"),
        )?;
        if (t.width, t.height) == (width as usize, height as usize) {
            return Ok(t);
        }
    }
    render_truth(options, scene, camera, (width, height), dir)
}

/// The `solver reference` command line for `camera` (without the output).
fn reference_args(scene: &SceneSpec, camera: &Camera, size: (u32, u32), e: f64) -> Vec<String> {
    let v = |a: [f64; 3]| a.map(|x| x.to_string());
    let mut args = vec!["reference".to_string(), scene.config.to_string()];
    args.push("--eye".into());
    args.extend(v(camera.eye));
    args.push("--target".into());
    args.extend(v(camera.target));
    args.push("--up".into());
    args.extend(v(camera.up));
    args.extend([
        "--fov-y".into(),
        camera.fov_y_deg.to_string(),
        "--size".into(),
        format!("{}x{}", size.0, size.1),
        "--target-error".into(),
        e.to_string(),
        // A cap far above what 0.5% needs at these sizes (the glossy Cornell
        // box needs about 210,000 samples per pixel at 32², the glossy room
        // 70,000 at 40×30), in passes
        // large enough that the per-pass noise estimate costs nothing.
        "--spp".into(),
        (1u64 << 22).to_string(),
        "--pass-spp".into(),
        "1024".into(),
        "--seed".into(),
        "1".into(),
    ]);
    args
}

/// What a rendered truth cost, cached beside it.
#[derive(Serialize, Deserialize)]
struct Rendered {
    key: String,
    wall_seconds: f64,
    cpu_seconds: f64,
}

fn render_truth(
    options: &TruthOptions,
    scene: &SceneSpec,
    camera: &Camera,
    size: (u32, u32),
    dir: &Path,
) -> anyhow::Result<Truth> {
    let args = reference_args(scene, camera, size, options.target_error);
    // The key holds the command and the scene's files, so a changed scene or
    // camera renders a new truth; a changed solver binary does not (the truth's
    // physics is meant not to change).
    let key = format!("{}\n{}", args.join(" "), scene_files_text(scene)?);
    let truth_dir = dir.join(format!(
        "truth-{}-{}x{}-e{}",
        camera.name, size.0, size.1, options.target_error
    ));
    std::fs::create_dir_all(&truth_dir)
        .with_context(|| format!("creating {}", truth_dir.display()))?;
    let path = truth_dir.join("truth.exr");
    let done_path = truth_dir.join("rendered.json");
    let cached = std::fs::read_to_string(&done_path)
        .ok()
        .and_then(|t| serde_json::from_str::<Rendered>(&t).ok())
        .filter(|r| r.key == key && path.is_file());
    let rendered = match cached {
        Some(r) => r,
        None => {
            println!(
                "   truth for {}/{} at {}×{} (solver reference --target-error {}): this takes minutes",
                scene.key, camera.name, size.0, size.1, options.target_error
            );
            let mut command = Command::new(options.solver);
            command.args(&args).arg("-o").arg(&path);
            let measured = run_measured(&mut command, &truth_dir.join("reference.log"))?;
            let r = Rendered {
                key: key.clone(),
                wall_seconds: measured.wall_seconds,
                cpu_seconds: measured.cpu_seconds,
            };
            crate::report::write_atomic(&done_path, &serde_json::to_string_pretty(&r)?)?;
            r
        }
    };
    let source = format!(
        "`solver {}`, {:.0} s wall, {:.0} CPU s",
        args.join(" "),
        rendered.wall_seconds,
        rendered.cpu_seconds
    );
    let mut t = read_truth(options.solver, camera, &path, source)?;
    t.key = format!("{}\n{}", t.key, rendered.key);
    Ok(t)
}

/// The scene config and the files it names, as one text (the truth's cache key).
fn scene_files_text(scene: &SceneSpec) -> anyhow::Result<String> {
    let config = Path::new(scene.config);
    let mut text =
        std::fs::read_to_string(config).with_context(|| format!("reading {}", config.display()))?;
    let dir = config.parent().unwrap_or(Path::new("."));
    let table: toml::Table = toml::from_str(&text).unwrap_or_default();
    if let Some(toml::Value::Array(files)) = table.get("geometry") {
        for file in files.iter().filter_map(|f| f.as_str()) {
            let obj = dir.join(file);
            text.push_str(&std::fs::read_to_string(&obj).unwrap_or_default());
            let mtl = obj.with_extension("mtl");
            text.push_str(&std::fs::read_to_string(&mtl).unwrap_or_default());
        }
    }
    Ok(text)
}

/// `solver compare --json` of an image with the truth: what the sweep keeps.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct TruthError {
    pub mare: f64,
    pub relative_rmse: f64,
    pub mean_signed: f64,
    pub flip: Option<f64>,
}

/// The subset of `solver compare --json` read here.
#[derive(Deserialize)]
struct CompareJson {
    width: usize,
    height: usize,
    mare: f64,
    relative_rmse: f64,
    mean_signed_relative_error: f64,
    flip: Option<FlipJson>,
    reference_noise: Option<f64>,
}

#[derive(Deserialize)]
struct FlipJson {
    mean: f64,
}

fn compare_json(
    solver: &Path,
    test: &Path,
    truth: &Path,
    flip: bool,
) -> anyhow::Result<CompareJson> {
    let output = Command::new(solver)
        .arg("compare")
        .arg(test)
        .arg(truth)
        .args(["--json", "--flip", if flip { "hdr" } else { "none" }])
        .output()
        .with_context(|| format!("running {} compare", solver.display()))?;
    if !output.status.success() {
        bail!(
            "solver compare {} {}: {}",
            test.display(),
            truth.display(),
            String::from_utf8_lossy(&output.stderr).trim()
        );
    }
    serde_json::from_slice(&output.stdout).context("parsing solver compare --json")
}

fn read_truth(
    solver: &Path,
    camera: &Camera,
    path: &Path,
    source: String,
) -> anyhow::Result<Truth> {
    let c = compare_json(solver, path, path, false)
        .with_context(|| format!("reading the truth {}", path.display()))?;
    let meta = std::fs::metadata(path)?;
    let modified = meta
        .modified()
        .ok()
        .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
        .map_or(0, |d| d.as_nanos());
    Ok(Truth {
        camera: camera.name.to_string(),
        path: path.to_path_buf(),
        width: c.width,
        height: c.height,
        noise: c.reference_noise,
        source,
        key: format!("{} {} {modified}", path.display(), meta.len()),
    })
}

/// A cached comparison: valid while both files are the ones it was made from.
#[derive(Serialize, Deserialize)]
struct CachedError {
    key: String,
    error: TruthError,
}

/// The error of `image` (a point's screenshot from `truth`'s camera) against
/// the truth, cached beside the image.
pub fn error_against(solver: &Path, image: &Path, truth: &Truth) -> anyhow::Result<TruthError> {
    let meta = std::fs::metadata(image).with_context(|| format!("reading {}", image.display()))?;
    let modified = meta
        .modified()
        .ok()
        .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
        .map_or(0, |d| d.as_nanos());
    let key = format!("{}\n{} {modified}", truth.key, meta.len());
    let cache = image.with_extension("truth.json");
    if let Some(c) = std::fs::read_to_string(&cache)
        .ok()
        .and_then(|t| serde_json::from_str::<CachedError>(&t).ok())
        .filter(|c| c.key == key)
    {
        return Ok(c.error);
    }
    let c = compare_json(solver, image, &truth.path, true)?;
    let error = TruthError {
        mare: c.mare,
        relative_rmse: c.relative_rmse,
        mean_signed: c.mean_signed_relative_error,
        flip: c.flip.map(|f| f.mean),
    };
    let cached = CachedError {
        key,
        error: error.clone(),
    };
    crate::report::write_atomic(&cache, &serde_json::to_string(&cached)?)?;
    Ok(error)
}

/// The mean over cameras of each figure (every camera counts alike, as the
/// image error's cameras do).
pub fn mean_error(errors: &[TruthError]) -> Option<TruthError> {
    if errors.is_empty() {
        return None;
    }
    let n = errors.len() as f64;
    let mean = |f: &dyn Fn(&TruthError) -> f64| errors.iter().map(f).sum::<f64>() / n;
    let flip = errors
        .iter()
        .map(|e| e.flip)
        .collect::<Option<Vec<f64>>>()
        .map(|f| f.iter().sum::<f64>() / n);
    Some(TruthError {
        mare: mean(&|e| e.mare),
        relative_rmse: mean(&|e| e.relative_rmse),
        mean_signed: mean(&|e| e.mean_signed),
        flip,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera(width: u32, height: u32, truth_divisor: u32) -> Camera {
        Camera {
            name: "c",
            eye: [0.0; 3],
            target: [0.0, 0.0, -1.0],
            up: [0.0, 1.0, 0.0],
            fov_y_deg: 60.0,
            width,
            height,
            truth_divisor,
            truth_fixture: None,
        }
    }

    #[test]
    fn truth_size_divides_the_screenshot_or_refuses() {
        assert_eq!(truth_size(&camera(256, 256, 4), None).unwrap(), (64, 64));
        assert_eq!(truth_size(&camera(320, 240, 8), None).unwrap(), (40, 30));
        assert_eq!(truth_size(&camera(320, 240, 4), Some(8)).unwrap(), (40, 30));
        assert!(truth_size(&camera(320, 240, 7), None).is_err());
        assert!(truth_size(&camera(320, 240, 8), Some(0)).is_err());
    }

    #[test]
    fn given_truths_parse() {
        assert_eq!(
            parse_given("cornell/front=a/b.exr").unwrap(),
            ("cornell/front".to_string(), PathBuf::from("a/b.exr"))
        );
        assert!(parse_given("front=a.exr").is_err());
        assert!(parse_given("cornell/front=").is_err());
        assert!(parse_given("cornell/front").is_err());
    }

    #[test]
    fn the_mean_over_cameras_is_per_figure() {
        let a = TruthError {
            mare: 0.02,
            relative_rmse: 0.1,
            mean_signed: -0.01,
            flip: Some(0.1),
        };
        let b = TruthError {
            mare: 0.04,
            relative_rmse: 0.3,
            mean_signed: 0.03,
            flip: None,
        };
        let m = mean_error(&[a.clone(), a.clone()]).unwrap();
        assert!((m.mare - 0.02).abs() < 1e-15 && m.flip == Some(0.1));
        let m = mean_error(&[a, b]).unwrap();
        assert!((m.mare - 0.03).abs() < 1e-15);
        assert!((m.relative_rmse - 0.2).abs() < 1e-15);
        assert!((m.mean_signed - 0.01).abs() < 1e-15);
        // A camera without FLIP leaves the mean FLIP unknown, not biased.
        assert_eq!(m.flip, None);
        assert!(mean_error(&[]).is_none());
    }
}
