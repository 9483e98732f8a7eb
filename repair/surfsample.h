/*
 * surfsample.h - even point samples on a triangle mesh's surface, with the
 * facet's unit normal, for the accuracy measurements (cusp height,
 * deviation, chordal error; docs/accuracy.md).
 *
 * A triangle is cut into k x k similar sub-triangles, k the fewest for
 * which every sub-triangle's edges are at most the spacing; its samples
 * are either the k^2 sub-triangles' centroids (each standing for the same
 * area, area / k^2) or the (k+1)(k+2)/2 corners of that grid (the
 * triangle's corners and edges included, where chordal error peaks).
 */
#ifndef STRATUM_REPAIR_SURFSAMPLE_H
#define STRATUM_REPAIR_SURFSAMPLE_H

#include <stdbool.h>
#include <stddef.h>

#include "mesh.h"

/* The largest k: a triangle never gets more than this squared samples. */
#define SURFSAMPLE_K_MAX 1024

/* surfsample_k - k for triangle abc at spacing mm (> 0), 1..SURFSAMPLE_K_MAX. */
size_t surfsample_k(const double a[3], const double b[3], const double c[3], double spacing);

/*
 * surfsample_centroids - the k^2 centroids of abc's sub-triangles into
 * out (room for k^2 points).
 */
void surfsample_centroids(const double a[3], const double b[3], const double c[3], size_t k,
			  double (*out)[3]);

/* surfsample_grid - the (k+1)(k+2)/2 grid corners of abc into out. */
void surfsample_grid(const double a[3], const double b[3], const double c[3], size_t k,
		     double (*out)[3]);

/*
 * surfsample_normal - abc's unit normal (right-handed: outward for an
 * outward-oriented mesh) into n and its area into *area; false (n zero)
 * for a triangle with no area.
 */
bool surfsample_normal(const double a[3], const double b[3], const double c[3], double n[3],
		       double *area);

/* surfsample_inside - whether p, a point of abc's plane (unit normal n),
 * lies in the triangle abc, edges included. */
bool surfsample_inside(const double a[3], const double b[3], const double c[3], const double n[3],
		       const double p[3]);

/* surfsample_area - the whole surface's area, mm^2. */
double surfsample_area(const struct mesh *m);

#endif /* STRATUM_REPAIR_SURFSAMPLE_H */
