//! Enclosing shells in generated glTF files (`scene::shell`,
//! `scene::skybox`): a skybox is reported, and with a sky an unlit textured
//! one becomes the sky's map; an ordinary closed room lit from inside is not.

use super::tests::{load, write_glb, Fixture};
use crate::scene::{load_scene, ImportOptions, LoadedScene, SkyFlag, SkyFlagKind};
use glam::DVec3;
use serde_json::{json, Value};
use std::path::Path;

/// A quad's corners, counter-clockwise seen from its front, and its material.
type Quad = ([[f32; 3]; 4], usize);

/// The six faces of the cube ±`h`, facing in, the top one (+y) of material
/// `top` and the others of `rest`.
fn cube_inward(h: f32, top: usize, rest: usize) -> Vec<Quad> {
    let lo = [-h, -h, -h];
    let s = 2.0 * h;
    let add = |p: [f32; 3], d: [f32; 3]| [p[0] + d[0], p[1] + d[1], p[2] + d[2]];
    let (x, y, z) = ([s, 0.0, 0.0], [0.0, s, 0.0], [0.0, 0.0, s]);
    let face = |c: [f32; 3], a: [f32; 3], b: [f32; 3], m: usize| {
        ([c, add(c, a), add(add(c, a), b), add(c, b)], m)
    };
    vec![
        face(lo, z, x, rest),
        face(add(lo, y), x, z, top),
        face(lo, y, z, rest),
        face(add(lo, x), z, y, rest),
        face(lo, x, y, rest),
        face(add(lo, z), y, x, rest),
    ]
}

/// A floor (y = −1, facing up) and a lamp (y = 2, facing down, material
/// `lamp`), well inside any cube of half-size 5 or more.
fn furniture(floor: usize, lamp: usize) -> Vec<Quad> {
    vec![
        (
            [
                [-2.0, -1.0, -2.0],
                [-2.0, -1.0, 2.0],
                [2.0, -1.0, 2.0],
                [2.0, -1.0, -2.0],
            ],
            floor,
        ),
        (
            [
                [-0.5, 2.0, -0.5],
                [0.5, 2.0, -0.5],
                [0.5, 2.0, 0.5],
                [-0.5, 2.0, 0.5],
            ],
            lamp,
        ),
    ]
}

/// A 1 × 1 white PNG.
fn white_png() -> Vec<u8> {
    crate::scene::texture_file::tests::png(1, 1, |_, _| 255)
}

/// A glTF of `quads` (one primitive each, `TEXCOORD_0` over the whole
/// quad) with `materials`, and the white PNG as image 0 in a buffer view.
fn fixture(quads: &[Quad], materials: Value) -> Fixture {
    let mut bin = Vec::new();
    let mut views = Vec::new();
    let mut accessors = Vec::new();
    let mut primitives = Vec::new();
    let mut view = |bin: &mut Vec<u8>, bytes: &[u8]| {
        let at = bin.len();
        bin.extend_from_slice(bytes);
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        views.push(json!({"buffer": 0, "byteOffset": at, "byteLength": bytes.len()}));
        views.len() - 1
    };
    for (corners, material) in quads {
        let positions: Vec<u8> = corners
            .iter()
            .flatten()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let uvs: Vec<u8> = [[0f32, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
            .iter()
            .flatten()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let indices: Vec<u8> = [0u16, 1, 2, 0, 2, 3]
            .iter()
            .flat_map(|i| i.to_le_bytes())
            .collect();
        let (lo, hi) = corners
            .iter()
            .fold(([f32::MAX; 3], [f32::MIN; 3]), |(lo, hi), c| {
                (
                    [lo[0].min(c[0]), lo[1].min(c[1]), lo[2].min(c[2])],
                    [hi[0].max(c[0]), hi[1].max(c[1]), hi[2].max(c[2])],
                )
            });
        let p = view(&mut bin, &positions);
        accessors.push(json!({"bufferView": p, "componentType": 5126, "count": 4, "type": "VEC3", "min": lo, "max": hi}));
        let u = view(&mut bin, &uvs);
        accessors.push(json!({"bufferView": u, "componentType": 5126, "count": 4, "type": "VEC2"}));
        let i = view(&mut bin, &indices);
        accessors
            .push(json!({"bufferView": i, "componentType": 5123, "count": 6, "type": "SCALAR"}));
        let a = accessors.len();
        primitives.push(json!({"attributes": {"POSITION": a - 3, "TEXCOORD_0": a - 2}, "indices": a - 1, "material": material}));
    }
    let png = view(&mut bin, &white_png());
    let json = json!({
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": "world"}],
        "meshes": [{"name": "world", "primitives": primitives}],
        "materials": materials,
        "textures": [{"source": 0}],
        "images": [{"bufferView": png, "mimeType": "image/png"}],
        "extensionsUsed": ["KHR_materials_unlit"],
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": views,
        "accessors": accessors,
    });
    Fixture { json, bin }
}

/// Materials 0 (`sky_top`) and 1 (`sky_rest`): unlit (or not), base colours
/// (0.2, 0.4, 1) and (0.1, 0.1, 0.1) times the white texture; 2 a grey
/// floor; 3 an emitting lamp.
fn materials(unlit: bool) -> Value {
    let sky = |name: &str, colour: [f64; 3]| {
        let mut m = json!({
            "name": name,
            "pbrMetallicRoughness": {"baseColorFactor": [colour[0], colour[1], colour[2], 1.0], "baseColorTexture": {"index": 0}}
        });
        if unlit {
            m["extensions"] = json!({"KHR_materials_unlit": {}});
        }
        m
    };
    json!([
        sky("sky_top", [0.2, 0.4, 1.0]),
        sky("sky_rest", [0.1, 0.1, 0.1]),
        {"name": "floor", "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1.0], "metallicFactor": 0.0}},
        {"name": "lamp", "emissiveFactor": [1.0, 1.0, 1.0]}
    ])
}

fn with_sky(path: &Path) -> LoadedScene {
    let mut options = ImportOptions::default();
    options.lights.sky = Some(SkyFlag {
        kind: SkyFlagKind::Uniform,
        value: None,
    });
    load_scene(path, &options).unwrap()
}

fn shell_warnings(scene: &crate::scene::Scene) -> Vec<String> {
    scene
        .warnings
        .iter()
        .filter(|w| w.message.contains("enclosing shell"))
        .map(|w| w.to_string())
        .collect()
}

/// Writes `skybox.glb`: an unlit textured cube of half-size 10 around the
/// floor and the lamp.
fn skybox(dir: &Path) -> std::path::PathBuf {
    let quads: Vec<Quad> = cube_inward(10.0, 0, 1)
        .into_iter()
        .chain(furniture(2, 3))
        .collect();
    write_glb(dir, "skybox", &fixture(&quads, materials(true)))
}

#[test]
fn an_unlit_skybox_is_reported_and_kept_without_a_sky() {
    let dir = tempfile::tempdir().unwrap();
    let path = skybox(dir.path());
    let scene = load(&path).scene;
    let warnings = shell_warnings(&scene);
    assert_eq!(warnings.len(), 1, "{:#?}", scene.warnings);
    for phrase in [
        "`sky_top`",
        "`sky_rest`",
        "unlit",
        "kept as geometry",
        "With a sky",
    ] {
        assert!(
            warnings[0].contains(phrase),
            "{phrase:?} in {}",
            warnings[0]
        );
    }
    assert!(warnings[0].contains(&path.display().to_string()));
    assert_eq!(
        scene.polygons.len(),
        14,
        "the six faces (12 textured triangles) stay"
    );
}

#[test]
fn with_a_sky_an_unlit_textured_skybox_becomes_the_sky_map() {
    let dir = tempfile::tempdir().unwrap();
    let path = skybox(dir.path());
    let scene = with_sky(&path).scene;
    let warnings = shell_warnings(&scene);
    assert_eq!(warnings.len(), 1, "{:#?}", scene.warnings);
    assert!(warnings[0].contains("environment map") && warnings[0].contains("removed"));
    assert_eq!(
        scene.polygons.len(),
        2,
        "only the floor and the lamp are left"
    );
    let sky = scene.lights.sky.as_ref().expect("a sky");
    // Straight up the ray meets the top face (0.2, 0.4, 1); 10° above the
    // horizon a side face (0.1, 0.1, 0.1): the ratio is the colours'.
    let up = sky.radiance(sky.up());
    let side_dir = sky.up() * 10f64.to_radians().sin()
        + sky.up().any_orthonormal_vector() * 10f64.to_radians().cos();
    let side = sky.radiance(side_dir);
    let ratio = up / side;
    let want = DVec3::new(2.0, 4.0, 10.0);
    assert!(
        (ratio - want).abs().max_element() < 1e-4,
        "{ratio} vs {want}"
    );
    // The configured sky's horizontal illuminance is kept.
    let plain = with_sky(&write_glb(
        dir.path(),
        "plain",
        &fixture(&furniture(2, 3), materials(true)),
    ))
    .scene;
    let luminance = |v: DVec3| v.dot(DVec3::new(0.2126, 0.7152, 0.0722));
    let (got, configured) = (
        luminance(sky.horizontal_irradiance()),
        luminance(plain.lights.sky.as_ref().unwrap().horizontal_irradiance()),
    );
    assert!(
        (got / configured - 1.0).abs() < 1e-9,
        "{got} vs {configured}"
    );
    assert!(shell_warnings(&plain).is_empty(), "no shell, no report");
}

#[test]
fn a_closed_room_lit_from_inside_is_not_reported_but_one_a_sky_cannot_enter_is() {
    let dir = tempfile::tempdir().unwrap();
    // The walls are ordinary (lit) materials: a closed room with its lamp.
    let quads: Vec<Quad> = cube_inward(5.0, 0, 1)
        .into_iter()
        .chain(furniture(2, 3))
        .collect();
    let path = write_glb(dir.path(), "room", &fixture(&quads, materials(false)));
    let room = load(&path).scene;
    assert!(shell_warnings(&room).is_empty(), "{:#?}", room.warnings);
    assert_eq!(room.polygons.len(), 14);
    // The same room under a sky: the sky is outside a closed shell.
    let lit = with_sky(&path).scene;
    let warnings = shell_warnings(&lit);
    assert_eq!(warnings.len(), 1, "{:#?}", lit.warnings);
    assert!(
        warnings[0].contains("the sky outside it cannot reach anything inside"),
        "{}",
        warnings[0]
    );
    assert_eq!(lit.polygons.len(), 14, "a lit shell is kept");
}

/// The largest radiance of any vertex after the lights' shot and a few more,
/// at draft.
fn brightest_after_lights(scene: &crate::scene::Scene) -> f64 {
    let mut settings = crate::settings::SolverSettings::preset(crate::settings::Preset::Draft);
    settings.max_shots = 20;
    let mut solver = crate::solve::Solver::new(scene, &settings).unwrap();
    while solver.step().is_some() {}
    solver
        .vertex_radiance()
        .iter()
        .map(|l| l.max_element())
        .fold(0.0, f64::max)
}

#[test]
fn the_sky_reaches_the_floor_once_the_skybox_is_its_map_and_not_through_a_kept_shell() {
    let dir = tempfile::tempdir().unwrap();
    // Converted: the floor under the sky map is lit. The lamp's radiance is
    // 1; the sky's 10 klux give an open floor E = 10000/683 = 14.6 W/m², so
    // ρE/π = 2.5 in luminance for its ρ = 0.54 (grey 0.5 with the
    // dielectric's 0.04 folded in); the map is blue overhead, so the blue
    // channel is brighter still (measured 5.8).
    let converted = with_sky(&skybox(dir.path())).scene;
    let lit = brightest_after_lights(&converted);
    println!("brightest vertex under the skybox's map: {lit}");
    assert!(lit > 2.0, "{lit}");
    // Kept (lit walls, not unlit): the sky outside meets only their backs,
    // and the lamp alone lights the room.
    let quads: Vec<Quad> = cube_inward(10.0, 0, 1)
        .into_iter()
        .chain(furniture(2, 3))
        .collect();
    let kept = with_sky(&write_glb(
        dir.path(),
        "kept",
        &fixture(&quads, materials(false)),
    ))
    .scene;
    let dark = brightest_after_lights(&kept);
    println!("brightest vertex inside the kept shell: {dark}");
    assert!(dark < 1.1, "{dark}");
}
