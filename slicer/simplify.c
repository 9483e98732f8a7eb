/*
 * simplify.c - Douglas-Peucker polyline simplification with an exact
 * deviation bound (simplify.h).
 */
#include "simplify.h"

#include <math.h>
#include <stdlib.h>

#include "st_grow.h"

/* Segment a-b with what every distance to it needs, computed once: a
 * Douglas-Peucker pass measures each point of a range against one segment. */
struct seg {
	int64_t ax, ay, bx, by;
	double dx, dy, l2, len;
};

static struct seg seg_make(int64_t ax, int64_t ay, int64_t bx, int64_t by)
{
	double dx = (double)(bx - ax), dy = (double)(by - ay);

	return (struct seg){.ax = ax, .ay = ay, .bx = bx, .by = by, .dx = dx, .dy = dy,
			    .l2 = dx * dx + dy * dy, .len = sqrt(dx * dx + dy * dy)};
}

static double seg_dist(const struct seg *s, int64_t px, int64_t py)
{
	double qx = (double)(px - s->ax), qy = (double)(py - s->ay);
	double t = qx * s->dx + qy * s->dy;

	if (s->l2 <= 0 || t <= 0)
		return hypot(qx, qy);
	if (t >= s->l2)
		return hypot((double)(px - s->bx), (double)(py - s->by));
	return fabs(s->dx * qy - s->dy * qx) / s->len;
}

double simplify_seg_dist(int64_t px, int64_t py, int64_t ax, int64_t ay, int64_t bx, int64_t by)
{
	struct seg s = seg_make(ax, ay, bx, by);

	return seg_dist(&s, px, py);
}

/* Push the range [i, j] onto the work stack. */
static int push_range(struct simplify_work *wk, size_t *top, size_t i, size_t j,
		      struct st_error *err)
{
	if (*top == wk->cap) {
		size_t *grown = st_grow(wk->stack, &wk->cap, *top + 1, 2 * sizeof(*grown));
		if (!grown)
			return st_error_set(err, ST_ERR_NOMEM,
					    "G-code: out of memory simplifying a path");
		wk->stack = grown;
	}
	wk->stack[2 * *top] = i;
	wk->stack[2 * *top + 1] = j;
	(*top)++;
	return 0;
}

/*
 * Iterative rather than recursive: a path of a million points that splits
 * at one end each time would recurse a million deep.
 */
int simplify_mark(struct simplify_work *wk, const int64_t *xy, size_t n, double tol, bool *keep,
		  struct st_error *err)
{
	double lim = tol - SIMPLIFY_SLACK_NM;
	size_t top = 0;
	int rc;

	if (n == 0)
		return 0;
	keep[0] = keep[n - 1] = true;
	if (n <= 2)
		return 0;
	if (!(lim > 0)) {
		for (size_t k = 1; k + 1 < n; k++)
			keep[k] = true;
		return 0;
	}
	rc = push_range(wk, &top, 0, n - 1, err);
	while (rc == 0 && top > 0) {
		size_t i, j, far = 0;
		double dmax = -1;

		top--;
		i = wk->stack[2 * top];
		j = wk->stack[2 * top + 1];
		struct seg s = seg_make(xy[2 * i], xy[2 * i + 1], xy[2 * j], xy[2 * j + 1]);
		for (size_t k = i + 1; k < j; k++) {
			double d = seg_dist(&s, xy[2 * k], xy[2 * k + 1]);
			if (d > dmax) {
				dmax = d;
				far = k;
			}
		}
		if (dmax <= lim) {
			for (size_t k = i + 1; k < j; k++)
				keep[k] = false;
			continue;
		}
		keep[far] = true;
		if (far - i > 1)
			rc = push_range(wk, &top, i, far, err);
		if (rc == 0 && j - far > 1)
			rc = push_range(wk, &top, far, j, err);
	}
	return rc;
}

/* The offset (nm, along the left normal of a-b) that gives segment a-b
 * the area the points xy[i .. j] enclose with it; 0 for no length. */
static double balance_offset(const int64_t *xy, size_t i, size_t j, double *nx, double *ny)
{
	double ax = (double)xy[2 * i], ay = (double)xy[2 * i + 1];
	double dx = (double)(xy[2 * j] - xy[2 * i]), dy = (double)(xy[2 * j + 1] - xy[2 * i + 1]);
	double len = hypot(dx, dy), twice = 0;

	*nx = len > 0 ? -dy / len : 0;
	*ny = len > 0 ? dx / len : 0;
	if (!(len > 0))
		return 0;
	for (size_t k = i; k < j; k++) /* shoelace about a: negative for a bulge to the left */
		twice += ((double)xy[2 * k] - ax) * ((double)xy[2 * k + 3] - ay) -
			 ((double)xy[2 * k + 2] - ax) * ((double)xy[2 * k + 1] - ay);
	return -twice / 2 / len;
}

/*
 * Point p moved for its two segments (unit left normals n0, n1, moved
 * c0, c1) along their bisector, so that it lies (c0 + c1) / 2 off both
 * lines: where the moved lines cross when c0 = c1, and never far along a
 * gentle turn as the crossing of two differently moved lines would be.  A
 * turn sharper than 120 degrees leaves p where it is.
 */
static void meet(double px, double py, double n0x, double n0y, double c0, double n1x, double n1y,
		 double c1, int64_t *out)
{
	double one_cos = 1 + n0x * n1x + n0y * n1y, lambda = 0; /* 1 + cos(turn) */

	if (one_cos > 0.5)
		lambda = (c0 + c1) / (2 * one_cos);
	out[0] = llround(px + lambda * (n0x + n1x));
	out[1] = llround(py + lambda * (n0y + n1y));
}

/* simplify_balance, and simplify_balance_loop when loop: the first point
 * (the last again) moved for the loop's last and first segments. */
static bool balance(const int64_t *xy, size_t n, const bool *keep, double tol, bool loop,
		    int64_t *out)
{
	double lim = tol - SIMPLIFY_SLACK_NM, pnx = 0, pny = 0, pc = 0;
	size_t m = 0;
	bool ok = true;

	if (loop && n > 2) { /* the segment into the seam, from the last kept point */
		size_t last = n - 2;
		while (last > 0 && !keep[last])
			last--;
		pc = balance_offset(xy, last, n - 1, &pnx, &pny);
	}
	for (size_t k = 0; k < n; k++) {
		double nx = 0, ny = 0, c = 0;
		if (!keep[k])
			continue;
		if (k + 1 < n) {
			size_t next = k + 1;
			while (!keep[next])
				next++;
			c = balance_offset(xy, k, next, &nx, &ny);
		}
		if (loop && k + 1 == n && m > 0) {
			out[2 * m] = out[0];
			out[2 * m + 1] = out[1];
		} else if ((k == 0 && !loop) || k + 1 == n) {
			out[2 * m] = xy[2 * k];
			out[2 * m + 1] = xy[2 * k + 1];
		} else {
			meet((double)xy[2 * k], (double)xy[2 * k + 1], pnx, pny, pc, nx, ny, c,
			     out + 2 * m);
		}
		pnx = nx;
		pny = ny;
		pc = c;
		m++;
	}
	/* The bound, on the moved points: every point of the polyline against
	 * the moved segment that replaces it. */
	for (size_t k = 0, j = 0; k + 1 < n && ok; j++) {
		size_t next = k + 1;
		while (!keep[next])
			next++;
		struct seg moved = seg_make(out[2 * j], out[2 * j + 1], out[2 * j + 2], out[2 * j + 3]);
		for (size_t i = k; i <= next && ok; i++)
			ok = seg_dist(&moved, xy[2 * i], xy[2 * i + 1]) <= lim;
		k = next;
	}
	if (ok)
		return m > 2;
	simplify_keep(xy, n, keep, out);
	return false;
}

bool simplify_balance(const int64_t *xy, size_t n, const bool *keep, double tol, int64_t *out)
{
	return balance(xy, n, keep, tol, false, out);
}

bool simplify_balance_loop(const int64_t *xy, size_t n, const bool *keep, double tol,
			   int64_t *out)
{
	return balance(xy, n, keep, tol, true, out);
}

size_t simplify_keep(const int64_t *xy, size_t n, const bool *keep, int64_t *out)
{
	size_t m = 0;
	for (size_t k = 0; k < n; k++)
		if (keep[k]) {
			out[2 * m] = xy[2 * k];
			out[2 * m + 1] = xy[2 * k + 1];
			m++;
		}
	return m;
}

void simplify_work_free(struct simplify_work *wk)
{
	if (!wk)
		return;
	free(wk->stack);
	wk->stack = NULL;
	wk->cap = 0;
}
