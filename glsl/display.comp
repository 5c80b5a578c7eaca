#version 450
// The window's display image, as `voxgi render --out FILE.png` makes it (src/output.rs):
// radiance x 2^exposure, the ACES filmic curve (Narkowicz's fit), then sRGB encoding, unless
// the swapchain's format encodes sRGB itself.

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, rgba32f) uniform readonly image2D radiance;
layout(set = 0, binding = 1, rgba8) uniform writeonly image2D display;

layout(push_constant) uniform Pass {
    float scale;        // 2^exposure
    uint encode_srgb;   // 0 when the swapchain image is an sRGB format
} pass;

vec3 aces(vec3 x) {
    x = max(x, vec3(0.0));
    return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
}

vec3 srgb_encode(vec3 v) {
    return mix(1.055 * pow(v, vec3(1.0 / 2.4)) - 0.055, v * 12.92, lessThanEqual(v, vec3(0.0031308)));
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, imageSize(display)))) return;
    vec3 v = imageLoad(radiance, px).rgb;
    // Non-finite radiance shows black, as in the PNG.
    for (int i = 0; i < 3; i++) {
        if (isnan(v[i]) || isinf(v[i])) v[i] = 0.0;
    }
    vec3 c = aces(v * pass.scale);
    if (pass.encode_srgb != 0u) c = srgb_encode(c);
    imageStore(display, px, vec4(c, 1.0));
}
