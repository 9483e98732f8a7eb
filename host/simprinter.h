/*
 * simprinter.h - the built-in simulated printers (serial/sim/) started in
 * this process for a profile, sped up: what `stratum print` with no port
 * and the farm node's `port = sim` print to.  The link is sped up with
 * motion and heating (capped), so a small part prints in seconds.
 */
#ifndef STRATUM_HOST_SIMPRINTER_H
#define STRATUM_HOST_SIMPRINTER_H

#include "profile.h"
#include "sim/marlin_sim.h"
#include "sim/sailfish_sim.h"
#include "st_error.h"

/*
 * simprinter_marlin - start the simulated Marlin printer of prof (its RX
 * buffer, ADVANCED_OK) on its own thread, speedup times faster than real
 * time, its execution log in log_path (NULL: none).  *out is
 * sim_marlin_free'd by the caller; its pty is sim_marlin_slave_path.
 * Returns 0 or the simulator's error (ST_ERR_ARG, ST_ERR_IO, ST_ERR_NOMEM).
 */
int simprinter_marlin(const struct profile *prof, double speedup, const char *log_path,
		      struct sim_marlin **out, struct st_error *err);

/* simprinter_sailfish - the same for a Sailfish printer (sim_sailfish_free). */
int simprinter_sailfish(const struct profile *prof, double speedup, const char *log_path,
			struct sim_sailfish **out, struct st_error *err);

#endif /* STRATUM_HOST_SIMPRINTER_H */
