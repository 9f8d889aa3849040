// Random numbers for Monte Carlo: a PCG hash (O'Neill 2014) seeds a per-thread
// state that advances by one PCG step per sample.
#ifndef COMMON_RANDOM_GLSL
#define COMMON_RANDOM_GLSL

uint pcg_hash(uint v) {
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// Hashes both inputs before combining, so that two (a, b) pairs collide only
// by chance (probability 2^-32), never for whole batches of a.
uint rng_seed(uint a, uint b) { return pcg_hash(pcg_hash(a) ^ pcg_hash(b * 0x9e3779b9u + 0x632be5abu)); }

// Uniform in [0, 1).
float rng_next(inout uint state) {
    state = state * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    word = (word >> 22u) ^ word;
    return float(word >> 8u) * (1.0 / 16777216.0);
}

#endif
