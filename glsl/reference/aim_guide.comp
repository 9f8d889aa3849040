#version 460
// Rebuilds the aim guide (aim_guide.glsl) before a photon pass: folds the
// last pass's counts into each cell's importance I_c, then sets
// g_c = (1 - m) + m I_c / mean(I) (uniform while nothing was useful),
// normalised to mean 1, and the row and column CDFs `guide_sample` draws
// from. One workgroup per light, one invocation per row.
#include "common.glsl"
#include "aim_guide.glsl"

layout(local_size_x = 64) in;

shared float row_importance[GUIDE_ROWS];
shared float row_density[GUIDE_ROWS];

void main() {
    uint l = gl_WorkGroupID.x;
    for (uint row = gl_LocalInvocationID.x; row < GUIDE_ROWS; row += gl_WorkGroupSize.x) {
        float sum = 0.0;
        for (uint column = 0u; column < GUIDE_COLUMNS; ++column) {
            uint i = row * GUIDE_COLUMNS + column;
            float importance = guide_word(l, GUIDE_IMPORTANCE, i) + guide_word(l, GUIDE_COUNTS, i);
            aim_guide[guide_index(l, GUIDE_IMPORTANCE, i)] = importance;
            aim_guide[guide_index(l, GUIDE_COUNTS, i)] = 0.0;
            sum += importance;
        }
        row_importance[row] = sum;
    }
    barrier();
    float total = 0.0;
    for (uint row = 0u; row < GUIDE_ROWS; ++row) total += row_importance[row];
    float mean = total / float(GUIDE_CELLS);
    for (uint row = gl_LocalInvocationID.x; row < GUIDE_ROWS; row += gl_WorkGroupSize.x) {
        float sum = 0.0;
        for (uint column = 0u; column < GUIDE_COLUMNS; ++column) {
            uint i = row * GUIDE_COLUMNS + column;
            float g = mean > 0.0
                ? (1.0 - GUIDE_LEARNED_SHARE) + GUIDE_LEARNED_SHARE * guide_word(l, GUIDE_IMPORTANCE, i) / mean
                : 1.0;
            sum += g;
            aim_guide[guide_index(l, GUIDE_DENSITY, i)] = g;
            aim_guide[guide_index(l, GUIDE_COLUMN_CDF, i)] = sum;
        }
        for (uint column = 0u; column < GUIDE_COLUMNS; ++column) {
            uint i = row * GUIDE_COLUMNS + column;
            aim_guide[guide_index(l, GUIDE_COLUMN_CDF, i)] /= sum;
        }
        row_density[row] = sum;
    }
    barrier();
    float density_total = 0.0;
    for (uint row = 0u; row < GUIDE_ROWS; ++row) density_total += row_density[row];
    for (uint row = gl_LocalInvocationID.x; row < GUIDE_ROWS; row += gl_WorkGroupSize.x) {
        float below = 0.0;
        for (uint r = 0u; r <= row; ++r) below += row_density[r];
        aim_guide[guide_index(l, GUIDE_ROW_CDF, row)] = below / density_total;
        // g as the pdf over the square: the cell's probability times the cells.
        for (uint column = 0u; column < GUIDE_COLUMNS; ++column) {
            uint i = row * GUIDE_COLUMNS + column;
            aim_guide[guide_index(l, GUIDE_DENSITY, i)] *= float(GUIDE_CELLS) / density_total;
        }
    }
}
