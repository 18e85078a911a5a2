//! Single-pass multiview, and the per-view workaround for lavapipe.
//!
//! **The bug.** Debian 12's Mesa 22.3.6 lavapipe mishandles primitives that are
//! clipped (by the near plane or the frustum sides) in a multiview draw with two
//! views: view 1's clipped pixels land in layer 0, and layer 1 stays empty where
//! those primitives should be. Any scene a walker can stand in clips something.
//!
//! **The workaround.** One multiview pass per view — view mask 0b01, then 0b10 —
//! with the same shaders (one pipeline per pass, since a pipeline belongs to a
//! render pass and the view mask is part of it). `gl_ViewIndex` still selects the
//! eye, so nothing else changes.
//!
//! **Choosing.** [`MultiviewMode::Auto`] uses the per-view path on lavapipe
//! (driver id `MESA_LLVMPIPE`, or a device name containing "llvmpipe") and a
//! single pass elsewhere. [`probe_clipping_bug`] renders a clipped triangle both
//! ways and reports whether the single pass is wrong: the tests use it to show
//! that the detection is needed, and `MultiviewMode::Probe` uses it at start-up.

use crate::gpu::Gpu;

/// How to draw the two eyes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum MultiviewMode {
    /// Per-view passes on lavapipe, a single pass elsewhere.
    #[default]
    Auto,
    /// Decide by rendering a clipped triangle at start-up ([`probe_clipping_bug`]).
    Probe,
    /// Always one pass with view mask 0b11 (wrong on lavapipe: for tests).
    SinglePass,
    /// Always one pass per view.
    PerView,
}

/// The path a renderer uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MultiviewPath {
    SinglePass,
    PerView,
}

impl MultiviewPath {
    /// The view masks of a stereo frame's passes, in order.
    pub fn stereo_masks(self) -> &'static [u32] {
        match self {
            MultiviewPath::SinglePass => &[0b11],
            MultiviewPath::PerView => &[0b01, 0b10],
        }
    }
}

/// The path for `mode` on this device.
pub fn resolve(gpu: &Gpu, mode: MultiviewMode) -> MultiviewPath {
    match mode {
        MultiviewMode::SinglePass => MultiviewPath::SinglePass,
        MultiviewMode::PerView => MultiviewPath::PerView,
        MultiviewMode::Auto => {
            if gpu.info.is_llvmpipe() {
                MultiviewPath::PerView
            } else {
                MultiviewPath::SinglePass
            }
        }
        MultiviewMode::Probe => match probe_clipping_bug(gpu) {
            Ok(false) => MultiviewPath::SinglePass,
            // A probe that fails to run leaves the safe path.
            Ok(true) | Err(_) => MultiviewPath::PerView,
        },
    }
}

/// Renders a triangle that crosses the near plane and the image's sides, in
/// one single-pass multiview draw and in per-view passes, and reports whether
/// the right eye (layer 1) differs between them — i.e. whether this device has
/// the multiview clipping bug.
pub fn probe_clipping_bug(gpu: &Gpu) -> Result<bool, crate::render::RenderError> {
    let (single, per_view) = probe_images(gpu)?;
    let differing = single
        .iter()
        .zip(&per_view)
        .filter(|(a, b)| (*a - *b).abs() > 1e-3)
        .count();
    Ok(differing > 0)
}

/// The right-eye radiance of the probe scene drawn single-pass and per view.
pub fn probe_images(gpu: &Gpu) -> Result<(Vec<f32>, Vec<f32>), crate::render::RenderError> {
    use crate::render::{RendererDesc, StereoRenderer};
    use crate::session::OffscreenSwapchain;
    let (solution, camera) = probe_scene();
    let size = 32;
    let swapchain = OffscreenSwapchain::new(gpu, size, size, 1)?;
    let mut right = Vec::new();
    for mode in [MultiviewMode::SinglePass, MultiviewMode::PerView] {
        let desc = RendererDesc {
            width: size,
            height: size,
            max_samples: 1,
            multiview: mode,
            ..RendererDesc::default()
        };
        let mut renderer = StereoRenderer::new(gpu, &solution, desc, &swapchain.desc())?;
        let views = camera.stereo_views(0.1, glam::DVec3::ZERO);
        renderer.render(&views, 0)?;
        let eyes = renderer.read_back(gpu, 0, 2)?;
        right.push(eyes[1].radiance.clone());
    }
    let per_view = right.pop().unwrap_or_default();
    let single = right.pop().unwrap_or_default();
    Ok((single, per_view))
}

/// A large diffuse floor under a camera looking along it: the floor crosses the
/// near plane and both sides of the image, so every view clips it.
fn probe_scene() -> (solution::format::Solution, solution::camera::Camera) {
    use solution::format::{Batch, Representation, ScalarType, Vertex};
    let v = |x: f32, z: f32| Vertex {
        position: [x, 0.0, z],
        normal: [0.0, 1.0, 0.0],
        tangent: [1.0, 0.0, 0.0],
    };
    let batch = Batch {
        representation: Representation::Sh { order: 0 },
        scalar: ScalarType::F32,
        vertices: vec![
            v(-10.0, 10.0),
            v(10.0, 10.0),
            v(10.0, -10.0),
            v(-10.0, -10.0),
        ],
        // Radiance 1 in every channel: c00 = 1 / Y00.
        coefficients: vec![(1.0 / solution::sh::Y00) as f32; 12],
        indices: vec![0, 1, 2, 0, 2, 3],
        texturing: None,
    };
    let camera = solution::camera::Camera {
        eye: [0.0, 0.5, 0.0],
        target: [0.0, 0.3, -1.0],
        up: [0.0, 1.0, 0.0],
        fov_y_deg: 60.0,
        width: 32,
        height: 32,
    };
    let header = solution::format::Header {
        units_per_metre: 1.0,
        up_axis: solution::camera::UpAxis::PosY,
        recentre_offset: [0.0; 3],
        camera,
        bounds_min: [-10.0, 0.0, -10.0],
        bounds_max: [10.0, 0.0, 10.0],
        partial: false,
        mode: solution::format::SolveMode::Diffuse,
        stats: Default::default(),
        settings_json: String::new(),
    };
    (
        solution::format::Solution {
            lighting: None,
            header,
            batches: vec![batch],
            textures: Vec::new(),
        },
        camera,
    )
}
