//! Hostile inputs that must be refused at import, fast and with an error naming
//! the file, the line and the value, rather than stall or fail after a solve.

use super::*;
use std::fmt::Write as _;
use std::fs;

/// An OBJ whose face 1 (on the returned line) is a unit disc sampled at `n`
/// vertices, convex and counter-clockwise seen from +y, under a square lamp.
fn disc_obj(dir: &Path, n: usize) -> (PathBuf, usize) {
    fs::write(
        dir.join("disc.mtl"),
        "newmtl floor\nKd 0.5 0.5 0.5\nnewmtl lamp\nKe 10 10 10\n",
    )
    .unwrap();
    let mut text = String::from("mtllib disc.mtl\nusemtl floor\n");
    for k in 0..n {
        let t = std::f64::consts::TAU * k as f64 / n as f64;
        writeln!(text, "v {} 0 {}", t.cos(), -t.sin()).unwrap();
    }
    let face_line = 2 + n + 1;
    text.push('f');
    for k in 1..=n {
        write!(text, " {k}").unwrap();
    }
    text.push_str(
        "\nusemtl lamp\nv -0.2 1 -0.2\nv -0.2 1 0.2\nv 0.2 1 0.2\nv 0.2 1 -0.2\nf -4 -3 -2 -1\n",
    );
    let path = dir.join("disc.obj");
    fs::write(&path, text).unwrap();
    (path, face_line)
}

#[test]
fn an_obj_face_over_the_vertex_cap_is_refused_naming_file_line_and_count() {
    let dir = tempfile::tempdir().unwrap();
    let n = MAX_POLYGON_VERTICES + 1;
    let (path, line) = disc_obj(dir.path(), n);
    let e = load_scene(&path, &ImportOptions::default()).unwrap_err();
    assert_eq!(
        e.source_ref(),
        Some(&SourceRef {
            file: path.clone(),
            line: Some(line),
            item: "face 1".to_owned(),
        })
    );
    let text = e.to_string();
    assert!(
        text.contains(&format!(
            "{n} vertices, more than the {MAX_POLYGON_VERTICES} one polygon may have"
        )),
        "{text}"
    );
}

#[test]
fn an_obj_face_at_the_vertex_cap_imports_whole() {
    let dir = tempfile::tempdir().unwrap();
    let (path, _) = disc_obj(dir.path(), MAX_POLYGON_VERTICES);
    let started = std::time::Instant::now();
    let scene = load_scene(&path, &ImportOptions::default()).unwrap().scene;
    // The dev profile imports it in well under a second; a quadratic step
    // gone cubic, or the cap raised past what the checks afford, shows here.
    assert!(started.elapsed().as_secs_f64() < 20.0);
    let disc = scene
        .polygons
        .iter()
        .max_by_key(|p| p.vertices.len())
        .unwrap();
    assert_eq!(disc.vertices.len(), MAX_POLYGON_VERTICES);
    // The inscribed regular n-gon's area, (n/2)·sin(2π/n), to f64 rounding.
    let n = MAX_POLYGON_VERTICES as f64;
    let exact = 0.5 * n * (std::f64::consts::TAU / n).sin();
    assert!((disc.area() - exact).abs() < 1e-12, "{}", disc.area());
}

#[test]
fn a_legacy_polygon_over_the_vertex_cap_is_refused_before_its_indices_are_read() {
    let dir = tempfile::tempdir().unwrap();
    let n = MAX_POLYGON_VERTICES + 1;
    let mut text =
        String::from("big polygon\nccw\npoints 3 patches 1 attributes 1\n0 0 0\n1 0 0\n0 0 -1\n");
    write!(text, "{n}").unwrap();
    for k in 0..n {
        write!(text, " {}", k % 3 + 1).unwrap();
    }
    text.push_str(" attribute 1\ncolor 0.5 0.5 0.5 emit 1 1 1\n");
    let path = dir.path().join("big.geom");
    fs::write(&path, text).unwrap();
    let e = load_scene(&path, &ImportOptions::default()).unwrap_err();
    let at = e.source_ref().unwrap();
    assert_eq!((at.line, at.item.as_str()), (Some(7), "polygon 1"));
    assert!(
        e.to_string().contains(&format!(
            "{n} vertices, more than the {MAX_POLYGON_VERTICES}"
        )),
        "{e}"
    );
}

/// The error a scene gives, with the location it names.
fn refusal(path: &Path) -> (SourceRef, String) {
    let e = load_scene(path, &ImportOptions::default()).unwrap_err();
    (e.source_ref().cloned().unwrap(), e.to_string())
}

const ABOVE_F32: &str = "exceeds 1e30 W·sr⁻¹·m⁻², the largest emitted radiance accepted";

#[test]
fn an_mtl_emission_beyond_f32_is_refused_at_its_ke_line() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(
        dir.path().join("l.mtl"),
        "newmtl floor\nKd 0.5 0.5 0.5\n\nnewmtl lamp\nKd 0 0 0\nKe 1 1e39 1\n",
    )
    .unwrap();
    let obj = dir.path().join("l.obj");
    fs::write(
        &obj,
        "mtllib l.mtl\nusemtl lamp\nv 0 0 0\nv 1 0 0\nv 1 0 -1\nf 1 2 3\n",
    )
    .unwrap();
    let (at, text) = refusal(&obj);
    let mtl = dir.path().join("l.mtl");
    assert_eq!((&at.file, at.line), (&mtl, Some(6)));
    assert_eq!(at.item, "material lamp");
    assert!(
        text.ends_with(&format!(
            "Ke (emitted radiance) (1e0, 1e39, 1e0) {ABOVE_F32} (the solution's radiance is \
             f32, at most 3.4e38, and light reflected between surfaces adds to the emission)"
        )),
        "{text}"
    );
    // Just under the bound is accepted: a bright but representable source.
    fs::write(
        &mtl,
        "newmtl floor\nKd 0.5 0.5 0.5\n\nnewmtl lamp\nKd 0 0 0\nKe 1e30 1e30 1e30\n",
    )
    .unwrap();
    let scene = load_scene(&obj, &ImportOptions::default()).unwrap().scene;
    assert_eq!(scene.materials[0].emission, DVec3::splat(MAX_EMISSION));
}

#[test]
fn a_legacy_emit_beyond_the_bound_is_refused_at_its_attribute_line() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("e.geom");
    fs::write(
        &path,
        "bright\nccw\npoints 3 patches 1 attributes 1\n0 0 0\n1 0 0\n0 0 -1\n\
         3 1 2 3 attribute 1\ncolor 0.5 0.5 0.5 emit 2e30 0 0\n",
    )
    .unwrap();
    let (at, text) = refusal(&path);
    assert_eq!((at.line, at.item.as_str()), (Some(8), "attribute 1"));
    assert!(
        text.contains(&format!(
            "emit (emitted radiance) (2e30, 0e0, 0e0) {ABOVE_F32}"
        )),
        "{text}"
    );
}

#[test]
fn a_toml_emission_override_is_refused_at_its_own_line() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(
        dir.path().join("t.mtl"),
        "newmtl lamp\nKd 0.5 0.5 0.5\nKe 1 1 1\n",
    )
    .unwrap();
    fs::write(
        dir.path().join("t.obj"),
        "mtllib t.mtl\nusemtl lamp\nv 0 0 0\nv 1 0 0\nv 1 0 -1\nf 1 2 3\n",
    )
    .unwrap();
    let config = dir.path().join("t.toml");
    for (value, shown) in [
        ("1e39", format!("(1e39, 1e39, 1e39) {ABOVE_F32}")),
        ("inf", "must be finite, is (inf, inf, inf)".to_owned()),
        (
            "[1, nan, 1]",
            "must be finite, is (1e0, NaN, 1e0)".to_owned(),
        ),
    ] {
        fs::write(
            &config,
            format!("geometry = [\"t.obj\"]\n\n[materials.lamp]\nkd = 0.5\nemission = {value}\n"),
        )
        .unwrap();
        let (at, text) = refusal(&config);
        assert_eq!(
            (&at.file, at.line, at.item.as_str()),
            (&config, Some(5), "materials.lamp")
        );
        assert!(text.contains(&format!(": emission {shown}")), "{text}");
    }
}

/// A legacy file whose attribute 2 (line 9) names reflectance file 9.
const LEGACY_WITH_MATERIAL_FILE: &str = "glossy\nccw\npoints 3 patches 1 attributes 2\n\
     0 0 0\n1 0 0\n0 0 -1\n3 1 2 3 attribute 2\n\
     color 0.5 0.5 0.5 emit 1 1 1\ncolor 0.2 0.2 0.2 material 9\n";

#[test]
fn a_legacy_material_file_is_refused_unless_a_toml_override_replaces_it() {
    let dir = tempfile::tempdir().unwrap();
    let geom = dir.path().join("m.geom");
    fs::write(&geom, LEGACY_WITH_MATERIAL_FILE).unwrap();
    let (at, text) = refusal(&geom);
    assert_eq!(
        (&at.file, at.line, at.item.as_str()),
        (&geom, Some(9), "attribute 2")
    );
    assert!(
        text.contains(
            "`material 9` names reflectance file 9 (Remington 1992, appendix F), which is not read"
        ),
        "{text}"
    );
    // Unused, the attribute is no error: polygon 1 uses attribute 1 only.
    fs::write(
        &geom,
        LEGACY_WITH_MATERIAL_FILE.replace("attribute 2\n", "attribute 1\n"),
    )
    .unwrap();
    assert!(load_scene(&geom, &ImportOptions::default()).is_ok());
    // A TOML override of `material 9` gives what the file would have.
    fs::write(&geom, LEGACY_WITH_MATERIAL_FILE).unwrap();
    let config = dir.path().join("m.toml");
    fs::write(
        &config,
        "geometry = [\"m.geom\"]\n\n[materials.\"material 9\"]\nkd = 0.3\nks = 0.4\nalpha = 0.2\n\
         emission = 1\n",
    )
    .unwrap();
    let scene = load_scene(&config, &ImportOptions::default())
        .unwrap()
        .scene;
    let m = &scene.materials[0];
    assert_eq!(
        (m.name.as_str(), m.kd, m.ks, m.alpha),
        ("attribute 2", DVec3::splat(0.3), DVec3::splat(0.4), 0.2)
    );
}
