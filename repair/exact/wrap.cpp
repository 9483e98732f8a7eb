/*
 * wrap.cpp - thickening for the repair (exact.h, exact_wrap): sheets are
 * closed into thin solids with CGAL's 3D alpha wrapping (CGAL 5.5), whose
 * result is watertight, 2-manifold, free of self-intersections and lies at
 * the offset distance around its input, orientable or not.  Seed 000 §4.2.1
 * offsets a doubled, stitched sheet instead; alpha wrapping gives the same
 * thin solid of total thickness 2 * offset without cutting unorientable
 * sheets first.
 */
#include "exact.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/alpha_wrap_3.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <new>
#include <vector>

namespace
{

typedef CGAL::Epick K;
typedef K::Point_3 Point;
typedef CGAL::Surface_mesh<Point> Surface;

typedef std::vector<K::Triangle_3>::const_iterator Tri_iter;
typedef CGAL::AABB_triangle_primitive<K, Tri_iter> Primitive;
typedef CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>> Tree;

} /* namespace */

extern "C" int exact_wrap(const double (*verts)[3], size_t nverts, const uint32_t (*tris)[3],
			  size_t ntris, double alpha, double offset, double (**out_verts)[3],
			  size_t *nout_verts, uint32_t (**out_tris)[3], size_t *nout_tris,
			  double *deviation, struct st_error *err)
{
	if (!out_verts || !nout_verts || !out_tris || !nout_tris || !deviation)
		return st_error_set(err, ST_ERR_ARG, "wrap: NULL output pointer");
	*out_verts = nullptr;
	*out_tris = nullptr;
	*nout_verts = *nout_tris = 0;
	*deviation = 0;
	if (!(alpha > 0) || !(offset > 0) || !std::isfinite(alpha) || !std::isfinite(offset))
		return st_error_set(err, ST_ERR_ARG, "wrap: alpha %g and offset %g must be > 0",
				    alpha, offset);
	if (ntris == 0 || !verts || !tris)
		return st_error_set(err, ST_ERR_ARG, "wrap: nothing to wrap");
	for (size_t t = 0; t < ntris; t++)
		for (int k = 0; k < 3; k++)
			if (tris[t][k] >= nverts)
				return st_error_set(err, ST_ERR_ARG,
						    "wrap: triangle %zu uses vertex %lu of %zu", t,
						    (unsigned long)tris[t][k], nverts);
	double (*ov)[3] = nullptr;
	uint32_t (*ot)[3] = nullptr;
	try {
		std::vector<Point> points;
		std::vector<std::array<size_t, 3>> faces;
		std::vector<K::Triangle_3> input;
		points.reserve(nverts);
		for (size_t v = 0; v < nverts; v++)
			points.emplace_back(verts[v][0], verts[v][1], verts[v][2]);
		faces.reserve(ntris);
		input.reserve(ntris);
		for (size_t t = 0; t < ntris; t++) {
			faces.push_back({tris[t][0], tris[t][1], tris[t][2]});
			input.emplace_back(points[tris[t][0]], points[tris[t][1]],
					   points[tris[t][2]]);
		}

		Surface wrap;
		CGAL::alpha_wrap_3(points, faces, alpha, offset, wrap);
		if (wrap.number_of_faces() == 0)
			return st_error_set(err, ST_ERR_INTERNAL,
					    "wrap: alpha wrapping of %zu triangles gave nothing",
					    ntris);

		/* How far the result strays from its input: at every vertex
		 * and face centroid. */
		Tree tree(input.begin(), input.end());
		tree.accelerate_distance_queries();
		double worst = 0;

		const size_t nv = wrap.number_of_vertices(), nf = wrap.number_of_faces();
		ov = static_cast<double(*)[3]>(std::malloc(nv * sizeof(*ov)));
		ot = static_cast<uint32_t(*)[3]>(std::malloc(nf * sizeof(*ot)));
		if (!ov || !ot)
			throw std::bad_alloc();
		std::vector<uint32_t> index(wrap.num_vertices());
		size_t i = 0;
		for (Surface::Vertex_index v : wrap.vertices()) {
			const Point &p = wrap.point(v);
			ov[i][0] = p.x();
			ov[i][1] = p.y();
			ov[i][2] = p.z();
			worst = std::max(worst, std::sqrt(tree.squared_distance(p)));
			index[v] = static_cast<uint32_t>(i++);
		}
		size_t j = 0;
		for (Surface::Face_index f : wrap.faces()) {
			int k = 0;
			Point c[3];
			for (Surface::Vertex_index v :
			     CGAL::vertices_around_face(wrap.halfedge(f), wrap)) {
				if (k < 3) {
					ot[j][k] = index[v];
					c[k] = wrap.point(v);
				}
				k++;
			}
			if (k != 3)
				throw std::logic_error("alpha wrap produced a non-triangle");
			worst = std::max(worst,
					 std::sqrt(tree.squared_distance(CGAL::centroid(c[0], c[1], c[2]))));
			j++;
		}
		*out_verts = ov;
		*out_tris = ot;
		*nout_verts = i;
		*nout_tris = j;
		*deviation = worst;
		return ST_OK;
	} catch (const std::bad_alloc &) {
		std::free(ov);
		std::free(ot);
		return st_error_set(err, ST_ERR_NOMEM, "wrap: out of memory wrapping %zu triangles",
				    ntris);
	} catch (const std::exception &e) {
		std::free(ov);
		std::free(ot);
		return st_error_set(err, ST_ERR_INTERNAL, "wrap: alpha wrapping failed: %s",
				    e.what());
	} catch (...) {
		std::free(ov);
		std::free(ot);
		return st_error_set(err, ST_ERR_INTERNAL, "wrap: alpha wrapping failed");
	}
}
