//! The lavapipe multiview clipping bug and its workaround
//! (runtime::render::multiview).

mod common;

use glam::DVec3;
use runtime::render::multiview::{probe_clipping_bug, probe_images, resolve, MultiviewPath};
use runtime::render::{MultiviewMode, RendererDesc, StereoRenderer};
use runtime::session::OffscreenSwapchain;

/// Renders the diffuse room (floor through the near plane, walls across the
/// image edges) with `mode`; returns the right eye's radiance.
fn right_eye(gpu: &runtime::gpu::Gpu, mode: MultiviewMode) -> Vec<f32> {
    let solution = common::diffuse_room(4);
    let (w, h) = (64, 64);
    let swapchain = OffscreenSwapchain::new(gpu, w, h, 1).unwrap();
    let desc = RendererDesc {
        width: w,
        height: h,
        multiview: mode,
        ..RendererDesc::default()
    };
    let mut renderer = StereoRenderer::new(gpu, &solution, desc, &swapchain.desc()).unwrap();
    let views = common::room_camera(w, h).stereo_views(0.064, DVec3::ZERO);
    renderer.render(&views, 0).unwrap();
    let eyes = renderer.read_back(gpu, 0, 2).unwrap();
    eyes[1].radiance.clone()
}

#[test]
fn lavapipe_needs_the_per_view_path_and_auto_detects_it() {
    let gpu = common::gpu();
    let has_bug = probe_clipping_bug(&gpu).unwrap();
    if gpu.info.is_llvmpipe() {
        // Debian 12's Mesa 22.3.6 lavapipe has the bug; if a newer Mesa fixes it
        // this assertion tells us the per-view path can be retired there.
        assert!(
            has_bug,
            "expected lavapipe ({}) to show the multiview clipping bug",
            gpu.info.describe()
        );
    }
    // Auto must pick the per-view path wherever the probe sees the bug.
    if has_bug {
        assert_eq!(resolve(&gpu, MultiviewMode::Auto), MultiviewPath::PerView);
    }
    assert_eq!(
        resolve(&gpu, MultiviewMode::Probe),
        if has_bug {
            MultiviewPath::PerView
        } else {
            MultiviewPath::SinglePass
        }
    );
    common::assert_validation_clean(&gpu);
}

#[test]
fn single_pass_loses_the_right_eye_on_lavapipe_and_per_view_does_not() {
    let gpu = common::gpu();
    let (single, per_view) = probe_images(&gpu).unwrap();
    // The probe floor covers the lower part of the image with radiance 1.
    let lit = |img: &[f32]| img.chunks_exact(3).filter(|p| p[0] > 0.5).count();
    let pixels = 32 * 32;
    assert!(
        lit(&per_view) > pixels / 4,
        "per-view right eye shows the floor"
    );

    let single_room = right_eye(&gpu, MultiviewMode::SinglePass);
    let per_view_room = right_eye(&gpu, MultiviewMode::PerView);
    let auto_room = right_eye(&gpu, MultiviewMode::Auto);
    let differing = |a: &[f32], b: &[f32]| {
        a.chunks_exact(3)
            .zip(b.chunks_exact(3))
            .filter(|(p, q)| p.iter().zip(q.iter()).any(|(x, y)| (x - y).abs() > 1e-3))
            .count()
    };
    if probe_clipping_bug(&gpu).unwrap() {
        // The default path is the per-view one, pixel for pixel (its right eye
        // is compared with the CPU reference in tests/reference.rs).
        assert_eq!(differing(&auto_room, &per_view_room), 0);
        // Forcing one pass breaks the right eye: the floor crosses the near
        // plane and the walls cross the image edges, so most of the image is
        // made of clipped triangles.
        assert!(lit(&single) < lit(&per_view));
        let wrong = differing(&single_room, &per_view_room);
        assert!(
            wrong > 64 * 64 / 4,
            "single pass on a buggy driver was expected to spoil the right eye; {wrong} pixels differ"
        );
    }
    common::assert_validation_clean(&gpu);
}
