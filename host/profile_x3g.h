/*
 * profile_x3g.h - a sailfish printer profile as the X3G encoder's machine
 * (serial/x3g.h): steps per mm, endstops, homing, feed-rate limits, the
 * command flavour and the build name.  Shared by `stratum x3g`, `stratum
 * send`, `stratum print` and the farm node, so none of them includes
 * another's header.
 */
#ifndef STRATUM_HOST_PROFILE_X3G_H
#define STRATUM_HOST_PROFILE_X3G_H

#include <stddef.h>

#include "profile.h"
#include "st_error.h"
#include "x3g.h"

/*
 * profile_x3g_machine - fill *m and *flavor from sailfish profile p (makerware
 * flavor selects X3G_FLAVOR_MAKERBOT, anything else X3G_FLAVOR_REPRAP).
 * Every value was checked when p was loaded; returns 0 (err is never filled,
 * kept so callers need not change if a check moves here).
 */
int profile_x3g_machine(const struct profile *p, struct x3g_machine *m, enum x3g_flavor *flavor,
			struct st_error *err);


#endif /* STRATUM_HOST_PROFILE_X3G_H */
