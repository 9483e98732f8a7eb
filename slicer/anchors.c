/*
 * anchors.c - sparse lines joined and anchored along their boundary
 * (anchors.h).
 */
#include "anchors.h"

#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "st_grow.h"

/* Where a line end meets the boundary. */
struct end {
	size_t contour; /* SIZE_MAX: not on the boundary */
	double s;	/* nm along the contour from its first point */
	long link;	/* the end it is joined to (2 line + side), -1 none */
	bool fwd;	/* the join runs forward along the contour from this end */
	double anchor;	/* nm of anchor along the contour (signed: + forward) */
};

/* A join candidate: consecutive ends along a contour. */
struct cand {
	double gap;
	size_t a, b; /* ends; the boundary runs forward from a to b */
};

/* Gaps this close are equal, nm: parallel lines' ends differ by rounding. */
#define ANCHOR_GAP_TIE_NM 1000.0

/* Shortest first; equal gaps in line order, so that lines given in order
 * across join into one zigzag (each line's free end the next's join). */
static int by_gap(const void *x, const void *y)
{
	const struct cand *p = x, *q = y;
	long long gp = llround(p->gap / ANCHOR_GAP_TIE_NM), gq = llround(q->gap / ANCHOR_GAP_TIE_NM);

	if (gp != gq)
		return gp < gq ? -1 : 1;
	return (p->a > q->a) - (p->a < q->a);
}

/* Union-find over the lines. */
static size_t root(size_t *up, size_t i)
{
	while (up[i] != i)
		i = up[i] = up[up[i]];
	return i;
}

/* Contour lengths: cum[c][k] nm from point 0 to point k, cum[c][m] all. */
struct contours {
	const struct clip_paths *b;
	double **cum;
};

/* The point at s along contour c. */
static void point_at(const struct contours *cs, size_t c, double s, int64_t *x, int64_t *y)
{
	const int64_t *xy = clip_path_xy(cs->b, c);
	size_t m = clip_path_len(cs->b, c);
	double per = cs->cum[c][m];
	size_t k = 0;

	s = fmod(fmod(s, per) + per, per);
	while (k + 1 < m && cs->cum[c][k + 1] <= s)
		k++;
	size_t j = (k + 1) % m;
	double len = cs->cum[c][k + 1] - cs->cum[c][k], t = len > 0 ? (s - cs->cum[c][k]) / len : 0;
	*x = llround((double)xy[2 * k] + t * (double)(xy[2 * j] - xy[2 * k]));
	*y = llround((double)xy[2 * k + 1] + t * (double)(xy[2 * j + 1] - xy[2 * k + 1]));
}

/* Growing point list. */
struct pts {
	int64_t *xy;
	size_t n, cap;
	bool failed;
};

static void put(struct pts *p, int64_t x, int64_t y)
{
	int64_t *g;

	if (p->n && p->xy[2 * p->n - 2] == x && p->xy[2 * p->n - 1] == y)
		return;
	g = st_grow(p->xy, &p->cap, p->n + 1, 2 * sizeof(*g));
	if (!g) {
		p->failed = true;
		return;
	}
	p->xy = g;
	p->xy[2 * p->n] = x;
	p->xy[2 * p->n + 1] = y;
	p->n++;
}

/* The boundary from s0 along contour c for len nm (signed: + forward),
 * s0's own point excluded, into p. */
static void arc(const struct contours *cs, size_t c, double s0, double len, struct pts *p)
{
	size_t m = clip_path_len(cs->b, c);
	const int64_t *xy = clip_path_xy(cs->b, c);
	double per = cs->cum[c][m], dir = len >= 0 ? 1 : -1, todo = fabs(len);
	int64_t x, y;

	s0 = fmod(fmod(s0, per) + per, per);
	/* the contour's vertices strictly between, in walking order: each time
	 * the next one along dir (contours here are short) */
	for (size_t step = 0; step < m; step++) {
		double d;
		size_t v = 0;
		double best = INFINITY;
		for (size_t q = 0; q < m; q++) {
			double dq = dir > 0 ? cs->cum[c][q] - s0 : s0 - cs->cum[c][q];
			dq = fmod(fmod(dq, per) + per, per);
			if (dq > 0 && dq < best) {
				best = dq;
				v = q;
			}
		}
		d = best;
		if (!(d < todo))
			break;
		put(p, xy[2 * v], xy[2 * v + 1]);
		todo -= d;
		s0 = cs->cum[c][v];
	}
	point_at(cs, c, s0 + dir * todo, &x, &y);
	put(p, x, y);
}

/* Line i's points from end side (0: its first point) to the other. */
static void line_pts(const struct clip_paths *l, size_t i, int side, struct pts *p)
{
	const int64_t *xy = clip_path_xy(l, i);
	size_t m = clip_path_len(l, i);

	for (size_t k = 0; k < m; k++) {
		size_t j = side ? m - 1 - k : k;
		put(p, xy[2 * j], xy[2 * j + 1]);
	}
}

/* Where end point (x, y) lies on the boundary, if it does. */
static void locate(const struct contours *cs, int64_t x, int64_t y, struct end *e)
{
	double best = ANCHOR_ON_BOUNDARY_NM;

	e->contour = SIZE_MAX;
	for (size_t c = 0; c < cs->b->n; c++) {
		const int64_t *xy = clip_path_xy(cs->b, c);
		size_t m = clip_path_len(cs->b, c);
		for (size_t k = 0; k < m; k++) {
			size_t j = (k + 1) % m;
			double ax = (double)xy[2 * k], ay = (double)xy[2 * k + 1];
			double dx = (double)xy[2 * j] - ax, dy = (double)xy[2 * j + 1] - ay;
			double l2 = dx * dx + dy * dy;
			double t = l2 > 0 ? ((x - ax) * dx + (y - ay) * dy) / l2 : 0;
			t = fmin(1, fmax(0, t));
			double d = hypot(ax + t * dx - (double)x, ay + t * dy - (double)y);
			if (d < best) {
				best = d;
				e->contour = c;
				e->s = cs->cum[c][k] + t * sqrt(l2);
			}
		}
	}
}

int anchors_connect(const struct clip_paths *boundary, struct clip_paths *lines, double anchor,
		    double max, struct st_error *err)
{
	size_t n = lines->n, ne = 2 * n, nc = 0;
	struct contours cs = {boundary, calloc(boundary->n ? boundary->n : 1, sizeof(double *))};
	struct end *e = calloc(ne ? ne : 1, sizeof(*e));
	size_t *up = malloc((n ? n : 1) * sizeof(*up)), *ord = malloc((ne ? ne : 1) * sizeof(*ord));
	struct cand *cand = malloc((ne ? ne : 1) * sizeof(*cand));
	bool *seen = calloc(n ? n : 1, sizeof(*seen));
	struct clip_paths out = {0};
	struct pts p = {0};
	int rc = 0;

	if (!(max > 0) || !n)
		goto out_free;
	if (!cs.cum || !e || !up || !ord || !cand || !seen) {
		rc = st_error_set(err, ST_ERR_NOMEM, "infill: out of memory joining %zu lines", n);
		goto out_free;
	}
	anchor = fmin(anchor, max);
	for (size_t c = 0; c < boundary->n && !rc; c++) {
		const int64_t *xy = clip_path_xy(boundary, c);
		size_t m = clip_path_len(boundary, c);
		if (!(cs.cum[c] = malloc((m + 1) * sizeof(double)))) {
			rc = st_error_set(err, ST_ERR_NOMEM, "infill: out of memory");
			break;
		}
		cs.cum[c][0] = 0;
		for (size_t k = 0; k < m; k++) {
			size_t j = (k + 1) % m;
			cs.cum[c][k + 1] = cs.cum[c][k] + hypot((double)(xy[2 * j] - xy[2 * k]),
								(double)(xy[2 * j + 1] - xy[2 * k + 1]));
		}
	}
	if (rc)
		goto out_free;
	for (size_t i = 0; i < n; i++) {
		const int64_t *xy = clip_path_xy(lines, i);
		size_t m = clip_path_len(lines, i);
		up[i] = i;
		for (int side = 0; side < 2; side++) {
			struct end *q = &e[2 * i + (size_t)side];
			size_t k = side ? m - 1 : 0;
			locate(&cs, xy[2 * k], xy[2 * k + 1], q);
			q->link = -1;
		}
	}
	/* Per contour, its ends in order; a candidate between each two consecutive. */
	for (size_t c = 0; c < boundary->n; c++) {
		size_t cnt = 0;
		double per = cs.cum[c][clip_path_len(boundary, c)];
		for (size_t q = 0; q < ne; q++)
			if (e[q].contour == c)
				ord[cnt++] = q;
		for (size_t a = 1; a < cnt; a++) /* insertion sort by s */
			for (size_t b = a; b > 0 && e[ord[b]].s < e[ord[b - 1]].s; b--) {
				size_t t = ord[b];
				ord[b] = ord[b - 1];
				ord[b - 1] = t;
			}
		for (size_t k = 0; cnt >= 2 && k < cnt; k++) {
			size_t a = ord[k], b = ord[(k + 1) % cnt];
			double gap = e[b].s - e[a].s + (k + 1 == cnt ? per : 0);
			cand[nc++] = (struct cand){gap, a, b};
		}
		/* anchors: toward the farther neighbour, at most half way */
		for (size_t k = 0; cnt >= 1 && k < cnt; k++) {
			size_t a = ord[k];
			double next = cnt >= 2 ? e[ord[(k + 1) % cnt]].s - e[a].s : per;
			double prev = cnt >= 2 ? e[a].s - e[ord[(k + cnt - 1) % cnt]].s : per;
			next = fmod(next + per, per);
			prev = fmod(prev + per, per);
			if (cnt == 1)
				next = prev = per;
			e[a].anchor = next >= prev ? fmin(anchor, next / 2) : -fmin(anchor, prev / 2);
		}
	}
	qsort(cand, nc, sizeof(*cand), by_gap);
	for (size_t k = 0; k < nc; k++) {
		struct end *a = &e[cand[k].a], *b = &e[cand[k].b];
		size_t la = cand[k].a / 2, lb = cand[k].b / 2;
		if (cand[k].gap > max || a->link >= 0 || b->link >= 0 || root(up, la) == root(up, lb))
			continue;
		a->link = (long)cand[k].b;
		a->fwd = true;
		b->link = (long)cand[k].a;
		b->fwd = false;
		up[root(up, la)] = root(up, lb);
	}
	/* Chains from an end that is not joined: anchor, line, join, line ... */
	for (size_t start = 0; start < ne && !rc; start++) {
		size_t i = start / 2;
		int side = (int)(start % 2);
		if (seen[i] || e[start].link >= 0)
			continue;
		p.n = 0;
		if (e[start].contour != SIZE_MAX && e[start].anchor != 0) {
			int64_t ax, ay;
			point_at(&cs, e[start].contour, e[start].s + e[start].anchor, &ax, &ay);
			put(&p, ax, ay);
			/* back from the anchor's tip to the end */
			arc(&cs, e[start].contour, e[start].s + e[start].anchor, -e[start].anchor, &p);
		}
		for (;;) {
			size_t outi = 2 * i + (size_t)(1 - side);
			seen[i] = true;
			line_pts(lines, i, side, &p);
			if (e[outi].link < 0) {
				if (e[outi].contour != SIZE_MAX && e[outi].anchor != 0)
					arc(&cs, e[outi].contour, e[outi].s, e[outi].anchor, &p);
				break;
			}
			size_t to = (size_t)e[outi].link;
			double gap = e[to].s - e[outi].s;
			double per = cs.cum[e[outi].contour][clip_path_len(boundary, e[outi].contour)];
			gap = fmod(fmod(gap, per) + per, per);
			arc(&cs, e[outi].contour, e[outi].s,
			    e[outi].fwd ? gap : -fmod(per - gap, per), &p);
			i = to / 2;
			side = (int)(to % 2);
			if (seen[i])
				break; /* not reached: joins never close a loop */
		}
		if (p.failed)
			rc = st_error_set(err, ST_ERR_NOMEM, "infill: out of memory joining lines");
		else if (p.n >= 2)
			rc = clip_paths_add(&out, p.xy, p.n, err);
	}
	if (!rc) {
		struct clip_paths t = *lines;
		*lines = out;
		out = t;
	}
out_free:
	for (size_t c = 0; cs.cum && c < boundary->n; c++)
		free(cs.cum[c]);
	free(cs.cum);
	free(e);
	free(up);
	free(ord);
	free(cand);
	free(seen);
	free(p.xy);
	clip_paths_free(&out);
	return rc;
}
