/*
 * perimeters_int.h - what the wall generator's parts share: perimeters.c
 * (walls, gap fill, thin walls) and perimeters_seam.c (the seam memory
 * and the seam choice); nothing else includes it.  The contract is
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

#endif /* STRATUM_SLICER_PERIMETERS_INT_H */
