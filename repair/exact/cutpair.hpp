/*
 * cutpair.hpp - private to repair/exact: the exact intersection of two
 * triangles that do not lie in one plane, built directly instead of
 * through Epeck's general triangle-triangle intersection.
 *
 * Why: Epeck's triangle-triangle intersection records the whole
 * construction in its lazy DAG, and nearly every cut point is later needed
 * exactly (it lies on an edge of the triangle it cuts, so the constrained
 * triangulation's interval filter cannot decide it): each such point then
 * redoes the whole intersection in rationals.  Here the combinatorics come
 * from filtered exact predicates (Epick on double corners) and each new point
 * (an edge crossing the other plane) is computed once, as an exact
 * rational, from the two orientation determinants.  Measured on eight
 * overlapping spheres (9750 pairs): see docs/benchmarks.md.
 */
#ifndef STRATUM_REPAIR_EXACT_CUTPAIR_HPP
#define STRATUM_REPAIR_EXACT_CUTPAIR_HPP

#include "emesh.hpp"

#include <utility>
#include <vector>

namespace cutpair
{

typedef EK::Exact_kernel XK; /* the rationals behind Epeck */
typedef XK::FT XFT;

/* Exact coordinates of a point, as rationals, and the point as Epeck's. */
inline void coords(const IK::Point_3 &p, XFT c[3])
{
	for (int k = 0; k < 3; k++)
		c[k] = XFT(p[k]);
}
inline void coords(const EPoint &p, XFT c[3])
{
	const XK::Point_3 &e = CGAL::exact(p);
	for (int k = 0; k < 3; k++)
		c[k] = e[k];
}
inline EPoint as_epoint(const IK::Point_3 &p)
{
	return EPoint(p.x(), p.y(), p.z());
}
inline const EPoint &as_epoint(const EPoint &p)
{
	return p;
}

/*
 * The exact point where segment pq crosses the plane through a with
 * normal n (exact), p and q strictly on opposite sides:
 * p + (q - p) * dp / (dp - dq) with dp = n.(p - a), dq = n.(q - a).
 */
template <class P>
EPoint edge_plane(const P &p, const P &q, const XFT a[3], const XFT n[3])
{
	XFT pp[3], qq[3];
	XFT dp = 0, dq = 0;

	coords(p, pp);
	coords(q, qq);
	for (int k = 0; k < 3; k++) {
		dp += n[k] * (pp[k] - a[k]);
		dq += n[k] * (qq[k] - a[k]);
	}
	const XFT t = dp / (dp - dq);
	EFT c[3];
	for (int k = 0; k < 3; k++)
		c[k] = EFT(XFT(pp[k] + (qq[k] - pp[k]) * t));
	return EPoint(c[0], c[1], c[2]);
}

/*
 * The part of triangle t in the plane of triangle s (o[i]: side of t's
 * corner i, never all zero): one or two points, in *pts.
 */
template <class P>
void plane_section(const P t[3], const CGAL::Orientation o[3], const P s[3],
		   std::vector<EPoint> &pts)
{
	XFT a[3], n[3];
	bool have_plane = false;

	for (int i = 0; i < 3; i++)
		if (o[i] == CGAL::COPLANAR)
			pts.push_back(as_epoint(t[i]));
	for (int i = 0; i < 3; i++) {
		const int j = (i + 1) % 3;
		if (o[i] == CGAL::COPLANAR || o[j] == CGAL::COPLANAR || o[i] == o[j])
			continue;
		if (!have_plane) {
			XFT s1[3], s2[3];
			coords(s[0], a);
			coords(s[1], s1);
			coords(s[2], s2);
			XFT e1[3], e2[3];
			for (int k = 0; k < 3; k++) {
				e1[k] = s1[k] - a[k];
				e2[k] = s2[k] - a[k];
			}
			n[0] = e1[1] * e2[2] - e1[2] * e2[1];
			n[1] = e1[2] * e2[0] - e1[0] * e2[2];
			n[2] = e1[0] * e2[1] - e1[1] * e2[0];
			have_plane = true;
		}
		pts.push_back(edge_plane(t[i], t[j], a, n));
	}
}

/* a before b in exact lexicographic (x, y, z) order. */
inline bool xyz_less(const EPoint &a, const EPoint &b)
{
	return CGAL::compare_xyz(a, b) == CGAL::SMALLER;
}

/*
 * Intersect triangles u and w (each non-degenerate; P is IK::Point_3 for
 * double corners, whose orientations Epick decides, or EPoint).
 * Returns false, adding nothing, when they lie in one plane (the caller
 * intersects them in general).  Otherwise appends their intersection to
 * *seg as a segment (two points) or a point (one), or nothing when they
 * miss.
 *
 * Both sections lie on the line where the two planes meet, and
 * lexicographic order is monotone along any line, so the intersection is
 * the overlap of the two sections in that order.
 */
template <class P> bool intersect(const P u[3], const P w[3], std::vector<EPoint> &seg)
{
	CGAL::Orientation ou[3], ow[3];

	for (int i = 0; i < 3; i++) {
		ou[i] = CGAL::orientation(w[0], w[1], w[2], u[i]);
		ow[i] = CGAL::orientation(u[0], u[1], u[2], w[i]);
	}
	if (ou[0] == CGAL::COPLANAR && ou[1] == CGAL::COPLANAR && ou[2] == CGAL::COPLANAR)
		return false;
	auto one_side = [](const CGAL::Orientation o[3]) {
		return o[0] != CGAL::COPLANAR && o[0] == o[1] && o[1] == o[2];
	};
	if (one_side(ou) || one_side(ow))
		return true;

	std::vector<EPoint> a, b;
	plane_section(u, ou, w, a);
	plane_section(w, ow, u, b);
	if (a.size() == 2 && xyz_less(a[1], a[0]))
		std::swap(a[0], a[1]);
	if (b.size() == 2 && xyz_less(b[1], b[0]))
		std::swap(b[0], b[1]);
	const EPoint &lo = xyz_less(a.front(), b.front()) ? b.front() : a.front();
	const EPoint &hi = xyz_less(a.back(), b.back()) ? a.back() : b.back();
	const CGAL::Comparison_result c = CGAL::compare_xyz(lo, hi);
	if (c == CGAL::LARGER)
		return true;
	seg.push_back(lo);
	if (c == CGAL::SMALLER)
		seg.push_back(hi);
	return true;
}

} /* namespace cutpair */

#endif /* STRATUM_REPAIR_EXACT_CUTPAIR_HPP */
