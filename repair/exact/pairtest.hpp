/*
 * pairtest.hpp - private to repair/exact: whether two triangles of an
 * indexed mesh meet anywhere but in a face they share (seed 000 Def. 3.6).
 *
 * Templated on the kernel so the count (doubles, Epick) and the refinement
 * (exact rational vertices, Epeck) decide with the same reasoning.
 */
#ifndef STRATUM_REPAIR_EXACT_PAIRTEST_HPP
#define STRATUM_REPAIR_EXACT_PAIRTEST_HPP

#include <CGAL/Intersections_3/Segment_3_Triangle_3.h>
#include <CGAL/Intersections_3/Triangle_3_Triangle_3.h>

#include <CGAL/Interval_nt.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

namespace pairtest
{

/*
 * Whether triangles u and w (corner indices) meet anywhere but in a face
 * they share.  Both are non-degenerate; equal indices are the same point
 * and different indices different points.  pt(i) gives vertex i as a
 * K::Point_3.
 */
template <class K, class GetPoint>
bool intersects(const uint32_t *u, const uint32_t *w, GetPoint pt)
{
	typedef typename K::Point_3 Point;
	typedef typename K::Segment_3 Segment;
	typedef typename K::Triangle_3 Triangle;
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
		const Point a = pt(u[su[0]]), b = pt(u[su[1]]);
		const Point c = pt(u[3 - su[0] - su[1]]);
		const Point d = pt(w[3 - sw[0] - sw[1]]);

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
		const Point v = pt(u[su[0]]);
		const Point a = pt(u[i1]), b = pt(u[i2]);
		const Point c = pt(w[j1]), d = pt(w[j2]);
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
	return CGAL::do_intersect(Triangle(pt(u[0]), pt(u[1]), pt(u[2])),
				  Triangle(pt(w[0]), pt(w[1]), pt(w[2])));
}

typedef CGAL::Interval_nt<false> Ival;
typedef std::array<Ival, 3> Ipt;

/*
 * Whether two triangles with no common corner are certainly apart: a
 * separating axis (either normal or a cross product of two edges) along
 * which their interval projections do not overlap.  Intervals enclose the
 * exact corners, so "apart" is certain; "not known" leaves it to the exact
 * test.  Where triangles only come near each other, as pieces of two cut
 * triangles do along their cut, this spares the exact arithmetic the
 * combined predicate falls back to whenever any one sign is zero.
 */
/* Whether triangles u and w (corner indices) have no corner in common. */
inline bool no_common_corner(const uint32_t *u, const uint32_t *w)
{
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++)
			if (u[i] == w[j])
				return false;
	return true;
}

inline bool certainly_apart(const Ipt p[3], const Ipt q[3])
{
	CGAL::Protect_FPU_rounding<true> guard;
	auto sub = [](const Ipt &a, const Ipt &b) {
		return Ipt{a[0] - b[0], a[1] - b[1], a[2] - b[2]};
	};
	auto cross = [](const Ipt &a, const Ipt &b) {
		return Ipt{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
			   a[0] * b[1] - a[1] * b[0]};
	};
	const Ipt e[3] = {sub(p[1], p[0]), sub(p[2], p[1]), sub(p[0], p[2])};
	const Ipt f[3] = {sub(q[1], q[0]), sub(q[2], q[1]), sub(q[0], q[2])};
	Ipt axes[11] = {cross(e[0], e[1]), cross(f[0], f[1])};
	int na = 2;
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++)
			axes[na++] = cross(e[i], f[j]);
	for (int k = 0; k < na; k++) {
		const Ipt &a = axes[k];
		double lp = HUGE_VAL, hp = -HUGE_VAL, lq = HUGE_VAL, hq = -HUGE_VAL;
		for (int i = 0; i < 3; i++) {
			const Ival dp = a[0] * p[i][0] + a[1] * p[i][1] + a[2] * p[i][2];
			const Ival dq = a[0] * q[i][0] + a[1] * q[i][1] + a[2] * q[i][2];
			lp = std::min(lp, dp.inf());
			hp = std::max(hp, dp.sup());
			lq = std::min(lq, dq.inf());
			hq = std::max(hq, dq.sup());
		}
		if (hp < lq || hq < lp)
			return true;
	}
	return false;
}

} /* namespace pairtest */

#endif /* STRATUM_REPAIR_EXACT_PAIRTEST_HPP */
