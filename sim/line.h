/* The line: what the timed machine's caches hold and what the L2 and every
 * DRAM level move, 64 bytes, aligned. One definition, so a cache, a DRAM
 * request and a byte count cannot disagree on it. (The functional traffic
 * model's line is a parameter of its own: sim/mem_functional.h.) */
#ifndef RTSIM_SIM_LINE_H
#define RTSIM_SIM_LINE_H

#define SIM_LINE_LG2 6
#define SIM_LINE_BYTES (1u << SIM_LINE_LG2)

#endif
