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
 * chordal_measure - for each facet of a, points on a grid over it (about
 * `samples` over all of a, corners and edges included), the distance along
 * the facet's normal, forwards or back, to ref's surface (where the line
 * misses it, or meets it farther than three times its nearest point and
 * than the facet's longest edge, so on another part of it, the distance
 * to that nearest point);
 * the facet's chordal error is the largest.  The facets above tolerance (mm, >= 0) are isolated
 * (seed 003): listed, counted in edge-connected regions.  Returns 0 or a
 * negative class as deviation_measure; *r is then empty.
 */
int chordal_measure(const struct mesh *a, const struct mesh *ref, size_t samples,
		    double tolerance, struct chordal_report *r, struct st_error *err);

/*
 * chordal_measure_near - chordal_measure where a crossing farther than
 * three times the nearest point always counts as that nearest point, the
 * facet's size aside: on a strongly curved surface a line along the normal
 * grazes it and meets it far off, which is no error a smaller facet would
 * remove (the refinement's measure, refine.h).  Every facet gets at least
 * the grid of 28 points that includes 10 inside it, whatever `samples`.
 */
int chordal_measure_near(const struct mesh *a, const struct mesh *ref, size_t samples,
			 double tolerance, struct chordal_report *r, struct st_error *err);

void chordal_report_free(struct chordal_report *r);

/*
 * chordal_measure_back - the other way round, for the facets of a against
 * ref: points on a grid over ref's facets (about `samples`, corners and
 * edges included), each with its distance to the nearest point of a; each
 * facet of a that is nearest to a point has facet[t] raised to that
 * distance (facet: a->ntris values, left as they are elsewhere).  So a
 * bump of ref that a facet passes over counts against that facet even
 * where no ray from the facet meets it.  Every facet of ref gets at least
 * a grid of 10 points (corners, two on each edge, the centroid).  0 or a
 * negative class as deviation_measure.
 */
int chordal_measure_back(const struct mesh *a, const struct mesh *ref, size_t samples,
			 float *facet, struct st_error *err);

#endif /* STRATUM_REPAIR_DEVIATION_H */
