//! glTF's metallic-roughness texture (`scene::metal_texture`): the
//! diffuse-mode fold per texel, the directional split from the texture's
//! means, and the fall-back to the factors when the texture cannot be used.

use super::tests::{load, textured_quad, write_glb, Fixture, QUAD_TEXELS};
use crate::scene::Scene;
use glam::DVec3;
use serde_json::json;
use std::io::Cursor;

/// The largest error of an 8-bit sRGB code against the linear value it
/// stores (`texture::linear_to_srgb8`: half the largest step, at code 255).
const CODE_TOLERANCE: f64 = 0.0045;

/// Gold's base colour (the glTF sample models' value).
const GOLD: [f64; 3] = [1.0, 0.766, 0.336];

/// A PNG of 2 × 2 RGB texels: G = `green`, B = `blue[row][column]`, R = 0.
fn metal_png(green: u8, blue: [[u8; 2]; 2]) -> Vec<u8> {
    let image = image::RgbImage::from_fn(2, 2, |x, y| {
        image::Rgb([0, green, blue[y as usize][x as usize]])
    });
    let mut bytes = Vec::new();
    image
        .write_to(&mut Cursor::new(&mut bytes), image::ImageFormat::Png)
        .unwrap();
    bytes
}

/// [`textured_quad`] with its textured material made a gold metal
/// (`metallicFactor` 1, `roughnessFactor` 0.5) and, when `metal` is given, a
/// metallic-roughness texture (`Some(Ok(png))` in a buffer view,
/// `Some(Err(uri))` a file name) on the same UVs.
fn gold_quad(metal: Option<Result<Vec<u8>, &str>>) -> Fixture {
    let mut f = textured_quad();
    let pbr = &mut f.json["materials"][0]["pbrMetallicRoughness"];
    pbr["baseColorFactor"] = json!([GOLD[0], GOLD[1], GOLD[2], 1.0]);
    pbr["metallicFactor"] = json!(1.0);
    pbr["roughnessFactor"] = json!(0.5);
    match metal {
        None => {}
        Some(Ok(png)) => {
            let at = f.bin.len();
            f.bin.extend_from_slice(&png);
            f.json["bufferViews"]
                .as_array_mut()
                .unwrap()
                .push(json!({"buffer": 0, "byteOffset": at, "byteLength": png.len()}));
            f.json["buffers"][0]["byteLength"] = json!(f.bin.len());
            f.json["images"]
                .as_array_mut()
                .unwrap()
                .push(json!({"bufferView": 4, "mimeType": "image/png"}));
        }
        Some(Err(uri)) => {
            f.json["images"]
                .as_array_mut()
                .unwrap()
                .push(json!({ "uri": uri }));
        }
    }
    if f.json["images"].as_array().unwrap().len() > 1 {
        f.json["textures"]
            .as_array_mut()
            .unwrap()
            .push(json!({"source": 1}));
        f.json["materials"][0]["pbrMetallicRoughness"]["metallicRoughnessTexture"] =
            json!({"index": 1});
    }
    f
}

/// The diffuse-mode reflectance of the quad at texel (column, row from the
/// image's top)'s centre, from every polygon of its material (all agree).
fn diffuse_mode_reflectance(scene: &Scene, column: usize, row: usize) -> DVec3 {
    let (x, y) = (0.25 + 0.5 * column as f64, 0.25 + 0.5 * row as f64);
    let at = DVec3::new(x, y, 0.0) - scene.recentre_offset;
    let values: Vec<DVec3> = scene
        .polygons
        .iter()
        .filter(|p| scene.materials[p.material].name == "checker")
        .map(|p| {
            let uv = p.uv_map.expect("the quad has UVs").at(at);
            let (kd, texture) = scene.materials[p.material]
                .diffuse_mode_texture()
                .expect("the quad is textured");
            kd * texture.texture.bilinear(uv)
        })
        .collect();
    assert!(!values.is_empty());
    for v in &values {
        assert!((*v - values[0]).abs().max_element() < 1e-12, "{values:?}");
    }
    values[0]
}

/// The linear base-colour texel (column, row) of [`QUAD_TEXELS`].
fn base_texel(column: usize, row: usize) -> f64 {
    f64::from(crate::texture::srgb_to_linear(QUAD_TEXELS[row][column]))
}

#[test]
fn a_metalness_texture_of_ones_reflects_as_metallic_factor_one_alone() {
    let dir = tempfile::tempdir().unwrap();
    let textured = load(&write_glb(
        dir.path(),
        "textured",
        &gold_quad(Some(Ok(metal_png(128, [[255; 2]; 2])))),
    ))
    .scene;
    let flat = load(&write_glb(dir.path(), "flat", &gold_quad(None))).scene;
    let material = |s: &Scene| {
        s.materials
            .iter()
            .find(|m| m.name == "checker")
            .unwrap()
            .clone()
    };
    assert!(
        material(&textured).folded_texture.is_some(),
        "{:?}",
        textured.warnings
    );
    assert!(material(&flat).folded_texture.is_none());
    for (column, row) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
        let got = diffuse_mode_reflectance(&textured, column, row);
        let want = diffuse_mode_reflectance(&flat, column, row);
        // Both are gold ⊙ the base texel (Kd 0, Ks = gold folded in).
        let exact = DVec3::from_array(GOLD) * base_texel(column, row);
        assert!(
            (want - exact).abs().max_element() < 1e-6,
            "{want} vs {exact}"
        );
        assert!(
            (got - want).abs().max_element() <= CODE_TOLERANCE,
            "texel ({column}, {row}): {got} with the texture, {want} without"
        );
    }
    // All metal: the material's own split is metallicFactor 1's.
    let (t, f) = (material(&textured), material(&flat));
    assert!((t.kd - f.kd).abs().max_element() < 1e-12 && (t.ks - f.ks).abs().max_element() < 1e-12);
}

#[test]
fn a_varying_metalness_folds_per_texel_and_splits_by_its_means() {
    let dir = tempfile::tempdir().unwrap();
    // Metalness codes per texel (B), and roughness 0.5 × 204/255 = 0.4 (G).
    let blue = [[255, 0], [128, 64]];
    let path = write_glb(
        dir.path(),
        "half",
        &gold_quad(Some(Ok(metal_png(204, blue)))),
    );
    let scene = load(&path).scene;
    let gold = DVec3::from_array(GOLD);
    for (column, row) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
        let m = f64::from(blue[row][column]) / 255.0;
        // Kd + Ks = b(1 − m) + lerp(0.04, b, m) = b + 0.04(1 − m), capped at 1.
        let want =
            (gold * base_texel(column, row) + DVec3::splat(0.04 * (1.0 - m))).min(DVec3::ONE);
        let got = diffuse_mode_reflectance(&scene, column, row);
        assert!(
            (got - want).abs().max_element() <= CODE_TOLERANCE,
            "texel ({column}, {row}), metalness {m}: {got}, want {want}"
        );
    }
    // The dielectric texel (metalness 0) gains 0.04 over the untextured
    // metal's fold, gold ⊙ the base texel: the test tells the texture from
    // its absence.
    let untextured = gold * base_texel(1, 0);
    let got = diffuse_mode_reflectance(&scene, 1, 0);
    assert!(
        (got - untextured).min_element() > 2.0 * CODE_TOLERANCE,
        "{got}"
    );
    // Directional mode's split uses the means: M̄ = (255 + 0 + 128 + 64) / 4 / 255.
    let mean = (255.0 + 128.0 + 64.0) / 4.0 / 255.0;
    let material = scene
        .materials
        .iter()
        .find(|m| m.name == "checker")
        .unwrap();
    let kd = gold * (1.0 - mean);
    let ks = DVec3::splat(0.04) + mean * (gold - DVec3::splat(0.04));
    // Gold's red is 1, so Kd + Ks = 1 + 0.04(1 − M̄) there, scaled to 1 as
    // for any material.
    let sum = kd + ks;
    let scale = DVec3::select(sum.cmpgt(DVec3::ONE), DVec3::ONE / sum, DVec3::ONE);
    let (kd, ks) = (kd * scale, ks * scale);
    assert!(
        (material.kd - kd).abs().max_element() < 1e-6,
        "{} vs {kd}",
        material.kd
    );
    assert!(
        (material.ks - ks).abs().max_element() < 1e-6,
        "{} vs {ks}",
        material.ks
    );
    let alpha = (0.5_f64 * 204.0 / 255.0).powi(2);
    assert!(
        (material.alpha - alpha).abs() < 1e-6,
        "{} vs {alpha}",
        material.alpha
    );
}

#[test]
fn an_unreadable_metallic_texture_is_warned_and_the_factors_used() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_glb(
        dir.path(),
        "missing",
        &gold_quad(Some(Err("no_such_metal.png"))),
    );
    let scene = load(&path).scene;
    let flat = load(&write_glb(dir.path(), "flat", &gold_quad(None))).scene;
    let hits: Vec<_> = scene
        .warnings
        .iter()
        .filter(|w| {
            w.message.contains("metallicRoughnessTexture texture")
                && w.message.contains("no_such_metal.png")
                && w.message
                    .contains("the flat factors (metallic 1, roughness 0.5) is used")
        })
        .collect();
    assert_eq!(hits.len(), 1, "{:#?}", scene.warnings);
    let material = scene
        .materials
        .iter()
        .find(|m| m.name == "checker")
        .unwrap();
    let flat_material = flat.materials.iter().find(|m| m.name == "checker").unwrap();
    assert!(material.folded_texture.is_none());
    assert_eq!(
        (material.kd, material.ks, material.alpha),
        (flat_material.kd, flat_material.ks, flat_material.alpha)
    );
}
