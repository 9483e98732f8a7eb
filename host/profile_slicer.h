/*
 * profile_slicer.h - the slicer's settings (slicer/slicer.h) from a printer
 * profile (profile.h): PrusaSlicer's keys mapped to the stages' fields.
 * Shared by `stratum slice` and the farm node (host/serve/) so an upload
 * sliced on the node gives the same G-code as the command line.  Lives in
 * host/ so slicer/ never includes host/.
 */
#ifndef STRATUM_HOST_PROFILE_SLICER_H
#define STRATUM_HOST_PROFILE_SLICER_H

#include "profile.h"
#include "slicer.h"
#include "st_error.h"

/*
 * profile_slicer_config - fill *c from profile p: slicer_config_init with
 * the first nozzle, then every setting the profile has.  The bed has no
 * centre override and threads is 0 (all cores); callers change those
 * fields afterwards.  The result is not range-checked here
 * (slicer_config_check does that).
 * Returns 0: every value was typed and range-checked when the profile was
 * loaded (err is kept for callers; it is never filled).
 * Thread-safe: reads p only.
 */
int profile_slicer_config(const struct profile *p, struct slicer_config *c,
			  struct st_error *err);

#endif /* STRATUM_HOST_PROFILE_SLICER_H */
