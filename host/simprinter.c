/*
 * simprinter.c - built-in simulated printers for a profile (simprinter.h).
 */
#include "simprinter.h"

#include <stddef.h>

#define SIM_BAUD_MAX 20000000.0 /* sped-up link of the simulated printer, bits/s */

/* The profile's link sped up like the rest, within what a pty keeps up with. */
static unsigned simprinter_baud(const struct profile *prof, double speedup)
{
	double baud = (double)(prof->baudrate > 0 ? prof->baudrate : 115200) * speedup;

	return (unsigned)(baud > SIM_BAUD_MAX ? SIM_BAUD_MAX : baud);
}

int simprinter_marlin(const struct profile *prof, double speedup, const char *log_path,
		      struct sim_marlin **out, struct st_error *err)
{
	struct sim_marlin_options so;
	int rc;

	*out = NULL;
	sim_marlin_options_init(&so);
	so.speedup = speedup;
	so.baud = simprinter_baud(prof, speedup);
	if (prof->rx_buffer_size > 0)
		so.rx_buffer = (unsigned)prof->rx_buffer_size;
	so.advanced_ok = true;
	so.log_path = log_path;
	if ((rc = sim_marlin_new(&so, out, err)))
		return rc;
	if ((rc = sim_marlin_start_thread(*out, err))) {
		sim_marlin_free(*out);
		*out = NULL;
	}
	return rc;
}

int simprinter_sailfish(const struct profile *prof, double speedup, const char *log_path,
			struct sim_sailfish **out, struct st_error *err)
{
	struct sim_sailfish_options so;
	int rc;

	*out = NULL;
	sim_sailfish_options_init(&so);
	so.speedup = speedup;
	so.baud = simprinter_baud(prof, speedup);
	so.log_path = log_path;
	if ((rc = sim_sailfish_new(&so, out, err)))
		return rc;
	if ((rc = sim_sailfish_start_thread(*out, err))) {
		sim_sailfish_free(*out);
		*out = NULL;
	}
	return rc;
}
