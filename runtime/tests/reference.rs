//! GPU images against the CPU reference rasterizer (`solution::raster`), stereo
//! parallax, and the view dependence of a glossy floor.

mod common;

use glam::DVec3;
use runtime::gpu::Gpu;
use runtime::render::{CoefficientStorage, EyeImage, MultiviewMode, RendererDesc, StereoRenderer};
use runtime::session::OffscreenSwapchain;
use solution::camera::{Camera, EyeView};
use solution::format::Solution;

fn render(gpu: &Gpu, solution: &Solution, views: &[EyeView], samples: u32) -> Vec<EyeImage> {
    render_with(gpu, solution, views, samples, CoefficientStorage::F32)
}

/// Renders `solution` written to a file with its coefficients stored as
/// `storage`, uploaded from the map as stored (`StereoRenderer::from_mapped`).
fn render_with(
    gpu: &Gpu,
    solution: &Solution,
    views: &[EyeView],
    samples: u32,
    storage: CoefficientStorage,
) -> Vec<EyeImage> {
    let (w, h) = (views[0].width, views[0].height);
    let swapchain = OffscreenSwapchain::new(gpu, w, h, 1).unwrap();
    let desc = RendererDesc {
        width: w,
        height: h,
        max_samples: samples,
        multiview: MultiviewMode::Auto,
        ..RendererDesc::default()
    };
    let (_dir, file) = common::mapped(&common::stored_as(solution, storage));
    let mut renderer = StereoRenderer::from_mapped(gpu, &file, desc, &swapchain.desc()).unwrap();
    assert_eq!(renderer.scene().storage, storage);
    renderer.render(views, 0).unwrap();
    renderer.read_back(gpu, 0, views.len()).unwrap()
}

/// Compares both eyes with the CPU reference; on failure writes
/// actual/expected/difference images and prints their folder.
fn check_against_reference(
    name: &str,
    solution: &Solution,
    samples: u32,
    storage: CoefficientStorage,
    mean_tol: f64,
    p99_tol: f64,
    fraction_tol: f64,
) {
    let gpu = common::gpu();
    let camera: Camera = common::room_camera(96, 80);
    let views = camera.stereo_views(0.3, DVec3::ZERO);
    let eyes = render_with(&gpu, solution, &views, samples, storage);
    let tol = common::Tolerances {
        mean: mean_tol,
        p99: p99_tol,
        fraction: fraction_tol,
    };
    for (eye, (view, label)) in eyes.iter().zip(views.iter().zip(["left", "right"])) {
        common::assert_matches_cpu_reference(&format!("{name}-{label}"), solution, view, eye, tol);
    }
    common::assert_validation_clean(&gpu);
}

// Tolerances (relative to the reference image's mean radiance, as
// `raster::compare` reports them). What sets them:
// * the half-float colour target: 2⁻¹¹ ≈ 4.9e-4 of the scene's radiance bound
//   (`GpuScene::radiance_scale`), about 1e-3 of the mean for these rooms;
// * f32 SH evaluation: below 1e-5 relative at L = 6 (`sh::f32_basis_tolerance`);
// * coverage: pixel centres within ~1/256 px of an edge may fall on the other
//   side on the GPU (f32 transforms). Inside the rooms radiance is continuous
//   across edges, so only the silhouette against the black background above
//   the walls (≈ 1 px × 96 px of 7680, i.e. ≤ 1.3% of pixels, each off by up to
//   ~2× the mean) matters: it can lift the mean by at most a few 1e-3 and stays
//   out of the 99th percentile unless more than 1% of pixels flip.
// Without MSAA: mean 2e-3, p99 5e-3, at most 1% of pixels above
// raster::DEFAULT_DIFF_THRESHOLD (measured: mean 5.5e-4, p99 2.4e-3, none).
// With 4× MSAA the reference (one sample at the centre) and the GPU (four
// samples) disagree on every silhouette pixel by up to the full step
// (background 0 against a wall at ~2× the mean): measured 2.9% of pixels differ,
// mean 9.2e-3, p99 0.37. Allowed: 5% of pixels, mean 5% × 0.5 = 2.5e-2, p99 1.0.

#[test]
fn diffuse_room_matches_cpu_reference_in_both_eyes() {
    let solution = common::diffuse_room(4);
    check_against_reference(
        "diffuse",
        &solution,
        1,
        CoefficientStorage::F32,
        2e-3,
        5e-3,
        0.01,
    );
}

#[test]
fn glossy_room_matches_cpu_reference_in_both_eyes() {
    let solution = common::glossy_room(12, 6);
    check_against_reference(
        "glossy",
        &solution,
        1,
        CoefficientStorage::F32,
        2e-3,
        5e-3,
        0.01,
    );
}

#[test]
fn msaa_image_stays_close_to_cpu_reference() {
    let solution = common::glossy_room(8, 4);
    check_against_reference(
        "glossy-msaa",
        &solution,
        4,
        CoefficientStorage::F32,
        2.5e-2,
        1.0,
        0.05,
    );
}

#[test]
fn order_16_floor_matches_cpu_reference_with_f32_and_f16_coefficients() {
    // The file's storage type, uploaded as stored: f16 rounds each coefficient
    // to 2⁻¹¹ relative (the writer's per-batch power-of-two scale keeps them
    // normal), and the radiance sums (L+1)² = 289 such terms whose signs vary,
    // so its error is a few 1e-4 of the lobe's peak; the bounds are those of
    // the f32 case. The reference is the f32 solution before rounding.
    let solution = common::glossy_room(12, 16);
    for storage in [CoefficientStorage::F32, CoefficientStorage::F16] {
        check_against_reference(
            &format!("glossy-L16-{storage:?}"),
            &solution,
            1,
            storage,
            2e-3,
            5e-3,
            0.01,
        );
    }
}

#[test]
fn parallax_of_a_known_point_is_ipd_times_focal_over_depth() {
    // A bright square facing the camera at depth 3 in front of a dim back wall.
    use solution::format::{Batch, Representation, ScalarType};
    let depth = 3.0;
    let quad = common::Quad {
        corner: DVec3::new(-0.15, 1.05, -depth),
        u: DVec3::new(0.3, 0.0, 0.0),
        v: DVec3::new(0.0, 0.3, 0.0),
        n: 1,
    };
    let (vertices, indices) = quad.vertices_and_indices();
    let marker = Batch {
        representation: Representation::Sh { order: 0 },
        scalar: ScalarType::F32,
        coefficients: vec![(5.0 / solution::sh::Y00) as f32; vertices.len() * 3],
        vertices,
        indices,
        texturing: None,
    };
    let camera = Camera {
        eye: [0.0, 1.2, 0.0],
        target: [0.0, 1.2, -1.0],
        up: [0.0, 1.0, 0.0],
        fov_y_deg: 60.0,
        width: 128,
        height: 96,
    };
    let solution = Solution {
        lighting: None,
        header: common::header([-0.15, 1.05, -3.0], [0.15, 1.35, -3.0], camera),
        batches: vec![marker],
        textures: Vec::new(),
    };
    let ipd = 0.3;
    let views = camera.stereo_views(ipd, DVec3::ZERO);
    let gpu = common::gpu();
    let eyes = render(&gpu, &solution, &views, 1);
    let (left, right) = (
        common::centroid(&eyes[0], 1.0),
        common::centroid(&eyes[1], 1.0),
    );
    let (f, _) = views[0].focal_lengths_px();
    let expected = ipd * f / depth;
    let measured = left.x - right.x;
    // Within 1 px (the criterion): the square's centroid is exact for a
    // fronto-parallel square; pixel sampling moves it by well under a pixel.
    assert!(
        (measured - expected).abs() < 1.0,
        "parallax {measured:.3} px, expected ipd·f/d = {expected:.3} px"
    );
    assert!((left.y - right.y).abs() < 0.5, "eyes differ vertically");
    // And each eye's centroid is where the f64 projection puts the square's centre.
    for (eye_c, view) in [left, right].iter().zip(&views) {
        let p = view.project_to_pixel(DVec3::new(0.0, 1.2, -depth)).unwrap();
        assert!((*eye_c - p).length() < 0.5, "{eye_c} vs {p}");
    }
    common::assert_validation_clean(&gpu);
}

#[test]
fn glossy_highlight_moves_on_the_floor_between_the_eyes() {
    // The highlight is the mirror image of common::LIGHT: for an eye at height
    // h_e and the light at h_l over the floor, moving the eye sideways by Δ moves
    // the mirror point by Δ·h_l/(h_e + h_l). A diffuse texture would not move.
    let solution = common::glossy_room(48, 8);
    let camera = common::room_camera(128, 128);
    let ipd = 0.6;
    let views = camera.stereo_views(ipd, DVec3::ZERO);
    let gpu = common::gpu();
    let eyes = render(&gpu, &solution, &views, 1);
    let mut floor_points = Vec::new();
    for (eye, view) in eyes.iter().zip(&views) {
        let max = eye
            .radiance
            .chunks_exact(3)
            .map(|p| p[0])
            .fold(0.0f32, f32::max);
        let c = common::centroid(eye, 0.7 * max);
        // Intersect the ray through the centroid with the floor y = 0.
        let ray = view.pixel_ray(c);
        let t = -view.position.y / ray.y;
        assert!(t > 0.0, "highlight is not on the floor");
        floor_points.push(view.position + ray * t);
    }
    let right_dir = views[1].position - views[0].position;
    let shift = (floor_points[1] - floor_points[0]).dot(right_dir.normalize());
    let (h_e, h_l) = (camera.eye[1], common::LIGHT.y);
    let expected = ipd * h_l / (h_e + h_l);
    // 25%: the highlight region is a thresholded blob of a Gouraud-shaded lobe on
    // a 1/6-unit mesh, plus a diffuse gradient; its centroid follows the mirror
    // point only approximately. A view-independent floor would give 0.
    assert!(
        (shift - expected).abs() < 0.25 * expected,
        "highlight moved {shift:.3} along the eye baseline, expected ≈ {expected:.3}"
    );
    common::assert_validation_clean(&gpu);
}
