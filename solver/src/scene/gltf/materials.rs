//! glTF materials as the solver's (metallic-roughness to Kd, Ks and α;
//! emissive factor × strength to emitted radiance), with a warning for each
//! feature not modelled, and the base-colour and emissive textures located
//! (decoded later, only if a polygon uses them).

use super::container::{decode_data_uri, relative_file, Buffer};
use super::Context;
use crate::brdf::MIN_ALPHA;
use crate::scene::raw::{MetalMap, RawMaterial};
use crate::scene::Warning;
use glam::{DAffine2, DVec2, DVec3};
use std::path::{Path, PathBuf};

/// The reflectance of a dielectric at normal incidence that the
/// metallic-roughness model assumes (glTF 2.0 specification, appendix B):
/// Ks = lerp(0.04, baseColor, metallic).
pub(crate) const DIELECTRIC_SPECULAR: f64 = 0.04;

/// Material extensions that change appearance and that the solver does not
/// model (warned once per material). `KHR_materials_emissive_strength` is
/// modelled and absent here.
const UNMODELLED_MATERIAL_EXTENSIONS: &[(&str, &str)] = &[
    (
        "KHR_materials_transmission",
        "transmission (the surface is taken as opaque)",
    ),
    (
        "KHR_materials_volume",
        "volume (the surface is taken as opaque)",
    ),
    ("KHR_materials_clearcoat", "clearcoat (no coat layer)"),
    ("KHR_materials_sheen", "sheen"),
    ("KHR_materials_specular", "specular strength and colour"),
    ("KHR_materials_ior", "index of refraction (0.04 at normal incidence is used)"),
    ("KHR_materials_iridescence", "iridescence"),
    ("KHR_materials_anisotropy", "anisotropy"),
    ("KHR_materials_dispersion", "dispersion"),
    (
        "KHR_materials_unlit",
        "unlit shading (the surface is lit like any other, as a diffuse surface of its base \
         colour; an unlit textured skybox can become the sky's environment map)",
    ),
    (
        "KHR_materials_pbrSpecularGlossiness",
        "the specular-glossiness model (the metallic-roughness factors, or their defaults, are used)",
    ),
];

/// Kd, Ks and α of the metallic-roughness model (glTF 2.0 specification,
/// appendix B): Kd = baseColor·(1 − metallic), Ks = lerp(0.04, baseColor,
/// metallic), α = roughness² clamped below at [`MIN_ALPHA`]. The last value
/// says whether α was clamped.
pub(crate) fn metallic_roughness(
    base: DVec3,
    metallic: f64,
    roughness: f64,
) -> (DVec3, DVec3, f64, bool) {
    let kd = base * (1.0 - metallic);
    let ks =
        DVec3::splat(DIELECTRIC_SPECULAR) + metallic * (base - DVec3::splat(DIELECTRIC_SPECULAR));
    let alpha = roughness * roughness;
    (kd, ks, alpha.max(MIN_ALPHA), alpha < MIN_ALPHA)
}

/// A glTF material as the solver's, with a warning for each feature of it
/// that is not modelled.
/// The third value, for a material with a usable base-colour texture, maps
/// its `TEXCOORD_0` to the solver's UVs.
pub(super) fn convert_material(
    ctx: &Context,
    buffers: &[Buffer],
    material: &gltf::Material,
) -> (RawMaterial, Vec<Warning>, Option<DAffine2>) {
    let index = material.index().unwrap_or(0);
    let name = material
        .name()
        .map(str::to_owned)
        .unwrap_or_else(|| format!("material {index}"));
    let item = format!("material `{name}` (materials[{index}])");
    let mut warnings = Vec::new();
    let mut warn = |message: String| warnings.push(ctx.warning(item.clone(), message));

    let pbr = material.pbr_metallic_roughness();
    let [r, g, b, _] = pbr.base_color_factor().map(f64::from);
    let metallic = f64::from(pbr.metallic_factor());
    let roughness = f64::from(pbr.roughness_factor());
    // Out-of-range factors are the file's error, but the cleaning step refuses
    // negative or non-finite reflectances with the material's name, so they
    // are clamped to glTF's [0, 1] here only where the model needs it.
    let (kd, ks, alpha, clamped) = metallic_roughness(
        DVec3::new(r, g, b),
        metallic.clamp(0.0, 1.0),
        roughness.clamp(0.0, 1.0),
    );
    if clamped {
        warn(format!(
            "roughness {roughness} gives α = roughness² = {:.3e}, below the solver's smallest \
             glossy lobe; α = {MIN_ALPHA} is used",
            roughness * roughness
        ));
    }
    if !(0.0..=1.0).contains(&metallic) || !(0.0..=1.0).contains(&roughness) {
        warn(format!(
            "metallicFactor {metallic} and roughnessFactor {roughness} must lie in [0, 1]; \
             clamped"
        ));
    }
    let strength = f64::from(material.emissive_strength().unwrap_or(1.0));
    let emission = DVec3::from_array(material.emissive_factor().map(f64::from)) * strength;

    let base_colour = match pbr.base_color_texture() {
        Some(info) => material_texture(ctx, buffers, &info, BASE_COLOUR, &mut warn),
        None => None,
    };
    // Le = emissiveFactor × strength × emissiveTexture (§3.9.3, sRGB like the
    // base colour), honouring its texCoord and `KHR_texture_transform`.
    let emissive = match material.emissive_texture() {
        Some(_) if emission == DVec3::ZERO => {
            warn(
                "emissiveTexture with emissiveFactor (0, 0, 0): the factor multiplies the \
                 texture, so the surface does not emit"
                    .to_owned(),
            );
            None
        }
        Some(info) => material_texture(ctx, buffers, &info, EMISSIVE, &mut warn),
        None => None,
    };
    // Both textures of a surface are sampled at its one UV set (the solution
    // file's two slots share the textured vertices' UVs), so an emitter's
    // base-colour texture is modelled when it maps like its emissive texture.
    let base_colour = match (base_colour, &emissive) {
        (Some(b), Some(e)) if b.uv_map != e.uv_map => {
            warn(
                "baseColorTexture and emissiveTexture map differently (texCoord or \
                 KHR_texture_transform) and a surface has one UV set: the emissive texture is \
                 used and the flat base colour reflects"
                    .to_owned(),
            );
            None
        }
        (b, _) => b,
    };
    // B is metalness and G roughness (§3.9.2), read by `scene::metal_texture`
    // at the polygon's one UV set, so it must map like the colour textures.
    let metal = match pbr.metallic_roughness_texture() {
        Some(info) => material_texture(ctx, buffers, &info, METALLIC_ROUGHNESS, &mut warn),
        None => None,
    };
    let metal = match (metal, emissive.as_ref().or(base_colour.as_ref())) {
        (Some(t), Some(other)) if t.uv_map != other.uv_map => {
            warn(
                "metallicRoughnessTexture maps differently from the colour textures (texCoord \
                 or KHR_texture_transform) and a surface has one UV set: it is ignored and the \
                 flat metallic and roughness factors used"
                    .to_owned(),
            );
            None
        }
        (t, _) => t,
    };
    if material.normal_texture().is_some() {
        warn("normal map ignored: surfaces are shaded with their geometric normals".to_owned());
    }
    match material.alpha_mode() {
        gltf::material::AlphaMode::Opaque => {}
        gltf::material::AlphaMode::Mask => warn(format!(
            "alpha mode MASK ignored: the surface is opaque everywhere (cutoff {})",
            material.alpha_cutoff().unwrap_or(0.5)
        )),
        gltf::material::AlphaMode::Blend => {
            warn("alpha mode BLEND ignored: the surface is opaque".to_owned())
        }
    }
    if material.double_sided() {
        warn(
            "doubleSided: the solver's surfaces are one-sided; each triangle receives, reflects \
             and emits on its front (counter-clockwise) side only"
                .to_owned(),
        );
    }
    for (extension, what) in UNMODELLED_MATERIAL_EXTENSIONS {
        if material.extension_value(extension).is_some() {
            warn(format!("{extension} ignored: {what} is not modelled"));
        }
    }
    // An unlit material shows its base colour as is (KHR_materials_unlit);
    // lit, the nearest is a diffuse surface of that colour, without the
    // metallic split (a metal's Kd would be 0).
    let unlit = material.extension_value("KHR_materials_unlit").is_some();
    // Its metalness would not apply.
    let metal = metal.filter(|_| !unlit);
    let (kd, ks) = if unlit {
        (DVec3::new(r, g, b), DVec3::ZERO)
    } else {
        (kd, ks)
    };
    let raw = RawMaterial {
        name,
        aliases: Vec::new(),
        kd,
        ks,
        alpha,
        emission,
        source: ctx.source(item.clone()),
        overridden_at: None,
        undefined: None,
        unread_reflectance_file: None,
        // This importer's warnings about unmodelled features are returned
        // beside the material (the MTL reader's per-statement list is not used).
        unmodelled: Vec::new(),
        diffuse_map: base_colour
            .as_ref()
            .map(|t| (t.name.clone(), ctx.source(item.clone()))),
        diffuse_bytes: base_colour.as_ref().and_then(|t| t.bytes.clone()),
        emission_map: emissive
            .as_ref()
            .map(|t| (t.name.clone(), ctx.source(item.clone()))),
        emission_bytes: emissive.as_ref().and_then(|t| t.bytes.clone()),
        metal_map: metal.as_ref().map(|t| MetalMap {
            file: t.name.clone(),
            bytes: t.bytes.clone(),
            source: ctx.source(item.clone()),
            base_colour: DVec3::new(r, g, b),
            metallic: metallic.clamp(0.0, 1.0),
            roughness: roughness.clamp(0.0, 1.0),
        }),
        unlit,
    };
    // A polygon has one UV set: the textures' maps are equal when several
    // are kept (above).
    let uv_map = emissive.or(base_colour).or(metal).map(|t| t.uv_map);
    (raw, warnings, uv_map)
}

/// Which texture of a material [`material_texture`] reads, for its messages.
struct Slot {
    name: &'static str,
    flat: &'static str,
}

const BASE_COLOUR: Slot = Slot {
    name: "baseColorTexture",
    flat: "the flat base colour",
};

const METALLIC_ROUGHNESS: Slot = Slot {
    name: "metallicRoughnessTexture",
    flat: "the flat metallic and roughness factors",
};

const EMISSIVE: Slot = Slot {
    name: "emissiveTexture",
    flat: "the flat emissive factor",
};

/// A base-colour or emissive texture as the importer hands it on: decoded
/// later by `texture_file` (like an MTL `map_Kd` or `map_Ke`) only if a
/// polygon uses it.
struct MaterialTexture {
    /// The image file, or the glTF file and image index naming embedded bytes.
    name: PathBuf,
    /// The encoded image when it is not a file of its own.
    bytes: Option<std::sync::Arc<[u8]>>,
    uv_map: DAffine2,
}

/// The base-colour or emissive texture of a material (glTF 2.0
/// specification, §3.9.2 and §3.9.3: sRGB, multiplied by `baseColorFactor`
/// or `emissiveFactor`, which is the MTL convention the solver follows: the
/// base factor · (1 − metallic) is Kd, the emissive factor × strength is Ke).
/// `None`, with a warning, when it uses another set of texture coordinates
/// than `TEXCOORD_0` or its image cannot be located.
fn material_texture(
    ctx: &Context,
    buffers: &[Buffer],
    info: &gltf::texture::Info,
    slot: Slot,
    warn: &mut impl FnMut(String),
) -> Option<MaterialTexture> {
    let transform = info.extension_value("KHR_texture_transform");
    let set = transform
        .and_then(|t| t.get("texCoord"))
        .and_then(|t| t.as_u64())
        .unwrap_or(u64::from(info.tex_coord()));
    if set != 0 {
        warn(format!(
            "{} uses TEXCOORD_{set}; only TEXCOORD_0 is read, so {} is used",
            slot.name, slot.flat
        ));
        return None;
    }
    let image = info.texture().source();
    let label = |how: &str| {
        PathBuf::from(format!(
            "{} images[{}] ({how})",
            ctx.path.display(),
            image.index()
        ))
    };
    let (name, bytes) = match image.source() {
        gltf::image::Source::View { view, .. } => {
            // `check_views` has checked every view against its buffer.
            let data = buffers[view.buffer().index()].data();
            let bytes = data.get(view.offset()..view.offset() + view.length())?;
            (
                label(&format!("bufferView {}", view.index())),
                Some(bytes.into()),
            )
        }
        gltf::image::Source::Uri { uri, .. } if uri.starts_with("data:") => {
            match decode_data_uri(uri) {
                Ok(bytes) => (label("data URI"), Some(bytes.into())),
                Err(why) => {
                    warn(format!("{}: {why}; {} is used", slot.name, slot.flat));
                    return None;
                }
            }
        }
        gltf::image::Source::Uri { uri, .. } => {
            let dir = ctx.path.parent().unwrap_or(Path::new(""));
            match relative_file(dir, uri) {
                Ok(file) => (file, None),
                Err(why) => {
                    warn(format!("{}: {why}; {} is used", slot.name, slot.flat));
                    return None;
                }
            }
        }
    };
    Some(MaterialTexture {
        name,
        bytes,
        uv_map: uv_map(transform),
    })
}

/// glTF UVs to the solver's: `KHR_texture_transform` first (its README's
/// T(offset) · R(rotation) · S(scale), applied to glTF's (u, v)), then glTF's v, which runs down
/// from the image's top row, turned into the OBJ convention the solver and
/// the solution file use (v up from the bottom row): v ↦ 1 − v.
fn uv_map(transform: Option<&serde_json::Value>) -> DAffine2 {
    let pair = |key: &str, default: f64| {
        let value = transform.and_then(|t| t.get(key));
        let at = |k: usize| {
            value
                .and_then(|v| v.get(k))
                .and_then(|x| x.as_f64())
                .filter(|x| x.is_finite())
                .unwrap_or(default)
        };
        DVec2::new(at(0), at(1))
    };
    let rotation = transform
        .and_then(|t| t.get("rotation"))
        .and_then(|x| x.as_f64())
        .filter(|x| x.is_finite())
        .unwrap_or(0.0);
    // R = [[cos, sin], [−sin, cos]] in row form: u' = cos·u + sin·v,
    // v' = −sin·u + cos·v, counter-clockwise in glTF's v-down UV space. The
    // README's GLSL listing, read as GLSL (column-major), gives the transpose;
    // KhronosGroup/glTF issue #1563 records that the listing is wrong and that
    // Blender, Babylon.js, three.js and the TextureTransformTest sample model
    // all turn this way, as does the README's own example (rotation π/2,
    // offset (0, 1), scale ½ selects the image's lower-left quadrant), which
    // `texture_transform_rotation_turns_as_the_extensions_example_says` checks.
    let (sin, cos) = rotation.sin_cos();
    let gltf = DAffine2::from_translation(pair("offset", 0.0))
        * DAffine2::from_mat2(glam::DMat2::from_cols(
            DVec2::new(cos, -sin),
            DVec2::new(sin, cos),
        ))
        * DAffine2::from_scale(pair("scale", 1.0));
    let flip = DAffine2::from_cols(DVec2::X, DVec2::NEG_Y, DVec2::Y);
    flip * gltf
}
