/*
 * patterns.c - straight line families and the gyroid cross-section for
 * infill (see patterns.h).
 */
#include "patterns.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Gyroid samples per period along the sampled axis. */
#define PAT_GYROID_STEPS 48
/* Samples closer than this to the chord of their neighbours are dropped, nm:
 * sparse infill needs no finer curve, and the full sampling made 70 % of
 * the G-code moves on the scan model. */
#define PAT_GYROID_TOLERANCE 10000.0

bool pat_box_of(const struct clip_paths *ps, struct pat_box *box)
{
	size_t n = clip_paths_points(ps);

	if (!n)
		return false;
	*box = (struct pat_box){ps->xy[0], ps->xy[1], ps->xy[0], ps->xy[1]};
	for (size_t i = 1; i < n; i++) {
		int64_t x = ps->xy[2 * i], y = ps->xy[2 * i + 1];
		box->x0 = x < box->x0 ? x : box->x0;
		box->x1 = x > box->x1 ? x : box->x1;
		box->y0 = y < box->y0 ? y : box->y0;
		box->y1 = y > box->y1 ? y : box->y1;
	}
	return true;
}

void pat_extent(const struct clip_paths *ps, double a, double *vmin, double *vmax)
{
	double sa = sin(a), ca = cos(a);
	size_t n = clip_paths_points(ps);

	*vmin = INFINITY;
	*vmax = -INFINITY;
	for (size_t i = 0; i < n; i++) {
		double v = -(double)ps->xy[2 * i] * sa + (double)ps->xy[2 * i + 1] * ca;
		*vmin = fmin(*vmin, v);
		*vmax = fmax(*vmax, v);
	}
}

int pat_lines(double a, double spacing, double phase, const struct pat_box *box,
	      struct clip_paths *out, struct st_error *err)
{
	double sa = sin(a), ca = cos(a);
	double umin = INFINITY, umax = -INFINITY, vmin = INFINITY, vmax = -INFINITY;
	const double cx[4] = {box->x0, box->x1, box->x1, box->x0};
	const double cy[4] = {box->y0, box->y0, box->y1, box->y1};

	if (!(spacing > 0))
		return st_error_set(err, ST_ERR_ARG, "infill: line spacing %g nm is not positive",
				    spacing);
	for (int i = 0; i < 4; i++) {
		double u = cx[i] * ca + cy[i] * sa, v = -cx[i] * sa + cy[i] * ca;
		umin = fmin(umin, u);
		umax = fmax(umax, u);
		vmin = fmin(vmin, v);
		vmax = fmax(vmax, v);
	}
	umin -= spacing;
	umax += spacing;
	double k0 = ceil((vmin - phase) / spacing), k1 = floor((vmax - phase) / spacing);
	if (k1 - k0 > PAT_MAX_LINES)
		return st_error_set(err, ST_ERR_RANGE,
				    "infill: %.0f lines at spacing %g mm are too many; use a "
				    "lower density or wider lines",
				    k1 - k0 + 1, spacing / 1e6);
	for (double k = k0; k <= k1; k++) {
		double v = phase + k * spacing;
		int64_t xy[4] = {llround(umin * ca - v * sa), llround(umin * sa + v * ca),
				 llround(umax * ca - v * sa), llround(umax * sa + v * ca)};
		int rc = clip_paths_add(out, xy, 2, err);
		if (rc)
			return rc;
	}
	return 0;
}

/*
 * One sampled branch of the gyroid section: the curve t -> (t, w(t)) with
 * w = phi(t) + sign acos(-c(t) / r(t)) + 2 pi m, where the section reads
 * a cos w + b sin w + c = 0 (see pat_gyroid), phi = atan2(b, a).  swap exchanges the
 * roles of x and y.  Points are appended to xy (2 * n doubles), in nm.
 */
static void gyroid_branch(double k, double sz, double cz, bool swap, double sign, double m,
			  double t0, double dt, size_t n, int64_t *xy)
{
	double prev = 0;

	for (size_t i = 0; i < n; i++) {
		double t = t0 + dt * (double)i, a, b, c;
		if (!swap) { /* sin x cos y + cos z sin y + sin z cos x = 0, solve for y */
			a = sin(t);
			b = cz;
			c = sz * cos(t);
		} else { /* sin z cos x + cos y sin x + sin y cos z = 0, solve for x */
			a = sz;
			b = cos(t);
			c = sin(t) * cz;
		}
		double r = hypot(a, b), q = r > 0 ? -c / r : 0;
		q = fmax(-1.0, fmin(1.0, q));
		/* phi unwrapped: atan2 jumps by 2 pi where b changes sign with a < 0 */
		double phi = atan2(b, a);
		if (i)
			phi += 2 * M_PI * round((prev - phi) / (2 * M_PI));
		prev = phi;
		double w = phi + sign * acos(q) + 2 * M_PI * m;
		double px = swap ? w : t, py = swap ? t : w;
		xy[2 * i] = llround(px / k);
		xy[2 * i + 1] = llround(py / k);
	}
}

/*
 * The point of xy strictly between a and b farthest from the line through
 * them (from point a when they coincide) into *far; returns that distance
 * squared, nm^2 (-1 when there is no point between).
 */
static double farthest(const int64_t *xy, size_t a, size_t b, size_t *far)
{
	double ax = (double)xy[2 * a], ay = (double)xy[2 * a + 1];
	double dx = (double)xy[2 * b] - ax, dy = (double)xy[2 * b + 1] - ay;
	double len2 = dx * dx + dy * dy, best = -1;

	for (size_t i = a + 1; i < b; i++) {
		double px = (double)xy[2 * i] - ax, py = (double)xy[2 * i + 1] - ay;
		double c = px * dy - py * dx;
		double d2 = len2 > 0 ? c * c / len2 : px * px + py * py;
		if (d2 > best) {
			best = d2;
			*far = i;
		}
	}
	return best;
}

/*
 * Keep the points of the polyline xy (n points) that Douglas-Peucker keeps
 * at tolerance tol (first and last always), compacted in place; returns
 * how many.  stack has room for n indices.
 */
static size_t simplify(int64_t *xy, size_t n, double tol, size_t *stack, unsigned char *keep)
{
	size_t top = 0, m = 0;

	if (n < 3)
		return n;
	memset(keep, 0, n);
	keep[0] = keep[n - 1] = 1;
	stack[top++] = 0;
	stack[top++] = n - 1;
	while (top) {
		size_t b = stack[--top], a = stack[--top], far = a;
		if (farthest(xy, a, b, &far) > tol * tol) {
			keep[far] = 1;
			stack[top++] = a;
			stack[top++] = far;
			stack[top++] = far;
			stack[top++] = b;
		}
	}
	for (size_t i = 0; i < n; i++)
		if (keep[i]) {
			xy[2 * m] = xy[2 * i];
			xy[2 * m + 1] = xy[2 * i + 1];
			m++;
		}
	return m;
}

/*
 * The section at height z is a family of curves.  Grouped in y it reads
 * sin x cos y + cos z sin y = -sin z cos x, i.e. r cos(y - phi) = -c with
 * r = hypot(sin x, cos z), phi = atan2(cos z, sin x): when |cos z| >=
 * |sin z|, |c| <= r for every x, so each branch y(x) is one continuous
 * curve across the box.  Otherwise the same holds with x and y exchanged
 * (grouping in x: sin z cos x + cos y sin x = -sin y cos z).  Branches
 * meet where |c| = r; together they trace the closed section.
 */
int pat_gyroid(double k, double z_nm, const struct pat_box *box, struct clip_paths *out,
	       struct st_error *err)
{
	double z = k * z_nm, sz = sin(z), cz = cos(z);
	bool swap = fabs(cz) < fabs(sz);
	double t0 = k * (double)(swap ? box->y0 : box->x0), t1 = k * (double)(swap ? box->y1 : box->x1);
	double w0 = k * (double)(swap ? box->x0 : box->y0), w1 = k * (double)(swap ? box->x1 : box->y1);
	double dt = 2 * M_PI / PAT_GYROID_STEPS;

	if (!(k > 0))
		return st_error_set(err, ST_ERR_ARG, "infill: gyroid scale %g is not positive", k);
	t0 = floor(t0 / dt) * dt - dt;
	double steps = ceil((t1 - t0) / dt) + 2;
	double m0 = floor(w0 / (2 * M_PI)) - 1, m1 = ceil(w1 / (2 * M_PI)) + 1;
	if (steps * (m1 - m0 + 1) > 50.0 * PAT_MAX_LINES)
		return st_error_set(err, ST_ERR_RANGE,
				    "infill: the gyroid period %g mm is too small for a region "
				    "this large; use a lower density or wider lines",
				    2 * M_PI / k / 1e6);
	size_t n = (size_t)steps;
	int64_t *xy = malloc(2 * n * sizeof(*xy));
	/* Each split pushes two ranges and pops one: at most 2 n entries. */
	size_t *stack = malloc(4 * n * sizeof(*stack));
	unsigned char *keep = malloc(n);
	int rc = 0;
	if (!xy || !stack || !keep) {
		rc = st_error_set(err, ST_ERR_NOMEM, "infill: out of memory for the gyroid");
		goto out_free;
	}
	for (double m = m0; m <= m1 && !rc; m++)
		for (int sign = -1; sign <= 1 && !rc; sign += 2) {
			gyroid_branch(k, sz, cz, swap, sign, m, t0, dt, n, xy);
			rc = clip_paths_add(out, xy,
					   simplify(xy, n, PAT_GYROID_TOLERANCE, stack, keep), err);
		}
out_free:
	free(xy);
	free(stack);
	free(keep);
	return rc;
}
