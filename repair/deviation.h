/*
 * deviation.h - how far one mesh's surface lies from another's
 * (docs/accuracy.md): the symmetric surface distance behind `stratum
 * compare`, and seed 003's chordal error of each facet of a mesh against a
 * finer reference surface, with the facets over a tolerance isolated.
 *
 * Both sample the surfaces evenly (surfsample.h) and ask CGAL's AABB tree
 * of the other surface (surfdist.h).  Distances are in double precision:
 * figures for a report, not decisions.
 */
#ifndef STRATUM_REPAIR_DEVIATION_H
#define STRATUM_REPAIR_DEVIATION_H

#include <stddef.h>
#include <stdint.h>

#include "mesh.h"
#include "st_error.h"

#define DEVIATION_BINS 10 /* the histogram's bins, 0 .. the largest distance */
/* Points on each surface by default, for `compare` and `refine` alike: a
 * refinement measured as `compare --reference` measures it. */
#define DEVIATION_SAMPLES_DEFAULT 200000

/* One direction: samples on one surface, distances to the other. */
struct deviation_side {
	size_t samples;
	double area;	  /* mm^2 of the sampled surface */
	double max, mean; /* mm; mean weighted by area */
};

struct deviation_report {
	struct deviation_side a_to_b, b_to_a;
	double max;  /* mm: the larger of the two (the Hausdorff distance) */
	double mean; /* mm: over both surfaces, weighted by area */
	double p95;  /* mm: 95 % of both surfaces' area is closer than this */
	double bin_width; /* mm: max / DEVIATION_BINS */
	double hist[DEVIATION_BINS]; /* share of both surfaces' area in each bin */
	float *facet_a;	/* per triangle of a: its samples' largest distance to b */
};

/*
 * deviation_measure - the symmetric surface distance between a and b (mm),
 * each sampled with about `samples` points (at least one per triangle).
 * Returns 0, or ST_ERR_ARG (a mesh without area), ST_ERR_NOMEM,
 * ST_ERR_INTERNAL with err filled; *r is then empty.
 */
int deviation_measure(const struct mesh *a, const struct mesh *b, size_t samples,
		      struct deviation_report *r, struct st_error *err);

void deviation_report_free(struct deviation_report *r);

/* Seed 003's chordal error of a against a finer reference surface. */
struct chordal_report {
	size_t points;	   /* on a's facets, corners and edges included */
	double max;	   /* mm: the largest facet's */
	double mean;	   /* mm: mean over all points (seed 003's average chordal error) */
	double tolerance;  /* mm, as asked */
	float *facet;	   /* per triangle of a: its chordal error, mm */
	uint32_t *over;	   /* the triangles above the tolerance, in order */
	size_t nover;
	size_t regions;	   /* edge-connected groups of them */
	double over_area;  /* mm^2 of them */
};

/*
 * chordal_measure - each facet's chordal error against ref, the one
 * measure of `stratum compare --reference` and of `stratum refine`'s
 * stopping test (docs/accuracy.md), the larger of two:
 * - from the facet (seed 003): on a grid over it (about `samples` points
 *   over all of a, at least 28 a facet, corners and edges' midpoints
 *   included), the distance along its normal, forwards or back, to where
 *   the line first meets ref, the nearer way, when ref's face there faces
 *   the facet's way within 70.5 degrees and lies no farther than three
 *   times ref's nearest point; else (the line grazes ref, meets the far
 *   side of a thin part, passes a tip and meets another part, or misses)
 *   the distance to ref's nearest point;
 * - from ref: on a grid over ref's facets (about `samples` points, at
 *   least 10 a facet), each point's distance to a, which raises the facet
 *   of a nearest to it by its offset along that facet's normal, so a bump
 *   of ref that a facet passes over counts against that facet, as does a
 *   crease's sagitta where ref's nearest point is on the other face.
 * The facets above tolerance (mm, >= 0) are isolated (seed 003): listed,
 * counted in edge-connected regions.  Returns 0 or a negative class as
 * deviation_measure; *r is then empty.
 */
int chordal_measure(const struct mesh *a, const struct mesh *ref, size_t samples,
		    double tolerance, struct chordal_report *r, struct st_error *err);

void chordal_report_free(struct chordal_report *r);

#endif /* STRATUM_REPAIR_DEVIATION_H */
