#version 450
#extension GL_EXT_multiview : require
// Mesh inspection lines (Remington 1992, app. D: prorad's -w wireframe and -n normals),
// drawn in the scene subpass into the linear radiance target.
//
// Edges: an indexed LINE_LIST over the batch's vertices (normal_length = 0).
// Normals: two vertices per instance, one instance per mesh vertex (the vertex
// attributes advance per instance); vertex 1 is moved along the normal.
//
// Each end is pulled toward the eye by `pull` of its distance, so a line on a
// surface is in front of it in the depth test (a relative offset: the same at
// every distance) while a line behind a surface stays hidden.

layout(std140, set = 0, binding = 0) uniform Frame {
    mat4 view_projection[2];
    vec4 eye_position[2];
} frame;

layout(push_constant) uniform Inspect {
    // Written as is to the linear target (radiance times the radiance scale,
    // chosen on the CPU so that it tone-maps to the wanted display colour).
    vec4 color;
    float normal_length;
    float pull;
} inspect;

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;

void main() {
    vec3 p = in_position;
    if (inspect.normal_length > 0.0 && gl_VertexIndex == 1) {
        p += in_normal * inspect.normal_length;
    }
    p = mix(p, frame.eye_position[gl_ViewIndex].xyz, inspect.pull);
    gl_Position = frame.view_projection[gl_ViewIndex] * vec4(p, 1.0);
}
