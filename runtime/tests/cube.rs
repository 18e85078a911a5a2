//! The global-cube batches (Immel, Cohen & Greenberg 1986, "The global cube")
//! on the GPU (`shaders/scene_cube.vert`) against the CPU reference rasterizer (`solution::raster`, which looks cubes up with
//! `solution::cube::eval_rgb`), and the view dependence of a glossy cube floor.

mod common;

use glam::DVec3;
use runtime::gpu::Gpu;
use runtime::render::{
    CoefficientStorage, DrawKind, EyeImage, MultiviewMode, RendererDesc, StereoRenderer,
};
use runtime::session::OffscreenSwapchain;
use solution::camera::EyeView;
use solution::format::Solution;

/// Cells along a cube face edge: D = 6·12² = 864 directions per vertex. A cell
/// spans about 9° at the face centre, half the lobe's 19° half-width at half
/// maximum (cos^12), so the highlight is resolved by a few cells.
const RESOLUTION: u32 = 12;
/// The floor's subdivisions: (24 + 1)² = 625 vertices.
const FLOOR_SUBDIVISIONS: usize = 24;

fn render(
    gpu: &Gpu,
    solution: &Solution,
    views: &[EyeView],
    storage: CoefficientStorage,
    max_order: Option<u32>,
) -> Vec<EyeImage> {
    let (w, h) = (views[0].width, views[0].height);
    let swapchain = OffscreenSwapchain::new(gpu, w, h, 1).unwrap();
    let desc = RendererDesc {
        width: w,
        height: h,
        max_samples: 1,
        multiview: MultiviewMode::Auto,
        max_order,
        ..RendererDesc::default()
    };
    // Written with its values stored as `storage` and uploaded as stored.
    let (_dir, file) = common::mapped(&common::stored_as(solution, storage));
    let mut renderer = StereoRenderer::from_mapped(gpu, &file, desc, &swapchain.desc()).unwrap();
    assert_eq!(renderer.scene().storage, storage);
    let draws = &renderer.scene().draws;
    assert_eq!(draws.len(), 2);
    assert_eq!(
        draws[0].kind,
        DrawKind::Sh,
        "the L = 0 walls are drawn first"
    );
    assert_eq!(
        draws[1].kind,
        DrawKind::Cube {
            resolution: RESOLUTION
        }
    );
    renderer.render(views, 0).unwrap();
    renderer.read_back(gpu, 0, views.len()).unwrap()
}

// Tolerances: those of the SH reference test (runtime/tests/reference.rs),
// relative to the reference image's mean radiance as `raster::compare` reports
// them: mean 2e-3, p99 5e-3, at most 1% of pixels above
// raster::DEFAULT_DIFF_THRESHOLD. What sets them here:
// * the half-float colour target: 2⁻¹¹ ≈ 4.9e-4 of the radiance bound (the
//   largest cube value, 2.2 here, against a mean near 0.5: ≈ 2e-3 of the mean
//   at the very brightest pixels, far less elsewhere);
// * the lookup in f32: the cell coordinate is rounded by a few ulps of k, and
//   the weights move by as much, so the radiance by ~1e-6 relative; the face is
//   chosen alike in f32 and f64 except within rounding of a face edge;
// * f16 coefficients: each value rounded to 2⁻¹¹ relative, blended with
//   convex weights, so at most 4.9e-4 of the local radiance;
// * coverage at the silhouette above the walls, as in the SH test.
const MEAN_TOL: f64 = 2e-3;
const P99_TOL: f64 = 5e-3;
const FRACTION_TOL: f64 = 0.01;

#[test]
fn cube_room_matches_cpu_reference_in_both_eyes_with_f32_and_f16_values() {
    let solution = common::cube_room(FLOOR_SUBDIVISIONS, RESOLUTION);
    let gpu = common::gpu();
    let camera = common::room_camera(96, 80);
    let views = camera.stereo_views(0.3, DVec3::ZERO);
    for storage in [CoefficientStorage::F32, CoefficientStorage::F16] {
        let eyes = render(&gpu, &solution, &views, storage, None);
        for (eye, (view, label)) in eyes.iter().zip(views.iter().zip(["left", "right"])) {
            common::assert_matches_cpu_reference(
                &format!("cube-{storage:?}-{label}"),
                &solution,
                view,
                eye,
                common::Tolerances {
                    mean: MEAN_TOL,
                    p99: P99_TOL,
                    fraction: FRACTION_TOL,
                },
            );
        }
    }
    common::assert_validation_clean(&gpu);
}

#[test]
fn an_order_cap_leaves_cube_batches_alone() {
    // `--max-order 0` drops SH bands; a cube lookup has no bands and must draw
    // the same image, pixel for pixel (same shaders, same inputs).
    let solution = common::cube_room(8, RESOLUTION);
    let gpu = common::gpu();
    let views = common::room_camera(48, 40).stereo_views(0.3, DVec3::ZERO);
    let plain = render(&gpu, &solution, &views, CoefficientStorage::F32, None);
    let capped = render(&gpu, &solution, &views, CoefficientStorage::F32, Some(0));
    for (a, b) in plain.iter().zip(&capped) {
        assert_eq!(a.radiance, b.radiance);
    }
    common::assert_validation_clean(&gpu);
}

#[test]
fn cube_highlight_moves_on_the_floor_between_the_eyes() {
    // As for the SH floor (reference.rs): the highlight is the mirror image of
    // common::LIGHT, so moving an eye at height h_e sideways by Δ moves the
    // mirror point on the floor by Δ·h_l/(h_e + h_l). A view-independent floor
    // would not move it at all.
    let solution = common::cube_room(FLOOR_SUBDIVISIONS, RESOLUTION);
    let camera = common::room_camera(128, 128);
    let ipd = 0.6;
    let views = camera.stereo_views(ipd, DVec3::ZERO);
    let gpu = common::gpu();
    let eyes = render(&gpu, &solution, &views, CoefficientStorage::F32, None);
    let mut floor_points = Vec::new();
    for (eye, view) in eyes.iter().zip(&views) {
        let max = eye
            .radiance
            .chunks_exact(3)
            .map(|p| p[0])
            .fold(0.0f32, f32::max);
        let c = common::centroid(eye, 0.7 * max);
        let ray = view.pixel_ray(c);
        let t = -view.position.y / ray.y;
        assert!(t > 0.0, "highlight is not on the floor");
        floor_points.push(view.position + ray * t);
    }
    let right_dir = views[1].position - views[0].position;
    let shift = (floor_points[1] - floor_points[0]).dot(right_dir.normalize());
    let (h_e, h_l) = (camera.eye[1], common::LIGHT.y);
    let expected = ipd * h_l / (h_e + h_l);
    eprintln!("cube highlight shift {shift:.4}, mirror-point shift {expected:.4}");
    // 25%, as for SH: the highlight is a thresholded blob of a Gouraud-shaded
    // lobe on a 1/3-unit mesh, looked up between cells about 9° apart, on a
    // diffuse gradient; its centroid follows the mirror point only
    // approximately. A view-independent floor gives 0.
    assert!(
        (shift - expected).abs() < 0.25 * expected,
        "highlight moved {shift:.3} along the eye baseline, expected ≈ {expected:.3}"
    );
    common::assert_validation_clean(&gpu);
}
