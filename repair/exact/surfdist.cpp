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

/* The nearer end of what a ray met (a point, or a segment when the ray
 * runs inside a triangle's plane) into *at; its distance, or -1 for none. */
double hit_distance(const K::Point_3 &from,
		    const boost::optional<Tree::Intersection_and_primitive_id<K::Ray_3>::Type> &hit,
		    K::Point_3 *at)
{
	if (!hit)
		return -1.0;
	if (const K::Point_3 *p = boost::get<K::Point_3>(&hit->first)) {
		*at = *p;
		return std::sqrt(CGAL::squared_distance(from, *p));
	}
	if (const K::Segment_3 *s = boost::get<K::Segment_3>(&hit->first)) {
		double ds = CGAL::squared_distance(from, s->source()),
		       dt = CGAL::squared_distance(from, s->target());
		*at = ds <= dt ? s->source() : s->target();
		return std::sqrt(std::min(ds, dt));
	}
	return -1.0;
}

} /* namespace */

struct surfdist {
	std::vector<K::Triangle_3> tris;
	std::vector<uint32_t> ids; /* the caller's index of each triangle kept */
	Tree tree;
};

namespace {

/* Whether triangle tri faces along d within the angle whose cosine is
 * min_cos (its right-handed normal's angle to d). */
bool faces_along(const K::Triangle_3 &tri, const K::Vector_3 &d, double min_cos)
{
	K::Vector_3 n = CGAL::cross_product(tri[1] - tri[0], tri[2] - tri[0]);
	double dot = n * d, len = std::sqrt(n.squared_length() * d.squared_length());

	return len > 0 && dot >= min_cos * len;
}

/* Where the line through q along d meets t's surface, the nearer way:
 * the distance (-1 when it misses both ways), the point in *at and the
 * caller's index of its triangle in *which.  When that triangle does not
 * face along d within min_cos (see faces_along; below -1, any), -1 too:
 * the line does not measure the surface there. */
double line_hit(const surfdist *t, const double q_[3], const double d_[3], double min_cos,
		K::Point_3 *at, uint32_t *which)
{
	K::Point_3 q = point(q_), p;
	K::Vector_3 d(d_[0], d_[1], d_[2]);
	double best = -1.0;
	TriIt met = t->tris.cend();

	for (int sign = 1; sign >= -1; sign -= 2) {
		auto hit = t->tree.first_intersection(K::Ray_3(q, sign * d));
		double h = hit_distance(q, hit, &p);
		if (h >= 0 && (best < 0 || h < best)) {
			best = h;
			*at = p;
			met = hit->second;
		}
	}
	if (best < 0)
		return best;
	*which = t->ids[met - t->tris.cbegin()];
	return min_cos >= -1 && !faces_along(*met, d, min_cos) ? -1.0 : best;
}

} /* namespace */

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

/* fn(i) for i in 0..n on all cores; 0, or the failure in err. */
template <class Fn> int each_point(size_t n, const char *what, struct st_error *err, Fn fn)
{
	try {
		tbb::parallel_for(tbb::blocked_range<size_t>(0, n, PARALLEL_GRAIN),
				  [&](const tbb::blocked_range<size_t> &r) {
					  for (size_t i = r.begin(); i != r.end(); i++)
						  fn(i);
				  });
		return 0;
	} catch (...) {
		return emesh::fail(err, what);
	}
}

extern "C" int surfdist_nearest(const struct surfdist *t, const double (*pts)[3], size_t n,
				double *dist, uint32_t *tri, struct st_error *err)
{
	return each_point(n, "nearest-point queries", err, [&](size_t i) {
		K::Point_3 q = point(pts[i]);
		Tree::Point_and_primitive_id pp = t->tree.closest_point_and_primitive(q);
		dist[i] = std::sqrt(CGAL::squared_distance(q, pp.first));
		if (tri)
			tri[i] = t->ids[pp.second - t->tris.cbegin()];
	});
}

extern "C" int surfdist_along(const struct surfdist *t, const double (*pts)[3],
			      const double (*dirs)[3], size_t n, double min_cos, double *dist,
			      struct st_error *err)
{
	return each_point(n, "ray queries", err, [&](size_t i) {
		K::Point_3 at;
		uint32_t which;
		dist[i] = line_hit(t, pts[i], dirs[i], min_cos, &at, &which);
	});
}

extern "C" int surfdist_closest(const struct surfdist *t, const double (*pts)[3], size_t n,
				double (*out)[3], uint32_t *tri, struct st_error *err)
{
	return each_point(n, "nearest-point queries", err, [&](size_t i) {
		Tree::Point_and_primitive_id pp = t->tree.closest_point_and_primitive(point(pts[i]));
		for (int k = 0; k < 3; k++)
			out[i][k] = pp.first[k];
		if (tri)
			tri[i] = t->ids[pp.second - t->tris.cbegin()];
	});
}

extern "C" int surfdist_hit(const struct surfdist *t, const double (*pts)[3],
			    const double (*dirs)[3], size_t n, double (*out)[3], uint32_t *tri,
			    double *dist, struct st_error *err)
{
	return each_point(n, "ray queries", err, [&](size_t i) {
		K::Point_3 at;
		tri[i] = UINT32_MAX;
		dist[i] = line_hit(t, pts[i], dirs[i], SURFDIST_ANY_FACING, &at, &tri[i]);
		for (int k = 0; k < 3; k++)
			out[i][k] = dist[i] >= 0 ? at[k] : pts[i][k];
	});
}
