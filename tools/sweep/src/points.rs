//! The sweep's scenes, fixed cameras, reference settings and points.
//!
//! Every point states its solver settings in full (written into the scene
//! config's `[solver]` table) rather than as changes to a preset, so that the
//! sweep measures the same thing after `config/presets.toml` is re-chosen from
//! it. The `presets` axis alone runs `--preset NAME` as shipped.

use anyhow::Context;
use std::path::Path;
use toml::Value;

/// A fixed camera for the image error (scene coordinates, as the runtime's
/// `screenshot --eye/--target/--up` take them).
#[derive(Clone, Debug)]
pub struct Camera {
    pub name: &'static str,
    pub eye: [f64; 3],
    pub target: [f64; 3],
    pub up: [f64; 3],
    pub fov_y_deg: f64,
    pub width: u32,
    pub height: u32,
    /// The path-traced truth's pixels are `truth_divisor` × `truth_divisor`
    /// blocks of the screenshot's (`solver compare` box-filters the screenshot
    /// to them): a truth at the screenshot's own size and 0.5% noise would take
    /// hours here.
    pub truth_divisor: u32,
    /// A committed truth for this camera (relative to the repository root), used
    /// when its size is the one asked for; otherwise one is rendered.
    pub truth_fixture: Option<&'static str>,
}

impl Camera {
    /// The view alone (what a screenshot depends on), for the points' cache
    /// key: a new truth re-compares the images but must not re-solve a point.
    pub fn view_key(&self) -> String {
        format!(
            "Camera {{ name: {:?}, eye: {:?}, target: {:?}, up: {:?}, fov_y_deg: {:?}, width: {:?}, height: {:?} }}",
            self.name, self.eye, self.target, self.up, self.fov_y_deg, self.width, self.height
        )
    }
}

pub struct SceneSpec {
    pub key: &'static str,
    pub title: &'static str,
    /// The scene config, relative to the repository root.
    pub config: &'static str,
    /// Settings every point starts from.
    pub base: Vec<(&'static str, Value)>,
    /// The converged reference's settings (over `base`).
    pub reference: Vec<(&'static str, Value)>,
    pub cameras: Vec<Camera>,
    /// The eye toward which per-vertex radiance is compared (scene coordinates).
    pub vertex_eye: [f64; 3],
}

/// One solve of the sweep.
#[derive(Clone, Debug)]
pub struct Point {
    pub axis: String,
    pub label: String,
    /// `[solver]` settings, applied in order (later wins).
    pub overrides: Vec<(String, Value)>,
    /// Extra command-line flags.
    pub flags: Vec<String>,
    /// Render the reference's own solution with the SH order capped here
    /// (`runtime screenshot --max-order`): plain truncation at display time, no
    /// solve of its own.
    pub render_max_order: Option<u32>,
}

impl Point {
    /// A file-name-safe identifier, unique within a scene.
    pub fn id(&self) -> String {
        let raw = format!("{}-{}", self.axis, self.label);
        raw.chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || c == '.' || c == '-' {
                    c
                } else {
                    '_'
                }
            })
            .collect()
    }

    /// The point's own settings (not the base's) as `key=value` text.
    pub fn settings_text(&self) -> String {
        let mut parts: Vec<String> = self
            .overrides
            .iter()
            .filter(|(k, _)| !k.starts_with("__"))
            .map(|(k, v)| format!("{k}={v}"))
            .collect();
        parts.extend(self.flags.iter().cloned());
        parts.join(" ")
    }
}

fn f(x: f64) -> Value {
    Value::Float(x)
}
fn i(x: i64) -> Value {
    Value::Integer(x)
}
fn s(x: &str) -> Value {
    Value::String(x.to_string())
}

/// The patch size (a fraction of the scene's diagonal, `--patch-size`) that
/// gives the Cornell box's 555 mm walls `n` patches a side: its diagonal is
/// 960.7 mm, so 0.6 / n (0.15 gives 4, 0.075 gives 8, as the presets say).
fn per_side(n: i64) -> Value {
    f(0.6 / n as f64)
}

/// The smallest element (`--min-element-size`, a fraction of the scene's
/// diagonal) whose square has `area` of a Cornell box wall's: 555 mm ×
/// √area over the 960.7 mm diagonal (2e-3 gives 0.026, the draft preset's).
fn floor_of(area: f64) -> Value {
    f(0.578 * area.sqrt())
}

/// The diffuse knobs as one tuple, for the ladder of combined settings:
/// (samples, edge, shadow, smallest element as an area fraction of a wall,
/// max depth, patches a wall side, threshold).
type Ladder = (i64, f64, f64, f64, i64, i64, f64);

fn ladder_overrides(l: Ladder) -> Vec<(String, Value)> {
    vec![
        ("samples".into(), i(l.0)),
        ("edge_threshold".into(), f(l.1)),
        ("shadow_threshold".into(), f(l.2)),
        ("min_element_size".into(), floor_of(l.3)),
        ("max_depth".into(), i(l.4)),
        ("patch_size".into(), per_side(l.5)),
        ("threshold".into(), f(l.6)),
    ]
}

pub fn scenes() -> Vec<SceneSpec> {
    vec![
        SceneSpec {
            key: "cornell",
            title: "Cornell box (diffuse)",
            config: "config/cornell_box.toml",
            // A draft-like starting point: each axis moves one knob from here.
            base: vec![
                ("samples", i(8)),
                ("threshold", f(0.01)),
                ("max_shots", i(100_000)),
                ("patch_size", per_side(4)),
                ("adaptive", Value::Boolean(true)),
                ("edge_threshold", f(0.5)),
                ("shadow_threshold", f(0.2)),
                ("min_element_size", floor_of(2e-4)),
                ("max_depth", i(5)),
                ("checkpoint_every", i(1_000_000)),
                ("seed", i(1)),
            ],
            // Converged: 64 rays per vertex and source, unshot power 0.1%, a mesh
            // refined to 1e-5 of a polygon where the radiance changes by 15%
            // (5% across shadow edges). Another seed than the points', so the
            // points' noise is not correlated with the reference's.
            reference: vec![
                ("samples", i(64)),
                ("threshold", f(0.001)),
                ("patch_size", per_side(6)),
                ("edge_threshold", f(0.15)),
                ("shadow_threshold", f(0.05)),
                ("min_element_size", floor_of(1e-5)),
                ("max_depth", i(8)),
                ("seed", i(7)),
            ],
            cameras: vec![
                Camera {
                    name: "front",
                    eye: [278.0, 273.0, -800.0],
                    target: [278.0, 273.0, 0.0],
                    up: [0.0, 1.0, 0.0],
                    fov_y_deg: 39.3077,
                    width: 256,
                    height: 256,
                    // 64²: the fixture of tests/cornell_truth.rs (the scene's
                    // own standard camera, noise 0.49%).
                    truth_divisor: 4,
                    truth_fixture: Some("tests/fixtures/cornell_truth_64.exr"),
                },
                // Inside the box, high in a front corner, looking down at the
                // blocks' shadows and the colour bleeding onto them.
                Camera {
                    name: "corner",
                    eye: [500.0, 480.0, 60.0],
                    target: [220.0, 60.0, 330.0],
                    up: [0.0, 1.0, 0.0],
                    fov_y_deg: 60.0,
                    width: 256,
                    height: 256,
                    truth_divisor: 8,
                    truth_fixture: None,
                },
            ],
            vertex_eye: [278.0, 273.0, -800.0],
        },
        SceneSpec {
            key: "glossy",
            title: "Glossy room (directional, spherical harmonics)",
            config: "config/glossy_floor.toml",
            base: vec![
                ("samples", i(4)),
                ("threshold", f(0.02)),
                ("max_shots", i(100_000)),
                ("patch_size", per_side(2)),
                ("adaptive", Value::Boolean(true)),
                ("edge_threshold", f(0.5)),
                ("shadow_threshold", f(0.2)),
                ("min_element_size", floor_of(2e-4)),
                ("max_depth", i(4)),
                ("checkpoint_every", i(1_000_000)),
                ("sh_error_target", f(1e-2)),
                ("max_sh_order", i(64)),
                ("seed", i(1)),
            ],
            // Converged enough to rank the points: 16 rays, unshot power 0.5%,
            // L ≈ 25 on the floor (SH target 1e-3). A finer mesh or a tighter
            // target costs minutes per solve here (the cost grows with L² per
            // glossy vertex and shot).
            reference: vec![
                ("samples", i(16)),
                ("threshold", f(0.005)),
                ("patch_size", per_side(4)),
                ("edge_threshold", f(0.4)),
                ("shadow_threshold", f(0.15)),
                ("min_element_size", floor_of(1e-4)),
                ("max_depth", i(5)),
                ("sh_error_target", f(1e-3)),
                ("seed", i(7)),
            ],
            cameras: vec![
                // The scene's own camera: the floor's highlight in view.
                Camera {
                    name: "front",
                    eye: [0.0, 0.6, 1.8],
                    target: [0.0, 0.0, 0.0],
                    up: [0.0, 1.0, 0.0],
                    fov_y_deg: 60.0,
                    width: 320,
                    height: 240,
                    // 40×30 at 0.5% noise: about 70,000 samples per pixel,
                    // 160 CPU s, so committed (the command and its figures
                    // are in tools/sweep/fixtures/README.md).
                    truth_divisor: 8,
                    truth_fixture: Some("tools/sweep/fixtures/glossy_front_40x30.exr"),
                },
                // From a side, lower: the highlight moves with the eye.
                Camera {
                    name: "side",
                    eye: [1.2, 0.4, 0.2],
                    target: [-0.6, 0.0, -1.2],
                    up: [0.0, 1.0, 0.0],
                    fov_y_deg: 60.0,
                    width: 320,
                    height: 240,
                    truth_divisor: 8,
                    truth_fixture: Some("tools/sweep/fixtures/glossy_side_40x30.exr"),
                },
            ],
            vertex_eye: [0.0, 0.6, 1.8],
        },
    ]
}

pub fn reference_point(scene: &SceneSpec) -> Point {
    Point {
        axis: "reference".into(),
        label: "converged".into(),
        overrides: scene
            .reference
            .iter()
            .map(|(k, v)| (k.to_string(), v.clone()))
            .collect(),
        flags: Vec::new(),
        render_max_order: None,
    }
}

fn point(axis: &str, label: impl Into<String>, overrides: Vec<(&str, Value)>) -> Point {
    Point {
        axis: axis.into(),
        label: label.into(),
        overrides: overrides
            .into_iter()
            .map(|(k, v)| (k.to_string(), v))
            .collect(),
        flags: Vec::new(),
        render_max_order: None,
    }
}

fn with_flags(mut p: Point, flags: &[&str]) -> Point {
    p.flags = flags.iter().map(|f| f.to_string()).collect();
    p
}

/// The flag that sets the global cube's D (`--method cube
/// --cube-resolution k`, D = 6k²), when the solver has one.
fn cube_flag(help: &str) -> Option<&'static str> {
    [
        "--cube-directions",
        "--directions",
        "--cube-resolution",
        "--cube-size",
    ]
    .into_iter()
    .find(|flag| help.contains(flag))
}

/// One point per value of the integer setting `key`, on the axis of that name.
fn int_axis(key: &str, values: &[i64]) -> Vec<Point> {
    values
        .iter()
        .map(|&n| point(key, format!("{key}={n}"), vec![(key, i(n))]))
        .collect()
}

/// The patch axis: `n` patches a Cornell box wall side each, set by
/// `--patch-size` (the label keeps the count, which the report compares).
fn patch_axis(values: &[i64]) -> Vec<Point> {
    values
        .iter()
        .map(|&n| {
            point(
                "patches",
                format!("patches={n}"),
                vec![("patch_size", per_side(n))],
            )
        })
        .collect()
}

/// The meshing axis: one point per (edge, shadow) threshold pair, with the
/// subdivision depth capped at `max_depth`.
fn mesh_axis(thresholds: &[(f64, f64)], max_depth: i64) -> Vec<Point> {
    thresholds
        .iter()
        .map(|&(edge, shadow)| {
            point(
                "mesh",
                format!("edge={edge} shadow={shadow}"),
                vec![
                    ("edge_threshold", f(edge)),
                    ("shadow_threshold", f(shadow)),
                    ("max_depth", i(max_depth)),
                ],
            )
        })
        .collect()
}

/// The sweep's points for `scene`: one knob at a time from the base, plus
/// combined settings (the ladder) and the shipped presets.
pub fn points(scene: &SceneSpec, quick: bool, has_cube: bool, help: &str) -> Vec<Point> {
    let mut out = match scene.key {
        "cornell" => cornell_points(quick),
        "glossy" => glossy_points(quick, has_cube, help),
        _ => Vec::new(),
    };
    // A quick run of these two scenes measures only their first axis (rays
    // per receiver, the SH target): no noise floor and no presets.
    if quick && matches!(scene.key, "cornell" | "glossy") {
        return out;
    }
    if !quick {
        // The reference's settings with the points' seed: how far two
        // converged solutions differ by noise alone, the floor under every
        // error in the tables.
        let mut floor = reference_point(scene);
        floor.axis = "floor".into();
        floor.label = "reference settings, seed 1".into();
        floor.overrides.push(("seed".into(), i(1)));
        out.push(floor);
    }
    for preset in ["draft", "medium", "final"] {
        if (quick && preset != "draft") || (scene.key == "glossy" && preset == "final") {
            // final asks for L ≈ 60 (SH target 1e-4) on the glossy floor's
            // 8×8-patch mesh: past the sweep's budget on this machine.
            continue;
        }
        let mut p = point("presets", format!("--preset {preset}"), vec![]);
        p.flags = vec!["--preset".into(), preset.into()];
        p.overrides
            .push(("__preset_only".into(), Value::Boolean(true)));
        out.push(p);
    }
    out
}

/// The Cornell box's one-knob axes, then its ladder and combinations; only
/// the samples axis when `quick`.
fn cornell_points(quick: bool) -> Vec<Point> {
    let mut out = Vec::new();
    let samples: &[i64] = if quick {
        &[2, 8, 32]
    } else {
        &[1, 2, 4, 8, 16, 32, 64]
    };
    out.extend(int_axis("samples", samples));
    if quick {
        return out;
    }
    out.extend(mesh_axis(
        &[(1.0, 0.5), (0.5, 0.2), (0.3, 0.1), (0.15, 0.05)],
        8,
    ));
    // The smallest element, with the depth cap lifted so that it binds
    // and the meshing thresholds tight enough to want small elements.
    for a in [2e-3, 5e-4, 1e-4, 2e-5] {
        out.push(point(
            "min_area",
            format!("min_size~{a:e} of a wall"),
            vec![
                ("min_element_size", floor_of(a)),
                ("max_depth", i(10)),
                ("edge_threshold", f(0.3)),
                ("shadow_threshold", f(0.1)),
            ],
        ));
    }
    out.extend(patch_axis(&[2, 4, 8]));
    for t in [0.05, 0.01, 0.002] {
        out.push(point(
            "threshold",
            format!("threshold={t}"),
            vec![("threshold", f(t))],
        ));
    }
    for m in ["analytic", "wallace", "hemicube"] {
        out.push(point("form_factors", m, vec![("form_factors", s(m))]));
    }
    for r in [16, 32, 64, 128, 256] {
        out.push(point(
            "hemicube",
            format!("hemicube R={r}"),
            vec![
                ("form_factors", s("hemicube")),
                ("hemicube_resolution", i(r)),
            ],
        ));
    }
    // The radiosity lecture notes' full-matrix gather: no adaptive meshing, so the patches are
    // the mesh.
    for (n, r) in [(4, 64), (8, 128), (12, 128)] {
        out.push(with_flags(
            point(
                "gauss_seidel",
                format!("GS patches={n} R={r}"),
                vec![("patch_size", per_side(n)), ("hemicube_resolution", i(r))],
            ),
            &["--method", "gauss-seidel"],
        ));
    }
    out.extend(cornell_ladder());
    out
}

/// Combined settings on the Cornell box: the ladder, from coarse to fine, and
/// the combinations the one-knob axes suggested.
fn cornell_ladder() -> Vec<Point> {
    let mut out = Vec::new();
    let ladder: [(&str, Ladder); 6] = [
        ("L0", (2, 1.0, 0.5, 1e-3, 3, 2, 0.05)),
        ("L1", (4, 0.5, 0.2, 2e-4, 4, 2, 0.02)),
        ("L2", (8, 0.4, 0.15, 1e-4, 5, 3, 0.01)),
        ("L3", (16, 0.3, 0.1, 5e-5, 6, 4, 0.005)),
        ("L4", (16, 0.2, 0.07, 2e-5, 7, 4, 0.003)),
        ("L5", (32, 0.2, 0.07, 2e-5, 7, 4, 0.002)),
    ];
    // Combinations suggested by the one-knob axes: tight meshing
    // thresholds with a *coarse* smallest element (min_area 2e-3 was
    // the cheapest way down in image error), finer patches, and few
    // rays (more rays lower the vertex error but hardly the image's).
    let combos: [(&str, Ladder); 7] = [
        ("C1", (2, 0.5, 0.2, 2e-3, 10, 4, 0.02)),
        ("C2", (4, 0.3, 0.1, 2e-3, 10, 4, 0.01)),
        ("C3", (4, 0.5, 0.2, 2e-3, 10, 8, 0.01)),
        ("C4", (8, 0.3, 0.1, 2e-3, 10, 8, 0.005)),
        ("C5", (8, 0.15, 0.05, 5e-4, 10, 8, 0.005)),
        ("C6", (16, 0.15, 0.05, 1e-4, 10, 8, 0.002)),
        ("C7", (16, 0.1, 0.03, 1e-4, 10, 12, 0.002)),
    ];
    let named = ladder
        .iter()
        .map(|&(n, l)| ("ladder", n, l))
        .chain(combos.iter().map(|&(n, l)| ("combo", n, l)));
    for (axis, name, l) in named {
        out.push(Point {
            axis: axis.into(),
            label: format!(
                "{name}: n={} e={} s={} a={:e} d={} p={} t={}",
                l.0, l.1, l.2, l.3, l.4, l.5, l.6
            ),
            overrides: ladder_overrides(l),
            flags: Vec::new(),
            render_max_order: None,
        });
    }
    out
}

/// The glossy room's axes: the SH target, the order cap, truncation, rays,
/// patches, meshing and (when the solver has it) the global cube; only the SH
/// target when `quick`.
fn glossy_points(quick: bool, has_cube: bool, help: &str) -> Vec<Point> {
    let mut out = Vec::new();
    let targets: &[f64] = if quick {
        &[1e-1, 1e-2]
    } else {
        &[1e-1, 3e-2, 1e-2, 3e-3]
    };
    for &t in targets {
        out.push(point(
            "sh_target",
            format!("sh_error_target={t:e}"),
            vec![("sh_error_target", f(t))],
        ));
    }
    if quick {
        return out;
    }
    // The order cap at a target that would ask for more (α = 0.1 needs
    // L ≈ 25 at 1e-3).
    for l in [2, 4, 8, 16] {
        out.push(point(
            "sh_order",
            format!("max_sh_order={l}"),
            vec![("sh_error_target", f(1e-3)), ("max_sh_order", i(l))],
        ));
    }
    // The same orders as plain truncation of the reference (windowed at
    // its own L ≈ 25) when it is displayed: what `runtime --max-order`
    // costs, against the solver's cap above (lobe windowed at L).
    for l in [2, 4, 8, 16] {
        let mut p = point(
            "truncation",
            format!("reference at --max-order {l}"),
            vec![],
        );
        p.render_max_order = Some(l);
        out.push(p);
    }
    out.extend(int_axis("samples", &[1, 4, 16]));
    out.extend(patch_axis(&[1, 2, 4]));
    out.extend(mesh_axis(&[(1.0, 0.5), (0.3, 0.1)], 6));
    if has_cube {
        match cube_flag(help) {
            Some(flag) => out.extend(cube_points(flag)),
            None => println!(
                "note: --method cube is listed but no flag for D was recognised; cube points skipped"
            ),
        }
    }
    out
}

/// The global cube at each of its sizes on a fixed mesh, and an SH row on the
/// same mesh.
fn cube_points(flag: &str) -> Vec<Point> {
    let mut out = Vec::new();
    // The cube is gathered on the fixed patch mesh (no
    // adaptive meshing), so it gets a finer one: 16×16
    // patches per polygon. The SH row beside it solves the
    // same fixed mesh (adaptive off, L ≈ 25) for a
    // like-for-like comparison of the representations.
    let fixed = || {
        vec![
            ("patch_size", per_side(CUBE_PATCHES)),
            ("adaptive", Value::Boolean(false)),
        ]
    };
    for d in cube_values(flag) {
        let label = if flag == "--cube-resolution" {
            // Immel, Cohen and Greenberg's (1986) global cube: D = 6k² directions.
            format!("cube k={d} (D={}) patches={CUBE_PATCHES}", 6 * d * d)
        } else {
            format!("cube {flag} {d} patches={CUBE_PATCHES}")
        };
        out.push(with_flags(
            point("cube", label, fixed()),
            &["--method", "cube", flag, &d.to_string()],
        ));
    }
    let mut sh = fixed();
    sh.push(("sh_error_target", f(1e-3)));
    out.push(point(
        "cube",
        format!("SH target 1e-3, fixed mesh patches={CUBE_PATCHES}"),
        sh,
    ));
    out
}

/// Patches per polygon of the fixed-mesh (global cube) comparison.
const CUBE_PATCHES: i64 = 16;

/// D values for the cube flag: per-face resolutions for a resolution-like
/// flag, direction counts otherwise.
fn cube_values(flag: &str) -> Vec<u32> {
    if flag.contains("resolution") || flag.contains("size") {
        vec![2, 4, 8, 16]
    } else {
        vec![24, 96, 384, 1536]
    }
}

/// The scene config for `point`: the scene's own config with absolute
/// geometry paths and a `[solver]` table of the base settings, then the
/// reference's or the point's. A `presets` point keeps the scene's own
/// `[solver]` table so that the preset decides.
pub fn scene_config(scene: &SceneSpec, point: &Point) -> anyhow::Result<String> {
    let path = Path::new(scene.config);
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let mut table: toml::Table =
        toml::from_str(&text).with_context(|| format!("parsing {}", path.display()))?;
    let dir = std::fs::canonicalize(path.parent().unwrap_or(Path::new(".")))
        .with_context(|| format!("resolving {}", path.display()))?;
    let absolute = |v: &Value| match v {
        Value::String(p) => Value::String(dir.join(p).to_string_lossy().into_owned()),
        other => other.clone(),
    };
    if let Some(Value::Array(files)) = table.get("geometry") {
        let files: Vec<Value> = files.iter().map(absolute).collect();
        table.insert("geometry".into(), Value::Array(files));
    }
    if let Some(display) = table.get("display").map(absolute) {
        table.insert("display".into(), display);
    }
    let preset_only = point.overrides.iter().any(|(k, _)| k == "__preset_only");
    if !preset_only {
        let mut solver = toml::Table::new();
        for (k, v) in &scene.base {
            solver.insert(k.to_string(), v.clone());
        }
        for (k, v) in &point.overrides {
            solver.insert(k.clone(), v.clone());
        }
        table.insert("solver".into(), Value::Table(solver));
    }
    toml::to_string(&table).context("writing the scene config")
}

#[cfg(test)]
mod tests {
    use super::scenes;
    use std::path::Path;

    /// A camera's committed truth is used only when its size is the camera's
    /// screenshot divided by its divisor; a missing or mis-sized fixture would
    /// silently cost a render of many minutes in every fresh work folder, so
    /// each one named must exist at exactly that size.
    #[test]
    fn committed_truths_exist_at_the_cameras_truth_size() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let mut checked = 0;
        for scene in scenes() {
            for camera in scene.cameras.iter() {
                let Some(fixture) = camera.truth_fixture else {
                    continue;
                };
                let image = sweep::image::read_exr(&root.join(fixture))
                    .unwrap_or_else(|e| panic!("{}/{}: {e:#}", scene.key, camera.name));
                let k = camera.truth_divisor;
                assert_eq!(
                    (image.width as u32 * k, image.height as u32 * k),
                    (camera.width, camera.height),
                    "{fixture}"
                );
                checked += 1;
            }
        }
        // The Cornell front camera's and both glossy cameras' truths.
        assert_eq!(checked, 3);
    }
}
