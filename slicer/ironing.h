/*
 * ironing.h - where and how a layer is ironed (the infill stage plans
 * it, infill.h; docs/slicing.md "Ironing").
 *
 * PrusaSlicer's ironing (Fill.cpp, Layer::make_ironing): after the top skin
 * the nozzle goes over the same area again at the same Z, along lines
 * ironing_spacing apart at 45 degrees to the skin's, extruding a little
 * (the flow is the writer's, gcode_writer.h).  What is ironed:
 *   top      the layer's top surfaces, its region not under the layer above;
 *   topmost  the same on the last layer only;
 *   solid    all of the layer when it is solid throughout (no bridge, void
 *            or sparse infill of 95 % or less inside its walls), else its
 *            top surfaces, the first layer and its solid infill;
 * top and topmost only with top_solid_layers > 0.  Either way the area is
 * kept half a nozzle inside the layer's outline.
 */
#ifndef STRATUM_SLICER_IRONING_H
#define STRATUM_SLICER_IRONING_H

#include <stdbool.h>
#include <stddef.h>

#include "clip.h"
#include "section.h"
#include "st_error.h"

/* What is ironed, in the order of ironing_type's names (settings.c). */
enum iron_type { IRON_TOP = 0, IRON_TOPMOST, IRON_SOLID };

/* iron_type_parse - the type named name; ST_ERR_ARG naming the accepted ones. */
int iron_type_parse(const char *name, enum iron_type *out, struct st_error *err);

/*
 * iron_area - the area (nm) of layer i of st to iron, into out (replaced).
 *   top_layers: top_solid_layers > 0.
 *   inner: the layer's region inside its walls; solid: the parts of it
 *     filled solid (both read for IRON_SOLID only).
 *   nozzle: mm.
 * Returns 0 or the Clipper bridge's error.
 */
int iron_area(enum iron_type type, bool top_layers, const struct slice_stack *st, size_t i,
	      const struct clip_paths *inner, const struct clip_paths *solid, double nozzle,
	      struct clip_paths *out, struct st_error *err);

/*
 * iron_lines - straight lines of direction a (radians), spacing nm apart,
 * clipped to area, into segs (replaced) as zigzags: a line's end is linked
 * to the nearer end of a line of the next row when they are at most three
 * spacings apart and the link stays inside area (PrusaSlicer's monotonic
 * ironing).  Returns 0, ST_ERR_RANGE (too many lines), ST_ERR_NOMEM.
 */
int iron_lines(const struct clip_paths *area, double a, double spacing, struct clip_paths *segs,
	       struct st_error *err);

#endif /* STRATUM_SLICER_IRONING_H */
