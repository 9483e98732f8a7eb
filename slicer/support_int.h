/*
 * support_int.h - what the support files share (support.h): support.c
 * (settings, contacts, columns), support_lines.c (lines and beads),
 * support_bridge.c (dont_support_bridges) and support_raft.c (the raft).
 */
#ifndef STRATUM_SLICER_SUPPORT_INT_H
#define STRATUM_SLICER_SUPPORT_INT_H

#include "support.h"

/* Everything one support call works with, lengths in nm. */
struct support_ctx {
	const struct support_settings *s;
	const struct slice_stack *st;
	double w, arc, body, xy;
	double sp;    /* the flow spacing of the layer being made (perimeters.h) */
	double angle; /* radians, the lines' direction (support_material_angle) */
	struct st_error *err;
};

/* Regions of layer i as one polygon set (outer CCW, holes CW). */
static inline const struct clip_paths *support_model(const struct support_ctx *c, size_t i)
{
	return &c->st->layers[i].regions.paths;
}

/*
 * support_line_pieces - cut = lines every gap nm on the global grid across
 * R (nm), along angle a (radians; axis 1: a + 90 degrees), clipped to R.
 */
int support_line_pieces(struct support_ctx *c, const struct clip_paths *R, double gap, double a,
			int axis, struct clip_paths *cut);

/*
 * support_fill_lines - the pieces of support_line_pieces at c->angle,
 * joined along R's boundary where the link is at most three lines long,
 * appended to l as role in a zigzag order (every other line reversed).
 */
int support_fill_lines(struct support_ctx *c, const struct clip_paths *R, double gap, int axis,
		       enum path_role role, struct layer_paths *l);

/*
 * support_area_paths - the paths of one support area A (nm) on layer l:
 * its centre region is A shrunk by w/2; interface lines along axis, or the
 * body: a loop around each island (support_material_with_sheath), then
 * the pattern (support_material_pattern: lines along axis, or honeycomb)
 * a spacing inside it, every gap nm, its lines joined along that inner
 * boundary (support_lines.c).
 */
int support_area_paths(struct support_ctx *c, const struct clip_paths *A, bool interface,
		       double gap, int axis, struct layer_paths *l);

/*
 * support_drop_bridges - take the bridges of layer i >= 1 out of its
 * contact area (support.h, dont_support_bridges); contact is replaced.
 */
int support_drop_bridges(struct support_ctx *c, size_t i, struct clip_paths *contact);

#endif /* STRATUM_SLICER_SUPPORT_INT_H */
