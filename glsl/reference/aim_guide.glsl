// The aim guide: where the aimed photons of each point, spot and
// directional light go (trace.comp `emit`), learned from the passes before.
//
// Aiming draws a point u of the unit square and maps it uniformly onto the
// aimed region: the cone toward the specular objects' bounding sphere for a
// point or spot light (u.x = (1 - cos theta) / (1 - cos theta_max), u.y =
// phi / 2 pi, `uniform_cone`), the disk the sphere projects for a
// directional light (u.x = (rho / R)^2, u.y = phi / 2 pi). Most of that
// region can be useless to the image: on ball_lens_top 1% of the aimed
// photons land where the camera sees the floor through the ball (the rays
// near the sphere's rim). The guide draws u from a piecewise-constant
// density g over a ROWS x COLUMNS grid of the square instead of uniformly,
// and the photon's pdf carries g (the estimate stays unbiased for any g > 0).
//
// g comes from visual importance (Peter & Pietrek 1998, "Importance driven
// construction of photon maps"), in the binary form of Hachisuka & Jensen
// 2011 ("Robust adaptive photon tracing using photon path visibility"): a
// photon is *useful* when it reaches the image, by a camera connection, a
// visible point within the gather radius, or a stored volume photon. Each
// useful aimed photon adds 1/g of its cell to the cell's count, so a cell's
// importance I_c (summed over every pass so far) estimates the useful
// photons it would send under uniform aiming, whatever g was. The next pass
// aims by the defensive mixture
//     g_c = (1 - m) + m I_c / mean(I),   m = GUIDE_LEARNED_SHARE,
// so no cell falls below 1 - m of the uniform density (a photon's weight
// grows at most 1 / (1 - m) times) and g is uniform until something was
// useful. aim_guide.comp folds the counts and rebuilds g and its CDFs
// before every photon pass.
#ifndef REFERENCE_AIM_GUIDE_GLSL
#define REFERENCE_AIM_GUIDE_GLSL

// Per light (index l < frame.counts.x) GUIDE_WORDS floats at l * GUIDE_WORDS.
layout(set = 1, binding = REFERENCE_BINDING_AIM_GUIDE, std430) buffer AimGuide { float aim_guide[]; };

const uint GUIDE_ROWS = REFERENCE_GUIDE_ROWS;
const uint GUIDE_COLUMNS = REFERENCE_GUIDE_COLUMNS;
const uint GUIDE_CELLS = GUIDE_ROWS * GUIDE_COLUMNS;
// Offsets within one light's words.
const uint GUIDE_COUNTS = 0u;                    // this pass: sum of 1/g over useful aimed photons
const uint GUIDE_IMPORTANCE = GUIDE_CELLS;       // I_c, summed over passes
const uint GUIDE_DENSITY = 2u * GUIDE_CELLS;     // g_c, mean 1 over the square
const uint GUIDE_COLUMN_CDF = 3u * GUIDE_CELLS;  // within each row, inclusive
const uint GUIDE_ROW_CDF = 4u * GUIDE_CELLS;     // over the rows, inclusive
const uint GUIDE_WORDS = 4u * GUIDE_CELLS + GUIDE_ROWS;
const float GUIDE_LEARNED_SHARE = 0.75;

uint guide_index(uint l, uint offset, uint i) { return l * GUIDE_WORDS + offset + i; }
float guide_word(uint l, uint offset, uint i) { return aim_guide[guide_index(l, offset, i)]; }

uint guide_cell(vec2 u) {
    uvec2 c = min(uvec2(max(u, vec2(0.0)) * vec2(GUIDE_ROWS, GUIDE_COLUMNS)),
                  uvec2(GUIDE_ROWS - 1u, GUIDE_COLUMNS - 1u));
    return c.x * GUIDE_COLUMNS + c.y;
}

// g at the point u of light l's square.
float guide_density(uint l, vec2 u) { return guide_word(l, GUIDE_DENSITY, guide_cell(u)); }

// The first of the n inclusive CDF entries at `offset` above u, and where u
// falls between it and the entry before, in [0, 1).
uint guide_search(uint l, uint offset, uint n, float u, out float fraction) {
    uint lo = 0u, hi = n - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (guide_word(l, offset, mid) > u) hi = mid;
        else lo = mid + 1u;
    }
    float below = lo == 0u ? 0.0 : guide_word(l, offset, lo - 1u);
    float above = guide_word(l, offset, lo);
    fraction = clamp((u - below) / max(above - below, 1e-30), 0.0, 0.99999994);
    return lo;
}

// Maps a uniform u to a point of the square distributed by light l's g
// (a row by the row CDF, a column by that row's CDF, the point uniform in
// the cell); `cell` and `density` (g there) for the photon's pdf and count.
vec2 guide_sample(uint l, vec2 u, out uint cell, out float density) {
    float fx, fy;
    uint row = guide_search(l, GUIDE_ROW_CDF, GUIDE_ROWS, u.x, fx);
    uint column = guide_search(l, GUIDE_COLUMN_CDF + row * GUIDE_COLUMNS, GUIDE_COLUMNS, u.y, fy);
    cell = row * GUIDE_COLUMNS + column;
    density = guide_word(l, GUIDE_DENSITY, cell);
    return vec2((float(row) + fx) / float(GUIDE_ROWS), (float(column) + fy) / float(GUIDE_COLUMNS));
}

#endif
