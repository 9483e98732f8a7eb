/*
 * stars.hpp - private to repair/exact: the self-intersections between
 * triangles that share a vertex, decided from the vertex stars (the
 * triangles around each vertex) rather than pair by pair.
 *
 * On a mesh that is already printable almost every candidate pair of the
 * box pass shares a vertex or an edge (6 of the 6.4 million box pairs of a
 * 1M-triangle torus), and none of them intersects.  A star that passes
 * fan_is_embedded() is proven free of such intersections with about two
 * orientation tests per triangle, in place of two to four per pair; stars
 * that fail it (boundaries of two fans, folds, flipped triangles, spikes)
 * fall back to the pair test of pairtest.hpp.  The reasoning is in
 * docs/check.md ("Self-intersections").
 */
#ifndef STRATUM_REPAIR_EXACT_STARS_HPP
#define STRATUM_REPAIR_EXACT_STARS_HPP

#include "pairtest.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

namespace stars
{

/* The usable triangles around each vertex, in compressed rows: those of
 * vertex v are tri[off[v]] .. tri[off[v + 1] - 1], in increasing order. */
struct table {
	std::vector<size_t> off;
	std::vector<uint32_t> tri;
};

/* Fill st with the stars of the triangles t with usable[t] set. */
inline void build(const uint32_t (*tris)[3], size_t ntris, size_t nverts,
		  const std::vector<uint8_t> &usable, table &st)
{
	st.off.assign(nverts + 1, 0);
	for (size_t t = 0; t < ntris; t++)
		if (usable[t])
			for (int k = 0; k < 3; k++)
				st.off[tris[t][k] + 1]++;
	for (size_t v = 0; v < nverts; v++)
		st.off[v + 1] += st.off[v];
	st.tri.resize(st.off[nverts]);
	/* Fill through off[v] (left pointing at the next row), then shift. */
	for (size_t t = 0; t < ntris; t++)
		if (usable[t])
			for (int k = 0; k < 3; k++)
				st.tri[st.off[tris[t][k]]++] = static_cast<uint32_t>(t);
	for (size_t v = nverts; v > 0; v--)
		st.off[v] = st.off[v - 1];
	st.off[0] = 0;
}

/* Scratch space of one thread for fan_is_embedded(). */
struct scratch {
	std::vector<std::pair<uint32_t, uint32_t>> next; /* (a, b) of (v, a, b) */
	std::vector<uint32_t> ends;			 /* every b, sorted */
	std::vector<uint32_t> ring;
};

/* Stars of up to this many triangles (nearly every vertex of a mesh) are
 * ordered by linear scans instead of two sorts and a search per step,
 * which took about 8 % of checking a 1M-triangle sphere. */
const size_t SMALL_FAN = 16;

/* order_fan() for 1 <= k <= SMALL_FAN: the same answer and the same ring
 * (an open fan from its one start, a closed one from its least a). */
inline bool order_small_fan(uint32_t v, const uint32_t *list, size_t k,
			    const uint32_t (*tris)[3], scratch &s, bool &closed)
{
	uint32_t a[SMALL_FAN], b[SMALL_FAN]; /* triangle i is (v, a[i], b[i]) */
	for (size_t i = 0; i < k; i++) {
		const uint32_t *c = tris[list[i]];
		const int j = c[0] == v ? 0 : c[1] == v ? 1 : 2;
		a[i] = c[(j + 1) % 3];
		b[i] = c[(j + 2) % 3];
	}
	/* The usual star, one closed fan, is found by walking it from the
	 * first triangle: each step takes the first triangle whose a is the
	 * last b, so coming back to a[0] after visiting all k proves the a
	 * (and so the b) distinct and every a a b.  The ring then starts at
	 * the least a, as below. */
	{
		uint8_t order[SMALL_FAN];
		uint32_t seen = 1;
		size_t at = 0, least = 0;
		for (size_t step = 0; step < k; step++) {
			order[step] = (uint8_t)at;
			if (a[at] < a[order[least]])
				least = step;
			const uint32_t next = b[at];
			for (at = 0; at < k && a[at] != next; at++)
				;
			if (at == k)
				break;
			if (step + 1 == k) {
				if (at != 0)
					break;
				closed = true;
				s.ring.clear();
				for (size_t i = 0; i < k; i++)
					s.ring.push_back(a[order[(least + i) % k]]);
				return true;
			}
			if ((seen >> at) & 1)
				break;
			seen |= (uint32_t)1 << at;
		}
	}
	for (size_t i = 1; i < k; i++)
		for (size_t j = 0; j < i; j++)
			if (a[i] == a[j] || b[i] == b[j])
				return false;
	size_t start = 0, starts = 0;
	for (size_t i = 0; i < k; i++) {
		bool is_b = false;
		for (size_t j = 0; j < k && !is_b; j++)
			is_b = b[j] == a[i];
		if (!is_b) {
			start = i;
			starts++;
		}
	}
	if (starts > 1)
		return false;
	closed = starts == 0;
	if (closed)
		for (size_t i = 1; i < k; i++)
			if (a[i] < a[start])
				start = i;
	s.ring.clear();
	s.ring.push_back(a[start]);
	for (size_t step = 0, at = start; step < k; step++) {
		const uint32_t next = b[at];
		if (next == s.ring[0])
			return closed && step + 1 == k;
		s.ring.push_back(next);
		if (step + 1 == k)
			return !closed;
		for (at = 0; at < k && a[at] != next; at++)
			;
		if (at == k)
			return false; /* the walk ends early: several fans */
	}
	return false;
}

/*
 * Order the star of v (k triangles) into one fan: ring r_0 .. r_{k-1}
 * (closed, triangle i is (v, r_i, r_{i+1 mod k})) or r_0 .. r_k (open,
 * triangle i is (v, r_i, r_{i+1})), each triangle listed with v first in
 * its own orientation.  False when the star is not one such fan: two
 * fans, a flipped triangle, an edge with more than two triangles.
 */
inline bool order_fan(uint32_t v, const uint32_t *list, size_t k, const uint32_t (*tris)[3],
		      scratch &s, bool &closed)
{
	if (k >= 1 && k <= SMALL_FAN)
		return order_small_fan(v, list, k, tris, s, closed);
	s.next.clear();
	s.ends.clear();
	for (size_t i = 0; i < k; i++) {
		const uint32_t *c = tris[list[i]];
		const int j = c[0] == v ? 0 : c[1] == v ? 1 : 2;
		s.next.emplace_back(c[(j + 1) % 3], c[(j + 2) % 3]);
		s.ends.push_back(c[(j + 2) % 3]);
	}
	std::sort(s.next.begin(), s.next.end());
	std::sort(s.ends.begin(), s.ends.end());
	for (size_t i = 1; i < k; i++)
		if (s.next[i].first == s.next[i - 1].first || s.ends[i] == s.ends[i - 1])
			return false;
	/* An open fan starts at the one triangle whose a is no triangle's b. */
	size_t start = 0, starts = 0;
	for (size_t i = 0; i < k; i++)
		if (!std::binary_search(s.ends.begin(), s.ends.end(), s.next[i].first)) {
			start = i;
			starts++;
		}
	if (starts > 1)
		return false;
	closed = starts == 0;
	s.ring.clear();
	s.ring.push_back(s.next[start].first);
	size_t at = start;
	for (size_t step = 0; step < k; step++) {
		const uint32_t b = s.next[at].second;
		if (b == s.ring[0])
			/* Back at the start: only after every triangle, closed. */
			return closed && step + 1 == k;
		if (step + 1 == k) {
			s.ring.push_back(b);
			return !closed;
		}
		s.ring.push_back(b);
		auto it = std::lower_bound(s.next.begin(), s.next.end(),
					   std::make_pair(b, static_cast<uint32_t>(0)));
		if (it == s.next.end() || it->first != b)
			return false; /* the walk ends early: several fans */
		at = static_cast<size_t>(it - s.next.begin());
	}
	return false;
}

/*
 * Whether a fan of k wedges, each turning counterclockwise by less than
 * half a turn, goes around its vertex v at most once: side(i) is the sign
 * (1, 0, -1) of the side of the line v r_0 that ring vertex r_i is on,
 * which must run + ... + [0] - ... -.  A zero after the first side is
 * half a turn and anything else (back to + or 0 after -) is a full one.
 */
template <class Side> bool once_around(size_t k, bool closed, Side side)
{
	/* Fewer than five turns of less than half a turn each cannot make
	 * two full turns, nor two of them one (an open fan). */
	if (closed ? k < 5 : k < 3)
		return true;
	int phase = 0; /* 0: +, 1: the half turn, 2: - */
	const size_t last = closed ? k - 1 : k;
	for (size_t i = 1; i <= last; i++) {
		const int h = side(i);
		if (h >= 0 && phase != 0)
			return false;
		if (h <= 0)
			phase = h == 0 ? 1 : 2;
	}
	return true;
}

/*
 * Whether the star of v is one fan that, seen along a direction n (the sum
 * of its triangles' normals), goes once around v with every triangle
 * turning counterclockwise: then its triangles meet only in the faces they
 * share (docs/check.md).  Exact: w = v + n is just some point, and every
 * decision is an orientation sign of input points and w.
 */
template <class K, class GetPoint>
bool fan_is_embedded(uint32_t v, const uint32_t *list, size_t k, const uint32_t (*tris)[3],
		     GetPoint pt, scratch &s)
{
	typedef typename K::Point_3 Point;
	bool closed;

	if (k < 2)
		return true;
	if (!order_fan(v, list, k, tris, s, closed))
		return false;
	const std::vector<uint32_t> &r = s.ring;
	const size_t nring = r.size();
	const Point pv = pt(v);
	double n[3] = {0, 0, 0}, reach = 0;
	for (size_t i = 0; i < k; i++) {
		const Point a = pt(r[i]), b = pt(r[(i + 1) % nring]);
		const double e[3] = {a.x() - pv.x(), a.y() - pv.y(), a.z() - pv.z()};
		const double f[3] = {b.x() - pv.x(), b.y() - pv.y(), b.z() - pv.z()};
		n[0] += e[1] * f[2] - e[2] * f[1];
		n[1] += e[2] * f[0] - e[0] * f[2];
		n[2] += e[0] * f[1] - e[1] * f[0];
		reach = std::max(reach, std::max(std::fabs(e[0]), std::max(std::fabs(e[1]),
									 std::fabs(e[2]))));
	}
	const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
	if (!(len > 0) || !std::isfinite(len))
		return false;
	const double scale = reach / len;
	const Point w(pv.x() + n[0] * scale, pv.y() + n[1] * scale, pv.z() + n[2] * scale);

	/* Every triangle counterclockwise around v, seen from w. */
	for (size_t i = 0; i < k; i++)
		if (CGAL::orientation(pv, pt(r[i]), pt(r[(i + 1) % nring]), w) != CGAL::POSITIVE)
			return false;
	const Point p0 = pt(r[0]);
	return once_around(k, closed, [&](size_t i) {
		const CGAL::Orientation h = CGAL::orientation(pv, p0, pt(r[i]), w);
		return h == CGAL::POSITIVE ? 1 : h == CGAL::COPLANAR ? 0 : -1;
	});
}

/*
 * How many pairs of the star of v that share v intersect (seed 000 Def.
 * 3.6), each pair counted only at the smallest vertex it shares so that
 * a pair sharing an edge is counted once.
 */
template <class K, class GetPoint>
uint64_t count_in_star(uint32_t v, const uint32_t *list, size_t k, const uint32_t (*tris)[3],
		       GetPoint pt, scratch &s)
{
	uint64_t hits = 0;

	if (fan_is_embedded<K>(v, list, k, tris, pt, s))
		return 0;
	for (size_t i = 0; i < k; i++)
		for (size_t j = i + 1; j < k; j++) {
			const uint32_t *a = tris[list[i]], *b = tris[list[j]];
			uint32_t least = v;
			for (int x = 0; x < 3; x++)
				for (int y = 0; y < 3; y++)
					if (a[x] == b[y])
						least = std::min(least, a[x]);
			if (least == v && pairtest::intersects<K>(a, b, pt))
				hits++;
		}
	return hits;
}

} /* namespace stars */

#endif /* STRATUM_REPAIR_EXACT_STARS_HPP */
