/*
 * spiral.h - spiral vase (PrusaSlicer's spiral_vase; private to slicer/,
 * docs/slicing.md "Spiral vase"): what the slicing job changes for it.
 *
 * As in PrusaSlicer: one wall, no top layers and no infill
 * (slicer_config_modes, slicer.h); the bottom layers are sliced and filled as usual, and
 * above them each layer keeps only the outline of its largest island,
 * holes and smaller islands dropped (PrusaSlicer's "largest contour"
 * slicing mode), so its one wall is one loop.  A layer above the bottom
 * ones whose paths are that single closed outer wall and nothing else
 * (no skirt, brim or thin wall on it) is marked spiral, and the G-code
 * writer prints it rising (gcode_writer.h).
 */
#ifndef STRATUM_SLICER_SPIRAL_H
#define STRATUM_SLICER_SPIRAL_H

#include <stdbool.h>
#include <stddef.h>

#include "section.h"
#include "slicer.h"
#include "st_error.h"
#include "toolpath.h"

/*
 * spiral_first_layer - index of the first layer above the bottom layers:
 * at least bottom_solid_layers, and the first whose mid-height reaches
 * bottom_solid_min_thickness (mm); never 0, since layer 0 has no layer
 * below to rise from.  st->n when no layer is above them.
 */
size_t spiral_first_layer(const struct slice_stack *st, int bottom_solid_layers,
			  double bottom_solid_min_thickness);

/*
 * spiral_keep_outline - replace l's regions by the outer contour of its
 * largest island (by area), without holes.  Returns 0 or ST_ERR_NOMEM /
 * ST_ERR_INTERNAL (l unchanged then).
 */
int spiral_keep_outline(struct slice_layer *l, struct st_error *err);

/* spiral_layer_fits - whether m's paths are one closed outer wall and nothing else. */
bool spiral_layer_fits(const struct layer_paths *m);

#endif /* STRATUM_SLICER_SPIRAL_H */
