/*
 * retri.hpp - private to repair/exact: re-triangulating a triangle along
 * the cuts other triangles make in it (seed 000 §4.1), for the refinement
 * in emesh.cpp.
 *
 * The triangle is triangulated in the coordinate plane it projects onto
 * without degenerating, with the cuts as constraints (constrained Delaunay,
 * exact intersections).  The projected points are built once, as Epeck
 * 2D points, and each vertex remembers the 3D point it came from: CGAL's
 * projection traits would build a new lazy 2D point for every predicate
 * call, which cost more than the predicates.
 */
#ifndef STRATUM_REPAIR_EXACT_RETRI_HPP
#define STRATUM_REPAIR_EXACT_RETRI_HPP

#define CGAL_NO_CDT_2_WARNING 1

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>
#include <CGAL/intersections.h>

#include "emesh.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <utility>
#include <vector>

namespace retri
{

/* What cuts one triangle: points and segments in its plane, and for each
 * point and segment end the edge of the triangle it is known to lie
 * inside (NO_EDGE when not known). */
struct cuts {
	std::vector<EPoint> points;
	std::vector<std::pair<EPoint, EPoint>> segments;
	std::vector<int8_t> point_edge;
	std::vector<std::array<int8_t, 2>> segment_edge;
};

/* Add the intersection of two triangles to c. */
inline void add_intersection(const EK::Triangle_3 &a, const EK::Triangle_3 &b, cuts &c)
{
	auto r = CGAL::intersection(a, b);
	if (!r)
		return;

	if (const EPoint *p = boost::get<EPoint>(&*r)) {
		c.points.push_back(*p);
	} else if (const EK::Segment_3 *s = boost::get<EK::Segment_3>(&*r)) {
		c.segments.emplace_back(s->source(), s->target());
	} else if (const EK::Triangle_3 *t = boost::get<EK::Triangle_3>(&*r)) {
		for (int k = 0; k < 3; k++)
			c.segments.emplace_back(t->vertex(k), t->vertex(k + 1));
	} else if (const std::vector<EPoint> *poly = boost::get<std::vector<EPoint>>(&*r)) {
		for (size_t k = 0; k < poly->size(); k++)
			c.segments.emplace_back((*poly)[k], (*poly)[(k + 1) % poly->size()]);
	}
	/* Nothing is known of where these points lie. */
	c.point_edge.resize(c.points.size(), NO_EDGE);
	c.segment_edge.resize(c.segments.size(), {{NO_EDGE, NO_EDGE}});
}

/* Which 3D point a triangulation vertex is; NONE for a point the
 * triangulation made where two constraints cross. */
struct source {
	static const uint32_t NONE = UINT32_MAX;
	uint32_t index = NONE;
};

typedef CGAL::Triangulation_vertex_base_with_info_2<source, EK> Vb;
typedef CGAL::Constrained_triangulation_face_base_2<EK> Fb;
typedef CGAL::Triangulation_data_structure_2<Vb, Fb> Tds;
typedef CGAL::Constrained_Delaunay_triangulation_2<EK, Tds, CGAL::Exact_intersections_tag> CDT;

/*
 * Triangulate triangle (p0, p1, p2) with the cuts c as constraints and
 * append the pieces as point triples with the triangle's own orientation.
 */
inline void split(const EPoint &p0, const EPoint &p1, const EPoint &p2, const cuts &c,
		  std::vector<std::array<EPoint, 3>> &pieces)
{
	const EK::Vector_3 nrm = CGAL::normal(p0, p1, p2);
	const EFT n[3] = {nrm.x(), nrm.y(), nrm.z()};
	/* Drop the axis where the normal is largest; its exact sign is checked
	 * so the projection never degenerates. */
	const double ax = std::fabs(CGAL::to_double(n[0])), ay = std::fabs(CGAL::to_double(n[1])),
		     az = std::fabs(CGAL::to_double(n[2]));
	int k = az >= ax && az >= ay ? 2 : (ay >= ax ? 1 : 0);
	if (CGAL::sign(n[k]) == CGAL::ZERO)
		for (k = 0; k < 3 && CGAL::sign(n[k]) == CGAL::ZERO; k++)
			;
	if (k == 3)
		throw std::logic_error("degenerate triangle reached the refinement");
	/* Kept axes in the order CGAL's projection traits use (xy, xz, yz). */
	const int i = k == 0 ? 1 : 0, j = k == 2 ? 1 : 2;

	std::vector<EPoint> pts;
	CDT cdt;
	auto record = [&](const CDT::Vertex_handle v, const EPoint &p) {
		if (v->info().index == source::NONE) {
			v->info().index = static_cast<uint32_t>(pts.size());
			pts.push_back(p);
		}
		return v;
	};
	auto insert = [&](const EPoint &p) {
		return record(cdt.insert(EK::Point_2(p[i], p[j])), p);
	};
	/*
	 * Every point in insertion order: the corners, the points, then both
	 * ends of each segment.  The cuts through a triangle form closed
	 * polylines, so nearly every end is given twice (by two pairs, as two
	 * handles of one exact point).  Inserting a point again made the
	 * triangulation's walk prove it equal to a vertex with exact
	 * orientations, the costliest part of the split; equal points are
	 * found here by sorting instead (exact comparisons of known values)
	 * and each is inserted once.
	 */
	std::vector<const EPoint *> all;
	std::vector<int8_t> on;
	all.reserve(3 + c.points.size() + 2 * c.segments.size());
	all.push_back(&p0);
	all.push_back(&p1);
	all.push_back(&p2);
	on.assign(3, NO_EDGE);
	for (size_t k = 0; k < c.points.size(); k++) {
		all.push_back(&c.points[k]);
		on.push_back(c.point_edge[k]);
	}
	for (size_t k = 0; k < c.segments.size(); k++) {
		all.push_back(&c.segments[k].first);
		all.push_back(&c.segments[k].second);
		on.push_back(c.segment_edge[k][0]);
		on.push_back(c.segment_edge[k][1]);
	}
	std::vector<uint32_t> order(all.size()), first(all.size());
	for (uint32_t a = 0; a < order.size(); a++)
		order[a] = first[a] = a;
	std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
		return CGAL::compare_xyz(*all[a], *all[b]) == CGAL::SMALLER;
	});
	for (size_t r = 1; r < order.size(); r++)
		if (CGAL::compare_xyz(*all[order[r - 1]], *all[order[r]]) == CGAL::EQUAL)
			first[order[r]] = first[order[r - 1]]; /* stable: smallest first */
	/* A point lies inside an edge when any of its copies is known to. */
	for (size_t a = 3; a < all.size(); a++)
		if (on[a] != NO_EDGE && first[a] >= 3)
			on[first[a]] = on[a];
	std::vector<CDT::Vertex_handle> vh(all.size());
	auto place = [&](size_t a) { /* each point once, at its first copy */
		if (vh[first[a]] == CDT::Vertex_handle())
			vh[first[a]] = insert(*all[first[a]]);
		return vh[a] = vh[first[a]];
	};
	for (size_t a = 0; a < 3; a++)
		place(a);
	/*
	 * Points known to lie inside an edge go onto it in their order along
	 * it, without being located: a walk to them ends in orientation tests
	 * that are exactly zero (they are collinear with the edge's corners),
	 * which the interval filter cannot decide, and falls back to
	 * rationals.  The edges of the triangle are its triangulation's hull,
	 * so no flip removes them.  The triangulation is the same whatever the
	 * order of insertion (the constrained Delaunay one).
	 */
	for (int e = 0; e < 3; e++) {
		std::vector<size_t> along;
		for (size_t a = 3; a < all.size(); a++)
			if (first[a] == a && on[a] == e)
				along.push_back(a);
		if (along.empty())
			continue;
		std::sort(along.begin(), along.end(), [&](size_t a, size_t b) {
			return CGAL::compare_xyz(*all[a], *all[b]) == CGAL::SMALLER;
		});
		if (CGAL::compare_xyz(*all[e], *all[(e + 1) % 3]) == CGAL::LARGER)
			std::reverse(along.begin(), along.end());
		CDT::Vertex_handle prev = vh[e];
		const CDT::Vertex_handle end = vh[(e + 1) % 3];
		for (size_t a : along) {
			CDT::Face_handle f;
			int li;
			const EPoint &p = *all[a];
			vh[a] = cdt.is_edge(prev, end, f, li)
				    ? record(cdt.insert(EK::Point_2(p[i], p[j]), CDT::EDGE, f, li), p)
				    : insert(p);
			prev = vh[a];
		}
	}
	const size_t nfirst = 3 + c.points.size();
	for (size_t a = 3; a < nfirst; a++)
		place(a);
	const CDT::Vertex_handle v0 = vh[0], v1 = vh[1], v2 = vh[2];
	for (size_t a = nfirst; a < all.size(); a += 2) {
		const CDT::Vertex_handle from = place(a), to = place(a + 1);
		if (from != to)
			cdt.insert_constraint(from, to);
	}
	/* The pieces are counter-clockwise in the projection; so is the
	 * triangle, or else every piece is reversed. */
	const bool reverse =
	    CGAL::orientation(v0->point(), v1->point(), v2->point()) == CGAL::CLOCKWISE;
	/*
	 * A point where constraints cross, back on the triangle's plane,
	 * computed in rationals: its exact value is always needed (the
	 * welding keys it by that), and as lazy numbers each of the lift's
	 * operations was a node evaluated exactly on its own.
	 */
	typedef EK::Exact_kernel XK;
	const XK::Point_3 *a = nullptr; /* p0 and the normal, once needed */
	const XK::Vector_3 *nx = nullptr;
	auto lift = [&](const EK::Point_2 &q) {
		if (!a) {
			a = &emesh::exact_of(p0);
			nx = &emesh::exact_of(nrm);
		}
		const XK::Point_2 &e = emesh::exact_of(q);
		XK::FT x[3];
		x[i] = e.x();
		x[j] = e.y();
		x[k] = (*a)[k] - ((*nx)[i] * (x[i] - (*a)[i]) + (*nx)[j] * (x[j] - (*a)[j])) / (*nx)[k];
		return EPoint(XK::Point_3(x[0], x[1], x[2]));
	};
	for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f) {
		std::array<EPoint, 3> t;
		for (int e = 0; e < 3; e++) {
			const CDT::Vertex_handle v = f->vertex(e);
			if (v->info().index == source::NONE) {
				v->info().index = static_cast<uint32_t>(pts.size());
				pts.push_back(lift(v->point()));
			}
			t[e] = pts[v->info().index];
		}
		if (reverse)
			std::swap(t[1], t[2]);
		pieces.push_back(t);
	}
}

} /* namespace retri */

#endif /* STRATUM_REPAIR_EXACT_RETRI_HPP */
