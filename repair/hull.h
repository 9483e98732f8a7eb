/*
 * hull.h - private to repair/: the outer hull of a self-intersection-free
 * exact mesh (seed 000 Algorithms 1 and 2) and the manifold-connected split
 * (Def. 3.10).  repair.c is the only user.
 */
#ifndef STRATUM_REPAIR_HULL_H
#define STRATUM_REPAIR_HULL_H

#include <stddef.h>
#include <stdint.h>

#include "exact.h"
#include "st_error.h"

/* Tags per triangle: outer only = M_solid, both = M_sheet, none = deleted. */
#define HULL_OUTER 1
#define HULL_INNER 2

struct hull_stats {
	size_t solid;		 /* triangles tagged outer only */
	size_t sheet;		 /* triangles tagged outer and inner */
	size_t sheet_components; /* edge-connected parts of M_sheet */
	size_t interior;	 /* never reached from outside */
	size_t enclosed;	 /* in components inside a component of M_solid */
};

/*
 * hull_extract - tag every triangle of em (arrays of exact_mesh_ntris(em)
 * bytes): tag[t] as above, flip[t] set when t must be reversed to face
 * outwards (M_solid) or to the side the growing left it on (M_sheet).
 * Triangles of enclosed components get tag 0.  Returns 0 or a negative
 * class with err filled.
 */
int hull_extract(const struct exact_mesh *em, uint8_t *tag, uint8_t *flip,
		 struct hull_stats *st, struct st_error *err);

/*
 * hull_manifold_components - number the manifold-connected components
 * (Def. 3.10) of em, a closed outward-oriented mesh without
 * self-intersections, into component[0..ntris-1]: triangles join across
 * edges with two triangles, and around singular edges each joins the
 * triangle it faces through the solid.  Returns how many, or -1 with err
 * filled.
 */
long hull_manifold_components(const struct exact_mesh *em, uint32_t *component,
			      struct st_error *err);

#endif /* STRATUM_REPAIR_HULL_H */
