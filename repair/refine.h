/*
 * refine.h - seed 003's vertex translation where a finer mesh of the same
 * part exists (`stratum refine`, docs/accuracy.md): the facets whose
 * chordal error against the reference is over a tolerance are split
 * (conforming edge bisection, seed 004's local densification), and each
 * new vertex is moved onto the reference surface, until every facet is
 * within the tolerance.
 *
 * A new vertex on an edge where the facets meet at a sharp angle (a
 * feature edge: a rim, a crease) goes to the line where the reference's two
 * faces on either side meet there, so it stays on the crease instead of
 * sliding onto one face; any other goes along the facets' normal onto the
 * surface.  A move that would make a triangle cross another, flip or
 * collapse (exact tests) is refused: the vertex stays on its edge.  Only
 * vertices are added, and every edge is split on both of its facets, so a
 * closed, printable mesh stays closed and printable.  New positions are
 * rounded to float32, as STL stores them, before they are checked.
 */
#ifndef STRATUM_REPAIR_REFINE_H
#define STRATUM_REPAIR_REFINE_H

#include <stdbool.h>
#include <stddef.h>

#include "mesh.h"
#include "st_error.h"

/* The options' defaults and ranges (the CLI and the docs read these). */
#define REFINE_FEATURE_ANGLE_DEFAULT 30.0 /* degrees between facets that make a crease */
#define REFINE_MAX_TRIANGLES_DEFAULT 4000000 /* give up beyond (about 200 MB of STL) */

struct refine_options {
	double tolerance;     /* mm, > 0: the largest chordal error allowed */
	double feature_angle; /* degrees, 0..180: facets meeting at more make a crease */
	size_t samples;	      /* about this many measuring points on each surface
			       * (chordal_measure, deviation.h) */
	size_t max_triangles; /* stop, not reached, rather than grow past this */
	bool uniform;	      /* split every edge each round: the comparison */
	bool move_vertices;   /* first move coarse's own vertices onto ref too */
	int threads;	      /* cores for the exact checks; 0 = all */
};

struct refine_report {
	size_t rounds;		   /* of measuring and splitting */
	size_t triangles_before, triangles_after;
	size_t vertices_added;
	size_t on_creases;	   /* new vertices placed on a crease of the reference */
	size_t vertices_moved;	   /* move_vertices: input vertices moved onto ref */
	size_t refused;		   /* moves refused (a crossing, a flip); left on the edge */
	double error_before;	   /* mm: the largest facet's chordal error */
	double error_after;
	double vertex_error;	   /* mm: the farthest input vertex from the reference
				    * (after move_vertices) */
	size_t facets_over;	   /* after: facets still over the tolerance */
	bool reached;		   /* every facet within the tolerance */
	float *facet_error;	   /* per output triangle, mm (refine_report_free) */
};

/* Defaults, tolerance 0.01 mm, all cores. */
void refine_options_init(struct refine_options *opt);

/*
 * refine_mesh - coarse refined against ref into *out (mesh_free).  coarse
 * must be printable (closed, no self-intersection; mesh_analyze) once
 * rounded to float32.  Returns 0 with *out and *rep filled, rep->reached
 * telling whether the tolerance was met (when not, *out is how far it got:
 * the rounds stopped making progress, or the next round would pass
 * max_triangles, or an input vertex lies farther than the tolerance from
 * ref, which moving new vertices cannot mend).  Else ST_ERR_ARG (bad
 * options, a mesh without area), ST_ERR_UNSUPPORTED (coarse not printable,
 * err says why), ST_ERR_RANGE (a coordinate beyond float32), ST_ERR_NOMEM
 * or ST_ERR_INTERNAL, with err filled and *out NULL.
 */
int refine_mesh(const struct mesh *coarse, const struct mesh *ref,
		const struct refine_options *opt, struct mesh **out, struct refine_report *rep,
		struct st_error *err);

void refine_report_free(struct refine_report *rep);

/* refine_stl_bytes - the size of a binary STL of n triangles. */
size_t refine_stl_bytes(size_t ntris);

#endif /* STRATUM_REPAIR_REFINE_H */
