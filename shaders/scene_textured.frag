#version 450
// Textured batches (solution format 2): the interpolated untextured radiance
// plus the albedo texture, decoded from sRGB and filtered trilinearly by the
// sampler, times the interpolated E/pi (already multiplied by the factor and
// the renderer's radiance scale): L = SH + factor * rho(uv) * E/pi, as
// solution::raster draws it.
layout(location = 0) in vec3 in_radiance;
layout(location = 1) in vec2 in_st;
layout(location = 2) in vec3 in_irradiance;
layout(set = 1, binding = 1) uniform sampler2D albedo;
layout(location = 0) out vec4 out_color;

void main() {
    out_color = vec4(in_radiance + texture(albedo, in_st).rgb * in_irradiance, 1.0);
}
