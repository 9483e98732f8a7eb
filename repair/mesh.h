/*
 * mesh.h - the indexed triangle mesh and its topology report.
 *
 * A mesh keeps every input triangle, in input order, as three indices into a
 * table of exactly welded vertices: two corners share an index only when
 * their coordinates are bit-identical (+0.0 and -0.0 count as equal).  Seed
 * 000 §3: vertex positions are the only reliable information in an STL, so
 * nothing here snaps "nearby" vertices and normals are ignored.
 *
 * Nothing is dropped on input: irregular triangles (a repeated vertex),
 * degenerate ones and duplicates stay in the triangle list so the report can
 * count them and the repair can set them aside.
 */
#ifndef STRATUM_REPAIR_MESH_H
#define STRATUM_REPAIR_MESH_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "st_error.h"

/* Largest vertex or triangle count we index with uint32_t. */
#define MESH_MAX_ELEMENTS 0xfffffff0u

struct mesh {
	double (*verts)[3];   /* welded positions, mm */
	uint32_t (*tris)[3];  /* corner indices into verts, input order */
	size_t nverts;
	size_t ntris;
	size_t cap_verts;     /* allocated slots (internal) */
	size_t cap_tris;
};

/* Opaque: welds vertices while a reader adds triangles. */
struct mesh_builder;

/*
 * mesh_builder_new - start a mesh.  tri_hint is the expected triangle count
 * (0 if unknown) so the tables can be sized once.  Returns NULL on OOM.
 */
struct mesh_builder *mesh_builder_new(size_t tri_hint);

/*
 * mesh_builder_vertex - weld position p (finite, checked by the caller) and
 * store its index in *index.  Returns 0, or ST_ERR_NOMEM / ST_ERR_RANGE
 * (more than MESH_MAX_ELEMENTS vertices) with err filled.
 */
int mesh_builder_vertex(struct mesh_builder *b, const double p[3], uint32_t *index,
			struct st_error *err);

/*
 * mesh_builder_prefetch - hint that p (finite) will be welded soon: starts
 * loading the hash slot mesh_builder_vertex probes first for it.  A reader
 * that calls this some positions ahead does not wait for memory there
 * (most lookups miss the cache: the table is larger than it).  Changes
 * nothing the builder holds, so the mesh built is the same without it.
 */
void mesh_builder_prefetch(const struct mesh_builder *b, const double p[3]);

/* How many positions ahead of mesh_builder_vertex to prefetch: enough for
 * a slot to arrive from memory, few enough that it is still cached. */
#define MESH_WELD_AHEAD 24

/* mesh_builder_triangle - append a triangle by welded indices. 0 or <0. */
int mesh_builder_triangle(struct mesh_builder *b, uint32_t a, uint32_t c1, uint32_t c2,
			  struct st_error *err);

/*
 * mesh_builder_append - add every triangle of part, in order, welding its
 * vertices into b's as mesh_builder_vertex would.  Building two halves of a
 * file separately and appending the second to the first gives exactly the
 * mesh one builder would have made (same vertex and triangle order).
 * Returns 0 or ST_ERR_NOMEM / ST_ERR_RANGE with err filled.
 */
int mesh_builder_append(struct mesh_builder *b, const struct mesh *part, struct st_error *err);

/*
 * mesh_weld_corners - the mesh of ntris triangles whose corners are
 * corner[3 t + k] (finite floats, as a binary STL holds them): exactly the
 * mesh mesh_builder_vertex and mesh_builder_triangle make corner by
 * corner in that order (the same vertices, numbered in order of first
 * use, the same triangles), welded on up to `threads` threads (0: the
 * cores there are, at most 8), each welding the points of one part of the
 * hash range.  Returns 0 with *out set, or ST_ERR_NOMEM / ST_ERR_RANGE
 * (more than MESH_MAX_ELEMENTS vertices or 2^32 corners) with err filled.
 */
int mesh_weld_corners(const float (*corner)[3], size_t ntris, int threads, struct mesh **out,
		      struct st_error *err);

/* Facets mesh_weld_read asks for at a time, at most. */
#define MESH_WELD_RUN 1024

/*
 * mesh_corner_reader - facets [first, first + count) of a file (count at
 * most MESH_WELD_RUN) decoded into corner[3 i + k], finite floats; false
 * when one does not read or decode.  Called from several threads at once.
 */
typedef bool (*mesh_corner_reader)(void *ctx, size_t first, size_t count, float (*corner)[3]);

/*
 * mesh_weld_read - mesh_weld_corners with the corners read through read
 * (each thread reads every facet for itself, so no array of all the
 * corners is kept).  Also ST_ERR_PARSE when read fails.
 */
int mesh_weld_read(mesh_corner_reader read, void *ctx, size_t ntris, int threads,
		   struct mesh **out, struct st_error *err);

/*
 * mesh_builder_finish - hand over the finished mesh (caller frees it with
 * mesh_free) and free the builder.  Returns NULL only on OOM.
 */
struct mesh *mesh_builder_finish(struct mesh_builder *b);

/* mesh_builder_free - abandon a mesh under construction; NULL is safe. */
void mesh_builder_free(struct mesh_builder *b);

/* mesh_free - free a mesh; NULL is safe. */
void mesh_free(struct mesh *m);

/* Axis-aligned bounding box of the vertices; all zero for an empty mesh. */
void mesh_bbox(const struct mesh *m, double min[3], double max[3]);

/*
 * The topology report behind `stratum check` (seed 001 §3, seed 000 §3-4).
 * Edge, component and Euler figures are over the "layer" of the input (seed
 * 000 Def. 3.1): irregular and degenerate triangles and all but one of each
 * set of equivalent triangles are left out there and counted on their own.
 */
enum mesh_reason {
	/* Each of these makes the mesh not printable (Definition 3.11, with
	 * several parts and cavities allowed: docs/check.md). */
	MESH_REASON_EMPTY,		/* no usable triangles */
	MESH_REASON_IRREGULAR,		/* a triangle repeats a vertex */
	MESH_REASON_DEGENERATE,		/* collinear corners (exact test) */
	MESH_REASON_OPEN,		/* a shell with an edge it does not close */
	MESH_REASON_SELF_INTERSECTION,	/* triangles cross or overlap */
	MESH_REASON_MISNESTED,		/* a shell facing out inside a solid, or in outside one */
	/* Warnings: worth knowing, but the file prints as it stands. */
	MESH_REASON_DUPLICATE,		/* equivalent triangles (a layer drops them) */
	MESH_REASON_INCONSISTENT_ORIENTATION,
	MESH_REASON_INSIDE_OUT,		/* closed but negative volume */
	MESH_REASON_SEVERAL_PARTS,	/* more than one part (solid with its cavities) */
	MESH_REASON_NOT_MANIFOLD_CONNECTED, /* shells touching along singular edges */
	MESH_REASON_COUNT
};

/* Reasons below this value block printing; the rest are warnings. */
#define MESH_REASON_FIRST_WARNING MESH_REASON_DUPLICATE

struct mesh_report {
	size_t input_triangles;		/* as read, nothing removed */
	size_t vertices;		/* welded vertices used by the layer */
	size_t edges;
	size_t triangles;		/* the layer: regular, non-degenerate, unique */
	size_t irregular;		/* triangles with a repeated vertex index */
	size_t degenerate;		/* regular but collinear corners */
	size_t duplicates;		/* extra copies of equivalent triangles */
	size_t boundary_edges;		/* one incident triangle */
	size_t singular_edges;		/* more than two incident triangles */
	size_t odd_edges;		/* odd count: boundary or e.g. three triangles */
	size_t nonmanifold_vertices;	/* star is not one disk or half-disk */
	size_t components;		/* edge-connected components (Def. 4.3) */
	size_t manifold_components;	/* shells: joined across 2-connected edges only */
	size_t parts;			/* outward shells, each with the cavities in it */
	size_t cavities;		/* closed shells facing inwards inside a part */
	size_t misnested_shells;	/* facing out inside a part, or in outside all */
	size_t open_singular_edges;	/* singular edges some shell does not close */
	size_t boundary_loops;
	size_t flipped_edges;		/* 2-connected edges walked the same way twice */
	uint64_t self_intersections;	/* intersecting triangle pairs, exact */
	long long euler;		/* V - E + F */
	bool genus_defined;		/* closed, manifold, orientable everywhere */
	long long genus;		/* sum over components of (2 - chi_c) / 2 */
	bool orientable;
	bool consistently_oriented;
	double volume;			/* signed, mm^3, by the divergence theorem */
	double bbox_min[3];		/* of the vertices the layer uses, mm */
	double bbox_max[3];
	bool printable;			/* Definition 3.11 per part (docs/check.md) */
	bool reasons[MESH_REASON_COUNT];
};

/* Short stable code ("boundary_edges") and one-line text for a reason. */
const char *mesh_reason_code(enum mesh_reason r);
const char *mesh_reason_text(enum mesh_reason r);

/*
 * mesh_analyze - fill *rep for m.  threads is how many cores the exact
 * self-intersection pass may use (0 = all available).  Returns 0, or a
 * negative class with err filled (ST_ERR_NOMEM, ST_ERR_INTERNAL).  The mesh is
 * not modified.  The exact pass runs on its own thread beside the topology
 * passes; peak extra memory is about 80 bytes per triangle.
 */
int mesh_analyze(const struct mesh *m, int threads, struct mesh_report *rep,
		 struct st_error *err);

/*
 * mesh_analyze_known - mesh_analyze for a caller that has just counted the
 * self-intersections of exactly this mesh exactly (the repair, whose last
 * refinement proved there are none): self_intersections >= 0 is taken as
 * the count and the exact pass is skipped; -1 runs it as mesh_analyze does.
 */
int mesh_analyze_known(const struct mesh *m, int threads, long long self_intersections,
		       struct mesh_report *rep, struct st_error *err);

/*
 * mesh_analyze_parts - mesh_analyze_known that also numbers the parts:
 * part (m->ntris entries, or NULL) receives each triangle's part,
 * 0..rep->parts-1, a cavity the number of the part around it, and
 * UINT32_MAX for triangles outside the layer (irregular, degenerate,
 * duplicate).  Writing each part to a file of its own gives files that
 * are each printable when the whole is.
 */
int mesh_analyze_parts(const struct mesh *m, int threads, long long self_intersections,
		       struct mesh_report *rep, uint32_t *part, struct st_error *err);

/*
 * mesh_analyze_nesting - mesh_analyze_parts that also tells, for each part
 * p, the part whose cavity holds it: around (m->ntris entries, enough for
 * every part; or NULL) receives that part's number at index p, UINT32_MAX
 * for a part in open space.
 */
int mesh_analyze_nesting(const struct mesh *m, int threads, long long self_intersections,
			 struct mesh_report *rep, uint32_t *part, uint32_t *around,
			 struct st_error *err);

#endif /* STRATUM_REPAIR_MESH_H */
