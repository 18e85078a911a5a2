//! FLIP, a perceptual difference evaluator for images shown alternately
//! (Andersson et al. 2020, "FLIP: A Difference Evaluator for Alternating Images",
//! HPG 2020), and its high-dynamic-range form HDR-FLIP (Andersson et al. 2021,
//! "Visualizing Errors in Rendered High Dynamic Range Images", Eurographics 2021).
//!
//! LDR-FLIP (Andersson et al. 2020, §4): both images in YCxCz are filtered with
//! contrast sensitivity functions (§4.1), compared in Hunt-adjusted L*a*b* with
//! the HyAB distance and compressed to [0, 1] (§4.1.1); edges and points are
//! detected on the achromatic channel (§4.2) and their difference raises the colour
//! error to a lower power. HDR-FLIP (Andersson et al. 2021, §3) tone maps both
//! images with ACES at exposures spaced one stop apart between a start and a stop
//! exposure found from the reference, runs LDR-FLIP on each pair and keeps each
//! pixel's maximum.
//!
//! The arithmetic is f32 throughout, in the order of the authors' published
//! implementation (NVlabs' `flip-evaluator` 1.7, separable filters as described in
//! their note "separatedConvolutions.pdf"), so that results agree with it to a few
//! units in the last place; `tests/flip_reference.rs` checks that agreement against
//! numbers it produced.

use super::image::Image;
use rayon::prelude::*;

const PI: f32 = std::f32::consts::PI;

/// Pixels per degree of visual angle for an observer `distance` metres from a
/// display `width_m` metres wide with `resolution_x` pixels across
/// (Andersson et al. 2020, §4).
pub fn pixels_per_degree(distance: f32, resolution_x: f32, width_m: f32) -> f32 {
    distance * (resolution_x / width_m) * (PI / 180.0)
}

/// The FLIP authors' default observer: 0.7 m from a 0.7 m wide 3840-pixel monitor,
/// 67.02 pixels per degree.
pub fn default_pixels_per_degree() -> f32 {
    pixels_per_degree(0.7, 3840.0, 0.7)
}

/// Which FLIP is computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Variant {
    /// Inputs are linear RGB clamped to [0, 1], displayed as they are.
    Ldr,
    /// Inputs are linear radiance of any range, shown at several exposures.
    Hdr,
}

/// The exposures HDR-FLIP used, in stops (log2 of the scale applied before ACES).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Exposures {
    pub start: f32,
    pub stop: f32,
    pub count: usize,
}

/// A FLIP evaluation: the per-pixel error in [0, 1] and its mean.
#[derive(Debug, Clone, PartialEq)]
pub struct FlipResult {
    pub map: Vec<f32>,
    pub mean: f32,
    /// Present for HDR-FLIP.
    pub exposures: Option<Exposures>,
}

/// Why HDR-FLIP could not be evaluated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FlipError {
    #[error("the reference has no positive luminance, so HDR-FLIP's exposure range is undefined")]
    BlackReference,
    #[error("images differ in size")]
    SizeMismatch,
}

// Constants of Andersson et al. 2020: colour pipeline (§4.1: q_c = 0.7, p_c = 0.4,
// p_t = 0.95), feature detection (§4.2: w = 0.082 degrees, q_f = 0.5).
const QC: f32 = 0.7;
const PC: f32 = 0.4;
const PT: f32 = 0.95;
const FEATURE_WIDTH_DEG: f32 = 0.082;
const QF: f32 = 0.5;

/// Contrast sensitivity functions as sums of Gaussians a·sqrt(π/b)·exp(−π²x²/b)
/// for the achromatic, red-green and blue-yellow channels (§4.1, Table 1):
/// (a1, b1, a2, b2), b in degrees².
const CSF_Y: (f32, f32) = (1.0, 0.0047);
const CSF_CX: (f32, f32) = (1.0, 0.0053);
const CSF_CZ: [(f32, f32); 2] = [(34.1, 0.04), (13.5, 0.025)];

/// Evaluates FLIP between `test` and `reference` (linear RGB) at `ppd` pixels per
/// degree.
pub fn flip(
    test: &Image,
    reference: &Image,
    variant: Variant,
    ppd: f32,
) -> Result<FlipResult, FlipError> {
    flip_with_progress(test, reference, variant, ppd, &mut |_, _| {})
}

/// [`flip`], calling `progress(done, total)` after each exposure (LDR-FLIP has one).
pub fn flip_with_progress(
    test: &Image,
    reference: &Image,
    variant: Variant,
    ppd: f32,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<FlipResult, FlipError> {
    if test.width != reference.width || test.height != reference.height {
        return Err(FlipError::SizeMismatch);
    }
    match variant {
        Variant::Ldr => {
            let clamp = |img: &Image| {
                img.rgb
                    .iter()
                    .map(|v| v.clamp(0.0, 1.0))
                    .collect::<Vec<f32>>()
            };
            let map = ldr_flip(
                &clamp(reference),
                &clamp(test),
                reference.width,
                reference.height,
                ppd,
            );
            Ok(FlipResult {
                mean: mean_f32(&map),
                map,
                exposures: None,
            })
        }
        Variant::Hdr => hdr_flip(test, reference, ppd, progress),
    }
}

/// The mean as the reference implementation takes it: an f32 running sum.
fn mean_f32(map: &[f32]) -> f32 {
    map.iter().sum::<f32>() / map.len() as f32
}

/// ACES filmic curve as fitted by Narkowicz (2015), with the 0.6 pre-exposure
/// folded into the coefficients: (c²·t0 + c·t1 + t2) / (c²·t3 + c·t4 + t5).
const ACES: [f32; 6] = [
    0.6 * 0.6 * 2.51,
    0.6 * 0.03,
    0.0,
    0.6 * 0.6 * 2.43,
    0.6 * 0.59,
    0.14,
];

fn aces(c: f32) -> f32 {
    let t = &ACES;
    (c * c * t[0] + c * t[1] + t[2]) / (c * c * t[3] + c * t[4] + t[5])
}

/// HDR-FLIP's exposure range (Andersson et al. 2021, §3): the start exposure maps
/// the reference's largest luminance, the stop exposure its median, to where the
/// tone curve reaches 0.85; one exposure per stop, at least two.
pub fn exposure_range(reference: &Image) -> Result<Exposures, FlipError> {
    // Solve tone(x) = 0.85 for x: (t0 − 0.85 t3) x² + (t1 − 0.85 t4) x + (t2 − 0.85 t5) = 0.
    let target = 0.85f32;
    let a = ACES[0] - target * ACES[3];
    let b = ACES[1] - target * ACES[4];
    let c = ACES[2] - target * ACES[5];
    let x_max = if a == 0.0 {
        -c / b
    } else {
        let d1 = -0.5 * (b / a);
        let d2 = (d1 * d1 - c / a).sqrt();
        d1 + d2
    };
    let mut y = reference.luminances();
    let y_max = y.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    if y_max.is_nan() || y_max <= 0.0 {
        return Err(FlipError::BlackReference);
    }
    let middle = y.len() / 2;
    let (_, median, _) = y.select_nth_unstable_by(middle, f32::total_cmp);
    // A median of zero (more than half the image black) would put the stop at infinity.
    let median = median.max(f32::EPSILON);
    let start = (x_max / y_max).log2();
    let stop = (x_max / median).log2();
    // The median is at most the maximum, so start ≤ stop.
    let count = ((stop - start).ceil()).max(2.0) as usize;
    Ok(Exposures { start, stop, count })
}

fn hdr_flip(
    test: &Image,
    reference: &Image,
    ppd: f32,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<FlipResult, FlipError> {
    let exposures = exposure_range(reference)?;
    let (w, h) = (reference.width, reference.height);
    let step = (exposures.stop - exposures.start) / (exposures.count - 1) as f32;
    let mut map = vec![0.0f32; w * h];
    for i in 0..exposures.count {
        let exposure = exposures.start + i as f32 * step;
        let scale = 2.0f32.powf(exposure);
        let tone = |img: &Image| -> Vec<f32> {
            img.rgb
                .iter()
                .map(|&v| aces(v * scale).clamp(0.0, 1.0))
                .collect()
        };
        let ldr = ldr_flip(&tone(reference), &tone(test), w, h, ppd);
        for (m, e) in map.iter_mut().zip(ldr) {
            if e > *m {
                *m = e;
            }
        }
        progress(i + 1, exposures.count);
    }
    Ok(FlipResult {
        mean: mean_f32(&map),
        map,
        exposures: Some(exposures),
    })
}

// ---------------------------------------------------------------------------
// Colour spaces (sRGB primaries, D65 white), as in Andersson et al. 2020, §4.1.

// The white point and matrices are written with the digits the FLIP authors
// publish; the compiler rounds them to the nearest f32, as theirs does.
#[allow(clippy::excessive_precision)]
const D65: [f32; 3] = [0.950428545, 1.0, 1.088900371];
#[allow(clippy::excessive_precision)]
const INV_D65: [f32; 3] = [1.052156925, 1.0, 0.918357670];

fn linear_rgb_to_xyz(c: [f32; 3]) -> [f32; 3] {
    // The sRGB-to-XYZ matrix with D65 white, as exact ratios.
    let m = [
        [
            10135552.0 / 24577794.0,
            8788810.0 / 24577794.0,
            4435075.0 / 24577794.0,
        ],
        [
            2613072.0 / 12288897.0,
            8788810.0 / 12288897.0,
            887015.0 / 12288897.0,
        ],
        [
            1425312.0 / 73733382.0,
            8788810.0 / 73733382.0,
            70074185.0 / 73733382.0,
        ],
    ];
    mat3(&m, c)
}

#[allow(clippy::excessive_precision)]
fn xyz_to_linear_rgb(c: [f32; 3]) -> [f32; 3] {
    let m = [
        [3.241003275, -1.537398934, -0.498615861],
        [-0.969224334, 1.875930071, 0.041554224],
        [0.055639423, -0.204011202, 1.057148933],
    ];
    mat3(&m, c)
}

fn mat3(m: &[[f32; 3]; 3], c: [f32; 3]) -> [f32; 3] {
    [
        m[0][0] * c[0] + m[0][1] * c[1] + m[0][2] * c[2],
        m[1][0] * c[0] + m[1][1] * c[1] + m[1][2] * c[2],
        m[2][0] * c[0] + m[2][1] * c[1] + m[2][2] * c[2],
    ]
}

/// YCxCz, the linearised opponent space of Zhang & Wandell's S-CIELAB (1997):
/// L*a*b* without the cube root, so that filtering in it is linear.
fn xyz_to_ycxcz(c: [f32; 3]) -> [f32; 3] {
    let x = c[0] * INV_D65[0];
    let y = c[1] * INV_D65[1];
    let z = c[2] * INV_D65[2];
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

fn ycxcz_to_xyz(c: [f32; 3]) -> [f32; 3] {
    let y = (c[0] + 16.0) / 116.0;
    let cx = c[1] / 500.0;
    let cz = c[2] / 200.0;
    [(y + cx) * D65[0], y * D65[1], (y - cz) * D65[2]]
}

fn xyz_to_lab(c: [f32; 3]) -> [f32; 3] {
    let delta = 6.0f32 / 29.0;
    let delta_sq = delta * delta;
    let delta_cube = delta * delta_sq;
    let factor = 1.0 / (3.0 * delta_sq);
    let term = 4.0f32 / 29.0;
    let f = |t: f32| {
        if t > delta_cube {
            t.powf(1.0 / 3.0)
        } else {
            factor * t + term
        }
    };
    let x = f(c[0] * INV_D65[0]);
    let y = f(c[1] * INV_D65[1]);
    let z = f(c[2] * INV_D65[2]);
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

/// The Hunt effect (§4.1.1): chroma appears weaker at low lightness, so a* and b*
/// are scaled by 0.01·L*.
fn hunt(lab: [f32; 3]) -> [f32; 3] {
    [lab[0], 0.01 * lab[0] * lab[1], 0.01 * lab[0] * lab[2]]
}

/// HyAB distance (Abasi et al. 2020): city-block in lightness, Euclidean in chroma.
fn hyab(a: [f32; 3], b: [f32; 3]) -> f32 {
    let dl = (a[0] - b[0]).abs();
    let da = a[1] - b[1];
    let db = a[2] - b[2];
    dl + (da * da + db * db).sqrt()
}

/// The largest colour distance (§4.1.1): between Hunt-adjusted pure green and
/// pure blue, raised to q_c.
fn max_colour_distance() -> f32 {
    let green = hunt(xyz_to_lab(linear_rgb_to_xyz([0.0, 1.0, 0.0])));
    let blue = hunt(xyz_to_lab(linear_rgb_to_xyz([0.0, 0.0, 1.0])));
    hyab(green, blue).powf(QC)
}

// ---------------------------------------------------------------------------
// Filters.

/// The CSF Gaussian a·sqrt(π/b)·exp(−π²x²/b) in x² (degrees²).
fn csf_gaussian(x2: f32, a: f32, b: f32) -> f32 {
    a * (PI / b).sqrt() * (-(PI * PI) * x2 / b).exp()
}

/// One factor of the separable 2D CSF: sqrt of the 1D weight's amplitude, so that
/// the outer product of two such factors gives the 2D Gaussian.
fn csf_gaussian_sqrt(x2: f32, a: f32, b: f32) -> f32 {
    (a * (PI / b).sqrt()).sqrt() * (-(PI * PI) * x2 / b).exp()
}

/// The spatial filter radius in pixels: three standard deviations of the widest
/// CSF Gaussian (σ = sqrt(b / 2π²) degrees).
fn spatial_filter_radius(ppd: f32) -> usize {
    let widest = [CSF_Y.1, CSF_CX.1, CSF_CZ[0].1, CSF_CZ[1].1, 1.0e-5, 1.0e-5]
        .into_iter()
        .fold(0.0f32, f32::max);
    (3.0 * (widest / (2.0 * PI * PI)).sqrt() * ppd).ceil() as usize
}

/// 1D weights of the separable CSF filters: for Y and Cx (each a single Gaussian,
/// normalised to sum 1), and the two factors of Cz's sum of Gaussians, normalised
/// together so that the 2D filter Σ g_k(x)g_k(y) sums to 1.
struct SpatialFilters {
    y: Vec<f32>,
    cx: Vec<f32>,
    cz: [Vec<f32>; 2],
}

fn spatial_filters(ppd: f32) -> SpatialFilters {
    let radius = spatial_filter_radius(ppd) as i64;
    let dx = 1.0 / ppd;
    let mut f = SpatialFilters {
        y: Vec::new(),
        cx: Vec::new(),
        cz: [Vec::new(), Vec::new()],
    };
    for i in -radius..=radius {
        let x = i as f32 * dx;
        let x2 = x * x;
        f.y.push(csf_gaussian(x2, CSF_Y.0, CSF_Y.1));
        f.cx.push(csf_gaussian(x2, CSF_CX.0, CSF_CX.1));
        f.cz[0].push(csf_gaussian_sqrt(x2, CSF_CZ[0].0, CSF_CZ[0].1));
        f.cz[1].push(csf_gaussian_sqrt(x2, CSF_CZ[1].0, CSF_CZ[1].1));
    }
    let sum = |v: &[f32]| v.iter().sum::<f32>();
    let (sy, scx) = (1.0 / sum(&f.y), 1.0 / sum(&f.cx));
    let (s0, s1) = (sum(&f.cz[0]), sum(&f.cz[1]));
    let scz = 1.0 / (s0 * s0 + s1 * s1).sqrt();
    f.y.iter_mut().for_each(|w| *w *= sy);
    f.cx.iter_mut().for_each(|w| *w *= scx);
    f.cz.iter_mut().flatten().for_each(|w| *w *= scz);
    f
}

/// Feature detection kernels (§4.2): a Gaussian of σ = w/2 degrees and its first
/// and second derivatives, sampled at whole pixels to ±3σ. The Gaussian sums to 1;
/// each derivative's positive and negative lobes are normalised separately to sum
/// to +1 and −1.
struct FeatureFilter {
    g: Vec<f32>,
    dg: Vec<f32>,
    ddg: Vec<f32>,
}

fn feature_filter(ppd: f32) -> FeatureFilter {
    let sigma = 0.5 * FEATURE_WIDTH_DEG * ppd;
    let radius = (3.0 * sigma).ceil() as i64;
    let mut f = FeatureFilter {
        g: Vec::new(),
        dg: Vec::new(),
        ddg: Vec::new(),
    };
    for i in -radius..=radius {
        let x = i as f32;
        let g = (-(x * x) / (2.0 * sigma * sigma)).exp();
        f.g.push(g);
        f.dg.push(-x * g);
        f.ddg.push((x * x / (sigma * sigma) - 1.0) * g);
    }
    let g_sum: f32 = f.g.iter().sum();
    f.g.iter_mut().for_each(|w| *w /= g_sum);
    for lobe in [&mut f.dg, &mut f.ddg] {
        let (mut pos, mut neg) = (0.0f32, 0.0f32);
        for &w in lobe.iter() {
            if w > 0.0 {
                pos += w;
            } else {
                neg -= w;
            }
        }
        lobe.iter_mut()
            .for_each(|w| *w /= if *w > 0.0 { pos } else { neg });
    }
    f
}

/// Index `i + k − r` clamped to [0, n): the reference implementation's border rule
/// (edge pixels repeat).
#[inline]
fn clamped(i: usize, k: usize, r: usize, n: usize) -> usize {
    (i + k).saturating_sub(r).min(n - 1)
}

// ---------------------------------------------------------------------------
// LDR-FLIP.

/// LDR-FLIP of two linear RGB images with values in [0, 1]; returns the per-pixel
/// error.
fn ldr_flip(reference: &[f32], test: &[f32], w: usize, h: usize, ppd: f32) -> Vec<f32> {
    let to_ycxcz = |rgb: &[f32]| -> Vec<[f32; 3]> {
        rgb.par_chunks_exact(3)
            .map(|p| xyz_to_ycxcz(linear_rgb_to_xyz([p[0], p[1], p[2]])))
            .collect()
    };
    let (ref_ycc, test_ycc) = (to_ycxcz(reference), to_ycxcz(test));
    let colour = colour_difference(&ref_ycc, &test_ycc, w, h, &spatial_filters(ppd));
    let feature = feature_difference(&ref_ycc, &test_ycc, w, h, &feature_filter(ppd));
    colour
        .iter()
        .zip(&feature)
        .map(|(&c, &f)| c.powf(1.0 - f))
        .collect()
}

/// Horizontal pass of the CSF: (Y·wY, Cx·wCx, Cz·wCz0, Cz·wCz1) per pixel.
fn csf_rows(img: &[[f32; 3]], w: usize, f: &SpatialFilters) -> Vec<[f32; 4]> {
    let r = f.y.len() / 2;
    let mut out = vec![[0.0f32; 4]; img.len()];
    out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, o) in row.iter_mut().enumerate() {
            let mut acc = [0.0f32; 4];
            for k in 0..f.y.len() {
                let p = img[y * w + clamped(x, k, r, w)];
                acc[0] += f.y[k] * p[0];
                acc[1] += f.cx[k] * p[1];
                acc[2] += f.cz[0][k] * p[2];
                acc[3] += f.cz[1][k] * p[2];
            }
            *o = acc;
        }
    });
    out
}

/// Vertical pass of the CSF at one pixel: the filtered YCxCz.
fn csf_column(
    tmp: &[[f32; 4]],
    x: usize,
    y: usize,
    w: usize,
    h: usize,
    f: &SpatialFilters,
) -> [f32; 3] {
    let r = f.y.len() / 2;
    let mut acc = [0.0f32; 4];
    for k in 0..f.y.len() {
        let p = tmp[clamped(y, k, r, h) * w + x];
        acc[0] += f.y[k] * p[0];
        acc[1] += f.cx[k] * p[1];
        acc[2] += f.cz[0][k] * p[2];
        acc[3] += f.cz[1][k] * p[3];
    }
    [acc[0], acc[1], acc[2] + acc[3]]
}

/// The colour pipeline (§4.1): CSF filtering, back to linear RGB clamped to
/// [0, 1], Hunt-adjusted L*a*b*, HyAB^q_c, and the compression to [0, 1] that maps
/// [0, p_c·c_max) to [0, p_t) and [p_c·c_max, c_max] to [p_t, 1].
fn colour_difference(
    reference: &[[f32; 3]],
    test: &[[f32; 3]],
    w: usize,
    h: usize,
    f: &SpatialFilters,
) -> Vec<f32> {
    let cmax = max_colour_distance();
    let pccmax = PC * cmax;
    let (ref_rows, test_rows) = (csf_rows(reference, w, f), csf_rows(test, w, f));
    let perceived = |tmp: &[[f32; 4]], x, y| {
        let rgb = xyz_to_linear_rgb(ycxcz_to_xyz(csf_column(tmp, x, y, w, h, f)));
        hunt(xyz_to_lab(linear_rgb_to_xyz(
            rgb.map(|c| c.clamp(0.0, 1.0)),
        )))
    };
    let mut out = vec![0.0f32; w * h];
    out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, o) in row.iter_mut().enumerate() {
            let d = hyab(perceived(&ref_rows, x, y), perceived(&test_rows, x, y)).powf(QC);
            *o = if d < pccmax {
                d * (PT / pccmax)
            } else {
                PT + ((d - pccmax) / (cmax - pccmax)) * (1.0 - PT)
            };
        }
    });
    out
}

/// Horizontal pass of feature detection on the normalised achromatic channel
/// (Y + 16)/116: (∂x, ∂²x, Gaussian) per pixel.
fn feature_rows(img: &[[f32; 3]], w: usize, f: &FeatureFilter) -> Vec<[f32; 3]> {
    let r = f.g.len() / 2;
    let mut out = vec![[0.0f32; 3]; img.len()];
    out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, o) in row.iter_mut().enumerate() {
            let mut acc = [0.0f32; 3];
            for k in 0..f.g.len() {
                let v = img[y * w + clamped(x, k, r, w)][0] * (1.0 / 116.0) + 16.0 / 116.0;
                acc[0] += f.dg[k] * v;
                acc[1] += f.ddg[k] * v;
                acc[2] += f.g[k] * v;
            }
            *o = acc;
        }
    });
    out
}

/// Edge and point strengths at one pixel: |∇(G∗Y)| and |(∂²x, ∂²y)(G∗Y)|.
fn features_at(
    tmp: &[[f32; 3]],
    x: usize,
    y: usize,
    w: usize,
    h: usize,
    f: &FeatureFilter,
) -> (f32, f32) {
    let r = f.g.len() / 2;
    let (mut dx, mut ddx, mut dy, mut ddy) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
    for k in 0..f.g.len() {
        let p = tmp[clamped(y, k, r, h) * w + x];
        dx += f.g[k] * p[0];
        ddx += f.g[k] * p[1];
        dy += f.dg[k] * p[2];
        ddy += f.ddg[k] * p[2];
    }
    ((dx * dx + dy * dy).sqrt(), (ddx * ddx + ddy * ddy).sqrt())
}

/// The feature exponent (§4.2): (max(|Δedge|, |Δpoint|) / √2)^q_f.
fn feature_difference(
    reference: &[[f32; 3]],
    test: &[[f32; 3]],
    w: usize,
    h: usize,
    f: &FeatureFilter,
) -> Vec<f32> {
    let (ref_rows, test_rows) = (feature_rows(reference, w, f), feature_rows(test, w, f));
    let mut out = vec![0.0f32; w * h];
    out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, o) in row.iter_mut().enumerate() {
            let (edge_r, point_r) = features_at(&ref_rows, x, y, w, h, f);
            let (edge_t, point_t) = features_at(&test_rows, x, y, w, h, f);
            let d = (edge_r - edge_t).abs().max((point_r - point_t).abs());
            *o = ((1.0 / 2.0f32.sqrt()) * d).powf(QF);
        }
    });
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gradient(w: usize, h: usize) -> Image {
        let rgb = (0..w * h)
            .flat_map(|i| {
                let (x, y) = ((i % w) as f32 / w as f32, (i / w) as f32 / h as f32);
                [x, y, 0.5 * (x + y)]
            })
            .collect();
        Image {
            width: w,
            height: h,
            rgb,
        }
    }

    #[test]
    fn identical_images_have_zero_flip() {
        let image = gradient(24, 20);
        for variant in [Variant::Ldr, Variant::Hdr] {
            let result = flip(&image, &image, variant, 67.0).unwrap();
            assert!(result.map.iter().all(|&e| e == 0.0), "{variant:?}");
        }
    }

    #[test]
    fn filters_are_normalised() {
        // The CSF filters each integrate to 1 (in 2D, Σ_k (Σ g_k)² for Cz), and the
        // derivative lobes to ±1: checked to f32 rounding over ~20 terms.
        for ppd in [10.0, 30.0, 67.02] {
            let s = spatial_filters(ppd);
            assert!((s.y.iter().sum::<f32>() - 1.0).abs() < 1e-5);
            assert!((s.cx.iter().sum::<f32>() - 1.0).abs() < 1e-5);
            let cz: f32 = s.cz.iter().map(|v| v.iter().sum::<f32>().powi(2)).sum();
            assert!((cz - 1.0).abs() < 1e-5);
            let f = feature_filter(ppd);
            assert!((f.g.iter().sum::<f32>() - 1.0).abs() < 1e-5);
            let pos: f32 = f.dg.iter().filter(|w| **w > 0.0).sum();
            assert!((pos - 1.0).abs() < 1e-5);
        }
    }

    #[test]
    fn flip_is_bounded_and_grows_with_the_difference() {
        let reference = gradient(32, 32);
        let mut previous = 0.0;
        for k in [1.05f32, 1.3, 2.0] {
            let test = Image {
                rgb: reference.rgb.iter().map(|v| v * k).collect(),
                ..reference.clone()
            };
            let r = flip(&test, &reference, Variant::Hdr, 67.0).unwrap();
            assert!(r.map.iter().all(|&e| (0.0..=1.0).contains(&e)));
            assert!(r.mean > previous, "k = {k}: {} ≤ {previous}", r.mean);
            previous = r.mean;
        }
    }

    #[test]
    fn black_reference_has_no_exposure_range() {
        let black = Image::filled(4, 4, [0.0; 3]);
        assert_eq!(exposure_range(&black), Err(FlipError::BlackReference));
        assert!(flip(&black, &black, Variant::Ldr, 67.0).is_ok());
    }
}
