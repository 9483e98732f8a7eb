/*
 * snap.cpp - rounding an exact mesh to the output grid without creating
 * intersections (exact.h, exact_mesh_snap_round).
 *
 * Rounding every vertex on its own can make nearly touching triangles
 * cross, and cutting them again exactly only makes new rational points next
 * to the old ones.  Here the vertices move one at a time, and a move is kept
 * only if the triangles around the vertex still meet nothing but their
 * neighbours in shared faces, tested exactly against the current mesh (its
 * other vertices partly rounded, partly still rational).  So the mesh is
 * free of intersections after every move, and once every vertex is on the
 * grid the written file is too.  A vertex whose nearest grid point is not
 * safe tries the other corners of its grid cell (the "hot voxel" of snap
 * rounding), then merging into a neighbour that is already on the grid (an
 * edge collapse: what rounding does anyway to points that share a voxel).
 * No point off the grid is ever made, so the process ends: every vertex is
 * placed at most once and every merge removes one.
 */
#include "exact.h"

#include <CGAL/intersections.h>

#include "boxpairs.hpp"
#include "emesh.hpp"
#include "pairtest.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <iterator>
#include <memory>
#include <vector>

namespace
{

using boxpairs::Box;

/* The rounding state of a whole mesh. */
struct snapper {
	int bits;		/* 24 or 53 */
	double reach;		/* mm, per coordinate */
	std::vector<EPoint> pos;	/* current exact position */
	std::vector<std::array<double, 3>> cur;	/* its double value */
	std::vector<char> isd;		/* pos is exactly cur */
	std::vector<char> done;		/* on the grid; never moves again */
	std::vector<std::array<double, 3>> lo, hi;	/* box of the exact places merged here */
	std::vector<uint32_t> into;	/* vertex merged into, or itself */
	std::vector<std::array<uint32_t, 3>> tris;
	std::vector<uint32_t> origin;
	std::vector<char> alive;
	std::vector<std::vector<uint32_t>> star;	/* vertex -> triangles (some dead) */
	std::vector<std::vector<uint32_t>> near;	/* triangle -> triangles it may meet */
	std::vector<std::array<uint32_t, 3>> tris0;	/* corners in the exact mesh */
	std::vector<char> moved;	/* not at its place in the exact mesh */
	std::vector<uint32_t> patch;	/* edge-connected coplanar piece it is in */
};

bool on_grid(int bits, double x)
{
	return bits == 53 || (std::fabs(x) <= FLT_MAX && static_cast<double>(static_cast<float>(x)) == x);
}

/* The grid value nearest a (a double near exact value e) and the grid value
 * on e's other side; one value when e is on the grid. */
int grid_values(int bits, double a, const EFT &e, double out[2])
{
	double g, other;

	if (bits == 24) {
		const float f = static_cast<float>(a);
		g = f;
		if (EFT(g) == e) {
			out[0] = g;
			return 1;
		}
		other = EFT(g) < e ? std::nextafter(f, FLT_MAX) : std::nextafter(f, -FLT_MAX);
	} else {
		g = a;
		if (EFT(g) == e) {
			out[0] = g;
			return 1;
		}
		other = EFT(g) < e ? std::nextafter(g, DBL_MAX) : std::nextafter(g, -DBL_MAX);
	}
	out[0] = g;
	out[1] = other;
	return 2;
}

bool tri_double(const snapper &s, uint32_t t)
{
	const auto &v = s.tris[t];
	return s.isd[v[0]] && s.isd[v[1]] && s.isd[v[2]];
}

bool degenerate(const snapper &s, uint32_t t)
{
	const auto &v = s.tris[t];
	if (tri_double(s, t)) {
		auto p = [&s](uint32_t i) {
			return IK::Point_3(s.cur[i][0], s.cur[i][1], s.cur[i][2]);
		};
		return CGAL::collinear(p(v[0]), p(v[1]), p(v[2]));
	}
	return CGAL::collinear(s.pos[v[0]], s.pos[v[1]], s.pos[v[2]]);
}

/*
 * Whether the double boxes of t and u overlap; rational corners are within
 * a few units in the last place of their doubles, so a margin of a
 * millionth of the coordinates keeps every real contact.
 */
bool boxes_meet(const snapper &s, uint32_t t, uint32_t u)
{
	for (int k = 0; k < 3; k++) {
		double lt = HUGE_VAL, ht = -HUGE_VAL, lu = HUGE_VAL, hu = -HUGE_VAL, big = 0;
		for (uint32_t v : s.tris[t]) {
			lt = std::min(lt, s.cur[v][k]);
			ht = std::max(ht, s.cur[v][k]);
			big = std::max(big, std::fabs(s.cur[v][k]));
		}
		for (uint32_t v : s.tris[u]) {
			lu = std::min(lu, s.cur[v][k]);
			hu = std::max(hu, s.cur[v][k]);
			big = std::max(big, std::fabs(s.cur[v][k]));
		}
		const double margin = 1e-12 * big + DBL_MIN;
		if (ht + margin < lu || hu + margin < lt)
			return false;
	}
	return true;
}

/* Corners of t not where t had them in the exact mesh; *x: the last one. */
int displaced(const snapper &s, uint32_t t, uint32_t *x)
{
	int n = 0;
	for (int k = 0; k < 3; k++)
		if (s.tris[t][k] != s.tris0[t][k] || s.moved[s.tris[t][k]]) {
			n++;
			*x = s.tris[t][k];
		}
	return n;
}

/*
 * Pieces of one plane (same patch) cost exact arithmetic on rational
 * points to tell apart, and they need not: in the exact mesh they met only
 * in shared faces.  If u is still in place and t has one corner x off the
 * plane, t meets the plane only in its opposite edge, which it had in the
 * exact mesh too, so t and u still meet only in shared faces.
 */
bool coplanar_pieces_apart(const snapper &s, uint32_t t, uint32_t u)
{
	uint32_t x = 0, y = 0;
	if (s.patch[t] != s.patch[u] || displaced(s, u, &y) != 0)
		return false;
	const int n = displaced(s, t, &x);
	if (n == 0)
		return true;
	if (n > 1)
		return false;
	const auto &w = s.tris[u];
	return CGAL::orientation(s.pos[w[0]], s.pos[w[1]], s.pos[w[2]], s.pos[x]) !=
	       CGAL::COPLANAR;
}

bool meet(const snapper &s, uint32_t t, uint32_t u)
{
	const uint32_t *a = s.tris[t].data(), *b = s.tris[u].data();
	if (!boxes_meet(s, t, u))
		return false;
	if (coplanar_pieces_apart(s, t, u) || coplanar_pieces_apart(s, u, t))
		return false;
	if (tri_double(s, t) && tri_double(s, u)) {
		auto p = [&s](uint32_t i) {
			return IK::Point_3(s.cur[i][0], s.cur[i][1], s.cur[i][2]);
		};
		return pairtest::intersects<IK>(a, b, p);
	}
	if (pairtest::no_common_corner(a, b)) {
		pairtest::Ipt p[3], q[3];
		for (int k = 0; k < 3; k++) {
			const auto &x = CGAL::approx(s.pos[a[k]]), &y = CGAL::approx(s.pos[b[k]]);
			p[k] = {x.x(), x.y(), x.z()};
			q[k] = {y.x(), y.y(), y.z()};
		}
		if (pairtest::certainly_apart(p, q))
			return false;
	}
	return pairtest::intersects<EK>(a, b, [&s](uint32_t i) { return s.pos[i]; });
}

/* Whether the live triangles listed are non-degenerate and meet nothing. */
bool safe(const snapper &s, const std::vector<uint32_t> &changed)
{
	for (uint32_t t : changed)
		if (s.alive[t] && degenerate(s, t))
			return false;
	for (uint32_t t : changed) {
		if (!s.alive[t])
			continue;
		for (uint32_t u : s.near[t])
			if (u != t && s.alive[u] && meet(s, t, u))
				return false;
	}
	return true;
}

/* Whether point p is within reach of every exact place merged into v. */
bool within_reach(const snapper &s, uint32_t v, const double p[3])
{
	for (int k = 0; k < 3; k++)
		if (p[k] < s.hi[v][k] - s.reach || p[k] > s.lo[v][k] + s.reach)
			return false;
	return true;
}

void set_pos(snapper &s, uint32_t v, const double p[3])
{
	s.cur[v] = {p[0], p[1], p[2]};
	s.pos[v] = EPoint(p[0], p[1], p[2]);
	s.isd[v] = 1;
	s.moved[v] = 1;
}

std::vector<uint32_t> live_star(const snapper &s, uint32_t v)
{
	std::vector<uint32_t> r;
	for (uint32_t t : s.star[v])
		if (s.alive[t] && (s.tris[t][0] == v || s.tris[t][1] == v || s.tris[t][2] == v))
			r.push_back(t);
	return r;
}

/* Move v to grid point p if that is safe; undo otherwise. */
bool try_move(snapper &s, uint32_t v, const double p[3])
{
	if (!within_reach(s, v, p))
		return false;
	const EPoint old_pos = s.pos[v];
	const std::array<double, 3> old_cur = s.cur[v];
	const char old_isd = s.isd[v], old_moved = s.moved[v];
	set_pos(s, v, p);
	if (safe(s, live_star(s, v))) {
		s.done[v] = 1;
		return true;
	}
	s.pos[v] = old_pos;
	s.cur[v] = old_cur;
	s.isd[v] = old_isd;
	s.moved[v] = old_moved;
	return false;
}

std::vector<uint32_t> neighbours(const snapper &s, const std::vector<uint32_t> &st, uint32_t v)
{
	std::vector<uint32_t> r;
	for (uint32_t t : st)
		for (uint32_t x : s.tris[t])
			if (x != v)
				r.push_back(x);
	std::sort(r.begin(), r.end());
	r.erase(std::unique(r.begin(), r.end()), r.end());
	return r;
}

/*
 * Merge v into its neighbour w (on the grid) if the link condition holds
 * (the vertices next to both are exactly the third corners of the
 * triangles on edge vw, so a manifold stays one), no triangle degenerates
 * or repeats, and nothing meets; undo otherwise.
 */
bool try_collapse(snapper &s, uint32_t v, uint32_t w, size_t &removed)
{
	if (!within_reach(s, v, s.cur[w].data()))
		return false;
	const std::vector<uint32_t> sv = live_star(s, v), sw = live_star(s, w);
	std::vector<uint32_t> both, moved, third;
	for (uint32_t t : sv) {
		const auto &x = s.tris[t];
		if (x[0] == w || x[1] == w || x[2] == w) {
			both.push_back(t);
			third.push_back(x[0] ^ x[1] ^ x[2] ^ v ^ w);
		} else {
			moved.push_back(t);
		}
	}
	if (both.empty())
		return false;
	std::sort(third.begin(), third.end());
	if (std::adjacent_find(third.begin(), third.end()) != third.end())
		return false;
	const std::vector<uint32_t> nv = neighbours(s, sv, v), nw = neighbours(s, sw, w);
	std::vector<uint32_t> common;
	std::set_intersection(nv.begin(), nv.end(), nw.begin(), nw.end(),
			      std::back_inserter(common));
	if (common != third)
		return false;
	/* Repeats: a moved triangle equal to one already at w. */
	std::vector<std::array<uint32_t, 3>> keys;
	for (uint32_t t : sw) {
		if (std::find(both.begin(), both.end(), t) != both.end())
			continue;
		std::array<uint32_t, 3> k = s.tris[t];
		std::sort(k.begin(), k.end());
		keys.push_back(k);
	}
	for (uint32_t t : moved) {
		std::array<uint32_t, 3> k = s.tris[t];
		for (uint32_t &x : k)
			if (x == v)
				x = w;
		std::sort(k.begin(), k.end());
		if (std::find(keys.begin(), keys.end(), k) != keys.end())
			return false;
	}
	for (uint32_t t : both)
		s.alive[t] = 0;
	for (uint32_t t : moved)
		for (uint32_t &x : s.tris[t])
			if (x == v)
				x = w;
	if (safe(s, moved)) {
		for (uint32_t t : moved)
			s.star[w].push_back(t);
		s.star[v].clear();
		for (int k = 0; k < 3; k++) {
			s.lo[w][k] = std::min(s.lo[w][k], s.lo[v][k]);
			s.hi[w][k] = std::max(s.hi[w][k], s.hi[v][k]);
		}
		s.into[v] = w;
		s.done[v] = 1;
		removed += both.size();
		return true;
	}
	for (uint32_t t : moved)
		for (uint32_t &x : s.tris[t])
			if (x == w)
				x = v;
	for (uint32_t t : both)
		s.alive[t] = 1;
	return false;
}

/* Grid candidates for v: the corners of its cell, nearest first. */
std::vector<std::array<double, 3>> corners(const snapper &s, uint32_t v)
{
	double g[3][2];
	int n[3];
	const EFT e[3] = {s.pos[v].x(), s.pos[v].y(), s.pos[v].z()};
	for (int k = 0; k < 3; k++)
		n[k] = grid_values(s.bits, s.cur[v][k], e[k], g[k]);
	std::vector<std::array<double, 3>> c;
	for (int i = 0; i < n[0]; i++)
		for (int j = 0; j < n[1]; j++)
			for (int k = 0; k < n[2]; k++)
				c.push_back({g[0][i], g[1][j], g[2][k]});
	const std::array<double, 3> a = s.cur[v];
	auto d2 = [&a](const std::array<double, 3> &p) {
		double r = 0;
		for (int k = 0; k < 3; k++)
			r += (p[k] - a[k]) * (p[k] - a[k]);
		return r;
	};
	/* The first is the nearest grid point (plain rounding); keep it first. */
	std::stable_sort(c.begin() + 1, c.end(), [&d2](const std::array<double, 3> &p,
						      const std::array<double, 3> &q) {
		return d2(p) < d2(q);
	});
	return c;
}

uint32_t find_patch(std::vector<uint32_t> &p, uint32_t x)
{
	while (p[x] != x)
		x = p[x] = p[p[x]];
	return x;
}

/*
 * Whether triangles t and u of m, sharing edge ab (third corners c and d),
 * lie in one plane, exactly.  Double corners go through Epick's static
 * filter (Epeck's interval filter fails into rationals on nearly flat
 * slab walls).  A piece of a split triangle lies in that triangle's plane
 * (m.split_planes), so t and u do exactly when u's plane's corners lie in
 * t's: doubles again, where the thin pieces along a cut have rational ones.
 */
bool same_plane(const snapper &s, const exact_mesh &m, uint32_t t, uint32_t u, uint32_t a,
		uint32_t b, uint32_t c, uint32_t d)
{
	auto p = [](const std::array<double, 3> &x) { return IK::Point_3(x[0], x[1], x[2]); };
	if (s.isd[a] && s.isd[b] && s.isd[c] && s.isd[d])
		return CGAL::orientation(p(s.cur[a]), p(s.cur[b]), p(s.cur[c]), p(s.cur[d])) ==
		       CGAL::COPLANAR;
	/* The double corners spanning triangle x's plane, if known. */
	auto corners = [&m, &p](uint32_t x, IK::Point_3 q[3]) {
		const auto it = m.split_planes.find(m.plane[x]);
		for (int k = 0; k < 3; k++) {
			const uint32_t v = m.tris[x][k];
			if (it == m.split_planes.end() && m.slot[v] >= 0)
				return false;
			q[k] = p(it != m.split_planes.end() ? it->second[k] : m.approx[v]);
		}
		return true;
	};
	IK::Point_3 pt[3], pu[3];
	if (!corners(t, pt) || !corners(u, pu) || CGAL::collinear(pt[0], pt[1], pt[2]))
		return CGAL::orientation(s.pos[a], s.pos[b], s.pos[c], s.pos[d]) == CGAL::COPLANAR;
	for (const IK::Point_3 &x : pu)
		if (CGAL::orientation(pt[0], pt[1], pt[2], x) != CGAL::COPLANAR)
			return false;
	return true;
}

/* Union of triangles that share an edge and lie in one plane (exactly).
 * Pieces of one split triangle are known to (m.plane): for them the
 * predicate would only confirm an exact zero, its costliest answer. */
void build_patches(snapper &s, const exact_mesh &m)
{
	struct edge {
		uint32_t lo, hi, t;
	};
	std::vector<edge> e;
	const size_t nt = s.tris.size();
	e.reserve(3 * nt);
	for (size_t t = 0; t < nt; t++)
		for (int k = 0; k < 3; k++) {
			const uint32_t a = s.tris[t][k], b = s.tris[t][(k + 1) % 3];
			e.push_back({std::min(a, b), std::max(a, b), static_cast<uint32_t>(t)});
		}
	std::sort(e.begin(), e.end(), [](const edge &x, const edge &y) {
		return x.lo != y.lo ? x.lo < y.lo : x.hi != y.hi ? x.hi < y.hi : x.t < y.t;
	});
	s.patch.resize(nt);
	for (size_t t = 0; t < nt; t++)
		s.patch[t] = static_cast<uint32_t>(t);
	auto third = [&s](uint32_t t, uint32_t a, uint32_t b) {
		const auto &v = s.tris[t];
		return v[0] ^ v[1] ^ v[2] ^ a ^ b;
	};
	for (size_t i = 0; i < e.size();) {
		size_t j = i;
		while (j < e.size() && e[j].lo == e[i].lo && e[j].hi == e[i].hi)
			j++;
		for (size_t a = i; a < j; a++)
			for (size_t b = a + 1; b < j; b++) {
				const uint32_t c = third(e[a].t, e[a].lo, e[a].hi),
					       d = third(e[b].t, e[b].lo, e[b].hi);
				if (m.plane[e[a].t] != m.plane[e[b].t] &&
				    !same_plane(s, m, e[a].t, e[b].t, e[a].lo, e[a].hi, c, d))
					continue;
				const uint32_t ra = find_patch(s.patch, e[a].t),
					       rb = find_patch(s.patch, e[b].t);
				s.patch[std::max(ra, rb)] = std::min(ra, rb);
			}
		i = j;
	}
	for (size_t t = 0; t < nt; t++)
		s.patch[t] = find_patch(s.patch, static_cast<uint32_t>(t));
}

void build(snapper &s, const exact_mesh &m, int threads)
{
	const size_t nv = m.approx.size(), nt = m.tris.size();
	s.pos.resize(nv);
	s.cur = m.approx;
	s.isd.assign(nv, 0);
	s.done.assign(nv, 0);
	s.lo = m.approx;
	s.hi = m.approx;
	s.into.resize(nv);
	s.tris = m.tris;
	s.tris0 = m.tris;
	s.moved.assign(nv, 0);
	s.origin = m.origin;
	s.alive.assign(nt, 1);
	s.star.assign(nv, {});
	for (size_t v = 0; v < nv; v++) {
		s.into[v] = static_cast<uint32_t>(v);
		s.isd[v] = m.slot[v] < 0;
		s.pos[v] = s.isd[v] ? EPoint(m.approx[v][0], m.approx[v][1], m.approx[v][2])
				    : m.ex[static_cast<size_t>(m.slot[v])];
		s.done[v] = s.isd[v] && on_grid(s.bits, m.approx[v][0]) &&
			    on_grid(s.bits, m.approx[v][1]) && on_grid(s.bits, m.approx[v][2]);
	}
	for (size_t t = 0; t < nt; t++)
		for (uint32_t v : m.tris[t])
			s.star[v].push_back(static_cast<uint32_t>(t));

	/* Candidate pairs for triangles that will change: boxes grown by the
	 * reach hold every place their corners can take. */
	std::vector<char> active(nt, 0);
	bool any = false;
	for (size_t t = 0; t < nt; t++)
		for (uint32_t v : m.tris[t])
			if (!s.done[v])
				active[t] = 1, any = true;
	s.near.assign(nt, {});
	if (!any)
		return;
	build_patches(s, m);
	std::vector<Box> boxes(nt);
	std::vector<const Box *> use(nt);
	for (size_t t = 0; t < nt; t++) {
		float lo[3], hi[3];
		for (int k = 0; k < 3; k++) {
			double a = HUGE_VAL, b = -HUGE_VAL;
			for (uint32_t v : m.tris[t]) {
				a = std::min(a, m.approx[v][k]);
				b = std::max(b, m.approx[v][k]);
			}
			/* One more float step covers the double approximation. */
			const float margin = static_cast<float>(s.reach);
			lo[k] = std::nextafter(boxpairs::box_coord(a) - margin, -boxpairs::BOX_LIMIT);
			hi[k] = std::nextafter(boxpairs::box_coord(b) + margin, boxpairs::BOX_LIMIT);
		}
		boxes[t] = Box(lo, hi);
		use[t] = &boxes[t];
	}
	/* On all cores, one pair list per leaf; each candidate list is then
	 * sorted, so the result is the same whatever the thread count. */
	std::vector<std::vector<std::pair<uint32_t, uint32_t>>> found;
	boxpairs::for_each_pair(
	    boxes, std::move(use), threads, [&](size_t n) { found.resize(n); },
	    [&](size_t leaf, size_t a, size_t b) {
		    if (active[a] || active[b])
			    found[leaf].emplace_back(static_cast<uint32_t>(a),
						     static_cast<uint32_t>(b));
	    });
	std::vector<Box>().swap(boxes);
	for (auto &f : found) {
		for (const auto &ab : f) {
			if (active[ab.first])
				s.near[ab.first].push_back(ab.second);
			if (active[ab.second])
				s.near[ab.second].push_back(ab.first);
		}
		std::vector<std::pair<uint32_t, uint32_t>>().swap(f);
	}
	boxpairs::for_each_index(nt, threads,
				 [&](size_t t) { std::sort(s.near[t].begin(), s.near[t].end()); });
}

/* Place v safely: a corner of its cell, else a merge; false if neither. */
bool place(snapper &s, uint32_t v, exact_snap_stats &st)
{
	const auto c = corners(s, v);
	for (size_t i = 0; i < c.size(); i++)
		if (try_move(s, v, c[i].data())) {
			(i == 0 ? st.rounded : st.other_corner)++;
			return true;
		}
	/* Merge into the nearest neighbour on the grid. */
	std::vector<uint32_t> nb = neighbours(s, live_star(s, v), v);
	const std::array<double, 3> a = s.cur[v];
	auto d2 = [&](uint32_t w) {
		double r = 0;
		for (int k = 0; k < 3; k++)
			r += (s.cur[w][k] - a[k]) * (s.cur[w][k] - a[k]);
		return r;
	};
	std::sort(nb.begin(), nb.end(), [&](uint32_t x, uint32_t y) { return d2(x) < d2(y); });
	for (uint32_t w : nb)
		if (s.done[w] && try_collapse(s, v, w, st.triangles_removed)) {
			st.collapsed++;
			return true;
		}
	return false;
}

/*
 * What each live triangle of check (sorted, no repeats) offends: bad[i]
 * (flat, or meets something) and with[i] (what it meets, none when flat)
 * for check[i]; in_check is all 0 on entry and on return.  Near
 * lists are symmetric between triangles that can move, so a pair of two
 * listed triangles is tested once, from its lower one, not from both.
 */
void offenders(const snapper &s, const std::vector<uint32_t> &check, std::vector<char> &in_check,
	       std::vector<char> &bad, std::vector<std::vector<uint32_t>> &with)
{
	const size_t n = check.size();
	std::vector<char> flat(n, 0);
	bad.assign(n, 0);
	with.assign(n, {});
	for (size_t i = 0; i < n; i++)
		if (s.alive[check[i]]) {
			in_check[check[i]] = 1;
			flat[i] = bad[i] = degenerate(s, check[i]);
		}
	auto at = [&check](uint32_t u) {
		return static_cast<size_t>(std::lower_bound(check.begin(), check.end(), u) -
					   check.begin());
	};
	for (size_t i = 0; i < n; i++) {
		const uint32_t t = check[i];
		if (!in_check[t])
			continue;
		for (uint32_t u : s.near[t]) {
			if (u == t || !s.alive[u] || (in_check[u] && u < t))
				continue;
			/* A flat triangle offends whatever it meets: only
			 * the other side of the pair needs the test. */
			const size_t j = in_check[u] ? at(u) : n;
			if ((flat[i] && (j == n || flat[j])) || !meet(s, t, u))
				continue;
			if (!flat[i]) {
				bad[i] = 1;
				with[i].push_back(u);
			}
			if (j < n && !flat[j]) {
				bad[j] = 1;
				with[j].push_back(t);
			}
		}
	}
	/* In near-list order. */
	for (size_t i = 0; i < n; i++) {
		std::sort(with[i].begin(), with[i].end());
		in_check[check[i]] = 0;
	}
}

/*
 * Round plainly, then take back to their exact places the rounded vertices
 * of every triangle that crosses something or degenerates, and of what
 * those then cross, until the mesh is free of intersections again (it is
 * once every vertex is back).  Returns the vertices taken back.  Tests
 * between rounded triangles are in doubles, so this costs little where
 * plain rounding is right, which is almost everywhere.
 */
std::vector<uint32_t> round_plainly(snapper &s, const std::vector<uint32_t> &todo)
{
	const size_t nv = s.pos.size();
	const std::vector<EPoint> epos = s.pos;
	const std::vector<std::array<double, 3>> ecur = s.cur;
	const std::vector<char> eisd = s.isd;
	std::vector<char> rounded(nv, 0), back(nv, 0), in_check(s.tris.size(), 0), bad;
	std::vector<uint32_t> check, taken;
	std::vector<std::vector<uint32_t>> with;

	for (uint32_t v : todo) {
		const auto c = corners(s, v);
		set_pos(s, v, c[0].data());
		s.done[v] = 1;
		rounded[v] = 1;
	}
	for (size_t t = 0; t < s.tris.size(); t++)
		if (!s.near[t].empty())
			check.push_back(static_cast<uint32_t>(t));
	while (!check.empty()) {
		std::vector<uint32_t> fresh;
		auto take = [&](uint32_t t) {
			for (uint32_t x : s.tris[t])
				if (rounded[x] && !back[x]) {
					back[x] = 1;
					fresh.push_back(x);
				}
		};
		offenders(s, check, in_check, bad, with);
		for (size_t i = 0; i < check.size(); i++) {
			if (!bad[i])
				continue;
			take(check[i]);
			for (uint32_t u : with[i])
				take(u);
		}
		for (uint32_t x : fresh) {
			s.pos[x] = epos[x];
			s.cur[x] = ecur[x];
			s.isd[x] = eisd[x];
			s.moved[x] = 0;
			s.done[x] = 0;
		}
		check.clear();
		for (uint32_t x : fresh)
			for (uint32_t t : live_star(s, x))
				check.push_back(t);
		std::sort(check.begin(), check.end());
		check.erase(std::unique(check.begin(), check.end()), check.end());
		taken.insert(taken.end(), fresh.begin(), fresh.end());
	}
	return taken;
}

void run(snapper &s, exact_snap_stats &st)
{
	const size_t nv = s.pos.size();
	std::vector<uint32_t> todo;
	for (size_t v = 0; v < nv; v++)
		if (!s.done[v] && !live_star(s, static_cast<uint32_t>(v)).empty())
			todo.push_back(static_cast<uint32_t>(v));
	if (todo.empty())
		return;
	const size_t all = todo.size();
	todo = round_plainly(s, todo);
	st.rounded += all - todo.size();

	/* The rest one at a time, as long as a round places any. */
	for (bool progress = true; progress && !todo.empty();) {
		progress = false;
		std::vector<uint32_t> left;
		for (uint32_t v : todo) {
			if (place(s, v, st))
				progress = true;
			else
				left.push_back(v);
		}
		todo.swap(left);
	}
	/* No safe place: plain rounding, and the caller's check decides. */
	for (uint32_t v : todo) {
		const auto c = corners(s, v);
		set_pos(s, v, c[0].data());
		s.done[v] = 1;
		st.unplaced++;
	}
}

/* Whether every vertex a triangle uses is exact and on the grid already. */
bool on_grid_already(const exact_mesh &m, int bits)
{
	for (const auto &t : m.tris)
		for (uint32_t v : t)
			if (m.slot[v] >= 0 || !on_grid(bits, m.approx[v][0]) ||
			    !on_grid(bits, m.approx[v][1]) || !on_grid(bits, m.approx[v][2]))
				return false;
	return true;
}

/* The live triangles (all when alive is NULL) with the vertices they use,
 * numbered in order of first use, at their double places. */
std::unique_ptr<exact_mesh> emit(const std::vector<std::array<uint32_t, 3>> &tris,
				 const std::vector<char> *alive,
				 const std::vector<std::array<double, 3>> &cur,
				 const std::vector<uint32_t> &origin)
{
	std::unique_ptr<exact_mesh> r(new exact_mesh);
	std::vector<uint32_t> map(cur.size(), UINT32_MAX);
	for (size_t t = 0; t < tris.size(); t++) {
		if (alive && !(*alive)[t])
			continue;
		std::array<uint32_t, 3> w;
		for (int k = 0; k < 3; k++) {
			const uint32_t v = tris[t][k];
			if (map[v] == UINT32_MAX) {
				map[v] = static_cast<uint32_t>(r->approx.size());
				r->approx.push_back(cur[v]);
				r->slot.push_back(-1);
			}
			w[k] = map[v];
		}
		/* Rounded corners leave no plane known: each its own id. */
		r->add_triangle(w, origin[t]);
	}
	return r;
}

} /* namespace */

extern "C" int exact_mesh_snap_round(const struct exact_mesh *m, int mantissa_bits, double reach,
				     int threads, struct exact_mesh **out,
				     struct exact_snap_stats *stats, struct st_error *err)
{
	exact_snap_stats st = exact_snap_stats();

	if (stats)
		*stats = st;
	if (!out)
		return st_error_set(err, ST_ERR_ARG, "exact: output pointer is NULL");
	*out = nullptr;
	if (!m || (mantissa_bits != 24 && mantissa_bits != 53) || !(reach >= 0))
		return st_error_set(err, ST_ERR_ARG,
				    "exact: snap rounding needs a mesh, 24 or 53 bits and a reach >= 0");
	for (const auto &p : m->approx)
		for (double x : p)
			if (mantissa_bits == 24 && std::fabs(x) > FLT_MAX)
				return st_error_set(err, ST_ERR_RANGE,
						    "coordinate %g does not fit a binary STL float; "
						    "write ASCII instead",
						    x);
	try {
		/* A mesh already on the grid (any clean float STL) keeps every
		 * vertex: skip the snapper, whose per-vertex exact points, stars
		 * and candidate lists would double the peak memory for nothing. */
		if (on_grid_already(*m, mantissa_bits)) {
			*out = emit(m->tris, nullptr, m->approx, m->origin).release();
			return ST_OK;
		}
		snapper s;
		s.bits = mantissa_bits;
		s.reach = reach;
		build(s, *m, threads);
		run(s, st);

		std::unique_ptr<exact_mesh> r = emit(s.tris, &s.alive, s.cur, s.origin);
		/* How far each exact place ended up: follow its merges. */
		for (size_t v = 0; v < s.pos.size(); v++) {
			uint32_t w = static_cast<uint32_t>(v);
			while (s.into[w] != w)
				w = s.into[w];
			double d = 0;
			for (int k = 0; k < 3; k++)
				d += (s.cur[w][k] - m->approx[v][k]) * (s.cur[w][k] - m->approx[v][k]);
			st.max_move = std::max(st.max_move, std::sqrt(d));
		}
		*out = r.release();
		if (stats)
			*stats = st;
		return ST_OK;
	} catch (...) {
		return emesh::fail(err, "rounding to the output grid");
	}
}
