//! The light tables of a TOML scene config (issue 41): `[sun]`, `[sky]` and
//! `[[lights]]`, turned into [`Lights`] by the pure light types of
//! `crate::light`.
//!
//! ```toml
//! north = [0, 0, -1]            # optional: the scene's north (default −z for a
//!                               # y-up scene, +y for a z-up one)
//! [sun]
//! direction = [1, 2, 1]         # toward the sun, or azimuth_deg + elevation_deg,
//!                               # or latitude, longitude, date, time, utc_offset_hours
//! irradiance = [146, 146, 146]  # W·m⁻² per channel facing it, or illuminance = lux
//! angular_diameter_deg = 0.53
//!
//! [sky]
//! kind = "cie-overcast"         # "uniform" | "cie-overcast" | "clear" | "map"
//! illuminance = 10000           # horizontal lux (or a kind's radiometric value)
//! below_horizon = "ground"      # "black" (default) | "same" | "ground"
//! ground_albedo = 0.2
//! portals = "none"              # "auto" (default): the geometry's openings
//!                               # are sky portals unless [[portals]] are given
//!
//! [[lights]]
//! kind = "spot"                 # "point" (default) | "spot"
//! position = [0, 2.5, 0]
//! candela = 800                 # or intensity = [r, g, b] W·sr⁻¹, or power = W
//! direction = [0, -1, 0]
//! inner_cone_deg = 20
//! outer_cone_deg = 30
//! radius = "5 cm"               # a number in scene units, or a length in m, cm, mm
//! ies = "downlight.ies"         # relative to this file
//! ```
//!
//! Every refusal is a [`SceneError`] naming the config file, the line of the
//! offending key (or of its table) and the value. docs/lights.md, "Where
//! lights come from", is the user's description.

use super::config::{parse_length, ConfigSource, RawLength, Rgb};
use super::text::read_text;
use super::{SceneError, SourceRef, Warning};
use crate::light::ies::IesProfile;
use crate::light::lamp::Lamp;
use crate::light::portal::Portal;
use crate::light::portal_detect::PortalMode;
use crate::light::sky::{BelowHorizon, Sky, SkyModel};
use crate::light::sun::{
    LocalTime, SceneAxes, Site, Sun, SunError, SunPosition, DEFAULT_ANGULAR_DIAMETER_DEG,
};
use crate::light::{units, Lights};
use glam::DVec3;
use serde::Deserialize;
use solution::camera::UpAxis;
use std::collections::HashMap;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use toml::Spanned;

/// The turbidity of a clear sky that names none: a clear, dry day (Preetham
/// et al. 1999 show T = 2 as very clear and 6 as hazy; 3 is a common default
/// of renderers that use the model).
pub(crate) const DEFAULT_TURBIDITY: f64 = 3.0;

/// `[sun]`: where the sun is, how strong, how wide.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SunTable {
    direction: Option<Spanned<[f64; 3]>>,
    azimuth_deg: Option<Spanned<f64>>,
    elevation_deg: Option<Spanned<f64>>,
    north: Option<Spanned<[f64; 3]>>,
    latitude: Option<Spanned<f64>>,
    longitude: Option<Spanned<f64>>,
    date: Option<Spanned<String>>,
    time: Option<Spanned<String>>,
    utc_offset_hours: Option<Spanned<f64>>,
    irradiance: Option<Spanned<Rgb>>,
    illuminance: Option<Spanned<f64>>,
    color: Option<Spanned<Rgb>>,
    angular_diameter_deg: Option<Spanned<f64>>,
}

/// `[sky]`: its kind, its strength, and what shows below the horizon.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SkyTable {
    kind: Spanned<String>,
    radiance: Option<Spanned<Rgb>>,
    luminance: Option<Spanned<f64>>,
    zenith_radiance: Option<Spanned<Rgb>>,
    zenith_luminance: Option<Spanned<f64>>,
    illuminance: Option<Spanned<f64>>,
    color: Option<Spanned<Rgb>>,
    turbidity: Option<Spanned<f64>>,
    below_horizon: Option<Spanned<String>>,
    ground_albedo: Option<Spanned<Rgb>>,
    /// `kind = "map"`: the `.hdr` or `.exr` file, relative to the config.
    file: Option<Spanned<String>>,
    /// `kind = "map"`: a factor on its texels (default 1).
    scale: Option<Spanned<f64>>,
    /// `kind = "map"`: degrees about up, from north toward east (default 0).
    rotation_deg: Option<Spanned<f64>>,
    /// `"auto"` (default): find the openings of the geometry as portals
    /// when no `[[portals]]` are declared; `"none"`: do not.
    portals: Option<Spanned<String>>,
}

/// One `[[lights]]` table: a point or spot lamp.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct LampTable {
    kind: Option<Spanned<String>>,
    name: Option<String>,
    position: Spanned<[f64; 3]>,
    intensity: Option<Spanned<Rgb>>,
    candela: Option<Spanned<f64>>,
    power: Option<Spanned<Rgb>>,
    color: Option<Spanned<Rgb>>,
    direction: Option<Spanned<[f64; 3]>>,
    inner_cone_deg: Option<Spanned<f64>>,
    outer_cone_deg: Option<Spanned<f64>>,
    radius: Option<Spanned<RawLength>>,
    ies: Option<Spanned<String>>,
}

/// A `[[portals]]` table: the corners of a window the sky lights the
/// interior through (`light/portal.rs`), in scene units.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct PortalTable {
    corners: Spanned<Vec<[f64; 3]>>,
}

/// The config's light tables as parsed.
pub(super) struct LightTables<'a> {
    pub north: Option<&'a Spanned<[f64; 3]>>,
    pub sun: Option<&'a Spanned<SunTable>>,
    pub sky: Option<&'a Spanned<SkyTable>>,
    pub lamps: &'a [Spanned<LampTable>],
    pub portals: &'a [Spanned<PortalTable>],
}

/// What the lights need from the rest of the scene.
pub(super) struct LightScene<'a> {
    pub up_axis: UpAxis,
    /// The scene's final scale, for a radius given in metres.
    pub units_per_metre: f64,
    /// The config's folder, against which `ies` files are read.
    pub dir: &'a Path,
}

/// The scene's axes: up from its up axis, north as given or by default −z
/// for a ±y-up scene and +y for a ±z-up one (east = north × up: +x for +y up
/// and for +z up).
pub(crate) fn scene_axes(up_axis: UpAxis, north: Option<DVec3>) -> Result<SceneAxes, SunError> {
    let up = DVec3::from(up_axis.vector());
    let north = north.unwrap_or(match up_axis {
        UpAxis::PosY | UpAxis::NegY => DVec3::NEG_Z,
        UpAxis::PosZ | UpAxis::NegZ => DVec3::Y,
    });
    SceneAxes::new(up, north)
}

/// The config's lights over those of its glTF files (`file_lights`): its
/// `[sun]` and `[sky]` replace theirs, its lamps follow theirs. Returns the
/// lights and the scene's axes.
pub(super) fn read_lights(
    at: &ConfigSource,
    tables: &LightTables,
    scene: &LightScene,
    file_lights: Lights,
    warnings: &mut Vec<Warning>,
) -> Result<(Lights, SceneAxes), SceneError> {
    let axes = config_axes(at, tables, scene.up_axis)?;
    let mut lights = file_lights;
    if let Some(table) = tables.sun {
        lights.sun = Some(read_sun(at, table, &axes, warnings)?);
    }
    if let Some(table) = tables.sky {
        lights.sky = Some(read_sky(at, table, &axes, scene.dir, lights.sun.as_ref())?);
    }
    let mut profiles = HashMap::new();
    for (index, table) in tables.lamps.iter().enumerate() {
        let lamp = read_lamp(at, table, index, scene, &axes, &mut profiles)?;
        lights.lamps.push(lamp);
    }
    for (index, table) in tables.portals.iter().enumerate() {
        let corners = table.get_ref().corners.get_ref();
        let corners: Vec<DVec3> = corners.iter().map(|c| DVec3::from(*c)).collect();
        let portal = Portal::new(&corners).map_err(|e| {
            at.err(
                table.get_ref().corners.span(),
                &format!("portals[{index}]"),
                format!("{e}: corners {corners:?}"),
            )
        })?;
        lights.portals.push(portal);
    }
    Ok((lights, axes))
}

/// The `[sky]` table's `portals` key: whether to detect portals
/// (`light/portal_detect.rs`); `auto` without the key or the table.
pub(super) fn portal_mode(
    at: &ConfigSource,
    tables: &LightTables,
) -> Result<PortalMode, SceneError> {
    let Some(given) = tables.sky.and_then(|t| t.get_ref().portals.as_ref()) else {
        return Ok(PortalMode::Auto);
    };
    PortalMode::parse(given.get_ref()).ok_or_else(|| {
        at.err(
            given.span(),
            "sky",
            format!(
                "portals = {:?}: expected \"auto\" or \"none\"",
                given.get_ref()
            ),
        )
    })
}

/// Adds one glTF file's lights to those of the files before it: lamps
/// appended; of two suns the brighter kept, with a warning.
pub(super) fn merge_file_lights(
    lights: &mut Lights,
    more: Lights,
    file: &Path,
    warnings: &mut Vec<Warning>,
) {
    lights.lamps.extend(more.lamps);
    if let Some(sun) = more.sun {
        match lights.sun {
            Some(kept) => {
                let brighter = if sun.irradiance().max_element() > kept.irradiance().max_element() {
                    sun
                } else {
                    kept
                };
                lights.sun = Some(brighter);
                warnings.push(Warning {
                    source: SourceRef {
                        file: file.to_path_buf(),
                        line: None,
                        item: "KHR_lights_punctual".to_owned(),
                    },
                    message: "a second directional light (sun) among the geometry files: \
                              the brighter one is kept"
                        .to_owned(),
                });
            }
            None => lights.sun = Some(sun),
        }
    }
}

/// The top-level `north` or the `[sun]` table's (one of them, or both the
/// same), with the scene's up.
fn config_axes(
    at: &ConfigSource,
    tables: &LightTables,
    up_axis: UpAxis,
) -> Result<SceneAxes, SceneError> {
    let in_sun = tables.sun.and_then(|s| s.get_ref().north.as_ref());
    let north = match (tables.north, in_sun) {
        (Some(a), Some(b)) if a.get_ref() != b.get_ref() => {
            return Err(at.err(
                b.span(),
                "sun",
                format!(
                    "[sun] north = {:?} conflicts with the top-level north = {:?}: give it once",
                    b.get_ref(),
                    a.get_ref()
                ),
            ))
        }
        (a, b) => a.or(b),
    };
    scene_axes(up_axis, north.map(|n| DVec3::from(*n.get_ref()))).map_err(|e| {
        let span = north.map_or(0..0, |n| n.span());
        at.err(span, "north", e.to_string())
    })
}

/// The spans of the keys given, by name, for "give only one" messages.
fn given<'a>(keys: &[(&'a str, Option<Range<usize>>)]) -> Vec<(&'a str, Range<usize>)> {
    keys.iter()
        .filter_map(|(k, s)| s.clone().map(|s| (*k, s)))
        .collect()
}

/// Refuses a second key of a group where one is allowed.
fn at_most_one(
    at: &ConfigSource,
    item: &str,
    keys: &[(&str, Range<usize>)],
) -> Result<(), SceneError> {
    if let [first, second, ..] = keys {
        return Err(at.err(
            second.1.clone(),
            item,
            format!("`{}` and `{}` are both given: give one", first.0, second.0),
        ));
    }
    Ok(())
}

fn span<T>(v: &Option<Spanned<T>>) -> Option<Range<usize>> {
    v.as_ref().map(|v| v.span())
}

/// The colour filter of a photometric value (white when not given), which
/// must be finite and ≥ 0; a radiometric value takes none.
fn color_filter(
    at: &ConfigSource,
    item: &str,
    color: &Option<Spanned<Rgb>>,
    photometric: bool,
) -> Result<DVec3, SceneError> {
    let Some(c) = color else {
        return Ok(DVec3::ONE);
    };
    let v = c.get_ref().0;
    if !photometric {
        return Err(at.err(
            c.span(),
            item,
            "`color` filters a photometric strength (candela, lux, cd/m²), and there is none \
             here (a radiometric RGB value is already coloured): leave `color` out"
                .to_owned(),
        ));
    }
    if !v.is_finite() || v.min_element() < 0.0 {
        return Err(at.err(
            c.span(),
            item,
            format!(
                "color = [{}, {}, {}] must be finite and ≥ 0 in every channel",
                v.x, v.y, v.z
            ),
        ));
    }
    Ok(v)
}

/// `[sun]`, with a warning when it is below the horizon.
fn read_sun(
    at: &ConfigSource,
    table: &Spanned<SunTable>,
    axes: &SceneAxes,
    warnings: &mut Vec<Warning>,
) -> Result<Sun, SceneError> {
    let s = table.get_ref();
    let position = sun_position(at, table, axes)?;
    let (_, elevation) = axes.azimuth_elevation(position.direction());
    if elevation <= 0.0 {
        warnings.push(Warning {
            source: SourceRef {
                file: at.path.to_path_buf(),
                line: at.line(table.span()),
                item: "sun".to_owned(),
            },
            message: format!(
                "the sun is at or below the horizon (elevation {elevation:.2}°): it lights \
                 nothing above the ground"
            ),
        });
    }
    let diameter = s
        .angular_diameter_deg
        .as_ref()
        .map_or(DEFAULT_ANGULAR_DIAMETER_DEG, |d| *d.get_ref());
    let strength = given(&[
        ("irradiance", span(&s.irradiance)),
        ("illuminance", span(&s.illuminance)),
    ]);
    at_most_one(at, "sun", &strength)?;
    let color = color_filter(at, "sun", &s.color, s.irradiance.is_none())?;
    let sun = match (&s.irradiance, &s.illuminance) {
        (Some(e), _) => Sun::new(position, e.get_ref().0, diameter),
        (None, Some(lux)) => Sun::from_illuminance(position, *lux.get_ref(), color, diameter),
        (None, None) => {
            return Err(at.err(
                table.span(),
                "sun",
                "[sun] needs a strength: `irradiance = [r, g, b]` (W·m⁻² per channel on a \
                 plane facing the sun) or `illuminance = LUX` (100000 is bright sunlight)"
                    .to_owned(),
            ))
        }
    };
    sun.map_err(|e| {
        let at_key = match &e {
            SunError::OutOfRange { what, .. } | SunError::NotFinite { what, .. }
                if what.contains("diameter") =>
            {
                span(&s.angular_diameter_deg)
            }
            _ => strength.first().map(|k| k.1.clone()),
        };
        at.err(at_key.unwrap_or(table.span()), "sun", e.to_string())
    })
}

/// The `[sun]` table's position: a direction, azimuth and elevation, or a
/// place and time (exactly one of them).
fn sun_position(
    at: &ConfigSource,
    table: &Spanned<SunTable>,
    axes: &SceneAxes,
) -> Result<SunPosition, SceneError> {
    let s = table.get_ref();
    let ways = given(&[
        ("direction", span(&s.direction)),
        (
            "azimuth_deg/elevation_deg",
            span(&s.azimuth_deg).or(span(&s.elevation_deg)),
        ),
        (
            "latitude/longitude/date/time",
            span(&s.latitude)
                .or(span(&s.longitude))
                .or(span(&s.date))
                .or(span(&s.time))
                .or(span(&s.utc_offset_hours)),
        ),
    ]);
    at_most_one(at, "sun", &ways)?;
    let err = |span: Range<usize>, e: SunError| at.err(span, "sun", e.to_string());
    if let Some(d) = &s.direction {
        return SunPosition::from_direction(DVec3::from(*d.get_ref()))
            .map_err(|e| err(d.span(), e));
    }
    if ways.is_empty() {
        return Err(at.err(
            table.span(),
            "sun",
            "[sun] needs a position: `direction = [x, y, z]` (toward the sun), \
             `azimuth_deg` and `elevation_deg`, or `latitude`, `longitude`, `date`, `time` \
             (and `utc_offset_hours`)"
                .to_owned(),
        ));
    }
    if s.azimuth_deg.is_some() || s.elevation_deg.is_some() {
        let (Some(az), Some(el)) = (&s.azimuth_deg, &s.elevation_deg) else {
            return Err(at.err(
                table.span(),
                "sun",
                "[sun] needs both `azimuth_deg` and `elevation_deg`".to_owned(),
            ));
        };
        return SunPosition::from_azimuth_elevation(*az.get_ref(), *el.get_ref(), axes).map_err(
            |e| match e {
                SunError::NotFinite { what, .. } if what.contains("azimuth") => err(az.span(), e),
                _ => err(el.span(), e),
            },
        );
    }
    sun_from_place(at, table, axes)
}

/// The sun seen from `latitude`, `longitude` at local `date` and `time`
/// (`utc_offset_hours`, default 0), by the NOAA algorithm.
fn sun_from_place(
    at: &ConfigSource,
    table: &Spanned<SunTable>,
    axes: &SceneAxes,
) -> Result<SunPosition, SceneError> {
    let s = table.get_ref();
    let (Some(lat), Some(lon), Some(date), Some(time)) =
        (&s.latitude, &s.longitude, &s.date, &s.time)
    else {
        return Err(at.err(
            table.span(),
            "sun",
            "[sun] from a place and time needs `latitude`, `longitude` (degrees, north and \
             east positive), `date = \"YYYY-MM-DD\"` and `time = \"HH:MM\"` (local), with \
             `utc_offset_hours` (default 0)"
                .to_owned(),
        ));
    };
    let (year, month, day) = parse_date(date.get_ref()).ok_or_else(|| {
        at.err(
            date.span(),
            "sun",
            format!("date = {:?} is not \"YYYY-MM-DD\"", date.get_ref()),
        )
    })?;
    let hours = parse_time(time.get_ref()).ok_or_else(|| {
        at.err(
            time.span(),
            "sun",
            format!(
                "time = {:?} is not \"HH:MM\" or \"HH:MM:SS\" (0:00 to 24:00)",
                time.get_ref()
            ),
        )
    })?;
    let zone = s.utc_offset_hours.as_ref();
    let site = Site {
        latitude_deg: *lat.get_ref(),
        longitude_deg: *lon.get_ref(),
    };
    let local = LocalTime {
        year,
        month,
        day,
        hours,
        utc_offset_hours: zone.map_or(0.0, |z| *z.get_ref()),
    };
    let (position, _) = SunPosition::from_place_and_time(&site, &local, axes).map_err(|e| {
        let key = match &e {
            SunError::OutOfRange { what, .. } | SunError::NotFinite { what, .. } => match *what {
                "latitude" => Some(lat.span()),
                "longitude" => Some(lon.span()),
                "the UTC offset" => zone.map(|z| z.span()),
                _ => Some(time.span()),
            },
            _ => Some(date.span()),
        };
        at.err(key.unwrap_or(table.span()), "sun", e.to_string())
    })?;
    Ok(position)
}

/// "YYYY-MM-DD" → (year, month, day); the calendar check is the NOAA code's.
fn parse_date(text: &str) -> Option<(i32, u32, u32)> {
    let mut parts = text.trim().splitn(3, '-');
    let year = parts.next()?.parse().ok()?;
    let month = parts.next()?.parse().ok()?;
    let day = parts.next()?.parse().ok()?;
    Some((year, month, day))
}

/// "HH:MM" or "HH:MM:SS" → hours since midnight, 0 to 24.
fn parse_time(text: &str) -> Option<f64> {
    let fields: Vec<&str> = text.trim().split(':').collect();
    if !(2..=3).contains(&fields.len()) {
        return None;
    }
    let mut hours = 0.0;
    for (k, (field, limit)) in fields.iter().zip([24u32, 59, 59]).enumerate() {
        let v: u32 = field.parse().ok()?;
        if v > limit {
            return None;
        }
        hours += f64::from(v) / [1.0, 60.0, 3600.0][k];
    }
    (hours <= 24.0).then_some(hours)
}

/// `[sky]`.
fn read_sky(
    at: &ConfigSource,
    table: &Spanned<SkyTable>,
    axes: &SceneAxes,
    dir: &Path,
    sun: Option<&Sun>,
) -> Result<Sky, SceneError> {
    let s = table.get_ref();
    let up = axes.up();
    let model = if s.kind.get_ref() == "map" {
        map_model(at, table, axes, dir)?
    } else {
        for (key, given) in [
            ("file", span(&s.file)),
            ("scale", span(&s.scale)),
            ("rotation_deg", span(&s.rotation_deg)),
        ] {
            if let Some(span) = given {
                return Err(at.err(
                    span,
                    "sky",
                    format!("`{key}` applies to kind = \"map\" only"),
                ));
            }
        }
        sky_model(at, table, sun)?
    };
    let below = below_horizon(at, table)?;
    Sky::new(model, up, below, sun).map_err(|e| {
        let key = match e {
            crate::light::sky::SkyError::Albedo(_) => span(&s.ground_albedo),
            _ => None,
        };
        at.err(key.unwrap_or(s.kind.span()), "sky", e.to_string())
    })
}

/// The `[sky]` table's kind and strength as a model (exactly one strength
/// key, and only one that the kind takes).
fn sky_model(
    at: &ConfigSource,
    table: &Spanned<SkyTable>,
    sun: Option<&Sun>,
) -> Result<SkyModel, SceneError> {
    let s = table.get_ref();
    let kind = s.kind.get_ref().as_str();
    let strengths = given(&[
        ("radiance", span(&s.radiance)),
        ("luminance", span(&s.luminance)),
        ("zenith_radiance", span(&s.zenith_radiance)),
        ("zenith_luminance", span(&s.zenith_luminance)),
        ("illuminance", span(&s.illuminance)),
        ("turbidity", span(&s.turbidity)),
    ]);
    let (takes, hint): (&[&str], &str) = match kind {
        "uniform" => (
            &["radiance", "luminance", "illuminance"],
            "`radiance = [r, g, b]` (W·sr⁻¹·m⁻²), `luminance = CD_PER_M2` or `illuminance = LUX` \
             (on a horizontal plane: L = E/π)",
        ),
        "cie-overcast" | "overcast" => (
            &["zenith_radiance", "zenith_luminance", "illuminance"],
            "`zenith_radiance = [r, g, b]`, `zenith_luminance = CD_PER_M2` or `illuminance = LUX` \
             (on a horizontal plane: L_z = 9E/(7π))",
        ),
        "clear" => (&["turbidity"], "`turbidity` (2 to 10, default 3)"),
        other => {
            return Err(at.err(
                s.kind.span(),
                "sky",
                format!(
                    "kind = {other:?} is not a sky kind: use \"uniform\", \"cie-overcast\" or \
                     \"clear\""
                ),
            ))
        }
    };
    if let Some((key, span)) = strengths.iter().find(|(k, _)| !takes.contains(k)) {
        return Err(at.err(
            span.clone(),
            "sky",
            format!("`{key}` does not apply to kind = {kind:?}: give {hint}"),
        ));
    }
    at_most_one(at, "sky", &strengths)?;
    let photometric =
        s.luminance.is_some() || s.zenith_luminance.is_some() || s.illuminance.is_some();
    let color = color_filter(at, "sky", &s.color, photometric)?;
    let model = match kind {
        "uniform" => match (&s.radiance, &s.luminance, &s.illuminance) {
            (Some(l), _, _) => SkyModel::uniform(l.get_ref().0),
            (_, Some(nits), _) => SkyModel::uniform_luminance(*nits.get_ref(), color),
            (_, _, Some(lux)) => non_negative_lux(*lux.get_ref())
                .and_then(|lux| SkyModel::uniform_luminance(lux / std::f64::consts::PI, color)),
            _ => return Err(missing_sky_strength(at, table, kind, hint)),
        },
        "clear" => {
            let Some(sun) = sun else {
                return Err(at.err(
                    s.kind.span(),
                    "sky",
                    "kind = \"clear\" is tied to the sun's position: give a [sun] table too"
                        .to_owned(),
                ));
            };
            let turbidity = s
                .turbidity
                .as_ref()
                .map_or(DEFAULT_TURBIDITY, |t| *t.get_ref());
            SkyModel::clear(turbidity, sun.direction())
        }
        _ => match (&s.zenith_radiance, &s.zenith_luminance, &s.illuminance) {
            (Some(l), _, _) => SkyModel::cie_overcast(l.get_ref().0),
            (_, Some(nits), _) => SkyModel::cie_overcast_luminance(*nits.get_ref(), color),
            (_, _, Some(lux)) => SkyModel::cie_overcast_illuminance(*lux.get_ref(), color),
            _ => return Err(missing_sky_strength(at, table, kind, hint)),
        },
    };
    model.map_err(|e| {
        let key = strengths.first().map(|k| k.1.clone());
        at.err(key.unwrap_or(s.kind.span()), "sky", e.to_string())
    })
}

/// A `kind = "map"` sky: its `file` read (relative to the config), times
/// `scale`, turned by `rotation_deg`; no other strength key applies.
fn map_model(
    at: &ConfigSource,
    table: &Spanned<SkyTable>,
    axes: &SceneAxes,
    dir: &Path,
) -> Result<SkyModel, SceneError> {
    let s = table.get_ref();
    let others = given(&[
        ("radiance", span(&s.radiance)),
        ("luminance", span(&s.luminance)),
        ("zenith_radiance", span(&s.zenith_radiance)),
        ("zenith_luminance", span(&s.zenith_luminance)),
        ("illuminance", span(&s.illuminance)),
        ("turbidity", span(&s.turbidity)),
        ("color", span(&s.color)),
    ]);
    if let Some((key, span)) = others.first() {
        return Err(at.err(
            span.clone(),
            "sky",
            format!("`{key}` does not apply to kind = \"map\": give `file`, and `scale` for its strength"),
        ));
    }
    let Some(file) = &s.file else {
        return Err(at.err(
            s.kind.span(),
            "sky",
            "kind = \"map\" needs `file = \"sky.hdr\"` (a Radiance .hdr or OpenEXR .exr)"
                .to_owned(),
        ));
    };
    let scale = s.scale.as_ref().map_or(1.0, |v| *v.get_ref());
    let rotation = s.rotation_deg.as_ref().map_or(0.0, |v| *v.get_ref());
    let path = dir.join(file.get_ref());
    let map = super::envmap_file::load_envmap(&path, scale, rotation).map_err(|e| {
        at.err(
            file.span(),
            "sky",
            format!("the map {} {e}", path.display()),
        )
    })?;
    Ok(SkyModel::Map {
        map: std::sync::Arc::new(map),
        north: axes.north(),
    })
}

/// A uniform sky's horizontal illuminance must be finite and ≥ 0 before it
/// is divided by π (so that the message shows the value as given).
fn non_negative_lux(lux: f64) -> Result<f64, crate::light::sky::SkyError> {
    if lux.is_finite() && lux >= 0.0 {
        Ok(lux)
    } else {
        Err(crate::light::sky::SkyError::Negative {
            what: "the sky's horizontal illuminance",
            value: lux,
        })
    }
}

fn missing_sky_strength(
    at: &ConfigSource,
    table: &Spanned<SkyTable>,
    kind: &str,
    hint: &str,
) -> SceneError {
    at.err(
        table.span(),
        "sky",
        format!("[sky] kind = {kind:?} needs a strength: {hint}"),
    )
}

/// `below_horizon` and `ground_albedo`.
fn below_horizon(at: &ConfigSource, table: &Spanned<SkyTable>) -> Result<BelowHorizon, SceneError> {
    let s = table.get_ref();
    let (rule, rule_span) = match &s.below_horizon {
        Some(b) => (b.get_ref().as_str(), b.span()),
        None => ("black", table.span()),
    };
    match (rule, &s.ground_albedo) {
        ("black", None) => Ok(BelowHorizon::Black),
        ("same", None) => Ok(BelowHorizon::Same),
        ("ground", Some(albedo)) => Ok(BelowHorizon::Ground {
            albedo: albedo.get_ref().0,
        }),
        ("ground", None) => Err(at.err(
            rule_span,
            "sky",
            "below_horizon = \"ground\" needs `ground_albedo = [r, g, b]` (0 to 1)".to_owned(),
        )),
        ("black" | "same", Some(albedo)) => Err(at.err(
            albedo.span(),
            "sky",
            "`ground_albedo` needs below_horizon = \"ground\"".to_owned(),
        )),
        (other, _) => Err(at.err(
            rule_span,
            "sky",
            format!("below_horizon = {other:?}: use \"black\", \"same\" or \"ground\""),
        )),
    }
}

/// One `[[lights]]` table. `profiles` keeps each IES file read once.
fn read_lamp(
    at: &ConfigSource,
    table: &Spanned<LampTable>,
    index: usize,
    scene: &LightScene,
    axes: &SceneAxes,
    profiles: &mut HashMap<PathBuf, Arc<IesProfile>>,
) -> Result<Lamp, SceneError> {
    let l = table.get_ref();
    let item = format!("lights[{index}]");
    let name = l.name.clone().unwrap_or_else(|| item.clone());
    let err = |span: Range<usize>, message: String| at.err(span, &item, message);
    let spot = match l.kind.as_ref().map(|k| (k.get_ref().as_str(), k.span())) {
        None | Some(("point", _)) => false,
        Some(("spot", _)) => true,
        Some((other, span)) => {
            return Err(err(
                span,
                format!("kind = {other:?} is not a lamp kind: use \"point\" or \"spot\""),
            ))
        }
    };
    let radius = match &l.radius {
        Some(r) => parse_length("radius", r.get_ref())
            .map_err(|m| err(r.span(), m))?
            .in_scene_units(scene.units_per_metre),
        None => 0.0,
    };
    let position = DVec3::from(*l.position.get_ref());
    let mut lamp = Lamp::point(&name, position, DVec3::ONE, radius).map_err(|e| {
        let [x, y, z] = *l.position.get_ref();
        err(
            l.position.span(),
            format!("position = [{x}, {y}, {z}]: {e}"),
        )
    })?;
    if spot {
        lamp = aim_spot(at, table, &item, lamp)?;
    } else if let Some(key) = given(&[
        ("inner_cone_deg", span(&l.inner_cone_deg)),
        ("outer_cone_deg", span(&l.outer_cone_deg)),
    ])
    .first()
    {
        return Err(err(
            key.1.clone(),
            format!("`{}` applies to kind = \"spot\" only", key.0),
        ));
    } else if l.direction.is_some() && l.ies.is_none() {
        return Err(err(
            span(&l.direction).unwrap_or(table.span()),
            "`direction` applies to a spot (its axis) or an `ies` lamp (its nadir): give \
             kind = \"spot\", or leave it out"
                .to_owned(),
        ));
    }
    if let Some(file) = &l.ies {
        let ies = read_ies(at, file, &item, scene.dir, profiles)?;
        // The profile's nadir: the spot's axis or the aim given, else down.
        let down = l
            .direction
            .as_ref()
            .map_or(-axes.up(), |d| DVec3::from(*d.get_ref()));
        lamp = lamp
            .with_profile(ies, down)
            .map_err(|e| err(span(&l.direction).unwrap_or(file.span()), e.to_string()))?;
    }
    lamp_strength(at, table, &item, lamp)
}

/// A spot's axis and cone from its table.
fn aim_spot(
    at: &ConfigSource,
    table: &Spanned<LampTable>,
    item: &str,
    lamp: Lamp,
) -> Result<Lamp, SceneError> {
    let l = table.get_ref();
    let (Some(direction), Some(outer)) = (&l.direction, &l.outer_cone_deg) else {
        return Err(at.err(
            table.span(),
            item,
            "kind = \"spot\" needs `direction = [x, y, z]` (its axis) and `outer_cone_deg` \
             (and optionally `inner_cone_deg`, default 0)"
                .to_owned(),
        ));
    };
    let inner = l.inner_cone_deg.as_ref().map_or(0.0, |i| *i.get_ref());
    let cone_span = span(&l.inner_cone_deg).unwrap_or(outer.span());
    lamp.with_spot(DVec3::from(*direction.get_ref()), inner, *outer.get_ref())
        .map_err(|e| {
            let key = match e {
                crate::light::lamp::LampError::Axis(..) => direction.span(),
                _ => cone_span,
            };
            at.err(key, item, e.to_string())
        })
}

/// Reads an `ies` file relative to the config (each file once); its errors
/// name the IES file and line, and the config line that names it.
fn read_ies(
    at: &ConfigSource,
    file: &Spanned<String>,
    item: &str,
    dir: &Path,
    profiles: &mut HashMap<PathBuf, Arc<IesProfile>>,
) -> Result<Arc<IesProfile>, SceneError> {
    let path = dir.join(file.get_ref());
    if let Some(profile) = profiles.get(&path) {
        return Ok(profile.clone());
    }
    let named_at = format!(
        "named at {}:{}",
        at.path.display(),
        at.line(file.span()).unwrap_or(0)
    );
    let text = read_text(&path).map_err(|e| {
        at.err(
            file.span(),
            item,
            format!("ies = {:?}: {e}", file.get_ref()),
        )
    })?;
    let profile = IesProfile::parse(&text, &path.display().to_string()).map_err(|e| {
        SceneError::at(
            &path,
            Some(e.line),
            item,
            format!("{} ({named_at})", e.problem),
        )
    })?;
    let profile = Arc::new(profile);
    profiles.insert(path, profile.clone());
    Ok(profile)
}

/// Gives a lamp (built with unit intensity) its strength: `intensity`
/// (W·sr⁻¹ per channel), `candela` with `color`, or `power` (W per channel,
/// over the lamp's solid angle: 4π for a point, the cone's for a spot, the
/// profile's flux over its peak with an IES file); with an IES file and none
/// of them, the file's own candela with `color`.
fn lamp_strength(
    at: &ConfigSource,
    table: &Spanned<LampTable>,
    item: &str,
    mut lamp: Lamp,
) -> Result<Lamp, SceneError> {
    let l = table.get_ref();
    let keys = given(&[
        ("intensity", span(&l.intensity)),
        ("candela", span(&l.candela)),
        ("power", span(&l.power)),
    ]);
    at_most_one(at, item, &keys)?;
    let amounts = [
        (
            "intensity",
            l.intensity
                .as_ref()
                .map(|v| (v.span(), v.get_ref().0.to_array())),
        ),
        (
            "candela",
            l.candela.as_ref().map(|v| (v.span(), [*v.get_ref(); 3])),
        ),
        (
            "power",
            l.power
                .as_ref()
                .map(|v| (v.span(), v.get_ref().0.to_array())),
        ),
    ];
    for (key, amount) in amounts {
        if let Some((span, values)) = amount {
            if let Some(bad) = values.iter().find(|v| !(v.is_finite() && **v >= 0.0)) {
                return Err(at.err(
                    span,
                    item,
                    format!("{key} has {bad}, which is not a finite number ≥ 0"),
                ));
            }
        }
    }
    let photometric = l.candela.is_some() || (keys.is_empty() && l.ies.is_some());
    let color = color_filter(at, item, &l.color, photometric)?;
    let intensity = match (&l.intensity, &l.candela, &l.power, &lamp.profile) {
        (Some(i), _, _, _) => i.get_ref().0,
        (_, Some(cd), _, _) => units::candela_to_intensity(*cd.get_ref(), color),
        (_, _, Some(p), _) => {
            // The unit-intensity lamp's power is its solid angle.
            let solid_angle = lamp.power().x;
            if solid_angle <= 0.0 {
                return Err(at.err(
                    p.span(),
                    item,
                    "`power` cannot be met: the lamp's IES profile emits nothing".to_owned(),
                ));
            }
            p.get_ref().0 / solid_angle
        }
        (_, _, _, Some(profile)) => units::candela_to_intensity(profile.peak_candela, color),
        _ => {
            return Err(at.err(
                table.span(),
                item,
                "a lamp needs a strength: `intensity = [r, g, b]` (W·sr⁻¹ per channel), \
                 `candela = CD` (with `color`), `power = [r, g, b]` (W per channel) or an `ies` \
                 file"
                    .to_owned(),
            ))
        }
    };
    let key = keys.first().map_or(table.span(), |k| k.1.clone());
    let checked = Lamp::point(&lamp.name, lamp.position, intensity, lamp.radius)
        .map_err(|e| at.err(key, item, e.to_string()))?;
    lamp.intensity = checked.intensity;
    Ok(lamp)
}
