/*
 * printer_profile.c - profile to printer.h options (printer_profile.h).
 */
#include "printer_profile.h"

#include <stdio.h>
#include <string.h>

#include "commands.h"
#include "portpick.h"
#include "profile_x3g.h"

int printer_profile_options(const struct profile *prof, const char *port, long baud,
			    struct printer_options *o, const struct printer_ops **ops,
			    struct st_error *err)
{
	int rc;

	printer_options_init(o);
	o->port = port;
	o->baud = baud ? baud : prof->baudrate;
	o->dtr_reset = prof->dtr_reset;
	o->rx_buffer = prof->rx_buffer_size > 0 ? (unsigned)prof->rx_buffer_size : 0;
	o->bufsize = prof->bufsize > 0 ? (unsigned)prof->bufsize : 0;
	if (prof->protocol != PROFILE_PROTOCOL_SAILFISH) {
		*ops = &printer_marlin_ops;
		return 0;
	}
	*ops = &printer_sailfish_ops;
	if ((rc = profile_x3g_machine(prof, &o->machine, &o->x3g.flavor, err)))
		return rc;
	return 0;
}

int printer_profile_cli(const char *cmd, const struct profile *prof, const char **port,
			long baud, bool quiet, char **port_auto, struct printer_options *o,
			const struct printer_ops **ops)
{
	struct st_error err = {0};

	if (!strcmp(*port, "auto")) {
		char why[512] = "";

		if (portpick_auto(prof, port_auto, why, sizeof(why), &err)) {
			fprintf(stderr, "%s: %s\n", cmd, err.msg); /* it says --port auto */
			return ST_EXIT_UNAVAILABLE;
		}
		if (!quiet)
			fprintf(stderr, "%s: --port auto: %s\n", cmd, why);
		*port = *port_auto;
	}
	if (printer_profile_options(prof, *port, baud, o, ops, &err))
		return cmd_fail(cmd, ST_EXIT_DATAERR, "%s: %s", prof->path, err.msg);
	return 0;
}
