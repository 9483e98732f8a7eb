/*
 * holefill.cpp - the CGAL side of holefill.h: hole triangulation of a
 * boundary polyline, then refinement and fairing of the patch.  Nothing
 * C++ leaves this file.
 */
#include "holefill.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/fair.h>
#include <CGAL/Polygon_mesh_processing/refine.h>
#include <CGAL/Polygon_mesh_processing/triangulate_hole.h>
#include <CGAL/Surface_mesh.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <map>
#include <new>
#include <set>
#include <vector>

namespace
{

typedef CGAL::Exact_predicates_inexact_constructions_kernel K;
typedef K::Point_3 Point;
typedef CGAL::Surface_mesh<Point> Mesh;

/* Three point indices, the output type triangulate_hole_polyline wants. */
struct Tri {
	int v[3];
	Tri(int a, int b, int c) : v{a, b, c} {}
};

/*
 * Whether the patch walks directed edge a->b of the loop (then it follows
 * the loop's direction) rather than b->a.
 */
bool walks(const std::vector<Tri> &patch, int a, int b)
{
	for (const Tri &t : patch)
		for (int k = 0; k < 3; k++)
			if (t.v[k] == a && t.v[(k + 1) % 3] == b)
				return true;
	return false;
}

/*
 * Refine patch (indices into pts, walking the loop's direction) and fair
 * its new vertices with the ring of triangles around the hole (far) held
 * fixed, so the patch continues the surface's curvature (Botsch 2008, as
 * CGAL's triangulate_refine_and_fair_hole does).  On success patch and
 * extra hold the faired patch: indices below pts.size() are loop points,
 * the others extra[i - pts.size()].  False (patch unchanged) when the
 * ring is not a manifold strip or fairing fails.
 */
bool refine_and_fair(const std::vector<Point> &pts, const std::vector<Point> &far,
		     std::vector<Tri> &patch, std::vector<Point> &extra)
{
	const size_t n = pts.size();
	Mesh m;
	std::vector<Mesh::Vertex_index> vi;
	std::map<std::array<double, 3>, Mesh::Vertex_index> far_vertex;
	std::set<Mesh::Face_index> ring;
	std::vector<Mesh::Face_index> faces, new_faces;
	std::vector<Mesh::Vertex_index> new_vertices;

	for (const Point &p : pts)
		vi.push_back(m.add_vertex(p));
	for (const Tri &t : patch) {
		const Mesh::Face_index f = m.add_face(vi[t.v[0]], vi[t.v[1]], vi[t.v[2]]);
		if (f == Mesh::null_face())
			return false;
		faces.push_back(f);
	}
	/* The triangle outside each edge walks it the other way round. */
	for (size_t i = 0; i < n && far.size() == n; i++) {
		const std::array<double, 3> key = {far[i].x(), far[i].y(), far[i].z()};
		auto it = far_vertex.find(key);
		if (it == far_vertex.end())
			it = far_vertex.emplace(key, m.add_vertex(far[i])).first;
		const Mesh::Face_index f = m.add_face(vi[(i + 1) % n], vi[i], it->second);
		if (f == Mesh::null_face())
			return false;
		ring.insert(f);
	}
	if (ring.size() != n)
		return false; /* without the ring fairing has nothing to hold on to */
	CGAL::Polygon_mesh_processing::refine(m, faces, std::back_inserter(new_faces),
					      std::back_inserter(new_vertices));
	if (new_vertices.empty())
		return false; /* nothing to fair: the plain triangulation stands */
	if (!CGAL::Polygon_mesh_processing::fair(m, new_vertices))
		return false;
	std::map<Mesh::Vertex_index, int> index;
	for (size_t i = 0; i < n; i++)
		index[vi[i]] = static_cast<int>(i);
	std::vector<Point> added;
	for (Mesh::Vertex_index v : new_vertices) {
		const Point &p = m.point(v);
		if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || !std::isfinite(p.z()))
			return false;
		index[v] = static_cast<int>(n + added.size());
		added.push_back(p);
	}
	std::vector<Tri> faired;
	for (Mesh::Face_index f : m.faces()) {
		if (ring.count(f))
			continue;
		int c[3], k = 0;
		for (Mesh::Vertex_index v : CGAL::vertices_around_face(m.halfedge(f), m)) {
			const auto it = index.find(v);
			if (it == index.end() || k == 3)
				return false; /* a ring vertex in the patch: not ours to move */
			c[k++] = it->second;
		}
		if (k != 3)
			return false;
		faired.emplace_back(c[0], c[1], c[2]);
	}
	patch.swap(faired);
	extra.swap(added);
	return true;
}

int fill(const double (*loop)[3], size_t n, const double (*third)[3], double (**points)[3],
	 size_t *npoints, uint32_t (**tris)[3], size_t *ntris, struct st_error *err)
{
	std::vector<Point> pts, far, extra;
	std::vector<Tri> patch;

	pts.reserve(n);
	for (size_t i = 0; i < n; i++)
		pts.emplace_back(loop[i][0], loop[i][1], loop[i][2]);
	if (third) {
		far.reserve(n);
		for (size_t i = 0; i < n; i++)
			far.emplace_back(third[i][0], third[i][1], third[i][2]);
	}
	CGAL::Polygon_mesh_processing::triangulate_hole_polyline(pts, far,
								 std::back_inserter(patch));
	if (patch.empty())
		return 0;
	/* Follow the loop's direction: reverse everything when the patch
	 * walks the loop's first edge backwards. */
	if (!walks(patch, 0, 1))
		for (Tri &t : patch)
			std::swap(t.v[0], t.v[2]);
	if (points)
		refine_and_fair(pts, far, patch, extra);
	uint32_t (*out)[3] = static_cast<uint32_t (*)[3]>(std::malloc(patch.size() * sizeof(*out)));
	double (*added)[3] = static_cast<double (*)[3]>(std::malloc((extra.size() + 1) * sizeof(*added)));
	if (!out || !added) {
		std::free(out);
		std::free(added);
		return st_error_set(err, ST_ERR_NOMEM, "holes: out of memory for %zu triangles",
				    patch.size());
	}
	for (size_t t = 0; t < patch.size(); t++)
		for (int k = 0; k < 3; k++)
			out[t][k] = static_cast<uint32_t>(patch[t].v[k]);
	for (size_t i = 0; i < extra.size(); i++) {
		added[i][0] = extra[i].x();
		added[i][1] = extra[i].y();
		added[i][2] = extra[i].z();
	}
	*tris = out;
	*ntris = patch.size();
	if (points) {
		*points = added;
		*npoints = extra.size();
	} else {
		std::free(added);
	}
	return 0;
}

} /* namespace */

extern "C" {

int exact_fill_hole(const double (*loop)[3], size_t n, const double (*third)[3],
		    double (**points)[3], size_t *npoints, uint32_t (**tris)[3], size_t *ntris,
		    struct st_error *err)
{
	if (tris)
		*tris = NULL;
	if (ntris)
		*ntris = 0;
	if (points)
		*points = NULL;
	if (npoints)
		*npoints = 0;
	if (points && !npoints)
		return st_error_set(err, ST_ERR_ARG, "holes: points without a count");
	if (!loop || !tris || !ntris || n < 3)
		return st_error_set(err, ST_ERR_ARG,
				    "holes: a hole needs a loop of at least 3 points (got %zu)", n);
	if (n > 0x7fffffffu)
		return st_error_set(err, ST_ERR_ARG, "holes: a loop of %zu points is too long", n);
	for (size_t i = 0; i < n; i++)
		for (int k = 0; k < 3; k++)
			if (!std::isfinite(loop[i][k]) || (third && !std::isfinite(third[i][k])))
				return st_error_set(err, ST_ERR_ARG,
						    "holes: point %zu of a hole loop is not finite",
						    i);
	try {
		return fill(loop, n, third, points, npoints, tris, ntris, err);
	} catch (const std::bad_alloc &) {
		return st_error_set(err, ST_ERR_NOMEM,
				    "holes: out of memory triangulating a hole of %zu edges", n);
	} catch (const std::exception &e) {
		return st_error_set(err, ST_ERR_INTERNAL,
				    "holes: triangulating a hole of %zu edges failed inside CGAL: %s",
				    n, e.what());
	} catch (...) {
		return st_error_set(err, ST_ERR_INTERNAL,
				    "holes: triangulating a hole of %zu edges failed with an "
				    "unknown exception",
				    n);
	}
}

} /* extern "C" */
