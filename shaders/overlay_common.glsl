// Shared by composite.frag and overlay.frag (runtime/src/mirror/present.rs):
// the push constants and the text overlay of runtime/src/mirror/font.rs.

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

const uint FONT_WORDS = 95u * 7u;
// Linear colour of lit text pixels, and the factor that darkens the picture
// behind the text block.
const vec3 TEXT_COLOR = vec3(1.0, 0.95, 0.6);
const float TEXT_BACKGROUND = 0.3;

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

// Whether pixel p is inside the text block, and its position in it.
bool in_text(ivec2 p, out ivec2 q) {
    q = p - params.text_origin;
    ivec2 size = ivec2(params.text_cols * 6u, params.text_rows * 9u) * int(params.text_scale);
    return params.text_cols > 0u && q.x >= 0 && q.y >= 0 && q.x < size.x && q.y < size.y;
}
