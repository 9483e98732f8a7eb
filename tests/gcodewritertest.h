/*
 * gcodewritertest.h - what the gcodewriter suite's files share
 * (check_gcodewriter.c, check_gcodewriter_cooling.c): layer stacks built
 * by hand, and the written G-code replayed like a printer would.
 */
#ifndef STRATUM_TESTS_GCODEWRITERTEST_H
#define STRATUM_TESTS_GCODEWRITERTEST_H

#include <stdbool.h>
#include <stddef.h>

#include "estimate.h"
#include "gcode_writer.h"

#define MAXL 64	     /* layers a replay tracks */
#define NM 1000000.0 /* nm per mm */

/* What replaying a written G-code text found (replay). */
struct replay {
	double retract_before_travel; /* in: travels longer than this must retract */
	bool relative;		      /* M83 seen last */
	int layers;		      /* ;LAYER_CHANGE count */
	double zc[MAXL], hc[MAXL];    /* ;Z: and ;HEIGHT: per layer */
	double e[MAXL];		      /* extruded per layer */
	double fmin[MAXL], fmax[MAXL]; /* F of extrusions, mm/min */
	double zmin[MAXL], zmax[MAXL]; /* Z of extrusions */
	int fan_first[MAXL];	       /* fan (0-255) at the layer's first extrusion */
	int fan_bridge;		       /* fan at the first extrusion after ;TYPE:Bridge infill */
	int fan_after_bridge;	       /* fan at the first extrusion of the next type */
	int retracts, unretracts, wipes; /* moves pulling back / restoring / wiping */
	int long_wet, long_dry, short_wet, short_dry; /* travels: retracted or not */
	double travel_dz_max;			      /* highest Z above the layer while travelling */
	int g1_lines; /* G1 lines from the first layer on (the start G-code's are the user's) */
	bool e_ok;
	char why[256];
	struct est_move *moves;
	size_t nmoves, capmoves;
};

/* A stack of n layers of height h (first at Z = h). */
struct layer_stack *stack_new(size_t n, double h);
/* A closed square of side mm, seam at (x0, y0), bead width w mm. */
void add_square(struct layer_paths *l, enum path_role role, double x0, double y0,
		double side, double w);
/* An open polyline of n points xy[2n] (mm), widths w[n] (mm). */
void add_line(struct layer_paths *l, enum path_role role, const double *xy,
	      const double *w, size_t n);
/* Filament (mm) the bead model needs for layer l: independent of the order
 * the writer prints in (segment i -> i+1 has the width of point i). */
double expected_e(const struct layer_paths *l, const struct gcodew_settings *s);
/* Replay text; asserts that every line parses. */
void replay(const char *text, struct replay *r);
/* Write the stack, replay it into *r (zeroed first) and check that E only
 * runs backwards in retractions that are exactly undone.  Returns the text. */
char *write_replay(const struct layer_stack *st, const struct gcodew_settings *s,
		   struct gcodew_summary *sum, struct replay *r);
/* G1 lines of text before the first occurrence of mark (asserted present). */
size_t g1_before(const char *text, const char *mark);
/* Count occurrences of needle in text. */
int count(const char *text, const char *needle);
/* Offset of needle in text (asserted present). */
long at(const char *text, const char *needle);
/* Offset of the k-th (from 1) occurrence of needle. */
long nth(const char *text, const char *needle, int k);
/* Planner time of the replayed moves [a, b), from rest at move a-1. */
double moves_time(const struct replay *r, const struct gcodew_settings *s, size_t a,
		  size_t b);

#endif
