/* Deterministic random numbers: a counter-free hash for stream seeds and a
 * small PCG32 stream. State is always a value the caller owns (no globals), and
 * streams are keyed by (seed, pixel, path) so results never depend on order. */
#ifndef RTSIM_RENDERER_RNG_H
#define RTSIM_RENDERER_RNG_H

#include <stdint.h>

/* Finaliser of SplitMix64: a good 64-bit mixing function. */
static inline uint64_t rng_mix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

static inline uint64_t rng_hash2(uint64_t a, uint64_t b) { return rng_mix64(a ^ rng_mix64(b)); }

struct rng {
  uint64_t state, inc;
};

static inline struct rng rng_make(uint64_t seed, uint64_t stream) {
  struct rng r;
  r.inc = (rng_mix64(stream) << 1) | 1u;
  r.state = rng_mix64(seed) + r.inc;
  return r;
}

/* PCG32 (XSH RR): uniform 32-bit value. */
static inline uint32_t rng_u32(struct rng *r) {
  uint64_t old = r->state;
  r->state = old * 6364136223846793005ull + r->inc;
  uint32_t xs = (uint32_t)(((old >> 18) ^ old) >> 27);
  uint32_t rot = (uint32_t)(old >> 59);
  return (xs >> rot) | (xs << ((32 - rot) & 31));
}

/* Uniform float in [0, 1). */
static inline float rng_f32(struct rng *r) {
  return (float)(rng_u32(r) >> 8) * (1.0f / 16777216.0f);
}

#endif
