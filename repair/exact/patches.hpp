/*
 * patches.hpp - private to repair/exact: patches of triangles proven to
 * project one-to-one onto a coordinate plane, so that no two triangles of
 * one patch can intersect and the pair search may skip such pairs.
 *
 * Why: on a finely tessellated model almost every pair of overlapping
 * boxes that shares no corner is a pair of near neighbours (2.3 million
 * exact tests and 32 million box tests on a 1M-triangle sphere, none of
 * them an intersection).  Splitting the surface into patches and proving
 * each one flat enough keeps those pairs out of the exact test and, where
 * a grid cell holds one patch only, out of the box tests too.
 *
 * A patch is the set of usable triangles with one label: the coordinate
 * axis their normal leans on most, its sign, and a coarse cube cell of
 * their centroid.  It is certified when, projected along its axis (by
 * dropping that coordinate, which is exact on doubles):
 *  1. every triangle turns counterclockwise (exact orientation sign);
 *  2. at each vertex its triangles form one fan; a closed fan goes once
 *     around the vertex;
 *  3. its boundary edges form one closed loop whose projection is a
 *     simple polygon (exact segment tests).
 * Then the projection is one-to-one on the patch (docs/check.md gives the
 * degree argument), so two of its triangles meet only in a face they
 * share.  Any check that fails only withdraws the patch: its triangles
 * are then tested pair by pair as before.
 */
#ifndef STRATUM_REPAIR_EXACT_PATCHES_HPP
#define STRATUM_REPAIR_EXACT_PATCHES_HPP

#include "boxpairs.hpp"
#include "stars.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

namespace patches
{

const uint32_t NONE = UINT32_MAX;
/* Coarse cell side, in median triangle box sides: patches of several
 * thousand triangles, whose seams hold a few per cent of them (48 gave
 * about 5 % more CPU time on 1M-triangle spheres and tori). */
const double CELL_SIDES = 96;
/* Coarse cells per axis at most. */
const int MAX_CELLS = 64;

typedef CGAL::Exact_predicates_inexact_constructions_kernel PK;

/* Exact sign of the orientation of a, b, c projected along the axis of
 * code (axis 2 * k + s: coordinate k dropped, s = 1 seen from below). */
inline int orient(const double *a, const double *b, const double *c, unsigned code)
{
	const int i = (code / 2 + 1) % 3, j = (code / 2 + 2) % 3;
	const CGAL::Orientation o = CGAL::orientation(
	    PK::Point_2(a[i], a[j]), PK::Point_2(b[i], b[j]), PK::Point_2(c[i], c[j]));
	const int sgn = o == CGAL::POSITIVE ? 1 : o == CGAL::NEGATIVE ? -1 : 0;
	return code & 1 ? -sgn : sgn;
}

/* The patches: tri[t] is t's patch or NONE, code[p] its projection. */
struct table {
	std::vector<uint32_t> tri;
	std::vector<uint8_t> code;
	std::unique_ptr<std::atomic<uint8_t>[]> bad; /* [patch] withdrawn */
	std::vector<uint8_t> open;		     /* [3 t + j] boundary half-edge */
	std::vector<uint8_t> pinch;		     /* [vertex] for settle() */
};

/* Label every usable triangle (condition 1 decided here). */
inline void label(const double (*verts)[3], size_t nverts, const uint32_t (*tris)[3], size_t ntris,
		  const std::vector<uint8_t> &usable, int threads, table &pt)
{
	pt.tri.assign(ntris, NONE);
	pt.open.assign(3 * ntris, 0);
	pt.pinch.assign(nverts, 0);
	pt.bad.reset(new std::atomic<uint8_t>[1]());
	/* Cell side from a sample of box sides; any partition is sound.
	 * Every pass over the triangles runs on all cores in spans, each
	 * span writing only its own results, so the labels do not depend
	 * on the number of threads. */
	const size_t span = 16384, spans = (ntris + span - 1) / span;
	const size_t stride = ntris / 8192 + 1;
	std::vector<double> sampled((ntris + stride - 1) / stride, -1);
	std::vector<std::array<double, 6>> span_box(spans);
	boxpairs::for_each_index(spans, threads, [&](size_t c) {
		std::array<double, 6> &r = span_box[c];
		r = {HUGE_VAL, HUGE_VAL, HUGE_VAL, -HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
		for (size_t t = c * span; t < std::min(ntris, (c + 1) * span); t++) {
			if (!usable[t])
				continue;
			double s = 0;
			for (int k = 0; k < 3; k++) {
				const double a = verts[tris[t][0]][k], b = verts[tris[t][1]][k],
					     c3 = verts[tris[t][2]][k];
				const double l = std::min(a, std::min(b, c3)),
					     h = std::max(a, std::max(b, c3));
				s = std::max(s, h - l);
				r[k] = std::min(r[k], l);
				r[3 + k] = std::max(r[3 + k], h);
			}
			if (t % stride == 0)
				sampled[t / stride] = s;
		}
	});
	double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
	for (const std::array<double, 6> &r : span_box)
		for (int k = 0; k < 3; k++) {
			lo[k] = std::min(lo[k], r[k]);
			hi[k] = std::max(hi[k], r[3 + k]);
		}
	std::vector<double> side;
	for (double s : sampled)
		if (s >= 0)
			side.push_back(s);
	if (side.empty())
		return;
	std::nth_element(side.begin(), side.begin() + side.size() / 2, side.end());
	double cell = CELL_SIDES * side[side.size() / 2];
	for (int k = 0; k < 3; k++)
		cell = std::max(cell, (hi[k] - lo[k]) / (MAX_CELLS - 1));
	if (!(cell > 0) || !std::isfinite(cell))
		return;
	const double inv = 1 / cell;
	int dim[3];
	for (int k = 0; k < 3; k++)
		dim[k] = std::min(MAX_CELLS, (int)((hi[k] - lo[k]) * inv) + 1);
	const size_t ncell = (size_t)dim[0] * dim[1] * dim[2];
	/* First the cell of each triangle (kept in tri for now) and its
	 * normal; then, in triangle order, how much area each cell's
	 * triangles show along each of the six directions. */
	std::vector<std::array<float, 3>> normal(ntris);
	boxpairs::for_each_index(spans, threads, [&](size_t c) {
		for (size_t t = c * span; t < std::min(ntris, (c + 1) * span); t++) {
			if (!usable[t])
				continue;
			const double *a = verts[tris[t][0]], *b = verts[tris[t][1]],
				     *c3 = verts[tris[t][2]];
			size_t at = 0;
			for (int x = 2; x >= 0; x--) {
				const double m = (a[x] + b[x] + c3[x]) / 3;
				/* Clamped as a double: near the top of the double
				 * range the sum overflows, and converting that is
				 * undefined. */
				const double f = (m - lo[x]) * inv;
				const int i = f >= dim[x] - 1 ? dim[x] - 1 : f > 0 ? (int)f : 0;
				at = at * dim[x] + i;
			}
			pt.tri[t] = (uint32_t)at;
			const double e[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
			const double f[3] = {c3[0] - a[0], c3[1] - a[1], c3[2] - a[2]};
			normal[t] = {(float)(e[1] * f[2] - e[2] * f[1]),
				     (float)(e[2] * f[0] - e[0] * f[2]),
				     (float)(e[0] * f[1] - e[1] * f[0])};
		}
	});
	std::vector<float> shown(6 * ncell, 0);
	for (size_t t = 0; t < ntris; t++) {
		if (!usable[t])
			continue;
		for (int k = 0; k < 3; k++)
			shown[6 * (size_t)pt.tri[t] + 2 * k + (normal[t][k] < 0)] +=
			    std::fabs(normal[t][k]);
	}
	std::vector<std::array<float, 3>>().swap(normal);
	/*
	 * Each triangle then takes the first direction, in its cell's order of
	 * most area shown, along which it turns counterclockwise (exactly).
	 * One order per cell, not the triangle's own best axis: where the
	 * surface leans between two axes the triangles' own choices alternate
	 * and leave patches touching themselves at a vertex, which condition 2
	 * rejects.
	 */
	std::vector<uint8_t> order(6 * ncell);
	for (size_t at = 0; at < ncell; at++) {
		const float *w = &shown[6 * at];
		uint8_t *o = &order[6 * at];
		for (int x = 0; x < 6; x++)
			o[x] = (uint8_t)x;
		std::sort(o, o + 6, [w](uint8_t x, uint8_t y) { return w[x] > w[y]; });
	}
	std::vector<float>().swap(shown);
	const uint8_t NO_CODE = 6;
	std::vector<uint8_t> chosen(ntris, NO_CODE);
	boxpairs::for_each_index(spans, threads, [&](size_t c) {
		for (size_t t = c * span; t < std::min(ntris, (c + 1) * span); t++) {
			if (!usable[t])
				continue;
			const double *a = verts[tris[t][0]], *b = verts[tris[t][1]],
				     *c3 = verts[tris[t][2]];
			for (int x = 0; x < 6; x++) {
				const unsigned code = order[6 * (size_t)pt.tri[t] + x];
				if (orient(a, b, c3, code) > 0) {
					chosen[t] = (uint8_t)code;
					break;
				}
			}
		}
	});
	/* Patch numbers in order of first use, as one pass would give. */
	std::vector<uint32_t> dense(6 * ncell, NONE);
	for (size_t t = 0; t < ntris; t++) {
		if (!usable[t])
			continue;
		const size_t at = pt.tri[t];
		pt.tri[t] = NONE;
		if (chosen[t] == NO_CODE)
			continue;
		uint32_t &d = dense[6 * at + chosen[t]];
		if (d == NONE) {
			d = (uint32_t)pt.code.size();
			pt.code.push_back(chosen[t]);
		}
		pt.tri[t] = d;
	}
	pt.bad.reset(new std::atomic<uint8_t>[pt.code.size() + 1]());
}

/* Mark the boundary half-edge v -> r0 of an open fan of patch p. */
inline void mark_open(uint32_t v, uint32_t r0, const uint32_t *list, size_t k,
		      const uint32_t (*tris)[3], table &pt)
{
	for (size_t i = 0; i < k; i++) {
		const uint32_t *c = tris[list[i]];
		for (int j = 0; j < 3; j++)
			if (c[j] == v && c[(j + 1) % 3] == r0)
				pt.open[3 * (size_t)list[i] + j] = 1;
	}
}

/* Whether the ordered ring r around v (k triangles) goes around v at
 * most once in the projection of code, its wedges turning
 * counterclockwise (stars::once_around, in the plane). */
inline bool once_around(const double (*verts)[3], uint32_t v, size_t k, bool closed,
			const std::vector<uint32_t> &r, unsigned code)
{
	return stars::once_around(k, closed, [&](size_t i) {
		return orient(verts[v], verts[r[0]], verts[r[i]], code);
	});
}

/*
 * Condition 2 at vertex v, whose usable triangles are list[0..k-1]: each
 * patch's triangles there must be one fan, closed only if it is the whole
 * star and goes once around.  Records the patches' boundary half-edges
 * leaving v; a patch whose triangles make several fans here is left to
 * settle() (pinch[v]).  Returns true when this also proves the star free
 * of intersections (it is one patch's fan, at most once around), so the
 * caller needs no star test.  Called for every vertex at once, from any
 * thread: it writes only v's corners and flags.
 */
inline bool check_vertex(const double (*verts)[3], uint32_t v, const uint32_t *list, size_t k,
			 const uint32_t (*tris)[3], table &pt, stars::scratch &s,
			 std::vector<uint32_t> &sub)
{
	if (k == 0)
		return true;
	const uint32_t p0 = pt.tri[list[0]];
	bool same = true;
	for (size_t i = 1; i < k && same; i++)
		same = pt.tri[list[i]] == p0;
	bool closed;
	if (same) {
		if (p0 == NONE)
			return false;
		if (!stars::order_fan(v, list, k, tris, s, closed)) {
			pt.pinch[v] = 1;
			return false;
		}
		if (!once_around(verts, v, k, closed, s.ring, pt.code[p0])) {
			pt.bad[p0].store(1, std::memory_order_relaxed);
			return false;
		}
		if (!closed)
			mark_open(v, s.ring[0], list, k, tris, pt);
		return true;
	}
	/* Several patches meet here: each must be one open fan. */
	sub.assign(list, list + k);
	std::sort(sub.begin(), sub.end(),
		  [&](uint32_t a, uint32_t b) { return pt.tri[a] < pt.tri[b]; });
	for (size_t i = 0, j; i < k; i = j) {
		const uint32_t p = pt.tri[sub[i]];
		for (j = i + 1; j < k && pt.tri[sub[j]] == p; j++)
			;
		if (p == NONE)
			continue;
		if (!stars::order_fan(v, sub.data() + i, j - i, tris, s, closed))
			pt.pinch[v] = 1;
		else if (closed)
			pt.bad[p].store(1, std::memory_order_relaxed);
		else
			mark_open(v, s.ring[0], sub.data() + i, j - i, tris, pt);
	}
	return false;
}

/* The corner of triangle t at vertex v. */
inline size_t corner(const uint32_t (*tris)[3], uint32_t t, uint32_t v)
{
	return 3 * (size_t)t + (tris[t][0] == v ? 0 : tris[t][1] == v ? 1 : 2);
}

/*
 * Where a patch's triangles make several fans at a vertex (the coarse
 * cells cut a jagged line through the surface, and a patch touches itself
 * at a vertex now and then), keep its largest fan there and take the
 * others out of the patch; their other corners are checked again, as
 * their fans changed.  One thread, after check_vertex() on every vertex.
 */
template <class Off>
void settle(const double (*verts)[3], const uint32_t (*tris)[3], const Off *off,
	    const uint32_t *star, table &pt)
{
	std::vector<uint32_t> work, sub;
	stars::scratch s;
	for (size_t v = 0; v < pt.pinch.size(); v++)
		if (pt.pinch[v])
			work.push_back((uint32_t)v);
	std::vector<std::array<uint32_t, 3>> e; /* (a, b, t) of (v, a, b) */
	std::vector<uint32_t> fan;
	while (!work.empty()) {
		const uint32_t v = work.back();
		work.pop_back();
		const uint32_t *list = star + off[v];
		const size_t k = off[v + 1] - off[v];
		sub.assign(list, list + k);
		for (uint32_t t : sub)
			pt.open[corner(tris, t, v)] = 0;
		std::sort(sub.begin(), sub.end(),
			  [&](uint32_t a, uint32_t b) { return pt.tri[a] < pt.tri[b]; });
		for (size_t i = 0, j; i < k; i = j) {
			const uint32_t p = pt.tri[sub[i]];
			for (j = i + 1; j < k && pt.tri[sub[j]] == p; j++)
				;
			if (p == NONE || pt.bad[p].load(std::memory_order_relaxed))
				continue;
			e.clear();
			for (size_t x = i; x < j; x++) {
				const uint32_t t = sub[x];
				const size_t c = corner(tris, t, v) % 3;
				e.push_back({tris[t][(c + 1) % 3], tris[t][(c + 2) % 3], t});
			}
			std::sort(e.begin(), e.end());
			bool ok = true;
			for (size_t x = 1; x < e.size() && ok; x++)
				ok = e[x][0] != e[x - 1][0];
			if (!ok) { /* an edge twice: not a surface here */
				pt.bad[p].store(1, std::memory_order_relaxed);
				continue;
			}
			/* Fans: chains from an a that is no b, then the cycles left. */
			std::vector<int> id(e.size(), -1);
			auto next = [&](size_t x) -> long {
				auto it = std::lower_bound(e.begin(), e.end(),
							   std::array<uint32_t, 3>{e[x][1], 0, 0});
				return it != e.end() && (*it)[0] == e[x][1] ? it - e.begin() : -1;
			};
			std::vector<size_t> size;
			std::vector<uint8_t> is_end(e.size(), 1);
			for (size_t x = 0; x < e.size(); x++) {
				const long y = next(x);
				if (y >= 0)
					is_end[y] = 0;
			}
			for (int pass = 0; pass < 2; pass++)
				for (size_t x = 0; x < e.size(); x++) {
					if (id[x] >= 0 || (pass == 0 && !is_end[x]))
						continue;
					size.push_back(0);
					for (long y = (long)x; y >= 0 && id[y] < 0; y = next(y)) {
						id[y] = (int)size.size() - 1;
						size.back()++;
					}
				}
			const int keep =
			    (int)(std::max_element(size.begin(), size.end()) - size.begin());
			fan.clear();
			for (size_t x = 0; x < e.size(); x++) {
				const uint32_t t = e[x][2];
				if (id[x] == keep) {
					fan.push_back(t);
					continue;
				}
				pt.tri[t] = NONE;
				for (int c = 0; c < 3; c++) {
					pt.open[3 * (size_t)t + c] = 0;
					if (tris[t][c] != v)
						work.push_back(tris[t][c]);
				}
			}
			bool closed;
			if (!stars::order_fan(v, fan.data(), fan.size(), tris, s, closed) ||
			    (closed && (fan.size() != k ||
					!once_around(verts, v, k, closed, s.ring, pt.code[p]))))
				pt.bad[p].store(1, std::memory_order_relaxed);
			else if (!closed)
				mark_open(v, s.ring[0], fan.data(), fan.size(), tris, pt);
		}
	}
	std::vector<uint8_t>().swap(pt.pinch);
}

/* Whether closed segments ab and cd of the projection of code meet. */
inline bool segments_meet(const double *a, const double *b, const double *c, const double *d,
			  unsigned code)
{
	const int i = (code / 2 + 1) % 3, j = (code / 2 + 2) % 3;
	return CGAL::do_intersect(PK::Segment_2(PK::Point_2(a[i], a[j]), PK::Point_2(b[i], b[j])),
				  PK::Segment_2(PK::Point_2(c[i], c[j]), PK::Point_2(d[i], d[j])));
}

/* Whether the loop's edges (a, b) (each vertex starting one edge and
 * ending one) project to a simple polygon: edges that share a vertex meet
 * only there, others not at all.  Swept along the first coordinate. */
inline bool simple_polygon(const double (*verts)[3], std::vector<std::pair<uint32_t, uint32_t>> &e,
			   unsigned code)
{
	const int i = (code / 2 + 1) % 3, j = (code / 2 + 2) % 3;
	const size_t n = e.size();
	auto lo = [&](size_t x, int c) {
		return std::min(verts[e[x].first][c], verts[e[x].second][c]);
	};
	auto hi = [&](size_t x, int c) {
		return std::max(verts[e[x].first][c], verts[e[x].second][c]);
	};
	std::vector<uint32_t> order(n);
	for (size_t x = 0; x < n; x++)
		order[x] = (uint32_t)x;
	std::sort(order.begin(), order.end(),
		  [&](uint32_t x, uint32_t y) { return lo(x, i) < lo(y, i); });
	for (size_t x = 0; x < n; x++) {
		const uint32_t u = order[x];
		const double end = hi(u, i);
		for (size_t y = x + 1; y < n && lo(order[y], i) <= end; y++) {
			const uint32_t w = order[y];
			if (hi(u, j) < lo(w, j) || hi(w, j) < lo(u, j))
				continue;
			const uint32_t a = e[u].first, b = e[u].second, c = e[w].first,
				       d = e[w].second;
			if (b == c || d == a) {
				/* Neighbours: they overlap iff the far ends lie on one ray
				 * from the shared corner. */
				const uint32_t m = b == c ? b : a, p = b == c ? a : b,
					       q = b == c ? d : c;
				if (orient(verts[p], verts[m], verts[q], code) != 0)
					continue;
				const int x2 = verts[p][i] != verts[m][i] ? i : j;
				if (verts[p][x2] == verts[m][x2] ||
				    (verts[p][x2] < verts[m][x2]) == (verts[q][x2] < verts[m][x2]))
					return false;
				continue;
			}
			if (segments_meet(verts[a], verts[b], verts[c], verts[d], code))
				return false;
		}
	}
	return true;
}

/*
 * Condition 3, then the final table: patches whose boundary half-edges do
 * not form one simple loop are withdrawn, and tri[t] is NONE for the
 * triangles of every withdrawn patch.
 */
inline void check_loops(const double (*verts)[3], const uint32_t (*tris)[3], size_t ntris,
			table &pt)
{
	const size_t np = pt.code.size();
	if (np == 0)
		return;
	std::vector<uint32_t> first(np + 1, 0);
	for (size_t c = 0; c < 3 * ntris; c++)
		if (pt.open[c] && pt.tri[c / 3] != NONE)
			first[pt.tri[c / 3] + 1]++;
	for (size_t p = 0; p < np; p++)
		first[p + 1] += first[p];
	std::vector<std::pair<uint32_t, uint32_t>> edge(first[np]);
	{
		std::vector<uint32_t> fill(first.begin(), first.end() - 1);
		for (size_t c = 0; c < 3 * ntris; c++)
			if (pt.open[c] && pt.tri[c / 3] != NONE) {
				const uint32_t *t = tris[c / 3];
				edge[fill[pt.tri[c / 3]]++] = {t[c % 3], t[(c % 3 + 1) % 3]};
			}
	}
	std::vector<uint8_t>().swap(pt.open);
	std::vector<std::pair<uint32_t, uint32_t>> e;
	for (size_t p = 0; p < np; p++) {
		if (pt.bad[p].load(std::memory_order_relaxed))
			continue;
		e.assign(edge.begin() + first[p], edge.begin() + first[p + 1]);
		const size_t n = e.size();
		/* No boundary: impossible for a flat patch, so not one. */
		bool ok = n >= 3;
		std::sort(e.begin(), e.end());
		for (size_t x = 1; x < n && ok; x++)
			ok = e[x].first != e[x - 1].first;
		/* One loop through every boundary vertex. */
		size_t steps = 0;
		for (uint32_t at = ok ? e[0].second : 0; ok && steps < n; steps++) {
			if (at == e[0].first)
				break;
			auto it =
			    std::lower_bound(e.begin(), e.end(), std::make_pair(at, uint32_t(0)));
			ok = it != e.end() && it->first == at;
			if (ok)
				at = it->second;
		}
		ok = ok && steps + 1 == n;
		if (!ok || !simple_polygon(verts, e, pt.code[p]))
			pt.bad[p].store(1, std::memory_order_relaxed);
	}
	for (size_t t = 0; t < ntris; t++)
		if (pt.tri[t] != NONE && pt.bad[pt.tri[t]].load(std::memory_order_relaxed))
			pt.tri[t] = NONE;
}

} /* namespace patches */

#endif /* STRATUM_REPAIR_EXACT_PATCHES_HPP */
