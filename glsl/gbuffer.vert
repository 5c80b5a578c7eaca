#version 450
// G-buffer: transforms object-space vertices by the instance's world matrix.
#include "common.glsl"

layout(push_constant) uniform Draw {
    mat4 model;
    uint material;
    uint flags;   // bit 0: the transform mirrors (winding flipped)
} draw;

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 3) in vec4 in_tangent;

layout(location = 0) out vec3 out_world;
layout(location = 1) out vec3 out_normal;
layout(location = 2) out vec2 out_uv;
layout(location = 3) out vec4 out_tangent;

void main() {
    vec4 world = draw.model * vec4(in_position, 1.0);
    mat3 m = mat3(draw.model);
    mat3 normal_matrix = transpose(inverse(m));
    out_world = world.xyz;
    out_normal = normal_matrix * in_normal;
    out_uv = in_uv;
    out_tangent = vec4(m * in_tangent.xyz, in_tangent.w);
    gl_Position = frame.view_proj * world;
}
