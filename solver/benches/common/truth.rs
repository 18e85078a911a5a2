//! The Cornell box's path-traced truth for the benches that print accuracy: the
//! committed 64 × 64 fixture `tests/fixtures/cornell_truth_64.exr` (made by
//! `solver reference config/cornell_box.toml -o cornell_truth_64.exr --size
//! 64x64 --target-error 0.005 --seed 1`, the standard camera), and a solution's
//! error against it as `solver compare` measures it.
//!
//! An error against a converged radiosity solution measures convergence; this
//! one measures accuracy (bias plus the truth's noise of about 0.5%), so the
//! benches print both.

use solution::camera::Camera;
use solution::format::Solution;
use solution::raster::{render, RenderOptions};
use solver::compare::flip::{default_pixels_per_degree, flip, Variant};
use solver::compare::image::Image;
use solver::compare::metrics::{reference_noise, summarize};
use solver::compare::read::read_image;
use std::path::Path;

/// The rasterized image's side: 8× the truth's, box-filtered to its footprints.
const RASTER_SIDE: u32 = 512;

/// The fixture, read once.
pub struct CornellTruth {
    pub image: Image,
    /// Mean relative standard error of luminance over lit pixels (its own noise).
    pub noise: f64,
}

/// A solution's error against the truth.
pub struct TruthError {
    /// Mean absolute relative luminance error over the truth's lit pixels.
    pub mare: f64,
    /// HDR-FLIP (Andersson et al. 2021) at FLIP's default pixels per degree.
    pub flip: f32,
}

impl CornellTruth {
    /// Reads the fixture below the repository `root`.
    pub fn load(root: &Path) -> CornellTruth {
        let loaded = read_image(&root.join("tests/fixtures/cornell_truth_64.exr"))
            .expect("tests/fixtures/cornell_truth_64.exr reads");
        let noise = loaded
            .standard_error
            .as_ref()
            .map_or(f64::NAN, |se| reference_noise(&loaded.image, se));
        CornellTruth {
            image: loaded.image,
            noise,
        }
    }

    /// One line for a bench's output: what the truth columns are measured against.
    pub fn describe(&self) -> String {
        format!(
            "truth: tests/fixtures/cornell_truth_64.exr ({}x{}, standard camera, path-traced \
             by solver reference, own noise {:.2}%); vs truth = MARE and HDR-FLIP of the \
             solution rasterized at {RASTER_SIDE}x{RASTER_SIDE} and box-filtered to the \
             truth's pixels (bias plus noise)",
            self.image.width,
            self.image.height,
            100.0 * self.noise
        )
    }

    /// `solution` drawn from the standard camera, against the truth.
    pub fn error(&self, solution: &Solution) -> TruthError {
        let camera = Camera {
            eye: [278.0, 273.0, -800.0],
            target: [278.0, 273.0, 0.0],
            up: [0.0, 1.0, 0.0],
            fov_y_deg: 39.3077,
            width: RASTER_SIDE,
            height: RASTER_SIDE,
        };
        let image = raster_at_truth(solution, &camera, &self.image);
        TruthError {
            mare: summarize(&image, &self.image).mare,
            flip: flip(
                &image,
                &self.image,
                Variant::Hdr,
                default_pixels_per_degree(),
            )
            .expect("same sizes")
            .mean,
        }
    }
}

/// `solution` drawn by the CPU rasterizer (`solution::raster`, what the runtime
/// shows) from `camera` at RASTER_SIDE², box-filtered to the pixel footprints
/// of `truth` (whose sides must divide RASTER_SIDE).
pub fn raster_at_truth(solution: &Solution, camera: &Camera, truth: &Image) -> Image {
    let camera = Camera {
        width: RASTER_SIDE,
        height: RASTER_SIDE,
        ..*camera
    };
    let offset = glam::DVec3::from_array(solution.header.recentre_offset);
    let raster = render(
        solution,
        &camera.mono_view(offset),
        &RenderOptions::default(),
    )
    .expect("the solution renders");
    let image = Image {
        width: raster.width as usize,
        height: raster.height as usize,
        rgb: raster.pixels.iter().flatten().copied().collect(),
    };
    let factor = image
        .supersampling_factor(truth.width, truth.height)
        .expect("the raster is a whole multiple of the truth's size");
    image.box_downsample(factor)
}
