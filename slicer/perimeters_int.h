/*
 * perimeters_int.h - what the wall generator's parts share: perimeters.c
 * (walls, gap fill, thin walls), perimeters_seam.c (the seam memory and
 * the seam choice) and perimeters_join.c (loops joined to the centre-line
 * beads beyond their tips); nothing else includes it.  The contract is
 * perimeters.h.
 */
#ifndef STRATUM_SLICER_PERIMETERS_INT_H
#define STRATUM_SLICER_PERIMETERS_INT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "perimeters.h"
#include "st_error.h"

struct perim_seams {
	int64_t *prev, *cur;	/* seam points (x, y pairs) of the last and this layer */
	size_t nprev, ncur, capprev, capcur;
	int64_t lx, ly;		/* where the nozzle was left */
	bool have_last;
	uint64_t rng;		/* xorshift64* state, never 0 */
};

/* Squared distance between two points, nm^2. */
static inline double perim_dist2(int64_t ax, int64_t ay, int64_t bx, int64_t by)
{
	double dx = (double)ax - (double)bx, dy = (double)ay - (double)by;
	return dx * dx + dy * dy;
}

/* Start a layer: this layer's seams become the reference of the next. */
void perim_seams_next_layer(struct perim_seams *sm);

/* Remember (x, y) as a seam of this layer; ST_ERR_NOMEM. */
int perim_seams_record(struct perim_seams *sm, int64_t x, int64_t y, struct st_error *err);

/*
 * Seam vertex of a closed loop: among the concave corners if any, else the
 * convex ones, else all vertices, the one nearest the previous layer's
 * seams (aligned), nearest the nozzle (nearest) or a random one; the
 * rearmost (largest y, then smallest x) when there is no reference yet, and
 * always for rear.  A corner's turn is summed over win nm (a bead width)
 * each way along the loop.
 */
size_t perim_seam_pick(struct perim_seams *sm, enum perim_seam mode, double win,
		       const int64_t *xy, size_t n);

/* How a loop's tip and a centre-line bead beyond it are joined, nm. */
struct perim_join {
	double k;	  /* h (1 - pi/4): the flow model's overlap of two beads */
	double min_width; /* the narrowest bead (the layer height) */
	double length;	  /* wall_transition_length: the diagonals' run along the line */
	double max_angle; /* wall_transition_angle, radians: blunter wedges stay apart */
	double reach;	  /* how much farther apart than touching the two ends may be */
};

/*
 * perim_join_tips - in out's paths from first on, each closed loop of
 * loop_role whose tip an open line of line_role ends at (their round ends
 * touching, within reach) becomes one open path: the line up to a point P
 * on its centre line, length short of where the loop's sides are cut (a
 * quarter bead past the tip), a diagonal from P to one side, the loop, a
 * diagonal back to P; the line's path is removed.  The diagonals' widths
 * carry, together, the flow of one bead as thick as the wall (linear from
 * the line's end width to the sides' thickness at the cut), so the joined
 * run prints the flow the single bead and the two sides did.  Only where
 * the sides are either side of the line about a bead apart, and the wall
 * widens no faster than a wedge of max_angle; one join a loop.  Returns 0
 * or ST_ERR_NOMEM.
 */
int perim_join_tips(struct layer_paths *out, size_t first, enum path_role loop_role,
		    enum path_role line_role, const struct perim_join *jp, struct st_error *err);

#endif /* STRATUM_SLICER_PERIMETERS_INT_H */
