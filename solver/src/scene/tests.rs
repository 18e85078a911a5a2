//! Import tests across the readers, cleaning, welding and re-centring, on the
//! bundled scenes in `config/` and on files written the way other tools write
//! them (into a temporary folder).

use super::*;
use solution::format::SolveMode;
use std::fs;

fn config_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../config")
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    if let Some(parent) = path.parent() {
        fs::create_dir_all(parent).unwrap();
    }
    fs::write(&path, text).unwrap();
    path
}

fn load(path: &Path) -> Result<LoadedScene, SceneError> {
    load_scene(path, &ImportOptions::default())
}

fn load_strict(path: &Path) -> Result<LoadedScene, SceneError> {
    load_scene(
        path,
        &ImportOptions {
            strict: true,
            ..Default::default()
        },
    )
}

/// A unit-square light at y = 1 facing down, material `lamp`, appended to test
/// OBJ files that need an emitter. Uses relative indices so it can go anywhere.
const LAMP_OBJ: &str = "\nusemtl lamp\nv 0 1 0\nv 1 1 0\nv 1 1 1\nv 0 1 1\nf -4 -3 -2 -1\n";
const LAMP_MTL: &str = "\nnewmtl lamp\nKd 0.5 0.5 0.5\nKe 10 10 10\n";

fn find<'a>(scene: &'a Scene, name: &str) -> &'a Material {
    scene
        .materials
        .iter()
        .find(|m| m.name == name)
        .unwrap_or_else(|| panic!("no material {name}"))
}

#[test]
fn cornell_box_config_imports_as_published() {
    let loaded = load(&config_dir().join("cornell_box.toml")).unwrap();
    let scene = &loaded.scene;
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    // 5 room quads + 5 + 5 block faces + the light; the red wall's 0.80 mm
    // (1.0e-3 of its size) is within the planarity tolerance, so it stays a quad.
    assert_eq!(scene.polygons.len(), 16);
    assert!(scene.polygons.iter().all(|p| p.vertices.len() == 4));
    assert!(scene.polygons.iter().all(|p| p.vertex_normals.is_none()));
    let emitters: Vec<&Polygon> = scene
        .polygons
        .iter()
        .filter(|p| scene.materials[p.material].is_emitter())
        .collect();
    assert_eq!(emitters.len(), 1);
    // The light is 130 mm × 105 mm; Newell's area in f64 on coordinates of a few
    // hundred is exact to ~1e-12 relative.
    assert!((emitters[0].area() - 13650.0).abs() < 1e-9 * 13650.0);
    assert!((emitters[0].normal() - DVec3::NEG_Y).length() < 1e-12);
    assert_eq!(emitters[0].patches, 1);

    assert_eq!(scene.materials.len(), 4);
    assert_eq!(find(scene, "white").kd, DVec3::new(0.725, 0.71, 0.68));
    assert_eq!(find(scene, "red").kd, DVec3::new(0.63, 0.065, 0.05));
    assert_eq!(find(scene, "green").kd, DVec3::new(0.14, 0.45, 0.091));
    let light = find(scene, "light");
    assert_eq!(light.emission, DVec3::new(17.0, 12.0, 4.0));
    assert!(scene.materials.iter().all(|m| !m.is_glossy()));

    // The box spans x 0..556, y 0..548.8, z 0..559.2: its centre is the offset.
    let expected = DVec3::new(278.0, 274.4, 279.6);
    assert!((scene.recentre_offset - expected).length() < 1e-12);
    let max = scene
        .polygons
        .iter()
        .flat_map(|p| p.vertices.iter())
        .fold(DVec3::splat(f64::NEG_INFINITY), |m, v| m.max(*v));
    assert!((max - DVec3::new(278.0, 274.4, 279.6)).length() < 1e-12);

    assert_eq!(scene.units_per_metre, 1000.0);
    assert_eq!(scene.up_axis, UpAxis::PosY);
    let camera = scene.camera.unwrap();
    assert_eq!(camera.eye, [278.0, 273.0, -800.0]);
    assert_eq!(camera.target, [278.0, 273.0, 0.0]);
    assert_eq!(camera.fov_y_deg, 39.3077);
    assert_eq!(loaded.settings.mode, Some(SolveMode::Diffuse));
    assert_eq!(loaded.settings.units_per_metre, Some(1000.0));

    // Walls take the preset's subdivision later; blocks asked for 2.
    let unset = scene
        .polygons
        .iter()
        .filter(|p| p.patches == PATCHES_UNSET)
        .count();
    assert_eq!(unset, 5);
    let mut filled = loaded.scene.clone();
    filled.fill_default_patches(4);
    assert!(filled.polygons.iter().all(|p| p.patches >= 1));
    assert_eq!(
        filled.polygons.iter().filter(|p| p.patches == 2).count(),
        10
    );
}

#[test]
fn legacy_and_display_copies_of_the_cornell_box_match_the_obj() {
    let obj = load(&config_dir().join("cornell_box.obj")).unwrap().scene;
    let geom = load(&config_dir().join("cornell_box.geom")).unwrap().scene;
    assert!(geom.warnings.is_empty(), "{:?}", geom.warnings);
    assert_eq!(geom.polygons.len(), obj.polygons.len());
    assert_eq!(geom.recentre_offset, obj.recentre_offset);
    for (g, o) in geom.polygons.iter().zip(&obj.polygons) {
        assert_eq!(g.vertices, o.vertices);
        let (gm, om) = (&geom.materials[g.material], &obj.materials[o.material]);
        assert_eq!((gm.kd, gm.emission), (om.kd, om.emission));
    }
    assert_eq!(geom.polygons[0].patches, 4);
    assert_eq!(geom.polygons[15].patches, 1);

    let display = load_display_file(&config_dir().join("cornell_box.display")).unwrap();
    assert!(display.warnings.is_empty());
    let camera = load(&config_dir().join("cornell_box.toml"))
        .unwrap()
        .scene
        .camera
        .unwrap();
    assert_eq!(display.camera.eye, camera.eye);
    assert_eq!(display.camera.target, camera.target);
    assert_eq!(display.camera.fov_y_deg, camera.fov_y_deg);
    assert_eq!(display.settings.threshold, Some(0.005));
}

#[test]
fn glossy_floor_scene_welds_its_floor_and_keeps_the_lobe() {
    let loaded = load(&config_dir().join("glossy_floor.toml")).unwrap();
    let scene = &loaded.scene;
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    // Floor (two triangles welded into one quad), ceiling, 4 walls, light.
    assert_eq!(scene.polygons.len(), 7);
    let floor = find(scene, "glossy_floor");
    assert_eq!(floor.ks, DVec3::splat(0.6));
    assert!((floor.alpha - 0.1).abs() < 1e-15);
    assert!(floor.kd.x + floor.ks.x <= 1.0);
    let floor_polygon = scene
        .polygons
        .iter()
        .find(|p| scene.materials[p.material].name == "glossy_floor")
        .unwrap();
    assert_eq!(floor_polygon.vertices.len(), 4);
    assert!((floor_polygon.area() - 12.0).abs() < 1e-12);
    assert!((floor_polygon.normal() - DVec3::Y).length() < 1e-12);
    assert_eq!(loaded.settings.mode, Some(SolveMode::Directional));
    let light = scene
        .polygons
        .iter()
        .find(|p| scene.materials[p.material].is_emitter())
        .unwrap();
    assert!((light.normal() - DVec3::NEG_Y).length() < 1e-12);
    // The room's normals all point inward: toward the room's centre (the origin
    // after re-centring) from each wall.
    for p in &scene.polygons {
        let centroid = p.vertices.iter().copied().sum::<DVec3>() / p.vertices.len() as f64;
        assert!(p.normal().dot(-centroid) > 0.0, "{}", p.source);
    }
}

#[test]
fn a_floor_exported_as_two_triangles_welds_into_one_quad() {
    let dir = tempfile::tempdir().unwrap();
    let obj = write(
        dir.path(),
        "floor.obj",
        &format!(
            "mtllib floor.mtl\nusemtl grey\nv 0 0 0\nv 4 0 0\nv 4 0 -3\nv 0 0 -3\n\
             f 1 2 3\nf 1 3 4\n{LAMP_OBJ}"
        ),
    );
    write(
        dir.path(),
        "floor.mtl",
        &format!("newmtl grey\nKd 0.5 0.5 0.5\n{LAMP_MTL}"),
    );
    let scene = load(&obj).unwrap().scene;
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    assert_eq!(scene.polygons.len(), 2);
    let floor = &scene.polygons[0];
    assert_eq!(floor.vertices.len(), 4);
    assert!((floor.area() - 12.0).abs() < 1e-12);
    assert_eq!(floor.source.item, "face 1 + 1 welded");
    assert_eq!(floor.source.line, Some(7));
}

#[test]
fn warnings_name_the_polygon_and_strict_turns_them_into_errors() {
    let dir = tempfile::tempdir().unwrap();
    let mtl = format!("newmtl grey\nKd 0.5 0.5 0.5\n{LAMP_MTL}");
    write(dir.path(), "w.mtl", &mtl);
    // (face lines, warning phrase, polygons left besides the lamp)
    let cases: [(&str, &str, usize); 8] = [
        ("v 0 0 0\nv 1 0 0\nf 1 2\n", "degenerate polygon", 0),
        (
            "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n",
            "degenerate polygon",
            0,
        ),
        // A bow-tie: its two halves cancel in Newell's area.
        (
            "v 0 0 0\nv 1 0 1\nv 1 0 0\nv 0 0 1\nf 1 2 3 4\n",
            "zero-area polygon",
            0,
        ),
        // A quad with one corner lifted by 0.5 on a 1 × 1 square (deviation 0.125,
        // 0.09 of its size, beyond 5e-3): split into two triangles.
        (
            "v 0 0 0\nv 1 0 0\nv 1 0.5 1\nv 0 0 1\nf 1 4 3 2\n",
            "non-planar polygon",
            2,
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nf 1 4 4 3 2\n",
            "repeated vertices",
            1,
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nv 0 0 0.5\nf 1 5 4 3 2\n",
            "collinear vertices",
            1,
        ),
        (
            "v 1 0 0\nv 0.309 0 0.951\nv -0.809 0 0.588\nv -0.809 0 -0.588\nv 0.309 0 -0.951\n\
             f 1 3 5 2 4\n",
            "self-intersecting polygon",
            0,
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 1 0 1\nvn 0 -1 0\nf 1//1 3//1 2//1\n",
            "vertex normals",
            1,
        ),
    ];
    for (faces, phrase, left) in cases {
        let obj = write(
            dir.path(),
            "w.obj",
            &format!("mtllib w.mtl\no thing\nusemtl grey\n{faces}{LAMP_OBJ}"),
        );
        let scene = load(&obj).unwrap().scene;
        let w = scene
            .warnings
            .iter()
            .find(|w| w.message.starts_with(phrase))
            .unwrap_or_else(|| panic!("no `{phrase}` warning in {:?}", scene.warnings));
        assert_eq!(w.source.file, obj);
        assert!(w.source.item.starts_with("face 1 of object thing"), "{w}");
        assert!(w.source.line.is_some(), "{w}");
        assert_eq!(scene.polygons.len() - 1, left, "{phrase}");
        match load_strict(&obj) {
            Err(SceneError::Strict { warning, .. }) => assert!(warning.message.starts_with(phrase)),
            other => panic!("strict import of `{phrase}` gave {other:?}"),
        }
    }
}

#[test]
fn kd_plus_ks_above_one_is_scaled_once_per_material_and_named() {
    let dir = tempfile::tempdir().unwrap();
    let obj = write(
        dir.path(),
        "shiny.obj",
        &format!(
            "mtllib shiny.mtl\nusemtl plastic\nv 0 0 0\nv 1 0 0\nv 1 0 -1\nv 0 0 -1\n\
             f 1 2 3 4\nv 2 0 0\nv 3 0 0\nv 3 0 -1\nf 5 6 7\n{LAMP_OBJ}"
        ),
    );
    // Exporters' "Kd 0.8 Ks 0.5": red sums to 1.3, green 0.9, blue to exactly 1.
    write(
        dir.path(),
        "shiny.mtl",
        &format!("# plastic\n\nnewmtl plastic\nKd 0.8 0.4 0.5\nKs 0.5 0.5 0.5\nNs 250\n{LAMP_MTL}"),
    );
    let scene = load(&obj).unwrap().scene;
    let warnings: Vec<&Warning> = scene
        .warnings
        .iter()
        .filter(|w| w.message.starts_with("Kd + Ks > 1"))
        .collect();
    assert_eq!(warnings.len(), 1, "once per material: {:?}", scene.warnings);
    let w = warnings[0];
    assert_eq!(w.source.file, dir.path().join("shiny.mtl"));
    assert_eq!(w.source.line, Some(3));
    assert!(
        w.message.contains("plastic") && w.message.contains("(0.8, 0.4, 0.5)"),
        "{w}"
    );
    let m = find(&scene, "plastic");
    // Red: both × 1/1.3 so they sum to 1; green and blue (≤ 1) untouched.
    assert!((m.kd.x + m.ks.x - 1.0).abs() < 1e-15);
    assert!((m.kd.x / m.ks.x - 0.8 / 0.5).abs() < 1e-12);
    assert_eq!((m.kd.y, m.ks.y, m.kd.z, m.ks.z), (0.4, 0.5, 0.5, 0.5));
    assert!((m.alpha - (2.0f64 / 252.0).sqrt()).abs() < 1e-15);
    match load_strict(&obj) {
        Err(SceneError::Strict { warning, .. }) => {
            assert!(warning.message.starts_with("Kd + Ks > 1"));
            assert!(warning.to_string().contains("shiny.mtl:3"));
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn obj_and_mtl_errors_name_file_and_face_or_material() {
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        "e.mtl",
        &format!("newmtl grey\nKd 0.5 0.5 0.5\n{LAMP_MTL}"),
    );
    let head = "mtllib e.mtl\no box\nusemtl grey\nv 0 0 0\nv 1 0 0\nv 1 0 1\n";
    let cases: [(&str, &str, &str); 8] = [
        (
            "f 1 2 3\nf 1 2 4\n",
            "e.obj:8 (face 2 of object box)",
            "vertex index 4 is out of range: 3 vertices are defined",
        ),
        (
            "f 1 2 -4\n",
            "e.obj:7 (face 1 of object box)",
            "vertex index -4 is out of range",
        ),
        (
            "f 1 2 0\n",
            "e.obj:7 (face 1 of object box)",
            "index 0 is invalid",
        ),
        (
            "f 1 2 3//1\n",
            "e.obj:7 (face 1 of object box)",
            "normal index 1 is out of range: 0 normals",
        ),
        (
            "f 1 2 x\n",
            "e.obj:7 (face 1 of object box)",
            "vertex index `x` is not an integer",
        ),
        (
            "f 1/2/3/4 2 3\n",
            "e.obj:7 (face 1 of object box)",
            "expected v, v/vt, v//vn or v/vt/vn",
        ),
        (
            "v 1 2 nan\n",
            "e.obj:7",
            "vertex 4 z is not a finite number",
        ),
        ("vn 1 2\n", "e.obj:7 (normal 1)", "`vn` needs 3 numbers"),
    ];
    for (tail, at, fragment) in cases {
        let obj = write(dir.path(), "e.obj", &format!("{head}{tail}"));
        let message = load(&obj).unwrap_err().to_string();
        let expected_at = format!("{}", dir.path().join(at).display());
        assert!(
            message.starts_with(&expected_at),
            "{message:?} should start with {expected_at:?}"
        );
        assert!(
            message.contains(fragment),
            "{message:?} should say {fragment:?}"
        );
    }

    // A missing library is named with the OBJ line that asks for it.
    let obj = write(dir.path(), "m.obj", "# x\nmtllib nowhere/missing.mtl\n");
    let message = load(&obj).unwrap_err().to_string();
    assert!(
        message.contains("m.obj:2") && message.contains("missing.mtl"),
        "{message}"
    );

    // A bad MTL line names the MTL file, its line and the material.
    write(dir.path(), "bad.mtl", "newmtl chalk\nKd 0.5 0.5\n");
    let obj = write(dir.path(), "b.obj", "mtllib bad.mtl\n");
    let message = load(&obj).unwrap_err().to_string();
    assert!(message.contains("bad.mtl:2 (material chalk)"), "{message}");
}

#[test]
fn undefined_materials_get_the_default_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "u.mtl", LAMP_MTL);
    let obj = write(
        dir.path(),
        "u.obj",
        &format!(
            "mtllib u.mtl\nusemtl Material.001\nv 0 0 0\nv 1 0 0\nv 1 0 -1\nf 1 2 3\n{LAMP_OBJ}"
        ),
    );
    let scene = load(&obj).unwrap().scene;
    let m = find(&scene, "Material.001");
    assert_eq!(m.kd, DVec3::splat(0.8));
    let w = scene
        .warnings
        .iter()
        .find(|w| w.message.contains("Material.001"))
        .unwrap();
    assert_eq!(w.source.line, Some(6));
}

#[test]
fn no_emitter_and_empty_scenes_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "d.mtl", "newmtl grey\nKd 0.5 0.5 0.5\n");
    let dark = write(
        dir.path(),
        "dark.obj",
        "mtllib d.mtl\nusemtl grey\nv 0 0 0\nv 1 0 0\nv 1 0 -1\nf 1 2 3\n",
    );
    let err = load(&dark).unwrap_err();
    assert!(matches!(err, SceneError::NoEmitter(_)));
    let message = err.to_string();
    assert!(message.starts_with("no emitter: "), "{message}");
    assert!(
        message.contains("grey") && message.contains("Ke r g b"),
        "{message}"
    );

    let empty = write(dir.path(), "empty.obj", "# nothing here\nv 0 0 0\n");
    let message = load(&empty).unwrap_err().to_string();
    assert!(
        message.starts_with("empty scene: ") && message.contains("no polygons"),
        "{message}"
    );

    let degenerate = write(
        dir.path(),
        "degenerate.obj",
        "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n",
    );
    let message = load(&degenerate).unwrap_err().to_string();
    assert!(
        message.starts_with("empty scene: ") && message.contains("degenerate"),
        "{message}"
    );

    let legacy = write(
        dir.path(),
        "none.geom",
        "title\nccw\npoints 0 patches 0 attributes 0\n",
    );
    let message = load(&legacy).unwrap_err().to_string();
    assert!(message.starts_with("empty scene: "), "{message}");

    let blank = write(dir.path(), "blank.geom", "");
    assert!(matches!(load(&blank), Err(SceneError::Empty(_))));
}

/// A UV sphere of radius `r` about `c` with `rings` × `segments` facets, written
/// with per-vertex normals as modelling tools export smooth surfaces: triangles
/// at the poles, quads elsewhere, counter-clockwise seen from outside.
/// `first` is the 1-based index its first `v` will have in the file (its normals
/// are the file's only ones, numbered from 1).
fn sphere_obj(c: [f64; 3], r: f64, rings: usize, segments: usize, first: usize) -> (String, usize) {
    use std::f64::consts::{PI, TAU};
    let mut text = String::new();
    let mut rows = Vec::new();
    for i in 0..=rings {
        let theta = PI * i as f64 / rings as f64;
        let mut row = Vec::new();
        let count = if i == 0 || i == rings { 1 } else { segments };
        for j in 0..count {
            let phi = TAU * j as f64 / segments as f64;
            let n = [
                theta.sin() * phi.cos(),
                theta.cos(),
                -theta.sin() * phi.sin(),
            ];
            text += &format!(
                "v\t{} {} {}\nvn {} {} {}\n",
                c[0] + r * n[0],
                c[1] + r * n[1],
                c[2] + r * n[2],
                n[0],
                n[1],
                n[2]
            );
            row.push(rows.iter().map(|r: &Vec<usize>| r.len()).sum::<usize>() + row.len() + 1);
        }
        rows.push(row);
    }
    let mut faces = 0;
    for i in 0..rings {
        for j in 0..segments {
            let (a, b) = (&rows[i], &rows[i + 1]);
            let corner = |row: &Vec<usize>, k: usize| row[k % row.len()];
            let ring: Vec<usize> = if i == 0 {
                vec![a[0], corner(b, j), corner(b, j + 1)]
            } else if i == rings - 1 {
                vec![corner(a, j), b[0], corner(a, j + 1)]
            } else {
                vec![
                    corner(a, j),
                    corner(b, j),
                    corner(b, j + 1),
                    corner(a, j + 1),
                ]
            };
            let refs: Vec<String> = ring
                .iter()
                .map(|v| format!("{}//{v}", v + first - 1))
                .collect();
            text += &format!("f {}\n", refs.join(" "));
            faces += 1;
        }
    }
    (text, faces)
}

#[test]
fn real_files_in_other_tools_styles_import_as_a_user_expects() {
    let dir = tempfile::tempdir().unwrap();
    // Materials in a subfolder, named relative to the OBJ; tabs and CRLF.
    write(
        dir.path(),
        "models/materials/room.mtl",
        "newmtl\twall\r\n\tKd\t0.6 0.6 0.6\r\nnewmtl ball\r\nKd 0.3 0.3 0.9\r\n\
         newmtl lamp\r\nKd 0.5\r\nKe 20 20 20\r\n",
    );
    let (sphere, sphere_faces) = sphere_obj([0.5, 0.4, -0.5], 0.2, 8, 12, 9);
    let obj_text = format!(
        "# Exported by a modelling tool\r\nmtllib materials/room.mtl\r\n\
         o\tFloor\r\nv 0 0 0\r\nv 1 0 0\r\nv 1 0 -1\r\nv 0 0 -1\r\nvt 0 0\r\nvt 1\r\ns off\r\n\
         usemtl\twall\r\nf -4/1 -3/2 -2/1 -1/2\r\n\
         o Wall\r\nv 0 0 -1\r\nv 1 0 -1\r\nv 1 1 -1.001\r\nv 0 1 -1\r\nf\t-4\t-3\t-2\t-1\r\n\
         o Ball\r\nusemtl ball\r\ns 1\r\n{sphere}\
         o Lamp\r\nusemtl lamp\r\nv 0.4 0.99 -0.4\r\nv 0.6 0.99 -0.4\r\nv 0.6 0.99 -0.6\r\nv 0.4 0.99 -0.6\r\n\
         f -1 -2 -3 -4\r\n"
    );
    let obj = write(dir.path(), "models/room.obj", &obj_text);
    let scene = load(&obj).unwrap().scene;
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    assert_eq!(scene.polygons.len(), 3 + sphere_faces);

    let wall = find(&scene, "wall");
    assert_eq!(wall.kd, DVec3::splat(0.6));
    assert_eq!(find(&scene, "lamp").emission, DVec3::splat(20.0));
    let floor = &scene.polygons[0];
    assert_eq!(floor.vertices.len(), 4);
    assert!((floor.normal() - DVec3::Y).length() < 1e-12);
    // The wall is 1 mm out of plane on a 1.4 m diagonal (deviation 2.5e-4, 1.8e-4 of
    // its size): kept as one quad, no warning.
    let back = &scene.polygons[1];
    assert_eq!(back.vertices.len(), 4);
    assert!(back.source.item.contains("object Wall"));

    let balls: Vec<&Polygon> = scene
        .polygons
        .iter()
        .filter(|p| scene.materials[p.material].name == "ball")
        .collect();
    assert_eq!(balls.len(), sphere_faces);
    assert_eq!(balls.iter().filter(|p| p.vertices.len() == 3).count(), 24);
    let centre = DVec3::new(0.5, 0.4, -0.5) - scene.recentre_offset;
    for p in &balls {
        // Smooth: the given normals differ from the facet normal by up to half a facet's
        // angular size (11° to 15° here), far beyond 0.1°, so they are kept.
        let normals = p
            .vertex_normals
            .as_ref()
            .expect("sphere facets keep vertex normals");
        for (v, n) in p.vertices.iter().zip(normals) {
            assert!((n.length() - 1.0).abs() < 1e-12);
            // Each given normal is the radial direction at its vertex.
            assert!((*n - (*v - centre) / 0.2).length() < 1e-9);
        }
        // Counter-clockwise seen from outside: the facet normal points away from the centre.
        let centroid = p.vertices.iter().copied().sum::<DVec3>() / p.vertices.len() as f64;
        assert!(p.normal().dot(centroid - centre) > 0.0);
    }
    let lamp = scene.polygons.last().unwrap();
    assert!((lamp.normal() - DVec3::NEG_Y).length() < 1e-12);
}

#[test]
fn a_scene_translated_by_a_million_units_recentres_to_the_same_positions() {
    let text = fs::read_to_string(config_dir().join("cornell_box.obj")).unwrap();
    let shift = DVec3::splat(1.0e6);
    let moved: String = text
        .lines()
        .map(|line| match line.strip_prefix("v ") {
            Some(rest) => {
                let p: Vec<f64> = rest
                    .split_whitespace()
                    .map(|t| t.parse().unwrap())
                    .collect();
                format!(
                    "v {:?} {:?} {:?}\n",
                    p[0] + shift.x,
                    p[1] + shift.y,
                    p[2] + shift.z
                )
            }
            None => format!("{line}\n"),
        })
        .collect();
    let dir = tempfile::tempdir().unwrap();
    fs::copy(
        config_dir().join("cornell_box.mtl"),
        dir.path().join("cornell_box.mtl"),
    )
    .unwrap();
    let obj = write(dir.path(), "far.obj", &moved);
    let near = load(&config_dir().join("cornell_box.obj")).unwrap().scene;
    let far = load(&obj).unwrap().scene;
    assert_eq!(far.polygons.len(), near.polygons.len());
    // Coordinates near 1e6 carry f64 spacing 1.2e-10; adding the shift, printing
    // and re-parsing, and re-centring each round once, so 1e-9 (8 ulps) bounds it.
    let tolerance = 1e-9;
    assert!((far.recentre_offset - near.recentre_offset - shift).length() < tolerance);
    for (a, b) in far.polygons.iter().zip(&near.polygons) {
        for (p, q) in a.vertices.iter().zip(&b.vertices) {
            assert!((*p - *q).abs().max_element() < tolerance, "{p} vs {q}");
        }
    }
}

#[test]
fn toml_overrides_change_materials_and_patches() {
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        "o.mtl",
        "newmtl grey\nKd 0.5 0.5 0.5\nnewmtl bulb\nKd 0.5 0.5 0.5\n",
    );
    write(
        dir.path(),
        "geo/o.obj",
        "mtllib ../o.mtl\no floor\nusemtl grey\nv 0 0 0\nv 1 0 0\nv 1 0 -1\nv 0 0 -1\nf 1 2 3 4\n\
         o lamp\nusemtl bulb\nv 0 1 0\nv 1 1 0\nv 1 1 -1\nf 7 6 5\n",
    );
    write(
        dir.path(),
        "legacy.geom",
        "legacy\nccw\npoints 3 patches 1 attributes 1\n0 2 0\n1 2 0\n1 2 -1\n3 1 2 3 attribute 1\n\
         color 0.2 0.2 0.2 material 9\n",
    );
    let config = write(
        dir.path(),
        "scene.toml",
        "geometry = [\"geo/o.obj\", \"legacy.geom\"]\nunits_per_metre = 100\nup = \"z\"\n\n\
         [materials.bulb]\nemission = [5, 6, 7]\n\n\
         [materials.grey]\nkd = 0.7\nks = [0.6, 0.2, 0.2]\nalpha = 0.05\npatches = 5\n\n\
         [materials.\"material 9\"]\nkd = [0.1, 0.2, 0.3]\n\n\
         [objects.lamp]\npatches = 1\n\n[solver]\nsamples = 7\nmode = \"directional\"\n",
    );
    let loaded = load(&config).unwrap();
    let scene = &loaded.scene;
    assert_eq!(find(scene, "bulb").emission, DVec3::new(5.0, 6.0, 7.0));
    assert_eq!(find(scene, "attribute 1").kd, DVec3::new(0.1, 0.2, 0.3));
    let grey = find(scene, "grey");
    assert_eq!(grey.alpha, 0.05);
    // kd 0.7 + ks 0.6 = 1.3 in red: scaled, and the warning cites the TOML line.
    assert!((grey.kd.x + grey.ks.x - 1.0).abs() < 1e-15);
    let w = scene
        .warnings
        .iter()
        .find(|w| w.message.starts_with("Kd + Ks > 1"))
        .unwrap();
    assert!(w.message.contains("scene.toml:8 (materials.grey)"), "{w}");
    assert_eq!(scene.polygons[0].patches, 5);
    assert_eq!(scene.polygons[1].patches, 1);
    assert_eq!(scene.polygons[2].patches, PATCHES_UNSET);
    assert_eq!(scene.units_per_metre, 100.0);
    assert_eq!(scene.up_axis, UpAxis::PosZ);
    assert_eq!(loaded.settings.samples, Some(7));
    assert_eq!(loaded.settings.mode, Some(SolveMode::Directional));
    assert!(scene.camera.is_none());

    // A command-line units_per_metre wins over the config's.
    let flagged = load_scene(
        &config,
        &ImportOptions {
            units_per_metre: Some(1.0),
            default_patches: 3,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(flagged.scene.units_per_metre, 1.0);
    assert_eq!(flagged.scene.polygons[2].patches, 3);
}

#[test]
fn toml_sizes_per_object_and_material_in_scene_units_and_metres() {
    use crate::mesh::{Mesh, Sizing};
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        "o.mtl",
        &format!("newmtl grey\nKd 0.5 0.5 0.5\n{LAMP_MTL}"),
    );
    // Scene units are centimetres: a 200 × 100 floor (2 m × 1 m), a 100 × 100
    // wall, and the unit lamp.
    write(
        dir.path(),
        "o.obj",
        &format!(
            "mtllib o.mtl\no floor\nusemtl grey\nv 0 0 0\nv 200 0 0\nv 200 0 -100\nv 0 0 -100\nf 1 2 3 4\n\
             o wall\nusemtl grey\nv 0 0 -100\nv 100 0 -100\nv 100 100 -100\nv 0 100 -100\nf 5 6 7 8\n\
             o lamp{LAMP_OBJ}"
        ),
    );
    let config = write(
        dir.path(),
        "scene.toml",
        "geometry = [\"o.obj\"]\nunits_per_metre = 100\n\n\
         [materials.grey]\npatches = 7\nmin_element_size = 5\n\n\
         [objects.floor]\npatch_size = \"0.5m\"\nmin_element_size = \"20mm\"\n\n\
         [objects.lamp]\npatch_size = 0.4\n",
    );
    let loaded = load(&config).unwrap();
    let scene = &loaded.scene;
    // Polygons in file order: floor, wall, lamp.
    let (floor, wall, lamp) = (&scene.polygons[0], &scene.polygons[1], &scene.polygons[2]);
    // The floor's own patch_size clears the material's count; the wall keeps it.
    assert_eq!(floor.patches, PATCHES_UNSET);
    assert_eq!(floor.sizes.patch_size, Some(Length::Metres(0.5)));
    // "20mm" is 20 × 1e-3 m, equal to 0.02 up to one rounding.
    let Some(Length::Metres(m)) = floor.sizes.min_element_size else {
        panic!("{:?}", floor.sizes)
    };
    assert!((m - 0.02).abs() < 1e-17, "{m}");
    assert_eq!(wall.patches, 7);
    assert_eq!(wall.sizes.min_element_size, Some(Length::SceneUnits(5.0)));
    assert_eq!(lamp.sizes.patch_size, Some(Length::SceneUnits(0.4)));

    let sizing = Sizing {
        units_per_metre: scene.units_per_metre,
        ..Sizing::flat(1)
    };
    let mesh = Mesh::with_sizing(scene, scene.recentre_offset, &sizing).unwrap();
    let n: Vec<u32> = mesh.surfaces.iter().map(|s| s.patches_per_side).collect();
    // Floor ⌈200 / 50⌉ = 4; wall 7 (the material's count); lamp ⌈1 / 0.4⌉ = 3.
    assert_eq!(n, vec![4, 7, 3]);
    let floors: Vec<Option<f64>> = mesh.surfaces.iter().map(|s| s.min_element_size).collect();
    assert!((floors[0].unwrap() - 2.0).abs() < 1e-12, "{floors:?}");
    assert_eq!(floors[1..], [Some(5.0), None]);

    // Metres follow the final scale: with the command line's 1000 units per
    // metre "0.5m" is 500 units, so the floor is one patch.
    let flagged = load_scene(
        &config,
        &ImportOptions {
            units_per_metre: Some(1000.0),
            ..Default::default()
        },
    )
    .unwrap()
    .scene;
    let sizing = Sizing {
        units_per_metre: flagged.units_per_metre,
        ..Sizing::flat(1)
    };
    let mesh = Mesh::with_sizing(&flagged, flagged.recentre_offset, &sizing).unwrap();
    assert_eq!(mesh.surfaces[0].patches_per_side, 1);
    assert!((mesh.surfaces[0].min_element_size.unwrap() - 20.0).abs() < 1e-12);
}

#[test]
fn every_malformed_toml_line_names_file_line_and_what() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "g.mtl", LAMP_MTL);
    write(
        dir.path(),
        "g.obj",
        &format!("mtllib g.mtl\no lamp{LAMP_OBJ}"),
    );
    write(
        dir.path(),
        "v.display",
        "x\neye 0 0 5 lookat 0 0 0\nup 0 1 0\nfovx 40 fovy 40\nnear 1 far 10\nxres 64 yres 64\ndiameter 1\nambient 0\nthreshold 1\n",
    );
    let ok = "geometry = [\"g.obj\"]\n";
    let cases: Vec<(String, usize, &str)> = vec![
        (format!("{ok}colour = 3\n"), 2, "unknown field `colour`"),
        (format!("{ok}units_per_metre = \"mm\"\n"), 2, "invalid type"),
        (
            format!("{ok}units_per_metre = -1.0\n"),
            2,
            "units_per_metre must be finite and > 0",
        ),
        (format!("{ok}up = \"x\"\n"), 2, "unknown variant `x`"),
        (
            format!("{ok}mode = \"glossy\"\n"),
            2,
            "unknown variant `glossy`",
        ),
        (
            format!("{ok}\n[solver]\nsamples = 4\nsample = 3\n"),
            5,
            "unknown field `sample`",
        ),
        (
            format!("{ok}\n[solver]\nsamples = -4\n"),
            4,
            "invalid value",
        ),
        (
            format!("{ok}\n[materials.lamp]\nkd = [1, 2]\n"),
            4,
            "invalid length 2",
        ),
        (
            format!("{ok}\n[materials.lamp]\nkd = -0.5\n"),
            4,
            "kd must be finite and non-negative",
        ),
        (
            format!("{ok}\n[materials.lamp]\nalpha = 0\n"),
            3,
            "alpha must be finite and > 0",
        ),
        (
            format!("{ok}\n[materials.lamp]\nshininess = 3\n"),
            4,
            "unknown field `shininess`",
        ),
        (
            format!("{ok}\n[materials.lamb]\nkd = 0.5\n"),
            3,
            "no material named `lamb`",
        ),
        (
            format!("{ok}\n[objects.lump]\npatches = 2\n"),
            3,
            "no object or group named `lump`",
        ),
        (
            format!("{ok}\n[objects.lamp]\npatches = 0\n"),
            3,
            "patches = 0 is out of range",
        ),
        (
            format!("{ok}\n[objects.lamp]\npatches = 2\npatch_size = \"0.25ft\"\n"),
            5,
            "patch_size = \"0.25ft\" is not a length > 0",
        ),
        (
            format!("{ok}\n[objects.lamp]\nmin_element_size = -3\n"),
            4,
            "min_element_size = -3 is not a length > 0",
        ),
        (
            format!("{ok}\n[materials.lamp]\n\npatch_size = \"m\"\n"),
            5,
            "patch_size = \"m\" is not a length",
        ),
        (
            format!("{ok}\n[objects.lamp]\npatch_size = true\n"),
            4,
            "a length: a number in scene units or a string",
        ),
        (
            format!("{ok}\n[solver]\npatch_size = 2.0\n"),
            3,
            "setting `patch_size` = 2 is out of range",
        ),
        (
            format!("{ok}mode = \"diffuse\"\n[solver]\nmode = \"directional\"\n"),
            2,
            "conflicts with `[solver] mode",
        ),
        (
            format!("{ok}\n[camera]\nfov_y_deg = 30\n"),
            3,
            "needs `eye` and `target`",
        ),
        (
            format!("{ok}\n[camera]\neye = [0, 0, 1]\ntarget = [0, 0, 1]\n"),
            3,
            "same point",
        ),
        (
            format!("{ok}\n[camera]\neye = [0, 0, 1]\ntarget = [0, 0, 0]\nfov_y_deg = 200\n"),
            3,
            "out of range",
        ),
        // Refused before the (missing) geometry is read: the settings come first.
        (
            "geometry = [\"missing.obj\"]\n\n[solver]\nmax_sh_order = 65\n".to_owned(),
            3,
            "setting `max_sh_order` = 65 is out of range: 0 to 64",
        ),
        ("geometry = []\n".to_owned(), 1, "names no file"),
        (
            "geometry = [\"missing.obj\"]\n".to_owned(),
            1,
            "geometry `missing.obj`: cannot read",
        ),
        (
            "geometry = [\"other.toml\"]\n".to_owned(),
            1,
            "cannot include another",
        ),
        (
            format!("{ok}display = \"nope.display\"\n"),
            2,
            "display `nope.display`: cannot read",
        ),
        ("geometry = [\"g.obj\"\n".to_owned(), 2, "expected `]`"),
        (
            "units_per_metre = 1\n".to_owned(),
            1,
            "missing field `geometry`",
        ),
    ];
    for (text, line, fragment) in cases {
        let config = write(dir.path(), "s.toml", &text);
        let message = load(&config).unwrap_err().to_string();
        let prefix = format!("{}:{line}", config.display());
        assert!(
            message.starts_with(&prefix),
            "{message:?} should start with {prefix:?} for\n{text}"
        );
        assert!(
            message.contains(fragment),
            "{message:?} should say {fragment:?}"
        );
    }

    // The display file a config names gives the camera and its own settings.
    let config = write(
        dir.path(),
        "s.toml",
        &format!("{ok}display = \"v.display\"\n[camera]\nwidth = 32\n"),
    );
    let loaded = load(&config).unwrap();
    let camera = loaded.scene.camera.unwrap();
    assert_eq!(
        (camera.eye, camera.width, camera.height),
        ([0.0, 0.0, 5.0], 32, 64)
    );
    let display = loaded.display.unwrap();
    assert_eq!(display.settings.threshold, Some(0.001));
    assert_eq!(display.settings.ambient, Some(false));
}

#[test]
fn strict_mode_from_the_config_and_files_that_are_not_scenes() {
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        "k.mtl",
        &format!("newmtl hot\nKd 0.9\nKs 0.5\n{LAMP_MTL}"),
    );
    write(
        dir.path(),
        "k.obj",
        &format!("mtllib k.mtl\nusemtl hot\nv 0 0 0\nv 1 0 0\nv 1 0 -1\nf 1 2 3\n{LAMP_OBJ}"),
    );
    let config = write(
        dir.path(),
        "k.toml",
        "geometry = [\"k.obj\"]\n[solver]\nstrict = true\n",
    );
    assert!(matches!(load(&config), Err(SceneError::Strict { .. })));

    let mtl = load(&dir.path().join("k.mtl")).unwrap_err().to_string();
    assert!(mtl.contains("materials only"), "{mtl}");
    let display = write(dir.path(), "a.display", "x\n");
    assert!(load(&display)
        .unwrap_err()
        .to_string()
        .contains("display parameter file"));
    let bad_units = load_scene(
        &config,
        &ImportOptions {
            units_per_metre: Some(0.0),
            ..Default::default()
        },
    );
    assert!(bad_units
        .unwrap_err()
        .to_string()
        .contains("units_per_metre"));
}

#[test]
fn mtl_statements_not_modelled_reach_the_scene_warnings_for_used_materials_only() {
    let dir = tempfile::tempdir().unwrap();
    let obj = write(
        dir.path(),
        "room.obj",
        &format!(
            "mtllib room.mtl\nusemtl wall\nv 0 0 0\nv 1 0 0\nv 1 0 -1\nv 0 0 -1\n\
             f 1 2 3 4\n{LAMP_OBJ}"
        ),
    );
    write(
        dir.path(),
        "room.mtl",
        &format!(
            "newmtl wall\nKd 0.1\nmap_Kd wall.png\nmap_Kd wall2.png\nillum 2\n\
             newmtl unused\nmap_Kd other.png\n{LAMP_MTL}map_Ke screen.png\n"
        ),
    );
    let scene = load(&obj).unwrap().scene;
    let texts: Vec<String> = scene.warnings.iter().map(|w| w.to_string()).collect();
    let mtl = dir.path().join("room.mtl");
    // The wall's texture (the later `map_Kd`, line 4) is modelled but its face
    // has no `vt`: one warning naming the file, flat Kd used; the lamp's
    // `map_Ke` (line 12: after the 7 lines above and LAMP_MTL's blank line,
    // newmtl, Kd and Ke) one; the unused material none.
    assert_eq!(texts.len(), 2, "{texts:?}");
    let wall_at = format!("{}:4 (material wall): map_Kd texture ", mtl.display());
    assert!(
        texts
            .iter()
            .any(|t| t.starts_with(&wall_at) && t.contains("wall2.png: no face")),
        "{texts:?}"
    );
    // `map_Ke` is modelled too: its face has no `vt`, so the flat Ke.
    let lamp_at = format!("{}:12 (material lamp): map_Ke texture ", mtl.display());
    assert!(
        texts
            .iter()
            .any(|t| t.starts_with(&lamp_at) && t.contains("screen.png: no face")),
        "{texts:?}"
    );
    match load_strict(&obj) {
        Err(SceneError::Strict { warning, others }) => {
            assert!(warning.message.contains("texture coordinates"), "{warning}");
            assert_eq!(others, 1);
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn diffuse_equivalent_kd_adds_ks_per_channel_and_caps_at_one() {
    let mut m = Material {
        name: "gold".into(),
        kd: DVec3::ZERO,
        ks: DVec3::ZERO,
        alpha: 0.2,
        emission: DVec3::ZERO,
        diffuse_texture: None,
        emission_texture: None,
        folded_texture: None,
    };
    // A gold metal: Kd = 0, Ks = the base colour. Exact in binary, so the
    // sums compare exactly.
    m.ks = DVec3::new(1.0, 0.75, 0.25);
    assert_eq!(m.diffuse_equivalent_kd(), DVec3::new(1.0, 0.75, 0.25));
    // Each channel on its own: Kd + Ks where below 1, 1 where above.
    m.kd = DVec3::new(0.5, 0.125, 0.0);
    assert_eq!(m.diffuse_equivalent_kd(), DVec3::new(1.0, 0.875, 0.25));
    m.kd = DVec3::new(0.75, 0.5, 0.5);
    assert_eq!(m.diffuse_equivalent_kd(), DVec3::new(1.0, 1.0, 0.75));
    // A diffuse material is unchanged.
    m.ks = DVec3::ZERO;
    assert_eq!(m.diffuse_equivalent_kd(), m.kd);
}
