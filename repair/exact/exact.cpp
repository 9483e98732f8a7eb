/*
 * exact.cpp - the CGAL side of exact.h: exact predicates (Epick) and the
 * self-intersection count of seed 000 Definition 3.6.
 *
 * Nothing C++ leaves this file: every extern "C" function validates its
 * arguments, catches every exception and answers with an st_status code.
 *
 * Self-intersection count, in three steps:
 *  1. One float box per usable triangle (24 bytes, identity = its address),
 *     and a vector of pointers to them (8 bytes each).  Skipped and
 *     degenerate triangles get no pointer, so they meet nothing.
 *  2. Parallel runs split the pointers along planes into "leaves" (below);
 *     each leaf goes through CGAL::box_self_intersection_d, Sequential_tag,
 *     which finds every pair of overlapping boxes once.
 *  3. Each candidate pair is classified by how many vertex indices the two
 *     triangles share, with exact predicates only (pair_intersects).
 *
 * Why not box_self_intersection_d<Parallel_tag>: CGAL 5.5 copies the range
 * once for the self case and then 4 more times for each of its two ranges,
 * so ten pointer copies live at once (80 bytes per triangle plus the boxes),
 * and splits the work into 16 sub-problems of half the input each.  A plane
 * split keeps every box in about two pointer vectors (about 40 bytes per
 * triangle in all) and each box pair is looked at about once.  Measured on
 * a 1M-triangle torus, 2 cores: 105 vs 40 bytes per triangle, 0.75 vs 0.45 s.
 */
#include "exact.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Intersections_3/Segment_3_Triangle_3.h>
#include <CGAL/Intersections_3/Triangle_3_Triangle_3.h>
#include <CGAL/box_intersection_d.h>

#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <new>
#include <stdexcept>
#include <utility>
#include <vector>

namespace
{

typedef CGAL::Exact_predicates_inexact_constructions_kernel K;
typedef K::Point_3 Point;
typedef K::Segment_3 Segment;
typedef K::Triangle_3 Triangle;
typedef CGAL::Box_intersection_d::Box_d<float, 3, CGAL::Box_intersection_d::ID_FROM_BOX_ADDRESS>
    Box;

/* Below this many boxes a leaf is not split further (not worth a thread). */
const size_t MIN_SPLIT = 4096;

/* Float box coordinates are clamped here so every box lies strictly inside
 * CGAL's float limits (+-FLT_MAX), which the segment tree treats as open. */
const float BOX_LIMIT = 1e38f;

/* Whether all three coordinates of p are finite. */
bool finite3(const double p[3])
{
	return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
}

Point to_point(const double p[3])
{
	return Point(p[0], p[1], p[2]);
}

/*
 * Round a double coordinate to float.  Rounding to nearest and clamping are
 * both monotone, so if two closed double intervals overlap (lo1 <= hi2 and
 * lo2 <= hi1) their rounded images overlap too: the float boxes never lose a
 * candidate pair.  They need not contain the double box for that.
 */
float box_coord(double x)
{
	float f = static_cast<float>(x);

	return std::min(std::max(f, -BOX_LIMIT), BOX_LIMIT);
}

/* The mesh as the callback sees it; boxes[i] belongs to triangle i. */
struct mesh_view {
	const double (*verts)[3];
	const uint32_t (*tris)[3];
	const Box *boxes;
};

/*
 * Whether triangles s and t meet anywhere but in a face they share (Def.
 * 3.6).  Both are non-degenerate; equal indices are the same point and
 * different indices different points.
 */
bool pair_intersects(const mesh_view &m, size_t s, size_t t)
{
	const uint32_t *u = m.tris[s], *w = m.tris[t];
	int su[3], sw[3], shared = 0;

	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++)
			if (u[i] == w[j]) {
				su[shared] = i;
				sw[shared] = j;
				shared++;
			}
	if (shared >= 3)
		return false; /* the same triangle twice: a duplicate, not ours */

	if (shared == 2) {
		/*
		 * Edge ab, third corners c and d.  Off their common plane the
		 * two only share ab; in it they overlap iff c and d are on the
		 * same side of line ab (d on the line would be degenerate).
		 */
		const Point a = to_point(m.verts[u[su[0]]]), b = to_point(m.verts[u[su[1]]]);
		const Point c = to_point(m.verts[u[3 - su[0] - su[1]]]);
		const Point d = to_point(m.verts[w[3 - sw[0] - sw[1]]]);

		if (CGAL::orientation(a, b, c, d) != CGAL::COPLANAR)
			return false;
		return CGAL::coplanar_orientation(a, b, c, d) == CGAL::POSITIVE;
	}

	if (shared == 1) {
		/*
		 * s = (v,a,b), t = (v,c,d).  Their intersection X is convex and
		 * holds v.  If X has a point p != v, the ray from v through p
		 * leaves s through edge ab and t through edge cd (any ray from
		 * a corner into a triangle exits through the opposite edge); the
		 * nearer exit point is in both, so ab meets t or cd meets s.
		 * The converse is plain since ab and cd miss v.  An edge va lying
		 * in t's corner is the case where that exit point is a itself or
		 * on cd, so it needs no test of its own.
		 */
		const int i1 = (su[0] + 1) % 3, i2 = (su[0] + 2) % 3;
		const int j1 = (sw[0] + 1) % 3, j2 = (sw[0] + 2) % 3;
		const Point v = to_point(m.verts[u[su[0]]]);
		const Point a = to_point(m.verts[u[i1]]), b = to_point(m.verts[u[i2]]);
		const Point c = to_point(m.verts[w[j1]]), d = to_point(m.verts[w[j2]]);
		CGAL::Orientation o1, o2;

		/* Quick reject: c and d strictly on one side of s's plane (or a
		 * and b of t's) leave only v in common. */
		o1 = CGAL::orientation(v, a, b, c);
		o2 = CGAL::orientation(v, a, b, d);
		if (o1 == o2 && o1 != CGAL::COPLANAR)
			return false;
		o1 = CGAL::orientation(v, c, d, a);
		o2 = CGAL::orientation(v, c, d, b);
		if (o1 == o2 && o1 != CGAL::COPLANAR)
			return false;
		return CGAL::do_intersect(Segment(a, b), Triangle(v, c, d)) ||
		       CGAL::do_intersect(Segment(c, d), Triangle(v, a, b));
	}

	/* No common vertex, so no common face: any contact counts. */
	return CGAL::do_intersect(
	    Triangle(to_point(m.verts[u[0]]), to_point(m.verts[u[1]]), to_point(m.verts[u[2]])),
	    Triangle(to_point(m.verts[w[0]]), to_point(m.verts[w[1]]), to_point(m.verts[w[2]])));
}

/* A splitting plane: coordinate axis and position (mm). */
struct cut {
	int axis;
	double at;
};

/* Whether box b meets the plane c (closed, like the box overlap test). */
bool straddles(const Box *b, const cut &c)
{
	return b->min_coord(c.axis) <= c.at && c.at <= b->max_coord(c.axis);
}

/*
 * A share of the work: the boxes to intersect among themselves, and the
 * planes whose straddling pairs another leaf already counts.
 */
struct leaf {
	std::vector<const Box *> boxes;
	std::vector<cut> skip;
};

/*
 * Box-pair callback for one leaf.  CGAL copies it by value, so it holds
 * pointers; one leaf runs on one thread, so the counter needs no atomics.
 */
struct pair_counter {
	const mesh_view *mesh;
	const std::vector<cut> *skip;
	uint64_t *count;

	void operator()(const Box *a, const Box *b) const
	{
		for (const cut &c : *skip)
			if (straddles(a, c) && straddles(b, c))
				return;
		if (pair_intersects(*mesh, static_cast<size_t>(a - mesh->boxes),
				    static_cast<size_t>(b - mesh->boxes)))
			++*count;
	}
};

/*
 * Split a leaf into up to 2^depth leaves appended to out.  Cut X at the
 * median box centre on its widest axis into L (below the plane), S (meeting
 * it) and R (above).  L and R boxes cannot overlap, so the pairs of X are
 * those of L+S plus those of S+R that are not S-S: the right half gets the
 * plane in its skip list.  A split that would not shrink both halves much
 * (S over half of X) is not made.
 */
void split_leaf(leaf &&x, int depth, std::vector<leaf> &out)
{
	std::vector<const Box *> &v = x.boxes;
	const size_t n = v.size();
	double lo[3], hi[3];
	cut c;

	if (depth <= 0 || n < MIN_SPLIT) {
		out.push_back(std::move(x));
		return;
	}
	/* Centres are kept doubled (lo + hi), exact in double. */
	for (int k = 0; k < 3; k++) {
		lo[k] = HUGE_VAL;
		hi[k] = -HUGE_VAL;
	}
	for (const Box *b : v)
		for (int k = 0; k < 3; k++) {
			double m = (double)b->min_coord(k) + b->max_coord(k);
			lo[k] = std::min(lo[k], m);
			hi[k] = std::max(hi[k], m);
		}
	c.axis = 0;
	for (int k = 1; k < 3; k++)
		if (hi[k] - lo[k] > hi[c.axis] - lo[c.axis])
			c.axis = k;
	const int ax = c.axis;
	auto centre_less = [ax](const Box *a, const Box *b) {
		return (double)a->min_coord(ax) + a->max_coord(ax) <
		       (double)b->min_coord(ax) + b->max_coord(ax);
	};
	std::nth_element(v.begin(), v.begin() + n / 2, v.end(), centre_less);
	c.at = ((double)v[n / 2]->min_coord(ax) + v[n / 2]->max_coord(ax)) / 2;

	auto mid = std::partition(v.begin(), v.end(),
				  [&c](const Box *b) { return b->max_coord(c.axis) < c.at; });
	auto end_s = std::partition(mid, v.end(),
				    [&c](const Box *b) { return b->min_coord(c.axis) <= c.at; });
	const size_t nl = static_cast<size_t>(mid - v.begin());
	const size_t ns = static_cast<size_t>(end_s - mid);
	if (2 * ns > n) {
		out.push_back(std::move(x));
		return;
	}

	leaf right;
	right.boxes.assign(mid, v.end());
	right.skip = x.skip;
	right.skip.push_back(c);
	v.resize(nl + ns);
	v.shrink_to_fit();
	split_leaf(std::move(x), depth - 1, out);
	split_leaf(std::move(right), depth - 1, out);
}

/* Count the intersecting pairs among one leaf's boxes, then free them. */
uint64_t run_leaf(const mesh_view &m, leaf &l)
{
	uint64_t n = 0;
	pair_counter cb = {&m, &l.skip, &n};

	CGAL::box_self_intersection_d<CGAL::Sequential_tag>(l.boxes.begin(), l.boxes.end(), cb);
	std::vector<const Box *>().swap(l.boxes);
	return n;
}

/* The body of exact_count_self_intersections once arguments are checked. */
int count_pairs(const double (*verts)[3], const uint32_t (*tris)[3], size_t ntris,
		const uint8_t *skip, int threads, uint64_t *count, struct st_error *err)
{
	std::vector<Box> boxes(ntris);
	leaf all;
	size_t nuse = 0;

	for (size_t t = 0; t < ntris; t++)
		if (!(skip && skip[t]))
			nuse++;
	all.boxes.reserve(nuse);
	for (size_t t = 0; t < ntris; t++) {
		const double *p[3];
		float lo[3], hi[3];

		if (skip && skip[t])
			continue;
		for (int k = 0; k < 3; k++) {
			p[k] = verts[tris[t][k]];
			if (!finite3(p[k]))
				return st_error_set(err, ST_ERR_ARG,
						    "exact: triangle %zu has a non-finite vertex "
						    "coordinate; check the input before counting",
						    t);
		}
		if (CGAL::collinear(to_point(p[0]), to_point(p[1]), to_point(p[2])))
			continue; /* degenerate: no box, as if skipped */
		for (int k = 0; k < 3; k++) {
			lo[k] = box_coord(std::min(std::min(p[0][k], p[1][k]), p[2][k]));
			hi[k] = box_coord(std::max(std::max(p[0][k], p[1][k]), p[2][k]));
		}
		boxes[t] = Box(lo, hi);
		all.boxes.push_back(&boxes[t]);
	}

	const mesh_view m = {verts, tris, boxes.data()};
	/* More threads than TBB has cores for only makes TBB print warnings. */
	const int cores = tbb::this_task_arena::max_concurrency();
	const int conc = threads > 0 && threads < cores ? threads : cores;
	if (conc <= 1) {
		*count = run_leaf(m, all);
		return ST_OK;
	}

	tbb::task_arena arena(conc);
	/* Twice as many leaves as threads, so an uneven split still balances. */
	int depth = 1;
	while ((1 << depth) < 2 * conc && depth < 10)
		depth++;
	std::vector<leaf> leaves;
	split_leaf(std::move(all), depth, leaves);

	/* Largest first: the long ones start early. */
	std::sort(leaves.begin(), leaves.end(),
		  [](const leaf &a, const leaf &b) { return a.boxes.size() > b.boxes.size(); });
	std::vector<uint64_t> counts(leaves.size(), 0);
	arena.execute([&] {
		tbb::task_group g;
		for (size_t k = 0; k < leaves.size(); k++)
			g.run([&, k] { counts[k] = run_leaf(m, leaves[k]); });
		g.wait();
	});
	uint64_t total = 0;
	for (uint64_t c : counts)
		total += c;
	*count = total;
	return ST_OK;
}

} /* namespace */

extern "C" {

/* Exact collinearity; a non-finite coordinate counts as degenerate (true). */
bool exact_collinear(const double a[3], const double b[3], const double c[3])
{
	if (!a || !b || !c || !finite3(a) || !finite3(b) || !finite3(c))
		return true;
	try {
		return CGAL::collinear(to_point(a), to_point(b), to_point(c));
	} catch (...) {
		return true;
	}
}

/* Exact orientation sign; a non-finite coordinate counts as coplanar (0). */
int exact_orient3d(const double a[3], const double b[3], const double c[3], const double d[3])
{
	if (!a || !b || !c || !d || !finite3(a) || !finite3(b) || !finite3(c) || !finite3(d))
		return 0;
	try {
		switch (CGAL::orientation(to_point(a), to_point(b), to_point(c), to_point(d))) {
		case CGAL::POSITIVE:
			return 1;
		case CGAL::NEGATIVE:
			return -1;
		default:
			return 0;
		}
	} catch (...) {
		return 0;
	}
}

/* Check the arguments, then count with exceptions turned into codes. */
int exact_count_self_intersections(const double (*verts)[3], size_t nverts,
				   const uint32_t (*tris)[3], size_t ntris, const uint8_t *skip,
				   int threads, uint64_t *count, struct st_error *err)
{
	if (!count)
		return st_error_set(err, ST_ERR_ARG, "exact: count output pointer is NULL");
	*count = 0;
	if (threads < 0)
		return st_error_set(err, ST_ERR_ARG,
				    "exact: thread count %d is negative; use 0 for all cores",
				    threads);
	if (ntris == 0)
		return ST_OK;
	if (!tris || (nverts && !verts))
		return st_error_set(err, ST_ERR_ARG,
				    "exact: NULL vertex or triangle array with nonzero count");
	for (size_t t = 0; t < ntris; t++)
		for (int k = 0; k < 3; k++)
			if (tris[t][k] >= nverts)
				return st_error_set(err, ST_ERR_ARG,
						    "exact: triangle %zu corner %d uses vertex %lu "
						    "but there are only %zu vertices",
						    t, k, (unsigned long)tris[t][k], nverts);
	try {
		return count_pairs(verts, tris, ntris, skip, threads, count, err);
	} catch (const std::bad_alloc &) {
		*count = 0;
		return st_error_set(err, ST_ERR_NOMEM,
				    "exact: out of memory counting self-intersections of %zu "
				    "triangles",
				    ntris);
	} catch (const std::length_error &) {
		*count = 0;
		return st_error_set(err, ST_ERR_NOMEM,
				    "exact: %zu triangles are too many to count "
				    "self-intersections for",
				    ntris);
	} catch (const std::exception &e) {
		*count = 0;
		return st_error_set(err, ST_ERR_INTERNAL,
				    "exact: self-intersection count failed inside CGAL/TBB: %s",
				    e.what());
	} catch (...) {
		*count = 0;
		return st_error_set(err, ST_ERR_INTERNAL,
				    "exact: self-intersection count failed with an unknown "
				    "exception");
	}
}

} /* extern "C" */
