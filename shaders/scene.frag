#version 450
// Gouraud shading: the rasterizer interpolates each vertex's radiance
// (perspective-correct); the colour target holds linear radiance times the
// renderer's radiance scale.
layout(location = 0) in vec3 in_radiance;
layout(location = 0) out vec4 out_color;

void main() {
    out_color = vec4(in_radiance, 1.0);
}
