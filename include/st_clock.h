/*
 * st_clock.h - the one monotonic clock, header-only like st_error.h so
 * every layer may use it: seconds (and milliseconds) since an arbitrary
 * start, never going back when the wall clock is set.  Every time-out and
 * rate in the program is measured with it.
 */
#ifndef STRATUM_ST_CLOCK_H
#define STRATUM_ST_CLOCK_H

#include <stdint.h>
#include <time.h>

/* Monotonic time in seconds. */
static inline double st_mono_s(void)
{
	struct timespec ts;

	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

/* Monotonic time in whole milliseconds. */
static inline int64_t st_mono_ms(void)
{
	struct timespec ts;

	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (int64_t)ts.tv_sec * 1000 + ts.tv_nsec / 1000000;
}

#endif /* STRATUM_ST_CLOCK_H */
