#version 450
#extension GL_GOOGLE_include_directive : require
// The text overlay over eye images copied into the window (mode 3 of
// runtime/src/mirror/present.rs), drawn over the text block's rectangle only
// and blended (SRC_ALPHA, ONE_MINUS_SRC_ALPHA, on linear values): lit pixels
// are TEXT_COLOR, the rest of the block keeps TEXT_BACKGROUND of the picture,
// exactly what composite.frag draws.
#include "overlay_common.glsl"

layout(location = 0) out vec4 out_color;

void main() {
    ivec2 q;
    if (!in_text(ivec2(gl_FragCoord.xy), q)) {
        discard;
    }
    out_color = lit(q) ? vec4(TEXT_COLOR, 1.0) : vec4(0.0, 0.0, 0.0, 1.0 - TEXT_BACKGROUND);
}
