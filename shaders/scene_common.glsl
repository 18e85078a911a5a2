// Shared declarations of the scene vertex shaders (included by scene_sh.vert and
// scene_l0.vert). Conventions: runtime/src/render/mod.rs and solution/src/camera.rs.

// Per-frame data: one view-projection matrix and eye position per view, indexed
// by gl_ViewIndex (0 = left, 1 = right), in file (re-centred) coordinates.
layout(std140, set = 0, binding = 0) uniform Frame {
    mat4 view_projection[2];
    vec4 eye_position[2];
} frame;

// Coefficients of every batch, laid out as in the solution file:
// coefficients[(v * n + k) * 3 + c], v relative to the batch's first vertex.
#ifdef COEFF_F16
// Two IEEE halves per 32-bit word (low half first), read with unpackHalf2x16:
// no 16-bit storage feature is needed.
layout(std430, set = 0, binding = 1) readonly buffer Coefficients { uint words[]; } coeffs;
float coefficient(uint i) {
    vec2 pair = unpackHalf2x16(coeffs.words[i >> 1]);
    return (i & 1u) == 0u ? pair.x : pair.y;
}
#else
layout(std430, set = 0, binding = 1) readonly buffer Coefficients { float values[]; } coeffs;
float coefficient(uint i) { return coeffs.values[i]; }
#endif

// Per-batch data (20 bytes).
layout(push_constant) uniform Batch {
    // SH batches: the order evaluated (the file's order, capped by --max-order).
    // Cube batches (scene_cube.vert): the cube resolution k, D = 6k^2.
    uint order;
    // Index of the batch's first vertex in the shared vertex buffer.
    uint vertex_base;
    // Index of the batch's first scalar in the coefficient buffer.
    uint coeff_base;
    // Scalars per vertex: SH (file order + 1)^2 * 3 (the stride does not change
    // with the cap: dropped bands are simply not read); cube 3D.
    uint stride;
    // Multiplies every coefficient: the f16 storage scale times the renderer's
    // radiance scale (which keeps half-float colour targets in range).
    float scale;
#ifdef TEXTURED
    // Textured batches (44 bytes): the texture factor (MTL Kd) times the
    // renderer's radiance scale, multiplying the stored E/pi;
    float texture_scale_r;
    float texture_scale_g;
    float texture_scale_b;
    // and the emission texture's factor (Ke, solution format 3's second slot)
    // times the radiance scale, zero when the batch has no emission texture.
    float emission_scale_r;
    float emission_scale_g;
    float emission_scale_b;
#endif
} batch;

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec3 in_tangent;

layout(location = 0) out vec3 out_radiance;

#ifdef TEXTURED
// Per vertex of a textured batch: u, v, E/pi RGB (solution::format::TexturedVertex),
// indexed like the coefficients, from the batch's first vertex.
layout(std430, set = 1, binding = 0) readonly buffer Textured { float values[]; } textured;
// Image coordinates (s, t) = (u, 1 - v): the file's v runs up from the
// image's bottom row, Vulkan's t down from its first row.
layout(location = 1) out vec2 out_st;
// E/pi times the factor and the radiance scale.
layout(location = 2) out vec3 out_irradiance;
// The emission texture's factor times the radiance scale (one per batch).
layout(location = 3) flat out vec3 out_emission_scale;

void write_textured() {
    uint at = (uint(gl_VertexIndex) - batch.vertex_base) * 5u;
    out_st = vec2(textured.values[at], 1.0 - textured.values[at + 1u]);
    out_irradiance = vec3(textured.values[at + 2u], textured.values[at + 3u],
                          textured.values[at + 4u])
        * vec3(batch.texture_scale_r, batch.texture_scale_g, batch.texture_scale_b);
    out_emission_scale =
        vec3(batch.emission_scale_r, batch.emission_scale_g, batch.emission_scale_b);
}
#endif
