/*
 * equery.cpp - the exact queries the repair makes of an exact mesh
 * (exact.h): orientation of four vertices, the seed triangle of the outer
 * hull, containment by ray parity, and whether a wire is hidden on or
 * inside the surface.  Rational vertices are decided with Epeck, double-
 * only ones with Epick's filtered predicates where that is enough.
 */
#include "exact.h"

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/intersections.h>

#include "emesh.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <exception>
#include <memory>
#include <stdexcept>
#include <utility>
#include <vector>

namespace
{

using emesh::epoint;
using emesh::fail;
using emesh::finite3;
using emesh::ipoint;

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

/* What a ray does at one triangle. */
enum ray_hit { RAY_MISS, RAY_CROSS, RAY_GRAZE };

/*
 * Ray from p in direction dir against triangle t of m, exactly: a crossing
 * of its interior, a miss, or a graze (through an edge or a vertex, or in
 * the triangle's plane), after which the ray must be cast again.
 */
ray_hit ray_meets(const exact_mesh &m, const std::array<uint32_t, 3> &t, const EK::Ray_3 &ray,
		  const EPoint &p)
{
	const EPoint a = epoint(m, t[0]), b = epoint(m, t[1]), c = epoint(m, t[2]);
	const EK::Triangle_3 tri(a, b, c);
	if (!CGAL::do_intersect(ray, tri))
		return RAY_MISS;
	auto r = CGAL::intersection(ray, tri);
	const EPoint *x = r ? boost::get<EPoint>(&*r) : nullptr;
	if (!x)
		return RAY_GRAZE; /* the ray runs in the triangle's plane */
	if (*x == p)
		throw std::logic_error("probe point lies on the surface");
	if (CGAL::collinear(a, b, *x) || CGAL::collinear(b, c, *x) || CGAL::collinear(c, a, *x))
		return RAY_GRAZE;
	return RAY_CROSS;
}

/* The double box of triangle t of m. */
void tri_bounds(const exact_mesh &m, const std::array<uint32_t, 3> &t, double lo[3], double hi[3])
{
	for (int k = 0; k < 3; k++) {
		lo[k] = std::min(std::min(m.approx[t[0]][k], m.approx[t[1]][k]), m.approx[t[2]][k]);
		hi[k] = std::max(std::max(m.approx[t[0]][k], m.approx[t[1]][k]), m.approx[t[2]][k]);
	}
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
			tri_bounds(m, t, lo, hi);
			if (!ray_may_hit(pd, dd, lo, hi))
				continue;
			const ray_hit h = ray_meets(m, t, ray, p);
			graze = h == RAY_GRAZE;
			crossings += h == RAY_CROSS;
		}
		if (!graze)
			return crossings % 2 == 1;
	}
	throw std::runtime_error("every parity ray grazed an edge");
}

} /* namespace */

/*
 * The triangles of one closed surface filed by where they lie seen along
 * the first parity ray's direction: a grid over the plane across that
 * direction, each cell listing the triangles whose shadow (a box, widened
 * by a margin far above double rounding) covers it.  A ray from p can
 * only meet triangles listed in p's cell, so a surface asked about many
 * probes (a soup's repair leaves thousands of parts in one box) is
 * scanned once, not once per probe.
 */
struct exact_ray_index {
	std::vector<uint32_t> closed;	       /* the surface, as given */
	double u[3], v[3], d[3];	       /* across the ray; along it */
	double lo_u, lo_v, cell_u, cell_v;     /* the grid */
	uint32_t cols, rows;
	double margin;
	std::vector<std::array<double, 5>> shadow; /* per listed triangle: u, v box, farthest d */
	std::vector<uint32_t> first, item;	   /* cells, as rows of item */
};

namespace
{

double dot3(const double a[3], const double b[3])
{
	return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* The cell of (pu, pv), clamped to the grid. */
size_t grid_cell(const exact_ray_index &ix, double pu, double pv, uint32_t *col, uint32_t *row)
{
	double fu = std::floor((pu - ix.lo_u) / ix.cell_u), fv = std::floor((pv - ix.lo_v) / ix.cell_v);
	fu = std::min(std::max(fu, 0.0), double(ix.cols - 1));
	fv = std::min(std::max(fv, 0.0), double(ix.rows - 1));
	*col = static_cast<uint32_t>(fu);
	*row = static_cast<uint32_t>(fv);
	return size_t(*row) * ix.cols + *col;
}

void build_ray_index(const exact_mesh &m, exact_ray_index &ix)
{
	const EK::Vector_3 dir = ray_direction(0);
	const double d[3] = {CGAL::to_double(dir.x()), CGAL::to_double(dir.y()),
			     CGAL::to_double(dir.z())};
	const double dl = std::sqrt(dot3(d, d));
	/* u: d crossed with the axis it leans on least; v = d x u. */
	const double ax[3] = {0, 0, 1};
	double u[3] = {d[1] * ax[2] - d[2] * ax[1], d[2] * ax[0] - d[0] * ax[2],
		       d[0] * ax[1] - d[1] * ax[0]};
	const double ul = std::sqrt(dot3(u, u));
	for (int k = 0; k < 3; k++) {
		ix.d[k] = d[k] / dl;
		ix.u[k] = u[k] / ul;
	}
	ix.v[0] = ix.d[1] * ix.u[2] - ix.d[2] * ix.u[1];
	ix.v[1] = ix.d[2] * ix.u[0] - ix.d[0] * ix.u[2];
	ix.v[2] = ix.d[0] * ix.u[1] - ix.d[1] * ix.u[0];

	const size_t n = ix.closed.size();
	double scale = 0;
	ix.shadow.resize(n);
	double lo_u = HUGE_VAL, hi_u = -HUGE_VAL, lo_v = HUGE_VAL, hi_v = -HUGE_VAL;
	for (size_t i = 0; i < n; i++) {
		std::array<double, 5> &sh = ix.shadow[i];
		sh = {HUGE_VAL, -HUGE_VAL, HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
		for (uint32_t c : m.tris[ix.closed[i]]) {
			const double *x = m.approx[c].data();
			const double pu = dot3(x, ix.u), pv = dot3(x, ix.v), pd = dot3(x, ix.d);
			sh[0] = std::min(sh[0], pu);
			sh[1] = std::max(sh[1], pu);
			sh[2] = std::min(sh[2], pv);
			sh[3] = std::max(sh[3], pv);
			sh[4] = std::max(sh[4], pd);
			for (int k = 0; k < 3; k++)
				scale = std::max(scale, std::fabs(x[k]));
		}
	}
	/* Rounding in the dot products is a few ulps of the coordinates;
	 * rational corners are within an ulp of their doubles. */
	ix.margin = 1e-9 * (1 + scale);
	for (auto &sh : ix.shadow) {
		sh[0] -= ix.margin;
		sh[1] += ix.margin;
		sh[2] -= ix.margin;
		sh[3] += ix.margin;
		sh[4] += ix.margin;
		lo_u = std::min(lo_u, sh[0]);
		hi_u = std::max(hi_u, sh[1]);
		lo_v = std::min(lo_v, sh[2]);
		hi_v = std::max(hi_v, sh[3]);
	}
	const uint32_t side =
	    static_cast<uint32_t>(std::max(1.0, std::min(1024.0, std::sqrt(double(n) / 2))));
	ix.cols = ix.rows = side;
	ix.lo_u = lo_u;
	ix.lo_v = lo_v;
	ix.cell_u = std::max((hi_u - lo_u) / side, 1e-300);
	ix.cell_v = std::max((hi_v - lo_v) / side, 1e-300);
	ix.first.assign(size_t(side) * side + 1, 0);
	/* Two passes: count each cell's triangles, then file them. */
	for (int pass = 0; pass < 2; pass++) {
		std::vector<uint32_t> fill;
		if (pass == 1) {
			for (size_t c = 1; c < ix.first.size(); c++)
				ix.first[c] += ix.first[c - 1];
			ix.item.resize(ix.first.back());
			fill.assign(ix.first.begin(), ix.first.end() - 1);
		}
		for (size_t i = 0; i < n; i++) {
			const std::array<double, 5> &sh = ix.shadow[i];
			uint32_t c0, r0, c1, r1;
			grid_cell(ix, sh[0], sh[2], &c0, &r0);
			grid_cell(ix, sh[1], sh[3], &c1, &r1);
			for (uint32_t r = r0; r <= r1; r++)
				for (uint32_t c = c0; c <= c1; c++) {
					const size_t cell = size_t(r) * side + c;
					if (pass == 0)
						ix.first[cell + 1]++;
					else
						ix.item[fill[cell]++] = static_cast<uint32_t>(i);
				}
		}
	}
}

/* point_inside through the index: the first ray, then the full scan if
 * it grazed (so the answer is point_inside's). */
bool point_inside_indexed(const exact_mesh &m, const exact_ray_index &ix, const EPoint &p)
{
	const double pd[3] = {CGAL::to_double(p.x()), CGAL::to_double(p.y()),
			      CGAL::to_double(p.z())};
	const double pu = dot3(pd, ix.u), pv = dot3(pd, ix.v), pdd = dot3(pd, ix.d);
	const EK::Ray_3 ray(p, ray_direction(0));
	uint32_t col, row;
	const size_t cell = grid_cell(ix, pu, pv, &col, &row);
	size_t crossings = 0;
	for (uint32_t k = ix.first[cell]; k < ix.first[cell + 1]; k++) {
		const std::array<double, 5> &sh = ix.shadow[ix.item[k]];
		if (pu < sh[0] || pu > sh[1] || pv < sh[2] || pv > sh[3] || pdd > sh[4])
			continue;
		const ray_hit h = ray_meets(m, m.tris[ix.closed[ix.item[k]]], ray, p);
		if (h == RAY_GRAZE)
			return point_inside(m, ix.closed.data(), ix.closed.size(), p);
		crossings += h == RAY_CROSS;
	}
	return crossings % 2 == 1;
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

/* Whether the centroid of triangle probe of m is inside, by test; the
 * checks and the error both containment queries give. */
template <class Test>
int answer_inside(const exact_mesh *m, bool args_ok, uint32_t probe, bool *inside, st_error *err,
		  Test test)
{
	if (!inside)
		return st_error_set(err, ST_ERR_ARG, "exact: answer pointer is NULL");
	*inside = false;
	if (!m || !args_ok || probe >= m->tris.size())
		return st_error_set(err, ST_ERR_ARG, "exact: bad containment query");
	try {
		const auto &t = m->tris[probe];
		*inside = test(CGAL::centroid(epoint(*m, t[0]), epoint(*m, t[1]), epoint(*m, t[2])));
		return ST_OK;
	} catch (...) {
		return fail(err, "testing containment");
	}
}

} /* namespace */

extern "C" {

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
	return answer_inside(m, !(n && !closed), probe, inside, err, [&](const EPoint &c) {
		return point_inside(*m, closed, n, c);
	});
}

int exact_ray_index_new(const struct exact_mesh *m, const uint32_t *closed, size_t n,
			struct exact_ray_index **out, struct st_error *err)
{
	if (!out)
		return st_error_set(err, ST_ERR_ARG, "exact: index pointer is NULL");
	*out = NULL;
	if (!m || (n && !closed))
		return st_error_set(err, ST_ERR_ARG, "exact: bad containment index");
	for (size_t i = 0; i < n; i++)
		if (closed[i] >= m->tris.size())
			return st_error_set(err, ST_ERR_ARG, "exact: triangle %lu out of range",
					    (unsigned long)closed[i]);
	try {
		std::unique_ptr<exact_ray_index> ix(new exact_ray_index());
		ix->closed.assign(closed, closed + n);
		build_ray_index(*m, *ix);
		*out = ix.release();
		return ST_OK;
	} catch (...) {
		return fail(err, "indexing a surface for containment");
	}
}

void exact_ray_index_free(struct exact_ray_index *ix)
{
	delete ix;
}

int exact_mesh_inside_indexed(const struct exact_mesh *m, const struct exact_ray_index *ix,
			      uint32_t probe, bool *inside, struct st_error *err)
{
	return answer_inside(m, ix != nullptr, probe, inside, err, [&](const EPoint &c) {
		return point_inside_indexed(*m, *ix, c);
	});
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
