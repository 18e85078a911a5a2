//! A generated scene and its files: `NAME.obj` (triangles, `vn` where a
//! surface is smooth), `NAME.mtl` (Kd reflectance, Ke emitted radiance in
//! W·sr⁻¹·m⁻², linear RGB, one-sided toward the winding's front; Ks and Ns
//! for a material made glossy by [`crate::glossy`]) and `NAME.toml`, the
//! solver's scene config (solver/src/scene/config.rs), which states the units
//! (millimetres: `units_per_metre = 1000`), +y up, the mode (`directional`
//! when a material is glossy, else `diffuse`), a camera inside the scene and,
//! for the daylit families, a `[sun]` and a `[sky]`.

use crate::mesh::{length, Mesh, Vec3};
use anyhow::Context;
use solution::atomic::write_atomically;
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};

/// A material as the MTL file states it.
#[derive(Clone, Debug)]
pub struct Material {
    /// The MTL's `newmtl` name (a `String`: `--glossy` may name a new
    /// material after the object it splits off, [`crate::glossy`]).
    pub name: String,
    /// Diffuse reflectance, linear RGB, in [0, 1); with [`Material::glossy`],
    /// Kd + Ks ≤ 1 per channel.
    pub kd: [f64; 3],
    /// Emitted radiance, W·sr⁻¹·m⁻² (zero for a reflector).
    pub ke: [f64; 3],
    /// The glossy lobe (`Ks`, `Ns`); `None` writes `Ks 0 0 0`, as every
    /// family does unless `--glossy` names the material.
    pub glossy: Option<Glossy>,
}

impl Material {
    /// A diffuse reflector of reflectance `kd`, as every family's surfaces
    /// are unless `--glossy` names them.
    pub fn diffuse(name: &str, kd: [f64; 3]) -> Material {
        Material::emitter(name, kd, [0.0; 3])
    }

    /// A diffuse surface of reflectance `kd` that emits radiance `ke`.
    pub fn emitter(name: &str, kd: [f64; 3], ke: [f64; 3]) -> Material {
        Material {
            name: name.into(),
            kd,
            ke,
            glossy: None,
        }
    }
}

/// A material's glossy part as the MTL states it: the solver's
/// `--mode directional` reflects Ks into a lobe of RMS slope
/// α = √(2 / (Ns + 2)) (docs/guide.md, "Glossy surfaces").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Glossy {
    /// Glossy (specular) reflectance, linear RGB, in [0, 1].
    pub ks: [f64; 3],
    /// The Phong exponent: 0 is broad, hundreds are polished, thousands
    /// near-mirrors.
    pub ns: f64,
}

/// The initial camera written to the TOML config (scene coordinates, mm).
#[derive(Clone, Debug)]
pub struct Camera {
    pub eye: [f64; 3],
    pub target: [f64; 3],
    pub fov_y_deg: f64,
}

/// The `[sun]` table: a distant disc.
#[derive(Clone, Debug)]
pub struct Sun {
    /// Toward the sun, scene frame (any length; never zero).
    pub direction: Vec3,
    /// Irradiance on a plane facing the sun, W·m⁻² per channel.
    pub irradiance: [f64; 3],
    pub angular_diameter_deg: f64,
}

/// The `[sky]` table: a uniform sky, black below the horizon.
#[derive(Clone, Debug)]
pub struct Sky {
    /// W·sr⁻¹·m⁻² per channel: πL on an open horizontal plane.
    pub radiance: [f64; 3],
}

/// The lights the config states besides the MTL's emitters (none for the
/// families lit by emissive polygons, whose configs stay as they were).
#[derive(Clone, Debug, Default)]
pub struct Lights {
    pub sun: Option<Sun>,
    pub sky: Option<Sky>,
}

/// 100 klux of white sun: 100 000 / 683 W·m⁻² per channel (a photometric X
/// with colour c is c·X/683 in the solver's units, docs/lights.md).
pub const SUN_100_KLUX: [f64; 3] = [146.4, 146.4, 146.4];
/// A bluish uniform sky; its horizontal illuminance is π · 683 · L ≈ 7.5 klux
/// for the green channel, a bright overcast-to-clear day's diffuse light.
pub const SKY_RADIANCE: [f64; 3] = [3.0, 3.5, 4.5];

impl Lights {
    /// A 100 klux sun at `elevation_deg` above the horizon, its horizontal
    /// bearing along `heading` (x, z; need not be unit length), and the
    /// uniform [`SKY_RADIANCE`] sky.
    pub fn daylight(elevation_deg: f64, heading: [f64; 2]) -> Lights {
        let (sin_e, cos_e) = elevation_deg.to_radians().sin_cos();
        let h = length([heading[0], 0.0, heading[1]]);
        Lights {
            sun: Some(Sun {
                direction: [cos_e * heading[0] / h, sin_e, cos_e * heading[1] / h],
                irradiance: SUN_100_KLUX,
                angular_diameter_deg: 0.53,
            }),
            sky: Some(Sky {
                radiance: SKY_RADIANCE,
            }),
        }
    }
}

#[derive(Clone, Debug)]
pub struct Scene {
    /// One line saying what the scene is and which parameters made it.
    pub description: String,
    pub mesh: Mesh,
    pub materials: Vec<Material>,
    pub camera: Camera,
    pub lights: Lights,
}

impl Scene {
    /// Whether any material has a glossy part (the config then asks for
    /// `mode = "directional"`).
    pub fn is_glossy(&self) -> bool {
        self.materials.iter().any(|m| m.glossy.is_some())
    }
}

/// Where [`write_scene`] put the three files.
#[derive(Clone, Debug)]
pub struct ScenePaths {
    pub obj: PathBuf,
    pub mtl: PathBuf,
    pub toml: PathBuf,
}

/// Writes `dir/stem.{obj,mtl,toml}`, each atomically.
pub fn write_scene(scene: &Scene, dir: &Path, stem: &str) -> anyhow::Result<ScenePaths> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let paths = ScenePaths {
        obj: dir.join(format!("{stem}.obj")),
        mtl: dir.join(format!("{stem}.mtl")),
        toml: dir.join(format!("{stem}.toml")),
    };
    write_text(&paths.obj, &obj_text(scene, &format!("{stem}.mtl")))?;
    write_text(&paths.mtl, &mtl_text(scene))?;
    write_text(&paths.toml, &toml_text(scene, &format!("{stem}.obj")))?;
    Ok(paths)
}

fn write_text(path: &Path, text: &str) -> anyhow::Result<()> {
    write_atomically(path, |file| {
        let mut out = std::io::BufWriter::new(file);
        out.write_all(text.as_bytes())?;
        out.flush()
    })
    .with_context(|| format!("writing {}", path.display()))
}

/// The OBJ text. Positions with 4 decimals (0.1 µm in millimetres: far below
/// the smallest generated feature, about 0.5 mm), normals with 6.
pub fn obj_text(scene: &Scene, mtl_name: &str) -> String {
    let mesh = &scene.mesh;
    let mut s = String::with_capacity(48 * (mesh.positions.len() + mesh.triangle_count()));
    let _ = writeln!(s, "# {}", scene.description);
    let _ = writeln!(
        s,
        "# Written by tools/scenegen. Units: millimetres, right-handed, +y up.\n\
         # {} triangles. Faces are wound counter-clockwise seen from their lit side\n\
         # (into a room, out of a solid); vn are smooth normals on curved surfaces.",
        mesh.triangle_count()
    );
    let _ = writeln!(s, "mtllib {mtl_name}");
    for p in &mesh.positions {
        let _ = writeln!(s, "v {:.4} {:.4} {:.4}", p[0], p[1], p[2]);
    }
    for n in &mesh.normals {
        let _ = writeln!(s, "vn {:.6} {:.6} {:.6}", n[0], n[1], n[2]);
    }
    for object in &mesh.objects {
        let _ = writeln!(s, "o {0}\ng {0}\nusemtl {1}", object.name, object.material);
        for t in &object.triangles {
            s.push('f');
            for c in t {
                let _ = match c.normal {
                    Some(n) => write!(s, " {}//{}", c.position + 1, n + 1),
                    None => write!(s, " {}", c.position + 1),
                };
            }
            s.push('\n');
        }
    }
    s
}

pub fn mtl_text(scene: &Scene) -> String {
    let mut s = String::from(
        "# Kd: diffuse reflectance (linear RGB). Ke: emitted radiance, W*sr^-1*m^-2\n\
         # (linear RGB), one-sided toward the face's front.\n",
    );
    // Only a scene with a glossy material says so, so that the others' files
    // stay as they were.
    if scene.is_glossy() {
        s.push_str(
            "# Ks: glossy reflectance (linear RGB), Ns: its Phong exponent; solve with\n\
             # --mode directional (the config sets it) to see the reflections.\n",
        );
    }
    for m in &scene.materials {
        let _ = writeln!(
            s,
            "\nnewmtl {}\nKd {} {} {}",
            m.name, m.kd[0], m.kd[1], m.kd[2]
        );
        match &m.glossy {
            Some(g) => {
                let _ = writeln!(s, "Ks {} {} {}\nNs {}", g.ks[0], g.ks[1], g.ks[2], g.ns);
            }
            None => s.push_str("Ks 0 0 0\n"),
        }
        if m.ke.iter().any(|&e| e > 0.0) {
            let _ = writeln!(s, "Ke {} {} {}", m.ke[0], m.ke[1], m.ke[2]);
        }
    }
    s
}

pub fn toml_text(scene: &Scene, obj_name: &str) -> String {
    let c = &scene.camera;
    let mut s = format!(
        "# {}\n# Scene config for `solver solve` (solver/src/scene/config.rs), written by tools/scenegen.\n\
         # No patch or solver overrides: the preset decides the meshing, as for a user's model.\n\n\
         geometry = [\"{obj_name}\"]\n\
         units_per_metre = 1000      # the OBJ is in millimetres\n\
         up = \"y\"\n\
         {}\n\n\
         [camera]\n\
         eye = [{:.1}, {:.1}, {:.1}]\n\
         target = [{:.1}, {:.1}, {:.1}]\n\
         up = [0.0, 1.0, 0.0]\n\
         fov_y_deg = {:.4}\n\
         width = 512\n\
         height = 512\n",
        scene.description,
        mode_line(scene),
        c.eye[0],
        c.eye[1],
        c.eye[2],
        c.target[0],
        c.target[1],
        c.target[2],
        c.fov_y_deg
    );
    s.push_str(&lights_text(&scene.lights));
    s
}

/// The config's `mode`: diffuse unless a material is glossy, whose lobe only
/// the directional solve shows (a diffuse solve folds Ks into Kd).
fn mode_line(scene: &Scene) -> &'static str {
    if scene.is_glossy() {
        "mode = \"directional\"        # glossy materials (Ks, Ns in the MTL)"
    } else {
        "mode = \"diffuse\"            # every material has Ks = 0"
    }
}

/// The `[sun]` and `[sky]` tables (empty when the scene has neither, so the
/// emitter-lit families' configs are unchanged).
pub fn lights_text(lights: &Lights) -> String {
    let mut s = String::new();
    if let Some(sun) = &lights.sun {
        let d = sun.direction;
        let elevation = (d[1] / length(d)).asin().to_degrees();
        let _ = write!(
            s,
            "\n# Sun at {elevation:.1} deg elevation. Irradiance in W*m^-2 per channel on a plane\n\
             # facing it (100 klux of white sun is 100000/683 = 146.4).\n\
             [sun]\n\
             direction = {}\n\
             irradiance = {}\n\
             angular_diameter_deg = {}\n",
            toml_vector(d),
            toml_vector(sun.irradiance),
            toml_number(sun.angular_diameter_deg)
        );
    }
    if let Some(sky) = &lights.sky {
        let _ = write!(
            s,
            "\n# Uniform sky radiance in W*sr^-1*m^-2 per channel (pi*L on an open horizontal plane).\n\
             [sky]\n\
             kind = \"uniform\"\n\
             radiance = {}\n\
             below_horizon = \"black\"\n",
            toml_vector(sky.radiance)
        );
    }
    s
}

/// `[a, b, c]` with each number as [`toml_number`] writes it.
fn toml_vector(v: [f64; 3]) -> String {
    format!(
        "[{}, {}, {}]",
        toml_number(v[0]),
        toml_number(v[1]),
        toml_number(v[2])
    )
}

/// A TOML float (always with a decimal point, so that no parser reads an
/// integer) with at most 6 decimals and no trailing zeros: 146.4, 3.0, 0.286788.
pub fn toml_number(x: f64) -> String {
    let fixed = format!("{x:.6}");
    let trimmed = fixed.trim_end_matches('0');
    let text = if trimmed.ends_with('.') {
        format!("{trimmed}0")
    } else {
        trimmed.to_owned()
    };
    // −0.000000 would print as "-0.0".
    if text == "-0.0" {
        "0.0".to_owned()
    } else {
        text
    }
}
