/*
 * simplify.c - Douglas-Peucker polyline simplification with an exact
 * deviation bound (simplify.h).
 */
#include "simplify.h"

#include <math.h>
#include <stdlib.h>

#include "st_grow.h"

double simplify_seg_dist(int64_t px, int64_t py, int64_t ax, int64_t ay, int64_t bx, int64_t by)
{
	double dx = (double)(bx - ax), dy = (double)(by - ay);
	double qx = (double)(px - ax), qy = (double)(py - ay);
	double l2 = dx * dx + dy * dy, t = qx * dx + qy * dy;

	if (l2 <= 0 || t <= 0)
		return hypot(qx, qy);
	if (t >= l2)
		return hypot((double)(px - bx), (double)(py - by));
	return fabs(dx * qy - dy * qx) / sqrt(l2);
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
		for (size_t k = i + 1; k < j; k++) {
			double d = simplify_seg_dist(xy[2 * k], xy[2 * k + 1], xy[2 * i], xy[2 * i + 1],
						     xy[2 * j], xy[2 * j + 1]);
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

void simplify_work_free(struct simplify_work *wk)
{
	if (!wk)
		return;
	free(wk->stack);
	wk->stack = NULL;
	wk->cap = 0;
}
