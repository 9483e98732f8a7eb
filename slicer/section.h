/*
 * section.h - cut a closed triangle mesh into layers: per layer, the solid
 * cross-section at the layer's mid-height as polygons with holes in integer
 * coordinates (1 unit = 1 nm, SLICE_UNITS_PER_MM in toolpath.h).
 *
 * The cut is exact in the sense that matters for topology: whether a
 * triangle edge crosses a plane is decided on the double coordinates with
 * no tolerance, and a vertex lying exactly on the plane is taken to be
 * infinitesimally above it (symbolic perturbation), so every crossing edge
 * is crossed once, no segment is produced twice and none is missing.
 * Segments are chained by the identity of the mesh edges they start and end
 * on (welded vertex indices), never by comparing coordinates; the ends of
 * chains that stay open (only possible on an open mesh) are joined when
 * closer than a tolerance.  The closed contours become regions through a
 * fill rule (non-zero by default), so outer walls and holes come out
 * right whatever the nesting.
 *
 * Layers: the mesh's lowest point sits on the bed (z = 0).  A plan lists
 * each layer's top and thickness (struct layer_span); every stage after
 * this one reads the heights from the stack, so uniform and adaptive
 * (adaptive.h) layers print alike.  The uniform plan: layer 0 is
 * first_layer_height thick, every later layer layer_height.  Layer i is
 * sliced at its mid-height, and the uniform plan makes layers while that
 * plane lies strictly below the top of the mesh.
 */
#ifndef STRATUM_SLICER_SECTION_H
#define STRATUM_SLICER_SECTION_H

#include <stddef.h>

#include "clip.h"
#include "mesh.h"
#include "st_error.h"

/* Most layers one mesh may produce. */
#define SLICE_MAX_LAYERS 10000000u

/* One planned layer, mm above the bed: its top and its thickness. */
struct layer_span {
	double z, height;
};

/* How to slice; slice_settings_init gives the defaults. */
struct slice_settings {
	double nozzle_diameter; /* mm; layers thicker than this are refused (0.4) */
	double close_gap;	/* mm; open contour ends closer than this are joined (0.05) */
	enum clip_fill fill;	/* rule turning contours into regions (CLIP_NONZERO) */
};

/* One layer's cross-section. */
struct slice_layer {
	double z;		     /* mm above the bed: top of the layer */
	double height;		     /* mm: layer thickness */
	double slice_z;		     /* mm, mesh coordinates: the cutting plane */
	struct clip_expolys regions; /* solid regions, nm; outer CCW, holes CW */
	size_t open_dropped;	     /* open contour pieces that could not be closed */
};

/* Every layer of one mesh, bottom to top. */
struct slice_stack {
	size_t n;
	struct slice_layer *layers;
};

/* slice_settings_init - fill s with the defaults named in the struct. */
void slice_settings_init(struct slice_settings *s);

/*
 * slice_settings_check - refuse settings and layer heights (mm) that cannot
 * be sliced: heights not > 0 or above the nozzle diameter, a negative gap,
 * a bad fill rule.  Returns 0 or ST_ERR_ARG / ST_ERR_RANGE with a message
 * naming the setting and its allowed range.
 */
int slice_settings_check(const struct slice_settings *s, double first_layer_height,
			 double layer_height, struct st_error *err);

/*
 * slice_mesh - slice m (mm, closed surface as the repair leaves it) into
 * layers of first_layer_height then layer_height mm (slice_plan_uniform,
 * slice_mesh_plan).  s may be NULL for the
 * defaults.  On success *out is a new stack (slice_stack_free) and 0 is
 * returned; on error *out is NULL and err says why: ST_ERR_ARG / ST_ERR_RANGE
 * (settings, empty mesh, coordinates beyond +-1e6 mm, too many layers),
 * ST_ERR_NOMEM, ST_ERR_INTERNAL.  m is not modified.
 */
int slice_mesh(const struct mesh *m, double first_layer_height, double layer_height,
	       const struct slice_settings *s, struct slice_stack **out, struct st_error *err);

/*
 * slice_plan_uniform - the uniform plan of a mesh height mm tall: layer 0
 * first_layer_height thick, the others layer_height (heights > 0, checked
 * by the caller), while the layer's mid-plane is below height.  *plan is
 * a new array of *n layers (free; NULL when none).  Returns 0, ST_ERR_RANGE
 * (more than SLICE_MAX_LAYERS) or ST_ERR_NOMEM.
 */
int slice_plan_uniform(double height, double first_layer_height, double layer_height,
		       struct layer_span **plan, size_t *n, struct st_error *err);

/*
 * slice_mesh_plan - slice m at the n layers of plan (tops above the mesh's
 * lowest point, rising; heights in (0, nozzle]), each at its mid-height.
 * Returns as slice_mesh (ST_ERR_RANGE / ST_ERR_ARG for a bad plan).
 */
int slice_mesh_plan(const struct mesh *m, const struct layer_span *plan, size_t n,
		    const struct slice_settings *s, struct slice_stack **out, struct st_error *err);

/*
 * slice_layer_shrink - elefant_foot_compensation: the islands of l shrunk
 * by mm (> 0), sharp corners kept (mitred), as the squashed first layer
 * spreads that much; an island the shrink would remove keeps its outline
 * rather than vanish.  tolerance: nm, > 0 (the offset's arc tolerance).
 * Returns 0, or a negative class with err filled (l unchanged).
 */
int slice_layer_shrink(struct slice_layer *l, double mm, double tolerance, struct st_error *err);

/* slice_stack_free - free a stack and its regions; NULL is safe. */
void slice_stack_free(struct slice_stack *st);

/*
 * slice_plane - the raw closed contours of m cut by the plane z (mesh
 * coordinates, mm), chained as slice_mesh chains them, before any fill rule:
 * oriented with the solid on the left for an outward-oriented mesh,
 * consecutive duplicate points removed.  loops is replaced.  *open_dropped
 * (may be NULL) counts open pieces that were not within close_gap mm of
 * any piece's start.  Returns 0 or a negative class with err filled.
 */
int slice_plane(const struct mesh *m, double z, double close_gap, struct clip_paths *loops,
		size_t *open_dropped, struct st_error *err);

#endif /* STRATUM_SLICER_SECTION_H */
