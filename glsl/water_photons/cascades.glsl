// Algorithm 1 of Kougianos & Moustakas 2021 (distribution of CCM dispatch
// threads), with the corrections documented in src/cascades.rs, operation
// for operation as `CascadeLayout::texel_of` (tests/water_photons.rs checks
// the two agree): thread -> (texel of ccm_0, cascade c).
#ifndef WATER_PHOTONS_CASCADES_GLSL
#define WATER_PHOTONS_CASCADES_GLSL

// False past the last thread of Eq. 5.
bool ccm_texel_of(uint thread, uvec2 size, uvec2 border, uint levels, out uvec2 texel, out uint cascade) {
    uint w = size.x, h = size.y, dx = border.x, dy = border.y;
    texel = uvec2(0u);
    cascade = 0u;
    if (thread < w * h) {
        texel = uvec2(thread % w, thread / w);
        return true;
    }
    // Eq. 4: the ring of every cascade above 0.
    uint ring = w * h - (w - 2u * dx) * (h - 2u * dy);
    if (ring == 0u) return false;
    uint beyond = thread - w * h;
    cascade = 1u + beyond / ring;
    if (cascade >= levels) return false;
    uint local = beyond % ring;
    uint region0 = w * dy;                           // ΔY full rows at the top
    uint region1 = region0 + 2u * dx * (h - 2u * dy); // ΔX columns each side
    if (local < region0) {
        texel = uvec2(local % w, local / w);
    } else if (local < region1) {
        uint l = local - region0;
        uint x = l % (2u * dx);
        // The right-hand column block starts at W − ΔX (x ≥ ΔX, corrected line 26).
        if (x >= dx) x += w - 2u * dx;
        texel = uvec2(x, dy + l / (2u * dx));
    } else {
        uint l = local - region1;
        texel = uvec2(l % w, h - dy + l / w);
    }
    return true;
}

#endif
