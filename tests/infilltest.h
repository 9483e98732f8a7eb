/*
 * infilltest.h - what the infill suite's files share (check_infill.c,
 * check_infill_solid.c): a mesh sliced with walls and infill, and the area
 * its beads deposit and cover.
 */
#ifndef STRATUM_TESTS_INFILLTEST_H
#define STRATUM_TESTS_INFILLTEST_H

#include <stdbool.h>
#include <stdint.h>

#include "clip.h"
#include "infill.h"
#include "mesh.h"
#include "section.h"
#include "toolpath.h"

#define NM SLICE_UNITS_PER_MM
#define ARC 2000.0 /* nm, chord error of the tests' round offsets */

/* A sliced mesh, its regions inside 2 walls, and the infill of every layer. */
struct run {
	struct slice_stack *st;
	struct clip_expolys *inner;
	struct layer_stack *ls;
};

#define ROLE(r) (1u << (r))
#define SOLID_ROLES                                                                        \
	(ROLE(PATH_BOTTOM_SKIN) | ROLE(PATH_TOP_SKIN) | ROLE(PATH_SOLID_INFILL) |          \
	 ROLE(PATH_GAP_FILL))

/* Slice m at layer height h, walls and infill with is, into *r (run_free). */
void run_infill(const struct mesh *m, double h, const struct infill_settings *is,
		struct run *r);
void run_free(struct run *r);
/*
 * Flow-equivalent area (nm^2) of the paths of role on layer l: length x
 * the bead spacing of their width at height h (perim_spacing), i.e. the
 * deposited volume over h.
 */
double flow_area(const struct layer_paths *l, enum path_role role, double h);
/* Sum of width x length (nm^2) of the paths of role on layer l. */
double bead_area(const struct layer_paths *l, enum path_role role);
/* Area (nm^2) of the region ex. */
double region_area(const struct clip_expolys *ex);
/*
 * Into all, the beads of the paths of the roles in mask on layer l, each
 * its width (or the given width when > 0) wide with ends as end.
 */
void beads_of(const struct layer_paths *l, unsigned mask, double width,
	      enum clip_end end, struct clip_paths *all);
/* Area (nm^2) of the region ps covered by the beads of beads_of(l, ...). */
double covered_paths(const struct layer_paths *l, unsigned mask, double width,
		     enum clip_end end, const struct clip_paths *ps);
/* Area (nm^2) of region covered by the beads of beads_of(l, ...). */
double covered(const struct layer_paths *l, unsigned mask, double width,
	       enum clip_end end, const struct clip_expolys *region);
/* Is (x, y) inside or on the polygon set ps? */
bool inside(const struct clip_paths *ps, int64_t x, int64_t y);
/* Every point of every path of layer l lies in region grown by d nm. */
void assert_inside(const struct layer_paths *l, const struct clip_expolys *region, double d);

#endif
