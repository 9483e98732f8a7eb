/*
 * perimeters_seam.c - where closed walls start: the seam memory carried
 * from layer to layer and the seam vertex of a loop (perimeters_int.h).
 */
#include "perimeters_int.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>

#include "grow.h"

/* A turn of at least this much within one bead width is a corner, degrees. */
#define PERIM_CORNER_DEG 30.0

struct perim_seams *perim_seams_new(unsigned seed)
{
	struct perim_seams *sm = calloc(1, sizeof(*sm));

	if (sm) {
		sm->rng = 0x9E3779B97F4A7C15ull ^ ((uint64_t)seed * 0xBF58476D1CE4E5B9ull);
		if (!sm->rng)
			sm->rng = 1;
	}
	return sm;
}

void perim_seams_free(struct perim_seams *sm)
{
	if (!sm)
		return;
	free(sm->prev);
	free(sm->cur);
	free(sm);
}

static uint64_t next_random(struct perim_seams *sm)
{
	sm->rng ^= sm->rng >> 12;
	sm->rng ^= sm->rng << 25;
	sm->rng ^= sm->rng >> 27;
	return sm->rng * 0x2545F4914F6CDD1Dull;
}

void perim_seams_next_layer(struct perim_seams *sm)
{
	if (!sm->ncur)
		return; /* a layer without loops keeps the older reference */
	int64_t *t = sm->prev;
	size_t cap = sm->capprev;
	sm->prev = sm->cur;
	sm->capprev = sm->capcur;
	sm->nprev = sm->ncur;
	sm->cur = t;
	sm->capcur = cap;
	sm->ncur = 0;
}

int perim_seams_record(struct perim_seams *sm, int64_t x, int64_t y, struct st_error *err)
{
	int64_t *grown = slice_grow(sm->cur, &sm->capcur, sm->ncur + 1, 2 * sizeof(*grown));

	if (!grown)
		return st_error_set(err, ST_ERR_NOMEM, "perimeters: out of memory for seams");
	sm->cur = grown;
	sm->cur[2 * sm->ncur] = x;
	sm->cur[2 * sm->ncur + 1] = y;
	sm->ncur++;
	return 0;
}

/* Signed turn at vertex i of a closed path, radians (> 0 left). */
static double turn_at(const int64_t *xy, size_t n, size_t i)
{
	size_t a = (i + n - 1) % n, b = (i + 1) % n;
	double ux = (double)(xy[2 * i] - xy[2 * a]), uy = (double)(xy[2 * i + 1] - xy[2 * a + 1]);
	double vx = (double)(xy[2 * b] - xy[2 * i]), vy = (double)(xy[2 * b + 1] - xy[2 * i + 1]);
	return atan2(ux * vy - uy * vx, ux * vx + uy * vy);
}

static double edge_len(const int64_t *xy, size_t n, size_t i)
{
	size_t j = (i + 1) % n;
	return sqrt(perim_dist2(xy[2 * i], xy[2 * i + 1], xy[2 * j], xy[2 * j + 1]));
}

/*
 * Corner class of vertex i: 0 concave, 1 convex, 2 smooth.  The turn is
 * summed over the vertices within win nm along the loop, so a corner that
 * the round joins spread over an arc counts as one corner.  With the solid
 * on the left of every loop (outer CCW, holes CW), a right turn is a
 * concave corner of the part, where a seam hides best.
 */
static int corner_class(const int64_t *xy, size_t n, size_t i, double win)
{
	double turn = turn_at(xy, n, i), d = 0.0;

	for (size_t k = 1; k < n / 2; k++) { /* forward */
		d += edge_len(xy, n, (i + k - 1) % n);
		if (d > win)
			break;
		turn += turn_at(xy, n, (i + k) % n);
	}
	d = 0.0;
	for (size_t k = 1; k < n / 2; k++) { /* backward */
		d += edge_len(xy, n, (i + n - k) % n);
		if (d > win)
			break;
		turn += turn_at(xy, n, (i + n - k) % n);
	}
	double lim = PERIM_CORNER_DEG * M_PI / 180.0;
	return turn <= -lim ? 0 : turn >= lim ? 1 : 2;
}

size_t perim_seam_pick(struct perim_seams *sm, enum perim_seam mode, double win,
		       const int64_t *xy, size_t n)
{
	int *cls = malloc(n * sizeof(*cls));
	int best_cls = 2;
	size_t pick = 0, ncand = 0;

	if (!cls)
		return 0; /* no memory for scoring: start where the loop starts */
	for (size_t i = 0; i < n; i++) {
		cls[i] = corner_class(xy, n, i, win);
		if (cls[i] < best_cls)
			best_cls = cls[i];
	}
	for (size_t i = 0; i < n; i++)
		ncand += cls[i] == best_cls;
	int64_t last[2] = {sm->lx, sm->ly};
	const int64_t *ref = NULL;
	size_t nref = 0;
	if (mode == PERIM_SEAM_ALIGNED && sm->nprev) {
		ref = sm->prev;
		nref = sm->nprev;
	} else if (mode == PERIM_SEAM_NEAREST && sm->have_last) {
		ref = last;
		nref = 1;
	}
	if (mode == PERIM_SEAM_RANDOM) {
		size_t k = (size_t)(next_random(sm) % ncand);
		for (size_t i = 0; i < n; i++)
			if (cls[i] == best_cls && k-- == 0) {
				pick = i;
				break;
			}
	} else {
		double bd = INFINITY;
		bool have = false;
		for (size_t i = 0; i < n; i++) {
			if (cls[i] != best_cls)
				continue;
			int64_t x = xy[2 * i], y = xy[2 * i + 1];
			double d;
			if (nref) {
				d = INFINITY;
				for (size_t r = 0; r < nref; r++)
					d = fmin(d, perim_dist2(x, y, ref[2 * r], ref[2 * r + 1]));
			} else {
				/* rearmost: compare (-y, x) lexicographically */
				if (!have || y > xy[2 * pick + 1] ||
				    (y == xy[2 * pick + 1] && x < xy[2 * pick])) {
					pick = i;
					have = true;
				}
				continue;
			}
			if (d < bd) {
				bd = d;
				pick = i;
			}
		}
	}
	free(cls);
	return pick;
}
