//! The TOML scene config: which geometry files make the scene, and what to
//! change about them.
//!
//! ```toml
//! geometry = ["cornell_box.obj"]      # OBJ or legacy files, relative to this file
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

use super::display::{load_display_file, DisplayParams};
use super::legacy::{parse_legacy, MAX_PATCHES};
use super::obj::parse_obj;
use super::raw::RawScene;
use super::text::{line_of_offset, read_text, rgb};
use super::{SceneError, SourceRef};
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
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MaterialOverride {
    kd: Option<Rgb>,
    ks: Option<Rgb>,
    alpha: Option<f64>,
    emission: Option<Rgb>,
    patches: Option<u32>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ObjectOverride {
    patches: u32,
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

/// A colour: one grey number or `[r, g, b]`.
#[derive(Clone, Copy, Debug)]
struct Rgb(DVec3);

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
}

/// Reads a TOML scene config and every file it names.
pub(crate) fn load_config(path: &Path) -> Result<ConfigScene, SceneError> {
    let text = read_text(path)?;
    let line = |span: std::ops::Range<usize>| Some(line_of_offset(&text, span.start));
    let err = |span: std::ops::Range<usize>, item: &str, message: String| {
        SceneError::at(path, line(span), item.to_owned(), message)
    };
    let config: ConfigFile = toml::from_str(&text).map_err(|e| {
        SceneError::at(
            path,
            e.span().map(|s| line_of_offset(&text, s.start)),
            "",
            e.message().trim().replace('\n', "; "),
        )
    })?;
    // Out-of-range solver settings are refused now, before any geometry is read.
    // Every range check is per setting and every preset is in range, so a value
    // the check refuses on top of the default preset is refused on top of any.
    if let Some(solver) = &config.solver {
        crate::settings::SolverSettings::resolve(Default::default(), &[solver.get_ref()])
            .map_err(|e| err(solver.span(), "[solver]", e.to_string()))?;
    }
    let dir = path.parent().unwrap_or(Path::new(""));
    // A file named by this config that cannot be read is reported at its line here.
    let reread = |name: &Spanned<String>, key: &str, file: &Path, e: SceneError| match e {
        SceneError::Io { path: p, source } if p == file => err(
            name.span(),
            "",
            format!(
                "{key} `{}`: cannot read {}: {source}",
                name.get_ref(),
                p.display()
            ),
        ),
        other => other,
    };

    // Geometry.
    if config.geometry.get_ref().is_empty() {
        return Err(err(
            config.geometry.span(),
            "",
            "`geometry` names no file: give at least one OBJ or legacy geometry file".to_owned(),
        ));
    }
    let mut raw = RawScene::default();
    for name in config.geometry.get_ref() {
        let file = dir.join(name.get_ref());
        let extension = file
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        let part = match extension.as_deref() {
            Some("obj") => parse_obj(&file),
            Some("toml") => {
                return Err(err(
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
        .map_err(|e| reread(name, "geometry", &file, e))?;
        raw.append(part);
    }

    // Material overrides.
    let mut material_patches: Vec<Option<u32>> = vec![None; raw.materials.len()];
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
            return Err(err(
                span,
                &item,
                format!(
                    "no material named `{key}` in the geometry (it has: {})",
                    names.join(", ")
                ),
            ));
        }
        for (what, v) in [("kd", o.kd), ("ks", o.ks), ("emission", o.emission)] {
            if let Some(Rgb(v)) = v {
                if !v.is_finite() || v.min_element() < 0.0 {
                    return Err(err(
                        span.clone(),
                        &item,
                        format!("{what} must be finite and non-negative, is {}", rgb(v)),
                    ));
                }
            }
        }
        if let Some(alpha) = o.alpha {
            if !(alpha.is_finite() && alpha > 0.0) {
                return Err(err(
                    span,
                    &item,
                    format!("alpha must be finite and > 0, is {alpha}"),
                ));
            }
        }
        if let Some(p) = o.patches {
            check_patches(p).map_err(|m| err(span.clone(), &item, m))?;
        }
        let at = SourceRef {
            file: path.to_path_buf(),
            line: line(span.clone()),
            item: item.clone(),
        };
        for i in targets {
            let m = &mut raw.materials[i];
            if let Some(Rgb(kd)) = o.kd {
                m.kd = kd;
            }
            if let Some(Rgb(ks)) = o.ks {
                m.ks = ks;
            }
            if let Some(alpha) = o.alpha {
                m.alpha = alpha;
            }
            if let Some(Rgb(e)) = o.emission {
                m.emission = e;
            }
            m.overridden_at = Some(at.clone());
            m.undefined = None;
            material_patches[i] = o.patches.or(material_patches[i]);
        }
    }
    for p in &mut raw.polygons {
        if let Some(n) = material_patches[p.material] {
            p.patches = Some(n);
        }
    }

    // Object overrides win over material ones.
    for (key, spanned) in &config.objects {
        let item = format!("objects.{key}");
        let patches = spanned.get_ref().patches;
        check_patches(patches).map_err(|m| err(spanned.span(), &item, m))?;
        let mut found = false;
        for p in raw
            .polygons
            .iter_mut()
            .filter(|p| p.object.as_deref() == Some(key.as_str()))
        {
            p.patches = Some(patches);
            found = true;
        }
        if !found {
            let mut names: Vec<&str> = raw
                .polygons
                .iter()
                .filter_map(|p| p.object.as_deref())
                .collect();
            names.dedup();
            return Err(err(
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

    // Solver settings, with the top-level `mode` and `units_per_metre`.
    let mut settings = SettingsPatch::default();
    if let Some(s) = &config.solver {
        settings = s.get_ref().clone();
    }
    if let Some(mode) = &config.mode {
        if let Some(other) = settings.mode.filter(|m| m != mode.get_ref()) {
            return Err(err(
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
            return Err(err(
                u.span(),
                "",
                format!("units_per_metre must be finite and > 0, is {value}"),
            ));
        }
        if let Some(other) = settings.units_per_metre.filter(|o| *o != value) {
            return Err(err(
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
            return Err(err(
                span,
                "solver",
                format!("units_per_metre must be finite and > 0, is {u}"),
            ));
        }
        units_per_metre = Some(u);
    }
    settings.units_per_metre = units_per_metre;

    // Display file and camera.
    let up_axis = config.up.unwrap_or_default();
    let display = match &config.display {
        Some(name) => {
            let file = dir.join(name.get_ref());
            let d = load_display_file(&file).map_err(|e| reread(name, "display", &file, e))?;
            raw.warnings.extend(d.warnings.iter().cloned());
            Some(d)
        }
        None => None,
    };
    let camera = match &config.camera {
        Some(spanned) => {
            let c = spanned.get_ref();
            let base = display.as_ref().map(|d| d.camera);
            let (Some(eye), Some(target)) = (
                c.eye.or(base.map(|b| b.eye)),
                c.target.or(base.map(|b| b.target)),
            ) else {
                return Err(err(
                    spanned.span(),
                    "camera",
                    "[camera] needs `eye` and `target` (or a `display` file that gives them)"
                        .to_owned(),
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
            validate_camera(&camera).map_err(|m| err(spanned.span(), "camera", m))?;
            Some(camera)
        }
        None => display.as_ref().map(|d| d.camera),
    };

    Ok(ConfigScene {
        raw,
        settings,
        display,
        camera,
        units_per_metre,
        up_axis,
    })
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
