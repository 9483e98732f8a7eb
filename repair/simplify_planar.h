/*
 * simplify_planar.h - planar simplification (seed 001 §4): nearly
 * coplanar facets merged into clusters and each cluster re-triangulated
 * with the fewest triangles its boundary allows, without changing the
 * topology or creating a self-intersection (docs/repair.md "Planar
 * simplification").
 *
 * Meant for what the exact repair writes: the repair cuts triangles
 * wherever surfaces cross and keeps every input vertex, so flat faces of
 * a CAD part come out in many pieces.  Only vertices are removed, none is
 * created or moved, so a mesh on the float32 grid stays on it.
 */
#ifndef STRATUM_REPAIR_SIMPLIFY_PLANAR_H
#define STRATUM_REPAIR_SIMPLIFY_PLANAR_H

#include <stddef.h>
#include <stdint.h>

#include "mesh.h"
#include "st_error.h"

/* The options' defaults and ranges (the CLI and the docs read these). */
#define PLANAR_ANGLE_DEFAULT 1.0     /* degrees */
#define PLANAR_ANGLE_MAX 45.0	     /* degrees: a cluster must still face one way */
#define PLANAR_FLATNESS_DEFAULT 0.01 /* mm: well under a printed layer */
#define PLANAR_FLATNESS_MAX 1.0	     /* mm; more is a typo, not a tolerance */

struct planar_options {
	/* A facet joins a cluster when its normal lies less than angle
	 * degrees (0..PLANAR_ANGLE_MAX) from the cluster plane's ... */
	double angle;
	/* ... and no vertex of the grown cluster lies farther than flatness
	 * mm (0..PLANAR_FLATNESS_MAX) from that plane, the area-weighted
	 * average of its facets' planes.  Facets exactly coplanar with a
	 * cluster that is exactly planar join at any tolerance, 0 included. */
	double flatness;
	int threads;	/* cores for the exact checks; 0 = all */
};

struct planar_report {
	size_t triangles_before, triangles_after;
	size_t vertices_before, vertices_after;
	size_t clusters;	/* clusters of more than one facet */
	size_t retriangulated;	/* of those, re-triangulated with fewer triangles */
	/* Clusters left as they were, by the check that refused them: */
	size_t refused_shape;	  /* not a disk with holes, or no valid triangulation */
	size_t refused_deviation; /* surfaces or volume apart beyond flatness */
	size_t refused_topology;  /* an edge would not be closed and manifold */
	size_t refused_crossing;  /* a new triangle would meet another (exact) */
	double max_deviation;	/* mm: widest gap between old and new surfaces */
	double volume_before;	/* mm^3, signed (divergence theorem) */
	double volume_after;
	double area;		/* mm^2 of the input */
};

/* Defaults: PLANAR_ANGLE_DEFAULT, PLANAR_FLATNESS_DEFAULT, all cores. */
void planar_options_init(struct planar_options *opt);

/*
 * planar_simplify - in simplified into a new mesh *out (mesh_free).
 * origin, when not NULL, receives a malloc'd array: for each output
 * triangle the input triangle it comes from (for a new triangle, the first
 * facet of its cluster), so per-triangle labels such as the repair's part
 * numbers carry over.
 *
 * Clusters grow only across edges with exactly two consistently oriented
 * facets; a vertex is removed only where its star is one closed disk of
 * such edges: inside a cluster, or on a straight seam between exactly two
 * clusters, which then both drop it.  Every re-triangulated cluster is
 * checked (shape, removed vertices and volume within flatness, edges
 * closed and manifold, no crossing, exact); one that fails is left as it
 * was, with its vertices, and its neighbours are redone keeping them.
 * The result is finally compared with the input by mesh_analyze: the
 * same components, shells, parts, Euler characteristic, boundary and
 * singular edges, no more self-intersections, printable if the input was.
 * Irregular and degenerate triangles are kept as they are.
 *
 * Returns 0 with *rep filled, or ST_ERR_ARG (bad options), ST_ERR_NOMEM,
 * ST_ERR_INTERNAL (a failure in the bridge, or the final comparison found
 * a change, which would be a bug) with err filled and *out NULL.
 */
int planar_simplify(const struct mesh *in, const struct planar_options *opt, struct mesh **out,
		    uint32_t **origin, struct planar_report *rep, struct st_error *err);

#endif /* STRATUM_REPAIR_SIMPLIFY_PLANAR_H */
