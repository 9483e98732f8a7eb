/*
 * holefill.h - C face of the CGAL hole triangulation (repair/exact/holefill.cpp),
 * used by the healing step before the exact repair (docs/repair.md, "Healing").
 *
 * Plain C11 like exact.h: points as double triples, triangles as uint32_t
 * index triples.  Every function catches all C++ exceptions.
 */
#ifndef STRATUM_REPAIR_EXACT_HOLEFILL_H
#define STRATUM_REPAIR_EXACT_HOLEFILL_H

#include <stddef.h>
#include <stdint.h>

#include "st_error.h"

#ifdef __cplusplus
extern "C" {
#endif

/*
 * exact_fill_hole - fill the hole bounded by the closed polyline loop[0..n)
 * (n >= 3 points in order, the first not repeated at the end).  First CGAL::
 * Polygon_mesh_processing::triangulate_hole_polyline: the triangulation of
 * the loop's own points that minimises the largest dihedral angle, then
 * the area (Liepa 2003), searched in the 3-D Delaunay triangulation of the
 * points first and among all triangulations when that finds none.  third:
 * NULL or n points, third[i] the far corner of the triangle outside the
 * hole along edge loop[i]-loop[i+1]; it keeps the patch from folding over
 * its neighbours.  Then, when points is not NULL and third is given, the
 * patch is refined to the density of its rim and its new vertices faired
 * (CGAL's refine and fair, the bi-Laplacian patch of Botsch 2008, as in
 * triangulate_refine_and_fair_hole) with the ring of triangles outside the
 * hole held fixed, so a curved hole gets a curved patch; when the ring is
 * not a manifold strip or fairing fails the plain triangulation stays.
 *
 * On success *tris (malloc'd, caller frees; NULL when *ntris is 0) holds
 * the patch triangles, each walking the loop's edges in the loop's
 * direction (so a loop given opposite to the surface's boundary edges
 * gives a patch oriented like the surface).  An index i < n is loop[i];
 * i >= n is (*points)[i - n], a new point of the faired patch (*points
 * malloc'd, caller frees; *npoints of them, 0 without fairing).  *ntris is
 * 0 when CGAL finds no triangulation (e.g. a loop that doubles back on
 * itself); that is not an error.  Returns 0, ST_ERR_ARG (n < 3, NULL,
 * non-finite point), ST_ERR_NOMEM or ST_ERR_INTERNAL with err filled.
 */
int exact_fill_hole(const double (*loop)[3], size_t n, const double (*third)[3],
		    double (**points)[3], size_t *npoints, uint32_t (**tris)[3], size_t *ntris,
		    struct st_error *err);

#ifdef __cplusplus
}
#endif

#endif /* STRATUM_REPAIR_EXACT_HOLEFILL_H */
