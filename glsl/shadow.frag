#version 450
// Shadow map: alpha-masked surfaces cast masked shadows.
#include "common.glsl"
#include "material.glsl"

layout(push_constant) uniform Draw {
    mat4 model;
    uint material;
    uint view;
} draw;

layout(location = 0) in vec2 in_uv;

void main() {
    Material m = material;
    if (m.params.w >= 0.0) {
        float a = m.base_color.a * texture(t_base_color, in_uv).a;
        if (a < m.params.w) discard;
    }
}
