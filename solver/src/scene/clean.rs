//! From parsed input to a [`Scene`]: re-centring, polygon cleaning, material
//! checks (Kd + Ks ≤ 1), welding, and the whole-scene checks (empty scene, no
//! emitter, strict mode).
//!
//! Cleaning follows the design notes ("Local frames and SH"): real files are
//! imperfect, so import what a user would expect and say what was changed.
//! Each change gives a [`Warning`] naming the polygon, whose message starts
//! with a fixed phrase (tests and users can search for it):
//!
//! | phrase | what happened |
//! | --- | --- |
//! | `repeated vertices` | coincident consecutive vertices removed |
//! | `collinear vertices` | vertices on a straight edge removed |
//! | `degenerate polygon` | fewer than 3 vertices remained: skipped |
//! | `zero-area polygon` | area ≈ 0 relative to its size: skipped |
//! | `self-intersecting polygon` | edges cross: skipped |
//! | `non-planar polygon` | beyond [`PLANARITY_TOLERANCE`]: split into triangles |
//! | `vertex normals` | shading normals against the winding: dropped |
//! | `Kd + Ks > 1` | both scaled down to sum 1 in that channel |
//! | `material ... defined in no mtllib` | default material used |

use super::planar::{bbox_diagonal, is_simple, max_plane_deviation, project};
use super::raw::{RawMaterial, RawPolygon, RawScene};
use super::recentre::recentre;
use super::text::{rgb, short};
use super::weld::weld;
use super::{Material, Polygon, Scene, SceneError, SourceRef, Warning};
use crate::geometry::polygon::{ear_clip, newell_normal};
use crate::light::portal_detect::{detect_portals, PortalMode};
use crate::light::Lights;
use glam::DVec3;
use solution::camera::{Camera, UpAxis};

/// A polygon is planar enough to keep as one when no vertex lies farther from its
/// Newell plane than this fraction of its bounding-box diagonal. Beyond it, it is
/// split into triangles. At 5e-3 the two halves of a bent quad differ in normal
/// by about 4 × 5e-3 rad ≈ 1°; the Cornell box's red wall (0.80 mm on a 784 mm
/// diagonal, 1.0e-3) is kept whole.
pub const PLANARITY_TOLERANCE: f64 = 5e-3;
/// Consecutive vertices closer than this fraction of the scene's bounding-box
/// diagonal are the same vertex repeated.
pub const REPEATED_VERTEX_TOLERANCE: f64 = 1e-9;
/// A vertex is collinear with its neighbours when its distance from the chord
/// joining them is at most this fraction of the chord's length (an angle of
/// about 2e-6 rad), far above f64 rounding of exact collinear input.
pub const COLLINEAR_TOLERANCE: f64 = 1e-6;
/// A polygon whose area is at most this fraction of its squared bounding-box
/// diagonal has zero area (a bow-tie that cancels, a sliver of rounding).
pub const ZERO_AREA_TOLERANCE: f64 = 1e-10;
/// Vertex normals within this angle of the facet normal at every corner mean a
/// flat polygon: they are dropped and the facet normal is used. 0.1° is far above
/// the rounding of normals written with 6 decimals (about 1e-6 rad) and below the
/// half-facet angle of any tessellation meant to look smooth (a sphere's facets
/// would have to span under 0.2°, some 1800 segments around, to come under it).
pub const SMOOTH_NORMAL_DEGREES: f64 = 0.1;

/// The most vertices one input polygon (an OBJ face, a legacy polygon line)
/// may have. Importing checks that a polygon is simple by testing every pair
/// of its edges, and meshing ear-clips a non-convex one: both are O(n²) in the
/// vertex count. At 8,192 vertices the worst shapes measured (a 4,096-tooth
/// comb, a star, a spiral band, each one face under a lamp) import, mesh and
/// solve at the draft preset in 1 to 3 s in the dev profile on two cores; a
/// 200,000-vertex disc, (200,000 / 8,192)² ≈ 600 times that work, gave no
/// output in 120 s. A face this large is a finely sampled curve: splitting or
/// triangulating it in the modelling tool loses nothing radiosity sees.
pub const MAX_POLYGON_VERTICES: usize = 8192;

/// The largest emitted radiance accepted, W·sr⁻¹·m⁻² in any channel. The
/// solution stores radiance (and its SH coefficients) as f32, whose largest
/// value is 3.4e38; the solve sums power as radiance × area × π in f64, which
/// does not bind. A surface's radiance is its emission plus what it reflects,
/// at most Le / (1 − ρ) for reflectance ρ (Kd + Ks ≤ 1, enforced below), so
/// 1e30 leaves a factor 3.4e8 for interreflection, the SH projection's
/// constant factors (√(4π) ≈ 3.5 for the mean) and sums over vertices before
/// anything overflows f32. The brightest natural source, the Sun's disc, is
/// about 2e7 W·sr⁻¹·m⁻²: no physical scene comes near the bound, and an
/// `Ke 1e39` (above f32's range) is a typing slip refused at import rather
/// than when the solution is written, after the whole solve.
pub const MAX_EMISSION: f64 = 1e30;

/// What is wrong with an emitted radiance, if anything: non-finite, negative
/// or above [`MAX_EMISSION`] in some channel.
pub(crate) fn emission_problem(value: DVec3) -> Option<String> {
    let shown = || format!("({:e}, {:e}, {:e})", value.x, value.y, value.z);
    if !value.is_finite() {
        Some(format!("must be finite, is {}", shown()))
    } else if value.min_element() < 0.0 {
        Some(format!("must not be negative, is {}", shown()))
    } else if value.max_element() > MAX_EMISSION {
        Some(format!(
            "{} exceeds {MAX_EMISSION:e} W·sr⁻¹·m⁻², the largest emitted radiance accepted \
             (the solution's radiance is f32, at most 3.4e38, and light reflected between \
             surfaces adds to the emission)",
            shown()
        ))
    } else {
        None
    }
}

/// Scene-wide inputs that do not come from the geometry files.
pub(crate) struct BuildOptions {
    pub strict: bool,
    pub default_patches: u32,
    pub units_per_metre: f64,
    pub up_axis: UpAxis,
    pub camera: Option<Camera>,
    /// The sun, sky and lamps, in the input's original coordinates.
    pub lights: Lights,
    /// Whether to find sky portals in the geometry (`[sky] portals`).
    pub portal_mode: PortalMode,
    /// Whether the input is a TOML scene config (for the no-emitter hint).
    pub from_config: bool,
}

/// Turns parsed input into a scene (the module comment lists the steps).
pub(crate) fn build_scene(mut raw: RawScene, options: &BuildOptions) -> Result<Scene, SceneError> {
    let files = describe_files(&raw.files);
    if raw.polygons.is_empty() {
        return Err(SceneError::Empty(format!("{files}: no polygons")));
    }
    let input_count = raw.polygons.len();
    let (recentre_offset, diagonal) = recentre(&mut raw.polygons);
    let mut warnings = std::mem::take(&mut raw.warnings);

    let mut polygons = Vec::with_capacity(raw.polygons.len());
    // UVs matter only where a material has a texture.
    let textured: Vec<bool> = raw
        .materials
        .iter()
        .map(|m| m.diffuse_map.is_some() || m.emission_map.is_some() || m.metal_map.is_some())
        .collect();
    for mut polygon in std::mem::take(&mut raw.polygons) {
        if !textured.get(polygon.material).copied().unwrap_or(false) {
            polygon.uvs = None;
        }
        clean_polygon(
            polygon,
            diagonal,
            options.default_patches,
            &mut polygons,
            &mut warnings,
        );
    }
    if polygons.is_empty() {
        return Err(SceneError::Empty(format!(
            "{files}: all {input_count} polygons were degenerate or had zero area{}",
            warnings
                .iter()
                .find(|w| w.message.contains("polygon"))
                .map(|w| format!(" (first: {w})"))
                .unwrap_or_default()
        )));
    }
    weld(&mut polygons, diagonal);
    // Welding merges pairs of triangles into quads, so a triangle mesh keeps
    // about half the polygons it was reserved (and filled) for; the scene
    // lives for the whole solve and the memory estimate counts it by length
    // (`solve::budget::scene_bytes`): about 100 MiB of the 1M Cornell boxes' peak.
    polygons.shrink_to_fit();

    let unlit_polygons: Vec<bool> = polygons
        .iter()
        .map(|p| raw.materials.get(p.material).is_some_and(|m| m.unlit))
        .collect();
    let materials = finish_materials(&raw.materials, &mut polygons, &mut warnings)?;
    let mut unlit = vec![false; materials.len()];
    for (p, &u) in polygons.iter().zip(&unlit_polygons) {
        unlit[p.material] |= u;
    }
    let mut lights = options.lights.recentred(recentre_offset);
    super::skybox::handle_enclosing_shell(
        &mut polygons,
        &materials,
        &unlit,
        &mut lights,
        diagonal,
        &mut warnings,
    );
    if options.lights.is_empty() && !polygons.iter().any(|p| materials[p.material].is_emitter()) {
        let names: Vec<&str> = materials.iter().map(|m| m.name.as_str()).collect();
        return Err(SceneError::NoEmitter(format!(
            "{files}: none of the materials in use ({}) emits light and the scene has no \
             lights, so the solution would be black. {}",
            names.join(", "),
            super::emitter_hint::no_emitter_hint(&raw.files, options.from_config)
        )));
    }
    if options.strict {
        if let Some(first) = warnings.first() {
            return Err(SceneError::Strict {
                warning: first.clone(),
                others: warnings.len() - 1,
            });
        }
    }
    if let Some(note) = detect_sky_portals(&mut lights, &polygons, diagonal, options.portal_mode) {
        // After the strict check: a note on which openings became portals
        // is no fault of the input.
        let source = SourceRef {
            file: raw.files.first().cloned().unwrap_or_default(),
            line: None,
            item: "sky portals".to_owned(),
        };
        warn(&mut warnings, &source, note);
    }
    Ok(Scene {
        lights,
        polygons,
        materials,
        units_per_metre: options.units_per_metre,
        up_axis: options.up_axis,
        camera: options.camera,
        recentre_offset,
        warnings,
    })
}

/// Gives a scene with a sky and no declared portals the portals of its
/// geometry's openings (`light::portal_detect`), in the polygons' frame,
/// unless `mode` turns detection off; returns detection's note.
fn detect_sky_portals(
    lights: &mut Lights,
    polygons: &[Polygon],
    diagonal: f64,
    mode: PortalMode,
) -> Option<String> {
    if lights.sky.is_none() || !lights.portals.is_empty() || mode == PortalMode::Off {
        return None;
    }
    let rings: Vec<&[DVec3]> = polygons.iter().map(|p| p.vertices.as_slice()).collect();
    let found = detect_portals(&rings, diagonal);
    lights.portals = found.portals;
    found.note
}

/// A product Kd ⊙ mean(texture) whose brightest channel is below this is
/// "very dark" (2% reflectance: darker than charcoal), worth a warning since
/// a texture over a small Kd is usually an exporter's placeholder Kd.
pub const DARK_TEXTURE: f64 = 0.02;

/// Reads material `index`'s `map_Kd` (`raw.diffuse_map`) when some polygon
/// using it has UVs, with warnings for a texture that is not used, cannot be
/// read, or makes a very dark product. An emitter's `map_Kd` is read too: its
/// surface reflects and shows ρ(uv) like any diffuse-textured one, beside its
/// emission (flat Ke, or `map_Ke` in the second texture slot of the solution
/// file).
fn diffuse_texture(
    raw: &RawMaterial,
    (kd, ks): (DVec3, DVec3),
    index: usize,
    polygons: &[Polygon],
    warnings: &mut Vec<Warning>,
) -> Option<std::sync::Arc<super::SceneTexture>> {
    let (file, at) = raw.diffuse_map.as_ref()?;
    if !some_user_has_uvs(raw, index, polygons, ("map_Kd", "Kd"), file, at, warnings) {
        return None;
    }
    let texture = super::texture_file::load_texture(
        file,
        raw.diffuse_bytes.as_deref(),
        at,
        "map_Kd",
        warnings,
    )?;
    let product = kd * texture.texture.mean();
    // Not dark when its glossy lobe reflects: a glTF metal (Kd 0) shows its
    // Ks ⊙ texture in either mode (diffuse mode folds Ks into the factor,
    // `Material::diffuse_equivalent_kd`).
    let reflected = (kd + ks).min(DVec3::ONE) * texture.texture.mean();
    if reflected.max_element() < DARK_TEXTURE {
        warn(
            warnings,
            at,
            format!(
                "map_Kd texture {}: Kd {} times the texture's mean {} is a very dark reflectance ({}); \
                 the MTL convention (Kd multiplies the texture) is followed, so the surface is dark. \
                 Set Kd 1 1 1 if the texture alone is meant",
                file.display(),
                rgb(kd),
                rgb(texture.texture.mean()),
                rgb(product)
            ),
        );
    }
    Some(texture)
}

/// Reads material `index`'s `map_Ke` (`raw.emission_map`) when it emits and
/// some polygon using it has UVs, with warnings for a texture that is not
/// used or cannot be read (the flat Ke is then used).
fn emission_texture(
    raw: &RawMaterial,
    index: usize,
    polygons: &[Polygon],
    warnings: &mut Vec<Warning>,
) -> Option<std::sync::Arc<super::SceneTexture>> {
    let (file, at) = raw.emission_map.as_ref()?;
    if raw.emission == DVec3::ZERO {
        // Ke 0 0 0 times any texture emits nothing (warned by the parser).
        return None;
    }
    if !some_user_has_uvs(raw, index, polygons, ("map_Ke", "Ke"), file, at, warnings) {
        return None;
    }
    super::texture_file::load_texture(file, raw.emission_bytes.as_deref(), at, "map_Ke", warnings)
}

/// Whether some polygon using material `index` has UVs, so that its texture
/// (`statement`, e.g. `map_Kd`, multiplying the flat `factor`) can be used;
/// if none has, a warning naming the first user says the flat factor is used.
pub(super) fn some_user_has_uvs(
    raw: &RawMaterial,
    index: usize,
    polygons: &[Polygon],
    (statement, factor): (&str, &str),
    file: &std::path::Path,
    at: &SourceRef,
    warnings: &mut Vec<Warning>,
) -> bool {
    let mut users = polygons.iter().filter(|p| p.material == index);
    if users.clone().any(|p| p.uv_map.is_some()) {
        return true;
    }
    let first = users
        .next()
        .map(|p| format!(" (first: {})", p.source))
        .unwrap_or_default();
    warn(
        warnings,
        at,
        format!(
            "{statement} texture {}: no face using material `{}` has texture coordinates (`vt`){first}; \
             the flat {factor} is used",
            file.display(),
            raw.name
        ),
    );
    false
}

fn describe_files(files: &[std::path::PathBuf]) -> String {
    let names: Vec<String> = files.iter().map(|f| f.display().to_string()).collect();
    if names.is_empty() {
        "the scene".to_owned()
    } else {
        names.join(", ")
    }
}

fn warn(warnings: &mut Vec<Warning>, source: &SourceRef, message: String) {
    warnings.push(Warning {
        source: source.clone(),
        message,
    });
}

/// Removes consecutive (and first/last) vertices closer than `eps`.
fn remove_repeated(vertices: &mut Vec<DVec3>, normals: &mut Option<Vec<DVec3>>, eps: f64) -> usize {
    let mut keep = vec![true; vertices.len()];
    let mut last: Option<usize> = None;
    for i in 0..vertices.len() {
        if let Some(l) = last {
            if (vertices[i] - vertices[l]).length() <= eps {
                keep[i] = false;
                continue;
            }
        }
        last = Some(i);
    }
    // Close the loop: the last kept vertex against the first.
    let first = keep.iter().position(|&k| k);
    while let (Some(f), Some(l)) = (first, keep.iter().rposition(|&k| k)) {
        if l == f || (vertices[l] - vertices[f]).length() > eps {
            break;
        }
        keep[l] = false;
    }
    retain(vertices, normals, &keep)
}

fn retain(vertices: &mut Vec<DVec3>, normals: &mut Option<Vec<DVec3>>, keep: &[bool]) -> usize {
    let removed = keep.iter().filter(|&&k| !k).count();
    if removed > 0 {
        let mut k = keep.iter();
        vertices.retain(|_| *k.next().unwrap_or(&true));
        if let Some(n) = normals {
            let mut k = keep.iter();
            n.retain(|_| *k.next().unwrap_or(&true));
        }
    }
    removed
}

/// Removes, one at a time, vertices that lie on the chord between their
/// neighbours (including spikes that double back). Returns how many.
fn remove_collinear(
    vertices: &mut Vec<DVec3>,
    normals: &mut Option<Vec<DVec3>>,
    eps: f64,
) -> usize {
    let mut removed = 0;
    'scan: while vertices.len() >= 3 {
        let n = vertices.len();
        for i in 0..n {
            let a = vertices[(i + n - 1) % n];
            let b = vertices[i];
            let c = vertices[(i + 1) % n];
            let chord = c - a;
            let length = chord.length();
            let collinear = if length <= eps {
                true // a spike a → b → a
            } else {
                (b - a).cross(chord).length() / length <= COLLINEAR_TOLERANCE * length
            };
            if collinear {
                let mut keep = vec![true; n];
                keep[i] = false;
                retain(vertices, normals, &keep);
                removed += 1;
                remove_repeated(vertices, normals, eps);
                continue 'scan;
            }
        }
        break;
    }
    removed
}

/// Cleans one polygon and appends what survives (itself, its triangles, or
/// nothing) to `out`, with a warning for each change.
fn clean_polygon(
    raw: RawPolygon,
    scene_diagonal: f64,
    default_patches: u32,
    out: &mut Vec<Polygon>,
    warnings: &mut Vec<Warning>,
) {
    let source = raw.source;
    let original_count = raw.vertices.len();
    // The UVs belong to the vertices as given: the map is fitted to those
    // (removing repeated or collinear corners leaves an affine map unchanged).
    let raw_vertices = raw.vertices.clone();
    let mut vertices = raw.vertices;
    let mut normals = raw.normals;
    let eps = REPEATED_VERTEX_TOLERANCE * scene_diagonal;
    let repeated = remove_repeated(&mut vertices, &mut normals, eps);
    let collinear = remove_collinear(&mut vertices, &mut normals, eps);
    if vertices.len() < 3 {
        warn(
            warnings,
            &source,
            format!(
                "degenerate polygon: {original_count} vertices, of which fewer than 3 are distinct and not collinear; skipped"
            ),
        );
        return;
    }
    if repeated > 0 {
        warn(
            warnings,
            &source,
            format!("repeated vertices: removed {repeated} repeated vertex position(s); {} vertices remain", vertices.len()),
        );
    }
    if collinear > 0 {
        warn(
            warnings,
            &source,
            format!("collinear vertices: removed {collinear} vertex(es) lying on a straight edge; {} vertices remain", vertices.len()),
        );
    }
    let n = newell_normal(&vertices);
    let area = 0.5 * n.length();
    let size = bbox_diagonal(&vertices);
    if area <= ZERO_AREA_TOLERANCE * size * size {
        warn(
            warnings,
            &source,
            format!(
                "zero-area polygon: area {} for a size of {}; skipped",
                short(area),
                short(size)
            ),
        );
        return;
    }
    let normal = n / n.length();
    let projected = project(&vertices, normal);
    if !is_simple(&projected) {
        warn(
            warnings,
            &source,
            "self-intersecting polygon: its edges cross; skipped".to_owned(),
        );
        return;
    }
    let patches = raw.patches.unwrap_or(default_patches);
    let sizes = raw.sizes;
    let uv_map = raw
        .uvs
        .as_ref()
        .and_then(|uvs| fit_uvs(&raw_vertices, uvs, normal, &source, warnings));
    let deviation = max_plane_deviation(&vertices, normal);
    if deviation <= PLANARITY_TOLERANCE * size {
        let vertex_normals = shading_normals(normals, &vertices, normal, &source, warnings);
        out.push(Polygon {
            vertices,
            vertex_normals,
            material: raw.material,
            uv_map,
            patches,
            sizes,
            source,
        });
        return;
    }
    let triangles = ear_clip(&projected);
    warn(
        warnings,
        &source,
        format!(
            "non-planar polygon: a vertex lies {} from its plane, {:.2e} of its size (tolerance {PLANARITY_TOLERANCE:.0e}); split into {} triangles",
            short(deviation),
            deviation / size,
            triangles.len()
        ),
    );
    for t in triangles {
        let tv: Vec<DVec3> = t.iter().map(|&i| vertices[i]).collect();
        let tn = newell_normal(&tv);
        let t_size = bbox_diagonal(&tv);
        if 0.5 * tn.length() <= ZERO_AREA_TOLERANCE * t_size * t_size {
            continue;
        }
        let t_normals = normals.as_ref().map(|n| t.iter().map(|&i| n[i]).collect());
        let vertex_normals = shading_normals(t_normals, &tv, tn.normalize(), &source, warnings);
        out.push(Polygon {
            vertices: tv,
            vertex_normals,
            material: raw.material,
            uv_map,
            patches,
            sizes,
            source: source.clone(),
        });
    }
}

/// The polygon's affine UV map ([`super::uv`]), with a warning when its UVs
/// are not an affine image of it (fitted by least squares) or unusable.
fn fit_uvs(
    vertices: &[DVec3],
    uvs: &[glam::DVec2],
    normal: DVec3,
    source: &SourceRef,
    warnings: &mut Vec<Warning>,
) -> Option<super::UvMap> {
    match super::UvMap::fit(vertices, uvs, normal) {
        Some((map, miss)) => {
            if miss > super::uv::AFFINE_TOLERANCE {
                warn(
                    warnings,
                    source,
                    format!(
                        "texture coordinates: not an affine image of the polygon (a corner misses the \
                         best planar fit by {:.1e} of the UV span); the fit is used, so the texture \
                         is placed slightly differently than in tools that split the face into triangles",
                        miss
                    ),
                );
            }
            Some(map)
        }
        None => {
            warn(
                warnings,
                source,
                "texture coordinates: not finite or degenerate; the polygon is untextured"
                    .to_owned(),
            );
            None
        }
    }
}

/// Keeps the input's vertex normals when they describe a curved surface (some
/// corner differs from the facet normal by more than [`SMOOTH_NORMAL_DEGREES`]),
/// normalised; drops them for flat polygons and, with a warning, when they point
/// against the winding (the winding decides the front, design notes).
fn shading_normals(
    normals: Option<Vec<DVec3>>,
    vertices: &[DVec3],
    facet: DVec3,
    source: &SourceRef,
    warnings: &mut Vec<Warning>,
) -> Option<Vec<DVec3>> {
    let normals = normals?;
    debug_assert_eq!(normals.len(), vertices.len());
    let unit: Vec<DVec3> = normals.iter().map(|n| n.normalize_or_zero()).collect();
    if unit.contains(&DVec3::ZERO) {
        warn(
            warnings,
            source,
            "vertex normals: a vertex normal has zero length; the facet normal is used".to_owned(),
        );
        return None;
    }
    let cos_smooth = SMOOTH_NORMAL_DEGREES.to_radians().cos();
    if unit.iter().all(|n| n.dot(facet) >= cos_smooth) {
        return None;
    }
    if unit.iter().any(|n| n.dot(facet) <= 0.0) {
        warn(
            warnings,
            source,
            "vertex normals: they point against the face's winding; the winding decides the front and the facet normal is used".to_owned(),
        );
        return None;
    }
    Some(unit)
}

/// Validates the materials that polygons use, scales Kd + Ks down to 1 where it
/// exceeds 1, gives pending warnings, merges identical duplicates, renames
/// differing ones, and re-indexes the polygons to the compacted list.
fn finish_materials(
    raw: &[RawMaterial],
    polygons: &mut [Polygon],
    warnings: &mut Vec<Warning>,
) -> Result<Vec<Material>, SceneError> {
    let mut used = vec![false; raw.len()];
    for p in polygons.iter() {
        used[p.material] = true;
    }
    let mut remap = vec![usize::MAX; raw.len()];
    let mut out: Vec<Material> = Vec::new();
    for (i, m) in raw.iter().enumerate() {
        if !used[i] {
            continue;
        }
        let at = m.overridden_at.as_ref().unwrap_or(&m.source);
        let bad = |what: &str, v: String| {
            Err(SceneError::Input {
                at: at.clone(),
                message: format!("material `{}`: {what} {v}", m.name),
            })
        };
        for (what, v) in [("Kd", m.kd), ("Ks", m.ks)] {
            if !v.is_finite() || v.min_element() < 0.0 {
                return bad(
                    what,
                    format!("must be finite and non-negative, is {}", rgb(v)),
                );
            }
        }
        if let Some(problem) = emission_problem(m.emission) {
            return bad("emission", problem);
        }
        if !(m.alpha.is_finite() && m.alpha > 0.0) {
            return bad("alpha", format!("must be finite and > 0, is {}", m.alpha));
        }
        if let Some((at, message)) = &m.unread_reflectance_file {
            return Err(SceneError::Input {
                at: at.clone(),
                message: message.clone(),
            });
        }
        if let Some(w) = &m.undefined {
            warnings.push(w.clone());
        }
        warnings.extend(m.unmodelled.iter().cloned());
        // glTF's metallic-roughness texture sets the material's Kd, Ks and α
        // from its means (`metal_texture`), before the sum is checked.
        let metal = super::metal_texture::read(m, i, polygons, warnings);
        let (raw_kd, raw_ks, alpha) = match &metal {
            Some(metal) => (metal.kd, metal.ks, metal.alpha),
            None => (m.kd, m.ks, m.alpha),
        };
        let (mut kd, mut ks) = (raw_kd, raw_ks);
        let sum = kd + ks;
        if sum.max_element() > 1.0 {
            // Design notes, "Units and conventions": reflectance ≥ 1 never converges
            // in a closed scene; scale both down to sum 1 in each offending channel.
            let scale = DVec3::select(sum.cmpgt(DVec3::ONE), DVec3::ONE / sum, DVec3::ONE);
            kd *= scale;
            ks *= scale;
            let overridden = m
                .overridden_at
                .as_ref()
                .map(|o| format!(" (values from {o})"))
                .unwrap_or_default();
            warnings.push(Warning {
                source: m.source.clone(),
                message: format!(
                    "Kd + Ks > 1 in material `{}`: Kd {} + Ks {} = {}{overridden}; both scaled by {} to Kd {}, Ks {}",
                    m.name,
                    rgb(raw_kd),
                    rgb(raw_ks),
                    rgb(sum),
                    rgb(scale),
                    rgb(kd),
                    rgb(ks)
                ),
            });
        }
        let diffuse_texture = diffuse_texture(m, (kd, ks), i, polygons, warnings);
        let emission_texture = emission_texture(m, i, polygons, warnings);
        let folded_texture = metal.and_then(|metal| metal.fold(diffuse_texture.as_deref()));
        let material = Material {
            name: m.name.clone(),
            kd,
            ks,
            alpha,
            emission: m.emission,
            diffuse_texture,
            emission_texture,
            folded_texture,
        };
        // The same name twice (two files, or an MTL that redefines it): share one
        // entry when identical, else tell them apart by their file.
        if let Some(j) = out.iter().position(|o| *o == material) {
            remap[i] = j;
            continue;
        }
        let mut material = material;
        if out.iter().any(|o| o.name == material.name) {
            let file = m
                .source
                .file
                .file_name()
                .map(|f| f.to_string_lossy().into_owned())
                .unwrap_or_default();
            material.name = match m.source.line {
                Some(line) => format!("{} ({file}:{line})", material.name),
                None => format!("{} ({file})", material.name),
            };
        }
        remap[i] = out.len();
        out.push(material);
    }
    for p in polygons.iter_mut() {
        p.material = remap[p.material];
    }
    Ok(out)
}
