//! glTF's metallic-roughness texture (glTF 2.0 specification, §3.9.2): its
//! B channel scales `metallicFactor`, its G channel `roughnessFactor`, both
//! linear (not sRGB). A DamagedHelmet-style material has `metallicFactor` 1
//! and says per texel what is metal.
//!
//! * **Diffuse mode** folds a material's specular albedo into its diffuse
//!   reflectance (`Material::diffuse_equivalent_kd`). With the metalness m
//!   and the textured base colour b = baseColorFactor ⊙ T(uv) at a texel,
//!   Kd + Ks = b(1 − m) + lerp(0.04, b, m) = b + 0.04(1 − m), so the folded
//!   reflectance is ρ(uv) = min(b + 0.04(1 − m), 1) per channel. It is
//!   computed per texel at import and stored as the material's
//!   `folded_texture` (factor 1), on the base-colour texture's grid (the
//!   metalness read at the nearest texel of its own image, which the importer
//!   has checked maps alike) or, without a base-colour texture, on the
//!   metalness texture's grid. It is stored as 8-bit sRGB like every texture
//!   (the solution file's texels; [`crate::texture::linear_to_srgb8`] picks
//!   the nearest code, within 0.0045 of ρ), so the solve, the path tracer
//!   and the display read the same values.
//! * **Directional mode** reflects Ks through a lobe that is one RGB value and
//!   one α per material (docs/textures.md, "Limits"), so there the
//!   material's split uses the texture's means: Kd = b̄(1 − M̄), Ks =
//!   lerp(0.04, b̄, M̄), α = (roughnessFactor · Ḡ)², with M̄ = metallicFactor ·
//!   B̄ and the bars the means over the texture's texels (not weighted by
//!   where the UVs fall). The base-colour texture multiplies that Kd as it
//!   did before.
//! * A texture that cannot be used (missing, unreadable, too large, no face
//!   with UVs, or a material whose values a TOML override replaced) is
//!   warned about by name, and the flat factors are used.

use super::raw::{MetalMap, RawMaterial};
use super::{Polygon, SceneTexture, Warning};
use crate::brdf::MIN_ALPHA;
use crate::texture::{linear_to_srgb8, srgb_to_linear};
use glam::DVec3;
use std::sync::Arc;

/// A read metallic-roughness texture: the material's values from its means,
/// and the metalness per texel.
pub(crate) struct Metal {
    /// Kd, Ks and α from the texture's mean metalness and roughness.
    pub kd: DVec3,
    pub ks: DVec3,
    pub alpha: f64,
    width: u32,
    height: u32,
    /// metallicFactor × B / 255 per texel, rows top to bottom.
    metalness: Vec<f32>,
    base_colour: DVec3,
    file: std::path::PathBuf,
}

/// Reads material `index`'s metallic-roughness texture (`raw.metal_map`)
/// when some polygon using it has UVs and no TOML override replaced its
/// values; `None`, with a warning naming the file, when it cannot be used.
pub(crate) fn read(
    raw: &RawMaterial,
    index: usize,
    polygons: &[Polygon],
    warnings: &mut Vec<Warning>,
) -> Option<Metal> {
    let map = raw.metal_map.as_ref()?;
    let statement = "metallicRoughnessTexture";
    let flat = format!(
        "the flat factors (metallic {}, roughness {})",
        map.metallic, map.roughness
    );
    if let Some(at) = &raw.overridden_at {
        warnings.push(Warning {
            source: map.source.clone(),
            message: format!(
                "{statement} texture {}: the scene config at {at} sets this material's \
                 values, so the texture is not read",
                map.file.display()
            ),
        });
        return None;
    }
    let users = (statement, "metallic and roughness factors");
    if !super::clean::some_user_has_uvs(
        raw,
        index,
        polygons,
        users,
        &map.file,
        &map.source,
        warnings,
    ) {
        return None;
    }
    let image = super::texture_file::load_rgba(
        &map.file,
        map.bytes.as_deref(),
        &map.source,
        (statement, &flat),
        warnings,
    )?;
    Some(from_image(map, image))
}

fn from_image(map: &MetalMap, image: super::texture_file::Rgba8) -> Metal {
    let texels = image.rgba.chunks_exact(4);
    let count = texels.len().max(1) as f64;
    let metalness: Vec<f32> = texels
        .clone()
        .map(|t| (map.metallic * f64::from(t[2]) / 255.0) as f32)
        .collect();
    let mean_metal = metalness.iter().map(|&m| f64::from(m)).sum::<f64>() / count;
    let mean_green = texels.map(|t| f64::from(t[1]) / 255.0).sum::<f64>() / count;
    let roughness = map.roughness * mean_green;
    let (kd, ks, alpha, _) =
        super::gltf::metallic_roughness(map.base_colour, mean_metal, roughness);
    Metal {
        kd,
        ks,
        alpha: alpha.max(MIN_ALPHA),
        width: image.width,
        height: image.height,
        metalness,
        base_colour: map.base_colour,
        file: map.file.clone(),
    }
}

impl Metal {
    /// The metalness at texel (x, y) of a `width × height` grid mapped like
    /// this texture: its nearest texel.
    fn metalness_at(&self, (x, y): (u32, u32), (width, height): (u32, u32)) -> f64 {
        let scale = |i: u32, from: u32, to: u32| {
            let at = (f64::from(i) + 0.5) / f64::from(from) * f64::from(to);
            (at.floor() as u32).min(to - 1)
        };
        let mx = scale(x, width, self.width);
        let my = scale(y, height, self.height);
        f64::from(self.metalness[(my * self.width + mx) as usize])
    }

    /// The diffuse-mode reflectance texture (see the module notes):
    /// ρ = min(baseColorFactor ⊙ T + 0.04(1 − m), 1) per texel, T the
    /// decoded base-colour texture (1 without one), as sRGB texels to be
    /// multiplied by 1.
    pub fn fold(&self, base_texture: Option<&SceneTexture>) -> Option<Arc<SceneTexture>> {
        let (width, height) = match base_texture {
            Some(t) => (t.width, t.height),
            None => (self.width, self.height),
        };
        let specular = super::gltf::DIELECTRIC_SPECULAR;
        let mut rgba = Vec::with_capacity(width as usize * height as usize * 4);
        for y in 0..height {
            for x in 0..width {
                let base = match base_texture {
                    Some(t) => {
                        let at = 4 * (y as usize * width as usize + x as usize);
                        let texel = &t.rgba[at..at + 3];
                        DVec3::new(
                            f64::from(srgb_to_linear(texel[0])),
                            f64::from(srgb_to_linear(texel[1])),
                            f64::from(srgb_to_linear(texel[2])),
                        )
                    }
                    None => DVec3::ONE,
                };
                let m = self.metalness_at((x, y), (width, height));
                let rho =
                    (self.base_colour * base + DVec3::splat(specular * (1.0 - m))).min(DVec3::ONE);
                rgba.extend(rho.to_array().map(linear_to_srgb8));
                rgba.push(255);
            }
        }
        let name = std::path::PathBuf::from(format!("{} (diffuse-mode fold)", self.file.display()));
        SceneTexture::from_rgba(name, width, height, rgba).map(Arc::new)
    }
}
