/*
 * cusp_measure.h - the staircase error of printing a mesh in layers of
 * one height: seed 004's bounding-box method (docs/accuracy.md).
 *
 * 1. An even point cloud on the surface, each point with its facet's
 *    outward normal (surfsample.h, points `spacing` mm apart).
 * 2. The mesh cut by each layer's plane, at the layer's mid-height as
 *    `stratum slice` cuts it (slicer/section.h: the lowest point on the
 *    bed, z = 0; a plane is made while it lies below the top): every facet
 *    the plane crosses gives a segment P1 P2.
 * 3. Two boxes on the segment, one on each side of it: P1 P2 times the
 *    layer height across, in the plane, times the layer from its bottom to
 *    its top in Z.  The printed wall of the layer is the vertical face
 *    through P1 P2; the layer's top and bottom are the box's.
 * 4. For each cloud point in a box (on a facet facing the same side as the
 *    box's facet), a ray along the point's normal or its reverse,
 *    whichever runs towards the wall, to where it leaves the box: that
 *    length is the point's cusp height.  A box's cusp height is the
 *    largest of its points'; the part's maximum is the largest box's, its
 *    mean the mean over the boxes that hold points.
 * 5. Not in the seed: a cloud's best point in a box sits within a spacing
 *    of the box's true largest value, which the cloud alone misses by a
 *    fraction of the spacing; so each box's best point is refined on its
 *    facet by finer and finer grids around it.
 *
 * For a plane surface at angle theta between its normal and Z this gives
 * (h / 2) |cos theta| (the staircase's corners at h / 2 above and below
 * the cutting plane): tests/check_analyze.c finds it within 0.05 % with
 * points h / 4 apart.
 */
#ifndef STRATUM_REPAIR_CUSP_MEASURE_H
#define STRATUM_REPAIR_CUSP_MEASURE_H

#include <stddef.h>

#include "mesh.h"
#include "st_error.h"

/* The cloud's default spacing is the layer height over this: with each
 * box's best point refined, a coarse cloud finds the largest values within
 * a fraction of a per cent (tests/check_analyze.c). */
#define CUSP_MEASURE_POINTS_PER_LAYER 4

/* The most layers one measurement makes. */
#define CUSP_MEASURE_LAYERS_MAX 100000

/* One layer's figures. */
struct cusp_slice {
	double z;     /* mm above the bed: the cutting plane, mid-height of the layer */
	double max;   /* mm: the largest box cusp height, 0 without boxes */
	double mean;  /* mm: mean of the box cusp heights */
	size_t boxes; /* boxes that hold cloud points */
};

/* One box with points: its layer's plane and its cusp height. */
struct cusp_box_value {
	float z;
	float cusp;
};

struct cusp_report {
	double layer_height; /* mm, as asked */
	double spacing;	     /* mm, between cloud points */
	size_t points;	     /* in the cloud */
	size_t nslices;
	struct cusp_slice *slices; /* bottom to top */
	size_t nboxes;		   /* boxes that hold points */
	struct cusp_box_value *boxes;
	double max, mean;	   /* mm, over all those boxes */
	double max_z;		   /* mm: the plane of the largest */
};

/*
 * cusp_measure - fill *r for m (mm; closed and outward, as repair leaves
 * it) printed in layers layer_height mm thick (> 0), the cloud's points
 * spacing mm apart (> 0).  Returns 0, or ST_ERR_ARG (empty mesh),
 * ST_ERR_RANGE (more than CUSP_MEASURE_LAYERS_MAX layers, or a cloud of
 * more than 2^31 points), ST_ERR_NOMEM with err filled; *r is then empty.
 */
int cusp_measure(const struct mesh *m, double layer_height, double spacing,
		 struct cusp_report *r, struct st_error *err);

/* cusp_report_free - free what cusp_measure allocated in r; r stays valid and empty. */
void cusp_report_free(struct cusp_report *r);

#endif /* STRATUM_REPAIR_CUSP_MEASURE_H */
