/*
 * emesh.cpp - exact meshes for the repair (exact.h, "exact mesh"): building,
 * appending and selecting, and exact self-intersection resolution (seed 000
 * §4.1).  The queries the outer-hull growing, containment and wire tests
 * make of a mesh are in equery.cpp.
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
using emesh::epoint;
using emesh::finite3;
using emesh::ipoint;
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

bool tri_is_double(const exact_mesh &m, size_t t)
{
	const std::array<uint32_t, 3> &v = m.tris[t];
	return m.slot[v[0]] < 0 && m.slot[v[1]] < 0 && m.slot[v[2]] < 0;
}

/* Whether rational q is exactly the double d (its nearest). */
bool is_double(const XPoint::FT &q, double d)
{
	/* A double's denominator is a power of two: most cut points fail
	 * this test, which costs no allocation. */
	if (mpz_popcount(mpq_denref(q.backend().data())) != 1)
		return false;
	return q == XPoint::FT(d);
}

/* Add a vertex at exact point p; stored as a double when p is one.  Read
 * from p's exact value: its lazy coordinates would each be a new node. */
uint32_t add_vertex(exact_mesh &m, const EPoint &p)
{
	const XPoint &e = emesh::exact_of(p);
	const double x = CGAL::to_double(e.x()), y = CGAL::to_double(e.y()),
		     z = CGAL::to_double(e.z());

	if (m.approx.size() >= MESH_LIMIT)
		throw std::length_error("too many vertices");
	m.approx.push_back({x, y, z});
	if (is_double(e.x(), x) && is_double(e.y(), y) && is_double(e.z(), z)) {
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

	/* GMP's conversion truncates: like the nearest double it depends on
	 * the value alone (and is that double when the value is one), at a
	 * fraction of the cost of the correctly rounded conversion. */
	static double key_double(const XPoint::FT &q)
	{
		return mpq_get_d(q.backend().data());
	}
	static dkey key(const EPoint &p)
	{
		const XPoint &e = emesh::exact_of(p);
		return dkey{{key_double(e.x()), key_double(e.y()), key_double(e.z())}};
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
	 * value is computed under a once flag), then gathered in pair order.
	 * The cuts carry the edges of the pair's first triangle; the same
	 * points' edges in the second are beside them. */
	struct pair_cut {
		cuts c;
		std::vector<int8_t> point_edge_w;
		std::vector<std::array<int8_t, 2>> segment_edge_w;
	};
	std::vector<pair_cut> meet(pairs.size());
	progress_count meeting(m.progress, "intersecting the crossing pairs", pairs.size());
	boxpairs::for_each_index(pairs.size(), threads, [&](size_t i) {
		meeting.one();
		const uint32_t s = pairs[i].first, t = pairs[i].second;
		const auto &u = m.tris[s], &w = m.tris[t];
		pair_cut &pc = meet[i];
		std::vector<EPoint> seg;
		std::vector<std::array<int8_t, 2>> on;
		auto keep = [&]() {
			if (seg.size() == 1) {
				pc.c.points.push_back(seg[0]);
				pc.c.point_edge.push_back(on[0][0]);
				pc.point_edge_w.push_back(on[0][1]);
			} else if (seg.size() == 2) {
				pc.c.segments.emplace_back(seg[0], seg[1]);
				pc.c.segment_edge.push_back({{on[0][0], on[1][0]}});
				pc.segment_edge_w.push_back({{on[0][1], on[1][1]}});
			}
		};
		if (tri_is_double(m, s) && tri_is_double(m, t)) {
			const IK::Point_3 pu[3] = {ipoint(m, u[0]), ipoint(m, u[1]), ipoint(m, u[2])};
			const IK::Point_3 pw[3] = {ipoint(m, w[0]), ipoint(m, w[1]), ipoint(m, w[2])};
			if (cutpair::intersect(pu, pw, seg, on))
				return keep();
		} else {
			const EPoint eu[3] = {epoint(m, u[0]), epoint(m, u[1]), epoint(m, u[2])};
			const EPoint ew[3] = {epoint(m, w[0]), epoint(m, w[1]), epoint(m, w[2])};
			if (cutpair::intersect(eu, ew, seg, on))
				return keep();
		}
		/* In one plane: the general intersection (an overlap polygon). */
		EK::Triangle_3 a(epoint(m, u[0]), epoint(m, u[1]), epoint(m, u[2]));
		EK::Triangle_3 b(epoint(m, w[0]), epoint(m, w[1]), epoint(m, w[2]));
		add_intersection(a, b, pc.c);
		pc.point_edge_w.resize(pc.c.points.size(), NO_EDGE);
		pc.segment_edge_w.resize(pc.c.segments.size(), {{NO_EDGE, NO_EDGE}});
	});
	std::unordered_map<uint32_t, cuts> cut;
	auto append = [](auto &to, const auto &from) { to.insert(to.end(), from.begin(), from.end()); };
	for (size_t i = 0; i < pairs.size(); i++)
		for (int side = 0; side < 2; side++) {
			const pair_cut &pc = meet[i];
			cuts &c = cut[side ? pairs[i].second : pairs[i].first];
			append(c.points, pc.c.points);
			append(c.segments, pc.c.segments);
			append(c.point_edge, side ? pc.point_edge_w : pc.c.point_edge);
			append(c.segment_edge, side ? pc.segment_edge_w : pc.c.segment_edge);
		}
	std::vector<pair_cut>().swap(meet);

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
	progress_count cutting(m.progress, "cutting the crossing triangles", order.size());
	boxpairs::for_each_index(order.size(), threads, [&](size_t i) {
		split_triangle(m, order[i], cut.find(order[i])->second, pieces_of[i]);
		cutting.one();
	});

	/* Points of affected triangles are unified through this map; it starts
	 * with their own corners so a cut point on a corner reuses it. */
	size_t npieces = 0;
	for (const auto &pc : pieces_of)
		npieces += pc.size();
	/* Sized once: on soups growing these maps rehashed them several
	 * times over. */
	point_index index{m, {}};
	index.map.reserve(3 * order.size() + npieces);
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

	by_handle.reserve(2 * npieces);
	emitted.reserve(npieces);

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
		if (tri_is_double(m, t)) /* kept when a piece of a piece */
			m.split_planes.emplace(m.plane[t], std::array<std::array<double, 3>, 3>{
							       {m.approx[m.tris[t][0]], m.approx[m.tris[t][1]],
								m.approx[m.tris[t][2]]}});
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

using emesh::fail;

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
		r->split_planes = m->split_planes;
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

void exact_mesh_set_progress(struct exact_mesh *m, exact_progress_fn fn, void *ctx)
{
	if (m) {
		m->progress.fn = fn;
		m->progress.ctx = ctx;
	}
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

} /* extern "C" */
