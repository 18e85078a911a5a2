#version 450
#extension GL_EXT_multiview : require
#extension GL_GOOGLE_include_directive : require
// Global-cube batches (Immel, Cohen & Greenberg 1986, "The global cube"):
// each vertex stores its outgoing radiance on the D = 6k² cell centres of a
// cube in its local frame (docs/solution-format.md, "Cube"); this view's radiance is the bilinear
// lookup toward the eye, exactly the arithmetic of solver::cube::bilinear_f32
// (whose tests state its rounding against the f64 solver::cube::bilinear):
//   * the direction to the eye in the vertex frame (x = t, y = n × t, z = n),
//     as scene_sh.vert computes it; zero or non-finite looks along +z;
//   * the face is the axis of largest |component|, ties to x, then y, then z;
//     the sign of that component picks + or −;
//   * (u, v) = the in-face components over |major|, with (u, v) the axes
//     (y, z), (z, x), (x, y) of the x, y, z faces;
//   * per axis the continuous cell coordinate (u + 1)·k/2 − ½ is clamped to
//     [0, k − 1] (no blending across faces), its floor (at most k − 2) and the
//     next cell are blended by the fraction;
//   * cell (i, j) of face f is value (f·k + i)·k + j.
// The work is four cells × three channels whatever D is. The push constant
// `order` carries the resolution k for these batches (DrawBatch::loop_parameter),
// `stride` is D·3.
#include "scene_common.glsl"

vec3 cell_rgb(uint base, uint cell) {
    uint i = base + 3u * cell;
    return vec3(coefficient(i), coefficient(i + 1u), coefficient(i + 2u));
}

// One axis of the lookup: lower cell, upper cell, weight of the upper one.
// `precise` keeps the compiler from fusing the multiply-adds, so the rounding
// is bilinear_f32's.
void axis_cells(float u, uint k, out uint lower, out uint upper, out float frac) {
    float kf = float(k);
    precise float x = clamp((u + 1.0) * 0.5 * kf - 0.5, 0.0, kf - 1.0);
    lower = min(uint(floor(x)), k >= 2u ? k - 2u : 0u);
    upper = min(lower + 1u, k - 1u);
    frac = x - float(lower);
}

void main() {
    vec3 eye = frame.eye_position[gl_ViewIndex].xyz;
    vec3 n = in_normal;
    vec3 t = in_tangent;
    vec3 b = cross(n, t);
    vec3 to_eye = eye - in_position;
    vec3 d = vec3(dot(to_eye, t), dot(to_eye, b), dot(to_eye, n));
    vec3 a = abs(d);
    if (!(max(a.x, max(a.y, a.z)) > 0.0) || any(isnan(d)) || any(isinf(d))) {
        d = vec3(0.0, 0.0, 1.0);
        a = d;
    }
    uint axis;
    float major, u, v;
    if (a.x >= a.y && a.x >= a.z) {
        axis = 0u; major = d.x; u = d.y; v = d.z;
    } else if (a.y >= a.z) {
        axis = 1u; major = d.y; u = d.z; v = d.x;
    } else {
        axis = 2u; major = d.z; u = d.x; v = d.y;
    }
    uint face = axis * 2u + (major < 0.0 ? 1u : 0u);
    float inv = 1.0 / abs(major);
    uint k = max(batch.order, 1u);
    uint j0, j1, i0, i1;
    float fu, fv;
    axis_cells(u * inv, k, j0, j1, fu);
    axis_cells(v * inv, k, i0, i1, fv);

    uint base = batch.coeff_base + (uint(gl_VertexIndex) - batch.vertex_base) * batch.stride;
    uint row0 = (face * k + i0) * k;
    uint row1 = (face * k + i1) * k;
    vec3 radiance = cell_rgb(base, row0 + j0) * ((1.0 - fu) * (1.0 - fv))
        + cell_rgb(base, row0 + j1) * (fu * (1.0 - fv))
        + cell_rgb(base, row1 + j0) * ((1.0 - fu) * fv)
        + cell_rgb(base, row1 + j1) * (fu * fv);
    // Cube values are non-negative from a solve, but a file may hold negative
    // ones: clamp per vertex before interpolation, as solver::raster does.
    out_radiance = max(radiance * batch.scale, vec3(0.0));
    gl_Position = frame.view_projection[gl_ViewIndex] * vec4(in_position, 1.0);
}
