/* fovea: the one monotonic clock. Every timestamp in fovea (stage times, trace events, camera
 * frames, vsync edges, photon times) is CLOCK_MONOTONIC in nanoseconds, so they compare directly. */
#ifndef FOVEA_BASE_CLOCK_H
#define FOVEA_BASE_CLOCK_H

#include <stdint.h>

int64_t fv_time_ns(void); /* CLOCK_MONOTONIC, ns */

static inline double fv_ns_to_ms(int64_t ns) { return (double)ns * 1e-6; }

#endif
