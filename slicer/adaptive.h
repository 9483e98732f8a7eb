/*
 * adaptive.h - adaptive layer heights (docs/slicing.md "Adaptive layer
 * heights"): a layer plan (section.h, struct layer_span) whose heights
 * follow the surface's slope so the staircase error stays under a bound,
 * and the measurement of that error for any plan.
 *
 * The cusp: a facet with unit normal n crossed by a layer h mm thick leaves
 * a step of h |n_z| (the distance, along the normal, between the facet and
 * the corner of the layer's vertical wall).  A layer starting at z is the
 * largest h in [min_height, max_height] for which every sloped facet it
 * crosses keeps h |n_z| <= max_cusp; vertical facets allow any height and
 * horizontal facets (all three corners at one Z) are left out: they leave
 * no staircase, and where a layer boundary falls near them is set by their
 * Z, as with uniform layers (PrusaSlicer's adaptive profile does not end
 * layers on them either).
 *
 * Smoothing: the allowed height, as a function of Z, is replaced by the
 * largest function under it whose slope is at most ADAPTIVE_SMOOTHING, so
 * a layer is at most that fraction thicker than the one below and the one
 * below at most that fraction thicker than it, and the smoothing only ever
 * lowers heights: the bound holds on every layer the minimum height allows.
 *
 * Thread safety: no global state.
 */
#ifndef STRATUM_SLICER_ADAPTIVE_H
#define STRATUM_SLICER_ADAPTIVE_H

#include <stddef.h>

#include "mesh.h"
#include "section.h"
#include "st_error.h"

/* Largest slope of the smoothed height profile (mm of height per mm of Z):
 * neighbouring layers differ by at most this fraction. */
#define ADAPTIVE_SMOOTHING 0.25
/* Resolution of the height profile along Z, mm (coarser only for meshes
 * taller than ADAPTIVE_MAX_CELLS of it). */
#define ADAPTIVE_CELL_MM 0.001
#define ADAPTIVE_MAX_CELLS (1u << 22)
/* Heights above the first layer are whole multiples of this, mm: the
 * G-code's Z resolution, so the Z written is the layer's top. */
#define ADAPTIVE_STEP_MM 0.001

struct adaptive_settings {
	double first_height; /* mm, layer 0's, fixed (first_layer_height) */
	double min_height;   /* mm, > 0 (min_layer_height) */
	double max_height;   /* mm, >= min_height (max_layer_height, at most 0.75 x nozzle) */
	double max_cusp;     /* mm, > 0: the bound on h |n_z| */
};

/* The cusp of a plan over a mesh's sloped facets. */
struct adaptive_cusp {
	double max;	    /* mm, the largest h |n_z| of any layer and facet it crosses */
	double mean;	    /* mm, over the sloped surface, weighted by the area in each layer */
	size_t worst_layer; /* index of a layer with the largest */
};

/*
 * adaptive_plan - the adaptive plan of m (mm, closed as the repair leaves
 * it): layer 0 first_height thick, then layers as the top describes, while a
 * layer's mid-plane lies below the mesh's top; Z from the mesh's lowest
 * point.  *plan is a new array of *n layers (free).  Returns 0, or
 * ST_ERR_RANGE (settings out of range, with the value and what is
 * allowed; more than SLICE_MAX_LAYERS layers), ST_ERR_ARG (empty mesh,
 * coordinates that are not finite),
 * ST_ERR_NOMEM; *plan is then NULL.
 */
int adaptive_plan(const struct mesh *m, const struct adaptive_settings *s, struct layer_span **plan,
		  size_t *n, struct st_error *err);

/*
 * adaptive_plan_profile - the plan of a layer height profile (PrusaSlicer's
 * variable layer height): zh holds pairs (z, height), z from the mesh's
 * lowest point, rising.  Layer 0 is first_height thick; each later layer
 * starting at z takes the profile's height at z + min_height / 2, linear
 * between two pairs (below the first pair the first height, above the last
 * the last), kept within min_height..max_height and in whole
 * ADAPTIVE_STEP_MM; layers while a layer's mid-plane lies below the top,
 * height mm above the lowest point.  *clamped (may be NULL) counts the
 * layers whose profile height lay outside min_height..max_height.
 * Returns as adaptive_plan (ST_ERR_ARG also for an empty profile).
 */
int adaptive_plan_profile(double height, const struct adaptive_settings *s, const double *zh,
			  size_t pairs, struct layer_span **plan, size_t *n, size_t *clamped,
			  struct st_error *err);

/*
 * adaptive_measure - the cusp of the n layers of plan (Z from m's lowest
 * point) over m's sloped facets.  layer_cusp (may be NULL) receives n
 * values, each layer's largest (0 where it crosses no sloped facet).
 * Returns 0 or ST_ERR_ARG (no mesh, no plan).
 */
int adaptive_measure(const struct mesh *m, const struct layer_span *plan, size_t n,
		     double *layer_cusp, struct adaptive_cusp *out, struct st_error *err);

#endif /* STRATUM_SLICER_ADAPTIVE_H */
