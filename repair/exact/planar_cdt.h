/*
 * planar_cdt.h - C face of the CGAL bridge behind planar simplification
 * (repair/simplify_planar.h): re-triangulating a nearly flat cluster of
 * facets from its boundary loops alone, and finding the new triangles that
 * meet the rest of the mesh, both decided exactly.
 *
 * Plain C11; every function catches all C++ exceptions and returns
 * ST_ERR_NOMEM / ST_ERR_INTERNAL with err filled instead.
 */
#ifndef STRATUM_REPAIR_EXACT_PLANAR_CDT_H
#define STRATUM_REPAIR_EXACT_PLANAR_CDT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "st_error.h"

#ifdef __cplusplus
extern "C" {
#endif

/* One cluster to re-triangulate. */
struct planar_cdt_cluster {
	const double (*verts)[3];	/* the whole mesh's vertices, mm */
	size_t nverts;
	const uint32_t *loop;		/* vertex indices of every loop, one after another */
	const size_t *loop_end;		/* loop i ends before loop[loop_end[i]] */
	size_t nloops;
	const uint32_t (*old_tris)[3];	/* the cluster's facets as they are */
	size_t nold;
	const uint32_t *probe;		/* removed vertices, each located in the result */
	size_t nprobe;
	double normal[3];		/* the direction the cluster is seen along */
};

/*
 * planar_cdt_triangulate - the constrained Delaunay triangulation (CGAL,
 * exact predicates, seen along c->normal through CGAL's projection traits)
 * of the region the loops bound, with no point but the loop vertices.
 * Each loop runs with the region on its left seen from +normal (the outer
 * one counter-clockwise, holes clockwise), as the boundary of consistently
 * oriented facets does.
 *
 * tris receives the triangles (room for cap), oriented like the old facets;
 * located[i] the index in tris of the triangle probe[i] lies in, seen along
 * the normal.  *why is NULL when the result is valid, else one phrase
 * saying why the cluster cannot be re-triangulated (an old facet does not
 * face along the normal, two loops cross or touch, a loop vertex or a
 * probe falls on another point, the region is not what the loops bound,
 * the triangle count is not loop vertices + 2 holes - 2, cap too small);
 * the caller then leaves it as it was.
 * Returns 0 (with *ntris, *why set), ST_ERR_ARG, ST_ERR_NOMEM or
 * ST_ERR_INTERNAL.
 */
int planar_cdt_triangulate(const struct planar_cdt_cluster *c, uint32_t (*tris)[3], size_t cap,
			   size_t *ntris, uint32_t *located, const char **why,
			   struct st_error *err);

/*
 * planar_cdt_crossings - hit[t] = 1 for each triangle t with fresh[t] set
 * that meets another triangle of the mesh anywhere but in a face they share
 * (seed 000 Def. 3.6, exact), else 0.  Triangles must be non-degenerate and
 * vertices welded (equal indices exactly when equal points).
 * Returns 0, ST_ERR_ARG (an index out of range), ST_ERR_NOMEM or
 * ST_ERR_INTERNAL.
 */
int planar_cdt_crossings(const double (*verts)[3], size_t nverts, const uint32_t (*tris)[3],
			 size_t ntris, const uint8_t *fresh, uint8_t *hit, struct st_error *err);

#ifdef __cplusplus
}
#endif

#endif /* STRATUM_REPAIR_EXACT_PLANAR_CDT_H */
