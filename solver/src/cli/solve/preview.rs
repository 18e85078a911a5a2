//! `--preview PNG`: a CPU rendering of the solution (the same rasterizer the
//! runtime's images are checked against), exposed and tone-mapped to sRGB.

use anyhow::Context;
use glam::DVec3;
use image::ImageEncoder;
use solution::camera::Camera;
use solution::format::Solution;
use solution::raster::{self, RenderOptions, ToneCurve};
use std::path::Path;

/// Mid-grey key for the automatic exposure (Reinhard et al. 2002): the radiance
/// level of a scene depends on its emitters and units, so a fixed exposure would
/// give black or white previews.
const EXPOSURE_KEY: f32 = 0.18;

/// The camera of the preview: the scene's (TOML config, or display file, already
/// merged by the caller), else the solution header's default view.
pub fn choose_camera(scene_camera: Option<Camera>, solution: &Solution) -> Camera {
    scene_camera.unwrap_or(solution.header.camera)
}

/// Renders `solution` from `camera` and writes an sRGB PNG of the camera's image
/// size atomically.
pub fn write_preview(path: &Path, solution: &Solution, camera: &Camera) -> anyhow::Result<()> {
    let context = || format!("writing the preview {}", path.display());
    camera.validate().with_context(context)?;
    let view = camera.mono_view(DVec3::from_array(solution.header.recentre_offset));
    let image = raster::render(solution, &view, &RenderOptions::default()).with_context(context)?;
    // A file with lights is exposed from its stored key, as the runtime
    // exposes it (its sky would otherwise weigh in the image's average).
    let stops = solution
        .lighting
        .as_ref()
        .and_then(|l| raster::tonemap::key_exposure_stops(l.exposure_key, EXPOSURE_KEY))
        .unwrap_or_else(|| raster::auto_exposure_stops(&image, EXPOSURE_KEY));
    let rgb = raster::tonemap_srgb8(&image, stops, ToneCurve::AcesFit);
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new(&mut png)
        .write_image(
            &rgb,
            image.width,
            image.height,
            image::ExtendedColorType::Rgb8,
        )
        .with_context(context)?;
    super::files::write_atomic(path, &png)
}
