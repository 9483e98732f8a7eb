/*
 * thicken.h - private to repair/: sheets into thin closed slabs (seed 000
 * §4.2.1).  repair_core.c is the only user.
 */
#ifndef STRATUM_REPAIR_THICKEN_H
#define STRATUM_REPAIR_THICKEN_H

#include <stddef.h>
#include <stdint.h>

#include "st_error.h"

struct thick_out {
	double (*verts)[3];	/* malloc'd; free() the three arrays */
	uint32_t (*tris)[3];
	uint32_t *sheet_ref;	/* per vertex: the sheet vertex it is, or UINT32_MAX */
	size_t nverts, ntris;
	double deviation;	/* largest distance of a new vertex from its own, mm */
	size_t cut_edges;	/* two-triangle edges cut to orient the sheets */
};

/*
 * thicken_sheets - a closed slab of total thickness 2 * half around the n
 * triangles listed in list (indices into tris, corners into verts): the
 * sheet cut where it cannot be offset as one surface (edges that are not
 * shared by exactly two of the listed triangles, creases, non-orientable
 * seams, fans whose normal leans too far), offset to both sides along
 * angle-weighted vertex normals and closed by a wall along every cut and
 * boundary edge.  Every directed edge of the slab occurs as often as its
 * reverse: closed and oriented by construction.  Copies of vertices closer
 * than weld (mm, in every coordinate) are made equal: the caller passes
 * the output's resolution, below which they would be clusters that
 * rounding flips.  Slabs of cut neighbours overlap and may fold where the
 * sheet bends sharply; the caller resolves that exactly.
 * Returns 0 or ST_ERR_NOMEM with err filled.
 */
int thicken_sheets(const double (*verts)[3], const uint32_t (*tris)[3], const uint32_t *list,
		   const uint8_t *free_edges, size_t n, double half, double weld,
		   struct thick_out *out, struct st_error *err);

/*
 * thicken_units - the triangles to thicken for the nsheet sheet triangles
 * listed in sheet (indices into tris, ntris triangles in all): a triangle
 * of before (the list the refinement cut, nbefore long) whose pieces
 * (parent: per triangle of tris, the one it came from; exact_mesh_parents)
 * are all sheet and cover it (whole) comes back once, whole; every other
 * sheet triangle as it is.  parent may be NULL (nothing is grouped).
 * *free_edges: per unit, thicken_sheets' free_edges (a whole triangle's
 * edges are free when none of its pieces' boundary edges is shared).
 * *units and *free_edges are malloc'd.  Returns 0 or ST_ERR_NOMEM.
 */
int thicken_units(const uint32_t (*tris)[3], const uint32_t *sheet, size_t nsheet,
		  const uint32_t *parent, const uint8_t *whole, const uint32_t (*before)[3],
		  size_t nbefore, size_t ntris, uint32_t (**units)[3], uint8_t **free_edges,
		  size_t *nunits, struct st_error *err);

#endif /* STRATUM_REPAIR_THICKEN_H */
