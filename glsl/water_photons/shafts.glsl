// water_photons: the tube of a shaft (shafts.vert, shafts.frag). Requires
// common.glsl (the Photon record).
//
// A refracted photon whose texel starts a k x k block of texels (k =
// `shaft_stride`, in the record's surface_u.w) stands for the block: its
// differential's axes times k (to first order the block's footprint, on
// the water and on the receiver), its ray moved to the block's centre by
// (k − 1)/2 of each axis at both ends, and k² times its flux. For flat
// water the blocks tile exactly, as the texels do (and the cascades' rings
// start at multiples of k for s = 2 and power-of-two maps); over waves the
// block takes its first texel's flux and bend, so k trades the shafts'
// finest detail (k texels) for a cost that goes as 1/k; at the water's
// edge a block carries k² times its first texel's flux even where some of
// its texels hold no water. k must divide the maps' side and their rings'
// border (`check_shaft_stride`), where the cascades meet.
#ifndef WATER_PHOTONS_SHAFTS_GLSL
#define WATER_PHOTONS_SHAFTS_GLSL

struct ShaftTube {
    vec3 start;     // on the water
    vec3 dir;       // unit, from start to the receiver
    float len;      // start to the receiver (m)
    vec3 surface_u; // the cross-section's axes at the start
    vec3 surface_v;
    vec3 end_u;     // and at the receiver
    vec3 end_v;
    vec3 flux;      // W, at the receiver (the water's extinction over len already taken)
};

// False for a photon that draws no shaft (reflected, or inside a block).
bool shaft_tube(Photon p, out ShaftTube t) {
    float k = p.surface_u.w;
    if (uint(p.axis_u.w) != WP_RAY_REFRACTED || !(k >= 1.0)) return false;
    float centre = 0.5 * (k - 1.0);
    vec3 hit = p.position.xyz;
    vec3 start = hit - p.dir.xyz * p.axis_v.w + centre * (p.surface_u.xyz + p.surface_v.xyz);
    vec3 end = hit + centre * (p.axis_u.xyz + p.axis_v.xyz);
    t.start = start;
    t.len = length(end - start);
    if (!(t.len > 0.0)) return false;
    t.dir = (end - start) / t.len;
    t.surface_u = k * p.surface_u.xyz;
    t.surface_v = k * p.surface_v.xyz;
    t.end_u = k * p.axis_u.xyz;
    t.end_v = k * p.axis_v.xyz;
    t.flux = k * k * p.flux.rgb;
    return true;
}

#endif
