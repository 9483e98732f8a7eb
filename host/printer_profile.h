/*
 * printer_profile.h - a printer profile as printer.h options: the one
 * place in host/ that knows which dialect a profile speaks.  `stratum
 * send`, `stratum print` and the farm node open their printers through it.
 */
#ifndef STRATUM_HOST_PRINTER_PROFILE_H
#define STRATUM_HOST_PRINTER_PROFILE_H

#include "printer.h"
#include "profile.h"
#include "st_error.h"

/*
 * printer_profile_options - the options and operations for printer prof
 * on port (a device, pty, tcp:// or "sim"); baud 0 = the profile's.
 * Strings are borrowed (prof and port must outlive the printer).  Returns
 * 0, or the profile's error class (a Sailfish profile without a usable
 * machine definition) with err naming the key.
 */
int printer_profile_options(const struct profile *prof, const char *port, long baud,
			    struct printer_options *o, const struct printer_ops **ops,
			    struct st_error *err);

/*
 * printer_profile_cli - what `stratum send`, `print` and `console` do
 * before they open a printer: *port "auto" becomes the port host/portpick.h
 * picks (why it was picked said on stderr unless quiet; *port_auto holds
 * it, free it), then printer_profile_options.  0, or the exit status
 * (st_error.h) after "CMD: ..." on stderr.
 */
int printer_profile_cli(const char *cmd, const struct profile *prof, const char **port,
			long baud, bool quiet, char **port_auto, struct printer_options *o,
			const struct printer_ops **ops);

#endif /* STRATUM_HOST_PRINTER_PROFILE_H */
