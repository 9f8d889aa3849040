#version 460
// Still-view accumulation (issue 28): the running mean of the frames of a
// view that has not changed, so that a technique's stochastic estimates
// (direct's sky visibility, the airlight's jittered strata), drawn anew each
// still frame (`frame.components.z`, the still frames so far), converge
// instead of leaving grain. `frames`: how many frames the history holds
// (0: a new view, the history restarts from this frame).
//     mean_{k+1} = mean_k + (L - mean_k) / (k + 1)
// The radiance image then holds the mean (its alpha, the frame's coverage,
// is the current frame's), so the tonemap, read-backs and outputs see it.

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, rgba32f) uniform image2D radiance;
layout(set = 0, binding = 1, rgba32f) uniform image2D history;
layout(push_constant) uniform Push { uint frames; } pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(radiance)))) return;
    vec4 l = imageLoad(radiance, p);
    vec3 mean = l.rgb;
    if (pc.frames > 0u) {
        vec3 previous = imageLoad(history, p).rgb;
        mean = previous + (l.rgb - previous) / float(pc.frames + 1u);
    }
    imageStore(history, p, vec4(mean, 1.0));
    imageStore(radiance, p, vec4(mean, l.a));
}
