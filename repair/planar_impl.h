/*
 * planar_impl.h - private to repair/: what simplify_planar.c,
 * planar_grow.c and planar_retri.c share (simplify_planar.h is the
 * public face).
 */
#ifndef STRATUM_REPAIR_PLANAR_IMPL_H
#define STRATUM_REPAIR_PLANAR_IMPL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "mesh.h"
#include "simplify_planar.h"
#include "st_error.h"

#define PLANAR_NONE UINT32_MAX

/* What may happen to a vertex (planar_classify). */
enum planar_role {
	PLANAR_KEEP,	 /* a corner, a meeting of 3+ clusters, or a non-disk star */
	PLANAR_INTERIOR, /* every facet around it in one cluster: removed */
	PLANAR_SEAM,	 /* on a straight seam between exactly two clusters: removed */
};

/* Where a cluster stands. */
enum planar_state {
	PLANAR_AS_IS,	/* nothing to remove, or one facet */
	PLANAR_NEW,	/* re-triangulated: new[] holds its triangles */
	PLANAR_REFUSED,	/* a check failed: left as it was, its vertices kept */
};

/* An undirected edge of the input (smaller vertex first) and its use count. */
struct planar_edge {
	uint32_t a, b;
	uint32_t count;
};

struct planar_cluster {
	size_t first, n;	/* its facets: ctx->cl_tris[first .. first+n) */
	double normal[3];	/* unit, area-weighted average of its facets' */
	bool exact;		/* every vertex exactly in its seed facet's plane */
	enum planar_state state;
	bool dirty;		/* to re-triangulate (again) */
	uint32_t (*tris)[3];	/* PLANAR_NEW: the new triangles */
	size_t ntris;
	double deviation;	/* mm: widest gap between its old and new surfaces */
};

struct planar_ctx {
	const struct mesh *m;
	const struct planar_options *opt;
	uint8_t *usable;	/* per triangle: regular and not degenerate */
	uint32_t (*nb)[3];	/* facet across edge k (corner k to k+1), or PLANAR_NONE */
	double *area;		/* mm^2 per triangle */
	double (*unit)[3];	/* unit normal per usable triangle */
	size_t *vt_start;	/* vertex -> triangles, CSR over all triangles */
	uint32_t *vt;
	uint8_t *clean;		/* vertex star is one closed fan of two-facet edges */
	struct planar_edge *edges; /* the input's undirected edges, sorted */
	size_t nedges;
	uint32_t *cluster;	/* per triangle, PLANAR_NONE when not usable */
	uint32_t *cl_tris;	/* facets grouped by cluster */
	struct planar_cluster *cl;
	size_t ncl;
	uint8_t *role;		/* enum planar_role per vertex */
	uint8_t *kept;		/* per vertex: a refused cluster keeps it */
	/* Scratch marks per vertex (growth and loops), each use a new stamp_gen. */
	uint32_t *next, *stamp, *seen;
	uint32_t stamp_gen;
};

/* planar_grow.c: adjacency, vertex stars, the clusters (seed 001 §4.2) and
 * each vertex's role.  0 or ST_ERR_NOMEM. */
int planar_grow(struct planar_ctx *x, struct st_error *err);

/* Corner of triangle t at vertex v (t must have it). */
int planar_corner(const uint32_t *t, uint32_t v);

/* How often undirected edge a-b is used by the input (0: not an edge). */
uint32_t planar_edge_count(const struct planar_ctx *x, uint32_t a, uint32_t b);

/*
 * planar_retriangulate - cluster c with the fewest triangles its loops
 * allow, dropping its interior vertices and its seam vertices not kept.
 * Sets c's state to PLANAR_NEW (tris, deviation) or *refusal to the
 * report counter that refused it (the caller refuses it).  0 or <0.
 */
int planar_retriangulate(struct planar_ctx *x, uint32_t c, size_t **refusal,
			 struct planar_report *rep, struct st_error *err);

#endif /* STRATUM_REPAIR_PLANAR_IMPL_H */
