/*
 * holefill.cpp - the CGAL side of holefill.h: hole triangulation of a
 * boundary polyline.  Nothing C++ leaves this file.
 */
#include "holefill.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/triangulate_hole.h>

#include <cmath>
#include <cstdlib>
#include <exception>
#include <new>
#include <vector>

namespace
{

typedef CGAL::Exact_predicates_inexact_constructions_kernel K;
typedef K::Point_3 Point;

/* Three point indices, the output type triangulate_hole_polyline wants. */
struct Tri {
	int v[3];
	Tri(int a, int b, int c) : v{a, b, c} {}
};

/*
 * Whether the patch walks directed edge a->b of the loop (then it follows
 * the loop's direction) rather than b->a.
 */
bool walks(const std::vector<Tri> &patch, int a, int b)
{
	for (const Tri &t : patch)
		for (int k = 0; k < 3; k++)
			if (t.v[k] == a && t.v[(k + 1) % 3] == b)
				return true;
	return false;
}

int fill(const double (*loop)[3], size_t n, const double (*third)[3], uint32_t (**tris)[3],
	 size_t *ntris, struct st_error *err)
{
	std::vector<Point> pts, far;
	std::vector<Tri> patch;

	pts.reserve(n);
	for (size_t i = 0; i < n; i++)
		pts.emplace_back(loop[i][0], loop[i][1], loop[i][2]);
	if (third) {
		far.reserve(n);
		for (size_t i = 0; i < n; i++)
			far.emplace_back(third[i][0], third[i][1], third[i][2]);
	}
	CGAL::Polygon_mesh_processing::triangulate_hole_polyline(pts, far,
								 std::back_inserter(patch));
	if (patch.empty())
		return 0;
	/* Follow the loop's direction: reverse everything when the patch
	 * walks the loop's first edge backwards. */
	const bool reverse = !walks(patch, 0, 1);
	uint32_t (*out)[3] = static_cast<uint32_t (*)[3]>(std::malloc(patch.size() * sizeof(*out)));
	if (!out)
		return st_error_set(err, ST_ERR_NOMEM, "holes: out of memory for %zu triangles",
				    patch.size());
	for (size_t t = 0; t < patch.size(); t++)
		for (int k = 0; k < 3; k++)
			out[t][k] = static_cast<uint32_t>(patch[t].v[reverse ? 2 - k : k]);
	*tris = out;
	*ntris = patch.size();
	return 0;
}

} /* namespace */

extern "C" {

int exact_fill_hole(const double (*loop)[3], size_t n, const double (*third)[3],
		    uint32_t (**tris)[3], size_t *ntris, struct st_error *err)
{
	if (tris)
		*tris = NULL;
	if (ntris)
		*ntris = 0;
	if (!loop || !tris || !ntris || n < 3)
		return st_error_set(err, ST_ERR_ARG,
				    "holes: a hole needs a loop of at least 3 points (got %zu)", n);
	if (n > 0x7fffffffu)
		return st_error_set(err, ST_ERR_ARG, "holes: a loop of %zu points is too long", n);
	for (size_t i = 0; i < n; i++)
		for (int k = 0; k < 3; k++)
			if (!std::isfinite(loop[i][k]) || (third && !std::isfinite(third[i][k])))
				return st_error_set(err, ST_ERR_ARG,
						    "holes: point %zu of a hole loop is not finite",
						    i);
	try {
		return fill(loop, n, third, tris, ntris, err);
	} catch (const std::bad_alloc &) {
		return st_error_set(err, ST_ERR_NOMEM,
				    "holes: out of memory triangulating a hole of %zu edges", n);
	} catch (const std::exception &e) {
		return st_error_set(err, ST_ERR_INTERNAL,
				    "holes: triangulating a hole of %zu edges failed inside CGAL: %s",
				    n, e.what());
	} catch (...) {
		return st_error_set(err, ST_ERR_INTERNAL,
				    "holes: triangulating a hole of %zu edges failed with an "
				    "unknown exception",
				    n);
	}
}

} /* extern "C" */
