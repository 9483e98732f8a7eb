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

#include <CGAL/Interval_nt.h>
#include <CGAL/Uncertain.h>
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
	const XK::Point_3 &e = emesh::exact_of(p);
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
 * refinement on soups.  Its integers are scratch space, kept per thread
 * (plane_scratch) rather than allocated for every section.
 */
class integer_plane
{
      public:
	integer_plane()
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

	/* Where pq crosses the plane through s[0], s[1], s[2]; p and q
	 * strictly on opposite sides. */
	EPoint cut(const IK::Point_3 s[3], const IK::Point_3 &p, const IK::Point_3 &q)
	{
		const IK::Point_3 *pt[5] = {&s[0], &s[1], &s[2], &p, &q};
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

inline integer_plane &plane_scratch()
{
	static thread_local integer_plane scratch;
	return scratch;
}

typedef CGAL::Interval_nt<false> Ival;

/*
 * One point of the part of a triangle t in the plane of a triangle s,
 * for double corners, before it is built: a corner of t in that plane,
 * or where t's edge pq crosses it.  Its box (intervals around the exact
 * coordinates) orders it against the other points of the pair; only the
 * points that end the pair's intersection are then built exactly.
 */
struct section_point {
	const IK::Point_3 *corner = nullptr; /* else the crossing of edge pq */
	const IK::Point_3 *p = nullptr, *q = nullptr, *s = nullptr;
	Ival box[3];

	EPoint build() const
	{
		return corner ? as_epoint(*corner) : plane_scratch().cut(s, *p, *q);
	}
};

/* Boxes of the crossings: p + (q - p) dp / (dp - dq), in intervals. */
inline void section_boxes(section_point *pts, size_t n)
{
	CGAL::Protect_FPU_rounding<true> guard;
	for (size_t k = 0; k < n; k++) {
		section_point &x = pts[k];
		if (x.corner) {
			for (int c = 0; c < 3; c++)
				x.box[c] = Ival((*x.corner)[c]);
			continue;
		}
		Ival e1[3], e2[3], n3[3], dp = 0, dq = 0;
		for (int c = 0; c < 3; c++) {
			e1[c] = Ival(x.s[1][c]) - Ival(x.s[0][c]);
			e2[c] = Ival(x.s[2][c]) - Ival(x.s[0][c]);
		}
		for (int c = 0; c < 3; c++)
			n3[c] = e1[(c + 1) % 3] * e2[(c + 2) % 3] - e1[(c + 2) % 3] * e2[(c + 1) % 3];
		for (int c = 0; c < 3; c++) {
			dp += n3[c] * (Ival((*x.p)[c]) - Ival(x.s[0][c]));
			dq += n3[c] * (Ival((*x.q)[c]) - Ival(x.s[0][c]));
		}
		const Ival den = dp - dq;
		if (den.inf() <= 0 && den.sup() >= 0) { /* too close to tell */
			for (int c = 0; c < 3; c++)
				x.box[c] = Ival::largest();
			continue;
		}
		const Ival t = dp / den;
		for (int c = 0; c < 3; c++)
			x.box[c] = Ival((*x.p)[c]) + (Ival((*x.q)[c]) - Ival((*x.p)[c])) * t;
	}
}

/* compare_xyz of two boxes; uncertain when they cannot tell. */
inline CGAL::Uncertain<CGAL::Comparison_result> compare_boxes(const section_point &a,
							       const section_point &b)
{
	for (int c = 0; c < 3; c++) {
		const CGAL::Uncertain<CGAL::Comparison_result> r = CGAL::compare(a.box[c], b.box[c]);
		if (!CGAL::is_certain(r) || r != CGAL::EQUAL)
			return r;
	}
	return CGAL::EQUAL;
}

/*
 * The part of triangle t in the plane of triangle s (o[i]: side of t's
 * corner i, never all zero): one or two points, in *pts, not yet built.
 */
inline void plane_section(const IK::Point_3 t[3], const CGAL::Orientation o[3],
			  const IK::Point_3 s[3], std::vector<section_point> &pts,
			  std::vector<int8_t> &edge)
{
	for (int i = 0; i < 3; i++)
		if (o[i] == CGAL::COPLANAR) {
			pts.emplace_back();
			pts.back().corner = &t[i];
			edge.push_back(NO_EDGE);
		}
	for (int i = 0; i < 3; i++) {
		const int j = (i + 1) % 3;
		if (o[i] == CGAL::COPLANAR || o[j] == CGAL::COPLANAR || o[i] == o[j])
			continue;
		pts.emplace_back();
		section_point &x = pts.back();
		x.p = &t[i];
		x.q = &t[j];
		x.s = s;
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

/* One point of a pair's two sections: point i of u's (side 0) or w's. */
struct end_ref {
	int side, i;
};

/*
 * Both sections lie on the line where the two planes meet, and
 * lexicographic order is monotone along any line, so the intersection is
 * the overlap of the two sections in that order: its ends *lo and *hi,
 * and c their comparison (LARGER: they miss).  cmp(x, y) compares two
 * points exactly or returns an uncertain answer; false when it did.
 */
template <class Cmp>
bool overlap(size_t na, size_t nb, Cmp cmp, end_ref *lo, end_ref *hi, CGAL::Comparison_result *c)
{
	end_ref a0{0, 0}, a1{0, static_cast<int>(na) - 1}, b0{1, 0}, b1{1, static_cast<int>(nb) - 1};
	auto less = [&cmp](end_ref x, end_ref y, bool *l) {
		const CGAL::Uncertain<CGAL::Comparison_result> r = cmp(x, y);
		if (!CGAL::is_certain(r))
			return false;
		*l = r == CGAL::SMALLER;
		return true;
	};
	bool l = false;
	if (na == 2 && !less(a1, a0, &l))
		return false;
	if (l)
		std::swap(a0, a1);
	l = false;
	if (nb == 2 && !less(b1, b0, &l))
		return false;
	if (l)
		std::swap(b0, b1);
	bool lo_b, hi_a;
	if (!less(a0, b0, &lo_b) || !less(a1, b1, &hi_a))
		return false;
	*lo = lo_b ? b0 : a0;
	*hi = hi_a ? a1 : b1;
	const CGAL::Uncertain<CGAL::Comparison_result> r = cmp(*lo, *hi);
	if (!CGAL::is_certain(r))
		return false;
	*c = r;
	return true;
}

/* Append the intersection from lo to hi (c: their order) to *seg and,
 * per point, the edges of u and w it lies inside to *on. */
template <class Build>
void emit(end_ref lo, end_ref hi, CGAL::Comparison_result c, const std::vector<int8_t> *edge,
	  Build build, std::vector<EPoint> &seg, std::vector<std::array<int8_t, 2>> &on)
{
	if (c == CGAL::LARGER)
		return;
	auto edges = [edge](end_ref x) {
		const int8_t e = edge[x.side][static_cast<size_t>(x.i)];
		return x.side ? std::array<int8_t, 2>{{NO_EDGE, e}} : std::array<int8_t, 2>{{e, NO_EDGE}};
	};
	seg.push_back(build(lo));
	on.push_back(edges(lo));
	if (c == CGAL::SMALLER) {
		seg.push_back(build(hi));
		on.push_back(edges(hi));
	}
}

/* The intersection of the built sections pts[0] of u and pts[1] of w,
 * ordered exactly, appended as emit does. */
inline void exact_ends(const std::vector<EPoint> *pts, const std::vector<int8_t> *edge,
		       std::vector<EPoint> &seg, std::vector<std::array<int8_t, 2>> &on)
{
	auto at = [pts](end_ref x) -> const EPoint & {
		return pts[x.side][static_cast<size_t>(x.i)];
	};
	end_ref lo, hi;
	CGAL::Comparison_result c;
	overlap(
	    pts[0].size(), pts[1].size(),
	    [&at](end_ref x, end_ref y) { return CGAL::make_uncertain(CGAL::compare_xyz(at(x), at(y))); },
	    &lo, &hi, &c);
	emit(lo, hi, c, edge, at, seg, on);
}

/* The sides of u's corners against w's plane and of w's against u's;
 * false when the pair needs no section (coplanar, or one side of the
 * other's plane: *coplanar tells which). */
template <class P>
bool sides(const P u[3], const P w[3], CGAL::Orientation ou[3], CGAL::Orientation ow[3],
	   bool *coplanar)
{
	for (int i = 0; i < 3; i++) {
		ou[i] = CGAL::orientation(w[0], w[1], w[2], u[i]);
		ow[i] = CGAL::orientation(u[0], u[1], u[2], w[i]);
	}
	*coplanar = ou[0] == CGAL::COPLANAR && ou[1] == CGAL::COPLANAR && ou[2] == CGAL::COPLANAR;
	auto one_side = [](const CGAL::Orientation o[3]) {
		return o[0] != CGAL::COPLANAR && o[0] == o[1] && o[1] == o[2];
	};
	return !*coplanar && !one_side(ou) && !one_side(ow);
}

/*
 * Intersect triangles u and w (each non-degenerate, rational corners).
 * Returns false, adding nothing, when they lie in one plane (the caller
 * intersects them in general).  Otherwise appends their intersection to
 * *seg as a segment (two points) or a point (one), or nothing when they
 * miss; *on gets, per point, the edge of u and the edge of w it is known
 * to lie inside (edge k runs from corner k to corner k + 1; NO_EDGE when
 * not known), so the re-triangulation can insert it there without
 * locating it (retri.hpp).
 */
inline bool intersect(const EPoint u[3], const EPoint w[3], std::vector<EPoint> &seg,
		      std::vector<std::array<int8_t, 2>> &on)
{
	CGAL::Orientation ou[3], ow[3];
	bool coplanar;
	if (!sides(u, w, ou, ow, &coplanar))
		return !coplanar;
	std::vector<EPoint> pts[2];
	std::vector<int8_t> edge[2];
	plane_section(u, ou, w, pts[0], edge[0]);
	plane_section(w, ow, u, pts[1], edge[1]);
	exact_ends(pts, edge, seg, on);
	return true;
}

/* The same for double corners, whose orientations Epick decides: the
 * sections are ordered by their boxes where those tell, and then only the
 * intersection's ends are built (half the cut points of a crossing pair
 * are not ends); where the boxes cannot tell, every point is built. */
inline bool intersect(const IK::Point_3 u[3], const IK::Point_3 w[3], std::vector<EPoint> &seg,
		      std::vector<std::array<int8_t, 2>> &on)
{
	CGAL::Orientation ou[3], ow[3];
	bool coplanar;
	if (!sides(u, w, ou, ow, &coplanar))
		return !coplanar;
	std::vector<section_point> sp[2];
	std::vector<int8_t> edge[2];
	plane_section(u, ou, w, sp[0], edge[0]);
	plane_section(w, ow, u, sp[1], edge[1]);
	section_boxes(sp[0].data(), sp[0].size());
	section_boxes(sp[1].data(), sp[1].size());
	end_ref lo, hi;
	CGAL::Comparison_result c;
	auto by_box = [&sp](end_ref x, end_ref y) {
		return compare_boxes(sp[x.side][static_cast<size_t>(x.i)],
				     sp[y.side][static_cast<size_t>(y.i)]);
	};
	if (overlap(sp[0].size(), sp[1].size(), by_box, &lo, &hi, &c)) {
		emit(lo, hi, c, edge,
		     [&sp](end_ref x) { return sp[x.side][static_cast<size_t>(x.i)].build(); }, seg,
		     on);
		return true;
	}
	std::vector<EPoint> pts[2];
	for (int k = 0; k < 2; k++)
		for (const section_point &x : sp[k])
			pts[k].push_back(x.build());
	exact_ends(pts, edge, seg, on);
	return true;
}

} /* namespace cutpair */

#endif /* STRATUM_REPAIR_EXACT_CUTPAIR_HPP */
