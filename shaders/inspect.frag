#version 450
// Inspection lines: one constant colour (see inspect.vert).
layout(push_constant) uniform Inspect {
    vec4 color;
    float normal_length;
    float pull;
} inspect;

layout(location = 0) out vec4 out_color;

void main() {
    out_color = inspect.color;
}
