/*
 * emesh.cpp - exact meshes for the repair (exact.h, "exact mesh"): exact
 * self-intersection resolution (seed 000 §4.1) and the exact predicates the
 * outer-hull growing, containment and wire tests need.
 *
 * Vertices read from a file are doubles and exact as they are; only the
 * points created where triangles cross are rationals (CGAL Epeck), kept in a
 * side table so a mesh that needs no cutting costs no more than doubles.
 * Decisions over double-only triangles use Epick's filtered predicates;
 * anything touching a rational vertex uses Epeck.
 */
#include "exact.h"

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/intersections.h>

#include "boxpairs.hpp"
#include "cutpair.hpp"
#include "emesh.hpp"
#include "pairtest.hpp"
#include "retri.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <exception>
#include <map>
#include <new>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>


namespace
{

using boxpairs::Box;
using boxpairs::box_coord;
using retri::cuts;
using retri::add_intersection;
typedef EK::Exact_kernel::Point_3 XPoint;

/* Hash of a triangle's sorted corners. */
struct tri_hash {
	size_t operator()(const std::array<uint32_t, 3> &t) const
	{
		return (static_cast<size_t>(t[0]) * 0x9e3779b97f4a7c15ull) ^
		       (static_cast<size_t>(t[1]) * 0xc2b2ae3d27d4eb4full) ^ t[2];
	}
};

EPoint epoint(const exact_mesh &m, uint32_t v)
{
	if (m.slot[v] >= 0)
		return m.ex[static_cast<size_t>(m.slot[v])];
	const std::array<double, 3> &a = m.approx[v];
	return EPoint(a[0], a[1], a[2]);
}

IK::Point_3 ipoint(const exact_mesh &m, uint32_t v)
{
	const std::array<double, 3> &a = m.approx[v];
	return IK::Point_3(a[0], a[1], a[2]);
}

bool tri_is_double(const exact_mesh &m, size_t t)
{
	const std::array<uint32_t, 3> &v = m.tris[t];
	return m.slot[v[0]] < 0 && m.slot[v[1]] < 0 && m.slot[v[2]] < 0;
}

/* Add a vertex at exact point p; stored as a double when p is one. */
uint32_t add_vertex(exact_mesh &m, const EPoint &p)
{
	const double x = CGAL::to_double(p.x()), y = CGAL::to_double(p.y()),
		     z = CGAL::to_double(p.z());

	if (m.approx.size() >= MESH_LIMIT)
		throw std::length_error("too many vertices");
	m.approx.push_back({x, y, z});
	if (EFT(x) == p.x() && EFT(y) == p.y() && EFT(z) == p.z()) {
		m.slot.push_back(-1);
	} else {
		m.slot.push_back(static_cast<int32_t>(m.ex.size()));
		m.ex.push_back(p);
	}
	return static_cast<uint32_t>(m.approx.size() - 1);
}

/* Key for welding double vertices bit-exactly (+0 and -0 are one). */
struct dkey {
	double v[3];
	bool operator==(const dkey &o) const
	{
		return v[0] == o.v[0] && v[1] == o.v[1] && v[2] == o.v[2];
	}
};
struct dkey_hash {
	size_t operator()(const dkey &k) const
	{
		size_t h = 1469598103934665603ull;
		for (double x : k.v) {
			if (x == 0)
				x = 0; /* -0 hashes like +0 */
			uint64_t b;
			std::memcpy(&b, &x, sizeof(b));
			h = (h ^ b) * 1099511628211ull;
		}
		return h;
	}
};

/*
 * Exact points unified by the doubles nearest their exact coordinates
 * (which, unlike interval approximations, depend on the value alone),
 * candidates with equal doubles then compared exactly.  A hash, not an
 * ordered map: on 200k-triangle soups the ordered map's cache misses
 * took a fifth of the exact pass.
 */
struct point_index {
	exact_mesh &m;
	std::unordered_multimap<dkey, uint32_t, dkey_hash> map;

	static dkey key(const EPoint &p)
	{
		const XPoint &e = CGAL::exact(p);
		return dkey{{CGAL::to_double(e.x()), CGAL::to_double(e.y()), CGAL::to_double(e.z())}};
	}
	/* Vertex v of m, once (distinct vertices are distinct points). */
	void add_existing(uint32_t v)
	{
		const dkey k = m.slot[v] < 0 ? dkey{{m.approx[v][0], m.approx[v][1], m.approx[v][2]}}
					     : key(m.ex[static_cast<size_t>(m.slot[v])]);
		for (auto r = map.equal_range(k); r.first != r.second; ++r.first)
			if (r.first->second == v)
				return;
		map.emplace(k, v);
	}
	/* The vertex at exact point p, added to m if new. */
	uint32_t find_or_add(const EPoint &p)
	{
		const dkey k = key(p);
		for (auto r = map.equal_range(k); r.first != r.second; ++r.first)
			if (epoint(m, r.first->second) == p)
				return r.first->second;
		const uint32_t v = add_vertex(m, p);
		map.emplace(k, v);
		return v;
	}
};

/*
 * The float box of triangle t.  Rational vertices are known only to within
 * an ulp of their double approximation, so their boxes grow by one float
 * step outwards and still contain the exact triangle.
 */
Box tri_box(const exact_mesh &m, size_t t)
{
	float lo[3], hi[3];
	const bool exact = tri_is_double(m, t);

	for (int k = 0; k < 3; k++) {
		double a = m.approx[m.tris[t][0]][k], b = m.approx[m.tris[t][1]][k],
		       c = m.approx[m.tris[t][2]][k];
		lo[k] = box_coord(std::min(std::min(a, b), c));
		hi[k] = box_coord(std::max(std::max(a, b), c));
		if (!exact) {
			lo[k] = std::nextafter(lo[k], -boxpairs::BOX_LIMIT);
			hi[k] = std::nextafter(hi[k], boxpairs::BOX_LIMIT);
		}
	}
	return Box(lo, hi);
}

/* Whether triangles u and w are certainly apart, from interval corners. */
bool apart(const exact_mesh &m, const uint32_t *u, const uint32_t *w)
{
	pairtest::Ipt p[3], q[3];
	for (int k = 0; k < 3; k++) {
		/* epoint returns a handle by value: keep it alive while its
		 * interval approximation is read (a reference into a temporary
		 * dangles). */
		const auto pu = epoint(m, u[k]), pw = epoint(m, w[k]);
		const auto x = CGAL::approx(pu), y = CGAL::approx(pw);
		p[k] = {x.x(), x.y(), x.z()};
		q[k] = {y.x(), y.y(), y.z()};
	}
	return pairtest::certainly_apart(p, q);
}

/* Every pair of triangles meeting outside a common face. */
std::vector<std::pair<uint32_t, uint32_t>> find_pairs(const exact_mesh &m, int threads)
{
	const size_t n = m.tris.size();
	std::vector<Box> boxes(n);
	std::vector<const Box *> use(n);
	std::vector<std::vector<std::pair<uint32_t, uint32_t>>> found;

	for (size_t t = 0; t < n; t++) {
		boxes[t] = tri_box(m, t);
		use[t] = &boxes[t];
	}
	auto geti = [&m](uint32_t v) { return ipoint(m, v); };
	auto gete = [&m](uint32_t v) { return epoint(m, v); };
	boxpairs::for_each_pair(
	    boxes, std::move(use), threads, [&](size_t nl) { found.resize(nl); },
	    [&](size_t leaf, size_t s, size_t t) {
		    const uint32_t *u = m.tris[s].data(), *w = m.tris[t].data();
		    bool hit;
		    if (tri_is_double(m, s) && tri_is_double(m, t))
			    hit = pairtest::intersects<IK>(u, w, geti);
		    else if (pairtest::no_common_corner(u, w) && apart(m, u, w))
			    hit = false;
		    else
			    hit = pairtest::intersects<EK>(u, w, gete);
		    if (hit)
			    found[leaf].emplace_back(static_cast<uint32_t>(std::min(s, t)),
						     static_cast<uint32_t>(std::max(s, t)));
	    });
	std::vector<std::pair<uint32_t, uint32_t>> all;
	for (auto &f : found)
		all.insert(all.end(), f.begin(), f.end());
	std::sort(all.begin(), all.end());
	return all;
}

/* Cut triangle t of m along c into *pieces (retri.hpp). */
void split_triangle(const exact_mesh &m, uint32_t t, const cuts &c,
		    std::vector<std::array<EPoint, 3>> &pieces)
{
	retri::split(epoint(m, m.tris[t][0]), epoint(m, m.tris[t][1]), epoint(m, m.tris[t][2]), c,
		     pieces);
}

/* The refinement itself; see exact_mesh_refine. */
void refine(exact_mesh &m, int threads, exact_refine_stats &st)
{
	const std::vector<std::pair<uint32_t, uint32_t>> pairs = find_pairs(m, threads);

	st = exact_refine_stats();
	st.intersecting_pairs = pairs.size();
	if (pairs.empty()) {
		m.parent.resize(m.tris.size());
		for (size_t t = 0; t < m.tris.size(); t++)
			m.parent[t] = static_cast<uint32_t>(t);
		m.parent_whole.assign(m.tris.size(), 1);
		return;
	}

	/* What each pair adds to both its triangles' cuts, found on all cores
	 * (Epeck's lazy numbers are thread-safe since CGAL 5.5: each exact
	 * value is computed under a once flag), then gathered in pair order. */
	std::vector<cuts> meet(pairs.size());
	boxpairs::for_each_index(pairs.size(), threads, [&](size_t i) {
		const uint32_t s = pairs[i].first, t = pairs[i].second;
		const auto &u = m.tris[s], &w = m.tris[t];
		std::vector<EPoint> seg;
		auto keep = [&](const std::vector<EPoint> &g) {
			if (g.size() == 1)
				meet[i].points.push_back(g[0]);
			else if (g.size() == 2)
				meet[i].segments.emplace_back(g[0], g[1]);
		};
		if (tri_is_double(m, s) && tri_is_double(m, t)) {
			const IK::Point_3 pu[3] = {ipoint(m, u[0]), ipoint(m, u[1]), ipoint(m, u[2])};
			const IK::Point_3 pw[3] = {ipoint(m, w[0]), ipoint(m, w[1]), ipoint(m, w[2])};
			if (cutpair::intersect(pu, pw, seg))
				return keep(seg);
		} else {
			const EPoint eu[3] = {epoint(m, u[0]), epoint(m, u[1]), epoint(m, u[2])};
			const EPoint ew[3] = {epoint(m, w[0]), epoint(m, w[1]), epoint(m, w[2])};
			if (cutpair::intersect(eu, ew, seg))
				return keep(seg);
		}
		/* In one plane: the general intersection (an overlap polygon). */
		EK::Triangle_3 a(epoint(m, u[0]), epoint(m, u[1]), epoint(m, u[2]));
		EK::Triangle_3 b(epoint(m, w[0]), epoint(m, w[1]), epoint(m, w[2]));
		add_intersection(a, b, meet[i]);
	});
	std::unordered_map<uint32_t, cuts> cut;
	for (size_t i = 0; i < pairs.size(); i++)
		for (uint32_t t : {pairs[i].first, pairs[i].second}) {
			cuts &c = cut[t];
			c.points.insert(c.points.end(), meet[i].points.begin(), meet[i].points.end());
			c.segments.insert(c.segments.end(), meet[i].segments.begin(),
					  meet[i].segments.end());
		}
	std::vector<cuts>().swap(meet);

	/* The cut triangles in order, each triangulated on any core. */
	std::vector<uint32_t> order;
	order.reserve(cut.size());
	for (const auto &kv : cut)
		order.push_back(kv.first);
	std::sort(order.begin(), order.end());
	std::vector<std::vector<std::array<EPoint, 3>>> pieces_of(order.size());
	std::vector<int32_t> piece_slot(m.tris.size(), -1);
	for (size_t i = 0; i < order.size(); i++)
		piece_slot[order[i]] = static_cast<int32_t>(i);
	boxpairs::for_each_index(order.size(), threads, [&](size_t i) {
		split_triangle(m, order[i], cut.find(order[i])->second, pieces_of[i]);
	});

	/* Points of affected triangles are unified through this map; it starts
	 * with their own corners so a cut point on a corner reuses it. */
	point_index index{m, {}};
	for (uint32_t t : order)
		for (uint32_t v : m.tris[t])
			index.add_existing(v);

	/* The same point reaches several pieces as one lazy handle (a cut
	 * point is shared by both triangles of its pair): those skip the
	 * exact comparisons of the map.  Every handle stays alive in
	 * pieces_of while this is used, so no id is reused. */
	std::unordered_map<EPoint::Id_type, uint32_t> by_handle;
	std::vector<std::array<uint32_t, 3>> tris;
	std::vector<uint32_t> origin, plane, parent;
	std::vector<uint8_t> parent_whole(m.tris.size(), 1);
	/* Pieces already emitted, by sorted corners: coplanar overlaps give
	 * the same piece from both triangles, and one layer is kept. */
	std::unordered_set<std::array<uint32_t, 3>, tri_hash> emitted;
	const size_t nverts0 = m.approx.size();

	tris.reserve(m.tris.size() + 4 * cut.size());
	origin.reserve(tris.capacity());
	plane.reserve(tris.capacity());
	parent.reserve(tris.capacity());
	for (size_t t = 0; t < m.tris.size(); t++) {
		if (piece_slot[t] < 0) {
			tris.push_back(m.tris[t]);
			origin.push_back(m.origin[t]);
			plane.push_back(m.plane[t]);
			parent.push_back(static_cast<uint32_t>(t));
			continue;
		}
		const std::vector<std::array<EPoint, 3>> &pieces =
		    pieces_of[static_cast<size_t>(piece_slot[t])];
		st.triangles_split++;
		for (const auto &pc : pieces) {
			std::array<uint32_t, 3> v;
			for (int k = 0; k < 3; k++) {
				auto h = by_handle.find(pc[k].id());
				if (h != by_handle.end()) {
					v[k] = h->second;
					continue;
				}
				v[k] = index.find_or_add(pc[k]);
				by_handle.emplace(pc[k].id(), v[k]);
			}
			std::array<uint32_t, 3> key = v;
			std::sort(key.begin(), key.end());
			if (!emitted.insert(key).second) {
				st.duplicates_removed++;
				parent_whole[t] = 0;
				continue;
			}
			if (tris.size() >= MESH_LIMIT)
				throw std::length_error("too many triangles");
			tris.push_back(v);
			origin.push_back(m.origin[t]);
			plane.push_back(m.plane[t]);
			parent.push_back(static_cast<uint32_t>(t));
		}
	}
	st.new_vertices = m.approx.size() - nverts0;
	m.tris.swap(tris);
	m.origin.swap(origin);
	m.plane.swap(plane);
	m.parent.swap(parent);
	m.parent_whole.swap(parent_whole);
}

/* Exact comparison of two vertices, lexicographic on (x, y, z). */
CGAL::Comparison_result compare_vertices(const exact_mesh &m, uint32_t a, uint32_t b)
{
	if (m.slot[a] < 0 && m.slot[b] < 0) {
		const std::array<double, 3> &p = m.approx[a], &q = m.approx[b];
		for (int k = 0; k < 3; k++)
			if (p[k] != q[k])
				return p[k] < q[k] ? CGAL::SMALLER : CGAL::LARGER;
		return CGAL::EQUAL;
	}
	return CGAL::compare_xyz(epoint(m, a), epoint(m, b));
}

/* See exact_mesh_seed. */
void find_seed(const exact_mesh &m, const uint32_t *list, size_t n, uint32_t &seed, bool &flip)
{
	uint32_t v0 = m.tris[list[0]][0];
	for (size_t i = 0; i < n; i++)
		for (uint32_t v : m.tris[list[i]])
			if (compare_vertices(m, v, v0) == CGAL::LARGER)
				v0 = v;
	const EPoint p0 = epoint(m, v0);

	/* Edge at v0 whose direction has the smallest |x| part:
	 * dx_i^2 / |e_i|^2 compared by cross-multiplying, exactly. */
	bool have = false;
	uint32_t w0 = 0;
	EFT best_dx2, best_len2;
	for (size_t i = 0; i < n; i++) {
		const auto &t = m.tris[list[i]];
		for (int k = 0; k < 3; k++) {
			if (t[k] != v0)
				continue;
			for (int j = 1; j <= 2; j++) {
				const uint32_t w = t[(k + j) % 3];
				const EK::Vector_3 d = epoint(m, w) - p0;
				const EFT dx2 = d.x() * d.x(), len2 = d.squared_length();
				if (!have || dx2 * best_len2 < best_dx2 * len2) {
					have = true;
					w0 = w;
					best_dx2 = dx2;
					best_len2 = len2;
				}
			}
		}
	}
	/* Triangle at edge v0-w0 whose normal has the largest |x| part. */
	have = false;
	EFT best_nx2, best_n2;
	for (size_t i = 0; i < n; i++) {
		const auto &t = m.tris[list[i]];
		const bool has_v = t[0] == v0 || t[1] == v0 || t[2] == v0;
		const bool has_w = t[0] == w0 || t[1] == w0 || t[2] == w0;
		if (!has_v || !has_w)
			continue;
		const EK::Vector_3 nrm =
		    CGAL::normal(epoint(m, t[0]), epoint(m, t[1]), epoint(m, t[2]));
		const EFT nx2 = nrm.x() * nrm.x(), n2 = nrm.squared_length();
		if (!have || nx2 * best_n2 > best_nx2 * n2) {
			have = true;
			seed = list[i];
			flip = CGAL::sign(nrm.x()) == CGAL::NEGATIVE;
			best_nx2 = nx2;
			best_n2 = n2;
		}
	}
}

/* Directions for parity rays: skewed so axis-aligned models rarely graze. */
EK::Vector_3 ray_direction(int k)
{
	static const int dirs[][3] = {{1000, 271, 137},	  {-311, 1000, 473}, {213, -389, 1000},
				      {-1000, -157, 611}, {577, 1000, -293}, {-431, 619, -1000}};
	const int nd = static_cast<int>(sizeof(dirs) / sizeof(dirs[0]));
	if (k < nd)
		return EK::Vector_3(dirs[k][0], dirs[k][1], dirs[k][2]);
	/* Past the table: a deterministic spread of other directions. */
	unsigned h = 2654435761u * static_cast<unsigned>(k + 1);
	int x = static_cast<int>(h % 2001) - 1000, y = static_cast<int>((h / 2001) % 2001) - 1000;
	return EK::Vector_3(x, y, 997 - (k % 7) * 311);
}

/*
 * Whether a ray from p in direction d might meet the box lo..hi, in
 * doubles with a margin: a false "maybe" only costs an exact test.
 */
bool ray_may_hit(const double p[3], const double d[3], const double lo[3], const double hi[3])
{
	double t0 = 0, t1 = HUGE_VAL;
	for (int k = 0; k < 3; k++) {
		const double margin = 1e-9 * (1 + std::fabs(lo[k]) + std::fabs(hi[k]));
		const double l = lo[k] - margin, h = hi[k] + margin;
		if (d[k] == 0) {
			if (p[k] < l - 1e-9 || p[k] > h + 1e-9)
				return false;
			continue;
		}
		double a = (l - p[k]) / d[k], b = (h - p[k]) / d[k];
		if (a > b)
			std::swap(a, b);
		t0 = std::max(t0, a - 1e-9);
		t1 = std::min(t1, b + 1e-9);
		if (t0 > t1)
			return false;
	}
	return true;
}

/*
 * Exact ray parity of point p against the closed triangles listed; a ray
 * through an edge, a vertex or in a triangle's plane is re-cast.
 */
bool point_inside(const exact_mesh &m, const uint32_t *closed, size_t n, const EPoint &p)
{
	const double pd[3] = {CGAL::to_double(p.x()), CGAL::to_double(p.y()),
			      CGAL::to_double(p.z())};
	for (int attempt = 0; attempt < 64; attempt++) {
		const EK::Vector_3 dir = ray_direction(attempt);
		const double dd[3] = {CGAL::to_double(dir.x()), CGAL::to_double(dir.y()),
				      CGAL::to_double(dir.z())};
		const EK::Ray_3 ray(p, dir);
		size_t crossings = 0;
		bool graze = false;
		for (size_t i = 0; i < n && !graze; i++) {
			const auto &t = m.tris[closed[i]];
			double lo[3], hi[3];
			for (int k = 0; k < 3; k++) {
				lo[k] = std::min(std::min(m.approx[t[0]][k], m.approx[t[1]][k]),
						 m.approx[t[2]][k]);
				hi[k] = std::max(std::max(m.approx[t[0]][k], m.approx[t[1]][k]),
						 m.approx[t[2]][k]);
			}
			if (!ray_may_hit(pd, dd, lo, hi))
				continue;
			const EPoint a = epoint(m, t[0]), b = epoint(m, t[1]), c = epoint(m, t[2]);
			const EK::Triangle_3 tri(a, b, c);
			if (!CGAL::do_intersect(ray, tri))
				continue;
			auto r = CGAL::intersection(ray, tri);
			const EPoint *x = r ? boost::get<EPoint>(&*r) : nullptr;
			if (!x) {
				graze = true; /* the ray runs in the triangle's plane */
				break;
			}
			if (*x == p)
				throw std::logic_error("probe point lies on the surface");
			if (CGAL::collinear(a, b, *x) || CGAL::collinear(b, c, *x) ||
			    CGAL::collinear(c, a, *x))
				graze = true;
			else
				crossings++;
		}
		if (!graze)
			return crossings % 2 == 1;
	}
	throw std::runtime_error("every parity ray grazed an edge");
}

/* See exact_segment_hidden. */
bool segment_hidden(const exact_mesh &m, const uint32_t *surface, size_t ns,
		    const uint32_t *closed, size_t nc, const EPoint &p, const EPoint &q)
{
	const EK::Segment_3 s(p, q);
	const EK::Vector_3 d = q - p;
	const EFT len2 = d.squared_length();
	std::vector<EFT> cutsat = {EFT(0), EFT(1)};
	auto param = [&](const EPoint &x) { return ((x - p) * d) / len2; };

	/* Where the segment meets the surface splits it into pieces that are
	 * each wholly on the surface or wholly off it. */
	for (size_t i = 0; i < ns; i++) {
		const auto &t = m.tris[surface[i]];
		const EK::Triangle_3 tri(epoint(m, t[0]), epoint(m, t[1]), epoint(m, t[2]));
		if (!CGAL::do_intersect(s, tri))
			continue;
		auto r = CGAL::intersection(s, tri);
		if (!r)
			continue;
		if (const EPoint *x = boost::get<EPoint>(&*r)) {
			cutsat.push_back(param(*x));
		} else if (const EK::Segment_3 *g = boost::get<EK::Segment_3>(&*r)) {
			cutsat.push_back(param(g->source()));
			cutsat.push_back(param(g->target()));
		}
	}
	std::sort(cutsat.begin(), cutsat.end());
	cutsat.erase(std::unique(cutsat.begin(), cutsat.end()), cutsat.end());
	for (size_t k = 0; k + 1 < cutsat.size(); k++) {
		const EPoint mid = p + d * ((cutsat[k] + cutsat[k + 1]) / 2);
		bool on_surface = false;
		for (size_t i = 0; i < ns && !on_surface; i++) {
			const auto &t = m.tris[surface[i]];
			const EK::Triangle_3 tri(epoint(m, t[0]), epoint(m, t[1]),
						 epoint(m, t[2]));
			on_surface = tri.has_on(mid);
		}
		if (on_surface)
			continue;
		if (nc == 0 || !point_inside(m, closed, nc, mid))
			return false;
	}
	return true;
}

using emesh::fail;

bool finite3(const double p[3])
{
	return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
}

} /* namespace */

extern "C" {

int exact_mesh_new(const double (*verts)[3], size_t nverts, const uint32_t (*tris)[3],
		   size_t ntris, const uint32_t *origin, struct exact_mesh **out,
		   struct st_error *err)
{
	if (!out)
		return st_error_set(err, ST_ERR_ARG, "exact: output pointer is NULL");
	*out = nullptr;
	if ((nverts && !verts) || (ntris && !tris))
		return st_error_set(err, ST_ERR_ARG, "exact: NULL array with a nonzero count");
	if (nverts > MESH_LIMIT || ntris > MESH_LIMIT)
		return st_error_set(err, ST_ERR_RANGE, "exact: %zu vertices / %zu triangles are "
				    "more than an exact mesh indexes", nverts, ntris);
	for (size_t v = 0; v < nverts; v++)
		if (!finite3(verts[v]))
			return st_error_set(err, ST_ERR_ARG, "exact: vertex %zu is not finite", v);
	for (size_t t = 0; t < ntris; t++)
		for (int k = 0; k < 3; k++)
			if (tris[t][k] >= nverts)
				return st_error_set(err, ST_ERR_ARG,
						    "exact: triangle %zu uses vertex %lu of %zu", t,
						    (unsigned long)tris[t][k], nverts);
	try {
		exact_mesh *m = new exact_mesh;
		m->approx.resize(nverts);
		for (size_t v = 0; v < nverts; v++)
			m->approx[v] = {verts[v][0], verts[v][1], verts[v][2]};
		m->slot.assign(nverts, -1);
		m->tris.reserve(ntris);
		m->origin.reserve(ntris);
		m->plane.reserve(ntris);
		for (size_t t = 0; t < ntris; t++)
			m->add_triangle({tris[t][0], tris[t][1], tris[t][2]},
					origin ? origin[t] : static_cast<uint32_t>(t));
		*out = m;
		return ST_OK;
	} catch (...) {
		return fail(err, "building an exact mesh");
	}
}

void exact_mesh_free(struct exact_mesh *m)
{
	delete m;
}

int exact_mesh_append(struct exact_mesh *m, const double (*verts)[3], size_t nverts,
		      const uint32_t (*tris)[3], size_t ntris, uint32_t origin, size_t *skipped,
		      struct st_error *err)
{
	return exact_mesh_append_ref(m, nullptr, nullptr, verts, nverts, tris, ntris, origin,
				     skipped, err);
}

int exact_mesh_append_ref(struct exact_mesh *m, const struct exact_mesh *src, const uint32_t *ref,
			  const double (*verts)[3], size_t nverts, const uint32_t (*tris)[3],
			  size_t ntris, uint32_t origin, size_t *skipped, struct st_error *err)
{
	if (skipped)
		*skipped = 0;
	if (!m || (nverts && !verts) || (ntris && !tris) || (ref && !src))
		return st_error_set(err, ST_ERR_ARG, "exact: NULL mesh or array");
	if (ref)
		for (size_t v = 0; v < nverts; v++)
			if (ref[v] != UINT32_MAX && ref[v] >= src->approx.size())
				return st_error_set(err, ST_ERR_ARG,
						    "exact: appended vertex %zu refers to vertex "
						    "%lu of %zu", v, (unsigned long)ref[v],
						    src->approx.size());
	for (size_t v = 0; v < nverts; v++)
		if (!finite3(verts[v]))
			return st_error_set(err, ST_ERR_ARG, "exact: appended vertex %zu is not "
					    "finite", v);
	for (size_t t = 0; t < ntris; t++)
		for (int k = 0; k < 3; k++)
			if (tris[t][k] >= nverts)
				return st_error_set(err, ST_ERR_ARG,
						    "exact: appended triangle %zu uses vertex %lu "
						    "of %zu", t, (unsigned long)tris[t][k], nverts);
	try {
		std::unordered_map<dkey, uint32_t, dkey_hash> weld;
		for (size_t v = 0; v < m->approx.size(); v++)
			if (m->slot[v] < 0)
				weld.emplace(dkey{{m->approx[v][0], m->approx[v][1],
						   m->approx[v][2]}},
					     static_cast<uint32_t>(v));
		/* Rational vertices by their approximation, compared exactly. */
		std::unordered_multimap<dkey, uint32_t, dkey_hash> rational;
		if (ref)
			for (size_t v = 0; v < m->approx.size(); v++)
				if (m->slot[v] >= 0)
					rational.emplace(dkey{{m->approx[v][0], m->approx[v][1],
							       m->approx[v][2]}},
							 static_cast<uint32_t>(v));
		std::vector<uint32_t> map(nverts);
		for (size_t v = 0; v < nverts; v++) {
			if (ref && ref[v] != UINT32_MAX && src->slot[ref[v]] >= 0) {
				const std::array<double, 3> &a = src->approx[ref[v]];
				const EPoint &p = src->ex[static_cast<size_t>(src->slot[ref[v]])];
				const dkey k = {{a[0], a[1], a[2]}};
				uint32_t found = UINT32_MAX;
				for (auto r = rational.equal_range(k); r.first != r.second; ++r.first)
					if (epoint(*m, r.first->second) == p) {
						found = r.first->second;
						break;
					}
				if (found == UINT32_MAX) {
					if (m->approx.size() >= MESH_LIMIT)
						throw std::length_error("too many vertices");
					m->approx.push_back(a);
					m->slot.push_back(static_cast<int32_t>(m->ex.size()));
					m->ex.push_back(p);
					found = static_cast<uint32_t>(m->approx.size() - 1);
					rational.emplace(k, found);
				}
				map[v] = found;
				continue;
			}
			const double *d = ref && ref[v] != UINT32_MAX ? src->approx[ref[v]].data()
								       : verts[v];
			dkey k = {{d[0], d[1], d[2]}};
			auto it = weld.find(k);
			if (it == weld.end()) {
				if (m->approx.size() >= MESH_LIMIT)
					throw std::length_error("too many vertices");
				m->approx.push_back({d[0], d[1], d[2]});
				m->slot.push_back(-1);
				it = weld.emplace(k, static_cast<uint32_t>(m->approx.size() - 1))
					 .first;
			}
			map[v] = it->second;
		}
		for (size_t t = 0; t < ntris; t++) {
			std::array<uint32_t, 3> w = {map[tris[t][0]], map[tris[t][1]],
						     map[tris[t][2]]};
			if (w[0] == w[1] || w[1] == w[2] || w[0] == w[2] ||
			    CGAL::collinear(epoint(*m, w[0]), epoint(*m, w[1]), epoint(*m, w[2]))) {
				if (skipped)
					++*skipped;
				continue;
			}
			m->add_triangle(w, origin);
		}
		return ST_OK;
	} catch (...) {
		return fail(err, "appending triangles");
	}
}

int exact_mesh_select(const struct exact_mesh *m, const uint8_t *keep, const uint8_t *flip,
		      struct exact_mesh **out, struct st_error *err)
{
	if (!out)
		return st_error_set(err, ST_ERR_ARG, "exact: output pointer is NULL");
	*out = nullptr;
	if (!m || (!keep && !m->tris.empty()))
		return st_error_set(err, ST_ERR_ARG, "exact: NULL mesh or keep flags");
	try {
		exact_mesh *r = new exact_mesh;
		std::vector<uint32_t> map(m->approx.size(), UINT32_MAX);
		for (size_t t = 0; t < m->tris.size(); t++) {
			if (!keep[t])
				continue;
			std::array<uint32_t, 3> w;
			for (int k = 0; k < 3; k++) {
				const uint32_t v = m->tris[t][k];
				if (map[v] == UINT32_MAX) {
					map[v] = static_cast<uint32_t>(r->approx.size());
					r->approx.push_back(m->approx[v]);
					if (m->slot[v] < 0) {
						r->slot.push_back(-1);
					} else {
						r->slot.push_back(
						    static_cast<int32_t>(r->ex.size()));
						r->ex.push_back(
						    m->ex[static_cast<size_t>(m->slot[v])]);
					}
				}
				w[k] = map[v];
			}
			if (flip && flip[t])
				std::swap(w[1], w[2]);
			r->tris.push_back(w);
			r->origin.push_back(m->origin[t]);
			r->plane.push_back(m->plane[t]);
		}
		r->next_plane = m->next_plane;
		*out = r;
		return ST_OK;
	} catch (...) {
		return fail(err, "selecting triangles");
	}
}

size_t exact_mesh_nverts(const struct exact_mesh *m)
{
	return m ? m->approx.size() : 0;
}

size_t exact_mesh_ntris(const struct exact_mesh *m)
{
	return m ? m->tris.size() : 0;
}

const double (*exact_mesh_verts(const struct exact_mesh *m))[3]
{
	static_assert(sizeof(std::array<double, 3>) == 3 * sizeof(double), "packed array");
	return m && !m->approx.empty()
		   ? reinterpret_cast<const double(*)[3]>(m->approx.data()->data())
		   : nullptr;
}

const uint32_t (*exact_mesh_tris(const struct exact_mesh *m))[3]
{
	static_assert(sizeof(std::array<uint32_t, 3>) == 3 * sizeof(uint32_t), "packed array");
	return m && !m->tris.empty()
		   ? reinterpret_cast<const uint32_t(*)[3]>(m->tris.data()->data())
		   : nullptr;
}

const uint32_t *exact_mesh_origin(const struct exact_mesh *m)
{
	return m && !m->origin.empty() ? m->origin.data() : nullptr;
}

const uint32_t *exact_mesh_parents(const struct exact_mesh *m, const uint8_t **whole)
{
	if (!m || m->tris.empty() || m->parent.size() != m->tris.size())
		return nullptr;
	if (whole)
		*whole = m->parent_whole.data();
	return m->parent.data();
}

bool exact_mesh_same_plane(const struct exact_mesh *m, uint32_t t, uint32_t u)
{
	return m && t < m->plane.size() && u < m->plane.size() && m->plane[t] == m->plane[u];
}

bool exact_mesh_vertex_is_double(const struct exact_mesh *m, uint32_t v)
{
	return m && v < m->slot.size() && m->slot[v] < 0;
}

int exact_mesh_refine(struct exact_mesh *m, int threads, struct exact_refine_stats *stats,
		      struct st_error *err)
{
	exact_refine_stats st = exact_refine_stats();

	if (stats)
		*stats = st;
	if (!m || threads < 0)
		return st_error_set(err, ST_ERR_ARG, "exact: NULL mesh or negative thread count");
	try {
		/* Work on a copy so a failure leaves the mesh as it was. */
		exact_mesh work = *m;
		refine(work, threads, st);
		*m = std::move(work);
		if (stats)
			*stats = st;
		return ST_OK;
	} catch (...) {
		return fail(err, "resolving self-intersections");
	}
}

int exact_mesh_orient3d(const struct exact_mesh *m, uint32_t a, uint32_t b, uint32_t c,
			uint32_t d)
{
	try {
		CGAL::Orientation o;
		if (m->slot[a] < 0 && m->slot[b] < 0 && m->slot[c] < 0 && m->slot[d] < 0)
			o = CGAL::orientation(ipoint(*m, a), ipoint(*m, b), ipoint(*m, c),
					      ipoint(*m, d));
		else
			o = CGAL::orientation(epoint(*m, a), epoint(*m, b), epoint(*m, c),
					      epoint(*m, d));
		return o == CGAL::POSITIVE ? 1 : o == CGAL::NEGATIVE ? -1 : 0;
	} catch (...) {
		return 0;
	}
}

int exact_mesh_seed(const struct exact_mesh *m, const uint32_t *tris, size_t n, uint32_t *seed,
		    bool *flip, struct st_error *err)
{
	if (!m || !tris || n == 0 || !seed || !flip)
		return st_error_set(err, ST_ERR_ARG, "exact: seed needs a non-empty triangle list");
	for (size_t i = 0; i < n; i++)
		if (tris[i] >= m->tris.size())
			return st_error_set(err, ST_ERR_ARG, "exact: seed candidate %lu out of range",
					    (unsigned long)tris[i]);
	try {
		*seed = tris[0];
		*flip = false;
		find_seed(*m, tris, n, *seed, *flip);
		return ST_OK;
	} catch (...) {
		return fail(err, "choosing the seed triangle");
	}
}

int exact_mesh_inside(const struct exact_mesh *m, const uint32_t *closed, size_t n,
		      uint32_t probe, bool *inside, struct st_error *err)
{
	if (!inside)
		return st_error_set(err, ST_ERR_ARG, "exact: answer pointer is NULL");
	*inside = false;
	if (!m || (n && !closed) || probe >= m->tris.size())
		return st_error_set(err, ST_ERR_ARG, "exact: bad containment query");
	try {
		const auto &t = m->tris[probe];
		const EPoint c = CGAL::centroid(epoint(*m, t[0]), epoint(*m, t[1]),
						epoint(*m, t[2]));
		*inside = point_inside(*m, closed, n, c);
		return ST_OK;
	} catch (...) {
		return fail(err, "testing containment");
	}
}

int exact_segment_hidden(const struct exact_mesh *m, const uint32_t *surface, size_t n_surface,
			 const uint32_t *closed, size_t n_closed, const double p[3],
			 const double q[3], bool *hidden, struct st_error *err)
{
	if (!hidden)
		return st_error_set(err, ST_ERR_ARG, "exact: answer pointer is NULL");
	*hidden = false;
	if (!m || (n_surface && !surface) || (n_closed && !closed) || !p || !q || !finite3(p) ||
	    !finite3(q))
		return st_error_set(err, ST_ERR_ARG, "exact: bad wire query");
	try {
		const EPoint a(p[0], p[1], p[2]), b(q[0], q[1], q[2]);
		if (a == b) {
			*hidden = true; /* a point draws nothing */
			return ST_OK;
		}
		*hidden = segment_hidden(*m, surface, n_surface, closed, n_closed, a, b);
		return ST_OK;
	} catch (...) {
		return fail(err, "testing a wire");
	}
}

} /* extern "C" */
