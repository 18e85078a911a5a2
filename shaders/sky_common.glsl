// Shared by sky.vert and sky.frag: the visible environment of a solution file
// of format x.1 (runtime/src/render/sky.rs writes this block; the CPU twin is
// solution::format::Environment::radiance and solution::raster's stage 7).
layout(std140, set = 0, binding = 0) uniform Sky {
    // Per view (gl_ViewIndex) the view direction at the full-screen
    // triangle's three corners, NDC (-1, -1), (3, -1), (-1, 3): forward +
    // tan_x right + tan_y up, computed in f64 on the CPU. Affine in screen
    // space, so interpolated without perspective it is exact at every pixel.
    vec4 corners[6];
    // The equirectangular frame: azimuth 0 along e1, pi/2 along e2, polar
    // axis up (the file's up axis; solution::format::equirect_frame).
    vec4 e1;
    vec4 e2;
    vec4 up;
    // Toward the sun, w = cos of its angular radius (2: no sun).
    vec4 sun_direction;
    // The disc's radiance, RGB.
    vec4 sun_radiance;
    // Texels per row and rows.
    uvec4 size;
} sky;
