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

/* What cuts one triangle: points and segments in its plane. */
struct cuts {
	std::vector<EPoint> points;
	std::vector<std::pair<EPoint, EPoint>> segments;
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
	auto insert = [&](const EPoint &p) {
		const CDT::Vertex_handle v = cdt.insert(EK::Point_2(p[i], p[j]));
		if (v->info().index == source::NONE) {
			v->info().index = static_cast<uint32_t>(pts.size());
			pts.push_back(p);
		}
		return v;
	};
	/*
	 * Every point in insertion order: the corners, the points, then both
	 * ends of each segment.  The cuts through a triangle form closed
	 * polylines, so nearly every end is given twice (by two pairs, as two
	 * handles of one exact point).  Inserting a point again made the
	 * triangulation's walk prove it equal to a vertex with exact
	 * orientations, the costliest part of the split; equal points are
	 * found here by sorting instead (exact comparisons of known values)
	 * and each is inserted once, at its first place in the order, so the
	 * triangulation is the one the full insertion sequence gives.
	 */
	std::vector<const EPoint *> all;
	all.reserve(3 + c.points.size() + 2 * c.segments.size());
	all.push_back(&p0);
	all.push_back(&p1);
	all.push_back(&p2);
	for (const EPoint &p : c.points)
		all.push_back(&p);
	for (const auto &s : c.segments) {
		all.push_back(&s.first);
		all.push_back(&s.second);
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
	std::vector<CDT::Vertex_handle> vh(all.size());
	auto place = [&](size_t a) { /* in order: first[a] <= a is placed */
		vh[a] = first[a] == a ? insert(*all[a]) : vh[first[a]];
		return vh[a];
	};
	const size_t nfirst = 3 + c.points.size();
	for (size_t a = 0; a < nfirst; a++)
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
	/* A point where constraints cross, back on the triangle's plane. */
	auto lift = [&](const EK::Point_2 &q) {
		EFT x[3];
		x[i] = q.x();
		x[j] = q.y();
		x[k] = p0[k] - (n[i] * (q.x() - p0[i]) + n[j] * (q.y() - p0[j])) / n[k];
		return EPoint(x[0], x[1], x[2]);
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
