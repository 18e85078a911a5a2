//! `--glossy` ([`crate::glossy`]): the MTL block it writes, Kd + Ks ≤ 1, its
//! errors, and the files of a scene without it, byte for byte as they were
//! before the option existed.

use crate::glossy::{apply, GlossyRequest, DEFAULT_GLOSSY};
use crate::scene::{mtl_text, obj_text, toml_text, Glossy, Scene};
use crate::{generate, Family};

fn request(text: &str) -> GlossyRequest {
    text.parse().unwrap()
}

fn cornell() -> Scene {
    generate(Family::CornellBoxes, 1000, 1).unwrap()
}

/// The MTL's blocks: (name, the lines under its `newmtl`).
fn mtl_blocks(mtl: &str) -> Vec<(String, Vec<String>)> {
    let mut blocks: Vec<(String, Vec<String>)> = Vec::new();
    for line in mtl.lines() {
        if let Some(name) = line.strip_prefix("newmtl ") {
            blocks.push((name.to_owned(), Vec::new()));
        } else if let Some((_, lines)) = blocks.last_mut() {
            if !line.is_empty() {
                lines.push(line.to_owned());
            }
        }
    }
    blocks
}

/// The three numbers after `key` in a block, parsed as the solver parses
/// them (f64); zero when the block lacks the key.
fn rgb(lines: &[String], key: &str) -> [f64; 3] {
    let Some(line) = lines.iter().find(|l| l.starts_with(&format!("{key} "))) else {
        return [0.0; 3];
    };
    let v: Vec<f64> = line[key.len() + 1..]
        .split(' ')
        .map(|x| x.parse().unwrap())
        .collect();
    [v[0], v[1], v[2]]
}

#[test]
fn a_glossy_cornell_floor_has_one_ks_ns_block_and_kd_plus_ks_at_most_1() {
    let mut scene = cornell();
    let plain = scene.clone();
    let notes = apply(&mut scene, "cornell-boxes", &[request("floor=0.6,1000")]).unwrap();
    let mtl = mtl_text(&scene);
    assert_eq!(mtl.matches("Ks 0.6 0.6 0.6").count(), 1, "{mtl}");
    assert_eq!(mtl.matches("\nNs ").count(), 1, "{mtl}");
    let blocks = mtl_blocks(&mtl);
    let floor: Vec<_> = blocks.iter().filter(|(name, _)| name == "floor").collect();
    assert_eq!(floor.len(), 1, "{mtl}");
    let lines = &floor[0].1;
    assert_eq!(lines.len(), 3, "Kd, Ks and Ns only: {lines:?}");
    assert_eq!(lines[1..], ["Ks 0.6 0.6 0.6", "Ns 1000"]);
    // White's Kd 0.725 0.71 0.68 is scaled by 0.4 / 0.725 (red is the
    // limiting channel: 0.725 + 0.6 > 1), keeping its colour to the 6
    // decimals written.
    let kd = rgb(lines, "Kd");
    let white = [0.725, 0.71, 0.68];
    assert_eq!(kd[0], 0.4, "{lines:?}");
    for c in 0..3 {
        assert!((kd[c] - white[c] * 0.4 / 0.725).abs() <= 5e-7, "{kd:?}");
    }
    assert_eq!(notes.len(), 1, "{notes:?}");
    assert!(notes[0].starts_with("floor: Kd 0.725 0.71 0.68 scaled by 0.552"));
    // Every material, as the solver would read it: Kd + Ks ≤ 1 per channel
    // in f64 (its check, solver/src/scene/clean.rs).
    for (name, lines) in &blocks {
        let (kd, ks) = (rgb(lines, "Kd"), rgb(lines, "Ks"));
        for c in 0..3 {
            assert!(kd[c] + ks[c] <= 1.0, "{name}: {kd:?} + {ks:?}");
        }
    }
    // Only the floor moved to the new material; the walls, ceiling and
    // boxes keep `white`, whose Kd is unchanged.
    for (before, after) in plain.mesh.objects.iter().zip(&scene.mesh.objects) {
        let expected = if before.name == "floor" {
            "floor"
        } else {
            before.material.as_str()
        };
        assert_eq!(after.material, expected, "{}", before.name);
    }
    let white_block = blocks.iter().find(|(n, _)| n == "white").unwrap();
    assert_eq!(white_block.1, ["Kd 0.725 0.71 0.68", "Ks 0 0 0"]);
    // The config asks for the directional solve, which shows the lobe.
    assert!(toml_text(&scene, "x.obj").contains("\nmode = \"directional\""));
    // The OBJ differs only in the description line and the floor's usemtl.
    let (old, new) = (obj_text(&plain, "x.mtl"), obj_text(&scene, "x.mtl"));
    let changed: Vec<(&str, &str)> = old
        .lines()
        .zip(new.lines())
        .filter(|(a, b)| a != b)
        .collect();
    assert_eq!(old.lines().count(), new.lines().count());
    assert_eq!(changed.len(), 2, "{changed:?}");
    assert!(changed[0]
        .1
        .ends_with("; glossy floor (Ks 0.6 0.6 0.6, Ns 1000)"));
    assert_eq!(changed[1], ("usemtl white", "usemtl floor"));
}

#[test]
fn a_named_material_turns_glossy_in_place_and_keeps_a_kd_that_fits() {
    // The floor plan's `floor` is a material: no new one. Its Kd 0.45 0.35
    // 0.25 plus Ks 0.5 stays below 1, so Kd is unchanged and nothing is said.
    let mut scene = generate(Family::FloorPlan, 1000, 1).unwrap();
    let count = scene.materials.len();
    let notes = apply(&mut scene, "floor-plan", &[request("floor")]).unwrap();
    assert!(notes.is_empty(), "{notes:?}");
    assert_eq!(scene.materials.len(), count);
    let floor = scene.materials.iter().find(|m| m.name == "floor").unwrap();
    assert_eq!(floor.kd, [0.45, 0.35, 0.25]);
    assert_eq!(floor.glossy, Some(DEFAULT_GLOSSY));
    let blocks = mtl_blocks(&mtl_text(&scene));
    let floor = blocks.iter().find(|(n, _)| n == "floor").unwrap();
    assert_eq!(floor.1, ["Kd 0.45 0.35 0.25", "Ks 0.5 0.5 0.5", "Ns 100"]);
}

#[test]
fn the_requests_order_does_not_change_the_result() {
    // The floor is split off from white's unscaled Kd either way.
    let both = |first: &str, second: &str| {
        let mut scene = cornell();
        apply(
            &mut scene,
            "cornell-boxes",
            &[request(first), request(second)],
        )
        .unwrap();
        let mut blocks = mtl_blocks(&mtl_text(&scene));
        blocks.sort();
        blocks
    };
    assert_eq!(
        both("white=0.2,10", "floor=0.6,1000"),
        both("floor=0.6,1000", "white=0.2,10")
    );
}

#[test]
fn every_family_keeps_kd_plus_ks_at_most_1_with_every_material_glossy() {
    // Ks 0.9 on every channel forces a scale wherever Kd > 0.1.
    let families = [
        (Family::CornellBoxes, 1000),
        (Family::SpheresRoom, 1000),
        (Family::FloorPlan, 1000),
        (Family::Office, 1000),
        (Family::Atrium, 5000),
        (Family::WindowRoom, 300),
        (Family::EmissiveBody, 5000),
    ];
    for (family, n) in families {
        let mut scene = generate(family, n, 1).unwrap();
        let requests: Vec<GlossyRequest> = scene
            .materials
            .iter()
            .map(|m| request(&format!("{}=0.9,0.8,0.7,50", m.name)))
            .collect();
        apply(&mut scene, family.name(), &requests).unwrap();
        for (name, lines) in mtl_blocks(&mtl_text(&scene)) {
            let (kd, ks) = (rgb(&lines, "Kd"), rgb(&lines, "Ks"));
            assert_eq!(ks, [0.9, 0.8, 0.7], "{}: {name}", family.name());
            for c in 0..3 {
                assert!(kd[c] + ks[c] <= 1.0, "{}: {name} {kd:?}", family.name());
            }
        }
    }
}

#[test]
fn an_unknown_name_is_an_error_that_lists_the_materials_and_changes_nothing() {
    let mut scene = cornell();
    let error = apply(
        &mut scene,
        "cornell-boxes",
        &[request("floor"), request("flor")],
    )
    .unwrap_err()
    .to_string();
    assert!(
        error.contains("--glossy flor: cornell-boxes has no material or object"),
        "{error}"
    );
    assert!(
        error.contains("materials are white, red, green, light"),
        "{error}"
    );
    assert!(error.contains("floor, ceiling"), "{error}");
    let plain = cornell();
    assert_eq!(mtl_text(&scene), mtl_text(&plain));
    assert_eq!(scene.description, plain.description);
    // A name given twice is refused too.
    let error = apply(
        &mut scene,
        "cornell-boxes",
        &[request("red"), request("red=0.2,5")],
    )
    .unwrap_err()
    .to_string();
    assert!(error.contains("given twice"), "{error}");
}

#[test]
fn the_argument_parses_its_three_forms_and_refuses_bad_values() {
    assert_eq!(
        request("floor"),
        GlossyRequest {
            name: "floor".into(),
            glossy: Glossy {
                ks: [0.5; 3],
                ns: 100.0
            }
        }
    );
    assert_eq!(
        request("floor=0.6,1000").glossy,
        Glossy {
            ks: [0.6; 3],
            ns: 1000.0
        }
    );
    assert_eq!(
        request("red=0.1, 0.2, 0.3, 0").glossy,
        Glossy {
            ks: [0.1, 0.2, 0.3],
            ns: 0.0
        }
    );
    for (bad, why) in [
        ("=0.5,10", "name is missing"),
        ("floor=0.6", "found 1 values"),
        ("floor=0.1,0.2,10", "found 3 values"),
        ("floor=1.2,10", "Ks must lie in [0, 1]"),
        ("floor=0,0,0,10", "one channel above 0"),
        ("floor=0.5,-1", "Ns must not be negative"),
        ("floor=x,10", "`x` is not a number"),
        ("floor=0.5,inf", "`inf` is not a number"),
    ] {
        let error = bad.parse::<GlossyRequest>().unwrap_err();
        assert!(error.contains(why), "{bad}: {error}");
    }
}

/// The cornell-boxes (1000 triangles, seed 1) and floor-plan (1000) MTL and
/// TOML as the generator wrote them before `--glossy` existed (dd47f58).
const CORNELL_MTL: &str =
    "# Kd: diffuse reflectance (linear RGB). Ke: emitted radiance, W*sr^-1*m^-2
# (linear RGB), one-sided toward the face's front.

newmtl white
Kd 0.725 0.71 0.68
Ks 0 0 0

newmtl red
Kd 0.63 0.065 0.05
Ks 0 0 0

newmtl green
Kd 0.14 0.45 0.091
Ks 0 0 0

newmtl light
Kd 0.78 0.78 0.78
Ks 0 0 0
Ke 17 12 4
";

const CORNELL_TOML: &str = "# cornell-boxes: the Cornell box with 82 small boxes (seed 1)
# Scene config for `solver solve` (solver/src/scene/config.rs), written by tools/scenegen.
# No patch or solver overrides: the preset decides the meshing, as for a user's model.

geometry = [\"cornell-boxes.obj\"]
units_per_metre = 1000      # the OBJ is in millimetres
up = \"y\"
mode = \"diffuse\"            # every material has Ks = 0

[camera]
eye = [278.0, 273.0, -800.0]
target = [278.0, 273.0, 0.0]
up = [0.0, 1.0, 0.0]
fov_y_deg = 39.3077
width = 512
height = 512
";

const FLOOR_PLAN_MTL: &str =
    "# Kd: diffuse reflectance (linear RGB). Ke: emitted radiance, W*sr^-1*m^-2
# (linear RGB), one-sided toward the face's front.

newmtl wall
Kd 0.7 0.68 0.65
Ks 0 0 0

newmtl floor
Kd 0.45 0.35 0.25
Ks 0 0 0

newmtl threshold
Kd 0.45 0.35 0.25
Ks 0 0 0

newmtl ceiling
Kd 0.8 0.8 0.8
Ks 0 0 0

newmtl light
Kd 0.78 0.78 0.78
Ks 0 0 0
Ke 10 10 10
";

const FLOOR_PLAN_TOML: &str = "# floor-plan: 2 x 2 rooms, walls cut into quads of at most 1468 mm
# Scene config for `solver solve` (solver/src/scene/config.rs), written by tools/scenegen.
# No patch or solver overrides: the preset decides the meshing, as for a user's model.

geometry = [\"floor-plan.obj\"]
units_per_metre = 1000      # the OBJ is in millimetres
up = \"y\"
mode = \"diffuse\"            # every material has Ks = 0

[camera]
eye = [600.0, 1600.0, 600.0]
target = [4000.0, 1100.0, 4000.0]
up = [0.0, 1.0, 0.0]
fov_y_deg = 60.0000
width = 512
height = 512
";

#[test]
fn without_glossy_the_files_are_byte_identical_to_before() {
    for (family, mtl, toml) in [
        (Family::CornellBoxes, CORNELL_MTL, CORNELL_TOML),
        (Family::FloorPlan, FLOOR_PLAN_MTL, FLOOR_PLAN_TOML),
    ] {
        let mut scene = generate(family, 1000, 1).unwrap();
        let obj = obj_text(&scene, "x.mtl");
        // No request changes nothing, not even the description.
        assert!(apply(&mut scene, family.name(), &[]).unwrap().is_empty());
        assert_eq!(mtl_text(&scene), mtl, "{}", family.name());
        let obj_name = format!("{}.obj", family.name());
        assert_eq!(toml_text(&scene, &obj_name), toml, "{}", family.name());
        assert_eq!(obj_text(&scene, "x.mtl"), obj, "{}", family.name());
    }
}
