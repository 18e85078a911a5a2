#version 450
// Exposure and tone-map curve: linear radiance (resolved colour target, read as
// an input attachment, which with multiview reads this view's layer) to display
// values in 0..1; the sRGB attachment format applies the sRGB transfer function
// on store. Exposure is in stops (gain = 2^stops / radiance scale); the curves
// are solver::raster::tonemap's (runtime/src/render/tonemap.rs is the CPU twin):
//   0 clamp:    v
//   1 reinhard: v / (1 + v)
//   2 aces:     Narkowicz's fit (x(2.51x + 0.03)) / (x(2.43x + 0.59) + 0.14), at most 1
layout(input_attachment_index = 0, set = 0, binding = 0) uniform subpassInput linear_radiance;

layout(push_constant) uniform Params {
    // 2^exposure_stops / radiance scale: undoes the scene pass's scale, exposes.
    float gain;
    uint curve;
} params;

layout(location = 0) out vec4 out_color;

void main() {
    // Negative values (ringing of a truncated SH lobe) carry no light.
    vec3 v = max(subpassLoad(linear_radiance).rgb * params.gain, vec3(0.0));
    if (params.curve == 1u) {
        v = v / (1.0 + v);
    } else if (params.curve == 2u) {
        v = (v * (2.51 * v + 0.03)) / (v * (2.43 * v + 0.59) + 0.14);
    }
    out_color = vec4(clamp(v, 0.0, 1.0), 1.0);
}
