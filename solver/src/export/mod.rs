//! glTF 2.0 export of a solved scene (`solver export`; the command line is
//! `cli/export.rs`, the description `docs/gltf.md`, "Export"). Pure: the glTF
//! JSON and its binary buffer are built in memory from a solution's header and
//! its batches' bytes; files are the caller's.
//!
//! Per exported batch (batches without triangles are skipped), one mesh with
//! one triangle primitive:
//!
//! * `POSITION`: the stored positions with the header's f64
//!   `recentre_offset` added back, in metres, +y up ([`GltfFrame`]), f32;
//! * `NORMAL`: the stored normals, rotated to +y up (exactly as stored
//!   otherwise);
//! * `_RADIANCE` ([`RADIANCE_ATTRIBUTE`]): linear radiance (W·sr⁻¹·m⁻² per
//!   RGB channel) per vertex, f32, as the CPU reference renderer's vertex stage
//!   computes it (`solution::raster::shade_vertices`, negative values clamped
//!   to 0 as every renderer of the project does). Diffuse (SH L = 0) vertices
//!   radiate the same in every direction; glossy vertices (SH L ≥ 1, global
//!   cubes) are evaluated toward one eye, by default the header camera's, so
//!   that from the exported camera a viewer shows at each vertex what the
//!   runtime's screenshot shows;
//! * `COLOR_0`: the tone-mapped radiance, `curve(radiance × 2^exposure)` per
//!   channel, the runtime's PNG tone map (`solution::raster::tone_map`) before
//!   its sRGB encoding: glTF's COLOR_0 is linear, so the stored value is the
//!   linear display value in 0..1 and the viewer's own sRGB output encoding
//!   does the rest;
//! * the indices as stored (the change of frame is a proper rotation, so front
//!   faces stay counter-clockwise);
//! * one `KHR_materials_unlit` material, white, so that viewers show COLOR_0
//!   unlit.
//!
//! Memory: the binary buffer is the output's size, allocated once after the
//! total length was checked against glTF's u32 limit; each batch is shaded in
//! chunks of at most [`CHUNK_SCALARS`] coefficients, so the transient copy is
//! small whatever the batch's size.
//!
//! A textured batch (format 2) gets `TEXCOORD_0` = (u, 1 − v), a material of
//! its own with the stored PNG as `baseColorTexture` times the batch's
//! factor, and E/π in `_RADIANCE` (tone-mapped in COLOR_0); its untextured SH
//! part is left out, which [`Exporter::add_batch`] reports. A batch with
//! format 3's emission slot also gets `emissiveTexture` and Ke × 2^exposure
//! as its emissive factor (`document.rs`).

mod attributes;
mod document;
mod frame;
mod glb;
#[cfg(test)]
mod tests;

pub use frame::GltfFrame;
pub use glb::{file_name_uri, glb_length, write_glb};

use attributes::{has_nonzero, shade_into, textured_into, write_geometry};
use document::{CameraJson, Placed};
use glam::DVec3;
use solution::format::{
    BatchInfo, BatchSection, BatchTexture, Header, Representation, TextureInfo,
};
use solution::raster::{default_clip_planes, ToneCurve};

/// The custom vertex attribute (glTF 2.0 §3.7.2.1: application-specific names
/// start with an underscore) holding linear radiance.
pub const RADIANCE_ATTRIBUTE: &str = "_RADIANCE";

/// Bytes per exported vertex: POSITION, NORMAL, COLOR_0 and `_RADIANCE`,
/// each three f32.
pub const VERTEX_BYTES: u64 = 48;

/// The most bytes an export may have: a `.glb`'s lengths are u32 (glTF 2.0
/// §4.4.2), and a `.gltf`'s one `.bin` is held to the same limit so both
/// forms of one scene can be written.
pub const MAX_GLTF_BYTES: u64 = u32::MAX as u64;

/// JSON bytes reserved per exported batch and for the rest of the document
/// in the size check made before allocating (a batch's mesh, node, five views
/// and five accessors take about 1.2 KB).
const JSON_BYTES_PER_BATCH: u64 = 4096;
const JSON_BYTES_FIXED: u64 = 16384;

/// Coefficient scalars widened into a temporary `Batch` per shading chunk:
/// 1 MiB of f32 (with the chunk's vertices, 4 MiB for a diffuse batch), so
/// shading a batch of any order needs little beside the output; still 87,000
/// diffuse vertices, enough for the vertex stage to spread over threads.
pub const CHUNK_SCALARS: usize = 1 << 18;

/// How COLOR_0 is made and where glossy vertices are seen from.
#[derive(Clone, Copy, Debug)]
pub struct ExportOptions {
    /// Radiance is multiplied by 2^exposure_stops before the tone curve.
    pub exposure_stops: f32,
    pub curve: ToneCurve,
    /// The point (original scene coordinates) toward which glossy vertices
    /// are evaluated; `None`: the header camera's eye.
    pub glossy_eye: Option<[f64; 3]>,
}

impl Default for ExportOptions {
    /// The runtime's screenshot defaults: exposure 0, the clamp curve.
    fn default() -> Self {
        ExportOptions {
            exposure_stops: 0.0,
            curve: ToneCurve::Clamp,
            glossy_eye: None,
        }
    }
}

/// The curve's name as `--tonemap` (and `runtime screenshot --tonemap`) spells it.
pub fn curve_name(curve: ToneCurve) -> &'static str {
    match curve {
        ToneCurve::Clamp => "clamp",
        ToneCurve::Reinhard => "reinhard",
        ToneCurve::AcesFit => "aces",
    }
}

/// One batch's sections as stored in a solution file (little-endian);
/// `textured_vertices` is empty for an untextured batch.
#[derive(Clone, Copy, Debug)]
pub struct BatchBytes<'a> {
    pub vertices: &'a [u8],
    pub coefficients: &'a [u8],
    pub indices: &'a [u8],
    pub textured_vertices: &'a [u8],
}

/// Bytes per textured vertex in the buffer beside [`VERTEX_BYTES`]:
/// `TEXCOORD_0`, two f32.
pub const TEXCOORD_BYTES: u64 = 8;

/// Where one batch goes in the buffer.
#[derive(Clone, Copy, Debug)]
struct Slot {
    offset: u64,
    vertices: u64,
    indices: u64,
    texture: Option<BatchTexture>,
}

#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    #[error(
        "the glTF would take at least {bytes} bytes, above glTF's limit of {limit} \
         (a .glb's lengths are u32, glTF 2.0 §4.4.2; {vertices} vertices × {VERTEX_BYTES} \
         bytes + {indices} indices × 4 bytes); export a coarser solution"
    )]
    TooLarge {
        bytes: u64,
        limit: u64,
        vertices: u64,
        indices: u64,
    },
    #[error("batch {batch}: {problem}")]
    Batch { batch: usize, problem: String },
    #[error("texture {texture}: {problem}")]
    Texture { texture: usize, problem: String },
    #[error("exposure {0} stops is not a finite number in -64..=64")]
    Exposure(f32),
}

/// A finished export: the JSON document (padded with spaces to a multiple
/// of 4) and the binary buffer.
#[derive(Debug)]
pub struct Exported {
    pub json: Vec<u8>,
    pub bin: Vec<u8>,
    pub vertices: u64,
    pub triangles: u64,
}

/// Builds an export batch by batch, so that a caller streaming a mapped file
/// can check and release each batch's pages once it is added.
pub struct Exporter<'h> {
    header: &'h Header,
    options: ExportOptions,
    frame: GltfFrame,
    /// Per batch of the solution: where it goes in `bin` (`None`: skipped).
    slots: Vec<Option<Slot>>,
    /// Per texture: its PNG's offset and length in `bin`, and whether added.
    images: Vec<(u64, u64, bool)>,
    placed: Vec<Placed>,
    bin: Vec<u8>,
}

impl<'h> Exporter<'h> {
    /// Plans the buffer for `batches` (the solution's batch table) and
    /// `textures` (its texture table; their PNGs go into the buffer as they
    /// are), checks its size against [`MAX_GLTF_BYTES`] in u64 and only then
    /// allocates it.
    pub fn new(
        header: &'h Header,
        batches: &[BatchInfo],
        textures: &[TextureInfo],
        options: ExportOptions,
    ) -> Result<Self, ExportError> {
        if !(options.exposure_stops.is_finite() && options.exposure_stops.abs() <= 64.0) {
            return Err(ExportError::Exposure(options.exposure_stops));
        }
        let mut slots = Vec::with_capacity(batches.len());
        let (mut offset, mut vertices, mut indices, mut exported) = (0u64, 0u64, 0u64, 0u64);
        for info in batches {
            let (v, i) = (u64::from(info.vertex_count), u64::from(info.index_count));
            if v == 0 || i == 0 {
                slots.push(None);
                continue;
            }
            slots.push(Some(Slot {
                offset,
                vertices: v,
                indices: i,
                texture: info.texture,
            }));
            let texcoords = if info.texture.is_some() {
                v * TEXCOORD_BYTES
            } else {
                0
            };
            // u32 counts: each term is below 2^38, so nothing here can wrap.
            offset += v * VERTEX_BYTES + texcoords + i * 4;
            (vertices, indices, exported) = (vertices + v, indices + i, exported + 1);
        }
        let mut images = Vec::with_capacity(textures.len());
        for texture in textures {
            // Encoded lengths are bounded by the file's length.
            images.push((offset, texture.encoded_bytes, false));
            offset = offset.saturating_add(texture.encoded_bytes.div_ceil(4) * 4);
            exported += 1;
        }
        let json_bound = JSON_BYTES_FIXED + exported * JSON_BYTES_PER_BATCH;
        let bytes = glb_length(json_bound, offset);
        let too_large = ExportError::TooLarge {
            bytes,
            limit: MAX_GLTF_BYTES,
            vertices,
            indices,
        };
        if bytes > MAX_GLTF_BYTES {
            return Err(too_large);
        }
        let len = usize::try_from(offset).map_err(|_| too_large)?;
        Ok(Exporter {
            header,
            options,
            frame: GltfFrame::new(
                header.recentre_offset,
                header.units_per_metre,
                header.up_axis,
            ),
            slots,
            images,
            placed: Vec::new(),
            bin: vec![0; len],
        })
    }

    /// The point glossy vertices are evaluated toward, scene coordinates.
    pub fn glossy_eye(&self) -> [f64; 3] {
        self.options.glossy_eye.unwrap_or(self.header.camera.eye)
    }

    /// Adds batch `index` (its entry `info` and its bytes). Lengths are checked
    /// against the counts; a skipped batch (no triangles) is accepted and ignored.
    /// Returns true for a textured batch whose untextured term (the
    /// coefficients: a glossy lobe or emission) is not zero, which the export
    /// leaves out (docs/gltf.md, "Export").
    /// `done` is called with each section as soon as it has been read for the
    /// last time (vertices and coefficients after shading, indices after the
    /// copy), so that a caller reading a mapped file can release its pages
    /// and hold little of the input beside the output.
    pub fn add_batch(
        &mut self,
        index: usize,
        info: &BatchInfo,
        bytes: BatchBytes,
        mut done: impl FnMut(BatchSection),
    ) -> Result<bool, ExportError> {
        let fail = |problem: String| ExportError::Batch {
            batch: index,
            problem,
        };
        let Some(&slot) = self.slots.get(index) else {
            return Err(fail(format!(
                "not in the planned {} batches",
                self.slots.len()
            )));
        };
        let Some(slot) = slot else {
            return Ok(false);
        };
        let counts = (u64::from(info.vertex_count), u64::from(info.index_count));
        if counts != (slot.vertices, slot.indices) || info.texture != slot.texture {
            return Err(fail("differs from the planned batch table".into()));
        }
        check_lengths(info, &bytes).map_err(fail)?;
        let eye = DVec3::from(self.glossy_eye()) - DVec3::from(self.header.recentre_offset);
        let (n, textured) = (slot.vertices as usize, slot.texture.is_some());
        let texcoord_len = if textured { 8 * n } else { 0 };
        // In bounds: the plan sized `bin` to hold every slot.
        let start = slot.offset as usize;
        let end = start + n * 48 + texcoord_len + slot.indices as usize * 4;
        let region = &mut self.bin[start..end];
        let (positions, rest) = region.split_at_mut(12 * n);
        let (normals, rest) = rest.split_at_mut(12 * n);
        let (colors, rest) = rest.split_at_mut(12 * n);
        let (radiance, rest) = rest.split_at_mut(12 * n);
        let (texcoords, index_out) = rest.split_at_mut(texcoord_len);
        let (min, max) = write_geometry(&self.frame, bytes.vertices, positions, normals);
        let dropped = if textured {
            textured_into(
                bytes.textured_vertices,
                &self.options,
                colors,
                radiance,
                texcoords,
            );
            done(BatchSection::TexturedVertices);
            has_nonzero(info.scalar, bytes.coefficients)
        } else {
            shade_into(info, &bytes, eye, &self.options, colors, radiance).map_err(fail)?;
            false
        };
        done(BatchSection::Vertices);
        done(BatchSection::Coefficients);
        index_out.copy_from_slice(bytes.indices);
        done(BatchSection::Indices);
        self.placed.push(Placed {
            batch: index,
            name: batch_name(index, info),
            offset: slot.offset,
            vertices: slot.vertices,
            indices: slot.indices,
            texture: slot.texture.map(|t| (t.texture, t.factor)),
            emission: slot
                .texture
                .and_then(|t| t.emission)
                .map(|e| (e.texture, e.factor)),
            min,
            max,
        });
        Ok(dropped)
    }

    /// Adds texture `k`'s encoded image (PNG, as the solution stores it).
    pub fn add_texture(&mut self, k: usize, png: &[u8]) -> Result<(), ExportError> {
        let fail = |problem: String| ExportError::Texture {
            texture: k,
            problem,
        };
        let Some((offset, len, added)) = self.images.get_mut(k) else {
            return Err(fail("not in the texture table".into()));
        };
        if png.len() as u64 != *len {
            return Err(fail(format!("{} bytes, the table says {len}", png.len())));
        }
        let start = *offset as usize;
        self.bin[start..start + png.len()].copy_from_slice(png);
        *added = true;
        Ok(())
    }

    /// The JSON document and the buffer. `bin_uri`: the URI of the `.bin`
    /// file for a `.gltf` ([`file_name_uri`]), `None` for a `.glb`. Refuses a
    /// batch that was planned but never added.
    pub fn finish(self, bin_uri: Option<&str>) -> Result<Exported, ExportError> {
        if let Some(texture) = self.images.iter().position(|(_, _, added)| !added) {
            return Err(ExportError::Texture {
                texture,
                problem: "planned but never added".into(),
            });
        }
        let images: Vec<(u64, u64)> = self.images.iter().map(|&(o, l, _)| (o, l)).collect();
        let added: Vec<usize> = self.placed.iter().map(|p| p.batch).collect();
        if let Some(batch) =
            (0..self.slots.len()).find(|b| self.slots[*b].is_some() && !added.contains(b))
        {
            return Err(ExportError::Batch {
                batch,
                problem: "planned but never added".into(),
            });
        }
        let camera = self.camera_json();
        let doc = document::document(
            &self.placed,
            &images,
            self.bin.len() as u64,
            bin_uri,
            &camera,
            &self.options,
            self.glossy_eye(),
        );
        // Serializing a `Value` of strings and finite numbers cannot fail.
        let mut json = serde_json::to_vec(&doc).unwrap_or_default();
        while !json.len().is_multiple_of(4) {
            json.push(b' ');
        }
        let bytes = glb_length(json.len() as u64, self.bin.len() as u64);
        if bytes > MAX_GLTF_BYTES {
            return Err(ExportError::TooLarge {
                bytes,
                limit: MAX_GLTF_BYTES,
                vertices: self.placed.iter().map(|p| p.vertices).sum(),
                indices: self.placed.iter().map(|p| p.indices).sum(),
            });
        }
        Ok(Exported {
            json,
            vertices: self.placed.iter().map(|p| p.vertices).sum(),
            triangles: self.placed.iter().map(|p| p.indices / 3).sum(),
            bin: self.bin,
        })
    }

    /// The header camera in glTF terms: placed in metres, +y up; the clip
    /// planes the project's renderers use for it (`default_clip_planes`, from
    /// the eye to the header's bounds), in metres.
    fn camera_json(&self) -> CameraJson {
        let camera = &self.header.camera;
        let (translation, rotation) = self.frame.camera_node(camera);
        let view = camera.mono_view(DVec3::from(self.header.recentre_offset));
        let (near, far) = default_clip_planes(self.header, &view);
        let znear_m = self.frame.length(near);
        let zfar_m = Some(self.frame.length(far)).filter(|f| f.is_finite() && *f > znear_m);
        CameraJson {
            translation,
            rotation,
            yfov_rad: camera.fov_y_deg.to_radians(),
            aspect: f64::from(camera.width) / f64::from(camera.height),
            // glTF requires znear > 0; the renderers' planes are positive.
            znear_m: if znear_m > 0.0 { znear_m } else { 1e-3 },
            zfar_m,
        }
    }
}

/// A mesh name that says what the batch was.
fn batch_name(index: usize, info: &BatchInfo) -> String {
    match info.representation {
        Representation::Sh { order: 0 } => format!("batch {index} (diffuse)"),
        Representation::Sh { order } => format!("batch {index} (SH order {order})"),
        Representation::Cube { directions } => {
            format!("batch {index} (cube, {directions} directions)")
        }
    }
}

/// The sections' lengths against the batch entry's counts.
fn check_lengths(info: &BatchInfo, bytes: &BatchBytes) -> Result<(), String> {
    let checks = [
        ("vertices", bytes.vertices.len() as u64, info.vertex_bytes()),
        (
            "textured vertices",
            bytes.textured_vertices.len() as u64,
            info.textured_vertex_bytes(),
        ),
        (
            "coefficients",
            bytes.coefficients.len() as u64,
            info.coefficient_bytes(),
        ),
        ("indices", bytes.indices.len() as u64, info.index_bytes()),
    ];
    for (what, found, expected) in checks {
        if found != expected {
            return Err(format!(
                "{what} section is {found} bytes, the batch entry says {expected}"
            ));
        }
    }
    Ok(())
}
