/*
 * infill_int.h - what the infill's parts share: infill.c (settings, the
 * job, the plan of a layer and its emission in order), infill_classify.c
 * (a layer's region into skins, bridges, solid and sparse infill) and
 * infill_fill.c (the lines of each class); nothing else includes it.
 * The contract is infill.h.
 */
#ifndef STRATUM_SLICER_INFILL_INT_H
#define STRATUM_SLICER_INFILL_INT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "infill.h"
#include "st_error.h"
#include "toolpath.h"

/* Chord error of round offsets, nm. */
#define INFILL_ARC_NM 2000.0
/* Heights closer than this are equal, mm. */
#define INFILL_EPS_MM 1e-6
/* Clipped pieces of lines shorter than this are dropped, nm. */
#define INFILL_MIN_SEGMENT_NM 10000.0

/*
 * One step of a layer's infill as planned: lines to be ordered nearest
 * first from wherever the nozzle is by then, or a path to append as it is
 * (gap fill).  Planning needs no nozzle position, so layers can be planned
 * in parallel and emitted in order.
 */
struct item {
	bool fixed;		/* a path as it is, else lines to order */
	bool loops;		/* segs are closed loops to order (not fixed) */
	bool monotonic;		/* segs (parallel lines) ordered across, not nearest */
	enum path_role role;
	double w;		/* nm, bead width of the lines */
	struct clip_paths segs; /* the lines */
	bool closed;		/* the path's */
	size_t n;
	struct path_point *pts; /* the path's n points */
};

struct infill_plan {
	size_t n, cap;
	struct item *v;
};

/* Everything the planning of one layer works with; lengths nm unless named. */
struct ctx {
	const struct infill_settings *s;
	const struct slice_stack *st;
	const struct clip_paths *R;	  /* this layer's region inside the walls */
	struct infill_plan *plan;
	struct st_error *err;
	size_t layer;	    /* index of the layer being filled */
	double h;	    /* mm, its height */
	double overlap;	    /* how far infill reaches into the walls */
	double t_top, t_bot; /* mm, shell thicknesses */
};

/* The lines of one solid class: width, flow spacing, role. */
struct bead {
	double w, sp;
	enum path_role role;
	bool gap_fill;
};

/* infill_classify.c: classify and fill layer c->layer into c->plan. */
int infill_fill_layer(struct ctx *c);

/* infill_fill.c */
/* Plan segs as open paths of role and width w (nm), to be ordered nearest
 * first when the layer is emitted. */
int infill_plan_lines(struct ctx *c, const struct clip_paths *segs, enum path_role role, double w);
/* Solid lines over every island of X: direction a (radians), or per island
 * the detected bridge direction over anchors when anchors is not NULL. */
int infill_fill_solid(struct ctx *c, const struct clip_paths *X, double a, const struct bead *b,
		      const struct clip_paths *anchors);
/* Sparse infill of X at fill_density with the chosen pattern, at angle a. */
int infill_fill_sparse(struct ctx *c, const struct clip_paths *X, double a);

#endif /* STRATUM_SLICER_INFILL_INT_H */
