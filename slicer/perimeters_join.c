/*
 * perimeters_join.c - where a wall loop's two sides come closer than two
 * beads, the loop ends and a centre-line bead (a thin wall, or a gap fill
 * beyond an inner loop) carries on alone.  Printed apart, the loop's round
 * tip and the bead's round end leave the corners between them empty (a
 * wedge: 0.10 mm^2 a layer).  Here the two sides continue into the bead in
 * one run, as Arachne's transitions do: each side runs diagonally over
 * wall_transition_length to a point on the centre line, from which the
 * bead goes on, and the diagonal beads together carry the flow of one bead
 * as wide as the wall there (perimeters_int.h, perim_join_tips).
 */
#include "perimeters_int.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Pieces of each diagonal, their widths following the wall's thickness. */
#define JOIN_PIECES 3
/* Points of a centre line closer than this to its end give no direction, nm. */
#define JOIN_MIN_STEP 1000.0

/* The frame of a centre line's end E: u along its direction d (towards the
 * loop), v across it, nm. */
struct frame {
	double ex, ey, dx, dy;
};

static double frame_u(const struct frame *f, double x, double y)
{
	return (x - f->ex) * f->dx + (y - f->ey) * f->dy;
}

static double frame_v(const struct frame *f, double x, double y)
{
	return (y - f->ey) * f->dx - (x - f->ex) * f->dy;
}

/* Where the loop first crosses u = cut outwards, walking from vertex i0 one
 * way (dir +1 or -1) at most budget nm: the point, with the width of the
 * segment it lies on, and the vertex beyond it; *steps the segments walked. */
static bool side_cut(const struct toolpath *loop, size_t i0, int dir, const struct frame *f,
		     double cut, double budget, struct path_point *at, size_t *beyond,
		     size_t *steps)
{
	size_t n = loop->n, j = i0;
	double walked = 0;

	for (*steps = 1; *steps < n / 2 && walked <= budget; (*steps)++) {
		size_t nx = dir > 0 ? (j + 1) % n : (j + n - 1) % n;
		const struct path_point *a = &loop->pts[j], *b = &loop->pts[nx];
		double ua = frame_u(f, (double)a->x, (double)a->y);
		double ub = frame_u(f, (double)b->x, (double)b->y);
		if (ua < cut && ub >= cut) {
			double t = (cut - ua) / (ub - ua);
			at->x = llround((double)a->x + t * (double)(b->x - a->x));
			at->y = llround((double)a->y + t * (double)(b->y - a->y));
			at->width = dir > 0 ? a->width : b->width; /* widths run forwards */
			*beyond = nx;
			return true;
		}
		walked += sqrt(perim_dist2(a->x, a->y, b->x, b->y));
		j = nx;
	}
	return false;
}

/* Point s of the line ordered so that the end being joined comes last. */
static const struct path_point *oriented(const struct toolpath *line, bool at_start, size_t s)
{
	return at_start ? &line->pts[line->n - 1 - s] : &line->pts[s];
}

/* Width of the segment from oriented point s to s + 1. */
static int64_t oriented_width(const struct toolpath *line, bool at_start, size_t s)
{
	return at_start ? line->pts[line->n - 2 - s].width : line->pts[s].width;
}

/* Append p to pts[*n], merging it with an equal last point (whose segment
 * is then p's). */
static void push(struct path_point *pts, size_t *n, struct path_point p)
{
	if (*n && pts[*n - 1].x == p.x && pts[*n - 1].y == p.y)
		pts[*n - 1].width = p.width;
	else
		pts[(*n)++] = p;
}

/* The wall's thickness at u along the transition: linear from t0 at u0 to
 * t1 at u1. */
static double thickness(double u, double u0, double t0, double u1, double t1)
{
	return u1 > u0 ? t0 + (t1 - t0) * fmin(fmax((u - u0) / (u1 - u0), 0.0), 1.0) : t1;
}

/* The diagonal from a to b in JOIN_PIECES pieces (b not appended), each as
 * wide as carries half the flow of a bead as thick as the wall at its
 * middle (from tp at P's u = up to tc at the cut's u = uc). */
static void diagonal(const struct perim_join *jp, struct path_point a, struct path_point b,
		     const struct frame *f, double up, double tp, double uc, double tc,
		     struct path_point *pts, size_t *n)
{
	double len = sqrt(perim_dist2(a.x, a.y, b.x, b.y));
	double ua = frame_u(f, (double)a.x, (double)a.y), ub = frame_u(f, (double)b.x, (double)b.y);
	double cosine = len > 1.0 ? fabs(ub - ua) / len : 1.0;

	for (int s = 0; s < JOIN_PIECES; s++) {
		double t = (double)s / JOIN_PIECES, tm = (s + 0.5) / JOIN_PIECES;
		double wall = thickness(ua + tm * (ub - ua), up, tp, uc, tc);
		double w = jp->k + (wall - jp->k) / 2.0 * cosine;
		struct path_point p = {llround((double)a.x + t * (double)(b.x - a.x)),
				       llround((double)a.y + t * (double)(b.y - a.y)),
				       llround(fmax(w, jp->min_width))};
		push(pts, n, p);
	}
}

/*
 * The closed loop and the end of the open centre line (its first point when
 * at_start, else its last) as one open path *out (*nout points, free it):
 * the line to its end E, on to P, diagonally to the loop's cut on one side,
 * around the loop, diagonally back to P.  *nout = 0 when they do not meet
 * at a tip of the loop narrow enough, and steep enough, for a transition.
 */
static int join_one(const struct perim_join *jp, const struct toolpath *loop,
		    const struct toolpath *line, bool at_start, struct path_point **out,
		    size_t *nout, struct st_error *err)
{
	size_t m = line->n, n = loop->n, i0 = 0, ja, jb, sa, sb, cnt, keep, k;
	const struct path_point *e = at_start ? &line->pts[0] : &line->pts[m - 1], *q = NULL;
	double we = (double)(at_start ? line->pts[0].width : line->pts[m - 2].width);
	double best = INFINITY, u0 = 0, wl, cut, va, vb, tc, slope, up, tp;
	struct path_point a, b, pp, *pts;
	struct frame f;

	*nout = 0;
	for (size_t s = 1; s < m && !q; s++) {
		const struct path_point *c = at_start ? &line->pts[s] : &line->pts[m - 1 - s];
		if (perim_dist2(c->x, c->y, e->x, e->y) > JOIN_MIN_STEP * JOIN_MIN_STEP)
			q = c;
	}
	if (!q || n < 4)
		return 0;
	f.ex = (double)e->x;
	f.ey = (double)e->y;
	f.dx = (double)(e->x - q->x);
	f.dy = (double)(e->y - q->y);
	{
		double d = hypot(f.dx, f.dy);
		f.dx /= d;
		f.dy /= d;
	}
	/* The loop's nearest point to E, on the segment from vertex i. */
	for (size_t i = 0; i < n; i++) {
		const struct path_point *p0 = &loop->pts[i], *p1 = &loop->pts[(i + 1) % n];
		double sx = (double)(p1->x - p0->x), sy = (double)(p1->y - p0->y);
		double l2 = sx * sx + sy * sy, t = 0, cx, cy, d2;
		if (l2 > 0)
			t = fmin(
			    fmax((((double)e->x - p0->x) * sx + ((double)e->y - p0->y) * sy) / l2,
				 0.0),
			    1.0);
		cx = (double)p0->x + t * sx;
		cy = (double)p0->y + t * sy;
		d2 = (cx - f.ex) * (cx - f.ex) + (cy - f.ey) * (cy - f.ey);
		if (d2 < best) {
			best = d2;
			i0 = t < 0.5 ? i : (i + 1) % n;
			u0 = frame_u(&f, cx, cy);
		}
	}
	wl = (double)loop->pts[i0].width;
	/* The bead's round end must touch the loop's, ahead of it. */
	if (u0 <= 0 || sqrt(best) > we / 2.0 + wl / 2.0 + jp->reach)
		return 0;
	cut = u0 + wl / 4.0; /* past the loop's round or square tip */
	if (!side_cut(loop, i0, -1, &f, cut, 2.0 * (we + wl), &a, &ja, &sa) ||
	    !side_cut(loop, i0, 1, &f, cut, 2.0 * (we + wl), &b, &jb, &sb) || sa + sb + 2 >= n)
		return 0;
	va = frame_v(&f, (double)a.x, (double)a.y);
	vb = frame_v(&f, (double)b.x, (double)b.y);
	/* A tip: the two sides either side of the line, about a bead apart. */
	if (va * vb >= 0 || fabs(va - vb) > 2.0 * fmax(wl, we) || fabs(va + vb) / 2.0 > wl / 2.0)
		return 0;
	tc = fabs(va - vb) + ((double)a.width + (double)b.width) / 2.0;
	slope = fmax(tc - we, 0.0) / cut;
	if (2.0 * atan(slope / 2.0) > jp->max_angle)
		return 0; /* a wedge this blunt gets no transition */
	/* P, the length of the transition short of the cut; the line is cut
	 * back to it, or carried on to it at its end width. */
	up = cut - jp->length;
	for (keep = m; keep > 0; keep--) {
		const struct path_point *c = oriented(line, at_start, keep - 1);
		if (frame_u(&f, (double)c->x, (double)c->y) < up - JOIN_MIN_STEP)
			break;
	}
	if (keep == 0)
		return 0;
	tp = up > 0 ? thickness(up, 0.0, we, cut, tc) : we;
	pp = (struct path_point){llround(f.ex + up * f.dx), llround(f.ey + up * f.dy), 0};
	cnt = (ja + n - jb) % n + 1;
	pts = malloc((keep + 2 * JOIN_PIECES + cnt + 4) * sizeof(*pts));
	if (!pts)
		return st_error_set(err, ST_ERR_NOMEM,
				    "perimeters: out of memory for a transition");
	k = 0;
	for (size_t s = 0; s < keep; s++) {
		struct path_point c = *oriented(line, at_start, s);
		/* the last kept point's segment runs on to P as wide as the
		 * segment it cuts, or as the line's end */
		c.width = s + 1 < m ? oriented_width(line, at_start, s) : llround(we);
		push(pts, &k, c);
	}
	diagonal(jp, pp, b, &f, up, tp, cut, tc, pts, &k);
	push(pts, &k, b);
	for (size_t s = 0; s < cnt; s++)
		push(pts, &k, loop->pts[(jb + s) % n]);
	diagonal(jp, a, pp, &f, up, tp, cut, tc, pts, &k);
	pp.width = pts[k - 1].width;
	push(pts, &k, pp);
	*out = pts;
	*nout = k;
	return 0;
}

/* A loop's bounding box, nm, grown by its widest bead's half width. */
struct box {
	double x0, y0, x1, y1;
};

static struct box loop_box(const struct toolpath *loop)
{
	struct box b = {INFINITY, INFINITY, -INFINITY, -INFINITY};
	double w = 0;

	for (size_t k = 0; k < loop->n; k++) {
		b.x0 = fmin(b.x0, (double)loop->pts[k].x);
		b.y0 = fmin(b.y0, (double)loop->pts[k].y);
		b.x1 = fmax(b.x1, (double)loop->pts[k].x);
		b.y1 = fmax(b.y1, (double)loop->pts[k].y);
		w = fmax(w, (double)loop->pts[k].width);
	}
	b.x0 -= w / 2.0;
	b.y0 -= w / 2.0;
	b.x1 += w / 2.0;
	b.y1 += w / 2.0;
	return b;
}

/* Whether the line's end (first point when at_start) can touch a loop
 * inside box b: join_one's distance test, against the box. */
static bool end_near(const struct box *b, const struct toolpath *line, bool at_start, double reach)
{
	const struct path_point *e = at_start ? &line->pts[0] : &line->pts[line->n - 1];
	double r =
	    (double)(at_start ? line->pts[0].width : line->pts[line->n - 2].width) / 2.0 + reach;

	return e->x >= b->x0 - r && e->x <= b->x1 + r && e->y >= b->y0 - r && e->y <= b->y1 + r;
}

int perim_join_tips(struct layer_paths *out, size_t first, enum path_role loop_role,
		    enum path_role line_role, const struct perim_join *jp, struct st_error *err)
{
	int rc = 0;

	for (size_t i = first; i < out->n && !rc; i++) {
		struct toolpath *loop = &out->paths[i];
		struct box near;
		if (loop->role != loop_role || !loop->closed)
			continue;
		near = loop_box(loop);
		for (size_t j = first; j < out->n && !rc; j++) {
			struct toolpath *line = &out->paths[j];
			struct path_point *joined = NULL;
			size_t nj = 0;
			if (line->role != line_role || line->closed || line->n < 2)
				continue;
			if (end_near(&near, line, false, jp->reach))
				rc = join_one(jp, loop, line, false, &joined, &nj, err);
			if (!rc && !nj && end_near(&near, line, true, jp->reach))
				rc = join_one(jp, loop, line, true, &joined, &nj, err);
			if (rc || !nj)
				continue;
			free(loop->pts);
			loop->pts = joined;
			loop->n = nj;
			loop->closed = false;
			free(line->pts);
			memmove(line, line + 1, (out->n - j - 1) * sizeof(*line));
			out->n--;
			if (j < i)
				i--;
			break; /* one transition a loop: it is open now */
		}
	}
	return rc;
}
