/*
 * skirt.h - skirt and brim around the first layer (slicer issue item 6).
 *
 * Both are built on the first layer's footprint: the union of the outer
 * contours of its regions (holes are not brimmed or skirted, PrusaSlicer's
 * "outer brim only"), plus the first layer of support when one is given.
 *
 * Brim: brim_loops = ceil(brim_width / s) concentric closed loops around
 * the footprint of the model (not of the support), loop k with its centre
 * line brim_separation + w/2 + k s outside the outline (round joins), so
 * with no separation the first loop's inner edge touches the part; s is
 * the flow spacing of perimeters.h for width w and the first layer's
 * height.  Printed from the outermost loop inwards, as PrusaSlicer does (its
 * maintainers: the outer loops prime the nozzle before the loop touching
 * the part), on layer 0 only.
 *
 * Skirt: skirts closed loops around the footprint grown by the brim, loop k
 * with its centre line skirt_distance + w/2 + k s outside it (PrusaSlicer
 * measures skirt_distance from the brim when there is one), on the first
 * skirt_height layers, outermost first; more loops are added while the
 * loops on layer 0 use less than min_skirt_length mm of filament.  Skirt
 * loops are printed before the brim.
 *
 * Lengths in settings are mm; geometry is nm (toolpath.h).
 */
#ifndef STRATUM_SLICER_SKIRT_H
#define STRATUM_SLICER_SKIRT_H

#include "section.h"
#include "st_error.h"
#include "toolpath.h"

/* Skirt and brim settings (PrusaSlicer key names); skirt_settings_init. */
struct skirt_settings {
	int skirts;		  /* skirt loops, >= 0 (1) */
	double skirt_distance;	  /* mm, gap between skirt and part or brim, >= 0 (6) */
	int skirt_height;	  /* layers carrying the skirt, >= 1 when skirts > 0 (1) */
	double min_skirt_length;  /* mm of filament the skirt uses at least, >= 0 (0) */
	double brim_width;	  /* mm, width of the brim, >= 0 (0: no brim) */
	double brim_separation;	  /* mm, gap between brim and part, >= 0 (0) */
	double extrusion_width;	  /* mm, first-layer bead width (1.125 x nozzle) */
	double filament_diameter; /* mm, for min_skirt_length (1.75) */
	double arc_tolerance;	  /* mm, chord error of the round offsets (0.002) */
};

/* skirt_settings_init - PrusaSlicer's defaults for a nozzle of nozzle_diameter mm. */
void skirt_settings_init(struct skirt_settings *s, double nozzle_diameter);

/*
 * skirt_settings_check - refuse settings that cannot make a skirt or brim:
 * negative counts or lengths, a skirt height below 1 with loops, a width
 * or filament diameter <= 0, an arc tolerance outside (0, w/4].  Returns 0
 * or ST_ERR_ARG / ST_ERR_RANGE with a message naming the setting, its
 * value and what is allowed.
 */
int skirt_settings_check(const struct skirt_settings *s, struct st_error *err);

/*
 * skirt_generate - append the skirt (PATH_SKIRT) and brim (PATH_BRIM)
 * loops to out.
 *   st: the sliced model; its layer 0 is the footprint.
 *   support: support paths (support_generate's output) or NULL; the beads
 *            of its layer 0 join the footprint the skirt goes around.
 *   out: st->n layers (z and height set by the caller); paths are appended
 *        to layers 0 .. min(skirt_height, n) - 1.  out may be support.
 * Nothing is added for an empty stack or an empty first layer.  Returns 0
 * or a negative class with err filled (bad settings, layer counts that do
 * not match, ST_ERR_NOMEM, ST_ERR_INTERNAL); on error out may hold some
 * loops.  Not thread-safe on one out.
 */
int skirt_generate(const struct skirt_settings *s, const struct slice_stack *st,
		   const struct layer_stack *support, struct layer_stack *out,
		   struct st_error *err);

#endif /* STRATUM_SLICER_SKIRT_H */
