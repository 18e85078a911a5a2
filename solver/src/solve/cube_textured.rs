//! Textured surfaces in the global-cube method (`--directional cube`,
//! [`super::cube_gather`]), around it rather than inside it.
//!
//! The cube gather keeps one radiance per diffuse vertex and reflects a
//! patch's area-weighted vertex radiance; giving it the E/π representation
//! and ∫ρE reflection of the other solves (`textured.rs`) would change its
//! unknowns and its reflection step. Instead, at the least cost:
//!
//! * **Transport** uses each textured material's mean reflectance, Kd ⊙ the
//!   texture's mean (what directional mode did before it modelled
//!   textures): the light a textured patch reflects is right on average over
//!   the texture, not per patch, so where a patch covers mostly dark or
//!   mostly light texels its reflected light is off by that patch's
//!   deviation from the mean.
//! * **Display** is textured for diffuse textured surfaces (Ks = 0): their
//!   vertices move out of the order-0 batch into a textured SH batch (format
//!   2 allows textured SH batches beside cube batches) holding E/π =
//!   (L − Le) / (Kd ⊙ mean), the light the vertex received, so the file shows
//!   ρ(uv) ⊙ E/π as in the other modes. A glossy textured surface (Ks > 0)
//!   is a cube batch, which cannot be textured: it stays at its mean
//!   reflectance, with a warning.
//! * **Emission textures** are honoured in the transport: each patch of the
//!   emitter emits its texel-integrated mean Le (`cube_gather/emission.rs`).
//!   A diffuse emitter's vertices are shown as the progressive solves show
//!   them (docs/solution-format.md, "Emission textures"): a textured order-0
//!   batch with the emission texture, factor Ke, "E/π" 1 and SH holding what
//!   it reflects, L − m̄ with m̄ the surface's mean Le. A glossy emitter is a
//!   cube batch at its mean Le, with a warning.

use super::cube_gather::{solve_cube, CubeError, CubeLimits, CubeResult};
use super::textured::SurfaceTexturing;
use crate::mesh::{Mesh, Sizing};
use crate::scene::{Material, Scene};
use crate::settings::SolverSettings;
use glam::DVec3;
use solution::format::{Batch, TexturedVertex, Texturing};
use std::f64::consts::PI;

/// [`solve_cube`] with textured surfaces handled as the module notes say;
/// returns the result and the warnings to show (none for an untextured
/// scene, which is solved exactly as by [`solve_cube`]).
pub fn solve_cube_textured(
    scene: &Scene,
    settings: &SolverSettings,
    limits: &CubeLimits,
) -> Result<(CubeResult, Vec<String>), CubeError> {
    let textured_materials = materials_with_uvs(scene, |m| m.diffuse_texture.is_some());
    let emitters = materials_with_uvs(scene, |m| m.emission_texture.is_some());
    if textured_materials.is_empty() && emitters.is_empty() {
        return Ok((solve_cube(scene, settings, limits)?, Vec::new()));
    }
    let mut mean_scene = scene.clone();
    for &m in &textured_materials {
        let material = &mut mean_scene.materials[m];
        if let Some(t) = material.diffuse_texture.take() {
            material.kd *= t.texture.mean();
        }
    }
    let mut result = solve_cube(&mean_scene, settings, limits)?;
    let mut warnings = Vec::new();
    let glossy: Vec<&str> = textured_materials
        .iter()
        .map(|&m| &scene.materials[m])
        .filter(|m| m.is_glossy())
        .map(|m| m.name.as_str())
        .collect();
    if !glossy.is_empty() {
        warnings.push(format!(
            "global cubes: textured glossy material(s) {} are shown and reflect with Kd times \
             their texture's mean (a cube batch cannot be textured); `--directional sh` models \
             their textures",
            glossy.join(", ")
        ));
    }
    if !textured_materials.is_empty() {
        warnings.push(
            "global cubes: textured surfaces reflect light with Kd times their texture's mean \
             (their display is textured); the progressive solves integrate the texture per patch"
                .to_owned(),
        );
    }
    let glossy_emitters: Vec<&str> = emitters
        .iter()
        .map(|&m| &scene.materials[m])
        .filter(|m| m.is_glossy())
        .map(|m| m.name.as_str())
        .collect();
    if !glossy_emitters.is_empty() {
        warnings.push(format!(
            "global cubes: glossy material(s) {} emit their emission texture per patch but are \
             shown at their mean emitted radiance (a cube batch cannot be textured); \
             `--directional sh` shows the texture",
            glossy_emitters.join(", ")
        ));
    }
    texture_diffuse_batch(scene, settings, &mean_scene, &mut result);
    Ok((result, warnings))
}

/// The materials for which `has` holds (a diffuse or an emission texture)
/// that some polygon with UVs uses (the surfaces [`SurfaceTexturing::new`]
/// gives a texture).
fn materials_with_uvs(scene: &Scene, has: impl Fn(&Material) -> bool) -> Vec<usize> {
    (0..scene.materials.len())
        .filter(|&m| {
            has(&scene.materials[m])
                && scene
                    .polygons
                    .iter()
                    .any(|p| p.material == m && p.uv_map.is_some())
        })
        .collect()
}

/// Moves the diffuse textured and emission-textured vertices of `result`'s
/// order-0 batch into one textured batch per material (see the module notes).
fn texture_diffuse_batch(
    scene: &Scene,
    settings: &SolverSettings,
    mean_scene: &Scene,
    result: &mut CubeResult,
) {
    // The cube solve's mesh, rebuilt: the same scene geometry, offset and
    // sizing give the same mesh (meshing is deterministic).
    let offset = super::scene_centre(scene);
    let Ok(mesh) = Mesh::with_sizing(scene, offset, &Sizing::from_settings(settings, scene)) else {
        return;
    };
    if mesh.vertices.len() != result.vertex_count() {
        debug_assert!(false, "the rebuilt mesh differs from the cube solve's");
        return;
    }
    let texturing = SurfaceTexturing::new(scene, &mesh, offset);
    // Per surface the emission its vertices hold: an emission texture's
    // mean Le m̄ as in the cube gather (`cube_gather/emission.rs`), else Ke.
    let mut surface_emission: Vec<DVec3> = mesh
        .surfaces
        .iter()
        .map(|s| scene.materials[s.material].emission)
        .collect();
    super::textured::patch_emission(&texturing, &mesh, &mut surface_emission);
    // Per mesh vertex its one value when diffuse (in the order-0 batch).
    let diffuse: Vec<Option<DVec3>> = mesh
        .vertices
        .iter()
        .enumerate()
        .map(|(v, mv)| {
            (!result.is_glossy(v as u32)).then(|| result.radiance_toward(v as u32, mv.normal))
        })
        .collect();
    let solution = &mut result.solution;
    // The order-0 batch holds the vertices with one RGB value, in mesh order.
    let Some(diffuse_at) = solution
        .batches
        .iter()
        .position(|b| b.representation == solution::format::Representation::Sh { order: 0 })
    else {
        return;
    };
    let whole = solution.batches.remove(diffuse_at);
    // The cube's batches replaced the base solve's, so no batch uses the
    // textures that solve listed (an emitter's): the list is rebuilt here,
    // in the order the batches below index it.
    solution.textures.clear();
    let empty = |texturing: Option<Texturing>| Batch {
        vertices: Vec::new(),
        coefficients: Vec::new(),
        indices: Vec::new(),
        texturing,
        ..whole.clone()
    };
    let mut batches = vec![empty(None)];
    let (mut materials, mut sources) = (Vec::new(), Vec::new());
    // Per vertex of the order-0 batch: (batch, index there).
    let mut slot: Vec<(usize, u32)> = Vec::with_capacity(whole.vertices.len());
    let scale = (4.0 * PI).sqrt();
    let diffuse_vertices = diffuse
        .iter()
        .enumerate()
        .filter_map(|(v, l)| l.map(|l| (v, l)));
    for (o, (v, radiance)) in diffuse_vertices.enumerate() {
        let mv = &mesh.vertices[v];
        let Some(t) = texturing.shown(mv.surface) else {
            let b = &mut batches[0];
            slot.push((0, b.vertices.len() as u32));
            b.vertices.push(whole.vertices[o]);
            b.coefficients
                .extend_from_slice(&whole.coefficients[3 * o..3 * o + 3]);
            continue;
        };
        let material = mesh.surfaces[mv.surface as usize].material;
        let g = match materials.iter().position(|&m| m == material) {
            Some(k) => k + 1,
            None => {
                let texture =
                    super::output_textured::texture_index(&mut sources, &mut solution.textures, t);
                materials.push(material);
                batches.push(empty(Some(Texturing {
                    texture,
                    factor: t.kd.as_vec3().to_array(),
                    emission: None,
                    vertices: Vec::new(),
                })));
                materials.len()
            }
        };
        let emission = surface_emission[mv.surface as usize];
        let (coefficient, e) = if texturing.get(mv.surface).is_some() {
            let mean = mean_scene.materials[material].kd;
            // L = Le + (Kd ⊙ mean) ⊙ E/π in the cube gather.
            let received = (radiance - emission).max(DVec3::ZERO);
            let e = DVec3::select(mean.cmpgt(DVec3::ZERO), received / mean, DVec3::ZERO);
            (emission, e)
        } else {
            // An emitter: the texture shows Le(uv), the SH what it reflects.
            ((radiance - emission).max(DVec3::ZERO), DVec3::ONE)
        };
        let uv = texturing.uv(t, mv.position).as_vec2().to_array();
        let b = &mut batches[g];
        slot.push((g, b.vertices.len() as u32));
        b.vertices.push(whole.vertices[o]);
        b.coefficients
            .extend((coefficient * scale).as_vec3().to_array());
        if let Some(tb) = &mut b.texturing {
            tb.vertices.push(TexturedVertex {
                uv,
                irradiance_over_pi: e.as_vec3().to_array(),
            });
        }
    }
    super::output_textured::place_triangles_and_prepend(solution, batches, &slot, &whole.indices);
}
