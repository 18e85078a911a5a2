//! The solution file: the contract between the solver and the runtime.
//!
//! The byte layout is specified in `docs/solution-format.md`; this module holds the
//! in-memory form ([`Solution`]), the atomic writer and the memory-mapped,
//! validating reader. Positions are re-centred scene units stored as f32; radiance
//! is linear RGB (W·sr⁻¹·m⁻²). Vertices come in batches of one representation
//! (SH order L, or D discrete directions), so the runtime can draw each batch with
//! a loop bound fixed per draw; a representation may span several batches
//! ([`split_to_storage_range`]).

use crate::camera::{Camera, UpAxis};
use serde::{Deserialize, Serialize};

mod describe;
mod error;
pub mod layout;
mod lighting;
mod read;
mod split;
mod texture;
mod validate;
mod write;

#[cfg(test)]
mod emission_slot_tests;
#[cfg(test)]
mod lighting_tests;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod texture_tests;

pub use describe::{
    batch_json, describe_json, describe_lighting_text, describe_text, describe_textures_text,
    lighting_json, textures_json,
};
pub use error::{FormatError, Problem};
pub use layout::MAX_SH_ORDER;
pub use lighting::{
    equirect_direction, equirect_frame, equirect_uv, Environment, Lighting, SunDisc,
    DEFAULT_ENVIRONMENT_SIZE, MAX_ENVIRONMENT_TEXELS,
};
pub use read::{decode, read_solution, BatchInfo, BatchSection, BatchTexture, MappedSolution};
pub use split::{split_to_storage_range, PORTABLE_STORAGE_RANGE};
pub use texture::{decode_png, encode_png, TextureInfo};
pub use validate::{
    check_frame_cost, frame_cost, terms_per_vertex, BOUNDS_RELATIVE_SLACK, DEFAULT_MAX_FRAME_COST,
    F16_MAX, FRAME_TOLERANCE, MAX_FRAME_COST_FLAG,
};
pub use write::{check_solution, encode, f16_scale_for, write_solution};

/// How a batch stores each vertex's outgoing radiance.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum Representation {
    /// Real orthonormal spherical harmonics up to order `order` inclusive:
    /// `(order + 1)²` coefficients per channel, index `l² + l + m`.
    Sh { order: u32 },
    /// Immel, Cohen and Greenberg's (1986) global cube: radiance on `directions` fixed directions per channel.
    Cube { directions: u32 },
}

impl Representation {
    /// Coefficients per colour channel per vertex (saturating: order u32::MAX, which
    /// no validated file holds, would need 2⁶⁴).
    pub fn coefficients_per_channel(self) -> u64 {
        match self {
            Representation::Sh { order } => (order as u64 + 1).saturating_mul(order as u64 + 1),
            Representation::Cube { directions } => directions as u64,
        }
    }
}

/// How coefficients are stored on disk. In memory ([`Batch::coefficients`]) they
/// are always f32 radiance; `F16` stores `value / scale` as IEEE half so that bright
/// emitters fit the half range.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum ScalarType {
    F32,
    F16 { scale: f32 },
}

/// Which transport the solve modelled: diffuse only, or directional (glossy) SH.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum SolveMode {
    #[default]
    Diffuse,
    Directional,
}

/// One mesh vertex as the runtime uploads it: 36 bytes, tightly packed.
///
/// The frame (design notes, "Local frames and SH"): `normal` is n, `tangent` is t,
/// the bitangent is `b = n × t`; SH directions are θ from n and φ from t toward b.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Default, Serialize, Deserialize)]
pub struct Vertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    pub tangent: [f32; 3],
}

/// Convergence figures of the solve that wrote the file.
#[derive(Clone, Copy, Debug, PartialEq, Default, Serialize, Deserialize)]
pub struct SolveStats {
    pub shots: u64,
    pub rays: u64,
    pub seconds: f64,
    /// Total unshot power divided by total emitted power when the file was written.
    pub unshot_fraction: f64,
    /// Total emitted power, W (per channel, summed over channels).
    pub emitted_power: f64,
    /// The ambient radiance term (Cohen et al. 1988) for partial solutions, RGB;
    /// zero when the solve converged or the ambient term is off.
    pub ambient: [f32; 3],
}

/// Everything in the file except the vertex data.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Header {
    /// Scene units per metre: XR poses, walking speed and IPD are scaled by it.
    pub units_per_metre: f64,
    pub up_axis: UpAxis,
    /// Subtracted from scene coordinates (in f64) before storing positions.
    pub recentre_offset: [f64; 3],
    /// The initial camera, in the scene's original (not re-centred) coordinates.
    pub camera: Camera,
    /// Bounds of the stored (re-centred) positions.
    pub bounds_min: [f32; 3],
    pub bounds_max: [f32; 3],
    /// Set on files written mid-solve (checkpoints a viewer can watch).
    pub partial: bool,
    pub mode: SolveMode,
    pub stats: SolveStats,
    /// The solver settings that produced this file, as JSON text.
    pub settings_json: String,
}

/// Vertices that share one representation, with the triangles drawn from them.
#[derive(Clone, Debug, PartialEq)]
pub struct Batch {
    pub representation: Representation,
    pub scalar: ScalarType,
    pub vertices: Vec<Vertex>,
    /// `vertices.len() × coefficients_per_channel × 3`, laid out vertex-major, then
    /// coefficient, then RGB: `coefficients[(v * n + k) * 3 + c]`.
    pub coefficients: Vec<f32>,
    /// Triangle list, indices into this batch's `vertices`, counter-clockwise seen
    /// from the side the normal points to.
    pub indices: Vec<u32>,
    /// `None`: the coefficients are the vertex's whole outgoing radiance (as in
    /// version 1). `Some`: the batch is textured, and the radiance toward ω is
    /// `Σ c·Y(ω) + factor ⊙ ρ(uv) ⊙ E/π` (plus `Ke ⊙ ρ_e(uv)` when the
    /// emission slot is used), with ρ the texture decoded to linear and the
    /// coefficients holding only the untextured part (a glossy term,
    /// emission; zero for a plain textured diffuse surface).
    pub texturing: Option<Texturing>,
}

/// How a textured batch is shaded: one texture, a constant factor (the MTL
/// convention: `Kd` multiplies `map_Kd`) and per vertex a UV and E/π; and
/// optionally (format 3) a second texture, the emission map, with its own
/// factor, sampled at the same UVs.
#[derive(Clone, Debug, PartialEq)]
pub struct Texturing {
    /// Index into [`Solution::textures`].
    pub texture: u32,
    /// Linear RGB multiplier of the decoded texture (finite, ≥ 0).
    pub factor: [f32; 3],
    /// The second slot: an emission texture added as `factor ⊙ ρ_e(uv)`
    /// (no E/π), so that a surface with both a diffuse and an emission map
    /// shows `Σ c·Y + Kd ⊙ ρ(uv) ⊙ E/π + Ke ⊙ ρ_e(uv)`. `None` in every
    /// format-2 batch; a solution using it is written as format 3.
    pub emission: Option<TextureSlot>,
    /// One per vertex of the batch, in the same order as [`Batch::vertices`].
    pub vertices: Vec<TexturedVertex>,
}

/// A texture and its factor: the second (emission) slot of a textured batch.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TextureSlot {
    /// Index into [`Solution::textures`].
    pub texture: u32,
    /// Linear RGB multiplier of the decoded texture (finite, ≥ 0): Ke.
    pub factor: [f32; 3],
}

/// Per-vertex data of a textured batch: 20 bytes, tightly packed.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Default, Serialize, Deserialize)]
pub struct TexturedVertex {
    /// Texture coordinates, OBJ convention: u from the image's left edge (0) to
    /// its right (1), v from its bottom row (0) to its top (1); the texture
    /// repeats outside [0, 1].
    pub uv: [f32; 2],
    /// Incident irradiance over π, E/π, linear RGB (W·m⁻²·sr⁻¹ per channel,
    /// the radiance a white Lambertian surface would reflect); finite, ≥ 0.
    pub irradiance_over_pi: [f32; 3],
}

/// A texture: 8-bit sRGB-encoded RGBA, rows from the image's top to its bottom
/// (PNG order). The alpha channel is stored but not used by any renderer.
#[derive(Clone, PartialEq, Eq)]
pub struct Texture {
    pub width: u32,
    pub height: u32,
    /// `width × height × 4` bytes.
    pub rgba: Vec<u8>,
}

impl std::fmt::Debug for Texture {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Texture")
            .field("width", &self.width)
            .field("height", &self.height)
            .field("rgba_bytes", &self.rgba.len())
            .finish()
    }
}

/// A whole solution in memory.
#[derive(Clone, Debug, PartialEq)]
pub struct Solution {
    pub header: Header,
    pub batches: Vec<Batch>,
    /// Textures the batches' [`Texturing::texture`] index. Empty for an
    /// untextured solution, which is then written as format 1.0, byte for byte
    /// what version 1 writers wrote.
    pub textures: Vec<Texture>,
    /// The exposure key, the lights and the visible sky (issue 41). `None`
    /// for a solution without lights, which is then written as x.0, byte for
    /// byte what older writers wrote; `Some` makes the file x.1.
    pub lighting: Option<Lighting>,
}
