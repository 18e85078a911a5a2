//! Textured batches (solution format 2) on the GPU: a checkerboard quad with
//! constant E/π drawn by the textured pipeline beside an untextured quad drawn
//! by today's, against the CPU reference renderer, and the checkerboard's
//! contrast in the GPU image against the texture's own.

mod common;

use glam::DVec3;
use runtime::gpu::Gpu;
use runtime::render::{EyeImage, MultiviewMode, RendererDesc, StereoRenderer};
use runtime::session::OffscreenSwapchain;
use solution::camera::{Camera, EyeView};
use solution::format::{
    Batch, Representation, ScalarType, Solution, Texture, TextureSlot, TexturedVertex, Texturing,
    Vertex,
};

/// Texel values of the two squares (sRGB bytes) and their linear values.
const LIGHT: u8 = 230;
const DARK: u8 = 40;
/// Squares per side and texels per square side: a 64 × 64 texture.
const SQUARES: u32 = 8;
const SQUARE: u32 = 8;

fn checkerboard() -> Texture {
    let n = SQUARES * SQUARE;
    let rgba = (0..n * n)
        .flat_map(|k| {
            let (x, y) = (k % n / SQUARE, k / n / SQUARE);
            let b = if (x + y) % 2 == 0 { LIGHT } else { DARK };
            [b, b, b, 255]
        })
        .collect();
    Texture {
        width: n,
        height: n,
        rgba,
    }
}

fn quad_vertices(x0: f32) -> Vec<Vertex> {
    [[0.0, -1.0], [2.0, -1.0], [2.0, 1.0], [0.0, 1.0]]
        .iter()
        .map(|&[x, y]| Vertex {
            position: [x0 + x, y, -2.0],
            normal: [0.0, 0.0, 1.0],
            tangent: [1.0, 0.0, 0.0],
        })
        .collect()
}

/// A textured 2 × 2 quad at z = −2, x ∈ [−2, 0] (uv 0..1 over it, E/π = 1,
/// factor 1, no SH term), and an untextured one at x ∈ [0, 2] of radiance 0.5.
fn scene() -> Solution {
    let textured = Batch {
        representation: Representation::Sh { order: 0 },
        scalar: ScalarType::F32,
        vertices: quad_vertices(-2.0),
        coefficients: vec![0.0; 12],
        indices: vec![0, 1, 2, 0, 2, 3],
        texturing: Some(Texturing {
            texture: 0,
            factor: [1.0; 3],
            emission: None,
            vertices: [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
                .iter()
                .map(|&uv| TexturedVertex {
                    uv,
                    irradiance_over_pi: [1.0; 3],
                })
                .collect(),
        }),
    };
    let c00 = (0.5 / solution::sh::Y00) as f32;
    let plain = Batch {
        representation: Representation::Sh { order: 0 },
        scalar: ScalarType::F32,
        vertices: quad_vertices(0.0),
        coefficients: vec![c00; 12],
        indices: vec![0, 1, 2, 0, 2, 3],
        texturing: None,
    };
    Solution {
        lighting: None,
        header: common::header([-2.0, -1.0, -2.0], [2.0, 1.0, -2.0], near()),
        batches: vec![textured, plain],
        textures: vec![checkerboard()],
    }
}

/// Looking down −z at the textured quad's centre from (−1, 0, z).
fn camera(z: f64, fov_y_deg: f64, size: u32) -> Camera {
    Camera {
        eye: [-1.0, 0.0, z],
        target: [-1.0, 0.0, -2.0],
        up: [0.0, 1.0, 0.0],
        fov_y_deg,
        width: size,
        height: size,
    }
}

/// Near: the textured quad fills most of a 96² image (64 texels over ~83
/// pixels: magnified, level 0).
fn near() -> Camera {
    camera(0.0, 60.0, 96)
}

/// Far: from 8 units with tan(fov/2) = 1/6 the quad spans 3/4 of a 32² image,
/// 24 pixels for 64 texels (λ ≈ 1.4: minified, levels 1 and 2 blended).
fn far() -> Camera {
    camera(6.0, 2.0 * (1.0f64 / 6.0).atan().to_degrees(), 32)
}

fn render(gpu: &Gpu, solution: &Solution, view: &EyeView, mapped: bool) -> EyeImage {
    let swapchain = OffscreenSwapchain::new(gpu, view.width, view.height, 1).unwrap();
    let desc = RendererDesc {
        width: view.width,
        height: view.height,
        max_samples: 1,
        multiview: MultiviewMode::Auto,
        ..RendererDesc::default()
    };
    let (_dir, file) = common::mapped(solution);
    let mut renderer = if mapped {
        StereoRenderer::from_mapped(gpu, &file, desc, &swapchain.desc()).unwrap()
    } else {
        StereoRenderer::new(gpu, solution, desc, &swapchain.desc()).unwrap()
    };
    assert!(renderer.scene().is_textured());
    renderer.render(std::slice::from_ref(view), 0).unwrap();
    renderer.read_back(gpu, 0, 1).unwrap().remove(0)
}

// Tolerances against the CPU reference (relative to the reference's mean
// radiance, as `raster::compare` reports them). What sets them:
// * the half-float target: 2⁻¹¹ of the radiance bound (1, the textured term's
//   largest factor · E/π), 4.9e-4 absolute, 1.4e-3 of the near image's mean;
// * lavapipe filters 8-bit texels with fixed-point bilinear weights (8
//   fractional bits: up to 1/256 of the step between neighbouring texels on
//   the pixels that straddle a square's edge);
// * coverage at the quads' silhouettes (f32 transforms), which measured none.
// Near (level 0 only), measured mean 2.2e-3, p99 5.2e-3, no pixel above the
// default threshold: allowed mean 5e-3, p99 1e-2, 1% of pixels.
const NEAR: common::Tolerances = common::Tolerances {
    mean: 5e-3,
    p99: 1e-2,
    fraction: 0.01,
};
// Far (minified, λ ≈ 1.4), in addition: the level of detail. The reference
// takes λ from the exact derivatives; Vulkan lets an implementation
// approximate the scale factor ρ within a factor √2 ("Scale Factor
// Operation"), i.e. λ within half a level, and lavapipe differences 2 × 2
// quads. So levels 1 and 2 (which differ where bilinear filtering blurs the
// squares' edges) are blended in other proportions on most of the quad's
// pixels: measured mean 7.6e-3, p99 2.2e-2 (both 2% of the local radiance at
// most), 37.5% of pixels above the default threshold. Allowed: mean 1.5e-2,
// p99 5e-2, 60% of pixels (the quads cover ~70% of the image).
const FAR: common::Tolerances = common::Tolerances {
    mean: 1.5e-2,
    p99: 5e-2,
    fraction: 0.6,
};

#[test]
fn textured_quad_matches_the_cpu_reference_near_and_far() {
    common::use_lavapipe_unless_chosen();
    let gpu = common::gpu();
    let solution = scene();
    for (camera, name, tolerances) in [(near(), "near", NEAR), (far(), "far", FAR)] {
        let view = camera.mono_view(DVec3::ZERO);
        for mapped in [false, true] {
            let eye = render(&gpu, &solution, &view, mapped);
            let label = format!(
                "textured-{name}-{}",
                if mapped { "mapped" } else { "memory" }
            );
            common::assert_matches_cpu_reference(&label, &solution, &view, &eye, tolerances);
        }
    }
    common::assert_validation_clean(&gpu);
}

/// Michelson contrast (L_light − L_dark) / (L_light + L_dark).
fn contrast(light: f64, dark: f64) -> f64 {
    (light - dark) / (light + dark)
}

#[test]
fn checkerboard_contrast_in_the_gpu_image_is_at_least_80_percent_of_the_texture() {
    common::use_lavapipe_unless_chosen();
    let gpu = common::gpu();
    let solution = scene();
    let view = near().mono_view(DVec3::ZERO);
    let eye = render(&gpu, &solution, &view, true);
    // The texture's own contrast, from its linear texel values (E/π = 1 and
    // factor 1, so these are also the radiances an ideal image shows).
    let linear = |b: u8| f64::from(solution::texture::srgb8_to_linear(b));
    let texture = contrast(linear(LIGHT), linear(DARK));
    // Each square's centre: quad point x = −2 + 2·(i + ½)/8, y = 1 − 2·(j + ½)/8
    // (square (i, j) from the texture's top-left), projected to its pixel.
    let (mut light, mut dark) = (Vec::new(), Vec::new());
    let half = 2.0 * 30f64.to_radians().tan();
    for j in 0..SQUARES {
        for i in 0..SQUARES {
            let x = -2.0 + 2.0 * (f64::from(i) + 0.5) / f64::from(SQUARES);
            let y = 1.0 - 2.0 * (f64::from(j) + 0.5) / f64::from(SQUARES);
            let px = (((x + 1.0) / half + 1.0) * 0.5 * 96.0) as u32;
            let py = ((1.0 - y / half) * 0.5 * 96.0) as u32;
            let r = f64::from(eye.radiance[((py * 96 + px) * 3) as usize]);
            if (i + j) % 2 == 0 {
                light.push(r);
            } else {
                dark.push(r);
            }
        }
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let image = contrast(mean(&light), mean(&dark));
    eprintln!(
        "texture contrast {texture:.4}, GPU image {image:.4} (light {:.4}, dark {:.4})",
        mean(&light),
        mean(&dark)
    );
    assert!(
        image >= 0.8 * texture,
        "GPU contrast {image} below 80% of the texture's {texture}"
    );
    common::assert_validation_clean(&gpu);
}

/// The scene with format 3's second slot on the textured quad: E/π 0.5 and an
/// emission texture of 16-texel vertical stripes (32², another size than the
/// checkerboard, so each texture has its own level of detail) times
/// Ke = (0.5, 0.25, 0.5), so the quad shows 0.5 ρ(uv) + Ke ⊙ ρ_e(uv) ≤ 1.
fn two_slot_scene() -> Solution {
    let mut solution = scene();
    let t = solution.batches[0].texturing.as_mut().unwrap();
    for v in &mut t.vertices {
        v.irradiance_over_pi = [0.5; 3];
    }
    t.emission = Some(TextureSlot {
        texture: 1,
        factor: [0.5, 0.25, 0.5],
    });
    let stripes = (0..32 * 32)
        .flat_map(|k| {
            let b = if (k % 32) / 16 == 0 { LIGHT } else { DARK };
            [b, b, b, 255]
        })
        .collect();
    solution.textures.push(Texture {
        width: 32,
        height: 32,
        rgba: stripes,
    });
    solution
}

/// The textured pipeline's second sampler and push constants against the CPU
/// reference (a consistency check of the two renderers, with the tolerances
/// of the one-slot quad above: the radiance bound is still 1), and the CPU
/// reference without the emission slot differing far beyond them, so that a
/// pipeline dropping the emission texture fails. Measured at commit time
/// (lavapipe): mean 1.9e-3, p99 4.4e-3, no pixel above the threshold.
#[test]
fn a_quad_with_both_textures_matches_the_cpu_reference() {
    common::use_lavapipe_unless_chosen();
    let gpu = common::gpu();
    let solution = two_slot_scene();
    let view = near().mono_view(DVec3::ZERO);
    for mapped in [false, true] {
        let eye = render(&gpu, &solution, &view, mapped);
        let label = format!("two-slot-{}", if mapped { "mapped" } else { "memory" });
        common::assert_matches_cpu_reference(&label, &solution, &view, &eye, NEAR);
    }
    let options = solution::raster::RenderOptions::default();
    let with = solution::raster::render(&solution, &view, &options).unwrap();
    let mut without = solution.clone();
    without.batches[0].texturing.as_mut().unwrap().emission = None;
    let without = solution::raster::render(&without, &view, &options).unwrap();
    let diff = solution::raster::compare(&with, &without).unwrap();
    assert!(diff.mean_abs > 10.0 * NEAR.mean, "{diff:?}");
    common::assert_validation_clean(&gpu);
}

/// A texture byte corrupted on disk: the mapped open the runtime uses defers
/// the texture's checksum to the upload, which refuses the file naming it and
/// the texture (no panic, nothing drawn).
#[test]
fn a_corrupted_texture_is_refused_at_upload_naming_file_and_texture() {
    common::use_lavapipe_unless_chosen();
    let gpu = common::gpu();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("textured.sol");
    solution::format::write_solution(&path, &scene()).unwrap();
    let at = {
        let file = solution::format::MappedSolution::open(&path).unwrap();
        let png = file.texture_bytes(0).to_vec();
        // A byte in the middle of the PNG stream (its image data).
        let start = std::fs::read(&path)
            .unwrap()
            .windows(png.len())
            .position(|w| w == png)
            .unwrap();
        start + png.len() / 2
    };
    let mut bytes = std::fs::read(&path).unwrap();
    bytes[at] ^= 0x40;
    std::fs::write(&path, &bytes).unwrap();
    let file = solution::format::MappedSolution::open_deferring_checksums(&path).unwrap();
    let view = near().mono_view(DVec3::ZERO);
    let swapchain = OffscreenSwapchain::new(&gpu, view.width, view.height, 1).unwrap();
    let desc = RendererDesc {
        width: view.width,
        height: view.height,
        ..RendererDesc::default()
    };
    let error = match StereoRenderer::from_mapped(&gpu, &file, desc, &swapchain.desc()) {
        Ok(_) => panic!("a corrupted texture was uploaded"),
        Err(e) => e.to_string(),
    };
    assert!(error.contains("textured.sol"), "{error}");
    assert!(
        error.contains("texture 0") && error.contains("CRC-32"),
        "{error}"
    );
}
