/*
 * refine_impl.h - what the two halves of the refinement share
 * (repair/refine.c: the rounds, the splits and their checks;
 * repair/refine_place.c: where a new vertex goes on the reference).
 */
#ifndef STRATUM_REPAIR_REFINE_IMPL_H
#define STRATUM_REPAIR_REFINE_IMPL_H

#include <stddef.h>
#include <stdint.h>

#include "mesh.h"
#include "st_error.h"
#include "surfdist.h"

#define REFINE_NONE UINT32_MAX

/* The edges of a mesh, each once. */
struct refine_edges {
	uint32_t (*ends)[2];   /* its two vertices, lower index first */
	uint32_t (*faces)[2];  /* its two facets; REFINE_NONE both when it has not
				* exactly two */
	uint32_t (*of_tri)[3]; /* per triangle: the edge from corner k to k + 1 */
	size_t n;
};

int refine_edges_build(const struct mesh *m, struct refine_edges *e, struct st_error *err);
void refine_edges_free(struct refine_edges *e);

/* How a new vertex was placed. */
enum refine_place_kind {
	PLACE_ON_EDGE,	 /* left at the edge's midpoint (not between two facets, or
			  * the reference found there faces away) */
	PLACE_ALONG,	 /* along the facets' normal onto the surface */
	PLACE_NEAREST,	 /* the surface's nearest point (the line missed, or met another part) */
	PLACE_ON_CREASE, /* onto the line where the reference's faces on either side meet */
};

/* The reference surface and what placing asks of it. */
struct refine_target {
	const struct mesh *ref;
	const struct surfdist *tree; /* over ref */
	double crease_cos;	     /* cos of the feature angle */
};

/*
 * refine_place - for each of the n edges listed in which, where its new
 * vertex goes on the reference: pos[i] (not yet rounded) and how, kind[i].
 * 0 or a negative class with err filled.
 */
int refine_place(const struct mesh *m, const struct refine_edges *e, const uint32_t *which,
		 size_t n, const struct refine_target *tg, double (*pos)[3], uint8_t *kind,
		 struct st_error *err);

/* refine_unit_normal - triangle t's unit normal (zero for no area). */
void refine_unit_normal(const struct mesh *m, uint32_t t, double n[3]);

/* refine_midpoint - the midpoint of edge i. */
void refine_midpoint(const struct mesh *m, const struct refine_edges *e, size_t i, double mid[3]);

#endif /* STRATUM_REPAIR_REFINE_IMPL_H */
