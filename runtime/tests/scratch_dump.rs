mod common;
use glam::DVec3;
use runtime::render::{MultiviewMode, RendererDesc, StereoRenderer};
use runtime::session::OffscreenSwapchain;
#[test]
fn dump() {
    let gpu = common::gpu();
    for (name, solution) in [("diffuse", common::diffuse_room(4)), ("glossy", common::glossy_room(16, 8))] {
        for mode in [MultiviewMode::SinglePass, MultiviewMode::Auto] {
            let (w, h) = (128, 128);
            let swapchain = OffscreenSwapchain::new(&gpu, w, h, 1).unwrap();
            let desc = RendererDesc { width: w, height: h, multiview: mode, ..RendererDesc::default() };
            let mut renderer = StereoRenderer::new(&gpu, &solution, desc, &swapchain.desc()).unwrap();
            let views = common::room_camera(w, h).stereo_views(0.3, DVec3::ZERO);
            renderer.render(&views, 0).unwrap();
            let eyes = renderer.read_back(&gpu, 0, 2).unwrap();
            for (i, e) in eyes.iter().enumerate() {
                let img = image::RgbaImage::from_raw(w, h, e.srgb.clone()).unwrap();
                img.save(format!("/tmp/dump-{name}-{mode:?}-{i}.png")).unwrap();
            }
        }
    }
    common::assert_validation_clean(&gpu);
}
