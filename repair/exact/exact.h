/*
 * exact.h - C face of the CGAL bridge (the only C++ in repair/).
 *
 * Everything that decides something from geometry goes through here so the
 * decision is exact (CGAL's filtered exact predicates, Epick; Epeck where new
 * points are constructed).  The header is plain C11: opaque data only as
 * arrays of doubles and uint32_t indices with their lengths.  Every function
 * catches all C++ exceptions and returns ST_ERR_INTERNAL / ST_ERR_NOMEM with
 * err filled instead.
 */
#ifndef STRATUM_REPAIR_EXACT_H
#define STRATUM_REPAIR_EXACT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "st_error.h"

#ifdef __cplusplus
extern "C" {
#endif

/*
 * exact_collinear - true when a, b, c are collinear or coincident (exact).
 * A non-finite coordinate also gives true (the degenerate answer).
 */
bool exact_collinear(const double a[3], const double b[3], const double c[3]);

/*
 * exact_orient3d - sign of the orientation of d relative to the plane
 * (a, b, c): +1, 0 (coplanar) or -1, exactly.  Same sign convention as
 * CGAL::orientation (positive when d is on the positive side).  A
 * non-finite coordinate gives 0.
 */
int exact_orient3d(const double a[3], const double b[3], const double c[3],
		   const double d[3]);

/*
 * exact_count_self_intersections - count pairs of triangles whose
 * intersection is not a common face (seed 000 Definition 3.6).
 *
 * verts: nverts xyz triples; tris: ntris index triples (indices < nverts).
 * Equal indices must mean equal points and different indices different
 * points (welded, as in struct mesh).  skip: NULL or ntris flags; triangles
 * with a nonzero flag are ignored (the caller passes irregular, degenerate
 * and duplicate triangles here).  A triangle not flagged but degenerate
 * (collinear corners, exact test) is ignored as well, never an error.
 * Pairs that share an edge intersect only when they overlap in their common
 * plane; pairs that share one vertex only when they meet anywhere else;
 * pairs sharing all three vertices never count.  Pairs sharing a vertex
 * are decided from the vertex stars, the others are found with a grid or
 * CGAL's box intersection (docs/check.md); threads: 1 = this thread only,
 * n > 1 = up to n cores (capped at what TBB has), 0 = all cores.
 *
 * Memory: about 50 bytes per triangle on top of the arrays, any thread
 * count.  Reentrant; the arrays are only read.
 *
 * Returns 0 with *count set, or a negative class with err filled and
 * *count = 0: ST_ERR_ARG for a NULL array with a nonzero count, an index
 * >= nverts, a non-finite coordinate in a triangle not skipped, or threads
 * < 0; ST_ERR_NOMEM; ST_ERR_INTERNAL for any other exception.
 */
int exact_count_self_intersections(const double (*verts)[3], size_t nverts,
				   const uint32_t (*tris)[3], size_t ntris,
				   const uint8_t *skip, int threads, uint64_t *count,
				   struct st_error *err);

/*
 * exact_count_self_intersections_stars - the same count for a caller that
 * has the vertex stars already (the topology report): skip must flag
 * every degenerate triangle as well (none is then tested again), and
 * star_tri[star_off[v]] .. star_tri[star_off[v + 1] - 1] list the
 * triangles around vertex v not skipped, in increasing order.  Saves
 * building them a second time (16 bytes per triangle).
 */
int exact_count_self_intersections_stars(const double (*verts)[3], size_t nverts,
					 const uint32_t (*tris)[3], size_t ntris,
					 const uint8_t *skip, const uint32_t *star_off,
					 const uint32_t *star_tri, int threads, uint64_t *count,
					 struct st_error *err);

/*
 * An exact mesh: triangles over vertices whose exact positions may be
 * rationals (points created where triangles cross).  Each vertex also has a
 * double approximation for boxes, output and anything that decides nothing.
 * Vertices given as doubles are exact as given.  Distinct vertex indices
 * always mean distinct exact points.  Every triangle remembers an origin
 * (a caller-chosen uint32_t, inherited by the pieces it is cut into).
 *
 * Not thread-safe: one thread per exact_mesh at a time.
 */
struct exact_mesh;

/*
 * exact_mesh_new - an exact mesh from double vertices and triangles.  The
 * vertices must be welded (equal coordinates only once) and finite; the
 * triangles regular (three different indices) and non-degenerate.  origin
 * may be NULL (then triangle i has origin i).  Returns 0 and *out (free with
 * exact_mesh_free), or ST_ERR_ARG / ST_ERR_NOMEM / ST_ERR_INTERNAL.
 */
int exact_mesh_new(const double (*verts)[3], size_t nverts, const uint32_t (*tris)[3],
		   size_t ntris, const uint32_t *origin, struct exact_mesh **out,
		   struct st_error *err);

/* exact_mesh_free - free; NULL is safe. */
void exact_mesh_free(struct exact_mesh *m);

/*
 * exact_mesh_append - add triangles over new double vertices (welded with
 * the mesh's double-exact vertices and among themselves), all with origin
 * origin.  Degenerate or irregular triangles (after welding) are skipped
 * and counted in *skipped (may be NULL).  Returns 0 or a negative class.
 */
int exact_mesh_append(struct exact_mesh *m, const double (*verts)[3], size_t nverts,
		      const uint32_t (*tris)[3], size_t ntris, uint32_t origin, size_t *skipped,
		      struct st_error *err);

/*
 * exact_mesh_append_ref - exact_mesh_append where vertex v may instead be
 * vertex ref[v] of src, exactly (ref[v] == UINT32_MAX: verts[v] as above).
 * A referenced rational point is welded with an equal one already in m, so
 * new triangles meet src's points exactly, not within rounding of them.
 * ref may be NULL (then src too).
 */
int exact_mesh_append_ref(struct exact_mesh *m, const struct exact_mesh *src, const uint32_t *ref,
			  const double (*verts)[3], size_t nverts, const uint32_t (*tris)[3],
			  size_t ntris, uint32_t origin, size_t *skipped, struct st_error *err);

/*
 * exact_mesh_select - a new exact mesh with the triangles whose keep flag
 * is set, in order, reversed where flip is set (flip may be NULL), over
 * only the vertices they use (exact positions kept).
 */
int exact_mesh_select(const struct exact_mesh *m, const uint8_t *keep, const uint8_t *flip,
		      struct exact_mesh **out, struct st_error *err);

/* Sizes and read-only views; valid until the mesh is next changed. */
size_t exact_mesh_nverts(const struct exact_mesh *m);
size_t exact_mesh_ntris(const struct exact_mesh *m);
const double (*exact_mesh_verts(const struct exact_mesh *m))[3];
const uint32_t (*exact_mesh_tris(const struct exact_mesh *m))[3];
const uint32_t *exact_mesh_origin(const struct exact_mesh *m);
/*
 * exact_mesh_parents - right after exact_mesh_refine (NULL after any other
 * change): per triangle, the index in the list before the refinement of
 * the triangle it is a piece of (its own when it was not cut); *whole[i]
 * is 0 when part of triangle i's area went to an equal piece of another
 * triangle (a coplanar overlap), so its own pieces do not cover it.
 */
const uint32_t *exact_mesh_parents(const struct exact_mesh *m, const uint8_t **whole);
/* True when triangles t and u are known to lie exactly in one plane (pieces
 * of one triangle the refinement split); false tells nothing.  Lets callers
 * skip the predicates whose exact zero is the costly case. */
bool exact_mesh_same_plane(const struct exact_mesh *m, uint32_t t, uint32_t u);
/* Whether vertex v's double approximation is its exact position. */
bool exact_mesh_vertex_is_double(const struct exact_mesh *m, uint32_t v);

/* A progress hook: phase named as a sentence, 0..1 of it done. */
typedef void (*exact_progress_fn)(void *ctx, const char *stage, double done);

/* exact_mesh_set_progress - exact_mesh_refine reports the pairs it
 * intersects and the triangles it cuts to fn (NULL: none), from worker
 * threads, one call at a time.  Kept by copies of m. */
void exact_mesh_set_progress(struct exact_mesh *m, exact_progress_fn fn, void *ctx);

struct exact_refine_stats {
	uint64_t intersecting_pairs;	/* pairs that met outside a shared face */
	size_t triangles_split;		/* triangles re-triangulated */
	size_t new_vertices;		/* exact points created */
	size_t duplicates_removed;	/* equal pieces of coplanar overlaps */
};

/*
 * exact_mesh_refine - resolve every self-intersection (seed 000 §4.1):
 * each pair of triangles that meets outside a common face is intersected
 * exactly (Epeck), every cut triangle is re-triangulated in its plane with
 * the intersection points and segments as constraints (constrained
 * Delaunay, exact intersections), coincident points are unified exactly and
 * equal pieces (coplanar overlaps) are kept once.  Triangles that meet
 * nothing are kept untouched, in order.  Pieces keep their triangle's
 * orientation and origin.  threads as for the count.  On error the mesh is
 * unchanged.
 */
int exact_mesh_refine(struct exact_mesh *m, int threads, struct exact_refine_stats *stats,
		      struct st_error *err);

struct exact_snap_stats {
	size_t rounded;		/* vertices moved to the grid point nearest them */
	size_t other_corner;	/* moved to another corner of their grid cell */
	size_t collapsed;	/* merged into a neighbour already on the grid */
	size_t triangles_removed;	/* triangles the merges collapsed */
	size_t unplaced;	/* left at the nearest grid point although unsafe */
	double max_move;	/* mm: farthest a vertex ended from its exact place */
};

/*
 * exact_mesh_snap_round - move every vertex of m onto the output grid
 * (mantissa_bits 24: float32, 53: double) without letting triangles meet
 * anywhere but in shared faces, into a new mesh *out whose vertices are all
 * exact doubles on that grid.
 *
 * Vertices are moved one at a time and each move is kept only when the
 * triangles around the vertex stay non-degenerate and meet no other
 * triangle (exact tests against the current, partly rounded mesh), so an
 * intersection-free m stays intersection-free after every move.  A vertex
 * goes to the grid point nearest it if that is safe, else to the nearest
 * safe corner of the grid cell around it, else it is merged into a
 * neighbour already on the grid (an edge collapse keeping the link
 * condition, so a closed manifold stays one) that lies within reach (mm,
 * in every coordinate) of the exact places of all vertices merged into
 * it.  Vertices already on the grid never move.  Rounds of this repeat
 * while they place more vertices; what still has no safe place is put on
 * its nearest grid point and counted in stats->unplaced (then the result
 * may have intersections; the caller checks).  threads as for the count
 * (the candidate search runs on them; the result does not depend on it).
 * Not thread-safe on m.
 * Returns 0, ST_ERR_ARG (bad bits, reach < 0, NULL), ST_ERR_RANGE (a
 * coordinate beyond float32), ST_ERR_NOMEM or ST_ERR_INTERNAL.
 */
int exact_mesh_snap_round(const struct exact_mesh *m, int mantissa_bits, double reach,
			  int threads, struct exact_mesh **out, struct exact_snap_stats *stats,
			  struct st_error *err);

/* exact_mesh_orient3d - exact_orient3d on vertex indices (exact positions). */
int exact_mesh_orient3d(const struct exact_mesh *m, uint32_t a, uint32_t b, uint32_t c,
			uint32_t d);

/*
 * exact_mesh_seed - the seed triangle of seed 000 §4.2.1 among the n
 * triangles listed in tris: at the vertex with the largest x (then y, z),
 * the incident edge with the smallest |x| component of its direction, and
 * at that edge the triangle with the largest |x| component of its unit
 * normal, all compared exactly.  *flip is set when that normal points to
 * -x, i.e. the triangle must be reversed to face outwards.
 */
int exact_mesh_seed(const struct exact_mesh *m, const uint32_t *tris, size_t n, uint32_t *seed,
		    bool *flip, struct st_error *err);

/*
 * exact_mesh_inside - whether the centroid of triangle probe lies inside
 * the closed surface made of the n triangles listed in closed (exact ray
 * parity; rays that graze an edge are re-cast).  The centroid must not lie
 * on that surface.  *inside receives the answer.
 */
int exact_mesh_inside(const struct exact_mesh *m, const uint32_t *closed, size_t n,
		      uint32_t probe, bool *inside, struct st_error *err);

/*
 * exact_ray_index_new - the n triangles listed in closed, filed for
 * exact_mesh_inside_indexed, which gives exact_mesh_inside's answer but
 * tests only the triangles a ray from the probe can meet: for a surface
 * asked about many probes.  Free with exact_ray_index_free.
 */
struct exact_ray_index;
int exact_ray_index_new(const struct exact_mesh *m, const uint32_t *closed, size_t n,
			struct exact_ray_index **out, struct st_error *err);
void exact_ray_index_free(struct exact_ray_index *ix);
int exact_mesh_inside_indexed(const struct exact_mesh *m, const struct exact_ray_index *ix,
			      uint32_t probe, bool *inside, struct st_error *err);

/*
 * exact_segment_hidden - seed 000 §4.2.1 wires: whether segment pq (double
 * points) is hidden, that is every part of it lies on one of the n_surface
 * triangles listed in surface or inside the closed surface of the n_closed
 * triangles listed in closed.  *hidden receives the answer.
 */
int exact_segment_hidden(const struct exact_mesh *m, const uint32_t *surface, size_t n_surface,
			 const uint32_t *closed, size_t n_closed, const double p[3],
			 const double q[3], bool *hidden, struct st_error *err);

#ifdef __cplusplus
}
#endif

#endif /* STRATUM_REPAIR_EXACT_H */
