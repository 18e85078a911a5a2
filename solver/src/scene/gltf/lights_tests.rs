//! `KHR_lights_punctual` on files written here: lights placed by node
//! transforms (composed through a parent), their glTF units through
//! `light::units`, and the errors and warnings of bad or unused values.

use super::*;
use crate::light::lamp::Beam;
use crate::scene::{load_scene, ImportOptions};
use glam::{DQuat, DVec3};
use serde_json::{json, Value};
use std::path::PathBuf;

/// A grey triangle (no emission) and `lights`, placed by `nodes` (after the
/// triangle's node 0), all in the scene's roots unless a node is a child.
fn document(lights: Value, nodes: Value, roots: Value) -> Value {
    let mut all = vec![json!({"mesh": 0})];
    all.extend(nodes.as_array().unwrap().iter().cloned());
    json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": roots}],
        "nodes": all,
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "material": 0}]}],
        "materials": [{"name": "grey", "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1.0], "metallicFactor": 0.0}}],
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": lights}},
        "buffers": [{"byteLength": 36, "uri": "tri.bin"}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0]}]
    })
}

/// Writes `name.gltf` and its triangle's buffer.
fn write(dir: &Path, name: &str, json: &Value) -> PathBuf {
    let bin: Vec<u8> = [[0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
        .iter()
        .flatten()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    std::fs::write(dir.join("tri.bin"), bin).unwrap();
    let path = dir.join(format!("{name}.gltf"));
    std::fs::write(&path, serde_json::to_vec_pretty(json).unwrap()).unwrap();
    path
}

/// A rotation as the file stores it (f32, which the importer reads and
/// normalises), and the same rotation in f64 for the expected values.
fn quat(q: DQuat) -> (Value, DQuat) {
    let f = |v: f64| f64::from(v as f32);
    let stored = DQuat::from_xyzw(f(q.x), f(q.y), f(q.z), f(q.w));
    (
        json!([stored.x, stored.y, stored.z, stored.w]),
        stored.normalize(),
    )
}

#[test]
fn a_spot_is_placed_and_aimed_by_its_node_transform() {
    let dir = tempfile::tempdir().unwrap();
    // A spot on a child node (translation + rotation) of a translated and
    // scaled parent: world = T(10, 0, 0) S(2) · T(1, 2, 3) R.
    let (rotation, r) = quat(DQuat::from_euler(glam::EulerRot::YXZ, 0.7, -0.4, 0.2));
    let lights = json!([{"type": "spot", "name": "desk", "intensity": 683.0, "color": [1.0, 0.5, 0.25],
                         "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.5}}]);
    let nodes = json!([
        {"name": "arm", "translation": [10.0, 0.0, 0.0], "scale": [2.0, 2.0, 2.0], "children": [2]},
        {"name": "head", "translation": [1.0, 2.0, 3.0], "rotation": rotation,
         "extensions": {"KHR_lights_punctual": {"light": 0}}}
    ]);
    let path = write(dir.path(), "spot", &document(lights, nodes, json!([0, 1])));
    let scene = parse_gltf(&path).unwrap();
    let lamp = &scene.lights.lamps[0];
    // Position: the parent's T S applied to (1, 2, 3).
    let expected = DVec3::new(10.0, 0.0, 0.0) + 2.0 * DVec3::new(1.0, 2.0, 3.0);
    assert!(
        (lamp.position - expected).length() < 1e-12,
        "{}",
        lamp.position
    );
    // Axis: the node's local −z rotated by R (the uniform scale does not
    // turn it).
    let axis = r * DVec3::NEG_Z;
    let Beam::Spot {
        axis: got,
        cos_inner,
        cos_outer,
    } = lamp.beam
    else {
        panic!("{:?}", lamp.beam)
    };
    assert!((got - axis).length() < 1e-12, "{got} vs {axis}");
    // The cones, radians in the file.
    assert!((cos_inner - 0.2f64.cos()).abs() < 1e-12);
    assert!((cos_outer - 0.5f64.cos()).abs() < 1e-12);
    // 683 cd through the colour filter: (1, 0.5, 0.25) W·sr⁻¹.
    assert!((lamp.intensity - DVec3::new(1.0, 0.5, 0.25)).length() < 1e-15);
    assert_eq!(lamp.name, "desk");
}

#[test]
fn point_and_directional_lights_take_their_units_and_defaults() {
    let dir = tempfile::tempdir().unwrap();
    let (rotation, tilt) = quat(DQuat::from_rotation_x(-1.0));
    let lights = json!([
        {"type": "point", "intensity": 68.3, "range": 4.0},
        {"type": "directional", "intensity": 100000.0},
        {"type": "directional", "intensity": 10.0},
        {"type": "spot"}
    ]);
    let nodes = json!([
        {"translation": [0.0, 3.0, 0.0], "extensions": {"KHR_lights_punctual": {"light": 0}}},
        {"rotation": rotation, "extensions": {"KHR_lights_punctual": {"light": 1}}},
        {"extensions": {"KHR_lights_punctual": {"light": 2}}},
        {"extensions": {"KHR_lights_punctual": {"light": 3}}}
    ]);
    let path = write(
        dir.path(),
        "mixed",
        &document(lights, nodes, json!([0, 1, 2, 3, 4])),
    );
    let scene = parse_gltf(&path).unwrap();
    let point = &scene.lights.lamps[0];
    assert_eq!(point.beam, Beam::Point);
    assert_eq!(point.position, DVec3::new(0.0, 3.0, 0.0));
    assert!((point.intensity - DVec3::splat(0.1)).length() < 1e-15);
    // The spot's defaults: inner 0, outer π/4, white 1 cd, down −z.
    let Beam::Spot {
        axis,
        cos_inner,
        cos_outer,
    } = scene.lights.lamps[1].beam
    else {
        panic!()
    };
    assert_eq!((axis, cos_inner), (DVec3::NEG_Z, 1.0));
    assert!((cos_outer - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-12);
    assert!((scene.lights.lamps[1].intensity - DVec3::splat(1.0 / 683.0)).length() < 1e-15);
    // The brighter directional light is the sun, toward the node's +z; 100
    // klux is 146.4 W·m⁻².
    let sun = scene.lights.sun.unwrap();
    assert!((sun.direction() - tilt * DVec3::Z).length() < 1e-12);
    assert!((sun.irradiance().x - 100_000.0 / 683.0).abs() < 1e-9);
    let warned = |phrase: &str| {
        scene
            .raw
            .warnings
            .iter()
            .filter(|w| w.message.contains(phrase) && w.source.file == path)
            .count()
    };
    assert_eq!(warned("range 4 ignored"), 1);
    assert_eq!(warned("2 directional lights placed"), 1);
    assert!(scene
        .raw
        .warnings
        .iter()
        .any(|w| w.source.item.contains("light 0")));
}

#[test]
fn bad_lights_are_errors_naming_the_file_and_the_light() {
    let dir = tempfile::tempdir().unwrap();
    let node = json!([{"extensions": {"KHR_lights_punctual": {"light": 1}}}]);
    let cases = [
        (
            json!([{"type": "point"}, {"type": "area"}]),
            "light 1",
            "\"area\"",
        ),
        (
            json!([{"type": "point"}, {"type": "point", "intensity": -2.0}]),
            "light 1",
            "-2",
        ),
        (
            json!([{"type": "point"}, {"type": "spot", "spot": {"innerConeAngle": 0.6, "outerConeAngle": 0.5}}]),
            "light 1",
            "inner 34.3",
        ),
        (
            json!([{"type": "point"}, {"type": "spot", "spot": {"outerConeAngle": 2.0}}]),
            "light 1",
            "outer 114.5",
        ),
        (
            json!([{"type": "point"}]),
            "nodes[1]",
            "light 1, but the file defines 1",
        ),
    ];
    for (lights, item, value) in cases {
        let path = write(
            dir.path(),
            "bad",
            &document(lights, node.clone(), json!([0, 1])),
        );
        let message = match parse_gltf(&path) {
            Ok(_) => panic!("accepted {item} {value}"),
            Err(e) => e.to_string(),
        };
        for needle in [&path.display().to_string(), item, value] {
            assert!(message.contains(needle), "{needle:?} not in {message}");
        }
    }
}

#[test]
fn lights_light_a_gltf_scene_without_emitters() {
    let dir = tempfile::tempdir().unwrap();
    let lights = json!([{"type": "point", "intensity": 100.0}]);
    let nodes = json!([{"translation": [0.5, 0.5, 2.0], "extensions": {"KHR_lights_punctual": {"light": 0}}}]);
    let lit = write(dir.path(), "lit", &document(lights, nodes, json!([0, 1])));
    let scene = load_scene(&lit, &ImportOptions::default()).unwrap().scene;
    // The lamp moves with the polygons into the re-centred frame.
    let lamp = &scene.lights.lamps[0];
    assert!((lamp.position + scene.recentre_offset - DVec3::new(0.5, 0.5, 2.0)).length() < 1e-12);
    // Without lights: the no-emitter error gives the glTF hint, not the MTL one.
    let dark = write(
        dir.path(),
        "dark",
        &document(json!([]), json!([]), json!([0])),
    );
    let message = load_scene(&dark, &ImportOptions::default())
        .unwrap_err()
        .to_string();
    assert!(message.contains("KHR_lights_punctual"), "{message}");
    assert!(message.contains("--sun AZIMUTH,ELEVATION"), "{message}");
    assert!(!message.contains("Ke r g b"), "{message}");
}

#[test]
fn a_scene_config_keeps_its_gltf_lights_and_adds_its_own() {
    let dir = tempfile::tempdir().unwrap();
    let lights =
        json!([{"type": "point", "intensity": 683.0}, {"type": "directional", "intensity": 683.0}]);
    let (rotation, tilt) = quat(DQuat::from_rotation_x(-0.8));
    let nodes = json!([
        {"translation": [0.0, 1.0, 0.0], "extensions": {"KHR_lights_punctual": {"light": 0}}},
        {"rotation": rotation, "extensions": {"KHR_lights_punctual": {"light": 1}}}
    ]);
    write(
        dir.path(),
        "lit",
        &document(lights, nodes, json!([0, 1, 2])),
    );
    let config = dir.path().join("scene.toml");
    std::fs::write(
        &config,
        "geometry = [\"lit.gltf\"]\n[sky]\nkind = \"clear\"\n\
         [[lights]]\nposition = [0, 2, 0]\nintensity = 2\n",
    )
    .unwrap();
    let scene = load_scene(&config, &ImportOptions::default())
        .unwrap()
        .scene;
    let lights = scene.lights.recentred(-scene.recentre_offset);
    // The file's lamp first, then the config's.
    let intensities: Vec<f64> = lights.lamps.iter().map(|l| l.intensity.x).collect();
    assert_eq!(intensities, [1.0, 2.0]);
    assert_eq!(lights.lamps[0].position, DVec3::new(0.0, 1.0, 0.0));
    // The config's clear sky follows the file's directional light.
    let sun = lights.sun.unwrap();
    assert!((sun.direction() - tilt * DVec3::Z).length() < 1e-12);
    let model = lights.sky.unwrap().model();
    assert!(matches!(
        model,
        crate::light::sky::SkyModel::Clear { sun_direction, .. }
            if (sun_direction - sun.direction()).length() < 1e-15
    ));
}
