/*
 * exact.h - C face of the CGAL bridge (the only C++ in repair/).
 *
 * Everything that decides something from geometry goes through here so the
 * decision is exact (CGAL's filtered exact predicates, Epick; Epeck where new
 * points are constructed).  The header is plain C11: opaque data only as
 * arrays of doubles and uint32_t indices with their lengths.  Every function
 * catches all C++ exceptions and returns ST_ERR_INTERNAL / ST_ERR_NOMEM with
 * err filled instead.
 */
#ifndef STRATUM_REPAIR_EXACT_H
#define STRATUM_REPAIR_EXACT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "st_error.h"

#ifdef __cplusplus
extern "C" {
#endif

/*
 * exact_collinear - true when a, b, c are collinear or coincident (exact).
 * A non-finite coordinate also gives true (the degenerate answer).
 */
bool exact_collinear(const double a[3], const double b[3], const double c[3]);

/*
 * exact_orient3d - sign of the orientation of d relative to the plane
 * (a, b, c): +1, 0 (coplanar) or -1, exactly.  Same sign convention as
 * CGAL::orientation (positive when d is on the positive side).  A
 * non-finite coordinate gives 0.
 */
int exact_orient3d(const double a[3], const double b[3], const double c[3],
		   const double d[3]);

/*
 * exact_count_self_intersections - count pairs of triangles whose
 * intersection is not a common face (seed 000 Definition 3.6).
 *
 * verts: nverts xyz triples; tris: ntris index triples (indices < nverts).
 * Equal indices must mean equal points and different indices different
 * points (welded, as in struct mesh).  skip: NULL or ntris flags; triangles
 * with a nonzero flag are ignored (the caller passes irregular, degenerate
 * and duplicate triangles here).  A triangle not flagged but degenerate
 * (collinear corners, exact test) is ignored as well, never an error.
 * Pairs that share an edge intersect only when they overlap in their common
 * plane; pairs that share one vertex only when they meet anywhere else;
 * pairs sharing all three vertices never count.  Candidate pairs come from
 * CGAL's box intersection; threads: 1 = this thread only, n > 1 = up to n
 * cores (capped at what TBB has), 0 = all cores.
 *
 * Memory: about 40 bytes per triangle on top of the arrays, any thread
 * count.  Reentrant; the arrays are only read.
 *
 * Returns 0 with *count set, or a negative class with err filled and
 * *count = 0: ST_ERR_ARG for a NULL array with a nonzero count, an index
 * >= nverts, a non-finite coordinate in a triangle not skipped, or threads
 * < 0; ST_ERR_NOMEM; ST_ERR_INTERNAL for any other exception.
 */
int exact_count_self_intersections(const double (*verts)[3], size_t nverts,
				   const uint32_t (*tris)[3], size_t ntris,
				   const uint8_t *skip, int threads, uint64_t *count,
				   struct st_error *err);

#ifdef __cplusplus
}
#endif

#endif /* STRATUM_REPAIR_EXACT_H */
