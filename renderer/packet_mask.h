/* A packet's rays as a 64-bit mask: its lowest set bit and its count. */
#ifndef RTSIM_RENDERER_PACKET_MASK_H
#define RTSIM_RENDERER_PACKET_MASK_H

#include <stdint.h>

static inline int packet_mask_first(uint64_t m) { return __builtin_ctzll(m); }

/* Written out: __builtin_popcountll is a libgcc call without -mpopcnt. */
static inline uint32_t packet_mask_count(uint64_t m) {
  m = m - ((m >> 1) & 0x5555555555555555ull);
  m = (m & 0x3333333333333333ull) + ((m >> 2) & 0x3333333333333333ull);
  m = (m + (m >> 4)) & 0x0f0f0f0f0f0f0f0full;
  return (uint32_t)((m * 0x0101010101010101ull) >> 56);
}

#endif
