/*
 * surfdist.h - C face of the nearest-point and ray queries on a triangle
 * mesh (CGAL's AABB_tree, repair/exact/surfdist.cpp), for the accuracy
 * measurements (repair/deviation.h; docs/accuracy.md).
 *
 * Queries are in double precision: they measure distances for reports,
 * they decide nothing about topology.  Degenerate triangles (collinear
 * corners) are left out of the tree.  A built tree is only read by the
 * queries, so the batch calls run their points on all cores (TBB).  Every
 * function catches all C++ exceptions and returns ST_ERR_INTERNAL /
 * ST_ERR_NOMEM with err filled instead.
 */
#ifndef STRATUM_REPAIR_SURFDIST_H
#define STRATUM_REPAIR_SURFDIST_H

#include <stddef.h>
#include <stdint.h>

#include "st_error.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Opaque: the tree over one mesh's triangles. */
struct surfdist;

/*
 * surfdist_new - build the tree over ntris triangles (index triples into
 * nverts xyz triples).  *out is the tree (surfdist_free), or NULL on error.
 * Returns 0, ST_ERR_ARG (no triangle that is not degenerate, an index out
 * of range), ST_ERR_NOMEM or ST_ERR_INTERNAL.
 */
int surfdist_new(const double (*verts)[3], size_t nverts, const uint32_t (*tris)[3],
		 size_t ntris, struct surfdist **out, struct st_error *err);

/* surfdist_free - NULL is safe. */
void surfdist_free(struct surfdist *t);

/*
 * surfdist_nearest - for each of the n points pts[i], the distance to the
 * closest point of the surface in dist[i], and that triangle's index (as
 * given to surfdist_new) in tri[i] (tri may be NULL).  0 or a negative
 * class with err filled.
 */
int surfdist_nearest(const struct surfdist *t, const double (*pts)[3], size_t n, double *dist,
		     uint32_t *tri, struct st_error *err);

/* surfdist_along's min_cos that takes a crossing whichever way its
 * triangle faces. */
#define SURFDIST_ANY_FACING (-2.0)

/*
 * surfdist_along - for each of the n points pts[i], how far the line
 * through it along dirs[i] (need not be unit) first meets the surface,
 * forwards or backwards, whichever is nearer: the distance in dist[i] (in
 * mm, not in units of dirs[i]), or -1 when the line misses the surface
 * both ways.  When the triangle met there faces away from dirs[i] by more
 * than the angle whose cosine is min_cos (the angle between its
 * right-handed normal and dirs[i]), -1 as well; SURFDIST_ANY_FACING takes
 * any.  0 or a negative class with err filled.
 */
int surfdist_along(const struct surfdist *t, const double (*pts)[3], const double (*dirs)[3],
		   size_t n, double min_cos, double *dist, struct st_error *err);

/*
 * surfdist_closest - for each of the n points pts[i], the closest point of
 * the surface into out[i] and its triangle's index in tri[i] (tri may be
 * NULL).  0 or a negative class with err filled.
 */
int surfdist_closest(const struct surfdist *t, const double (*pts)[3], size_t n,
		     double (*out)[3], uint32_t *tri, struct st_error *err);

/*
 * surfdist_hit - surfdist_along that also tells where: the nearer point
 * where the line through pts[i] along dirs[i] meets the surface into
 * out[i], its triangle in tri[i], the distance in dist[i]; tri[i] is
 * UINT32_MAX and dist[i] -1 when the line misses the surface both ways.
 */
int surfdist_hit(const struct surfdist *t, const double (*pts)[3], const double (*dirs)[3],
		 size_t n, double (*out)[3], uint32_t *tri, double *dist, struct st_error *err);

#ifdef __cplusplus
}
#endif

#endif /* STRATUM_REPAIR_SURFDIST_H */
