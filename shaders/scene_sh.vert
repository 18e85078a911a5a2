#version 450
#extension GL_EXT_multiview : require
#extension GL_GOOGLE_include_directive : require
// Glossy batches: evaluate the vertex's SH toward this view's eye. Compiled
// with -DTEXTURED for textured batches of any order (their coefficients hold
// the untextured part; the textured part is passed on to scene_textured.frag).
//
// The direction from the vertex to the eye is taken into the vertex frame
// (x = tangent t, y = n × t, z = normal n; design notes, "Local frames and SH")
// and the real orthonormal basis (no Condon–Shortley phase) is evaluated with
// exactly the recurrences of solver::sh::eval_basis_f32, so the solver's tests
// of that function state this shader's precision:
//   Q_00 = 1/sqrt(4π), Q_mm = sqrt((2m+1)/(2m)) Q_{m-1,m-1},
//   Q_{m+1,m} = sqrt(2m+3) z Q_mm,
//   Q_lm = a_lm (z Q_{l-1,m} − b_lm Q_{l-2,m}),
//   C_m + i S_m = (x + iy)^m,  Y_l0 = Q_l0,  Y_l,±m = √2 Q_lm (C_m | S_m).
// The loop bound is the batch's order from the push constant.
#include "scene_common.glsl"

const float Y00 = 0.28209479177387814;
const float SQRT2 = 1.4142135623730951;

vec3 coefficient_rgb(uint base, uint k) {
    uint i = base + 3u * k;
    return vec3(coefficient(i), coefficient(i + 1u), coefficient(i + 2u));
}

void main() {
    vec3 eye = frame.eye_position[gl_ViewIndex].xyz;
    vec3 n = in_normal;
    vec3 t = in_tangent;
    vec3 b = cross(n, t);
    vec3 to_eye = eye - in_position;
    vec3 d = vec3(dot(to_eye, t), dot(to_eye, b), dot(to_eye, n));
    float len = length(d);
    // An eye exactly at the vertex has no direction: use the normal, as
    // eval_basis_f32 does for a zero direction.
    d = len > 0.0 ? d / len : vec3(0.0, 0.0, 1.0);
    float x = d.x, y = d.y, z = d.z;

    uint base = batch.coeff_base + (uint(gl_VertexIndex) - batch.vertex_base) * batch.stride;
    int order = int(batch.order);
    vec3 radiance = vec3(0.0);
    float c = 1.0, s = 0.0;
    float q_mm = Y00;
    for (int m = 0; m <= order; ++m) {
        float mf = float(m);
        if (m > 0) {
            q_mm *= sqrt((2.0 * mf + 1.0) / (2.0 * mf));
            float c_next = x * c - y * s;
            s = x * s + y * c;
            c = c_next;
        }
        // k = l² + l ± m; the basis value of (l, ±m) is √2 Q_lm (C_m | S_m).
        float wc = m == 0 ? 1.0 : SQRT2 * c;
        float ws = SQRT2 * s;
        // l = m
        uint k0 = uint(m * m + m);
        radiance += coefficient_rgb(base, k0 + uint(m)) * (q_mm * wc);
        if (m > 0) radiance += coefficient_rgb(base, k0 - uint(m)) * (q_mm * ws);
        if (m == order) break;
        // l = m + 1
        float q_prev = q_mm;
        float q = sqrt(2.0 * mf + 3.0) * z * q_mm;
        int l1 = m + 1;
        uint k1 = uint(l1 * l1 + l1);
        radiance += coefficient_rgb(base, k1 + uint(m)) * (q * wc);
        if (m > 0) radiance += coefficient_rgb(base, k1 - uint(m)) * (q * ws);
        for (int l = m + 2; l <= order; ++l) {
            float lf = float(l);
            float a = sqrt((4.0 * lf * lf - 1.0) / (lf * lf - mf * mf));
            float lm1 = lf - 1.0;
            float bb = sqrt((lm1 * lm1 - mf * mf) / (4.0 * lm1 * lm1 - 1.0));
            float q_next = a * (z * q - bb * q_prev);
            q_prev = q;
            q = q_next;
            uint kl = uint(l * l + l);
            radiance += coefficient_rgb(base, kl + uint(m)) * (q * wc);
            if (m > 0) radiance += coefficient_rgb(base, kl - uint(m)) * (q * ws);
        }
    }
    // Negative radiance (ringing of a truncated lobe) carries no light: clamp per
    // vertex before interpolation, as solver::raster does.
    out_radiance = max(radiance * batch.scale, vec3(0.0));
#ifdef TEXTURED
    write_textured();
#endif
    gl_Position = frame.view_projection[gl_ViewIndex] * vec4(in_position, 1.0);
}
