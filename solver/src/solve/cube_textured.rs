//! Textured surfaces in the global-cube method (`--directional cube`,
//! [`super::cube_gather`]): what the gather does with them, and their display.
//!
//! * **Transport** is the gather's own ([`super::cube_gather`]'s `textured`
//!   module): a textured vertex stores E/π, and each patch reflects the
//!   integral of ρ · E/π over its area through the progressive solver's RGB
//!   gather weights (the texture integrated over each display triangle's UV
//!   triangle at its mip level, `crate::texture`), as the other solves do.
//!   The mesh is fixed, so there is no refinement to steer.
//! * **Display** is textured for diffuse textured surfaces (Ks = 0): their
//!   vertices move out of the order-0 batch into a textured SH batch (format
//!   2 allows textured SH batches beside cube batches) holding their E/π and
//!   their emission as the SH term, so the file shows ρ(uv) ⊙ E/π + Le as in
//!   the other modes. A glossy textured surface (Ks > 0) is a cube batch,
//!   which format 2 cannot texture: it shows, in every cell, its glossy
//!   light plus the texels' mean around each vertex times its E/π, the
//!   texture blurred to the mesh's resolution, with a warning. Its transport
//!   is per element as for a diffuse surface.
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
    let mut result = solve_cube(scene, settings, limits)?;
    let mut warnings = Vec::new();
    let glossy: Vec<&str> = textured_materials
        .iter()
        .map(|&m| &scene.materials[m])
        .filter(|m| m.is_glossy())
        .map(|m| m.name.as_str())
        .collect();
    if !glossy.is_empty() {
        warnings.push(format!(
            "global cubes: textured glossy material(s) {} reflect their texture per patch, but \
             are shown with the texture averaged around each vertex (solution format 2 cannot \
             texture a cube batch); `--directional sh` shows their textures",
            glossy.join(", ")
        ));
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
    texture_diffuse_batch(scene, settings, &mut result);
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
fn texture_diffuse_batch(scene: &Scene, settings: &SolverSettings, result: &mut CubeResult) {
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
    // Per mesh vertex in the order-0 batch (the diffuse ones), its one
    // value and, on a diffuse textured surface, its E/π.
    let diffuse: Vec<Option<(DVec3, Option<DVec3>)>> = mesh
        .vertices
        .iter()
        .enumerate()
        .map(|(v, mv)| {
            let v = v as u32;
            (!result.is_glossy(v)).then(|| {
                (
                    result.radiance_toward(v, mv.normal),
                    result.irradiance_over_pi(v),
                )
            })
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
    for (o, (v, (radiance, irradiance))) in diffuse_vertices.enumerate() {
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
        let (coefficient, e) = match irradiance {
            // A diffuse textured vertex: the texture shows ρ(uv) ⊙ E/π, the
            // SH its emission.
            Some(e) => (emission, e),
            // An emitter: the texture shows Le(uv), the SH what it reflects.
            None => ((radiance - emission).max(DVec3::ZERO), DVec3::ONE),
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
