#version 450
// Antialiasing by accumulation: the conventions' pixel is the mean over its footprint. While
// the view holds still, each frame's G-buffer is drawn with the camera shifted by a sub-pixel
// offset (accumulate.rs: jitter), and this pass keeps the running mean of the frames' radiance:
// weight 1 / (frames so far) up to the setting's count, then 0 (the mean is complete; anything
// that changes the view starts it again). The mean goes back into the radiance image, which
// the readback and the window show.
layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0, rgba32f) uniform image2D radiance;
layout(set = 0, binding = 1, rgba32f) uniform image2D history;

layout(push_constant) uniform Accumulate {
    uvec2 size;
    float weight;  // this frame's share of the mean (1: the mean starts again)
} acc;

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(px), acc.size))) return;
    vec4 current = imageLoad(radiance, px);
    // A new mean never reads the history (it holds another view's light, or nothing yet).
    vec4 mean = acc.weight >= 1.0 ? current : mix(imageLoad(history, px), current, acc.weight);
    imageStore(history, px, mean);
    imageStore(radiance, px, mean);
}
