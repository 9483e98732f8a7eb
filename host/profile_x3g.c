/*
 * profile_x3g.c - a sailfish profile as the X3G encoder's machine
 * (profile_x3g.h).
 */
#include "profile_x3g.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* The machine definition and flavour from a sailfish profile (shared with
 * stratum send); returns 0 or the profile's error, err filled. */
int profile_x3g_machine(const struct profile *p, struct x3g_machine *m, enum x3g_flavor *flavor,
			struct st_error *err)
{
	(void)err;
	*flavor = p->gcode_flavor == PROFILE_FLAVOR_MAKERWARE ? X3G_FLAVOR_MAKERBOT
							      : X3G_FLAVOR_REPRAP;
	memset(m, 0, sizeof(*m));
	for (int i = 0; i < 3; i++) {
		m->axis[i].steps_per_mm = p->steps_per_mm[i];
		m->axis[i].home_feedrate = p->home_feedrate[i];
		m->axis[i].endstop =
		    p->home_direction[i] == PROFILE_HOME_MAX ? X3G_ENDSTOP_MAX : X3G_ENDSTOP_MIN;
	}
	for (int i = 0; i < 4; i++) {
		/* mm/s in the profile, mm/min in X3G maths; round off the 1e-13
		 * left by 26.666... x 60 so limits land exactly on GPX's. */
		double mm_min = round(p->machine_max_feedrate[i] * 60 * 1e6) / 1e6;

		if (i < 3)
			m->axis[i].max_feedrate = mm_min;
		else
			m->axis[3].max_feedrate = m->axis[4].max_feedrate = mm_min;
	}
	m->extruder_count = p->extruder_count;
	for (int e = 0; e < 2; e++)
		m->axis[3 + e].steps_per_mm = p->steps_per_mm_e[e < p->extruder_count ? e : 0];
	m->heated_platform = p->x3g_heated_platform;
	m->home_timeout = (unsigned)p->x3g_home_timeout;
	return 0;
}
