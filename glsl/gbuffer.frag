#version 450
// G-buffer: writes what deferred shading needs per pixel. Every surface reflects on both
// sides, so normals are turned towards the viewer; emission leaves front faces only unless the
// material is double-sided (CONVENTIONS.md).
#include "common.glsl"
#include "material.glsl"

layout(push_constant) uniform Draw {
    mat4 model;
    uint material;
    uint flags;
} draw;

layout(location = 0) in vec3 in_world;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 3) in vec4 in_tangent;

layout(location = 0) out vec4 gb_position;   // xyz world position, a 1 where covered
layout(location = 1) out vec4 gb_normals;    // xy shading normal, zw geometric normal (octahedral)
layout(location = 2) out vec4 gb_albedo;     // rgb base colour, a metallic
layout(location = 3) out vec4 gb_emission;   // rgb emitted radiance, a roughness
layout(location = 4) out vec4 gb_specular;   // rgb specular colour, a specular factor

void main() {
    Material m = material;
    vec4 base = m.base_color * texture(t_base_color, in_uv);
    if (m.params.w >= 0.0 && base.a < m.params.w) discard;

    // Geometric normal from the triangle itself, so it is right for any vertex normals.
    vec3 geo = normalize(cross(dFdx(in_world), dFdy(in_world)));
    bool front = gl_FrontFacing != ((draw.flags & 1u) != 0u);

    vec3 n = in_normal;
    float nl = length(n);
    n = nl > 1e-8 ? n / nl : geo;
    if (m.tex0.z >= 0) {
        vec3 t = in_tangent.xyz - n * dot(n, in_tangent.xyz);
        float tl = length(t);
        if (tl > 1e-8) {
            t /= tl;
            vec3 b = cross(n, t) * (in_tangent.w < 0.0 ? -1.0 : 1.0);
            vec3 tn = texture(t_normal, in_uv).xyz * 2.0 - 1.0;
            tn.xy *= m.params.z;
            vec3 mapped = t * tn.x + b * tn.y + n * tn.z;
            float ml = length(mapped);
            if (ml > 1e-8) n = mapped / ml;
        }
    }
    // Turn both normals towards the viewer.
    vec3 v = frame.eye.xyz - in_world;
    if (dot(geo, v) < 0.0) geo = -geo;
    if (!front) n = -n;
    if (dot(n, v) < 0.0) n = reflect(n, geo);

    vec4 mr = texture(t_metallic_roughness, in_uv);
    float metallic = clamp(m.params.x * mr.b, 0.0, 1.0);
    float roughness = clamp(m.params.y * mr.g, 0.0, 1.0);
    vec3 emission = vec3(0.0);
    if (front || m.tex1.z != 0) {
        emission = m.emissive.rgb * texture(t_emissive, in_uv).rgb;
    }
    float spec = m.specular.a * texture(t_specular, in_uv).a;
    vec3 spec_color = m.specular.rgb * texture(t_specular_color, in_uv).rgb;

    gb_position = vec4(in_world, 1.0);
    gb_normals = vec4(oct_encode(n), oct_encode(geo));
    gb_albedo = vec4(base.rgb, metallic);
    gb_emission = vec4(emission, roughness);
    gb_specular = vec4(spec_color, spec);
}
