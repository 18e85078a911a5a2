//! Per-chunk frustum culling (`runtime::render::cull`) changes no pixel: the
//! same mapped city drawn with culling on and off gives identical images, for
//! a stereo pair and a mono view, while culling drops most chunks.
//!
//! This is a consistency check (both images come from the same renderer, with
//! the same reordered index buffer), not a check against an outside truth: the
//! reorder itself is held to the CPU reference by `tests/reference.rs`.

mod common;

use glam::DVec3;
use runtime::render::{CullStats, Culling, EyeImage, MultiviewMode, RendererDesc, StereoRenderer};
use runtime::session::OffscreenSwapchain;
use solution::camera::EyeView;

fn render(
    file: &solution::format::MappedSolution,
    views: &[EyeView],
    culling: Culling,
) -> (Vec<EyeImage>, CullStats) {
    let gpu = common::gpu();
    let (w, h) = (views[0].width, views[0].height);
    let swapchain = OffscreenSwapchain::new(&gpu, w, h, 1).unwrap();
    let desc = RendererDesc {
        width: w,
        height: h,
        max_samples: 4,
        multiview: MultiviewMode::Auto,
        culling,
        ..RendererDesc::default()
    };
    let mut renderer = StereoRenderer::from_mapped(&gpu, file, desc, &swapchain.desc()).unwrap();
    renderer.render(views, 0).unwrap();
    let eyes = renderer.read_back(&gpu, 0, views.len()).unwrap();
    common::assert_validation_clean(&gpu);
    (eyes, renderer.cull_stats())
}

/// Exact equality: a culled chunk lies wholly outside a clip plane of every
/// view its pass draws, so none of its triangles covers a sample, and the
/// triangles that are drawn are drawn in the same order (the chunks keep their
/// place in the index buffer), so depth ties resolve the same way. Any
/// differing pixel is a culling bug.
#[test]
fn culling_changes_no_pixel_of_a_city_street() {
    // 6 × 6 buildings of 4 × 4 cells per face (5,760 triangles plus the
    // ground's 1,152) in chunks of at most 64 triangles.
    let solution = common::city(6, 4);
    let (_dir, file) = common::mapped(&solution);
    let mut camera = solution.header.camera;
    camera.width = 96;
    camera.height = 80;
    let stereo = camera.stereo_views(0.064, DVec3::ZERO);
    let mono = [camera.mono_view(DVec3::ZERO)];
    for views in [&stereo[..], &mono[..]] {
        let on = Culling {
            enabled: true,
            chunk_triangles: 64,
        };
        let off = Culling {
            enabled: false,
            ..on
        };
        let (culled, kept) = render(&file, views, on);
        let (full, all) = render(&file, views, off);
        assert_eq!(all.triangles_drawn, all.triangles);
        // The street view sees under half of the city (the half behind the
        // eye and the blocks beside the street's wedge): over half of the
        // triangles' chunks are dropped.
        assert!(
            2 * kept.triangles_drawn < kept.triangles,
            "culling kept {} of {} triangles",
            kept.triangles_drawn,
            kept.triangles
        );
        for (eye, (a, b)) in culled.iter().zip(&full).enumerate() {
            let differing = a
                .radiance
                .iter()
                .zip(&b.radiance)
                .filter(|(x, y)| x.to_bits() != y.to_bits())
                .count();
            assert_eq!(differing, 0, "eye {eye}: {differing} values differ");
            assert_eq!(a.srgb, b.srgb, "eye {eye}: sRGB differs");
            // Not an empty image: the street is lit.
            assert!(a.radiance.iter().any(|&r| r > 0.1));
        }
    }
}
