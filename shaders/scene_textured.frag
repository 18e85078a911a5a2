#version 450
// Textured batches (solution format 2): the interpolated untextured radiance
// plus the albedo texture, decoded from sRGB and filtered trilinearly by the
// sampler, times the interpolated E/pi (already multiplied by the factor and
// the renderer's radiance scale), plus the emission texture (format 3's second
// slot, sampled at the same UV) times its factor Ke:
// L = SH + factor * rho(uv) * E/pi + Ke * rho_e(uv), as solution::raster draws
// it. A batch without an emission texture binds its albedo texture here with
// a zero factor.
layout(location = 0) in vec3 in_radiance;
layout(location = 1) in vec2 in_st;
layout(location = 2) in vec3 in_irradiance;
layout(location = 3) flat in vec3 in_emission_scale;
layout(set = 1, binding = 1) uniform sampler2D albedo;
layout(set = 1, binding = 2) uniform sampler2D emission;
layout(location = 0) out vec4 out_color;

void main() {
    out_color = vec4(in_radiance + texture(albedo, in_st).rgb * in_irradiance
                         + texture(emission, in_st).rgb * in_emission_scale,
                     1.0);
}
