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

#include <gmp.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <climits>
#include <cmath>
#include <utility>
#include <vector>

namespace cutpair
{

typedef EK::Exact_kernel XK; /* the rationals behind Epeck */
typedef XK::FT XFT;

/* Exact coordinates of a point, as rationals, and the point as Epeck's. */
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
inline EPoint edge_plane(const EPoint &p, const EPoint &q, const XFT a[3], const XFT n[3])
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
	XFT c[3];
	for (int k = 0; k < 3; k++)
		c[k] = pp[k] + (qq[k] - pp[k]) * t;
	return EPoint(XK::Point_3(c[0], c[1], c[2]));
}

/*
 * The same for double corners, in integers: every double is an integer
 * times a power of two, so with the smallest exponent of the five points
 * factored out the construction is integer products and sums, and only
 * the three final quotients are reduced.  Rationals reduce (a gcd) after
 * every operation, which made the cut points about a quarter of the
 * refinement on soups.
 */
class integer_plane
{
      public:
	/* The plane through s[0], s[1], s[2]. */
	explicit integer_plane(const IK::Point_3 s[3]) : s_(s)
	{
		for (auto &row : v_)
			for (auto &x : row)
				mpz_init(x);
		for (auto &x : tmp_)
			mpz_init(x);
		mpq_init(r_);
	}
	~integer_plane()
	{
		for (auto &row : v_)
			for (auto &x : row)
				mpz_clear(x);
		for (auto &x : tmp_)
			mpz_clear(x);
		mpq_clear(r_);
	}
	integer_plane(const integer_plane &) = delete;
	integer_plane &operator=(const integer_plane &) = delete;

	/* Where pq crosses the plane; p and q strictly on opposite sides. */
	EPoint cut(const IK::Point_3 &p, const IK::Point_3 &q)
	{
		const IK::Point_3 *pt[5] = {&s_[0], &s_[1], &s_[2], &p, &q};
		/* The smallest exponent of a significand bit: every coordinate
		 * is then an integer times 2^e. */
		int e = INT_MAX;
		for (const IK::Point_3 *x : pt)
			for (int k = 0; k < 3; k++)
				if ((*x)[k] != 0) {
					int ex;
					std::frexp((*x)[k], &ex);
					e = std::min(e, ex - 53);
				}
		if (e == INT_MAX) /* all zero: cannot happen for a real plane */
			e = 0;
		for (int i = 0; i < 5; i++)
			for (int k = 0; k < 3; k++)
				to_integer((*pt[i])[k], e, v_[i][k]);
		mpz_t *e1 = tmp_, *e2 = tmp_ + 3, *n = tmp_ + 6, &dp = tmp_[9], &dq = tmp_[10],
		      &t = tmp_[11], &den = tmp_[12];
		for (int k = 0; k < 3; k++) {
			mpz_sub(e1[k], v_[1][k], v_[0][k]);
			mpz_sub(e2[k], v_[2][k], v_[0][k]);
		}
		for (int k = 0; k < 3; k++) { /* n = e1 x e2 */
			const int i = (k + 1) % 3, j = (k + 2) % 3;
			mpz_mul(n[k], e1[i], e2[j]);
			mpz_submul(n[k], e1[j], e2[i]);
		}
		mpz_set_ui(dp, 0);
		mpz_set_ui(dq, 0);
		for (int k = 0; k < 3; k++) {
			mpz_sub(t, v_[3][k], v_[0][k]);
			mpz_addmul(dp, n[k], t);
			mpz_sub(t, v_[4][k], v_[0][k]);
			mpz_addmul(dq, n[k], t);
		}
		mpz_sub(den, dp, dq); /* not 0: p and q are on opposite sides */
		XFT c[3];
		for (int k = 0; k < 3; k++) { /* (q dp - p dq) / (dp - dq) * 2^e */
			mpz_mul(mpq_numref(r_), v_[4][k], dp);
			mpz_submul(mpq_numref(r_), v_[3][k], dq);
			mpz_set(mpq_denref(r_), den);
			mpq_canonicalize(r_);
			if (e > 0)
				mpq_mul_2exp(r_, r_, (mp_bitcnt_t)e);
			else if (e < 0)
				mpq_div_2exp(r_, r_, (mp_bitcnt_t)-e);
			c[k] = XFT(r_);
		}
		return EPoint(XK::Point_3(c[0], c[1], c[2]));
	}

      private:
	const IK::Point_3 *s_;
	mpz_t v_[5][3], tmp_[13];
	mpq_t r_;

	/* x / 2^e into out, exactly (x is an integer multiple of 2^e). */
	static void to_integer(double x, int e, mpz_t out)
	{
		int ex;
		const double m = std::frexp(x, &ex); /* x = m 2^ex, 1/2 <= |m| < 1 */
		mpz_set_si(out, (long)std::ldexp(m, 53)); /* exact: 53 bits */
		if (x != 0 && ex - 53 > e)
			mpz_mul_2exp(out, out, (mp_bitcnt_t)(ex - 53 - e));
	}
};

/*
 * The part of triangle t in the plane of triangle s (o[i]: side of t's
 * corner i, never all zero): one or two points, in *pts.  Double corners.
 */
inline void plane_section(const IK::Point_3 t[3], const CGAL::Orientation o[3],
			  const IK::Point_3 s[3], std::vector<EPoint> &pts, std::vector<int8_t> &edge)
{
	for (int i = 0; i < 3; i++)
		if (o[i] == CGAL::COPLANAR) {
			pts.push_back(as_epoint(t[i]));
			edge.push_back(NO_EDGE);
		}
	bool crosses = false;
	for (int i = 0; i < 3; i++)
		crosses |= o[i] != CGAL::COPLANAR && o[(i + 1) % 3] != CGAL::COPLANAR &&
			   o[i] != o[(i + 1) % 3];
	if (!crosses)
		return;
	integer_plane plane(s);
	for (int i = 0; i < 3; i++) {
		const int j = (i + 1) % 3;
		if (o[i] == CGAL::COPLANAR || o[j] == CGAL::COPLANAR || o[i] == o[j])
			continue;
		pts.push_back(plane.cut(t[i], t[j]));
		edge.push_back(static_cast<int8_t>(i));
	}
}

/* The same with rational corners. */
inline void plane_section(const EPoint t[3], const CGAL::Orientation o[3], const EPoint s[3],
			  std::vector<EPoint> &pts, std::vector<int8_t> &edge)
{
	XFT a[3], n[3];
	bool have_plane = false;

	for (int i = 0; i < 3; i++)
		if (o[i] == CGAL::COPLANAR) {
			pts.push_back(as_epoint(t[i]));
			edge.push_back(NO_EDGE);
		}
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
		edge.push_back(static_cast<int8_t>(i));
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
 * miss; *on gets, per point, the edge of u and the edge of w it is known
 * to lie inside (edge k runs from corner k to corner k + 1; NO_EDGE when
 * not known), so the re-triangulation can insert it there without
 * locating it (retri.hpp).
 *
 * Both sections lie on the line where the two planes meet, and
 * lexicographic order is monotone along any line, so the intersection is
 * the overlap of the two sections in that order.
 */
template <class P>
bool intersect(const P u[3], const P w[3], std::vector<EPoint> &seg,
	       std::vector<std::array<int8_t, 2>> &on)
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
	std::vector<int8_t> ea, eb;
	plane_section(u, ou, w, a, ea);
	plane_section(w, ow, u, b, eb);
	if (a.size() == 2 && xyz_less(a[1], a[0])) {
		std::swap(a[0], a[1]);
		std::swap(ea[0], ea[1]);
	}
	if (b.size() == 2 && xyz_less(b[1], b[0])) {
		std::swap(b[0], b[1]);
		std::swap(eb[0], eb[1]);
	}
	/* Each end is an end of u's section (on an edge of u) or of w's. */
	const bool lo_b = xyz_less(a.front(), b.front()), hi_a = xyz_less(a.back(), b.back());
	const EPoint &lo = lo_b ? b.front() : a.front();
	const EPoint &hi = hi_a ? a.back() : b.back();
	const std::array<int8_t, 2> lo_on = lo_b ? std::array<int8_t, 2>{{NO_EDGE, eb.front()}}
						 : std::array<int8_t, 2>{{ea.front(), NO_EDGE}};
	const std::array<int8_t, 2> hi_on = hi_a ? std::array<int8_t, 2>{{ea.back(), NO_EDGE}}
						 : std::array<int8_t, 2>{{NO_EDGE, eb.back()}};
	const CGAL::Comparison_result c = CGAL::compare_xyz(lo, hi);
	if (c == CGAL::LARGER)
		return true;
	seg.push_back(lo);
	on.push_back(lo_on);
	if (c == CGAL::SMALLER) {
		seg.push_back(hi);
		on.push_back(hi_on);
	}
	return true;
}

} /* namespace cutpair */

#endif /* STRATUM_REPAIR_EXACT_CUTPAIR_HPP */
