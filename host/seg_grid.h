/*
 * seg_grid.h - every edge of a set of closed polygons (clip_paths, nm) on a
 * uniform grid of about one edge a cell, for many nearest-edge distance and
 * inside queries (host/region.c measures the printed region's deviation
 * from the model's sections with it).  Units: the paths' (nm).
 */
#ifndef STRATUM_HOST_SEG_GRID_H
#define STRATUM_HOST_SEG_GRID_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "clip.h"

struct seg_grid {
	size_t nseg;
	double *seg;	 /* 4 per segment: x0 y0 x1 y1 */
	double x0, y0;	 /* grid origin */
	double cell;	 /* cell size */
	long nx, ny;
	size_t *start;	 /* nx * ny + 1 */
	uint32_t *items; /* segment indices per cell */
};

/* seg_grid_build - g over every edge of the closed paths ps; 0 or ST_ERR_NOMEM
 * (seg_grid_free frees what was built either way). */
int seg_grid_build(struct seg_grid *g, const struct clip_paths *ps);

void seg_grid_free(struct seg_grid *g);

/* seg_grid_dist - distance from (px, py) to the nearest edge of g; INFINITY
 * when g is empty. */
double seg_grid_dist(const struct seg_grid *g, double px, double py);

/* seg_grid_inside - even-odd inside test of (px, py) against every edge of g. */
bool seg_grid_inside(const struct seg_grid *g, double px, double py);

#endif /* STRATUM_HOST_SEG_GRID_H */
