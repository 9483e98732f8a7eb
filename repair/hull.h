/*
 * hull.h - private to repair/: the outer hull of a self-intersection-free
 * exact mesh (seed 000 Algorithms 1 and 2, with cavities kept) and the
 * manifold-connected split (Def. 3.10).  repair_core.c and parts.c use it.
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
	size_t enclosed_components; /* components deleted as enclosed */
	size_t cavities;	 /* inward-facing enclosed shells kept as cavities */
	size_t cavity_triangles; /* their triangles */
};

/*
 * hull_extract - tag every triangle of em (arrays of exact_mesh_ntris(em)
 * bytes): tag[t] as above, flip[t] set when t must be reversed to face
 * outwards (M_solid) or to the side the growing left it on (M_sheet).
 * Triangles of enclosed components get tag 0, except that an enclosed
 * closed shell the input oriented inwards is a cavity and keeps tag outer
 * with the input orientation (flip 0), and a component inside a cavity
 * counts as outside (docs/repair.md, "Cavities").  Returns 0 or a
 * negative class with err filled.
 */
int hull_extract(const struct exact_mesh *em, uint8_t *tag, uint8_t *flip,
		 struct hull_stats *st, struct st_error *err);

/*
 * hull_manifold_components - number the manifold-connected components
 * (Def. 3.10) of em, closed and without self-intersections, its triangles
 * facing away from the material (outwards, or into a cavity), into
 * component[0..ntris-1]: triangles join across edges with two triangles,
 * and around singular edges each joins the triangle it faces through the
 * material.  *unpaired counts the singular edges where that did not pair
 * the triangles of every component (one left over, or two walking the
 * edge the same way): the orientation contradicts a solid there.  Returns
 * how many components, or -1 with err filled.
 */
long hull_manifold_components(const struct exact_mesh *em, uint32_t *component,
			      size_t *unpaired, struct st_error *err);

#endif /* STRATUM_REPAIR_HULL_H */
