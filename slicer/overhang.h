/*
 * overhang.h - PrusaSlicer's `overhangs = 1` ("detect bridging
 * perimeters"): the parts of a layer's walls whose centre line lies more
 * than half the nozzle's diameter outside the layer below (PrusaSlicer's
 * rule: the nozzle is not wholly supported there) are printed as
 * PATH_OVERHANG_PERIMETER, with bridge flow (a round thread of the
 * nozzle's diameter times the square root of bridge_flow_ratio, or with
 * thick_bridges off the wall's bead, its cross-section times the ratio),
 * and the writer gives them bridge_speed and bridge_fan_speed.  A wall
 * wholly over the layer below is left as it is.
 *
 * The boundary between the pieces is found by sampling each segment every
 * OVERHANG_STEP_NM and cutting midway between two samples that differ, so
 * it is within half a step of the exact crossing.
 * Thread safety: no shared state.
 */
#ifndef STRATUM_SLICER_OVERHANG_H
#define STRATUM_SLICER_OVERHANG_H

#include <stdbool.h>

#include "clip.h"
#include "st_error.h"
#include "toolpath.h"

/* Sample distance along a wall, nm (0.1 mm). */
#define OVERHANG_STEP_NM 100000.0

/* What the overhanging pieces print with. */
struct overhang_settings {
	double nozzle_diameter;	  /* mm */
	bool thick_bridges;	  /* round threads, else the wall's bead scaled */
	double bridge_flow_ratio; /* (0, 2] */
};

/*
 * overhang_split - cut the walls (PATH_OUTER_PERIMETER,
 * PATH_INNER_PERIMETER: closed loops, and the open runs where a loop's tip
 * carries on into its centre-line bead) of layer l, whose solid regions
 * are here, where they leave below (the solid regions of the layer under
 * it, nm) grown by half the nozzle: each wall that does becomes its pieces
 * in order from its start, open paths of its own role (each segment as
 * wide as it was) and of PATH_OVERHANG_PERIMETER (a wall wholly outside
 * stays as it is, of that role).  Other paths and their order are kept.
 * Returns 0, ST_ERR_NOMEM, or Clipper's error; on error l is unchanged.
 */
int overhang_split(struct layer_paths *l, const struct clip_paths *here,
		   const struct clip_paths *below, const struct overhang_settings *s,
		   struct st_error *err);

#endif /* STRATUM_SLICER_OVERHANG_H */
