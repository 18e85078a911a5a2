//! What the importer does with an enclosing shell ([`super::shell`]): warn
//! when it matters, and turn an unlit, textured skybox into the sky's
//! environment map when the scene has a sky.
//!
//! **The mapping.** The skybox is seen from its bounding box's centre, as a
//! viewer inside a skybox sees it: for each texel of an equirectangular map
//! (the layout of `light::envmap`: row 0 the zenith, column 0 the sky's
//! north, columns toward east), a ray from the centre in the texel's
//! direction meets the shell, and the texel is the material's base colour
//! times its texture at the hit's UV (bilinear). For a cube box that is each
//! face's own texel in its direction, whatever the faces' UV layout (one
//! atlas, six materials, a cross); for a sphere or dome likewise. The
//! assumption is that the box is centred on the scene, as skyboxes are. The
//! map's height is the tallest texture's, between 64 and 512 rows, and its
//! width twice that.
//!
//! **The brightness.** A skybox's texture is a picture (display values in
//! [0, 1]), not radiance. The map keeps the configured sky's horizontal
//! illuminance (its luminance, Y = 0.2126 R + 0.7152 G + 0.0722 B) and takes
//! the skybox's pattern and colour: it is scaled so that its horizontal
//! irradiance has the configured sky's luminance.

use super::shell::{find_enclosing_shell, Shell};
use super::{Material, Polygon, SourceRef, Warning};
use crate::geometry::visibility::Occluder;
use crate::light::envmap::EnvMap;
use crate::light::sky::{Sky, SkyModel};
use crate::light::Lights;
use glam::DVec3;
use std::f64::consts::PI;

/// Finds an enclosing shell in `polygons` and, where it matters (see
/// `shell.rs`), warns naming it; when the scene has a sky and every material
/// of the shell is unlit (`unlit`, per material) with one textured, its
/// texture becomes the sky's map and the shell leaves the geometry.
pub(super) fn handle_enclosing_shell(
    polygons: &mut Vec<Polygon>,
    materials: &[Material],
    unlit: &[bool],
    lights: &mut Lights,
    diagonal: f64,
    warnings: &mut Vec<Warning>,
) {
    let Some(shell) = find_enclosing_shell(polygons, diagonal) else {
        return;
    };
    let mut shell_materials: Vec<usize> = shell
        .polygons
        .iter()
        .map(|&i| polygons[i].material)
        .collect();
    shell_materials.sort_unstable();
    shell_materials.dedup();
    let all_unlit = shell_materials
        .iter()
        .all(|&m| unlit.get(m).copied().unwrap_or(false));
    let textured = shell_materials
        .iter()
        .any(|&m| materials[m].diffuse_texture.is_some());
    let emissive_textured = shell_materials
        .iter()
        .any(|&m| materials[m].emission_texture.is_some());
    let outside = outside_lights(&shell, lights);
    if outside.is_empty() && !all_unlit && !emissive_textured {
        // An ordinary closed room lit from inside: nothing to say.
        return;
    }
    let first = &polygons[shell.polygons[0]];
    let names: Vec<String> = shell_materials
        .iter()
        .map(|&m| format!("`{}`", materials[m].name))
        .collect();
    let what = format!(
        "an enclosing shell ({} polygon(s) of material {}, first {}) is closed, faces inward and \
         holds the whole scene",
        shell.polygons.len(),
        names.join(", "),
        first.source.item
    );
    let source = SourceRef {
        item: "enclosing shell".to_owned(),
        ..first.source.clone()
    };
    let kind = if all_unlit {
        "its material is unlit (KHR_materials_unlit): a skybox"
    } else if emissive_textured {
        "its material has an emission texture: a skybox"
    } else {
        "it may be a skybox"
    };
    let converted = match (&lights.sky, all_unlit && textured) {
        (Some(sky), true) => skybox_sky(&shell, polygons, materials, sky, lights),
        _ => None,
    };
    let message = match converted {
        Some(sky) => {
            lights.sky = Some(sky);
            let mut keep = vec![true; polygons.len()];
            for &i in &shell.polygons {
                keep[i] = false;
            }
            let mut k = 0;
            polygons.retain(|_| {
                k += 1;
                keep[k - 1]
            });
            format!(
                "{what}; {kind}. The scene has a sky, so the skybox's texture became the sky's \
                 environment map (seen from the shell's centre, scaled to the configured sky's \
                 horizontal illuminance; docs/lights.md, \"Skyboxes and other enclosing shells\") and the shell was removed \
                 from the geometry, so it no longer keeps outside light from the scene"
            )
        }
        None => format!(
            "{what}; {kind}. It is kept as geometry{}{}",
            blocked_note(
                &outside,
                &format!(
                    ", so the {} outside it cannot reach anything inside and the scene will be \
                     dark; remove the shell from the file, or light the scene from inside",
                    outside.join(", ")
                )
            ),
            if all_unlit && lights.sky.is_none() {
                ". With a sky (`--sky`, or `[sky]` in a scene config) an unlit textured skybox \
                 becomes the sky's environment map"
            } else {
                ""
            }
        ),
    };
    warnings.push(Warning { source, message });
}

fn blocked_note(outside: &[String], note: &str) -> String {
    if outside.is_empty() {
        String::new()
    } else {
        note.to_owned()
    }
}

/// The lights a closed shell keeps out: the sun and the sky (which come from
/// infinitely far), and each lamp outside its bounding box.
fn outside_lights(shell: &Shell, lights: &Lights) -> Vec<String> {
    let mut out = Vec::new();
    if lights.sun.is_some() {
        out.push("sun".to_owned());
    }
    if lights.sky.is_some() {
        out.push("sky".to_owned());
    }
    let lamps = lights
        .lamps
        .iter()
        .filter(|l| !shell.contains(l.position))
        .count();
    if lamps > 0 {
        out.push(format!("{lamps} lamp(s)"));
    }
    out
}

/// `sky` with the skybox's texture as its map (see the module notes);
/// `None` when the shell shows nothing.
fn skybox_sky(
    shell: &Shell,
    polygons: &[Polygon],
    materials: &[Material],
    sky: &Sky,
    lights: &Lights,
) -> Option<Sky> {
    let rings: Vec<&[DVec3]> = shell
        .polygons
        .iter()
        .map(|&i| polygons[i].vertices.as_slice())
        .collect();
    let occluder = Occluder::new(&rings);
    let up = sky.up();
    let north = match sky.model() {
        SkyModel::Map { north, .. } => north,
        _ => up.any_orthonormal_vector(),
    };
    let east = north.cross(up);
    let rows = shell
        .polygons
        .iter()
        .filter_map(|&i| materials[polygons[i].material].diffuse_texture.as_ref())
        .map(|t| t.height as usize)
        .max()
        .unwrap_or(64)
        .clamp(64, 512);
    let columns = 2 * rows;
    let centre = shell.centre();
    let mut texels = Vec::with_capacity(rows * columns);
    for row in 0..rows {
        let theta = (row as f64 + 0.5) * PI / rows as f64;
        for column in 0..columns {
            let phi = (column as f64 + 0.5) * 2.0 * PI / columns as f64;
            let d = (north * phi.cos() + east * phi.sin()) * theta.sin() + up * theta.cos();
            let value = occluder
                .closest_hit(centre, d, f64::INFINITY)
                .map_or(DVec3::ZERO, |hit| {
                    let polygon = &polygons[shell.polygons[hit.polygon]];
                    let uv = polygon.uv_map.map(|m| m.at(centre + d * hit.t));
                    materials[polygon.material].kd_at(uv)
                });
            texels.push(value.as_vec3().to_array());
        }
    }
    let luminance = |v: DVec3| v.dot(DVec3::new(0.2126, 0.7152, 0.0722));
    let unscaled = EnvMap::new(columns, rows, texels.clone(), 1.0, 0.0).ok()?;
    let (have, want) = (
        luminance(unscaled.horizontal_irradiance()),
        luminance(sky.horizontal_irradiance()),
    );
    let scale = if have > 0.0 && want > 0.0 {
        want / have
    } else {
        1.0
    };
    let map = EnvMap::new(columns, rows, texels, scale, 0.0).ok()?;
    Sky::new(
        SkyModel::Map {
            map: std::sync::Arc::new(map),
            north,
        },
        up,
        sky.below_horizon(),
        lights.sun.as_ref(),
    )
    .ok()
}
