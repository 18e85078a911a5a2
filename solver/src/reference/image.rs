//! Image accumulation: per pixel, the running sums of the radiance samples and
//! of their squares (R, G, B and luminance), from which the mean (the pixel's
//! value: mean radiance over its footprint) and the standard error of that mean
//! follow; rendering one pass of samples in parallel, deterministically.

use super::camera::pixel_ray;
use super::integrator::Integrator;
use crate::geometry::sampling::{stream_id, Rng};
use glam::DVec3;
use rayon::prelude::*;
use solution::camera::EyeView;

/// Rec. 709 luminance weights (linear RGB): the scalar whose relative error
/// `--target-error` measures.
pub const LUMINANCE: [f64; 3] = [0.2126, 0.7152, 0.0722];

/// One pixel's sums: `sum[c]`, `sum_sq[c]` for c = R, G, B, luminance.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PixelSums {
    pub count: u64,
    pub sum: [f64; 4],
    pub sum_sq: [f64; 4],
}

impl PixelSums {
    fn add(&mut self, l: DVec3) {
        let y = l.x * LUMINANCE[0] + l.y * LUMINANCE[1] + l.z * LUMINANCE[2];
        for (c, v) in [l.x, l.y, l.z, y].into_iter().enumerate() {
            self.sum[c] += v;
            self.sum_sq[c] += v * v;
        }
        self.count += 1;
    }

    /// The mean of channel `c`.
    pub fn mean(&self, c: usize) -> f64 {
        if self.count == 0 {
            0.0
        } else {
            self.sum[c] / self.count as f64
        }
    }

    /// The standard error of channel `c`'s mean, `√(s² / n)` with the unbiased
    /// sample variance s² (infinite with fewer than two samples).
    pub fn standard_error(&self, c: usize) -> f64 {
        if self.count < 2 {
            return f64::INFINITY;
        }
        let n = self.count as f64;
        let mean = self.sum[c] / n;
        let var = ((self.sum_sq[c] - n * mean * mean) / (n - 1.0)).max(0.0);
        (var / n).sqrt()
    }
}

/// The image being rendered.
#[derive(Clone, Debug, PartialEq)]
pub struct Accumulator {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<PixelSums>,
    /// Passes rendered so far.
    pub passes: u64,
}

impl Accumulator {
    pub fn new(width: u32, height: u32) -> Accumulator {
        Accumulator {
            width,
            height,
            pixels: vec![PixelSums::default(); width as usize * height as usize],
            passes: 0,
        }
    }

    /// Adds `spp` samples to every pixel: positions uniform over the pixel
    /// square, each pixel's random stream keyed by `(seed, pass, pixel)` so the
    /// result does not depend on the thread count. Rows are rendered in
    /// parallel on the current rayon pool; `progress` is called with each
    /// finished row's sample count.
    pub fn render_pass(
        &mut self,
        integrator: &Integrator,
        view: &EyeView,
        seed: u64,
        spp: u32,
        progress: &(dyn Fn(u64) + Sync),
    ) {
        let pass = self.passes;
        let width = self.width;
        self.pixels
            .par_chunks_mut(width as usize)
            .enumerate()
            .for_each(|(j, row)| {
                for (i, pixel) in row.iter_mut().enumerate() {
                    let index = j as u64 * width as u64 + i as u64;
                    let mut rng = Rng::new(seed, stream_id(pass, index));
                    for _ in 0..spp {
                        let (du, dv) = (rng.next_f64(), rng.next_f64());
                        let (o, d) = pixel_ray(view, i as u32, j as u32, du, dv);
                        let l = integrator.radiance(o, d, &mut rng);
                        // A non-finite sample (never expected) would poison the
                        // pixel forever: count it as black instead.
                        pixel.add(if l.is_finite() { l } else { DVec3::ZERO });
                    }
                }
                progress(spp as u64 * row.len() as u64);
            });
        self.passes += 1;
    }

    /// The mean over lit pixels (mean luminance > 0) of the luminance's relative
    /// standard error `se(Y) / Y`; `None` when no pixel is lit yet.
    pub fn mean_relative_error(&self) -> Option<f64> {
        let (mut sum, mut lit) = (0.0, 0usize);
        for p in &self.pixels {
            let y = p.mean(3);
            if y > 0.0 {
                sum += p.standard_error(3) / y;
                lit += 1;
            }
        }
        (lit > 0).then(|| sum / lit as f64)
    }

    /// Samples taken per pixel so far.
    pub fn samples_per_pixel(&self) -> u64 {
        self.pixels.first().map_or(0, |p| p.count)
    }
}

/// The material and object index of the surface that the ray through each
/// pixel's centre meets (front or back), `-1` where it meets nothing; row-major.
pub fn id_buffers(integrator: &Integrator, view: &EyeView) -> (Vec<i32>, Vec<i32>) {
    let (w, h) = (view.width, view.height);
    let ids: Vec<(i32, i32)> = (0..w as u64 * h as u64)
        .into_par_iter()
        .map(|index| {
            let (i, j) = ((index % w as u64) as u32, (index / w as u64) as u32);
            let (o, d) = pixel_ray(view, i, j, 0.5, 0.5);
            match integrator.intersect(o, d) {
                Some(hit) => {
                    let s = &integrator.scene.surfaces[hit.polygon];
                    (s.material as i32, s.object as i32)
                }
                None => (-1, -1),
            }
        })
        .collect();
    ids.into_iter().unzip()
}
