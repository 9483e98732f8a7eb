/*
 * sliceclitest.h - what the slicecli suite's files share (check_slicecli.c,
 * check_slicecli_config.c, check_slicesettings.c, check_slicesettings_more.c):
 * the shipped MK3S profile, models written as STL for `stratum slice`, and
 * the settings tests' slicing and G-code readers.
 */
#ifndef STRATUM_TESTS_SLICECLITEST_H
#define STRATUM_TESTS_SLICECLITEST_H

#include <stdbool.h>
#include <stddef.h>

#include "mesh.h"

#define MK3S "--printer prusa-i3-mk3s"

/* m as a binary STL scratch file named name; m is freed. */
const char *stl_file(struct mesh *m, const char *name);

/* What the last slice() printed (the settings tests run tu_run into it too). */
extern char slice_out[1 << 16];

/* Feed rates (mm/min) of the extrusions of one ;TYPE: on the first layer or on the others. */
struct feeds {
	double lo, hi;
	long moves;
};

/* Cooling off, so no layer is slowed down and every feed is the setting's. */
#define STEADY "--set cooling=0 "

/* m as a binary STL scratch file named name (m is freed), copied to buf. */
void model_file(struct mesh *m, const char *name, char *buf, size_t cap);
/* Slice model for generic-marlin with the extra arguments; the G-code (free it). */
char *slice(const char *model, const char *args);
/* The feeds of role (its ;TYPE: name) in text, first layer (first) or above. */
struct feeds role_feeds(const char *text, const char *role, bool first);
/* Every extrusion of role on the layers asked for is at feed (mm/min). */
void assert_feed(const char *text, const char *role, bool first, double feed);
/* The header line "; KEY = VALUE". */
void assert_header(const char *text, const char *line);
/* fx_bridge twice as wide and deep: pillars of 10 x 20 mm, so no wall loop
 * is a small perimeter (at most 2 pi 6.5 mm long). */
struct mesh *wide_bridge(void);
/* Lines of text starting with cmd before the n-th ;LAYER_CHANGE (n = 0:
 * in the whole text). */
int count_before_layer(const char *text, const char *cmd, int n);
/* Layers with a ;TYPE: role, and the smallest X its extrusions reach. */
int role_layers(const char *text, const char *role, double *min_x);

#endif
