#version 450
#extension GL_EXT_multiview : require
#extension GL_GOOGLE_include_directive : require
// Diffuse (L = 0) batches: radiance = c00 · Y00, the same toward every eye, so
// there is no per-frame SH work (design notes, "Directional mode": a diffuse
// material costs one coefficient per channel).
#include "scene_common.glsl"

const float Y00 = 0.28209479177387814;

void main() {
    uint base = batch.coeff_base + (uint(gl_VertexIndex) - batch.vertex_base) * batch.stride;
    out_radiance = vec3(coefficient(base), coefficient(base + 1u), coefficient(base + 2u))
        * (Y00 * batch.scale);
    gl_Position = frame.view_projection[gl_ViewIndex] * vec4(in_position, 1.0);
}
