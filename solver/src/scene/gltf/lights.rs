//! glTF `KHR_lights_punctual` (Khronos, "KHR_lights_punctual" extension
//! specification): the file's light definitions, placed by the nodes that
//! name them.
//!
//! - A **point** or **spot** light becomes a lamp at the node's world origin;
//!   its `intensity` is luminous intensity in candela, with `color` a filter
//!   (W·sr⁻¹ per channel = color · intensity / 683, `light::units`).
//! - A spot shines down the node's local −z; its `innerConeAngle` and
//!   `outerConeAngle` (radians from the axis, defaults 0 and π/4) become the
//!   lamp's cone, with the falloff the specification recommends.
//! - A **directional** light becomes the sun, toward the node's local +z
//!   (it shines down −z); its `intensity` is illuminance in lux on a plane
//!   facing it. The sun is one light: of several the brightest is kept, with
//!   a warning.
//! - `range` is ignored, with a warning: the solver uses the inverse-square
//!   law out to any distance.
//!
//! An unknown light `type`, a node naming a light that does not exist, or a
//! value out of range is an error naming the file and the light.

use super::nodes::LightNode;
use super::Context;
use crate::light::lamp::Lamp;
use crate::light::sun::{Sun, SunPosition, DEFAULT_ANGULAR_DIAMETER_DEG};
use crate::light::{units, Lights};
use crate::scene::{SceneError, Warning};
use glam::DVec3;
use gltf::Document;
use serde::Deserialize;

/// One entry of the root `KHR_lights_punctual.lights` array.
#[derive(Deserialize)]
struct LightDef {
    #[serde(rename = "type")]
    kind: String,
    name: Option<String>,
    color: Option<[f64; 3]>,
    intensity: Option<f64>,
    range: Option<f64>,
    spot: Option<SpotDef>,
}

#[derive(Deserialize)]
#[serde(rename_all = "camelCase")]
struct SpotDef {
    inner_cone_angle: Option<f64>,
    outer_cone_angle: Option<f64>,
}

/// A node's `{"light": N}`.
#[derive(Deserialize)]
struct NodeLight {
    light: usize,
}

/// The file's punctual lights at their nodes: lamps in scene-graph order and
/// the brightest directional light as the sun.
pub(super) fn read_lights(
    ctx: &Context,
    document: &Document,
    nodes: &[LightNode],
    warnings: &mut Vec<Warning>,
) -> Result<Lights, SceneError> {
    let defs = light_defs(ctx, document)?;
    for (index, def) in defs.iter().enumerate() {
        if let Some(range) = def.range {
            warnings.push(ctx.warning(
                light_item(index, def),
                format!(
                    "range {range} ignored: the light falls off by the inverse-square law at \
                     every distance"
                ),
            ));
        }
    }
    let mut lights = Lights::default();
    let mut suns = 0;
    for node in nodes {
        let index = serde_json::from_value::<NodeLight>(node.extension.clone())
            .map_err(|e| {
                ctx.err(
                    node.name.clone(),
                    format!("its KHR_lights_punctual object is not {{\"light\": INDEX}}: {e}"),
                )
            })?
            .light;
        let Some(def) = defs.get(index) else {
            return Err(ctx.err(
                node.name.clone(),
                format!(
                    "it names KHR_lights_punctual light {index}, but the file defines {}",
                    defs.len()
                ),
            ));
        };
        let item = format!("{}, {}", light_item(index, def), node.name);
        let placed = place(ctx, def, node, &item)?;
        match placed {
            Placed::Lamp(lamp) => lights.lamps.push(lamp),
            Placed::Sun(sun) => {
                suns += 1;
                let brighter = lights.sun.is_none_or(|kept| {
                    sun.irradiance().max_element() > kept.irradiance().max_element()
                });
                if brighter {
                    lights.sun = Some(sun);
                }
            }
        }
    }
    if suns > 1 {
        warnings.push(ctx.warning(
            "KHR_lights_punctual",
            format!(
                "{suns} directional lights placed: the scene has one sun, so the brightest is \
                 kept and the others are ignored"
            ),
        ));
    }
    Ok(lights)
}

/// The root's light definitions, each with a known type.
fn light_defs(ctx: &Context, document: &Document) -> Result<Vec<LightDef>, SceneError> {
    let Some(root) = document.extension_value("KHR_lights_punctual") else {
        return Ok(Vec::new());
    };
    let Some(list) = root.get("lights").and_then(|l| l.as_array()) else {
        return Err(ctx.err("KHR_lights_punctual", "the extension has no `lights` array"));
    };
    let mut defs = Vec::with_capacity(list.len());
    for (index, value) in list.iter().enumerate() {
        let def: LightDef = serde_json::from_value(value.clone()).map_err(|e| {
            ctx.err(
                format!("KHR_lights_punctual light {index}"),
                format!("not a light definition: {e}"),
            )
        })?;
        if !matches!(def.kind.as_str(), "point" | "spot" | "directional") {
            return Err(ctx.err(
                light_item(index, &def),
                format!(
                    "unknown light type {:?}: KHR_lights_punctual defines \"point\", \"spot\" \
                     and \"directional\"",
                    def.kind
                ),
            ));
        }
        defs.push(def);
    }
    Ok(defs)
}

fn light_item(index: usize, def: &LightDef) -> String {
    match &def.name {
        Some(name) => format!("KHR_lights_punctual light {index} ({name})"),
        None => format!("KHR_lights_punctual light {index}"),
    }
}

enum Placed {
    Lamp(Lamp),
    Sun(Sun),
}

/// One light definition at one node.
fn place(
    ctx: &Context,
    def: &LightDef,
    node: &LightNode,
    item: &str,
) -> Result<Placed, SceneError> {
    let err = |message: String| ctx.err(item.to_owned(), message);
    let color = DVec3::from(def.color.unwrap_or([1.0; 3]));
    if !color.is_finite() || color.min_element() < 0.0 {
        return Err(err(format!(
            "color [{}, {}, {}] must be finite and ≥ 0 in every channel",
            color.x, color.y, color.z
        )));
    }
    let intensity = def.intensity.unwrap_or(1.0);
    if !(intensity.is_finite() && intensity >= 0.0) {
        return Err(err(format!(
            "intensity {intensity} must be a finite number ≥ 0"
        )));
    }
    let origin = node.world.transform_point3(DVec3::ZERO);
    // The light shines down its node's local −z (the specification's
    // "Light orientation").
    let axis = node.world.transform_vector3(DVec3::NEG_Z);
    if def.kind == "directional" {
        let toward_sun = SunPosition::from_direction(-axis).map_err(|e| err(e.to_string()))?;
        let sun = Sun::from_illuminance(toward_sun, intensity, color, DEFAULT_ANGULAR_DIAMETER_DEG)
            .map_err(|e| err(e.to_string()))?;
        return Ok(Placed::Sun(sun));
    }
    let name = def.name.clone().unwrap_or_else(|| item.to_owned());
    let candela = units::candela_to_intensity(intensity, color);
    let mut lamp = Lamp::point(&name, origin, candela, 0.0).map_err(|e| err(e.to_string()))?;
    if def.kind == "spot" {
        let spot = def.spot.as_ref();
        let inner = spot.and_then(|s| s.inner_cone_angle).unwrap_or(0.0);
        let outer = spot
            .and_then(|s| s.outer_cone_angle)
            .unwrap_or(std::f64::consts::FRAC_PI_4);
        let (inner, outer) = (degrees(inner), degrees(outer));
        lamp = lamp.with_spot(axis, inner, outer).map_err(|e| {
            err(format!(
                "{e} (innerConeAngle and outerConeAngle are radians)"
            ))
        })?;
    }
    Ok(Placed::Lamp(lamp))
}

/// Radians to degrees, with the specification's largest cone, π/2, exactly
/// 90° (its product with 180/π rounds above 90, which the cone check would
/// refuse).
fn degrees(radians: f64) -> f64 {
    if radians == std::f64::consts::FRAC_PI_2 {
        90.0
    } else {
        radians.to_degrees()
    }
}
