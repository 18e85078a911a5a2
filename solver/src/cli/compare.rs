//! `solver compare TEST REFERENCE`: how far a rendered image is from ground truth.
//! Files, flags and printing live here; the measurements are `crate::compare`.

use crate::compare::edge_band::{
    edge_band_error, edge_mask, render_mask, EdgeBand, DEFAULT_EDGE_RATIO,
};
use crate::compare::flip::{default_pixels_per_degree, flip_with_progress, Exposures, Variant};
use crate::compare::heatmap;
use crate::compare::image::{IdChannel, Image, LoadedImage};
use crate::compare::metrics::{
    error_by_id, reference_noise, signed_relative_luminance_error, summarize, GroupError, Summary,
    LIT_FRACTION,
};
use crate::compare::read::read_image;
use anyhow::{bail, Context};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// `solver compare --help`: what each metric measures.
pub const LONG_ABOUT: &str = "\
Compares a TEST image (e.g. a `runtime screenshot` EXR) with a REFERENCE image
(e.g. `solver reference`'s path-traced EXR) and prints:

  mean            mean radiance of each image over all pixels and channels.
  relative RMSE   root-mean-square error over all pixels and channels, divided by
                  the reference's mean: a scale-free overall error.
  MARE            mean absolute relative error of luminance Y = 0.2126 R +
                  0.7152 G + 0.0722 B (Rec. 709 primaries), |Y_t − Y_r| / Y_r,
                  over the reference's lit pixels (Y_r above 1e-3 of the mean Y_r).
  signed error    the same mean without the absolute value: the bias (+ too bright).
  max error       largest absolute difference of one channel of one pixel.
  FLIP            mean perceptual error in [0, 1] (Andersson et al. 2020); HDR-FLIP
                  (Andersson et al. 2021) by default: ACES tone mapping at one
                  exposure per stop between the reference's maximum and median,
                  maximum over exposures. LDR-FLIP clamps linear RGB to [0, 1].

When the reference carries `material_id` / `object_id` channels (with the header
attributes `materials` / `objects` naming them), the luminance error is broken
down per material and per object (MARE, mean signed error, pixel count, share of
the total absolute luminance error), largest share first. When it carries `se.R`,
`se.G`, `se.B`, the reference's own noise (mean relative standard error of
luminance over lit pixels) is printed too: a test error no larger than it
cannot be told apart from the truth's own noise.

With --edge-band the luminance error, relative RMSE and FLIP are also given
separately for the reference's edge pixels (max/min luminance over the 3 × 3
neighbourhood above --edge-ratio, default 2: sun and lamp shadow edges, and
creases and material boundaries of more than a factor 2) and for the rest. It
shows how much of the error is a shadow edge drawn as a one-element ramp, which
finer meshing near the edge buys back, and how much is in the smooth parts.

Inputs: OpenEXR (linear, channels R, G, B) or NumPy .npy (float32, shape
height × width × 3, C order), recognised by content. Both must be the same size,
or the test an integer multiple k of the reference's on both sides: then each
k × k block of the test is averaged (box filter) to the reference's pixel
footprint, so a supersampled render compares with a footprint-mean truth.";

#[derive(clap::Args, Debug)]
pub struct CompareArgs {
    /// The image under test (OpenEXR or .npy).
    pub test: PathBuf,
    /// The ground-truth image (OpenEXR or .npy), optionally with se.*, material_id
    /// and object_id channels.
    pub reference: PathBuf,
    /// Which FLIP to compute: `hdr` (radiance of any range, several exposures),
    /// `ldr` (linear RGB clamped to [0, 1], one exposure) or `none` (skip it:
    /// HDR-FLIP costs about one LDR-FLIP per stop of the reference's range).
    #[arg(long, value_enum, default_value_t = FlipChoice::Hdr)]
    pub flip: FlipChoice,
    /// Pixels per degree of visual angle for FLIP. The default, 67.02, is FLIP's:
    /// 0.7 m from a 0.7 m wide 3840-pixel monitor. Fewer pixels per degree (a
    /// closer look) make FLIP more sensitive to fine detail.
    #[arg(long, value_name = "PPD")]
    pub ppd: Option<f32>,
    /// Write the signed relative luminance error as a PNG: white where the images
    /// agree, red where the test is too bright, blue where too dark, grey where
    /// the reference is unlit (skipped by MARE).
    #[arg(long, value_name = "PNG")]
    pub heatmap: Option<PathBuf>,
    /// Write the per-pixel FLIP error (the `--flip` variant; for HDR-FLIP each
    /// pixel's maximum over the exposures) as a PNG in the FLIP authors' magma
    /// colours: black where no difference is perceived, through purple and red
    /// to pale yellow at 1. It shows where the mean FLIP comes from.
    #[arg(long, value_name = "PNG")]
    pub flip_map: Option<PathBuf>,
    /// Relative error at which the heatmap's colours saturate (0.25: ±25 %).
    #[arg(long, value_name = "FRACTION", default_value_t = heatmap::DEFAULT_RANGE)]
    pub heatmap_range: f64,
    /// Also report the error on the reference's sharp edges (a band about two
    /// pixels wide along shadow edges, creases and material boundaries) apart from
    /// the rest: it separates an edge drawn too soft from error in smooth regions.
    #[arg(long)]
    pub edge_band: bool,
    /// The --edge-band threshold: a pixel is an edge pixel where its reference
    /// luminance's max/min over its 3 × 3 neighbourhood exceeds this (default 2:
    /// far above a 2–5 % noisy reference's 1.1–1.3, below a sun shadow's 5+).
    #[arg(long, value_name = "RATIO", default_value_t = DEFAULT_EDGE_RATIO)]
    pub edge_ratio: f64,
    /// With --edge-band, write the band as a PNG: edge pixels orange over the
    /// reference in grey, to see which edges it holds.
    #[arg(long, value_name = "PNG", requires = "edge_band")]
    pub edge_map: Option<PathBuf>,
    /// Print everything as one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}

#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum FlipChoice {
    Hdr,
    Ldr,
    None,
}

/// Everything the command reports.
#[derive(serde::Serialize)]
struct Report {
    test: String,
    reference: String,
    width: usize,
    height: usize,
    #[serde(flatten)]
    summary: Summary,
    lit_fraction: f64,
    flip: Option<FlipReport>,
    /// Mean relative standard error of the reference over lit pixels.
    reference_noise: Option<f64>,
    by_material: Option<Vec<GroupError>>,
    by_object: Option<Vec<GroupError>>,
    edge_band: Option<EdgeBand>,
    heatmap: Option<HeatmapReport>,
}

#[derive(serde::Serialize)]
struct FlipReport {
    variant: Variant,
    pixels_per_degree: f32,
    mean: f32,
    exposures: Option<Exposures>,
    /// Where `--flip-map` wrote the per-pixel map.
    #[serde(skip_serializing_if = "Option::is_none")]
    map: Option<String>,
}

#[derive(serde::Serialize)]
struct HeatmapReport {
    file: String,
    range: f64,
}

pub fn run(args: CompareArgs) -> anyhow::Result<ExitCode> {
    if !(args.heatmap_range > 0.0 && args.heatmap_range.is_finite()) {
        bail!(
            "--heatmap-range must be a positive number, not {}",
            args.heatmap_range
        );
    }
    if args.flip_map.is_some() && args.flip == FlipChoice::None {
        bail!("--flip-map needs a FLIP to draw: drop `--flip none` or the --flip-map");
    }
    if !(args.edge_ratio > 1.0 && args.edge_ratio.is_finite()) {
        bail!(
            "--edge-ratio must be a number above 1, not {}",
            args.edge_ratio
        );
    }
    let ppd = args.ppd.unwrap_or_else(default_pixels_per_degree);
    if !(ppd > 0.0 && ppd.is_finite()) {
        bail!("--ppd must be a positive number, not {ppd}");
    }
    let mut test = load(&args.test)?;
    let reference = load(&args.reference)?;
    let (width, height) = (reference.image.width, reference.image.height);
    if let Some(factor) = test.image.supersampling_factor(width, height) {
        eprintln!(
            "solver: note: the test image is {factor}× the reference's size on both \
             sides; comparing its {factor}×{factor} box-filtered means (each reference \
             pixel is the mean over its footprint)"
        );
        test.image = test.image.box_downsample(factor);
    }
    let (t, r) = (&test.image, &reference.image);
    if (t.width, t.height) != (r.width, r.height) {
        bail!(
            "the images differ in size: test {} is {}×{}, reference {} is {}×{}",
            args.test.display(),
            t.width,
            t.height,
            args.reference.display(),
            r.width,
            r.height
        );
    }

    let mut flip_map = None;
    let flip_report = match args.flip {
        FlipChoice::None => None,
        choice => {
            let variant = if choice == FlipChoice::Hdr {
                Variant::Hdr
            } else {
                Variant::Ldr
            };
            // HDR-FLIP of a large image takes seconds: show the exposures on a terminal.
            #[allow(clippy::disallowed_methods)] // An edge: the terminal belongs to cli/.
            let show = std::io::stderr().is_terminal();
            let mut progress = |done: usize, total: usize| {
                if show {
                    eprint!("\rHDR-FLIP: exposure {done} of {total}");
                    if done == total {
                        eprint!("\r\x1b[K");
                    }
                }
            };
            let result = flip_with_progress(t, r, variant, ppd, &mut progress)
                .with_context(|| format!("FLIP of {}", args.reference.display()))?;
            if let Some(path) = &args.flip_map {
                write_png(path, &heatmap::render_flip(&result.map), t.width, t.height)?;
            }
            flip_map = Some(result.map);
            Some(FlipReport {
                variant,
                pixels_per_degree: ppd,
                mean: result.mean,
                exposures: result.exposures,
                map: args.flip_map.as_ref().map(|p| p.display().to_string()),
            })
        }
    };
    let by = |ids: &Option<IdChannel>| ids.as_ref().map(|ids| error_by_id(t, r, ids));
    let heatmap_report = match &args.heatmap {
        Some(path) => {
            write_heatmap(path, t, r, args.heatmap_range)?;
            Some(HeatmapReport {
                file: path.display().to_string(),
                range: args.heatmap_range,
            })
        }
        None => None,
    };
    let edge_band = match args.edge_band {
        false => None,
        true => {
            let mask = edge_mask(r, args.edge_ratio);
            if let Some(path) = &args.edge_map {
                write_png(path, &render_mask(r, &mask), r.width, r.height)?;
            }
            let relative = signed_relative_luminance_error(t, r);
            let errors = &relative.errors;
            let map = flip_map.as_deref();
            Some(edge_band_error(t, r, errors, map, &mask, args.edge_ratio))
        }
    };
    let report = Report {
        test: args.test.display().to_string(),
        reference: args.reference.display().to_string(),
        width: t.width,
        height: t.height,
        summary: summarize(t, r),
        lit_fraction: LIT_FRACTION,
        flip: flip_report,
        reference_noise: reference
            .standard_error
            .as_ref()
            .map(|se| reference_noise(r, se)),
        by_material: by(&reference.material_id),
        by_object: by(&reference.object_id),
        edge_band,
        heatmap: heatmap_report,
    };
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print!("{}", describe(&report));
    }
    Ok(ExitCode::SUCCESS)
}

/// Reads an image and refuses non-finite values, which would make every mean NaN.
fn load(path: &Path) -> anyhow::Result<LoadedImage> {
    let loaded = read_image(path)?;
    if let Some(((x, y, c), count)) = loaded.image.first_non_finite() {
        bail!(
            "{}: {count} non-finite value(s) (NaN or infinity), the first at pixel ({x}, {y}) channel {}",
            path.display(),
            ["R", "G", "B"][c]
        );
    }
    Ok(loaded)
}

fn write_heatmap(path: &Path, test: &Image, reference: &Image, range: f64) -> anyhow::Result<()> {
    let errors = signed_relative_luminance_error(test, reference).errors;
    write_png(
        path,
        &heatmap::render(&errors, range),
        test.width,
        test.height,
    )
}

/// Writes RGB8 pixels (row 0 at the top) as a PNG, atomically.
fn write_png(path: &Path, rgb: &[u8], width: usize, height: usize) -> anyhow::Result<()> {
    use image::ImageEncoder;
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new(&mut png)
        .write_image(
            rgb,
            width as u32,
            height as u32,
            image::ExtendedColorType::Rgb8,
        )
        .with_context(|| format!("encoding {}", path.display()))?;
    super::solve::files::write_atomic(path, &png)
}

fn describe(r: &Report) -> String {
    use std::fmt::Write;
    let s = &r.summary;
    let mut out = String::new();
    let _ = writeln!(out, "test:      {} ({}×{})", r.test, r.width, r.height);
    let _ = writeln!(out, "reference: {}", r.reference);
    let _ = writeln!(
        out,
        "mean radiance:       test {:.6}, reference {:.6}",
        s.test_mean, s.reference_mean
    );
    let _ = writeln!(out, "relative RMSE:       {:.6}", s.relative_rmse);
    let _ = writeln!(
        out,
        "MARE (luminance):    {:.6}  over {} of {} pixels lit (Y_ref > {:.3e})",
        s.mare, s.lit_pixels, s.pixels, s.lit_threshold
    );
    let _ = writeln!(
        out,
        "mean signed error:   {:+.6}",
        s.mean_signed_relative_error
    );
    let (x, y, c) = s.max_abs_error_at;
    let _ = writeln!(
        out,
        "max absolute error:  {:.6}  at pixel ({x}, {y}) channel {}",
        s.max_abs_error,
        ["R", "G", "B"][c]
    );
    if let Some(noise) = r.reference_noise {
        let _ = writeln!(
            out,
            "reference noise:     {noise:.6}  (mean relative standard error of Y_ref, lit pixels)"
        );
    }
    if let Some(f) = &r.flip {
        let name = match f.variant {
            Variant::Hdr => "HDR-FLIP",
            Variant::Ldr => "LDR-FLIP",
        };
        let _ = write!(
            out,
            "mean {name}:       {:.6}  ({:.2} pixels per degree",
            f.mean, f.pixels_per_degree
        );
        if let Some(e) = f.exposures {
            let _ = write!(
                out,
                "; {} exposures from {:+.3} to {:+.3} stops",
                e.count, e.start, e.stop
            );
        }
        let _ = writeln!(out, ")");
    }
    for (title, rows) in [("material", &r.by_material), ("object", &r.by_object)] {
        if let Some(rows) = rows {
            let _ = writeln!(
                out,
                "\nerror by {title}, largest share of absolute error first:"
            );
            let _ = writeln!(
                out,
                "  {:>6}  {:>10}  {:>8}  {:>9}  {:>9}  name",
                "share", "MARE", "signed", "pixels", "lit"
            );
            for g in rows {
                let _ = writeln!(
                    out,
                    "  {:>5.1}%  {:>10.6}  {:>+8.4}  {:>9}  {:>9}  {}",
                    100.0 * g.share_of_abs_error,
                    g.mare,
                    g.mean_signed,
                    g.pixels,
                    g.lit_pixels,
                    g.name
                );
            }
        }
    }
    if let Some(band) = &r.edge_band {
        describe_edge_band(&mut out, band);
    }
    if let Some(h) = &r.heatmap {
        let _ = writeln!(out, "\nheatmap: {} (saturates at ±{})", h.file, h.range);
    }
    if let Some(map) = r.flip.as_ref().and_then(|f| f.map.as_ref()) {
        let _ = writeln!(out, "FLIP map: {map} (magma: black 0, pale yellow 1)");
    }
    out
}

fn describe_edge_band(out: &mut String, band: &EdgeBand) {
    use std::fmt::Write;
    let _ = writeln!(
        out,
        "\nedge band (reference max/min luminance over 3×3 > {}):",
        band.ratio
    );
    let _ = writeln!(
        out,
        "  {:>5}  {:>9}  {:>9}  {:>10}  {:>8}  {:>10}  {:>8}",
        "", "pixels", "lit", "MARE", "signed", "rel. RMSE", "FLIP"
    );
    for (name, e) in [("edge", &band.edge), ("rest", &band.rest)] {
        if e.pixels == 0 {
            let _ = writeln!(out, "  {name:>5}  {:>9}  (no pixels)", 0);
            continue;
        }
        let flip = e.flip.map_or("-".to_string(), |f| format!("{f:.4}"));
        let _ = writeln!(
            out,
            "  {:>5}  {:>9}  {:>9}  {:>10.6}  {:>+8.4}  {:>10.6}  {:>8}",
            name, e.pixels, e.lit_pixels, e.mare, e.mean_signed, e.relative_rmse, flip
        );
    }
}
