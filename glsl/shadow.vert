#version 450
// Shadow map: depth of the scene as one light view sees it.
#include "common.glsl"

layout(push_constant) uniform Draw {
    mat4 model;
    uint material;
    uint view;
} draw;

layout(location = 0) in vec3 in_position;
layout(location = 2) in vec2 in_uv;
layout(location = 0) out vec2 out_uv;

void main() {
    out_uv = in_uv;
    gl_Position = shadow_views[draw.view].view_proj * (draw.model * vec4(in_position, 1.0));
}
