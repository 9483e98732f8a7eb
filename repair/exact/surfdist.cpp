/*
 * surfdist.cpp - nearest-point and ray queries on a triangle mesh through
 * CGAL's AABB_tree (surfdist.h).  Epick: the answers are distances for
 * reports, so inexact constructions are enough.
 */
#include "surfdist.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "emesh.hpp"

namespace {

typedef CGAL::Exact_predicates_inexact_constructions_kernel K;
typedef std::vector<K::Triangle_3>::const_iterator TriIt;
typedef CGAL::AABB_triangle_primitive<K, TriIt> Primitive;
typedef CGAL::AABB_traits<K, Primitive> Traits;
typedef CGAL::AABB_tree<Traits> Tree;

K::Point_3 point(const double p[3])
{
	return K::Point_3(p[0], p[1], p[2]);
}

/* Below this many points a batch is not worth splitting over threads. */
const size_t PARALLEL_GRAIN = 256;

/* The nearer end of what a ray met: a point, or a segment when the ray
 * runs inside a triangle's plane. */
double hit_distance(const K::Point_3 &from,
		    const boost::optional<Tree::Intersection_and_primitive_id<K::Ray_3>::Type> &hit)
{
	if (!hit)
		return -1.0;
	if (const K::Point_3 *p = boost::get<K::Point_3>(&hit->first))
		return std::sqrt(CGAL::squared_distance(from, *p));
	if (const K::Segment_3 *s = boost::get<K::Segment_3>(&hit->first))
		return std::sqrt(std::min(CGAL::squared_distance(from, s->source()),
					  CGAL::squared_distance(from, s->target())));
	return -1.0;
}

} /* namespace */

struct surfdist {
	std::vector<K::Triangle_3> tris;
	std::vector<uint32_t> ids; /* the caller's index of each triangle kept */
	Tree tree;
};

extern "C" int surfdist_new(const double (*verts)[3], size_t nverts, const uint32_t (*tris)[3],
			    size_t ntris, struct surfdist **out, struct st_error *err)
{
	*out = nullptr;
	try {
		std::unique_ptr<surfdist> t(new surfdist);
		t->tris.reserve(ntris);
		t->ids.reserve(ntris);
		for (size_t i = 0; i < ntris; i++) {
			for (int k = 0; k < 3; k++)
				if (tris[i][k] >= nverts)
					return st_error_set(err, ST_ERR_ARG,
							    "surface distance: triangle %zu names vertex %u "
							    "of %zu",
							    i, (unsigned)tris[i][k], nverts);
			K::Triangle_3 tri(point(verts[tris[i][0]]), point(verts[tris[i][1]]),
					  point(verts[tris[i][2]]));
			if (tri.is_degenerate())
				continue;
			t->tris.push_back(tri);
			t->ids.push_back((uint32_t)i);
		}
		if (t->tris.empty())
			return st_error_set(err, ST_ERR_ARG,
					    "surface distance: the mesh has no triangle with an area");
		t->tree.insert(t->tris.cbegin(), t->tris.cend());
		t->tree.build();
		/* Built now: the lazy build inside a query is not thread-safe. */
		t->tree.accelerate_distance_queries();
		*out = t.release();
		return 0;
	} catch (...) {
		return emesh::fail(err, "building the surface distance tree");
	}
}

extern "C" void surfdist_free(struct surfdist *t)
{
	delete t;
}

extern "C" int surfdist_nearest(const struct surfdist *t, const double (*pts)[3], size_t n,
				double *dist, uint32_t *tri, struct st_error *err)
{
	try {
		tbb::parallel_for(tbb::blocked_range<size_t>(0, n, PARALLEL_GRAIN),
				  [&](const tbb::blocked_range<size_t> &r) {
					  for (size_t i = r.begin(); i != r.end(); i++) {
						  K::Point_3 q = point(pts[i]);
						  Tree::Point_and_primitive_id pp =
						      t->tree.closest_point_and_primitive(q);
						  dist[i] = std::sqrt(CGAL::squared_distance(q, pp.first));
						  if (tri)
							  tri[i] = t->ids[pp.second - t->tris.cbegin()];
					  }
				  });
		return 0;
	} catch (...) {
		return emesh::fail(err, "nearest-point queries");
	}
}

extern "C" int surfdist_along(const struct surfdist *t, const double (*pts)[3],
			      const double (*dirs)[3], size_t n, double *dist, struct st_error *err)
{
	try {
		tbb::parallel_for(tbb::blocked_range<size_t>(0, n, PARALLEL_GRAIN),
				  [&](const tbb::blocked_range<size_t> &r) {
					  for (size_t i = r.begin(); i != r.end(); i++) {
						  K::Point_3 q = point(pts[i]);
						  K::Vector_3 d(dirs[i][0], dirs[i][1], dirs[i][2]);
						  double best = -1.0;
						  for (int sign = 1; sign >= -1; sign -= 2) {
							  K::Ray_3 ray(q, sign * d);
							  double h = hit_distance(
							      q, t->tree.first_intersection(ray));
							  if (h >= 0 && (best < 0 || h < best))
								  best = h;
						  }
						  dist[i] = best;
					  }
				  });
		return 0;
	} catch (...) {
		return emesh::fail(err, "ray queries");
	}
}
