//! The reference renderer's textured batches against analytic values: texel
//! centres under magnification, the linear-light mean of a checkerboard under
//! minification (which an sRGB-space mip chain would get wrong by 2.3×), and
//! the SH term and factor added and multiplied as the format states.

use super::*;
use crate::camera::{Camera, Fov, UpAxis};
use crate::format::{
    Header, ScalarType, SolveMode, SolveStats, Texture, TextureSlot, TexturedVertex, Texturing,
    Vertex,
};
use crate::texture::srgb8_to_linear;

const SIZE: u32 = 64;

/// An n × n checkerboard of `square`-texel squares, white (255) where
/// `(i + j)` is even, black (0) elsewhere, counted from the top-left square.
fn checkerboard(squares: u32, square: u32) -> Texture {
    let n = squares * square;
    let rgba = (0..n * n)
        .flat_map(|k| {
            let (x, y) = (k % n / square, k / n / square);
            let b = if (x + y) % 2 == 0 { 255 } else { 0 };
            [b, b, b, 255]
        })
        .collect();
    Texture {
        width: n,
        height: n,
        rgba,
    }
}

/// A 2 × 2 quad at z = −2 facing the eye at the origin, uv = (x + 1)/2,
/// (y + 1)/2, with `c00` as its SH term and `texture` times `factor · e`.
fn quad(texture: Texture, factor: [f32; 3], e: f32, c00: f32) -> Solution {
    let corners = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];
    let vertices = corners
        .iter()
        .map(|&[x, y]| Vertex {
            position: [x, y, -2.0],
            normal: [0.0, 0.0, 1.0],
            tangent: [1.0, 0.0, 0.0],
        })
        .collect();
    let textured = corners
        .iter()
        .map(|&[x, y]| TexturedVertex {
            uv: [(x + 1.0) / 2.0, (y + 1.0) / 2.0],
            irradiance_over_pi: [e; 3],
        })
        .collect();
    let batch = Batch {
        representation: Representation::Sh { order: 0 },
        scalar: ScalarType::F32,
        vertices,
        coefficients: vec![c00; 12],
        indices: vec![0, 1, 2, 0, 2, 3],
        texturing: Some(Texturing {
            texture: 0,
            factor,
            emission: None,
            vertices: textured,
        }),
    };
    Solution {
        lighting: None,
        header: Header {
            units_per_metre: 1.0,
            up_axis: UpAxis::PosY,
            recentre_offset: [0.0; 3],
            camera: Camera::default(),
            bounds_min: [-1.0, -1.0, -2.0],
            bounds_max: [1.0, 1.0, -2.0],
            partial: false,
            mode: SolveMode::Diffuse,
            stats: SolveStats::default(),
            settings_json: String::new(),
        },
        batches: vec![batch],
        textures: vec![texture],
    }
}

fn view() -> EyeView {
    EyeView {
        position: DVec3::ZERO,
        right: DVec3::X,
        up: DVec3::Y,
        forward: DVec3::NEG_Z,
        fov: Fov::symmetric(60f64.to_radians(), SIZE, SIZE),
        width: SIZE,
        height: SIZE,
    }
}

/// The pixel whose centre sees the quad point (x, y, −2).
fn pixel_at(x: f64, y: f64) -> (u32, u32) {
    // The quad's half-width 1 at distance 2 spans tan(30°)·2 = 1.155 of the
    // image's half-height.
    let half = 2.0 * (30f64).to_radians().tan();
    let px = (x / half + 1.0) * 0.5 * SIZE as f64;
    let py = (1.0 - y / half) * 0.5 * SIZE as f64;
    (px as u32, py as u32)
}

#[test]
fn magnified_checkerboard_shows_its_texels_times_factor_and_e() {
    // 4 × 4 one-texel squares over ~55 pixels: ~14 pixels per texel (LOD < 0,
    // level 0). Within half a pixel of a texel centre the bilinear weight of
    // the other texels is at most 2 · 0.5/13.8, so a white texel reads at
    // least 0.93 and a black one at most 0.07.
    let factor = [1.0, 0.5, 0.25];
    let solution = quad(checkerboard(4, 1), factor, 0.8, 0.0);
    let image = render(&solution, &view(), &RenderOptions::default()).unwrap();
    for ty in 0..4 {
        for tx in 0..4 {
            // Texel (tx, ty) from the top-left; v runs up from the bottom row.
            let (u, v) = ((tx as f64 + 0.5) / 4.0, 1.0 - (ty as f64 + 0.5) / 4.0);
            let (i, j) = pixel_at(2.0 * u - 1.0, 2.0 * v - 1.0);
            let white = (tx + ty) % 2 == 0;
            let p = image.pixel(i, j);
            for c in 0..3 {
                let full = 0.8 * factor[c];
                let rho = p[c] / full;
                if white {
                    assert!(rho >= 0.93, "texel ({tx}, {ty}) channel {c}: {p:?}");
                } else {
                    assert!(rho <= 0.07, "texel ({tx}, {ty}) channel {c}: {p:?}");
                }
            }
        }
    }
}

#[test]
fn minified_checkerboard_is_its_linear_light_mean() {
    // 256² one-texel squares over ~55 pixels: about 4.6 texels per pixel, so
    // λ ≈ 2.2 and the filter reads levels 2 and 3, both uniformly the
    // linear-light mean of black and white (0.5, stored as sRGB byte 188).
    // Averaging sRGB bytes instead would give byte 128 = 0.216 linear.
    let solution = quad(checkerboard(256, 1), [1.0; 3], 1.0, 0.0);
    let image = render(&solution, &view(), &RenderOptions::default()).unwrap();
    let expected = f64::from(srgb8_to_linear(188));
    for (x, y) in [(0.0, 0.0), (-0.7, 0.5), (0.6, -0.6)] {
        let (i, j) = pixel_at(x, y);
        for c in image.pixel(i, j) {
            // The f32 image holds the f64 result rounded once.
            assert!((f64::from(c) - expected).abs() < 1e-6, "({x}, {y}): {c}");
        }
    }
}

#[test]
fn sh_term_adds_to_the_textured_term() {
    // A white texture: every pixel is c00·Y00 + factor · E/π exactly (the
    // bilinear weights sum to 1 over white texels).
    let white = Texture {
        width: 2,
        height: 2,
        rgba: vec![255; 16],
    };
    let c00 = 0.3;
    let solution = quad(white, [0.5, 1.0, 2.0], 0.25, c00);
    let image = render(&solution, &view(), &RenderOptions::default()).unwrap();
    let (i, j) = pixel_at(0.1, 0.2);
    let p = image.pixel(i, j);
    let sh = f64::from(c00) * sh::Y00;
    for (c, f) in [0.5, 1.0, 2.0].into_iter().enumerate() {
        let expected = (sh as f32 as f64) + f * 0.25;
        assert!((f64::from(p[c]) - expected).abs() < 1e-6, "{p:?}");
    }
}

#[test]
fn a_texture_index_out_of_range_is_refused() {
    let mut solution = quad(checkerboard(2, 1), [1.0; 3], 1.0, 0.0);
    solution.textures.clear();
    assert!(matches!(
        render(&solution, &view(), &RenderOptions::default()),
        Err(RenderError::TextureIndex { texture: 0, .. })
    ));
}

/// A `width × height` texture of one sRGB colour.
fn constant(width: u32, height: u32, rgb: [u8; 3]) -> Texture {
    Texture {
        width,
        height,
        rgba: (0..width * height)
            .flat_map(|_| [rgb[0], rgb[1], rgb[2], 255])
            .collect(),
    }
}

#[test]
fn a_batch_with_both_textures_shows_the_sh_the_diffuse_and_the_emission_term() {
    // Constant textures make every trilinear sample exactly the texel's linear
    // value (the weights sum to 1 over equal texels, on every mip level, since
    // a level is the linear mean of equal texels re-encoded to the same byte),
    // so each pixel is c00·Y00 + Kd ⊙ ρ ⊙ E/π + Ke ⊙ ρ_e, to f32 rounding.
    // The emission texture has another size (its own level of detail).
    let rho = [200, 100, 30];
    let rho_e = [40, 250, 128];
    let (kd, e, c00) = ([0.5, 1.0, 0.8], 0.25, 0.3);
    let ke = [3.0, 0.5, 2.0];
    let mut solution = quad(constant(4, 4, rho), kd, e, c00);
    solution.textures.push(constant(3, 7, rho_e));
    solution.batches[0].texturing.as_mut().unwrap().emission = Some(TextureSlot {
        texture: 1,
        factor: ke,
    });
    let image = render(&solution, &view(), &RenderOptions::default()).unwrap();
    let sh = (f64::from(c00) * sh::Y00) as f32 as f64;
    let expected: [f64; 3] = [0, 1, 2].map(|c| {
        let diffuse = f64::from(kd[c] * e) * f64::from(srgb8_to_linear(rho[c]));
        sh + diffuse + f64::from(ke[c]) * f64::from(srgb8_to_linear(rho_e[c]))
    });
    for (x, y) in [(0.1, 0.2), (-0.8, -0.9), (0.7, -0.3)] {
        let (i, j) = pixel_at(x, y);
        let p = image.pixel(i, j);
        for c in 0..3 {
            // The f32 image holds the f64 sum rounded once (relative 6e-8).
            assert!(
                (f64::from(p[c]) - expected[c]).abs() < 1e-6 * expected[c],
                "({x}, {y}) channel {c}: {p:?} against {expected:?}"
            );
        }
    }
    // Each term is at least 1e-3 in every channel, over 100 × the tolerance, so
    // a renderer dropping either texture fails the check above.
    for c in 0..3 {
        let diffuse = f64::from(kd[c] * e) * f64::from(srgb8_to_linear(rho[c]));
        let emission = f64::from(ke[c]) * f64::from(srgb8_to_linear(rho_e[c]));
        assert!(diffuse.min(emission) > 1e-3, "channel {c}");
    }
}

#[test]
fn an_emission_texture_index_out_of_range_is_refused() {
    let mut solution = quad(checkerboard(2, 1), [1.0; 3], 1.0, 0.0);
    solution.batches[0].texturing.as_mut().unwrap().emission = Some(TextureSlot {
        texture: 1,
        factor: [1.0; 3],
    });
    assert!(matches!(
        render(&solution, &view(), &RenderOptions::default()),
        Err(RenderError::TextureIndex { texture: 1, .. })
    ));
}
