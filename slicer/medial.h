/*
 * medial.h - centre lines of narrow regions (private to the perimeter
 * generator): where the perimeter offsets leave a strip too narrow for two
 * walls, one bead runs along the strip's medial axis with the strip's local
 * width.
 *
 * Method (no Voronoi diagram): sample the boundary; from every sample p
 * grow the largest disk tangent to the boundary at p that stays inside the
 * region (the "shrinking ball": its centre lies on the inward normal, and
 * its radius is the smallest, over all boundary edges, of the radius of the
 * circle tangent at p through a point of that edge - found in closed form
 * per edge; the edges are binned in a grid and tried ring by ring around p,
 * stopping where the rest are too far to give a smaller circle, since one
 * through a point q has radius at least |pq| / 2).  Such a disk is a
 * maximal inscribed disk, so its centre is a point of the medial axis and
 * its diameter is the local width.  A centre
 * is kept only where the disk's two contacts face each other (the angle
 * between them seen from the centre is at least 135 degrees): that is the
 * strip's centre line, while the branches running into convex corners,
 * whose contacts are on two sides meeting at the corner, are pruned.  Each
 * centre line is found from both sides of the strip; only the side earlier
 * in boundary order keeps it.  Consecutive kept samples form polylines,
 * which are joined end to end, extended along their end direction to where
 * a bead of their end width meets the boundary, and simplified.
 */
#ifndef STRATUM_SLICER_MEDIAL_H
#define STRATUM_SLICER_MEDIAL_H

#include <stdbool.h>
#include <stddef.h>

#include "clip.h"
#include "st_error.h"
#include "toolpath.h"

/* One centre line: points with the bead width that fills the region there. */
struct medial_line {
	bool closed;		/* a loop (a ring-shaped region) */
	size_t n;
	struct path_point *pts; /* owned */
};

struct medial_lines {
	size_t n, cap;
	struct medial_line *v;
};

/*
 * perim_medial_axis - append to out the centre lines of one region piece
 * (contours of one expolygon: outer CCW, holes CW, nm).  Only stretches at
 * least min_width nm wide are kept; step (nm, > 0) is the boundary sampling
 * distance; tol (nm) the simplification tolerance of the output (points
 * and widths).  Returns 0 or ST_ERR_NOMEM / ST_ERR_ARG.  A piece with no
 * stretch longer than its width (a square pillar) has no centre line kept.
 */
int perim_medial_axis(const struct clip_paths *piece, double min_width, double step, double tol,
		      struct medial_lines *out, struct st_error *err);

/* perim_medial_free - free every line of ls and leave it empty; NULL is safe. */
void perim_medial_free(struct medial_lines *ls);

#endif /* STRATUM_SLICER_MEDIAL_H */
