// A material's factors and textures (set 1, bound per material). Absent textures are bound to a
// 1x1 white texture, which leaves every factor unchanged.
#ifndef MATERIAL_GLSL
#define MATERIAL_GLSL

layout(set = 1, binding = 0) uniform sampler2D t_base_color;
layout(set = 1, binding = 1) uniform sampler2D t_metallic_roughness;
layout(set = 1, binding = 2) uniform sampler2D t_normal;
layout(set = 1, binding = 3) uniform sampler2D t_emissive;
layout(set = 1, binding = 4) uniform sampler2D t_specular;
layout(set = 1, binding = 5) uniform sampler2D t_specular_color;
// Uniform, not a storage buffer indexed by the draw: every fragment of a draw reads the same.
layout(set = 1, binding = 6, std140) uniform MaterialFactors { Material material; };

#endif
