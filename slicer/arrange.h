/*
 * arrange.h - several models on one bed (docs/slicing.md "Several
 * models"): their footprints packed without overlap around the bed's
 * centre, as PrusaSlicer's arrange lays out a plate.
 *
 * A footprint is the bounding box of a model's XY projection; two
 * footprints end at least the bed's object_distance apart
 * (PrusaSlicer's duplicate_distance, 6 mm).  The largest footprint goes
 * first; each next one is tried beside every one already placed (to its
 * right, left, front and back, aligned with either edge or the centre) and
 * goes where the pile of footprints fills the least of the bed: the
 * smallest max(pile width / room width, pile depth / room depth), then the
 * smallest pile area, then the nearest to the pile's centre.  The room is
 * what the bed leaves around the point the pile is centred on (the bed's
 * centre, or center_x/y): slicer_place centres the merged pile there.
 */
#ifndef STRATUM_SLICER_ARRANGE_H
#define STRATUM_SLICER_ARRANGE_H

#include <stddef.h>

#include "slicer.h"

/* At most this many models on one bed (the packing tries O(n^3) places). */
#define ARRANGE_MAX_ITEMS 256

/* One model's footprint, and where the packing moved it. */
struct arrange_item {
	double min[2], max[2]; /* mm: its bounding box in X and Y, as the model lies */
	double shift[2];       /* out: mm to add to its X and Y (whole nanometres) */
};

/*
 * arrange_footprints - pack the n footprints of it[] for bed (its
 * object_distance, center and size) and fill every it[i].shift.
 * Returns 0, or ST_ERR_RANGE with *failed (may be NULL) = the index of the
 * first footprint, largest first, that finds no place where the pile still
 * fits the room (the message gives its size, the room and the distance;
 * the caller names the model), or ST_ERR_ARG (n is 0 or over
 * ARRANGE_MAX_ITEMS, an empty footprint).
 */
int arrange_footprints(struct arrange_item *it, size_t n, const struct slicer_bed *bed,
		       size_t *failed, struct st_error *err);

/*
 * arrange_overlap - whether two of the n footprints (as they lie, shifts
 * not applied) overlap: their boxes share more than an edge.
 */
bool arrange_overlap(const struct arrange_item *it, size_t n);

#endif /* STRATUM_SLICER_ARRANGE_H */
