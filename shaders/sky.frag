#version 450
#extension GL_GOOGLE_include_directive : require
// The sky toward the pixel's view direction, bilinear between texel centres
// of the equirectangular RGB f32 texture (u wraps, v clamps at the pole
// rows), plus the sun's disc; times the renderer's radiance scale, clamped
// below the half-float target's largest value (65504).
#include "sky_common.glsl"

layout(std430, set = 0, binding = 1) readonly buffer Texels { float values[]; } texels;

layout(push_constant) uniform Params {
    float radiance_scale;
} params;

layout(location = 0) noperspective in vec3 in_direction;
layout(location = 0) out vec4 out_color;

const float PI = 3.14159265358979;

vec3 texel(uint i, uint j) {
    uint k = (j * sky.size.x + i) * 3u;
    return vec3(texels.values[k], texels.values[k + 1u], texels.values[k + 2u]);
}

void main() {
    vec3 d = normalize(in_direction);
    float phi = atan(dot(d, sky.e2.xyz), dot(d, sky.e1.xyz));
    if (phi < 0.0) {
        phi += 2.0 * PI;
    }
    float u = phi / (2.0 * PI);
    float v = acos(clamp(dot(d, sky.up.xyz), -1.0, 1.0)) / PI;
    float w = float(sky.size.x);
    float h = float(sky.size.y);
    float x = u * w - 0.5;
    float y = clamp(v * h - 0.5, 0.0, h - 1.0);
    float x0 = floor(x);
    float y0 = floor(y);
    int width = int(sky.size.x);
    uint c0 = uint(((int(x0) % width) + width) % width);
    uint c1 = uint(((int(x0) + 1) % width + width) % width);
    uint r0 = uint(y0);
    uint r1 = min(r0 + 1u, sky.size.y - 1u);
    vec3 top = mix(texel(c0, r0), texel(c1, r0), x - x0);
    vec3 bottom = mix(texel(c0, r1), texel(c1, r1), x - x0);
    vec3 radiance = mix(top, bottom, y - y0);
    if (dot(d, sky.sun_direction.xyz) >= sky.sun_direction.w) {
        radiance += sky.sun_radiance.rgb;
    }
    out_color = vec4(min(radiance * params.radiance_scale, vec3(65504.0)), 1.0);
}
