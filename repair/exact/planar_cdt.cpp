/*
 * planar_cdt.cpp - planar_cdt.h: a cluster's boundary loops triangulated
 * by CGAL's constrained Delaunay triangulation seen along the cluster's
 * normal (Projection_traits_3 over Epick: its orientation and in-circle
 * tests are filtered exact predicates on the 3-D points, so nothing is
 * rounded by projecting), and the exact crossing test of new triangles
 * against the mesh (CGAL's box intersection, then pairtest.hpp).
 */
#include "planar_cdt.h"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Projection_traits_3.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>
#include <CGAL/box_intersection_d.h>

#include "pairtest.hpp"

#include <exception>
#include <new>
#include <vector>

namespace
{

typedef CGAL::Epick K;
typedef CGAL::Projection_traits_3<K> PT;

/* in: the face belongs to the region; out: its index in the result. */
struct face_info {
	int in = -1; /* -1 not reached, 0 outside, 1 inside */
	uint32_t out = 0;
};

typedef CGAL::Triangulation_vertex_base_with_info_2<uint32_t, PT> Vb;
typedef CGAL::Triangulation_face_base_with_info_2<face_info, PT> Fbi;
typedef CGAL::Constrained_triangulation_face_base_2<PT, Fbi> Fb;
typedef CGAL::Triangulation_data_structure_2<Vb, Fb> Tds;
/* Loops that cross or touch are refused, never cut: no new points. */
typedef CGAL::Constrained_Delaunay_triangulation_2<PT, Tds, CGAL::No_constraint_intersection_tag>
    CDT;
typedef CDT::Vertex_handle VH;
typedef CDT::Face_handle FH;

K::Point_3 point(const double *p)
{
	return K::Point_3(p[0], p[1], p[2]);
}

/* The face on the left of directed edge a->b (seen from +normal), or null. */
FH left_of(const CDT &cdt, VH a, VH b)
{
	FH f;
	int i;
	if (!cdt.is_edge(a, b, f, i))
		return FH();
	/* Edge i of a counter-clockwise face runs from vertex ccw(i) to cw(i). */
	return f->vertex(CDT::ccw(i)) == a ? f : f->neighbor(i);
}

/*
 * Fill the region from the faces left of every loop edge, never across a
 * loop edge; *why when it reaches infinity or lies on both sides of one.
 */
void mark_region(CDT &cdt, const std::vector<VH> &vh, const struct planar_cdt_cluster *c,
		 const char **why)
{
	std::vector<FH> stack;
	size_t first = 0;
	for (size_t l = 0; l < c->nloops; l++) {
		const size_t end = c->loop_end[l];
		for (size_t i = first; i < end; i++) {
			VH a = vh[i], b = vh[i + 1 < end ? i + 1 : first];
			FH f = left_of(cdt, a, b), g = left_of(cdt, b, a);
			if (f == FH() || g == FH()) {
				*why = "a loop edge is not an edge of the triangulation";
				return;
			}
			stack.push_back(f);
			g->info().in = g->info().in == 1 ? 1 : 0; /* outside unless reached */
		}
		first = end;
	}
	while (!stack.empty()) {
		FH f = stack.back();
		stack.pop_back();
		if (cdt.is_infinite(f)) {
			*why = "the loops do not bound a finite region on their left";
			return;
		}
		if (f->info().in == 1)
			continue;
		if (f->info().in == 0) {
			*why = "the region lies on both sides of a loop edge";
			return;
		}
		f->info().in = 1;
		for (int i = 0; i < 3; i++)
			if (!cdt.is_constrained(CDT::Edge(f, i)))
				stack.push_back(f->neighbor(i));
	}
}

/* The body of planar_cdt_triangulate once arguments are checked. */
void triangulate(const struct planar_cdt_cluster *c, uint32_t (*tris)[3], size_t cap,
		 size_t *ntris, uint32_t *located, const char **why)
{
	const PT traits(K::Vector_3(c->normal[0], c->normal[1], c->normal[2]));
	const auto orient = traits.orientation_2_object();
	*ntris = 0;
	for (size_t t = 0; t < c->nold; t++) {
		const uint32_t *o = c->old_tris[t];
		if (orient(point(c->verts[o[0]]), point(c->verts[o[1]]), point(c->verts[o[2]])) !=
		    CGAL::LEFT_TURN) {
			*why = "a facet does not face along the cluster's normal";
			return;
		}
	}

	CDT cdt(traits);
	const size_t nloop = c->nloops ? c->loop_end[c->nloops - 1] : 0;
	std::vector<VH> vh(nloop);
	for (size_t i = 0; i < nloop; i++) {
		const size_t before = cdt.number_of_vertices();
		vh[i] = cdt.insert(point(c->verts[c->loop[i]]));
		if (cdt.number_of_vertices() != before + 1) {
			*why = "two loop vertices fall on one point seen along the normal";
			return;
		}
		vh[i]->info() = c->loop[i];
	}
	size_t first = 0;
	try {
		for (size_t l = 0; l < c->nloops; l++) {
			const size_t end = c->loop_end[l];
			for (size_t i = first; i < end; i++)
				cdt.insert_constraint(vh[i], vh[i + 1 < end ? i + 1 : first]);
			first = end;
		}
	} catch (const CDT::Intersection_of_constraints_exception &) {
		*why = "two loop edges cross or touch seen along the normal";
		return;
	}
	mark_region(cdt, vh, c, why);
	if (*why)
		return;

	/* A polygon with h holes and n corners has n + 2h - 2 triangles. */
	const size_t expect = nloop + 2 * (c->nloops - 1) - 2;
	size_t n = 0;
	for (FH f : cdt.finite_face_handles())
		if (f->info().in == 1)
			f->info().out = static_cast<uint32_t>(n++);
	if (n != expect || n > cap) {
		*why = "the triangulation is not the one the loops allow";
		return;
	}
	for (FH f : cdt.finite_face_handles())
		if (f->info().in == 1)
			for (int k = 0; k < 3; k++)
				tris[f->info().out][k] = f->vertex(k)->info();

	for (size_t i = 0; i < c->nprobe; i++) {
		CDT::Locate_type lt;
		int li;
		FH f = cdt.locate(point(c->verts[c->probe[i]]), lt, li);
		if (lt == CDT::EDGE && f->info().in != 1)
			f = f->neighbor(li);
		if ((lt != CDT::FACE && lt != CDT::EDGE) || f->info().in != 1) {
			*why = "a removed vertex does not lie inside the new triangles";
			return;
		}
		located[i] = f->info().out;
	}
	*ntris = n;
}

typedef CGAL::Box_intersection_d::Box_with_info_d<double, 3, uint32_t,
						  CGAL::Box_intersection_d::ID_EXPLICIT>
    Box;

Box box_of(const double (*verts)[3], const uint32_t *t, uint32_t id)
{
	double lo[3], hi[3];
	for (int k = 0; k < 3; k++) {
		lo[k] = std::min(std::min(verts[t[0]][k], verts[t[1]][k]), verts[t[2]][k]);
		hi[k] = std::max(std::max(verts[t[0]][k], verts[t[1]][k]), verts[t[2]][k]);
	}
	return Box(lo, hi, id);
}

int fail(struct st_error *err, const char *what)
{
	try {
		throw;
	} catch (const std::bad_alloc &) {
		return st_error_set(err, ST_ERR_NOMEM, "planar simplification: out of memory %s",
				    what);
	} catch (const std::exception &e) {
		return st_error_set(err, ST_ERR_INTERNAL, "planar simplification: CGAL failed %s: %s",
				    what, e.what());
	} catch (...) {
		return st_error_set(err, ST_ERR_INTERNAL,
				    "planar simplification: unknown exception %s", what);
	}
}

} /* namespace */

extern "C" {

int planar_cdt_triangulate(const struct planar_cdt_cluster *c, uint32_t (*tris)[3], size_t cap,
			   size_t *ntris, uint32_t *located, const char **why,
			   struct st_error *err)
{
	if (!c || !tris || !ntris || !why || (c->nprobe && (!located || !c->probe)) ||
	    !c->nloops || !c->loop || !c->loop_end || (c->nold && !c->old_tris) || !c->verts)
		return st_error_set(err, ST_ERR_ARG, "planar_cdt_triangulate: NULL argument");
	*why = NULL;
	*ntris = 0;
	for (size_t i = 0; i < c->loop_end[c->nloops - 1]; i++)
		if (c->loop[i] >= c->nverts)
			return st_error_set(err, ST_ERR_ARG,
					    "planar_cdt_triangulate: loop vertex %lu of %zu",
					    (unsigned long)c->loop[i], c->nverts);
	for (size_t l = 0; l < c->nloops; l++)
		if (c->loop_end[l] < (l ? c->loop_end[l - 1] : 0) + 3)
			return st_error_set(err, ST_ERR_ARG,
					    "planar_cdt_triangulate: loop %zu has under 3 vertices", l);
	try {
		triangulate(c, tris, cap, ntris, located, why);
		if (*why)
			*ntris = 0;
		return ST_OK;
	} catch (...) {
		*ntris = 0;
		return fail(err, "triangulating a cluster");
	}
}

int planar_cdt_crossings(const double (*verts)[3], size_t nverts, const uint32_t (*tris)[3],
			 size_t ntris, const uint8_t *fresh, uint8_t *hit, struct st_error *err)
{
	if (ntris && (!verts || !tris || !fresh || !hit))
		return st_error_set(err, ST_ERR_ARG, "planar_cdt_crossings: NULL argument");
	for (size_t t = 0; t < ntris; t++)
		for (int k = 0; k < 3; k++)
			if (tris[t][k] >= nverts)
				return st_error_set(err, ST_ERR_ARG,
						    "planar_cdt_crossings: triangle %zu uses vertex "
						    "%lu of %zu",
						    t, (unsigned long)tris[t][k], nverts);
	try {
		std::vector<Box> all, fresh_boxes;
		all.reserve(ntris);
		for (size_t t = 0; t < ntris; t++) {
			hit[t] = 0;
			all.push_back(box_of(verts, tris[t], static_cast<uint32_t>(t)));
			if (fresh[t])
				fresh_boxes.push_back(all.back());
		}
		auto pt = [verts](uint32_t i) { return point(verts[i]); };
		auto test = [&](const Box &a, const Box &b) {
			const uint32_t s = a.info(), t = b.info();
			/* either order: nothing to learn once both fresh ones are hit */
			if (s == t || ((!fresh[s] || hit[s]) && (!fresh[t] || hit[t])))
				return;
			if (pairtest::intersects<K>(tris[s], tris[t], pt)) {
				hit[s] |= fresh[s];
				hit[t] |= fresh[t];
			}
		};
		CGAL::box_intersection_d(fresh_boxes.begin(), fresh_boxes.end(), all.begin(), all.end(),
					 test);
		return ST_OK;
	} catch (...) {
		return fail(err, "looking for crossings of the new triangles");
	}
}

} /* extern "C" */
