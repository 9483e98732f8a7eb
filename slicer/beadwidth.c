/*
 * beadwidth.c - wall loops whose beads widen into the strips too narrow
 * for gap fill beside them (see beadwidth.h).
 */
#include "beadwidth.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "grow.h"
#include "medial.h"

/* Strips narrower than this are the offsets' rounding, not the wall's, nm. */
#define BEAD_MIN_STRIP_NM 10000.0
/* Samples whose widths differ by at most this print as one segment, nm. */
#define BEAD_WIDTH_TOL_NM 1000.0
/* A strip's far side must cross the ray at least this steeply (45 degrees). */
#define BEAD_MIN_SINE 0.70710678118654752
/* A sample this close to the line of its neighbours is merged into it, nm. */
#define BEAD_MERGE_NM 20.0

/* One contour of a strip: its edges and bounding box, nm. */
struct contour {
	const int64_t *xy;
	size_t n;
	double x0, y0, x1, y1;
};

/* A strip's contours, and the ones near the segment being sampled. */
struct strip {
	struct contour *c;
	size_t n;
	size_t *near, nnear;
};

/* A point of the widened loop before it is written. */
struct spot {
	double x, y;	  /* on the loop's centre line */
	double nx, ny;	  /* unit left normal of its segment (vertices: unused) */
	double gin, gout; /* absorbed strip widths left and right */
	bool vertex;	  /* one of the loop's own vertices */
	size_t seg;	  /* the segment it lies on (a vertex: the one it starts) */
};

static int strip_init(struct strip *s, const struct clip_paths *ps, struct st_error *err)
{
	memset(s, 0, sizeof(*s));
	if (!ps || !ps->n)
		return 0;
	s->c = calloc(ps->n, sizeof(*s->c));
	s->near = calloc(ps->n, sizeof(*s->near));
	if (!s->c || !s->near)
		return st_error_set(err, ST_ERR_NOMEM, "perimeters: out of memory for bead widths");
	for (size_t i = 0; i < ps->n; i++) {
		struct contour *c = &s->c[s->n];
		c->xy = clip_path_xy(ps, i);
		c->n = clip_path_len(ps, i);
		if (c->n < 3)
			continue;
		c->x0 = c->x1 = (double)c->xy[0];
		c->y0 = c->y1 = (double)c->xy[1];
		for (size_t k = 1; k < c->n; k++) {
			c->x0 = fmin(c->x0, (double)c->xy[2 * k]);
			c->x1 = fmax(c->x1, (double)c->xy[2 * k]);
			c->y0 = fmin(c->y0, (double)c->xy[2 * k + 1]);
			c->y1 = fmax(c->y1, (double)c->xy[2 * k + 1]);
		}
		s->n++;
	}
	return 0;
}

static void strip_free(struct strip *s)
{
	free(s->c);
	free(s->near);
}

/* The contours within reach of the segment a-b; returns how many. */
static size_t strip_near(struct strip *s, const double *a, const double *b, double reach)
{
	double x0 = fmin(a[0], b[0]) - reach, x1 = fmax(a[0], b[0]) + reach;
	double y0 = fmin(a[1], b[1]) - reach, y1 = fmax(a[1], b[1]) + reach;

	s->nnear = 0;
	for (size_t i = 0; i < s->n; i++)
		if (!(s->c[i].x1 < x0 || s->c[i].x0 > x1 || s->c[i].y1 < y0 || s->c[i].y0 > y1))
			s->near[s->nnear++] = i;
	return s->nnear;
}

/*
 * The strip's width along the ray from (px, py) in direction (ux, uy): the
 * ray must cross into it first within f->tol of spacing / 2, then the
 * distance to its next crossing; 0 when it does not, or when that is not
 * below gmax (or a sliver below BEAD_MIN_STRIP_NM).
 */
static double strip_width(const struct strip *s, double px, double py, double ux, double uy,
			  const struct bead_fit *f, double gmax)
{
	double edge = f->spacing / 2.0, reach = edge + f->tol + gmax, t1 = INFINITY, t2 = INFINITY;
	double sin1 = 0.0, sin2 = 0.0; /* of the angle between the ray and the edge it crosses */

	for (size_t k = 0; k < s->nnear; k++) {
		const struct contour *c = &s->c[s->near[k]];
		for (size_t i = 0; i < c->n; i++) {
			size_t j = (i + 1) % c->n;
			double ax = (double)c->xy[2 * i], ay = (double)c->xy[2 * i + 1];
			double ex = (double)c->xy[2 * j] - ax, ey = (double)c->xy[2 * j + 1] - ay;
			double den = ux * ey - uy * ex;
			if (den == 0.0)
				continue;
			double wx = ax - px, wy = ay - py;
			double t = (wx * ey - wy * ex) / den; /* along the ray */
			double e = (wx * uy - wy * ux) / den; /* along the edge, [0, 1) */
			if (!(t > 0.0 && t <= reach && e >= 0.0 && e < 1.0))
				continue;
			double sine = fabs(den) / hypot(ex, ey);
			if (t < t1) {
				t2 = t1;
				sin2 = sin1;
				t1 = t;
				sin1 = sine;
			} else if (t < t2) {
				t2 = t;
				sin2 = sine;
			}
		}
	}
	/* The far side must face this one: a ray leaving through a side it
	 * runs along (a strip's end, a corner) measures no width. */
	if (!(fabs(t1 - edge) <= f->tol) || !isfinite(t2) || sin2 < BEAD_MIN_SINE)
		return 0.0;
	double g = t2 - t1;
	return g >= BEAD_MIN_STRIP_NM && g < gmax ? g : 0.0;
}

/* Displacement of a spot: along its normal by (g_in - g_out) / 4. */
static double shift_of(const struct spot *p)
{
	return (p->gin - p->gout) / 4.0;
}

/*
 * Where vertex v moves when the spot before it (on the segment with unit
 * direction u1, normal n1) moves by d1 and the one after it (u2, n2) by
 * d2: the meeting point of the two shifted lines, or the mean of the two
 * shifts where they are nearly parallel or meet far out.
 */
static void corner_shift(const double *u1, double d1, const double *u2, double d2, double *dx,
			 double *dy)
{
	double n1[2] = {-u1[1], u1[0]}, n2[2] = {-u2[1], u2[0]};
	double cr = u1[0] * u2[1] - u1[1] * u2[0];
	double wx = n2[0] * d2 - n1[0] * d1, wy = n2[1] * d2 - n1[1] * d1;
	double lim = 2.0 * fmax(fabs(d1), fabs(d2));

	*dx = (n1[0] * d1 + n2[0] * d2) / 2.0;
	*dy = (n1[1] * d1 + n2[1] * d2) / 2.0;
	if (fabs(cr) < 1e-3)
		return;
	double t = (wx * u2[1] - wy * u2[0]) / cr;
	double mx = n1[0] * d1 + t * u1[0], my = n1[1] * d1 + t * u1[1];
	if (hypot(mx, my) <= lim) {
		*dx = mx;
		*dy = my;
	}
}

/* Unit direction of segment i of the loop. */
static void seg_dir(const int64_t *xy, size_t n, size_t i, double *u)
{
	size_t j = (i + 1) % n;
	double ex = (double)(xy[2 * j] - xy[2 * i]), ey = (double)(xy[2 * j + 1] - xy[2 * i + 1]);
	double len = hypot(ex, ey);

	u[0] = len > 0.0 ? ex / len : 1.0;
	u[1] = len > 0.0 ? ey / len : 0.0;
}

/* Sample the loop, measuring the strips near each segment; spots into *out. */
static int sample_loop(const int64_t *xy, size_t n, struct strip *in, struct strip *outs,
		       const struct bead_fit *f, struct spot **out, size_t *nout, bool *changed,
		       struct st_error *err)
{
	double gmax = fmin(f->gmax, f->spacing);
	double gmax_in = fmin(f->gmax_in > 0.0 ? f->gmax_in : f->gmax, f->spacing);
	double reach = f->spacing / 2.0 + f->tol + fmax(gmax, gmax_in);
	struct spot *sp = NULL;
	size_t cap = 0, m = 0;

	*changed = false;
	for (size_t i = 0; i < n; i++) {
		size_t j = (i + 1) % n;
		double a[2] = {(double)xy[2 * i], (double)xy[2 * i + 1]};
		double b[2] = {(double)xy[2 * j], (double)xy[2 * j + 1]}, u[2];
		double len = hypot(b[0] - a[0], b[1] - a[1]);
		size_t near_in = strip_near(in, a, b, reach), near_out = strip_near(outs, a, b, reach);
		size_t k = near_in + near_out && len > 0.0 ? (size_t)ceil(len / f->step) : 0;
		struct spot *grown = slice_grow(sp, &cap, m + k + 1, sizeof(*sp));

		if (!grown) {
			free(sp);
			return st_error_set(err, ST_ERR_NOMEM, "perimeters: out of memory for bead widths");
		}
		sp = grown;
		sp[m++] = (struct spot){.x = a[0], .y = a[1], .vertex = true, .seg = i};
		seg_dir(xy, n, i, u);
		for (size_t s = 0; s < k; s++) {
			double t = (s + 0.5) / (double)k;
			struct spot *p = &sp[m++];
			*p = (struct spot){.x = a[0] + t * (b[0] - a[0]), .y = a[1] + t * (b[1] - a[1]),
					   .nx = -u[1], .ny = u[0], .seg = i};
			if (near_in)
				p->gin = strip_width(in, p->x, p->y, p->nx, p->ny, f, gmax_in);
			if (near_out)
				p->gout = strip_width(outs, p->x, p->y, -p->nx, -p->ny, f, gmax);
			*changed |= p->gin > 0.0 || p->gout > 0.0;
		}
	}
	*out = sp;
	*nout = m;
	return 0;
}

int bead_fit_loop(const int64_t *xy, size_t n, const struct clip_paths *inside,
		  const struct clip_paths *outside, const struct bead_fit *f,
		  struct path_point **out, size_t *nout, bool *changed, struct st_error *err)
{
	struct strip in, outs;
	struct spot *sp = NULL;
	struct path_point *pts = NULL;
	size_t m = 0, k = 0;
	int rc = strip_init(&in, inside, err);

	if (!rc)
		rc = strip_init(&outs, outside, err);
	else
		memset(&outs, 0, sizeof(outs));
	if (!rc)
		rc = sample_loop(xy, n, &in, &outs, f, &sp, &m, changed, err);
	if (!rc && !(pts = malloc((m ? m : 1) * sizeof(*pts))))
		rc = st_error_set(err, ST_ERR_NOMEM, "perimeters: out of memory for bead widths");
	for (size_t i = 0; i < m && !rc; i++) {
		const struct spot *p = &sp[i], *prev = &sp[(i + m - 1) % m], *next = &sp[(i + 1) % m];
		double dx = 0.0, dy = 0.0, w = f->width;
		if (!*changed) {
			/* Nothing absorbed: the loop as it was. */
		} else if (!p->vertex) {
			dx = p->nx * shift_of(p);
			dy = p->ny * shift_of(p);
			w += (p->gin + p->gout) / 2.0;
		} else {
			double u1[2], u2[2];
			double d1 = prev->vertex ? 0.0 : shift_of(prev), d2 = next->vertex ? 0.0 : shift_of(next);
			seg_dir(xy, n, (p->seg + n - 1) % n, u1);
			seg_dir(xy, n, p->seg, u2);
			if (d1 != 0.0 || d2 != 0.0)
				corner_shift(u1, d1, u2, d2, &dx, &dy);
			if (!next->vertex)
				w += (next->gin + next->gout) / 2.0;
		}
		struct path_point q = {llround(p->x + dx), llround(p->y + dy), llround(w)};
		/* The sample before, in line with its neighbours and as wide as the
		 * point before it, adds nothing. */
		if (k >= 2 && !sp[i - 1].vertex) {
			const struct path_point *a = &pts[k - 2], *b = &pts[k - 1];
			double ex = (double)(q.x - a->x), ey = (double)(q.y - a->y), el = hypot(ex, ey);
			double off = el > 0.0 ? fabs((double)(b->x - a->x) * ey -
						     (double)(b->y - a->y) * ex) / el
					      : 0.0;
			if (off <= BEAD_MERGE_NM && llabs(a->width - b->width) <= BEAD_WIDTH_TOL_NM) {
				pts[k - 1] = q;
				continue;
			}
		}
		pts[k++] = q;
	}
	/* Widths within BEAD_WIDTH_TOL_NM of the run they continue take its
	 * width, so the writer can merge their segments (it never merges
	 * segments of different widths) instead of keeping every sample and
	 * the loop's own short arc segments. */
	for (size_t i = 1, run = 0; i < k && !rc; i++) {
		if (llabs(pts[i].width - pts[run].width) <= BEAD_WIDTH_TOL_NM)
			pts[i].width = pts[run].width;
		else
			run = i;
	}
	free(sp);
	strip_free(&in);
	strip_free(&outs);
	if (rc) {
		free(pts);
		return rc;
	}
	*out = pts;
	*nout = k;
	return 0;
}

int bead_strips(const struct clip_expolys *strip, double gmax, double min_len, double arc,
		struct clip_paths *out, struct st_error *err)
{
	struct clip_paths piece = {0};
	struct medial_lines ml = {0};
	int rc = 0;

	for (size_t i = 0; strip && i < strip->n && !rc; i++) {
		bool narrow = false;
		double area = 0.0;
		rc = clip_expolys_get(strip, i, &piece, err);
		if (!rc)
			rc = clip_paths_area(&piece, &area, err);
		/* A piece as large as a strip gmax wide and min_len long is no
		 * corner's speck: the rays measure it (its medial axis would cost
		 * as much as gap fill's, per layer and wall). */
		narrow = area >= gmax * min_len;
		if (!rc && !narrow)
			rc = perim_medial_axis(&piece, BEAD_MIN_STRIP_NM, fmax(gmax / 8.0, 1000.0), arc,
					       &ml, err);
		for (size_t k = 0; k < ml.n && !narrow; k++) {
			const struct medial_line *l = &ml.v[k];
			double len = 0.0;
			bool below = false;
			for (size_t j = 0; j < l->n; j++) {
				const struct path_point *p = &l->pts[j], *q = &l->pts[(j + 1) % l->n];
				below |= (double)p->width < gmax;
				if (j + 1 < l->n || l->closed)
					len += hypot((double)(q->x - p->x), (double)(q->y - p->y));
			}
			narrow = below && len >= min_len;
		}
		perim_medial_free(&ml);
		if (!rc && narrow)
			rc = clip_paths_append(out, &piece, err);
	}
	clip_paths_free(&piece);
	return rc;
}

int bead_split_line(const struct medial_line *l, double k, double min_width,
		    struct path_point **out, size_t *n, struct st_error *err)
{
	size_t m = l->n;
	struct path_point *q;

	*out = NULL;
	*n = 0;
	if (l->closed || m < 2)
		return 0;
	for (size_t i = 0; i + 1 < m; i++)
		if ((double)l->pts[i].width < min_width)
			return 0;
	q = malloc(2 * m * sizeof(*q));
	if (!q)
		return st_error_set(err, ST_ERR_NOMEM, "perimeters: out of memory for a thin wall");
	for (size_t i = 0; i < m; i++) {
		/* Segment s starts at point s; the last point takes the one before. */
		size_t s = i + 1 < m ? i : i - 1, a = i ? i - 1 : 0, b = i + 1 < m ? i + 1 : i;
		double W = (double)l->pts[s].width, w2 = (W + k) / 2.0, d = (W - k) / 4.0;
		double ux = (double)(l->pts[b].x - l->pts[a].x), uy = (double)(l->pts[b].y - l->pts[a].y);
		double len = hypot(ux, uy), x = (double)l->pts[i].x, y = (double)l->pts[i].y;
		ux = len > 0.0 ? ux / len : 1.0;
		uy = len > 0.0 ? uy / len : 0.0;
		if (i == 0 || i + 1 == m) { /* the ends reach out as the single bead's */
			double e = (W - w2) / 2.0 * (i ? 1.0 : -1.0);
			x += e * ux;
			y += e * uy;
		}
		/* Left on the way out, right on the way back. */
		q[i] = (struct path_point){llround(x - d * uy), llround(y + d * ux), llround(w2)};
		q[2 * m - 1 - i] = (struct path_point){llround(x + d * uy), llround(y - d * ux),
						       llround(i ? (double)(l->pts[i - 1].width + k) / 2.0
								 : w2)};
	}
	*out = q;
	*n = 2 * m;
	return 0;
}
