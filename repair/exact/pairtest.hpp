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

} /* namespace pairtest */

#endif /* STRATUM_REPAIR_EXACT_PAIRTEST_HPP */
