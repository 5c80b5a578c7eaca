#version 450
// Voxelization, step 1 of the paper: vertices to world space; the geometry shader projects.
#include "common.glsl"

layout(push_constant) uniform Draw {
    mat4 model;
    uint material;
    uint flags;
} draw;

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;

layout(location = 0) out vec3 v_world;
layout(location = 1) out vec3 v_normal;
layout(location = 2) out vec2 v_uv;

void main() {
    vec4 world = draw.model * vec4(in_position, 1.0);
    v_world = world.xyz;
    v_normal = transpose(inverse(mat3(draw.model))) * in_normal;
    v_uv = in_uv;
    gl_Position = world;
}
