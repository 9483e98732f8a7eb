/*
 * patterns.c - straight line families and the gyroid cross-section for
 * infill (see patterns.h).
 */
#include "patterns.h"

#include "simplify.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Gyroid samples per period along the sampled axis. */
#define PAT_GYROID_STEPS 48

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
 * The points of the polyline xy (n points) that simplify_mark keeps at
 * PAT_GYROID_TOLERANCE_NM, moved across the curve so each chord encloses
 * no area with it on balance (simplify_balance), into out; returns how
 * many.  Chords with their ends on the curve would be shorter than it: at
 * 75 um the sparse infill printed 0.75 % less line than its curves, 0.26 %
 * more balanced (tests/check_infill.c).
 */
static size_t gyroid_simplify(struct simplify_work *wk, const int64_t *xy, size_t n, bool *keep,
			      int64_t *out, struct st_error *err)
{
	size_t m = 0;

	if (simplify_mark(wk, xy, n, PAT_GYROID_TOLERANCE_NM, keep, err))
		return 0;
	simplify_balance(xy, n, keep, PAT_GYROID_TOLERANCE_NM, out);
	for (size_t k = 0; k < n; k++)
		m += keep[k];
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
	int64_t *xy = malloc(2 * n * sizeof(*xy)), *moved = malloc(2 * n * sizeof(*moved));
	bool *keep = malloc(n * sizeof(*keep));
	struct simplify_work wk = {0};
	int rc = 0;
	if (!xy || !keep || !moved) {
		rc = st_error_set(err, ST_ERR_NOMEM, "infill: out of memory for the gyroid");
		goto out_free;
	}
	for (double m = m0; m <= m1 && !rc; m++)
		for (int sign = -1; sign <= 1 && !rc; sign += 2) {
			gyroid_branch(k, sz, cz, swap, sign, m, t0, dt, n, xy);
			size_t kept = gyroid_simplify(&wk, xy, n, keep, moved, err);
			rc = kept ? clip_paths_add(out, moved, kept, err) : ST_ERR_NOMEM;
		}
out_free:
	simplify_work_free(&wk);
	free(xy);
	free(moved);
	free(keep);
	return rc;
}

/* Append the line from (u0, v0) to (u1, v1), coordinates along and across
 * direction (ca, sa), to out. */
static int add_uv_line(double ca, double sa, double u0, double v0, double u1, double v1,
		       struct clip_paths *out, struct st_error *err)
{
	int64_t xy[4] = {llround(u0 * ca - v0 * sa), llround(u0 * sa + v0 * ca),
			 llround(u1 * ca - v1 * sa), llround(u1 * sa + v1 * ca)};

	return clip_paths_add(out, xy, 2, err);
}

int pat_line_set(const struct clip_paths *ps, double a, double spacing, double osc,
		 struct clip_paths *out, struct st_error *err)
{
	double ca = cos(a), sa = sin(a), vmin, vmax, umin, umax;

	if (!(spacing > 0))
		return st_error_set(err, ST_ERR_ARG, "infill: line spacing %g nm is not positive",
				    spacing);
	if (!clip_paths_points(ps))
		return 0;
	pat_extent(ps, a, &vmin, &vmax);
	pat_extent(ps, a - M_PI / 2.0, &umin, &umax); /* v of a - 90 degrees is u */
	double k0 = ceil((vmin - osc) / spacing), k1 = floor((vmax + osc) / spacing);
	if (k1 - k0 > PAT_MAX_LINES)
		return st_error_set(err, ST_ERR_RANGE,
				    "infill: %.0f lines at spacing %g mm are too many; use a "
				    "lower density or wider lines",
				    k1 - k0 + 1, spacing / 1e6);
	/* v changes by slope per nm along the tilted lines */
	double slope = umax > umin ? -2.0 * osc / (umax - umin) : 0.0;
	int rc = 0;
	for (double k = k0; k <= k1 && !rc; k++) {
		double v = k * spacing, lift = fmod(fabs(k), 2.0) == 1.0 ? osc : 0.0;
		double t = lift ? slope : 0.0;
		rc = add_uv_line(ca, sa, umin - spacing, v + lift - t * spacing, umax + spacing,
				 v + lift + t * (umax - umin + spacing), out, err);
	}
	return rc;
}

double pat_honeycomb_cell(double sp, double S)
{
	return (2.0 * S + sqrt(4.0 * S * S - 3.0 * S * sp)) / 3.0;
}

int pat_honeycomb(double d, double inset, double theta, const struct pat_box *box,
		  struct clip_paths *out, struct st_error *err)
{
	const double hs = 2.0 * d / sqrt(3.0), ys = hs / 2.0, yo = inset / sqrt(3.0);
	const double period = 3.0 * hs, cx = d, cy = hs;
	/* frame: columns along its y; world = C + R(theta - 90 deg) (frame - C) */
	const double cp = cos(theta - M_PI / 2.0), sp = sin(theta - M_PI / 2.0);
	const double wx[4] = {box->x0, box->x1, box->x1, box->x0};
	const double wy[4] = {box->y0, box->y0, box->y1, box->y1};
	double fx0 = INFINITY, fx1 = -INFINITY, fy0 = INFINITY, fy1 = -INFINITY;

	if (!(inset > 0 && d > 2.0 * inset && isfinite(d)))
		return st_error_set(err, ST_ERR_ARG,
				    "infill: honeycomb cell %g nm too small for lines %g nm apart", d,
				    2.0 * inset);
	for (int i = 0; i < 4; i++) {
		double x = cx + (wx[i] - cx) * cp + (wy[i] - cy) * sp;
		double y = cy - (wx[i] - cx) * sp + (wy[i] - cy) * cp;
		fx0 = fmin(fx0, x);
		fx1 = fmax(fx1, x);
		fy0 = fmin(fy0, y);
		fy1 = fmax(fy1, y);
	}
	/* The grid is anchored at the origin, so cells stack from layer to layer. */
	double x0 = floor(fx0 / (2.0 * d)) * 2.0 * d, y0 = floor(fy0 / period) * period;
	double nx = floor((fx1 - x0) / (2.0 * d)) + 1, ny = floor((fy1 - y0) / period) + 1;
	if (nx * ny > PAT_MAX_LINES)
		return st_error_set(err, ST_ERR_RANGE,
				    "infill: %.0f honeycomb cells of %g mm are too many; use a "
				    "lower density or wider lines",
				    nx * ny, d / 1e6);
	size_t npts = 2 * (4 * (size_t)ny + 1);
	double *f = malloc(2 * npts * sizeof(*f));
	int64_t *xy = malloc(2 * npts * sizeof(*xy));
	int rc = 0;
	if (!f || !xy) {
		rc = st_error_set(err, ST_ERR_NOMEM, "infill: out of memory for the honeycomb");
		goto out_free;
	}
	for (double ix = 0; ix < nx && !rc; ix++) {
		double ax0 = x0 + 2.0 * d * ix + inset, ax1 = x0 + 2.0 * d * ix + d - inset;
		size_t m = 0;
		for (int half = 0; half < 2; half++) {
			/* the first column is traced downwards, the mirrored one upwards */
			for (size_t i = 0, j = m - 1; half && i < j; i++, j--)
				for (int c = 0; c < 2; c++) {
					double t = f[2 * i + c];
					f[2 * i + c] = f[2 * j + c];
					f[2 * j + c] = t;
				}
			for (double j = 0; j < ny; j++) {
				double y = y0 + j * period;
				const double px[4] = {ax1, ax0, ax0, ax1};
				const double py[4] = {y + yo, y + ys - yo, y + ys + hs + yo,
						      y + 2.0 * ys + hs - yo};
				for (int q = 0; q < 4; q++, m++) {
					f[2 * m] = px[q];
					f[2 * m + 1] = py[q];
				}
			}
			f[2 * m] = ax1;
			f[2 * m + 1] = y0 + ny * period + yo;
			m++;
			double t = ax0 + d;
			ax0 = ax1 + d;
			ax1 = t;
		}
		for (size_t i = 0; i < m; i++) {
			double x = f[2 * i] - cx, y = f[2 * i + 1] - cy;
			xy[2 * i] = llround(cx + x * cp - y * sp);
			xy[2 * i + 1] = llround(cy + x * sp + y * cp);
		}
		rc = clip_paths_add(out, xy, m, err);
	}
out_free:
	free(f);
	free(xy);
	return rc;
}
