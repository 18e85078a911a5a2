#version 450
// The mirror window (runtime/src/mirror/present.rs): the renderer's two-layer
// eye image (sRGB, sampled as linear values) to the window's swapchain image,
// with the text overlay (help, frame time) of runtime/src/mirror/font.rs.
//
// Modes: 0 side by side (layer 0 in the left half, layer 1 in the right),
// 1 one layer alone, 2 red-cyan anaglyph (red of layer 0, green and blue of
// layer 1). Pixels outside the eye images are black. Pixel (x, y) of the
// window reads pixel (x, y) of its eye's image: the renderer draws at the
// window's per-eye size, so there is no resampling.

layout(set = 0, binding = 0) uniform sampler2DArray eyes;
// The font (95 glyphs x 7 rows of 5 bits, from ' '), then the text grid's
// character codes, row-major.
layout(std430, set = 0, binding = 1) readonly buffer Overlay { uint words[]; } overlay;

layout(push_constant) uniform Params {
    ivec2 eye_size;
    uint mode;
    // 1 when the swapchain is UNORM: the shader applies the sRGB curve itself.
    uint encode_srgb;
    ivec2 text_origin;
    uint text_cols;
    uint text_rows;
    uint text_scale;
    // The layer mode 1 shows.
    uint layer;
} params;

layout(location = 0) out vec4 out_color;

const uint FONT_WORDS = 95u * 7u;
// Linear colour of lit text pixels, and the factor that darkens the picture
// behind the text block.
const vec3 TEXT_COLOR = vec3(1.0, 0.95, 0.6);
const float TEXT_BACKGROUND = 0.3;

vec3 fetch(ivec2 p, int layer) {
    if (p.x < 0 || p.y < 0 || p.x >= params.eye_size.x || p.y >= params.eye_size.y) {
        return vec3(0.0);
    }
    return texelFetch(eyes, ivec3(p, layer), 0).rgb;
}

// Font rule of font.rs (TextGrid::lit): cells of 6 x 9, glyph rows 1..7.
bool lit(ivec2 q) {
    uvec2 px = uvec2(q) / params.text_scale;
    uint col = px.x / 6u;
    uint row = px.y / 9u;
    uint gx = px.x % 6u;
    uint gy = px.y % 9u;
    if (gx >= 5u || gy < 1u || gy > 7u) {
        return false;
    }
    uint code = overlay.words[FONT_WORDS + row * params.text_cols + col];
    uint bits = overlay.words[(code - 32u) * 7u + (gy - 1u)];
    return ((bits >> (4u - gx)) & 1u) == 1u;
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
    ivec2 q = p - params.text_origin;
    ivec2 size = ivec2(params.text_cols * 6u, params.text_rows * 9u) * int(params.text_scale);
    if (params.text_cols > 0u && q.x >= 0 && q.y >= 0 && q.x < size.x && q.y < size.y) {
        c = lit(q) ? TEXT_COLOR : c * TEXT_BACKGROUND;
    }
    if (params.encode_srgb == 1u) {
        c = srgb_encode(c);
    }
    out_color = vec4(c, 1.0);
}
