//! A small CPU rasterizer: the reference renderer that the runtime's Vulkan images
//! are checked against pixel by pixel, and the solver's `--preview`.
//!
//! [`render`] draws a [`Solution`] as the runtime's pipeline does, step for step:
//!
//! 1. **Vertex stage.** Each vertex's outgoing radiance is its batch's spherical
//!    harmonics evaluated (in f64, [`crate::sh::eval_rgb_with`]) toward the eye:
//!    the direction from the vertex to [`EyeView::position`], normalised and taken
//!    into the vertex's frame ([`crate::sh::to_local`]; n = `normal`, t = `tangent`,
//!    re-orthonormalised by [`crate::sh::orthonormal_frame`] since the stored frame
//!    is f32). Order-0 (diffuse) batches are constant. The order can be capped by
//!    [`RenderOptions::max_order`] (the first `(L'+1)²` coefficients of each
//!    channel). Negative radiance (ringing of a truncated expansion) is clamped to
//!    0 per vertex, before interpolation, unless [`RenderOptions::clamp_negative`]
//!    is off. Discrete-direction (Immel, Cohen and Greenberg's (1986) global cube) batches are looked up toward
//!    the same local direction by [`crate::cube::eval_rgb`] (bilinear between the
//!    four nearest cell centres of the face the direction leaves through; the
//!    order cap does not apply to them), and clamped the same way.
//!    Positions go to clip space by [`EyeView::view_projection`].
//! 2. **Clipping** in homogeneous coordinates against the near plane (`z ≥ 0`),
//!    the far plane (`z ≤ w`) and a guard band `|x|, |y| ≤ 4w` outside the image
//!    (which changes no pixel; it bounds the fixed-point arithmetic). Radiance is
//!    interpolated linearly in clip space at new vertices, which is exact because
//!    it is an affine function of the 3-D point there. So a triangle crossing the
//!    near plane, or passing behind the eye, draws exactly its visible part.
//! 3. **Rasterization** with Vulkan's rules: positions are snapped to 1/256 pixel
//!    ([`SUBPIXEL_BITS`], the `subPixelPrecisionBits` of common GPUs and lavapipe),
//!    edge functions are exact integers, a pixel is covered when its centre
//!    `(i + 0.5, j + 0.5)` is inside, and a centre exactly on an edge belongs to the
//!    triangle for which the edge is a top or a left edge (so triangles sharing an
//!    edge cover each pixel exactly once: no cracks, no double blending).
//! 4. **Culling**: front faces are counter-clockwise seen from the side the normal
//!    points to; with the y-down projection of [`crate::camera`] they are
//!    counter-clockwise in Vulkan's framebuffer sense, so the GPU pipeline uses
//!    `frontFace = COUNTER_CLOCKWISE`, `cullMode = BACK`. Zero-area triangles draw
//!    nothing.
//! 5. **Interpolation**: radiance is interpolated perspective-correctly (Vulkan's
//!    default `smooth` qualifier: `Σ λ_i r_i / w_i / Σ λ_i / w_i` with screen
//!    barycentrics λ), depth `z/w` linearly in screen space, as Vulkan does.
//!    **Textured batches** (solution format 2) add, per fragment, the texture's
//!    linear RGB ρ(u, v) times the interpolated `factor · E/π` (both
//!    interpolated perspective-correctly like the radiance), ρ filtered as a
//!    Vulkan sampler with `LINEAR` min/mag/mipmap filters and `REPEAT` does
//!    ([`crate::texture::MipChain::sample_trilinear`], over the same mip levels
//!    the runtime uploads) at the level of detail of the exact derivatives of
//!    (u, v) at the pixel centre (a GPU differences them across a 2 × 2 quad).
//!    A batch with format 3's emission slot also adds `Ke ⊙ ρ_e(u, v)`, the
//!    emission texture filtered the same way at the same (u, v).
//! 6. **Depth test** LESS against a 32-bit float buffer cleared to 1.0, in draw order
//!    (batches in file order, triangles in index order). The background is black,
//!    except in a file with an environment (format x.1):
//! 7. **Environment**: each pixel nothing covered shows the sky toward its
//!    centre's view direction and the sun's disc (`draw_environment`).
//!
//! The stored radiance is drawn as it is: no ambient term (a partial solution's
//! ambient estimate is the caller's to add), no exposure, no tone mapping; see
//! [`tonemap`] for display and [`compare`](mod@compare) for GPU-versus-CPU checks.
//!
//! **Precision and expected GPU differences.** Geometry and radiance are computed in
//! f64 and stored as f32. A GPU transforms in f32 and evaluates SH in f32
//! (`sh::f32_basis_tolerance`), so its interior pixels differ by that tolerance; a
//! pixel whose centre lies within about 1/256 pixel of an edge may be covered by the
//! other triangle (or the background) on the GPU, because f32 transforms move the
//! snapped vertex by one step. A cube lookup in f32 (`cube::bilinear_f32`, what
//! the shader does) moves the cell coordinate by a few ulps of k, so the radiance
//! by ~1e-6 relative, except for a direction within rounding of a face edge,
//! where the two precisions may pick different faces. Comparisons should therefore bound the *fraction* of
//! differing pixels by the edge pixels, not demand zero.

pub mod compare;
#[cfg(test)]
mod environment_tests;
mod pipeline;
pub mod tonemap;

#[cfg(test)]
mod tests;
#[cfg(test)]
mod texture_tests;

pub use compare::{compare, compare_with, difference_image, ImageDiff, DEFAULT_DIFF_THRESHOLD};
pub use pipeline::SUBPIXEL_BITS;
pub use tonemap::{
    auto_exposure_stops, encode_srgb8, linear_to_srgb, srgb_to_linear, tone_map, tonemap_srgb8,
    ToneCurve,
};

use crate::camera::{clip_planes_for, EyeView, UpAxis, MAX_IMAGE_SIDE};
use crate::format::{Batch, Environment, Header, Representation, Solution};
use crate::sh;
use crate::texture::MipChain;
use glam::{DVec3, DVec4};
use pipeline::{ClipVertex, Rasterizer};

/// The largest image [`render`] allocates, in pixels (64 Mpx: 1 GiB of radiance
/// and depth). Image sizes can come from an untrusted solution header.
pub const MAX_RENDER_PIXELS: u64 = 1 << 26;

/// A rendered image: linear RGB radiance (W·sr⁻¹·m⁻²) and the depth buffer,
/// row-major with row 0 at the top (pixel (i, j) at `j * width + i`).
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 3]>,
    /// Vulkan depth `z/w` in 0..1 of the visible surface; 1.0 where nothing was drawn.
    pub depth: Vec<f32>,
}

impl Image {
    /// A black image with a cleared (1.0) depth buffer. Callers that take the size
    /// from untrusted input check it first ([`render`] does).
    pub fn new(width: u32, height: u32) -> Image {
        let n = width as usize * height as usize;
        Image {
            width,
            height,
            pixels: vec![[0.0; 3]; n],
            depth: vec![1.0; n],
        }
    }

    /// Radiance of pixel (column `i`, row `j`).
    ///
    /// # Panics
    /// If the pixel is outside the image.
    pub fn pixel(&self, i: u32, j: u32) -> [f32; 3] {
        assert!(
            i < self.width && j < self.height,
            "pixel ({i}, {j}) outside {}x{}",
            self.width,
            self.height
        );
        self.pixels[j as usize * self.width as usize + i as usize]
    }

    /// Whether something was drawn at pixel (`i`, `j`) (its depth is below the clear value).
    pub fn covered(&self, i: u32, j: u32) -> bool {
        self.depth[j as usize * self.width as usize + i as usize] < 1.0
    }

    /// Mean over pixels and channels of the radiance.
    pub fn mean_radiance(&self) -> f64 {
        if self.pixels.is_empty() {
            return 0.0;
        }
        let sum: f64 = self
            .pixels
            .iter()
            .map(|p| p.iter().map(|&c| c as f64).sum::<f64>())
            .sum();
        sum / (3.0 * self.pixels.len() as f64)
    }
}

/// Options of [`render`]. `Default` is what the runtime draws.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderOptions {
    /// Evaluate at most this SH order (`None`: every stored coefficient).
    pub max_order: Option<u32>,
    /// `(near, far)` clip distances; `None` uses
    /// [`crate::camera::clip_planes_for`] with the header's bounds, as the runtime does.
    pub clip_planes: Option<(f64, f64)>,
    /// Skip back faces (default true). Off draws both sides.
    pub cull_back_faces: bool,
    /// Clamp each vertex's radiance at 0 before interpolation (default true; the
    /// vertex shader does the same).
    pub clamp_negative: bool,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            max_order: None,
            clip_planes: None,
            cull_back_faces: true,
            clamp_negative: true,
        }
    }
}

/// Why [`render`] (or an image comparison) refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RenderError {
    /// A global-cube batch whose direction count is not D = 6k² for a whole k in
    /// 1..=[`crate::cube::MAX_RESOLUTION`] (the format reader refuses such files;
    /// an in-memory solution can still hold one).
    #[error(
        "batch {batch}: a global cube of {directions} directions is not 6·k² for a whole k \
         in 1..={max}",
        max = crate::cube::MAX_RESOLUTION
    )]
    CubeDirections { batch: usize, directions: u32 },
    #[error("batch {batch}: {found} coefficients for {vertices} vertices, expected {expected}")]
    CoefficientCount {
        batch: usize,
        vertices: usize,
        expected: u64,
        found: usize,
    },
    #[error("batch {batch}: {count} indices is not a whole number of triangles")]
    IndexCount { batch: usize, count: usize },
    #[error(
        "batch {batch}: index {index} at position {position} is out of range ({vertices} vertices)"
    )]
    IndexOutOfRange {
        batch: usize,
        position: usize,
        index: u32,
        vertices: usize,
    },
    #[error(
        "image size {width}x{height} is outside 1..={MAX_IMAGE_SIDE} per side or above \
         {MAX_RENDER_PIXELS} pixels"
    )]
    ImageSize { width: u32, height: u32 },
    #[error("clip planes near = {near}, far = {far} need 0 < near < far (far may be infinite)")]
    ClipPlanes { near: f64, far: f64 },
    #[error("eye view is not finite or its basis is not orthonormal: {0}")]
    View(String),
    #[error("batch {batch}: {found} textured vertices (UV + E/π) for {vertices} vertices")]
    TexturedVertexCount {
        batch: usize,
        vertices: usize,
        found: usize,
    },
    #[error("batch {batch}: texture {texture} but the solution has {count} textures")]
    TextureIndex {
        batch: usize,
        texture: u32,
        count: usize,
    },
    #[error("images differ in size: {0}x{1} versus {2}x{3}")]
    SizeMismatch(u32, u32, u32, u32),
}

/// Renders `solution` as seen from `view` (file coordinates, see
/// [`crate::camera::Camera::mono_view`]). See the module documentation for what
/// each stage does and which Vulkan state mirrors it.
pub fn render(
    solution: &Solution,
    view: &EyeView,
    options: &RenderOptions,
) -> Result<Image, RenderError> {
    check_view(view)?;
    let (near, far) = options
        .clip_planes
        .unwrap_or_else(|| default_clip_planes(&solution.header, view));
    if !(near > 0.0 && near.is_finite() && far > near) {
        return Err(RenderError::ClipPlanes { near, far });
    }
    // Check every batch before drawing, so a bad one is reported without a
    // half-drawn image.
    for (index, batch) in solution.batches.iter().enumerate() {
        check_batch(index, batch, solution.textures.len())?;
    }
    let view_projection = view.view_projection(near, far);
    // Each texture's mip chain, built once (only those a batch uses).
    let chains: Vec<Option<MipChain>> = solution
        .textures
        .iter()
        .enumerate()
        .map(|(k, texture)| {
            let used = solution.batches.iter().any(|b| {
                b.texturing.as_ref().is_some_and(|t| {
                    t.texture as usize == k || t.emission.is_some_and(|e| e.texture as usize == k)
                })
            });
            used.then(|| MipChain::new(texture))
        })
        .collect();
    let mut image = Image::new(view.width, view.height);
    let mut rasterizer = Rasterizer::new(&mut image, options.cull_back_faces);
    for batch in &solution.batches {
        let order = options.max_order.unwrap_or(u32::MAX);
        let radiance = shade_vertices(batch, order, view.position, options.clamp_negative)?;
        let texturing = batch.texturing.as_ref();
        rasterizer.set_texture(
            texturing.and_then(|t| chains.get(t.texture as usize).and_then(Option::as_ref)),
        );
        rasterizer.set_emission(texturing.and_then(|t| {
            let slot = t.emission?;
            let chain = chains.get(slot.texture as usize)?.as_ref()?;
            Some((chain, slot.factor.map(f64::from)))
        }));
        // u, v and factor · E/π per vertex (zero when untextured).
        let textured = |v: usize| -> [f64; 5] {
            match texturing.and_then(|t| t.vertices.get(v).map(|tv| (t.factor, tv))) {
                Some((factor, tv)) => {
                    let e = tv.irradiance_over_pi;
                    [
                        f64::from(tv.uv[0]),
                        f64::from(tv.uv[1]),
                        f64::from(factor[0] * e[0]),
                        f64::from(factor[1] * e[1]),
                        f64::from(factor[2] * e[2]),
                    ]
                }
                None => [0.0; 5],
            }
        };
        let clip: Vec<DVec4> = batch
            .vertices
            .iter()
            .map(|v| view_projection * DVec3::from(v.position.map(f64::from)).extend(1.0))
            .collect();
        for triangle in batch.indices.chunks_exact(3) {
            let corner = |k: usize| {
                let v = triangle[k] as usize;
                ClipVertex {
                    position: clip[v],
                    radiance: radiance[v].map(f64::from),
                    textured: textured(v),
                }
            };
            rasterizer.draw_triangle([corner(0), corner(1), corner(2)]);
        }
    }
    if let Some(env) = solution
        .lighting
        .as_ref()
        .and_then(|l| l.environment.as_ref())
    {
        draw_environment(&mut image, env, solution.header.up_axis, view);
    }
    Ok(image)
}

/// The view direction through the centre of pixel (`i`, `j`) (not unit
/// length): forward + tan_x · right + tan_y · up, the tangents interpolated
/// across the view's (possibly asymmetric) field of view, row 0 at the top.
pub fn pixel_direction(view: &EyeView, i: u32, j: u32) -> DVec3 {
    let (tl, tr, tu, td) = view.fov.tangents();
    let x = tl + (tr - tl) * (f64::from(i) + 0.5) / f64::from(view.width);
    let y = tu - (tu - td) * (f64::from(j) + 0.5) / f64::from(view.height);
    view.forward + x * view.right + y * view.up
}

/// Stage 7 (format x.1): the environment behind the geometry. Every pixel no
/// triangle covered (its depth still the cleared 1.0, the far plane) shows
/// the sky toward its centre's view direction, bilinear in the
/// equirectangular texture, plus the sun's disc
/// ([`crate::format::Environment::radiance`]); the depth stays 1.0. The
/// runtime's background pass draws the same at depth 1.0 behind a LESS test.
fn draw_environment(image: &mut Image, env: &Environment, up: UpAxis, view: &EyeView) {
    for j in 0..image.height {
        for i in 0..image.width {
            let k = j as usize * image.width as usize + i as usize;
            if image.depth[k] < 1.0 {
                continue;
            }
            image.pixels[k] = env.radiance(up, pixel_direction(view, i, j).to_array());
        }
    }
}

/// The clip planes both renderers use for `view` when none are given:
/// [`clip_planes_for`] from the eye to the header's (file-coordinate) bounds. Each
/// eye of a stereo pair gets its own pair (its position differs).
pub fn default_clip_planes(header: &Header, view: &EyeView) -> (f64, f64) {
    clip_planes_for(
        view.position,
        DVec3::from(header.bounds_min.map(f64::from)),
        DVec3::from(header.bounds_max.map(f64::from)),
    )
}

fn check_view(view: &EyeView) -> Result<(), RenderError> {
    let (w, h) = (view.width, view.height);
    if w == 0
        || h == 0
        || w > MAX_IMAGE_SIDE
        || h > MAX_IMAGE_SIDE
        || w as u64 * h as u64 > MAX_RENDER_PIXELS
    {
        return Err(RenderError::ImageSize {
            width: w,
            height: h,
        });
    }
    let basis = [view.right, view.up, view.forward];
    // The basis comes from normalisations and cross products (or a unit
    // quaternion): 1e-9 leaves room for f32-derived poses and flags real mistakes.
    let orthonormal = basis.iter().all(|v| (v.length() - 1.0).abs() < 1e-9)
        && view.right.dot(view.up).abs() < 1e-9
        && view.right.dot(view.forward).abs() < 1e-9
        && view.up.dot(view.forward).abs() < 1e-9
        && (view.right.cross(view.up) + view.forward).length() < 1e-9;
    let (tl, tr, tu, td) = view.fov.tangents();
    let fov_ok = [tl, tr, tu, td].iter().all(|t| t.is_finite()) && tr > tl && tu > td;
    if !view.position.is_finite() || !orthonormal || !fov_ok {
        return Err(RenderError::View(format!("{view:?}")));
    }
    Ok(())
}

fn check_batch(index: usize, batch: &Batch, textures: usize) -> Result<(), RenderError> {
    check_coefficients(index, batch)?;
    let vertices = batch.vertices.len();
    if let Some(t) = &batch.texturing {
        let emission = t.emission.map(|e| e.texture);
        for texture in std::iter::once(t.texture).chain(emission) {
            if texture as usize >= textures {
                return Err(RenderError::TextureIndex {
                    batch: index,
                    texture,
                    count: textures,
                });
            }
        }
        if t.vertices.len() != vertices {
            return Err(RenderError::TexturedVertexCount {
                batch: index,
                vertices,
                found: t.vertices.len(),
            });
        }
    }
    if !batch.indices.len().is_multiple_of(3) {
        return Err(RenderError::IndexCount {
            batch: index,
            count: batch.indices.len(),
        });
    }
    if let Some((position, &bad)) = batch
        .indices
        .iter()
        .enumerate()
        .find(|(_, &i)| i as usize >= vertices)
    {
        return Err(RenderError::IndexOutOfRange {
            batch: index,
            position,
            index: bad,
            vertices,
        });
    }
    Ok(())
}

fn check_coefficients(index: usize, batch: &Batch) -> Result<(), RenderError> {
    if let Representation::Cube { directions } = batch.representation {
        if crate::cube::resolution_from_directions(directions).is_none() {
            return Err(RenderError::CubeDirections {
                batch: index,
                directions,
            });
        }
    }
    let vertices = batch.vertices.len();
    let expected = (vertices as u64)
        .saturating_mul(batch.representation.coefficients_per_channel())
        .saturating_mul(3);
    if batch.coefficients.len() as u64 != expected {
        return Err(RenderError::CoefficientCount {
            batch: index,
            vertices,
            expected,
            found: batch.coefficients.len(),
        });
    }
    Ok(())
}

/// Work (vertices × coefficients) above which vertex shading is spread over threads.
const PARALLEL_SHADING_WORK: usize = 1 << 16;

/// The vertex stage: each vertex's radiance toward `eye`, in f64, stored as f32
/// (what the vertex shader hands to the rasterizer). For SH batches `order` may
/// be below the batch's (a cap; above it, the batch's own order is used); cube
/// batches ignore it (a lookup reads four cells whatever D is). Refuses a cube
/// whose D is not 6k² or a coefficient array of the wrong length.
pub fn shade_vertices(
    batch: &Batch,
    order: u32,
    eye: DVec3,
    clamp_negative: bool,
) -> Result<Vec<[f32; 3]>, RenderError> {
    // Batch index 0: callers that know the index report it themselves.
    check_coefficients(0, batch)?;
    let stored = batch.representation.coefficients_per_channel() as usize;
    let lookup = match batch.representation {
        Representation::Sh {
            order: stored_order,
        } => Lookup::Sh {
            order: order.min(stored_order),
        },
        Representation::Cube { directions } => Lookup::Cube {
            // Checked by `check_coefficients`.
            resolution: crate::cube::resolution_from_directions(directions).ok_or(
                RenderError::CubeDirections {
                    batch: 0,
                    directions,
                },
            )?,
        },
    };
    // Scalars read per vertex and channel (sets when shading is worth threads).
    let used = match lookup {
        Lookup::Sh { order } => sh::coefficient_count(order).min(stored),
        Lookup::Cube { .. } => 4,
    };
    let n = batch.vertices.len();
    let mut out = vec![[0.0f32; 3]; n];
    let shade_range = |start: usize, out: &mut [[f32; 3]]| {
        let mut scratch = match lookup {
            Lookup::Sh { order } => vec![0.0; sh::coefficient_count(order)],
            Lookup::Cube { .. } => Vec::new(),
        };
        for (k, radiance) in out.iter_mut().enumerate() {
            let v = start + k;
            let vertex = &batch.vertices[v];
            // Values of vertex v: `coefficients[(v * n + k) * 3 + c]`.
            let values = &batch.coefficients[v * stored * 3..(v + 1) * stored * 3];
            let rgb = match lookup {
                // Y_00 is constant: no direction needed.
                Lookup::Sh { order: 0 } => [0, 1, 2].map(|c| f64::from(values[c]) * sh::Y00),
                // The first `used` coefficients per channel form the capped expansion.
                Lookup::Sh { order } => sh::eval_rgb_with(
                    order,
                    &values[..used * 3],
                    local_eye(vertex, eye),
                    &mut scratch,
                ),
                Lookup::Cube { resolution } => {
                    crate::cube::eval_rgb(resolution, values, local_eye(vertex, eye))
                }
            };
            *radiance = rgb.map(|c| {
                let c = c as f32;
                if clamp_negative {
                    c.max(0.0)
                } else {
                    c
                }
            });
        }
    };
    let threads = std::thread::available_parallelism().map_or(1, |t| t.get());
    if threads < 2 || n.saturating_mul(used) < PARALLEL_SHADING_WORK {
        shade_range(0, &mut out);
    } else {
        let chunk = n.div_ceil(threads);
        std::thread::scope(|scope| {
            for (index, part) in out.chunks_mut(chunk).enumerate() {
                let shade_range = &shade_range;
                scope.spawn(move || shade_range(index * chunk, part));
            }
        });
    }
    Ok(out)
}

/// How a batch's vertices are shaded.
#[derive(Clone, Copy)]
enum Lookup {
    /// Spherical harmonics up to this (possibly capped) order.
    Sh { order: u32 },
    /// Immel, Cohen and Greenberg's (1986) global cube with `resolution` cells along a face edge.
    Cube { resolution: u32 },
}

/// The direction from `vertex` toward `eye` in the vertex's local frame
/// (x = t, y = b, z = n), not normalised: both lookups normalise it themselves,
/// and both take a zero direction (eye on the vertex) as the local normal.
fn local_eye(vertex: &crate::format::Vertex, eye: DVec3) -> DVec3 {
    let position = DVec3::from(vertex.position.map(f64::from));
    match sh::orthonormal_frame(
        DVec3::from(vertex.normal.map(f64::from)),
        DVec3::from(vertex.tangent.map(f64::from)),
    ) {
        Some((normal, tangent)) => sh::to_local(eye - position, normal, tangent),
        // A zero normal (corrupt frame): look along the local normal.
        None => DVec3::Z,
    }
}
