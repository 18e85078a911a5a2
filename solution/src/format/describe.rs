//! Human- and machine-readable descriptions of a solution file (`solver info`).

use super::layout;
use super::read::BatchInfo;
use super::texture::TextureInfo;
use super::{Header, Lighting, Representation, ScalarType, SolveMode};
use serde_json::{json, Value};

fn triple<T: std::fmt::Display>(v: &[T; 3]) -> String {
    format!("{} {} {}", v[0], v[1], v[2])
}

fn mode_name(mode: SolveMode) -> &'static str {
    match mode {
        SolveMode::Diffuse => "diffuse",
        SolveMode::Directional => "directional",
    }
}

fn representation_text(r: Representation) -> String {
    match r {
        Representation::Sh { order } => {
            let n = r.coefficients_per_channel();
            let plural = if n == 1 { "" } else { "s" };
            format!("sh L={order} ({n} coefficient{plural} per channel)")
        }
        Representation::Cube { directions } => format!("cube D={directions} directions"),
    }
}

fn scalar_text(s: ScalarType) -> String {
    match s {
        ScalarType::F32 => "f32".into(),
        ScalarType::F16 { scale } => format!("f16 (scale {scale})"),
    }
}

fn frame_name(code: u32) -> &'static str {
    match code {
        layout::FRAME_POLYGON_NTB => "polygon-ntb",
        _ => "unknown",
    }
}

fn basis_name(code: u32) -> &'static str {
    match code {
        layout::BASIS_SH_REAL_ORTHONORMAL => "sh-real-orthonormal-no-condon-shortley",
        layout::BASIS_CUBE_CELL_CENTRES => "cube-cell-centres",
        _ => "unknown",
    }
}

/// The header and batches as text, one `name: value` per line; batches follow as
/// indented blocks.
pub fn describe_text(header: &Header, batches: &[BatchInfo]) -> String {
    use std::fmt::Write;
    let mut out = String::new();
    let h = header;
    let c = &h.camera;
    let s = &h.stats;
    // Writing into a String cannot fail.
    let _ = (|| -> std::fmt::Result {
        writeln!(out, "units_per_metre: {}", h.units_per_metre)?;
        writeln!(out, "up_axis: {}", h.up_axis)?;
        writeln!(out, "recentre_offset: {}", triple(&h.recentre_offset))?;
        writeln!(out, "camera.eye: {}", triple(&c.eye))?;
        writeln!(out, "camera.target: {}", triple(&c.target))?;
        writeln!(out, "camera.up: {}", triple(&c.up))?;
        writeln!(out, "camera.fov_y_deg: {}", c.fov_y_deg)?;
        writeln!(out, "camera.image: {}x{}", c.width, c.height)?;
        writeln!(out, "bounds_min: {}", triple(&h.bounds_min))?;
        writeln!(out, "bounds_max: {}", triple(&h.bounds_max))?;
        writeln!(out, "partial: {}", h.partial)?;
        writeln!(out, "mode: {}", mode_name(h.mode))?;
        writeln!(out, "stats.shots: {}", s.shots)?;
        writeln!(out, "stats.rays: {}", s.rays)?;
        writeln!(out, "stats.seconds: {}", s.seconds)?;
        writeln!(out, "stats.unshot_fraction: {}", s.unshot_fraction)?;
        writeln!(out, "stats.emitted_power_w: {}", s.emitted_power)?;
        writeln!(out, "stats.ambient_radiance: {}", triple(&s.ambient))?;
        writeln!(out, "settings: {}", h.settings_json.replace('\n', " "))?;
        let vertices: u64 = batches.iter().map(|b| u64::from(b.vertex_count)).sum();
        let triangles: u64 = batches.iter().map(|b| u64::from(b.triangle_count())).sum();
        writeln!(out, "batches: {}", batches.len())?;
        writeln!(out, "total_vertices: {vertices}")?;
        writeln!(out, "total_triangles: {triangles}")?;
        for (i, b) in batches.iter().enumerate() {
            writeln!(out, "batch {i}:")?;
            writeln!(
                out,
                "  representation: {}",
                representation_text(b.representation)
            )?;
            writeln!(out, "  scalar: {}", scalar_text(b.scalar))?;
            writeln!(out, "  vertices: {}", b.vertex_count)?;
            writeln!(out, "  triangles: {}", b.triangle_count())?;
            writeln!(out, "  vertex_bytes: {}", b.vertex_bytes())?;
            writeln!(out, "  coefficient_bytes: {}", b.coefficient_bytes())?;
            writeln!(out, "  index_bytes: {}", b.index_bytes())?;
            writeln!(out, "  frame: {}", frame_name(b.frame_convention))?;
            writeln!(out, "  basis: {}", basis_name(b.basis_convention))?;
            if let Some(t) = b.texture {
                writeln!(out, "  texture: {}", t.texture)?;
                writeln!(out, "  texture_factor: {}", triple(&t.factor))?;
                if let Some(e) = t.emission {
                    writeln!(out, "  emission_texture: {}", e.texture)?;
                    writeln!(out, "  emission_factor: {}", triple(&e.factor))?;
                }
                writeln!(
                    out,
                    "  textured_vertex_bytes: {}",
                    b.textured_vertex_bytes()
                )?;
            }
        }
        Ok(())
    })();
    out
}

/// One batch as a JSON object.
pub fn batch_json(b: &BatchInfo) -> Value {
    let representation = match b.representation {
        Representation::Sh { order } => json!({ "kind": "sh", "order": order }),
        Representation::Cube { directions } => json!({ "kind": "cube", "directions": directions }),
    };
    let scalar = match b.scalar {
        ScalarType::F32 => json!({ "kind": "f32" }),
        ScalarType::F16 { scale } => json!({ "kind": "f16", "scale": scale }),
    };
    json!({
        "representation": representation,
        "coefficients_per_channel": b.coefficients_per_channel(),
        "scalar": scalar,
        "vertex_count": b.vertex_count,
        "index_count": b.index_count,
        "triangle_count": b.triangle_count(),
        "vertex_bytes": b.vertex_bytes(),
        "coefficient_bytes": b.coefficient_bytes(),
        "index_bytes": b.index_bytes(),
        "frame_convention": frame_name(b.frame_convention),
        "basis_convention": basis_name(b.basis_convention),
        "texture": b.texture.map(|t| json!({
            "index": t.texture,
            "factor": t.factor,
            "emission": t.emission.map(|e| json!({ "index": e.texture, "factor": e.factor })),
        })),
        "textured_vertex_bytes": b.textured_vertex_bytes(),
    })
}

/// The textures as text, one indented block each (nothing when there are none).
pub fn describe_textures_text(textures: &[TextureInfo]) -> String {
    let mut out = String::new();
    if textures.is_empty() {
        return out;
    }
    out.push_str(&format!("textures: {}\n", textures.len()));
    for (k, t) in textures.iter().enumerate() {
        out.push_str(&format!(
            "texture {k}:\n  size: {}x{}\n  encoding: png-srgb8\n  encoded_bytes: {}\n  decoded_bytes: {}\n",
            t.width,
            t.height,
            t.encoded_bytes,
            t.decoded_bytes()
        ));
    }
    out
}

/// The textures as a JSON array.
pub fn textures_json(textures: &[TextureInfo]) -> Value {
    Value::Array(
        textures
            .iter()
            .map(|t| {
                json!({
                    "width": t.width,
                    "height": t.height,
                    "encoding": "png-srgb8",
                    "encoded_bytes": t.encoded_bytes,
                    "decoded_bytes": t.decoded_bytes(),
                })
            })
            .collect(),
    )
}

/// The header and batches as one JSON object. The settings appear parsed under
/// `settings` when they are JSON (as the solver writes them), else as a string.
pub fn describe_json(header: &Header, batches: &[BatchInfo]) -> Value {
    let h = header;
    let c = &h.camera;
    let s = &h.stats;
    let settings = serde_json::from_str::<Value>(&h.settings_json)
        .unwrap_or_else(|_| Value::String(h.settings_json.clone()));
    json!({
        "units_per_metre": h.units_per_metre,
        "up_axis": h.up_axis.to_string(),
        "recentre_offset": h.recentre_offset,
        "camera": {
            "eye": c.eye,
            "target": c.target,
            "up": c.up,
            "fov_y_deg": c.fov_y_deg,
            "width": c.width,
            "height": c.height,
        },
        "bounds_min": h.bounds_min,
        "bounds_max": h.bounds_max,
        "partial": h.partial,
        "mode": mode_name(h.mode),
        "stats": {
            "shots": s.shots,
            "rays": s.rays,
            "seconds": s.seconds,
            "unshot_fraction": s.unshot_fraction,
            "emitted_power_w": s.emitted_power,
            "ambient_radiance": s.ambient,
        },
        "settings": settings,
        "batches": batches.iter().map(batch_json).collect::<Vec<_>>(),
    })
}

/// The lighting of a format x.1 file as text: the exposure key, the lights
/// (one line each, from the JSON record) and the environment's size and sun.
/// Empty for an x.0 file.
pub fn describe_lighting_text(lighting: Option<&Lighting>) -> String {
    use std::fmt::Write;
    let mut out = String::new();
    let Some(l) = lighting else {
        return out;
    };
    let _ = (|| -> std::fmt::Result {
        writeln!(out, "exposure_key: {}", l.exposure_key)?;
        if let Some(text) = &l.lights_json {
            match serde_json::from_str::<Value>(text) {
                Ok(v) => {
                    let list = v["lights"].as_array().cloned().unwrap_or_default();
                    writeln!(out, "lights: {}", list.len())?;
                    for light in list {
                        writeln!(out, "  {light}")?;
                    }
                    if let Some(p) = v.get("power_into_scene") {
                        writeln!(out, "lights.power_into_scene: {p}")?;
                    }
                }
                Err(_) => writeln!(out, "lights: {}", text.replace('\n', " "))?,
            }
        }
        if let Some(env) = &l.environment {
            writeln!(out, "environment: {}x{} RGB f32", env.width, env.height)?;
            if let Some(sun) = &env.sun {
                writeln!(out, "environment.sun.direction: {}", triple(&sun.direction))?;
                writeln!(
                    out,
                    "environment.sun.angular_diameter_deg: {}",
                    sun.angular_diameter_deg
                )?;
                writeln!(out, "environment.sun.radiance: {}", triple(&sun.radiance))?;
            }
        }
        Ok(())
    })();
    out
}

/// The lighting as a JSON object (`null` for an x.0 file); the lights record
/// parsed when it is JSON.
pub fn lighting_json(lighting: Option<&Lighting>) -> Value {
    let Some(l) = lighting else {
        return Value::Null;
    };
    let lights = l
        .lights_json
        .as_ref()
        .map(|t| serde_json::from_str::<Value>(t).unwrap_or_else(|_| Value::String(t.clone())));
    let environment = l.environment.as_ref().map(|e| {
        json!({
            "width": e.width,
            "height": e.height,
            "texels": "RGB f32",
            "sun": e.sun.map(|s| json!({
                "direction": s.direction,
                "angular_diameter_deg": s.angular_diameter_deg,
                "radiance": s.radiance,
            })),
        })
    });
    json!({
        "exposure_key": l.exposure_key,
        "lights": lights,
        "environment": environment,
    })
}
