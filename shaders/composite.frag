#version 450
#extension GL_GOOGLE_include_directive : require
// The mirror window (runtime/src/mirror/present.rs): the renderer's two-layer
// eye image (sRGB, sampled as linear values) to the window's swapchain image,
// with the text overlay (help, frame time) of runtime/src/mirror/font.rs. Used
// for the anaglyph, and for any layout when the window's format is not the eye
// images' (else those are copied and overlay.frag draws the text).
//
// Modes: 0 side by side (layer 0 in the left half, layer 1 in the right),
// 1 one layer alone, 2 red-cyan anaglyph (red of layer 0, green and blue of
// layer 1). Pixels outside the eye images are black. Pixel (x, y) of the
// window reads pixel (x, y) of its eye's image: the renderer draws at the
// window's per-eye size, so there is no resampling.
#include "overlay_common.glsl"

layout(set = 0, binding = 0) uniform sampler2DArray eyes;

layout(location = 0) out vec4 out_color;

vec3 fetch(ivec2 p, int layer) {
    if (p.x < 0 || p.y < 0 || p.x >= params.eye_size.x || p.y >= params.eye_size.y) {
        return vec3(0.0);
    }
    return texelFetch(eyes, ivec3(p, layer), 0).rgb;
}

vec3 srgb_encode(vec3 c) {
    c = clamp(c, 0.0, 1.0);
    return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), c));
}

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec3 c;
    if (params.mode == 0u) {
        int w = params.eye_size.x;
        c = p.x < w ? fetch(p, 0) : fetch(ivec2(p.x - w, p.y), 1);
    } else if (params.mode == 1u) {
        c = fetch(p, int(params.layer));
    } else {
        c = vec3(fetch(p, 0).r, fetch(p, 1).gb);
    }
    ivec2 q;
    if (in_text(p, q)) {
        c = lit(q) ? TEXT_COLOR : c * TEXT_BACKGROUND;
    }
    if (params.encode_srgb == 1u) {
        c = srgb_encode(c);
    }
    out_color = vec4(c, 1.0);
}
