/*
 * arcfit.c - arcs fitted to a polyline with an exact bound (arcfit.h).
 *
 * An arc from point i to point j has its centre on the perpendicular
 * bisector of the chord, so that it starts and ends on the polyline's own
 * points; the one free parameter, the centre's offset along the bisector,
 * starts from the circle through the two ends and the point farthest from
 * the chord, and is refined by Gauss-Newton least squares over the
 * vertices and the segments' midpoints (as PrusaSlicer's ArcWelder fits
 * over both, so the arc runs between the polygon's corners and its
 * chords).  Whatever the fit gives is then held to the exact test.
 */
#include "arcfit.h"

#include <math.h>
#include <stdlib.h>

#include "simplify.h"
#include "st_grow.h"

#define GN_STEPS 4     /* Gauss-Newton refinements of the centre */
#define ANGLE_EPS 1e-7 /* rad: the polyline's turning must equal the arc's */

/* Point k of xy, as doubles relative to (cx, cy). */
static inline void rel(const int64_t *xy, size_t k, double cx, double cy, double *x, double *y)
{
	*x = (double)xy[2 * k] - cx;
	*y = (double)xy[2 * k + 1] - cy;
}

double arcfit_deviation(const int64_t *xy, size_t first, size_t last, double cx, double cy,
			bool ccw, double *sweep)
{
	double dir = ccw ? 1 : -1, ax, ay, ex, ey, r, total = 0, dev = 0, s;

	rel(xy, first, cx, cy, &ax, &ay);
	r = hypot(ax, ay);
	if (!(r > 0) || last <= first)
		return INFINITY;
	for (size_t k = first; k < last; k++) {
		double px, py, qx, qy, cr, dx, dy, d2, t;

		if (xy[2 * k] == xy[2 * k + 2] && xy[2 * k + 1] == xy[2 * k + 3])
			continue; /* a segment of no length sweeps nothing */
		rel(xy, k, cx, cy, &px, &py);
		rel(xy, k + 1, cx, cy, &qx, &qy);
		cr = px * qy - py * qx;
		if (!(cr * dir > 0))
			return INFINITY; /* turns back, or runs through the centre */
		total += atan2(cr * dir, px * qx + py * qy);
		dev = fmax(dev, fabs(hypot(qx, qy) - r));
		dx = qx - px;
		dy = qy - py;
		d2 = dx * dx + dy * dy;
		t = -(px * dx + py * dy) / d2; /* the foot of the centre on the segment */
		if (t > 0 && t < 1)
			dev = fmax(dev, fabs(fabs(cr) / sqrt(d2) - r));
	}
	rel(xy, last, cx, cy, &ex, &ey);
	s = atan2((ax * ey - ay * ex) * dir, ax * ex + ay * ey);
	if (s <= 0)
		s += 2 * M_PI;
	if (!(fabs(total - s) <= ANGLE_EPS))
		return INFINITY; /* round more than once, or a polyline of no turn */
	if (sweep)
		*sweep = dir * s;
	return dev;
}

/* Residual and derivative (by t) of point (qx, qy) for the centre
 * m + t n: its distance to the centre less the start's. */
static void residual(double qx, double qy, double cx, double cy, double nx, double ny, double ra,
		     double ga, double *res, double *g)
{
	double dx = qx - cx, dy = qy - cy, rq = hypot(dx, dy);

	*res = rq - ra;
	*g = (rq > 0 ? -(dx * nx + dy * ny) / rq : 0) - ga;
}

/*
 * Fit an arc to the points i .. j into *a; true when it holds the bound
 * within lim (tol less the slack).  Straightness is not judged here.
 */
static bool fit(const int64_t *xy, size_t i, size_t j, double lim, struct arcfit_arc *a)
{
	double ax = (double)xy[2 * i], ay = (double)xy[2 * i + 1];
	double bx = (double)xy[2 * j], by = (double)xy[2 * j + 1];
	double dx = bx - ax, dy = by - ay, len = hypot(dx, dy), far = 0, side = 0;
	double mx = (ax + bx) / 2, my = (ay + by) / 2, nx, ny, t, cx, cy, dev, sweep;
	size_t kf = i;

	if (len < ARCFIT_MIN_CHORD_NM)
		return false;
	nx = -dy / len;
	ny = dx / len;
	for (size_t k = i + 1; k < j; k++) {
		double c = dx * ((double)xy[2 * k + 1] - ay) - dy * ((double)xy[2 * k] - ax);
		if (fabs(c) > far) {
			far = fabs(c);
			side = c;
			kf = k;
		}
	}
	if (kf == i)
		return false; /* every point on the chord's line */
	{
		double px = mx - (double)xy[2 * kf], py = my - (double)xy[2 * kf + 1];
		double den = 2 * (nx * px + ny * py);
		if (den == 0)
			return false;
		t = (len * len / 4 - (px * px + py * py)) / den;
	}
	for (int step = 0; step < GN_STEPS && fabs(t) < ARCFIT_MAX_RADIUS_NM; step++) {
		double num = 0, den = 0, res, g;
		cx = mx + t * nx;
		cy = my + t * ny;
		double ra = hypot(ax - cx, ay - cy), ga = -((ax - cx) * nx + (ay - cy) * ny) / ra;
		for (size_t k = i; k < j; k++) {
			double px = (double)xy[2 * k], py = (double)xy[2 * k + 1];
			double qx = (double)xy[2 * k + 2], qy = (double)xy[2 * k + 3];
			residual((px + qx) / 2, (py + qy) / 2, cx, cy, nx, ny, ra, ga, &res, &g);
			num += res * g;
			den += g * g;
			if (k + 1 < j) {
				residual(qx, qy, cx, cy, nx, ny, ra, ga, &res, &g);
				num += res * g;
				den += g * g;
			}
		}
		if (!(den > 0))
			break;
		t -= num / den;
	}
	cx = mx + t * nx;
	cy = my + t * ny;
	a->radius = hypot(ax - cx, ay - cy);
	if (!(a->radius <= ARCFIT_MAX_RADIUS_NM))
		return false;
	/* Bulging left of the chord, the polyline goes round clockwise. */
	dev = arcfit_deviation(xy, i, j, cx, cy, side < 0, &sweep);
	if (!(dev <= lim))
		return false;
	*a = (struct arcfit_arc){
	    .first = i, .last = j, .cx = cx, .cy = cy, .radius = a->radius, .sweep = sweep};
	return true;
}

/* Whether the chord of points i .. j holds every point within tol. */
static bool straight(const int64_t *xy, size_t i, size_t j, double tol)
{
	for (size_t k = i + 1; k < j; k++)
		if (simplify_seg_dist(xy[2 * k], xy[2 * k + 1], xy[2 * i], xy[2 * i + 1], xy[2 * j],
				      xy[2 * j + 1]) > tol - SIMPLIFY_SLACK_NM)
			return false;
	return true;
}

/* The longest arc from point i (at least to i + 2) into *a, found by
 * doubling the reach while it fits, then halving back; false if none. */
static bool longest(const int64_t *xy, size_t n, size_t i, double lim, struct arcfit_arc *a)
{
	struct arcfit_arc t;
	size_t ok = i + 2, bad = 0, step = 1; /* bad: a reach that does not fit, 0 none yet */

	if (!fit(xy, i, ok, lim, a))
		return false;
	while (!bad && ok + 1 < n) {
		size_t next = ok + step < n ? ok + step : n - 1;
		if (fit(xy, i, next, lim, &t)) {
			*a = t;
			ok = next;
			step *= 2;
		} else {
			bad = next;
		}
	}
	while (bad && bad - ok > 1) {
		size_t mid = ok + (bad - ok) / 2;
		if (fit(xy, i, mid, lim, &t)) {
			*a = t;
			ok = mid;
		} else {
			bad = mid;
		}
	}
	return true;
}

int arcfit_find(struct arcfit_work *wk, const int64_t *xy, size_t n, double tol, size_t *count,
		struct st_error *err)
{
	double lim = tol - ARCFIT_SLACK_NM;
	size_t c = 0;

	*count = 0;
	if (!(lim > 0))
		return 0;
	for (size_t i = 0; i + 2 < n;) {
		struct arcfit_arc a;

		if (!longest(xy, n, i, lim, &a) || straight(xy, a.first, a.last, tol)) {
			i++;
			continue;
		}
		struct arcfit_arc *grown = st_grow(wk->arcs, &wk->cap, c + 1, sizeof(*grown));
		if (!grown)
			return st_error_set(err, ST_ERR_NOMEM, "arc fitting: out of memory");
		wk->arcs = grown;
		wk->arcs[c++] = a;
		i = a.last;
	}
	*count = c;
	return 0;
}

void arcfit_work_free(struct arcfit_work *wk)
{
	if (!wk)
		return;
	free(wk->arcs);
	wk->arcs = NULL;
	wk->cap = 0;
}
