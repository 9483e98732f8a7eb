/*
 * heal.h - private to repair/: telling inaccuracies from intended sheets
 * before the exact repair (seed 000 §5.2 made automatic; docs/repair.md,
 * "Healing").
 *
 * Three steps on the input mesh, each reported in struct repair_report:
 *  1. weld vertices closer than opt->weld (default: HEAL_WELD_ULPS float32
 *     ulps of the largest coordinate), the level at which two corners are
 *     one point once written as binary STL;
 *  2. stitch: snap boundary vertices onto the nearest other boundary vertex
 *     within gamma = opt->stitch (default HEAL_STITCH_FACTOR * epsilon),
 *     nearest pairs first, when the two run along a gap (a boundary edge
 *     at each whose far ends are within gamma too), the snap is shorter
 *     than HEAL_STITCH_EDGE of both vertices' shortest edges and no edge
 *     joins the two groups merged, so no edge or triangle collapses;
 *  3. fill: close every boundary loop of a shell with a patch
 *     (repair/exact/holefill.h) when the patches together are at most
 *     HEAL_FILL_FRACTION of the shell's own area; other open shells are left
 *     as they are, and the repair thickens them as sheets.
 * With opt->keep_holes only step 1 runs.
 */
#ifndef STRATUM_REPAIR_HEAL_H
#define STRATUM_REPAIR_HEAL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "mesh.h"
#include "repair.h"
#include "st_error.h"

/* Default weld tolerance, in float32 ulps of the largest |coordinate|. */
#define HEAL_WELD_ULPS 8
/* Default gamma, as a multiple of epsilon (seed 000 §5.2: gamma > epsilon). */
#define HEAL_STITCH_FACTOR 1.5
/* A snap moves a vertex less than this fraction of its shortest edge. */
#define HEAL_STITCH_EDGE 0.5
/* A shell is filled when its patches cover at most this part of its area. */
#define HEAL_FILL_FRACTION 0.25

/*
 * heal_mesh - run the three steps on in.  When any changed something,
 * *out is the healed mesh (caller frees with mesh_free); when nothing
 * changed *out is NULL and the caller goes on with in, so a mesh with
 * nothing to heal is repaired bit for bit as before.  Fills the healing
 * fields of *rep (the rest untouched).  Returns 0, or ST_ERR_ARG (a
 * tolerance that is not finite), ST_ERR_NOMEM, ST_ERR_INTERNAL with err
 * filled and *out NULL.
 */
int heal_mesh(const struct mesh *in, const struct repair_options *opt, struct mesh **out,
	      struct repair_report *rep, struct st_error *err);

/*
 * The working mesh the steps change in place: positions (only vertices
 * some triangle uses matter) and triangles.
 */
struct heal_work {
	double (*verts)[3];
	size_t nverts, cap_verts;
	uint32_t (*tris)[3];
	size_t ntris, cap_tris;
};

/* One undirected edge of a regular triangle: a < b, triangle t. */
struct heal_edge {
	uint32_t a, b, t;
};

/*
 * heal_edges - the edges of w's regular triangles, sorted by (a, b): equal
 * edges are adjacent, so a run of one is a boundary edge.  *edges is
 * malloc'd (caller frees).  Returns 0 or ST_ERR_NOMEM.
 */
int heal_edges(const struct heal_work *w, struct heal_edge **edges, size_t *n,
	       struct st_error *err);

/*
 * heal_fill - step 3 on w: appends the accepted patches to w->tris and
 * fills the hole figures of rep.  Returns 0 or a negative class.
 */
int heal_fill(struct heal_work *w, struct repair_report *rep, struct st_error *err);

#endif /* STRATUM_REPAIR_HEAL_H */
