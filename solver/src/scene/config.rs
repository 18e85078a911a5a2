//! The TOML scene config: which geometry files make the scene, and what to
//! change about them.
//!
//! ```toml
//! geometry = ["cornell_box.obj"]      # OBJ, glTF or legacy files, relative to this file
//! units_per_metre = 1000              # scene units per metre (default 1)
//! up = "y"                            # viewer's up axis: y, -y, z, -z (Remington 1992, appendix C)
//! mode = "diffuse"                    # or "directional" (glossy SH)
//! display = "cornell_box.display"     # optional Remington 1992, appendix A display file
//!
//! [materials.white]                   # by material name (legacy: "attribute K" or "material N")
//! kd = [0.725, 0.71, 0.68]            # a number or [r, g, b]
//! ks = 0.0
//! alpha = 0.1                         # RMS slope (Remington 1992, eq. 4.1); overrides MTL Ns
//! emission = [0, 0, 0]                # emitted radiance, W·sr⁻¹·m⁻²
//! patches = 4                         # N × N patches for polygons of this material
//!
//! [objects.light]                     # by OBJ object/group name
//! patches = 1                         # wins over the material's
//!
//! [objects.sphere]
//! patch_size = "0.25m"                # target patch size: "…m", "…cm", "…mm", or
//!                                     # a number in scene units
//! min_element_size = 5                # smallest element's longest edge, same syntax
//!
//! [sun]                               # and [sky], [[lights]], a top-level north:
//! direction = [1, 2, 1]               # the scene's lights (`config_lights.rs`)
//! illuminance = 100000
//!
//! [solver]                            # any solver setting (SettingsPatch)
//! samples = 16
//!
//! [camera]                            # initial camera, original scene coordinates
//! eye = [278, 273, -800]
//! target = [278, 273, 0]
//! up = [0, 1, 0]
//! fov_y_deg = 39.3077
//! width = 512
//! height = 512
//! ```
//!
//! Unknown keys are errors. Every error names this file and the line (from the
//! TOML parser's byte span, or the span of the offending table).
//!
//! Patch sizes (see `crate::mesh::sizing`): a polygon's `patches` count, if an
//! override or the geometry file gives one, wins over any `patch_size`; an
//! override's `patch_size` clears the counts that lower levels gave (the
//! geometry file's, or a material's under an object's), so the most specific
//! override decides. Objects win over materials, both over the `[solver]`
//! settings and the preset. Lengths in metres are converted with the scene's
//! final `units_per_metre` (the command line's, else this file's).

use super::clean::emission_problem;
use super::config_lights::{
    merge_file_lights, portal_mode, read_lights, LampTable, LightScene, LightTables, PortalTable,
    SkyTable, SunTable,
};
use super::display::{load_display_file, DisplayParams};
use super::legacy::{parse_legacy, MAX_PATCHES};
use super::obj::parse_obj;
use super::raw::{RawMaterial, RawPolygon, RawScene};
use super::text::{line_of_offset, read_text, rgb};
use super::{SceneError, SourceRef};
use crate::light::portal_detect::PortalMode;
use crate::light::sun::SceneAxes;
use crate::light::Lights;
use crate::settings::SettingsPatch;
use glam::DVec3;
use serde::de::{self, SeqAccess, Visitor};
use serde::{Deserialize, Deserializer};
use solution::camera::{Camera, UpAxis};
use solution::format::SolveMode;
use std::collections::BTreeMap;
use std::path::Path;
use toml::Spanned;

/// The largest image side a camera may ask for.
const MAX_IMAGE_SIDE: u32 = 16384;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ConfigFile {
    geometry: Spanned<Vec<Spanned<String>>>,
    units_per_metre: Option<Spanned<f64>>,
    up: Option<UpAxis>,
    mode: Option<Spanned<SolveMode>>,
    display: Option<Spanned<String>>,
    #[serde(default)]
    materials: BTreeMap<String, Spanned<MaterialOverride>>,
    #[serde(default)]
    objects: BTreeMap<String, Spanned<ObjectOverride>>,
    solver: Option<Spanned<SettingsPatch>>,
    camera: Option<Spanned<CameraConfig>>,
    /// The scene's north for the sun's azimuth (`config_lights.rs`).
    north: Option<Spanned<[f64; 3]>>,
    sun: Option<Spanned<SunTable>>,
    sky: Option<Spanned<SkyTable>>,
    #[serde(default)]
    lights: Vec<Spanned<LampTable>>,
    #[serde(default)]
    portals: Vec<Spanned<PortalTable>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MaterialOverride {
    kd: Option<Spanned<Rgb>>,
    ks: Option<Spanned<Rgb>>,
    alpha: Option<f64>,
    emission: Option<Spanned<Rgb>>,
    patches: Option<u32>,
    patch_size: Option<Spanned<RawLength>>,
    min_element_size: Option<Spanned<RawLength>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ObjectOverride {
    patches: Option<u32>,
    patch_size: Option<Spanned<RawLength>>,
    min_element_size: Option<Spanned<RawLength>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraConfig {
    eye: Option<[f64; 3]>,
    target: Option<[f64; 3]>,
    up: Option<[f64; 3]>,
    fov_y_deg: Option<f64>,
    width: Option<u32>,
    height: Option<u32>,
}

/// A length of a per-object meshing size, as the config wrote it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Length {
    /// A bare number: scene units.
    SceneUnits(f64),
    /// A string with `m`, `cm` or `mm`, converted to metres.
    Metres(f64),
}

impl Length {
    /// The length in scene units, given the scene's scale.
    pub fn in_scene_units(self, units_per_metre: f64) -> f64 {
        match self {
            Length::SceneUnits(v) => v,
            Length::Metres(m) => m * units_per_metre,
        }
    }
}

/// Per-object (or per-material) meshing sizes from a TOML config; `None` leaves
/// the solve's settings (see `crate::mesh::sizing`).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct MeshSizes {
    /// Target patch size: patches per side ⌈longest edge / size⌉.
    pub patch_size: Option<Length>,
    /// Smallest element's longest edge for adaptive subdivision.
    pub min_element_size: Option<Length>,
}

/// A length value before its check: a number or a string.
#[derive(Clone, Debug)]
pub(super) enum RawLength {
    Number(f64),
    Text(String),
}

impl<'de> Deserialize<'de> for RawLength {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct LengthVisitor;
        impl<'de> Visitor<'de> for LengthVisitor {
            type Value = RawLength;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str(
                    "a length: a number in scene units or a string such as \"0.25m\" (m, cm or mm)",
                )
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<RawLength, E> {
                Ok(RawLength::Number(v))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<RawLength, E> {
                Ok(RawLength::Number(v as f64))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<RawLength, E> {
                Ok(RawLength::Number(v as f64))
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<RawLength, E> {
                Ok(RawLength::Text(v.to_owned()))
            }
        }
        deserializer.deserialize_any(LengthVisitor)
    }
}

/// Checks a length: finite and > 0; a string is a number followed by `m`,
/// `cm` or `mm` (spaces allowed between).
pub(super) fn parse_length(key: &str, raw: &RawLength) -> Result<Length, String> {
    let (length, shown) = match raw {
        RawLength::Number(v) => (Some(Length::SceneUnits(*v)), v.to_string()),
        RawLength::Text(t) => {
            let t = t.trim();
            let (number, scale) = if let Some(n) = t.strip_suffix("mm") {
                (n, 1e-3)
            } else if let Some(n) = t.strip_suffix("cm") {
                (n, 1e-2)
            } else if let Some(n) = t.strip_suffix('m') {
                (n, 1.0)
            } else {
                ("", f64::NAN)
            };
            let metres = number.trim().parse::<f64>().ok().map(|v| v * scale);
            (metres.map(Length::Metres), format!("{t:?}"))
        }
    };
    match length {
        Some(l) if matches!(l, Length::SceneUnits(v) | Length::Metres(v) if v.is_finite() && v > 0.0) => {
            Ok(l)
        }
        _ => Err(format!(
            "{key} = {shown} is not a length > 0: give a number in scene units (e.g. 250) \
             or a string in metres, centimetres or millimetres (e.g. \"0.25m\", \"25cm\", \"250mm\")"
        )),
    }
}

/// A colour: one grey number or `[r, g, b]`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Rgb(pub DVec3);

impl<'de> Deserialize<'de> for Rgb {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct RgbVisitor;
        impl<'de> Visitor<'de> for RgbVisitor {
            type Value = Rgb;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number or an array of 3 numbers [r, g, b]")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Rgb, E> {
                Ok(Rgb(DVec3::splat(v)))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Rgb, E> {
                Ok(Rgb(DVec3::splat(v as f64)))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Rgb, E> {
                Ok(Rgb(DVec3::splat(v as f64)))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Rgb, A::Error> {
                let mut values = [0.0; 3];
                let mut count = 0;
                while let Some(x) = seq.next_element::<f64>()? {
                    if count == 3 {
                        return Err(de::Error::invalid_length(4, &self));
                    }
                    values[count] = x;
                    count += 1;
                }
                if count != 3 {
                    return Err(de::Error::invalid_length(count, &self));
                }
                Ok(Rgb(DVec3::from(values)))
            }
        }
        deserializer.deserialize_any(RgbVisitor)
    }
}

/// What a scene config contributes besides geometry.
pub(crate) struct ConfigScene {
    pub raw: RawScene,
    pub settings: SettingsPatch,
    pub display: Option<DisplayParams>,
    pub camera: Option<Camera>,
    pub units_per_metre: Option<f64>,
    pub up_axis: UpAxis,
    /// The sun, sky and lamps of the config's tables and its glTF files, in
    /// the geometry's original coordinates.
    pub lights: Lights,
    /// The scene's up and north, for command-line lights (`light_flags.rs`).
    pub axes: SceneAxes,
    /// `[sky] portals`: whether to detect portals in the geometry.
    pub portal_mode: PortalMode,
}

/// Reads a TOML scene config and every file it names. `units_per_metre_flag`
/// is the command line's scale, which wins over the config's for lengths in
/// metres (a lamp's radius).
pub(crate) fn load_config(
    path: &Path,
    units_per_metre_flag: Option<f64>,
) -> Result<ConfigScene, SceneError> {
    let text = read_text(path)?;
    let at = ConfigSource { path, text: &text };
    let config = parse_config(&at)?;
    let dir = path.parent().unwrap_or(Path::new(""));
    let (mut raw, file_lights) = read_geometry(&at, &config, dir)?;
    apply_material_overrides(&at, &config, &mut raw)?;
    apply_object_overrides(&at, &config, &mut raw)?;
    let (settings, units_per_metre) = solver_settings(&at, &config)?;
    let up_axis = config.up.unwrap_or_default();
    let tables = LightTables {
        north: config.north.as_ref(),
        sun: config.sun.as_ref(),
        sky: config.sky.as_ref(),
        lamps: &config.lights,
        portals: &config.portals,
    };
    let scene = LightScene {
        up_axis,
        units_per_metre: units_per_metre_flag.or(units_per_metre).unwrap_or(1.0),
        dir,
    };
    let (lights, axes) = read_lights(&at, &tables, &scene, file_lights, &mut raw.warnings)?;
    let portal_mode = portal_mode(&at, &tables)?;
    let display = match &config.display {
        Some(name) => {
            let file = dir.join(name.get_ref());
            let d = load_display_file(&file).map_err(|e| at.reread(name, "display", &file, e))?;
            raw.warnings.extend(d.warnings.iter().cloned());
            Some(d)
        }
        None => None,
    };
    let camera = match &config.camera {
        Some(spanned) => Some(config_camera(&at, spanned, display.as_ref(), up_axis)?),
        None => display.as_ref().map(|d| d.camera),
    };
    Ok(ConfigScene {
        raw,
        settings,
        display,
        camera,
        units_per_metre,
        up_axis,
        lights,
        axes,
        portal_mode,
    })
}

/// The config file being read, for errors at the line of a TOML span.
pub(super) struct ConfigSource<'a> {
    pub path: &'a Path,
    pub text: &'a str,
}

impl ConfigSource<'_> {
    pub(super) fn line(&self, span: std::ops::Range<usize>) -> Option<usize> {
        Some(line_of_offset(self.text, span.start))
    }

    pub(super) fn err(
        &self,
        span: std::ops::Range<usize>,
        item: &str,
        message: String,
    ) -> SceneError {
        SceneError::at(self.path, self.line(span), item.to_owned(), message)
    }

    /// A file named by this config that cannot be read, reported at its line here.
    fn reread(&self, name: &Spanned<String>, key: &str, file: &Path, e: SceneError) -> SceneError {
        match e {
            SceneError::Io { path: p, source } if p == file => self.err(
                name.span(),
                "",
                format!(
                    "{key} `{}`: cannot read {}: {source}",
                    name.get_ref(),
                    p.display()
                ),
            ),
            other => other,
        }
    }

    /// A per-object or per-material size, checked at the value's own line.
    fn sizes(
        &self,
        patch_size: &Option<Spanned<RawLength>>,
        min_element_size: &Option<Spanned<RawLength>>,
        item: &str,
    ) -> Result<MeshSizes, SceneError> {
        let one = |key: &str, value: &Option<Spanned<RawLength>>| {
            value
                .as_ref()
                .map(|v| parse_length(key, v.get_ref()).map_err(|m| self.err(v.span(), item, m)))
                .transpose()
        };
        Ok(MeshSizes {
            patch_size: one("patch_size", patch_size)?,
            min_element_size: one("min_element_size", min_element_size)?,
        })
    }
}

/// The TOML document, with its `[solver]` settings range-checked before any
/// geometry is read.
fn parse_config(at: &ConfigSource) -> Result<ConfigFile, SceneError> {
    let config: ConfigFile = toml::from_str(at.text).map_err(|e| {
        SceneError::at(
            at.path,
            e.span().map(|s| line_of_offset(at.text, s.start)),
            "",
            e.message().trim().replace('\n', "; "),
        )
    })?;
    // Every range check is per setting and every preset is in range, so a value
    // the check refuses on top of the default preset is refused on top of any.
    if let Some(solver) = &config.solver {
        crate::settings::SolverSettings::resolve(Default::default(), &[solver.get_ref()])
            .map_err(|e| at.err(solver.span(), "[solver]", e.to_string()))?;
    }
    Ok(config)
}

/// Every geometry file the config names, in order, as one raw scene, and
/// the lights of its glTF files (`KHR_lights_punctual`).
fn read_geometry(
    at: &ConfigSource,
    config: &ConfigFile,
    dir: &Path,
) -> Result<(RawScene, Lights), SceneError> {
    if config.geometry.get_ref().is_empty() {
        return Err(at.err(
            config.geometry.span(),
            "",
            "`geometry` names no file: give at least one OBJ, glTF or legacy geometry file"
                .to_owned(),
        ));
    }
    let mut raw = RawScene::default();
    let mut lights = Lights::default();
    for name in config.geometry.get_ref() {
        let file = dir.join(name.get_ref());
        let extension = file
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        let part = match extension.as_deref() {
            Some("obj") => parse_obj(&file),
            // A glTF's geometry, materials and lights only: in a scene
            // config, the config's own `units_per_metre` (default 1, which is
            // glTF's metre) and `camera` apply, not the glTF file's camera.
            Some("gltf") | Some("glb") => super::gltf::parse_gltf(&file).map(|g| {
                merge_file_lights(&mut lights, g.lights, &file, &mut raw.warnings);
                g.raw
            }),
            Some("toml") => {
                return Err(at.err(
                    name.span(),
                    "",
                    format!(
                        "geometry `{}`: a scene config cannot include another one",
                        name.get_ref()
                    ),
                ))
            }
            _ => parse_legacy(&file),
        }
        .map_err(|e| at.reread(name, "geometry", &file, e))?;
        raw.append(part);
    }
    Ok((raw, lights))
}

/// Checks one `[materials.KEY]` table's values, each at its own line.
fn check_material_override(
    at: &ConfigSource,
    spanned: &Spanned<MaterialOverride>,
    item: &str,
) -> Result<(), SceneError> {
    let o = spanned.get_ref();
    for (what, value) in [("kd", &o.kd), ("ks", &o.ks)] {
        if let Some(value) = value {
            let Rgb(v) = *value.get_ref();
            if !v.is_finite() || v.min_element() < 0.0 {
                return Err(at.err(
                    value.span(),
                    item,
                    format!("{what} must be finite and non-negative, is {}", rgb(v)),
                ));
            }
        }
    }
    if let Some(value) = &o.emission {
        if let Some(problem) = emission_problem(value.get_ref().0) {
            return Err(at.err(value.span(), item, format!("emission {problem}")));
        }
    }
    if let Some(alpha) = o.alpha {
        if !(alpha.is_finite() && alpha > 0.0) {
            return Err(at.err(
                spanned.span(),
                item,
                format!("alpha must be finite and > 0, is {alpha}"),
            ));
        }
    }
    if let Some(p) = o.patches {
        check_patches(p).map_err(|m| at.err(spanned.span(), item, m))?;
    }
    Ok(())
}

/// Applies the `[materials]` tables to every material that answers to their
/// key, then their patch counts and sizes to the polygons that use them.
fn apply_material_overrides(
    at: &ConfigSource,
    config: &ConfigFile,
    raw: &mut RawScene,
) -> Result<(), SceneError> {
    let mut material_patches: Vec<Option<u32>> = vec![None; raw.materials.len()];
    let mut material_sizes: Vec<MeshSizes> = vec![MeshSizes::default(); raw.materials.len()];
    for (key, spanned) in &config.materials {
        let span = spanned.span();
        let item = format!("materials.{key}");
        let o = spanned.get_ref();
        let targets: Vec<usize> = (0..raw.materials.len())
            .filter(|&i| raw.materials[i].answers_to(key))
            .collect();
        if targets.is_empty() {
            let mut names: Vec<&str> = raw.materials.iter().map(|m| m.name.as_str()).collect();
            names.dedup();
            return Err(at.err(
                span,
                &item,
                format!(
                    "no material named `{key}` in the geometry (it has: {})",
                    names.join(", ")
                ),
            ));
        }
        check_material_override(at, spanned, &item)?;
        let sizes = at.sizes(&o.patch_size, &o.min_element_size, &item)?;
        let source = SourceRef {
            file: at.path.to_path_buf(),
            line: at.line(span.clone()),
            item: item.clone(),
        };
        for i in targets {
            override_material(&mut raw.materials[i], o, &source);
            material_patches[i] = o.patches.or(material_patches[i]);
            let m = &mut material_sizes[i];
            m.patch_size = sizes.patch_size.or(m.patch_size);
            m.min_element_size = sizes.min_element_size.or(m.min_element_size);
        }
    }
    for p in &mut raw.polygons {
        let patches = material_patches[p.material];
        if let Some(n) = patches {
            p.patches = Some(n);
        }
        apply_sizes(p, material_sizes[p.material], patches.is_some());
    }
    Ok(())
}

/// Gives material `m` an override's values; it is then defined by the config
/// (no warning for a missing definition, no refusal of an unread file).
fn override_material(m: &mut RawMaterial, o: &MaterialOverride, source: &SourceRef) {
    if let Some(kd) = &o.kd {
        m.kd = kd.get_ref().0;
    }
    if let Some(ks) = &o.ks {
        m.ks = ks.get_ref().0;
    }
    if let Some(alpha) = o.alpha {
        m.alpha = alpha;
    }
    if let Some(emission) = &o.emission {
        m.emission = emission.get_ref().0;
    }
    m.overridden_at = Some(source.clone());
    m.undefined = None;
    m.unread_reflectance_file = None;
}

/// Applies the `[objects]` tables to the polygons of each OBJ object or group;
/// they win over material overrides.
fn apply_object_overrides(
    at: &ConfigSource,
    config: &ConfigFile,
    raw: &mut RawScene,
) -> Result<(), SceneError> {
    for (key, spanned) in &config.objects {
        let item = format!("objects.{key}");
        let o = spanned.get_ref();
        if let Some(patches) = o.patches {
            check_patches(patches).map_err(|m| at.err(spanned.span(), &item, m))?;
        }
        let sizes = at.sizes(&o.patch_size, &o.min_element_size, &item)?;
        let mut found = false;
        for p in raw
            .polygons
            .iter_mut()
            .filter(|p| p.object.as_deref() == Some(key.as_str()))
        {
            if let Some(patches) = o.patches {
                p.patches = Some(patches);
            }
            apply_sizes(p, sizes, o.patches.is_some());
            found = true;
        }
        if !found {
            let mut names: Vec<&str> = raw
                .polygons
                .iter()
                .filter_map(|p| p.object.as_deref())
                .collect();
            names.dedup();
            return Err(at.err(
                spanned.span(),
                &item,
                format!(
                    "no object or group named `{key}` in the geometry (it has: {})",
                    if names.is_empty() {
                        "none".to_owned()
                    } else {
                        names.join(", ")
                    }
                ),
            ));
        }
    }
    Ok(())
}

/// The `[solver]` settings with the top-level `mode` and `units_per_metre`
/// folded in (a conflict between the two places is an error), and the scene's
/// `units_per_metre` if either gives one.
fn solver_settings(
    at: &ConfigSource,
    config: &ConfigFile,
) -> Result<(SettingsPatch, Option<f64>), SceneError> {
    let mut settings = SettingsPatch::default();
    if let Some(s) = &config.solver {
        settings = s.get_ref().clone();
    }
    if let Some(mode) = &config.mode {
        if let Some(other) = settings.mode.filter(|m| m != mode.get_ref()) {
            return Err(at.err(
                mode.span(),
                "",
                format!(
                    "`mode = {:?}` conflicts with `[solver] mode = {other:?}`",
                    mode.get_ref()
                ),
            ));
        }
        settings.mode = Some(*mode.get_ref());
    }
    let mut units_per_metre = None;
    if let Some(u) = &config.units_per_metre {
        let value = *u.get_ref();
        if !(value.is_finite() && value > 0.0) {
            return Err(at.err(
                u.span(),
                "",
                format!("units_per_metre must be finite and > 0, is {value}"),
            ));
        }
        if let Some(other) = settings.units_per_metre.filter(|o| *o != value) {
            return Err(at.err(
                u.span(),
                "",
                format!("`units_per_metre = {value}` conflicts with `[solver] units_per_metre = {other}`"),
            ));
        }
        units_per_metre = Some(value);
    }
    if let Some(u) = settings.units_per_metre {
        let span = config.solver.as_ref().map(|s| s.span()).unwrap_or(0..0);
        if !(u.is_finite() && u > 0.0) {
            return Err(at.err(
                span,
                "solver",
                format!("units_per_metre must be finite and > 0, is {u}"),
            ));
        }
        units_per_metre = Some(u);
    }
    settings.units_per_metre = units_per_metre;
    Ok((settings, units_per_metre))
}

/// The `[camera]` table over the display file's camera (each value the
/// table leaves out comes from the display file, else the default camera).
fn config_camera(
    at: &ConfigSource,
    spanned: &Spanned<CameraConfig>,
    display: Option<&DisplayParams>,
    up_axis: UpAxis,
) -> Result<Camera, SceneError> {
    let c = spanned.get_ref();
    let base = display.map(|d| d.camera);
    let (Some(eye), Some(target)) = (
        c.eye.or(base.map(|b| b.eye)),
        c.target.or(base.map(|b| b.target)),
    ) else {
        return Err(at.err(
            spanned.span(),
            "camera",
            "[camera] needs `eye` and `target` (or a `display` file that gives them)".to_owned(),
        ));
    };
    let default = Camera::default();
    let camera = Camera {
        eye,
        target,
        up: c.up.or(base.map(|b| b.up)).unwrap_or(up_axis.vector()),
        fov_y_deg: c
            .fov_y_deg
            .or(base.map(|b| b.fov_y_deg))
            .unwrap_or(default.fov_y_deg),
        width: c.width.or(base.map(|b| b.width)).unwrap_or(default.width),
        height: c
            .height
            .or(base.map(|b| b.height))
            .unwrap_or(default.height),
    };
    validate_camera(&camera).map_err(|m| at.err(spanned.span(), "camera", m))?;
    Ok(camera)
}

/// Gives polygon `p` an override's sizes. A `patch_size` replaces the patch
/// count that a lower level gave (the geometry file, a material) unless the
/// same override also sets `patches`, which then wins.
fn apply_sizes(p: &mut RawPolygon, sizes: MeshSizes, sets_patches: bool) {
    if sizes.patch_size.is_some() {
        p.sizes.patch_size = sizes.patch_size;
        if !sets_patches {
            p.patches = None;
        }
    }
    if sizes.min_element_size.is_some() {
        p.sizes.min_element_size = sizes.min_element_size;
    }
}

fn check_patches(p: u32) -> Result<(), String> {
    if (1..=MAX_PATCHES).contains(&p) {
        Ok(())
    } else {
        Err(format!(
            "patches = {p} is out of range (1 to {MAX_PATCHES})"
        ))
    }
}

/// Checks a camera from a config: finite, eye ≠ target, up not along the view,
/// 0 < fov < 180, image sides 1 to 16384.
pub(crate) fn validate_camera(c: &Camera) -> Result<(), String> {
    let (eye, target, up) = (DVec3::from(c.eye), DVec3::from(c.target), DVec3::from(c.up));
    if !(eye.is_finite() && target.is_finite() && up.is_finite() && c.fov_y_deg.is_finite()) {
        return Err("camera values must be finite".to_owned());
    }
    let view = target - eye;
    if view.length() == 0.0 {
        return Err(format!(
            "camera eye and target are the same point {:?}",
            c.eye
        ));
    }
    if up.length() == 0.0 || view.normalize().cross(up.normalize()).length() < 1e-6 {
        return Err(format!(
            "camera up {:?} is zero or parallel to the view direction",
            c.up
        ));
    }
    if !(c.fov_y_deg > 0.0 && c.fov_y_deg < 180.0) {
        return Err(format!(
            "camera fov_y_deg = {} is out of range (0 < fov < 180)",
            c.fov_y_deg
        ));
    }
    if !(1..=MAX_IMAGE_SIDE).contains(&c.width) || !(1..=MAX_IMAGE_SIDE).contains(&c.height) {
        return Err(format!(
            "camera image {}×{} is out of range (1 to {MAX_IMAGE_SIDE} pixels a side)",
            c.width, c.height
        ));
    }
    Ok(())
}
