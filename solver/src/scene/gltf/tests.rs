//! Tests of the glTF importer on files written here: JSON built with
//! `serde_json`, binary buffers packed by hand, as `.gltf` + `.bin`, `.glb` and
//! data-URI buffers in a temporary folder.

use super::materials::metallic_roughness;
use super::nodes::{assemble, camera_from_node};
use super::*;
use crate::brdf::MIN_ALPHA;
use crate::scene::{load_scene, ImportOptions, LoadedScene};
use base64::Engine as _;
use glam::{DMat4, DQuat, DVec3};
use gltf::mesh::Mode;
use serde_json::{json, Value};
use std::path::PathBuf;

/// A glTF document and its one binary buffer, before it is written.
pub(super) struct Fixture {
    pub json: Value,
    pub bin: Vec<u8>,
}

/// Little-endian bytes of f32 triples.
fn floats(values: &[[f32; 3]]) -> Vec<u8> {
    values
        .iter()
        .flatten()
        .flat_map(|v| v.to_le_bytes())
        .collect()
}

/// One triangle (0,0,0), (1,0,0), (0,1,0), facing +z, indexed by u16, on a
/// node with translation (1, 2, 3) and scale (2, 2, 2), with an emissive
/// metallic-roughness material.
fn triangle() -> Fixture {
    let positions = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let mut bin = floats(&positions);
    for i in [0u16, 1, 2] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    bin.extend_from_slice(&[0, 0]); // pad to 4 bytes
    let json = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "holder", "mesh": 0, "translation": [1.0, 2.0, 3.0], "scale": [2.0, 2.0, 2.0]}],
        "meshes": [{"name": "tri", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
        "materials": [{
            "name": "lamp",
            "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.6, 0.4, 1.0], "metallicFactor": 0.25, "roughnessFactor": 0.5},
            "emissiveFactor": [1.0, 2.0, 3.0],
            "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 5.0}}
        }],
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 6}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0]},
            {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}
        ]
    });
    Fixture { json, bin }
}

/// Writes `name.gltf` with its buffer in `name.bin`.
fn write_gltf(dir: &Path, name: &str, f: &Fixture) -> PathBuf {
    let mut json = f.json.clone();
    json["buffers"][0]["uri"] = json!(format!("{name}.bin"));
    std::fs::write(dir.join(format!("{name}.bin")), &f.bin).unwrap();
    let path = dir.join(format!("{name}.gltf"));
    std::fs::write(&path, serde_json::to_vec_pretty(&json).unwrap()).unwrap();
    path
}

/// Writes `name.gltf` with its buffer as a base64 data URI.
fn write_data_uri(dir: &Path, name: &str, f: &Fixture) -> PathBuf {
    let mut json = f.json.clone();
    let data = base64::engine::general_purpose::STANDARD.encode(&f.bin);
    json["buffers"][0]["uri"] = json!(format!("data:application/octet-stream;base64,{data}"));
    let path = dir.join(format!("{name}.gltf"));
    std::fs::write(&path, serde_json::to_vec(&json).unwrap()).unwrap();
    path
}

/// The bytes of a binary glTF (glTF 2.0 specification, chapter 4): header, JSON
/// chunk padded with spaces, BIN chunk padded with zeros.
fn glb_bytes(f: &Fixture) -> Vec<u8> {
    let mut json = serde_json::to_vec(&f.json).unwrap();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut bin = f.bin.clone();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::new();
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    out
}

pub(super) fn write_glb(dir: &Path, name: &str, f: &Fixture) -> PathBuf {
    let path = dir.join(format!("{name}.glb"));
    std::fs::write(&path, glb_bytes(f)).unwrap();
    path
}

pub(super) fn load(path: &Path) -> LoadedScene {
    load_scene(path, &ImportOptions::default()).unwrap()
}

fn error_of(path: &Path) -> String {
    match parse_gltf(path) {
        Ok(_) => panic!("{} imported", path.display()),
        Err(e) => e.to_string(),
    }
}

#[test]
fn node_translation_and_scale_place_the_vertices_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_gltf(dir.path(), "tri", &triangle());
    let raw = parse_gltf(&path).unwrap().raw;
    assert_eq!(raw.polygons.len(), 1);
    // x' = 2x + t: every product and sum is exact in f64, so 1e-12 is rounding
    // headroom only.
    let expected = [
        DVec3::new(1.0, 2.0, 3.0),
        DVec3::new(3.0, 2.0, 3.0),
        DVec3::new(1.0, 4.0, 3.0),
    ];
    for (v, e) in raw.polygons[0].vertices.iter().zip(expected) {
        assert!((*v - e).abs().max_element() <= 1e-12, "{v} vs {e}");
    }
    // Through the whole import (re-centred by the bounding-box centre in f64):
    // the same positions back, and metres.
    let loaded = load(&path);
    let scene = &loaded.scene;
    assert_eq!(scene.units_per_metre, 1.0);
    assert_eq!(scene.up_axis, solution::camera::UpAxis::PosY);
    for (v, e) in scene.polygons[0].vertices.iter().zip(expected) {
        assert!((*v + scene.recentre_offset - e).abs().max_element() <= 1e-12);
    }
    let scaled = load_scene(
        &path,
        &ImportOptions {
            units_per_metre: Some(1000.0),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(
        scaled.scene.units_per_metre, 1000.0,
        "the command line wins"
    );
}

#[test]
fn metallic_roughness_maps_to_kd_ks_alpha_and_emission() {
    // The model on exact numbers: Kd = 0.8·0.75 = 0.6, …; Ks = 0.04 + 0.25·(base
    // − 0.04); α = 0.5² = 0.25. f64 rounding only: 1e-15.
    let (kd, ks, alpha, clamped) = metallic_roughness(DVec3::new(0.8, 0.6, 0.4), 0.25, 0.5);
    assert!((kd - DVec3::new(0.6, 0.45, 0.3)).abs().max_element() < 1e-15);
    assert!((ks - DVec3::new(0.23, 0.18, 0.13)).abs().max_element() < 1e-15);
    assert_eq!(alpha, 0.25);
    assert!(!clamped);
    // α below the solver's smallest lobe is clamped to it and says so.
    let (_, _, alpha, clamped) = metallic_roughness(DVec3::ONE, 0.0, 0.01);
    assert_eq!(alpha, MIN_ALPHA);
    assert!(clamped);
    // Fully metallic: no diffuse part, Ks = baseColor.
    let (kd, ks, _, _) = metallic_roughness(DVec3::new(0.9, 0.5, 0.1), 1.0, 1.0);
    assert_eq!(kd, DVec3::ZERO);
    assert!((ks - DVec3::new(0.9, 0.5, 0.1)).abs().max_element() < 1e-15);

    // Through the file: the factors are f32 in glTF (0.8f32 = 0.800000011920929),
    // so Kd and Ks agree with the decimal values to f32 rounding, ≤ 6e-8
    // relative; α = 0.25 and Le = (1, 2, 3) × 5 are exact in f32.
    let dir = tempfile::tempdir().unwrap();
    let path = write_gltf(dir.path(), "tri", &triangle());
    let scene = load(&path).scene;
    let m = &scene.materials[0];
    assert_eq!(m.name, "lamp");
    assert!(
        (m.kd - DVec3::new(0.6, 0.45, 0.3)).abs().max_element() < 1e-7,
        "{}",
        m.kd
    );
    assert!(
        (m.ks - DVec3::new(0.23, 0.18, 0.13)).abs().max_element() < 1e-7,
        "{}",
        m.ks
    );
    assert_eq!(m.alpha, 0.25);
    assert_eq!(m.emission, DVec3::new(5.0, 10.0, 15.0));
}

#[test]
fn glb_and_data_uri_give_the_same_scene_as_gltf_with_bin() {
    let dir = tempfile::tempdir().unwrap();
    let f = triangle();
    let separate = load(&write_gltf(dir.path(), "a", &f)).scene;
    for path in [
        write_glb(dir.path(), "b", &f),
        write_data_uri(dir.path(), "c", &f),
    ] {
        let other = load(&path).scene;
        assert_eq!(other.materials, separate.materials, "{}", path.display());
        assert_eq!(other.polygons.len(), separate.polygons.len());
        for (p, q) in other.polygons.iter().zip(&separate.polygons) {
            assert_eq!(p.vertices, q.vertices, "{}", path.display());
            assert_eq!(p.material, q.material);
            assert_eq!(p.source.file, path, "sources name the file read");
        }
        assert_eq!(other.recentre_offset, separate.recentre_offset);
        assert_eq!(other.camera, separate.camera);
    }
}

#[test]
fn out_of_range_index_names_file_mesh_primitive_and_index() {
    let dir = tempfile::tempdir().unwrap();
    let mut f = triangle();
    f.bin[36 + 4..36 + 6].copy_from_slice(&3u16.to_le_bytes());
    let path = write_gltf(dir.path(), "bad", &f);
    let message = error_of(&path);
    for part in [
        "bad.gltf",
        "mesh `tri`",
        "primitive 0",
        "index 3",
        "has 3 vertices",
    ] {
        assert!(message.contains(part), "{part:?} missing from: {message}");
    }
}

#[test]
fn buffer_shorter_than_its_views_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    // The buffer claims fewer bytes than the index view reaches.
    let mut f = triangle();
    f.json["buffers"][0]["byteLength"] = json!(40);
    let message = error_of(&write_gltf(dir.path(), "short_view", &f));
    assert!(message.contains("short_view.gltf"), "{message}");
    assert!(message.contains("bufferView 1"), "{message}");
    assert!(message.contains("shorter than its views"), "{message}");
    // The file holds fewer bytes than the buffer's byteLength.
    let f = triangle();
    let path = write_gltf(dir.path(), "short_file", &f);
    std::fs::write(dir.path().join("short_file.bin"), &f.bin[..20]).unwrap();
    let message = error_of(&path);
    assert!(
        message.contains("short_file.gltf") && message.contains("buffer 0"),
        "{message}"
    );
    assert!(
        message.contains("is 20 bytes, shorter than the buffer's byteLength 44"),
        "{message}"
    );
    // An accessor running past the end of its view.
    let mut f = triangle();
    f.json["accessors"][0]["count"] = json!(4);
    let message = error_of(&write_gltf(dir.path(), "long_accessor", &f));
    assert!(
        message.contains("POSITION accessor 0") && message.contains("need 48 bytes"),
        "{message}"
    );
}

#[test]
fn draco_and_meshopt_as_required_extensions_are_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    for (extension, phrase) in [
        ("KHR_draco_mesh_compression", "Draco"),
        ("EXT_meshopt_compression", "meshopt"),
        ("KHR_texture_basisu", "textures cannot be read"),
        ("EXT_texture_webp", "textures cannot be read"),
        ("EXT_made_up", "does not know"),
    ] {
        let mut f = triangle();
        f.json["extensionsUsed"] = json!([extension]);
        f.json["extensionsRequired"] = json!([extension]);
        let message = error_of(&write_gltf(dir.path(), "compressed", &f));
        assert!(message.contains("compressed.gltf"), "{message}");
        assert!(
            message.contains(extension) && message.contains(phrase),
            "{message}"
        );
    }
    // Tolerated required extensions are read past (and warned about where used).
    let mut f = triangle();
    f.json["extensionsRequired"] = json!(["KHR_materials_emissive_strength"]);
    assert!(parse_gltf(&write_gltf(dir.path(), "tolerated", &f)).is_ok());
}

#[test]
fn truncated_glb_is_an_error_at_every_length() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = glb_bytes(&triangle());
    let path = dir.path().join("cut.glb");
    // Every prefix: the header, the JSON chunk and the BIN chunk each cut.
    for length in 0..bytes.len() {
        std::fs::write(&path, &bytes[..length]).unwrap();
        let message = error_of(&path);
        assert!(message.contains("cut.glb"), "{length}: {message}");
    }
    std::fs::write(&path, &bytes[..bytes.len() - 10]).unwrap();
    let message = error_of(&path);
    assert!(message.contains("truncated binary glTF"), "{message}");
    // A header length that lies about the file is caught before any slice.
    let mut lying = bytes.clone();
    lying[8..12].copy_from_slice(&u32::MAX.to_le_bytes());
    std::fs::write(&path, &lying).unwrap();
    assert!(error_of(&path).contains("the header says 4294967295 bytes"));
    let mut tiny = bytes;
    tiny[8..12].copy_from_slice(&3u32.to_le_bytes());
    std::fs::write(&path, &tiny).unwrap();
    error_of(&path);
}

#[test]
fn missing_bin_names_the_gltf_and_the_bin() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_gltf(dir.path(), "lonely", &triangle());
    std::fs::remove_file(dir.path().join("lonely.bin")).unwrap();
    let message = error_of(&path);
    assert!(
        message.contains("lonely.gltf") && message.contains("buffer 0"),
        "{message}"
    );
    assert!(
        message.contains("uri `lonely.bin`: cannot read"),
        "{message}"
    );
}

#[test]
fn camera_node_gives_the_eye_and_the_view_direction() {
    let dir = tempfile::tempdir().unwrap();
    let mut f = triangle();
    f.json["cameras"] = json!([
        {"type": "orthographic", "orthographic": {"xmag": 1.0, "ymag": 1.0, "znear": 0.1, "zfar": 10.0}},
        {"type": "perspective", "perspective": {"yfov": 0.5, "aspectRatio": 2.0, "znear": 0.1}},
        {"type": "perspective", "perspective": {"yfov": 1.0, "znear": 0.1}}
    ]);
    // Scene-graph order: the orthographic camera (ignored), then the first
    // perspective one at (0, 1, 5), then another that must not win.
    f.json["nodes"] = json!([
        {"mesh": 0},
        {"camera": 0, "translation": [9.0, 9.0, 9.0]},
        {"camera": 1, "translation": [0.0, 1.0, 5.0]},
        {"camera": 2, "translation": [0.0, 0.0, -5.0]}
    ]);
    f.json["scenes"] = json!([{"nodes": [0, 1, 2, 3]}]);
    let path = write_gltf(dir.path(), "view", &f);
    let loaded = load(&path);
    let camera = loaded.scene.camera.expect("a camera");
    assert_eq!(camera.eye, [0.0, 1.0, 5.0]);
    let direction = DVec3::from(camera.target) - DVec3::from(camera.eye);
    assert!((direction - DVec3::NEG_Z).length() < 1e-15, "{direction}");
    assert_eq!(camera.up, [0.0, 1.0, 0.0]);
    // yfov 0.5 rad in f32, in degrees: 28.6479 to f32 rounding.
    assert!((camera.fov_y_deg - 0.5f64.to_degrees()).abs() < 1e-5);
    assert_eq!((camera.width, camera.height), (512, 256), "aspect ratio 2");
    let warned = loaded
        .scene
        .warnings
        .iter()
        .filter(|w| w.message.contains("orthographic"))
        .count();
    assert_eq!(warned, 1);

    // A camera turned half round y looks down +z; a parent's transform applies.
    let turned = camera_from_node(
        DMat4::from_translation(DVec3::new(278.0, 273.0, -800.0))
            * DMat4::from_quat(DQuat::from_xyzw(0.0, 1.0, 0.0, 0.0)),
        1.0,
        None,
    );
    assert_eq!(turned.eye, [278.0, 273.0, -800.0]);
    let d = DVec3::from(turned.target) - DVec3::from(turned.eye);
    assert!((d - DVec3::Z).length() < 1e-15, "{d}");
}

#[test]
fn mirroring_nodes_keep_front_faces_and_normals_follow_the_inverse_transpose() {
    let dir = tempfile::tempdir().unwrap();
    let mut f = triangle();
    // NORMAL (0, 0, 1) on every vertex.
    let normals_at = f.bin.len();
    f.bin.extend(floats(&[[0.0, 0.0, 1.0]; 3]));
    f.json["buffers"][0]["byteLength"] = json!(f.bin.len());
    f.json["bufferViews"]
        .as_array_mut()
        .unwrap()
        .push(json!({"buffer": 0, "byteOffset": normals_at, "byteLength": 36}));
    f.json["accessors"]
        .as_array_mut()
        .unwrap()
        .push(json!({"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC3"}));
    f.json["meshes"][0]["primitives"][0]["attributes"]["NORMAL"] = json!(2);
    // Mirrored in x and stretched in z: the facet must still face +z.
    f.json["nodes"][0] = json!({"mesh": 0, "scale": [-1.0, 1.0, 4.0]});
    let raw = parse_gltf(&write_gltf(dir.path(), "mirror", &f))
        .unwrap()
        .raw;
    let p = &raw.polygons[0];
    let facet = (p.vertices[1] - p.vertices[0]).cross(p.vertices[2] - p.vertices[0]);
    assert!(facet.normalize().dot(DVec3::Z) > 1.0 - 1e-15, "{facet}");
    // (M⁻¹)ᵀ (0, 0, 1) = (0, 0, 1/4), still along +z.
    for n in p.normals.as_ref().unwrap() {
        assert!((*n - DVec3::new(0.0, 0.0, 0.25)).length() < 1e-15, "{n}");
    }
}

#[test]
fn strips_and_fans_follow_the_specification() {
    // §3.7.3: strip triangle i = (v_i, v_{i+1+i%2}, v_{i+2−i%2}); fan
    // triangle i = (v_{i+1}, v_{i+2}, v_0). A strip's repeated index (a join) is
    // dropped.
    assert_eq!(
        assemble(Mode::TriangleStrip, &[0, 1, 2, 3]),
        vec![0, 1, 2, 1, 3, 2]
    );
    assert_eq!(
        assemble(Mode::TriangleFan, &[0, 1, 2, 3]),
        vec![1, 2, 0, 2, 3, 0]
    );
    assert_eq!(assemble(Mode::TriangleStrip, &[0, 1, 2, 2, 3]).len(), 3);
    assert_eq!(assemble(Mode::Triangles, &[0, 1, 2, 3, 4]), vec![0, 1, 2]);
    assert!(assemble(Mode::TriangleStrip, &[0, 1]).is_empty());
}

#[test]
fn unmodelled_features_are_warned_once_each_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let mut f = triangle();
    f.json["images"] = json!([{"uri": "never_read.png"}]);
    f.json["textures"] = json!([{"source": 0}]);
    let material = &mut f.json["materials"][0];
    material["pbrMetallicRoughness"]["baseColorTexture"] =
        json!({"index": 0, "extensions": {"KHR_texture_transform": {"scale": [2.0, 2.0]}}});
    material["emissiveTexture"] = json!({"index": 0, "texCoord": 1});
    material["pbrMetallicRoughness"]["metallicRoughnessTexture"] = json!({"index": 0});
    material["normalTexture"] = json!({"index": 0});
    material["alphaMode"] = json!("BLEND");
    material["doubleSided"] = json!(true);
    material["extensions"]["KHR_materials_transmission"] = json!({"transmissionFactor": 1.0});
    material["extensions"]["KHR_materials_clearcoat"] = json!({"clearcoatFactor": 1.0});
    f.json["extensions"] = json!({"KHR_lights_punctual": {"lights": [{"type": "point"}]}});
    // The mesh is used twice, by two nodes: its material is still warned once.
    f.json["nodes"] = json!([
        {"mesh": 0},
        {"mesh": 0, "translation": [5.0, 0.0, 0.0]},
        {"extensions": {"KHR_lights_punctual": {"light": 0}}},
        {"mesh": 1}
    ]);
    f.json["meshes"].as_array_mut().unwrap().push(json!({
        "name": "wire",
        "primitives": [{"attributes": {"POSITION": 0}, "mode": 1}]
    }));
    f.json["scenes"] = json!([{"nodes": [0, 1, 2, 3]}]);
    f.json["skins"] = json!([{"joints": [2]}]);
    let path = write_gltf(dir.path(), "fancy", &f);
    let scene = parse_gltf(&path).unwrap();
    assert_eq!(scene.raw.polygons.len(), 2, "two instances of the triangle");
    // The punctual light is imported (`lights.rs`), not warned about.
    assert_eq!(scene.lights.lamps.len(), 1);
    let warnings = &scene.raw.warnings;
    for phrase in [
        "metallicRoughnessTexture maps differently from the colour textures",
        "emissiveTexture uses TEXCOORD_1; only TEXCOORD_0 is read, so the flat emissive factor",
        "normal map ignored",
        "alpha mode BLEND ignored",
        "doubleSided",
        "KHR_materials_transmission ignored",
        "KHR_materials_clearcoat ignored",
        "1 skin(s) ignored",
        "Lines primitive skipped",
    ] {
        let hits: Vec<&Warning> = warnings
            .iter()
            .filter(|w| w.message.contains(phrase))
            .collect();
        assert_eq!(hits.len(), 1, "{phrase:?} in {warnings:#?}");
        assert_eq!(hits[0].source.file, path);
    }
    // Every warning names the file when printed.
    assert!(warnings
        .iter()
        .all(|w| w.to_string().starts_with(&path.display().to_string())));
}

/// A change made to the triangle fixture.
type Edit = Box<dyn Fn(&mut Fixture)>;

#[test]
fn hostile_documents_are_errors_not_panics() {
    let dir = tempfile::tempdir().unwrap();
    let cases: Vec<(&str, Edit, &str)> = vec![
        (
            "cycle",
            Box::new(|f| {
                f.json["nodes"] = json!([{"mesh": 0, "children": [1]}, {"children": [0]}]);
            }),
            "appears twice in the scene graph",
        ),
        (
            "stride",
            Box::new(|f| f.json["bufferViews"][0]["byteStride"] = json!(4)),
            "less than its 12-byte elements",
        ),
        (
            "type",
            Box::new(|f| f.json["accessors"][0]["componentType"] = json!(5123)),
            "expected VEC3 of FLOAT",
        ),
        (
            "huge_count",
            Box::new(|f| f.json["accessors"][1]["count"] = json!(u32::MAX)),
            "need",
        ),
        (
            "no_view",
            Box::new(|f| {
                f.json["accessors"][0]
                    .as_object_mut()
                    .unwrap()
                    .remove("bufferView");
            }),
            "bufferView",
        ),
        (
            "bad_index",
            Box::new(|f| f.json["meshes"][0]["primitives"][0]["indices"] = json!(7)),
            "invalid glTF",
        ),
        (
            "bad_json",
            Box::new(|f| f.json = json!({"asset": 3})),
            "not a glTF 2.0 document",
        ),
        (
            "remote",
            Box::new(|f| f.json["buffers"][0]["uri"] = json!("https://example.invalid/a.bin")),
            "only relative file names and data URIs",
        ),
    ];
    for (name, edit, phrase) in cases {
        let mut f = triangle();
        edit(&mut f);
        // These two documents are written as they are, with no buffer file.
        let path = if name == "remote" || name == "bad_json" {
            let path = dir.path().join(format!("{name}.gltf"));
            std::fs::write(&path, serde_json::to_vec(&f.json).unwrap()).unwrap();
            path
        } else {
            write_gltf(dir.path(), name, &f)
        };
        let message = error_of(&path);
        assert!(message.contains(&format!("{name}.gltf")), "{message}");
        assert!(
            message.contains(phrase),
            "{name}: {phrase:?} missing from: {message}"
        );
    }
}

#[test]
fn normals_reach_the_smooth_surfaces_as_obj_vn_do() {
    // Two triangles of a strip folded by 20° about the x axis (below the 30°
    // crease angle), with NORMALs bisecting the fold on the shared edge and
    // the facet normals elsewhere: one smooth group whose corners shade with
    // the file's normals.
    let (c, s) = (10f32.to_radians().cos(), 10f32.to_radians().sin());
    let positions = [
        [0.0, -c, s],
        [1.0, -c, s],
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, c, s],
        [1.0, c, s],
    ];
    // The strip's facet normals (from its winding, §3.7.3): (0, s, c) below
    // the fold, (0, −s, c) above; the shared edge gets +z, the bisector.
    let lower = [0.0, s, c];
    let upper = [0.0, -s, c];
    let normals = [lower, lower, [0.0, 0.0, 1.0], [0.0, 0.0, 1.0], upper, upper];
    let mut bin = floats(&positions);
    let normals_at = bin.len();
    bin.extend(floats(&normals));
    let mut f = triangle();
    f.json["buffers"][0]["byteLength"] = json!(bin.len());
    f.json["bufferViews"] = json!([
        {"buffer": 0, "byteOffset": 0, "byteLength": normals_at},
        {"buffer": 0, "byteOffset": normals_at, "byteLength": normals_at}
    ]);
    f.json["accessors"] = json!([
        {"bufferView": 0, "componentType": 5126, "count": 6, "type": "VEC3",
         "min": [0.0, -c, 0.0], "max": [1.0, c, s]},
        {"bufferView": 1, "componentType": 5126, "count": 6, "type": "VEC3"}
    ]);
    f.json["meshes"][0]["primitives"][0] =
        json!({"attributes": {"POSITION": 0, "NORMAL": 1}, "mode": 5, "material": 0});
    f.json["nodes"][0] = json!({"mesh": 0});
    f.bin = bin;
    let dir = tempfile::tempdir().unwrap();
    let path = write_gltf(dir.path(), "fold", &f);
    let mut scene = load(&path).scene;
    let facets: Vec<DVec3> = scene.polygons.iter().map(|p| p.normal()).collect();
    assert!(
        facets.iter().all(|n| n.z > 0.9),
        "front faces toward +z: {facets:?}"
    );
    let report = crate::scene::smooth_scene(&mut scene, crate::scene::DEFAULT_CREASE_ANGLE);
    assert_eq!(report.groups, 1, "{report:?}");
    assert!(report.with_input_normals > 0, "{report:?}");
    // On the shared edge (y = 0) every polygon shades with the file's +z.
    for p in &scene.polygons {
        let normals = p.vertex_normals.as_ref().expect("smooth corners");
        for (v, n) in p.vertices.iter().zip(normals) {
            if (v.y + scene.recentre_offset.y).abs() < 1e-9 {
                assert!((*n - DVec3::Z).length() < 1e-6, "{v}: {n}");
            }
        }
    }
}

#[test]
fn a_scene_config_can_name_a_gltf_file_as_geometry() {
    let dir = tempfile::tempdir().unwrap();
    write_glb(dir.path(), "tri", &triangle());
    let config = dir.path().join("scene.toml");
    std::fs::write(
        &config,
        "geometry = [\"tri.glb\"]\nunits_per_metre = 1000\n",
    )
    .unwrap();
    let loaded = load(&config);
    // The same triangle as the glb alone (x' = 2x + t, exact in f64), under the
    // config's units rather than glTF's metres.
    let scene = &loaded.scene;
    assert_eq!(scene.polygons.len(), 1);
    assert_eq!(scene.units_per_metre, 1000.0);
    let alone = load(&dir.path().join("tri.glb"));
    for (a, b) in scene.polygons[0]
        .vertices
        .iter()
        .zip(&alone.scene.polygons[0].vertices)
    {
        let (a, b) = (*a + scene.recentre_offset, *b + alone.scene.recentre_offset);
        assert!((a - b).abs().max_element() <= 1e-12, "{a} vs {b}");
    }
    assert_eq!(scene.materials.len(), alone.scene.materials.len());
}

/// sRGB codes of the 2 × 2 texture of [`textured_quad`], rows from the
/// image's top: distinct, so that a flipped or rotated lookup is caught.
pub(super) const QUAD_TEXELS: [[u8; 2]; 2] = [[255, 128], [64, 0]];

/// The unit square in z = 0 facing +z (two triangles), `TEXCOORD_0` = (x, y)
/// in glTF's convention (v down from the image's top row), with a white
/// dielectric material whose base colour is the 2 × 2 PNG [`QUAD_TEXELS`],
/// stored in a buffer view (with `mimeType`) after the geometry; and the same
/// square, untextured and emitting, at z = 2 (the importer refuses a scene
/// without light).
pub(super) fn textured_quad() -> Fixture {
    let positions = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ];
    let mut bin = floats(&positions);
    for uv in [[0f32, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]] {
        bin.extend(uv.iter().flat_map(|v| v.to_le_bytes()));
    }
    for i in [0u16, 1, 2, 0, 2, 3] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    let png =
        crate::scene::texture_file::tests::png(2, 2, |x, y| QUAD_TEXELS[y as usize][x as usize]);
    let png_at = bin.len();
    bin.extend_from_slice(&png);
    let json = json!({
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"mesh": 0}, {"mesh": 1, "translation": [0.0, 0.0, 2.0]}],
        "meshes": [
            {"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2, "material": 0}]},
            {"primitives": [{"attributes": {"POSITION": 0}, "indices": 2, "material": 1}]}
        ],
        "materials": [{
            "name": "checker",
            "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "baseColorFactor": [0.96, 0.96, 0.96, 1.0], "metallicFactor": 0.0}
        }, {
            "name": "lamp",
            "emissiveFactor": [1.0, 1.0, 1.0]
        }],
        "textures": [{"source": 0}],
        "images": [{"bufferView": 3, "mimeType": "image/png"}],
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 32},
            {"buffer": 0, "byteOffset": 80, "byteLength": 12},
            {"buffer": 0, "byteOffset": png_at, "byteLength": png.len()}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0]},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}
        ]
    });
    Fixture { json, bin }
}

/// The reflectance the imported scene gives the quad's point (x, y, 0), from
/// each of its textured polygons' UV maps (all must agree: the UVs are affine
/// in position).
fn albedo_at(scene: &crate::scene::Scene, x: f64, y: f64) -> f64 {
    let p = DVec3::new(x, y, 0.0) - scene.recentre_offset;
    let values: Vec<f64> = scene
        .polygons
        .iter()
        .filter(|p| scene.materials[p.material].name == "checker")
        .map(|polygon| {
            let uv = polygon
                .uv_map
                .expect("a textured polygon has a UV map")
                .at(p);
            let material = &scene.materials[polygon.material];
            assert!(material.diffuse_texture.is_some(), "{:?}", scene.warnings);
            material.kd_at(Some(uv)).x
        })
        .collect();
    assert!(
        values.len() == 2 && (values[0] - values[1]).abs() < 1e-9,
        "{values:?}"
    );
    values[0]
}

/// The albedo of texel (column, row from the top) of [`QUAD_TEXELS`]: its
/// linear value times Kd = baseColorFactor · (1 − metallic) = 0.96 (0.96, so
/// that Kd + Ks, Ks = 0.04 for a dielectric, is 1 and nothing is rescaled).
fn texel(column: usize, row: usize) -> f64 {
    0.96 * f64::from(crate::texture::srgb_to_linear(QUAD_TEXELS[row][column]))
}

// At a texel's centre the bilinear lookup is that texel's linear value alone,
// so the only error is f32 rounding of the UVs and the pyramid (1e-6).
const TEXEL_TOLERANCE: f64 = 1e-6;

#[test]
fn base_colour_texture_gives_each_texel_centre_its_linear_albedo() {
    let dir = tempfile::tempdir().unwrap();
    let f = textured_quad();
    // The image in a buffer view (GLB and .gltf + .bin) and as a data URI.
    let mut uri = f.json.clone();
    let png =
        &f.bin[f.bin.len() - (f.json["bufferViews"][3]["byteLength"].as_u64().unwrap() as usize)..];
    let data = base64::engine::general_purpose::STANDARD.encode(png);
    uri["images"] = json!([{"uri": format!("data:image/png;base64,{data}")}]);
    let paths = [
        write_glb(dir.path(), "quad", &f),
        write_gltf(dir.path(), "quad", &f),
        write_gltf(
            dir.path(),
            "quad_uri",
            &Fixture {
                json: uri,
                bin: f.bin.clone(),
            },
        ),
    ];
    for path in paths {
        let scene = load(&path).scene;
        // glTF's (u, v) = (x, y) with v down from the image's top: texel
        // (column i, row j) is centred at x = (i + ½)/2, y = (j + ½)/2.
        for (column, row) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            let (x, y) = (0.25 + 0.5 * column as f64, 0.25 + 0.5 * row as f64);
            let got = albedo_at(&scene, x, y);
            assert!(
                (got - texel(column, row)).abs() <= TEXEL_TOLERANCE,
                "{}: at ({x}, {y}) albedo {got}, texel ({column}, {row}) is {}",
                path.display(),
                texel(column, row)
            );
        }
    }
}

/// A glTF with no emitter is told the fix in glTF's terms (`emissiveFactor`,
/// `KHR_lights_punctual`), and the sun and sky options, not the MTL's `Ke`.
#[test]
fn a_gltf_without_emitter_is_told_the_gltf_fix() {
    let dir = tempfile::tempdir().unwrap();
    let mut f = textured_quad();
    f.json["materials"][1]["emissiveFactor"] = json!([0.0, 0.0, 0.0]);
    let path = write_glb(dir.path(), "dark", &f);
    let Err(err) = load_scene(&path, &ImportOptions::default()) else {
        panic!("a scene with no emitter is refused");
    };
    let message = err.to_string();
    assert!(
        matches!(err, crate::scene::SceneError::NoEmitter(_)),
        "{message}"
    );
    for phrase in [
        "`\"emissiveFactor\": [r, g, b]`",
        "KHR_lights_punctual",
        "`[sun]`, `[sky]`",
        "--sun AZIMUTH,ELEVATION",
        "--sky KIND",
    ] {
        assert!(message.contains(phrase), "{phrase:?} not in {message}");
    }
    assert!(!message.contains("Ke r g b"), "{message}");
}

/// An image `uri` in the wrong letter case (`CHECKER.PNG` for the file
/// `checker.png`) is read, with a warning naming both spellings.
#[test]
fn an_image_uri_in_the_wrong_case_is_found_in_its_folder() {
    let dir = tempfile::tempdir().unwrap();
    let mut f = textured_quad();
    let png =
        &f.bin[f.bin.len() - (f.json["bufferViews"][3]["byteLength"].as_u64().unwrap() as usize)..];
    std::fs::write(dir.path().join("checker.png"), png).unwrap();
    f.json["images"] = json!([{"uri": "CHECKER.PNG"}]);
    let scene = load(&write_gltf(dir.path(), "quad", &f)).scene;
    let got = albedo_at(&scene, 0.25, 0.25);
    assert!((got - texel(0, 0)).abs() <= TEXEL_TOLERANCE, "{got}");
    assert!(
        scene
            .warnings
            .iter()
            .any(|w| w.message.contains("CHECKER.PNG: no file has that name")
                && w.message
                    .contains("checker.png differs from it only in letter case")),
        "{:?}",
        scene.warnings
    );
}

#[test]
fn texture_transform_offsets_scales_and_rotates_the_uvs() {
    let dir = tempfile::tempdir().unwrap();
    // Rotation π with offset (1, 1): (u, v) ↦ (1 − u, 1 − v) whichever way
    // the rotation turns, so each texel centre shows the opposite texel.
    let mut f = textured_quad();
    f.json["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"] =
        json!({"KHR_texture_transform": {"offset": [1.0, 1.0], "rotation": std::f64::consts::PI}});
    let scene = load(&write_gltf(dir.path(), "turned", &f)).scene;
    for (column, row) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
        let (x, y) = (0.25 + 0.5 * column as f64, 0.25 + 0.5 * row as f64);
        let got = albedo_at(&scene, x, y);
        let want = texel(1 - column, 1 - row);
        assert!(
            (got - want).abs() <= TEXEL_TOLERANCE,
            "at ({x}, {y}): {got} vs {want}"
        );
    }
    // Offset (0.5, 0), scale (0.5, 1): u' = 0.5 + 0.5 u, so the quad's middle
    // column x = 0.5 shows the right texels' centres (u' = 0.75), where the
    // untransformed quad would blend both columns half and half.
    f.json["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"] =
        json!({"KHR_texture_transform": {"offset": [0.5, 0.0], "scale": [0.5, 1.0]}});
    let scene = load(&write_gltf(dir.path(), "scaled", &f)).scene;
    for row in [0, 1] {
        let y = 0.25 + 0.5 * row as f64;
        let got = albedo_at(&scene, 0.5, y);
        assert!(
            (got - texel(1, row)).abs() <= TEXEL_TOLERANCE,
            "at (0.5, {y}): {got}"
        );
    }
}

/// Rotation π/2 alone: glTF (u, v) ↦ (v, −u) (`uv_map`'s matrix), so the
/// texel centred at (column, row) shows texel (row, 1 − column) (wrapping);
/// the README's GLSL listing taken literally, (−v, u), would show texel
/// (1 − row, column), a different value for every centre of
/// [`QUAD_TEXELS`]. And the README's example (offset (0, 1), rotation π/2,
/// scale ½: "only the lower left quadrant of the source image, rotated
/// clockwise 90°") maps the quad's centre to the centre of the lower-left
/// texel (column 0, row 1), where the listing would give (1, 0).
#[test]
fn texture_transform_rotation_turns_as_the_extensions_example_says() {
    let dir = tempfile::tempdir().unwrap();
    let mut f = textured_quad();
    let turn = std::f64::consts::FRAC_PI_2;
    f.json["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"] =
        json!({"KHR_texture_transform": {"rotation": turn}});
    let scene = load(&write_gltf(dir.path(), "quarter", &f)).scene;
    for (column, row) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
        let (x, y) = (0.25 + 0.5 * column as f64, 0.25 + 0.5 * row as f64);
        let got = albedo_at(&scene, x, y);
        let want = texel(row, 1 - column);
        assert!(
            (got - want).abs() <= TEXEL_TOLERANCE,
            "at ({x}, {y}): {got} vs texel ({row}, {}) = {want}",
            1 - column
        );
    }
    f.json["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"] = json!(
        {"KHR_texture_transform": {"offset": [0.0, 1.0], "rotation": turn, "scale": [0.5, 0.5]}}
    );
    let scene = load(&write_gltf(dir.path(), "example", &f)).scene;
    let got = albedo_at(&scene, 0.5, 0.5);
    assert!((got - texel(0, 1)).abs() <= TEXEL_TOLERANCE, "{got}");
}

/// An emissive texture: Le = emissiveFactor × strength × texture(uv), decoded
/// from sRGB, through its own `KHR_texture_transform` (rotation π/2, as in
/// the test above); the emitter's base-colour texture, mapped without the
/// rotation, cannot share its UV set and is not modelled (warned).
#[test]
fn emissive_texture_multiplies_factor_and_strength_and_follows_its_transform() {
    let dir = tempfile::tempdir().unwrap();
    let mut f = textured_quad();
    let material = &mut f.json["materials"][0];
    material["emissiveFactor"] = json!([2.0, 2.0, 2.0]);
    material["extensions"] = json!({"KHR_materials_emissive_strength": {"emissiveStrength": 3.0}});
    material["emissiveTexture"] = json!({"index": 0, "extensions":
        {"KHR_texture_transform": {"rotation": std::f64::consts::FRAC_PI_2}}});
    let scene = load(&write_gltf(dir.path(), "screen", &f)).scene;
    let screens: Vec<&crate::scene::Polygon> = scene
        .polygons
        .iter()
        .filter(|p| scene.materials[p.material].name == "checker")
        .collect();
    assert_eq!(screens.len(), 2);
    let m = &scene.materials[screens[0].material];
    assert!(m.emission_texture.is_some(), "{:?}", scene.warnings);
    assert!(m.diffuse_texture.is_none());
    assert!(
        scene
            .warnings
            .iter()
            .any(|w| w.message.contains("map differently")),
        "{:?}",
        scene.warnings
    );
    for (column, row) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
        let (x, y) = (0.25 + 0.5 * column as f64, 0.25 + 0.5 * row as f64);
        let p = DVec3::new(x, y, 0.0) - scene.recentre_offset;
        let want = 6.0 * f64::from(crate::texture::srgb_to_linear(QUAD_TEXELS[1 - column][row]));
        for polygon in &screens {
            let got = m.emission_at(Some(polygon.uv_map.unwrap().at(p))).x;
            // f32 UVs and pyramid, times Le's scale 6.
            assert!(
                (got - want).abs() <= 6.0 * TEXEL_TOLERANCE,
                "({x}, {y}): {got} vs {want}"
            );
        }
    }
    // A zero factor emits nothing, whatever the texture: warned.
    f.json["materials"][0]["emissiveFactor"] = json!([0.0, 0.0, 0.0]);
    let loaded = load(&write_gltf(dir.path(), "dark", &f));
    assert!(
        loaded
            .scene
            .warnings
            .iter()
            .any(|w| w.message.contains("does not emit")),
        "{:?}",
        loaded.scene.warnings
    );
}

/// An emitter whose base-colour and emissive textures share their mapping
/// keeps both (the solution file's two texture slots), with no warning about
/// either.
#[test]
fn an_emitter_keeps_its_base_colour_texture_when_both_map_alike() {
    let dir = tempfile::tempdir().unwrap();
    let mut f = textured_quad();
    let material = &mut f.json["materials"][0];
    material["emissiveFactor"] = json!([2.0, 2.0, 2.0]);
    material["emissiveTexture"] = json!({"index": 0});
    let scene = load(&write_gltf(dir.path(), "both", &f)).scene;
    let m = scene
        .materials
        .iter()
        .find(|m| m.name == "checker")
        .unwrap();
    assert!(m.emission_texture.is_some(), "{:?}", scene.warnings);
    assert!(m.diffuse_texture.is_some(), "{:?}", scene.warnings);
    assert!(
        !scene
            .warnings
            .iter()
            .any(|w| w.message.contains("map differently") || w.message.contains("map_Kd")),
        "{:?}",
        scene.warnings
    );
}

#[test]
fn base_colour_texture_on_another_uv_set_is_warned_and_flat() {
    let dir = tempfile::tempdir().unwrap();
    let mut f = textured_quad();
    f.json["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["texCoord"] = json!(1);
    let loaded = load(&write_gltf(dir.path(), "set1", &f));
    let checker = loaded.scene.materials.iter().find(|m| m.name == "checker");
    assert!(checker.unwrap().diffuse_texture.is_none());
    assert!(
        loaded
            .scene
            .warnings
            .iter()
            .any(|w| w.message.contains("uses TEXCOORD_1")),
        "{:?}",
        loaded.scene.warnings
    );
}

#[test]
fn an_emission_beyond_the_bound_is_refused_naming_the_material() {
    let dir = tempfile::tempdir().unwrap();
    // emissiveFactor (1, 2, 3) × strength 1e30: each number fits f32, the
    // product's blue channel is 3e30, above `MAX_EMISSION`.
    let mut f = triangle();
    f.json["materials"][0]["extensions"] =
        json!({"KHR_materials_emissive_strength": {"emissiveStrength": 1e30}});
    let path = write_gltf(dir.path(), "bright", &f);
    let e = load_scene(&path, &ImportOptions::default()).unwrap_err();
    let at = e.source_ref().unwrap();
    assert_eq!(
        (&at.file, at.item.as_str()),
        (&path, "material `lamp` (materials[0])")
    );
    let text = e.to_string();
    assert!(
        text.contains("emission (")
            && text.contains("3.0000000") // the f32 strength widened to f64
            && text.contains("e30) exceeds 1e30 W·sr⁻¹·m⁻²"),
        "{text}"
    );
}

#[test]
fn a_textured_metal_is_not_warned_dark_but_a_dark_dielectric_is() {
    // A metal's Kd is 0, so Kd ⊙ texture is black; but its lobe reflects
    // Ks ⊙ texture (diffuse mode folds Ks into the factor the texture
    // multiplies), so "very dark reflectance" would be wrong advice. A
    // dielectric of base colour 0.01 is dark either way (0.01 + Ks 0.04,
    // times the texture's mean, below the 2% threshold).
    let dir = tempfile::tempdir().unwrap();
    let dark = |metallic: f64, base: f64| {
        let mut f = textured_quad();
        let pbr = &mut f.json["materials"][0]["pbrMetallicRoughness"];
        pbr["metallicFactor"] = json!(metallic);
        pbr["baseColorFactor"] = json!([base, base, base, 1.0]);
        let scene = load(&write_glb(dir.path(), "quad", &f)).scene;
        scene
            .warnings
            .iter()
            .any(|w| w.message.contains("very dark reflectance"))
    };
    assert!(!dark(1.0, 0.96), "a metal");
    assert!(dark(0.0, 0.01), "a dark dielectric");
}
