#version 450
#extension GL_EXT_multiview : require
#extension GL_GOOGLE_include_directive : require
// The background: one triangle covering the view, at the far plane, drawn
// before the geometry (no depth test or write), so every pixel no triangle
// covers keeps the sky.
#include "sky_common.glsl"

layout(location = 0) noperspective out vec3 out_direction;

void main() {
    vec2 ndc = vec2(gl_VertexIndex == 1 ? 3.0 : -1.0, gl_VertexIndex == 2 ? 3.0 : -1.0);
    out_direction = sky.corners[gl_ViewIndex * 3 + gl_VertexIndex].xyz;
    gl_Position = vec4(ndc, 1.0, 1.0);
}
