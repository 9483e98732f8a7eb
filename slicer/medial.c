/*
 * medial.c - centre lines of narrow regions by maximal inscribed disks
 * grown from boundary samples (see medial.h for why this is the medial
 * axis and how its corner branches are pruned).
 */
#include "medial.h"

#include "grow.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* Contacts of a kept disk must subtend at least 135 degrees at its centre. */
#define MEDIAL_COS_MIN_ANGLE (-0.70710678118654752)
/* A centre line's width varies along it, a bead's is constant from one
 * point to the next (toolpath.h): segments are cut so that the width
 * varies by at most this along each piece, which prints its mean, nm. */
#define MEDIAL_WIDTH_STEP 10000.0
/* Most boundary samples per piece; the step grows to stay below it. */
#define MEDIAL_MAX_SAMPLES 2000000.0

/* One boundary edge a->b with the region on its left. */
struct edge {
	double ax, ay, bx, by;
	double nx, ny;	/* unit inward (left) normal */
	double len;
	double pos0;	/* arc length of a along its contour */
	size_t contour;
};

/* A boundary sample and the maximal disk tangent there. */
struct sample {
	double px, py, nx, ny;
	double cx, cy, r;	/* disk centre and radius; r = INFINITY if none */
	size_t contour;
	double pos;
	bool ok;		/* a centre-line point this side keeps */
};

/* A polyline under construction: x, y, width per point (nm, doubles). */
struct line {
	double *p;	/* 3 doubles per point */
	size_t n, cap;
	bool closed;
};

/*
 * Radius of the smallest circle tangent at p (inward normal n) that passes
 * through a point of edge e, or INFINITY if e lies wholly behind p's
 * tangent.  In p's frame (U along the tangent, V along n) that radius is
 * f = (U^2 + V^2) / (2V) for V > 0; along the edge U and V are linear in
 * lambda, and f' = 0 reduces to the quadratic
 * dV L^2 lambda^2 + 2 V0 L^2 lambda + (2 dU U0 V0 + dV (V0^2 - U0^2)) = 0
 * with L^2 = dU^2 + dV^2, so the minimum is at an end or a root.
 */
static double touch(const struct edge *e, double px, double py, double nx, double ny,
		    double *lam_out)
{
	double tx = ny, ty = -nx;
	double U0 = (e->ax - px) * tx + (e->ay - py) * ty;
	double V0 = (e->ax - px) * nx + (e->ay - py) * ny;
	double dU = (e->bx - e->ax) * tx + (e->by - e->ay) * ty;
	double dV = (e->bx - e->ax) * nx + (e->by - e->ay) * ny;
	double l0 = 0.0, l1 = 1.0, best = INFINITY, cand[4];
	int nc = 0;

	if (dV == 0.0) {
		if (V0 <= 0.0)
			return INFINITY;
	} else {
		double lz = -V0 / dV;
		if (dV > 0.0)
			l0 = fmax(l0, lz);
		else
			l1 = fmin(l1, lz);
		if (l0 >= l1)
			return INFINITY;
	}
	cand[nc++] = l0;
	cand[nc++] = l1;
	double L2 = dU * dU + dV * dV;
	double qa = dV * L2, qb = 2.0 * V0 * L2, qc = 2.0 * dU * U0 * V0 + dV * (V0 * V0 - U0 * U0);
	if (qa == 0.0) {
		if (qb != 0.0)
			cand[nc++] = -qc / qb;
	} else {
		double disc = qb * qb - 4.0 * qa * qc;
		if (disc >= 0.0) {
			double sq = sqrt(disc);
			cand[nc++] = (-qb + sq) / (2.0 * qa);
			cand[nc++] = (-qb - sq) / (2.0 * qa);
		}
	}
	for (int i = 0; i < nc; i++) {
		double l = cand[i];
		if (!(l >= l0 && l <= l1))
			continue;
		double U = U0 + l * dU, V = V0 + l * dV;
		if (V <= 0.0)
			continue;
		double f = (U * U + V * V) / (2.0 * V);
		if (f < best) {
			best = f;
			*lam_out = l;
		}
	}
	return best;
}

/* Distance from (x, y) along unit direction (ux, uy) to the first edge hit. */
static double ray_hit(const struct edge *edges, size_t ne, double x, double y, double ux,
		      double uy)
{
	double best = INFINITY;

	for (size_t i = 0; i < ne; i++) {
		const struct edge *e = &edges[i];
		double ex = e->bx - e->ax, ey = e->by - e->ay;
		double den = ux * ey - uy * ex;
		if (den == 0.0)
			continue;
		double wx = e->ax - x, wy = e->ay - y;
		double t = (wx * ey - wy * ex) / den; /* along the ray */
		double s = (wx * uy - wy * ux) / den; /* along the edge */
		if (t > 0.0 && s >= 0.0 && s <= 1.0 && t < best)
			best = t;
	}
	return best;
}

static int line_push(struct line *l, double x, double y, double w, struct st_error *err)
{
	double *grown = slice_grow(l->p, &l->cap, l->n + 1, 3 * sizeof(*grown));

	if (!grown)
		return st_error_set(err, ST_ERR_NOMEM, "medial: out of memory for a centre line");
	l->p = grown;
	l->p[3 * l->n] = x;
	l->p[3 * l->n + 1] = y;
	l->p[3 * l->n + 2] = w;
	l->n++;
	return 0;
}

static void line_reverse(struct line *l)
{
	for (size_t i = 0, j = l->n ? l->n - 1 : 0; i < j; i++, j--)
		for (int k = 0; k < 3; k++) {
			double t = l->p[3 * i + k];
			l->p[3 * i + k] = l->p[3 * j + k];
			l->p[3 * j + k] = t;
		}
}

static double pdist(const double *a, const double *b)
{
	return hypot(a[0] - b[0], a[1] - b[1]);
}

static double line_length(const struct line *l)
{
	double s = 0.0;

	for (size_t i = 1; i < l->n; i++)
		s += pdist(&l->p[3 * (i - 1)], &l->p[3 * i]);
	return s;
}

/* Build the edge table of piece; returns the count or SIZE_MAX on OOM. */
static size_t build_edges(const struct clip_paths *piece, struct edge **out)
{
	size_t total = clip_paths_points(piece), ne = 0;
	struct edge *e = malloc((total ? total : 1) * sizeof(*e));

	*out = e;
	if (!e)
		return SIZE_MAX;
	for (size_t c = 0; c < piece->n; c++) {
		const int64_t *xy = clip_path_xy(piece, c);
		size_t n = clip_path_len(piece, c);
		double pos = 0.0;
		for (size_t i = 0; i < n && n >= 3; i++) {
			size_t j = (i + 1) % n;
			double ax = (double)xy[2 * i], ay = (double)xy[2 * i + 1];
			double bx = (double)xy[2 * j], by = (double)xy[2 * j + 1];
			double len = hypot(bx - ax, by - ay);
			if (len == 0.0)
				continue;
			e[ne++] = (struct edge){.ax = ax, .ay = ay, .bx = bx, .by = by,
						.nx = -(by - ay) / len, .ny = (bx - ax) / len,
						.len = len, .pos0 = pos, .contour = c};
			pos += len;
		}
	}
	return ne;
}

/*
 * The edges binned by their bounding boxes into square cells, so that the
 * disk search of a sample tries the cells around it first, ring by ring,
 * and stops where every edge left is too far to touch a smaller disk: a
 * disk tangent at p through q has radius at least |pq| / 2.  The search
 * finds the same disk as trying every edge (ties to the lowest edge
 * number), in about the time of its neighbourhood: gap fill sweeps
 * pieces with thousands of edges (a 1M-triangle sphere's skins).
 * ncx == 0: no grid, every edge is tried.
 */
struct edge_grid {
	double x0, y0, cell;
	size_t ncx, ncy;
	size_t *start;	/* ncx * ncy + 1 offsets into idx, cell by cell (row-major) */
	size_t *idx;	/* edge numbers */
	size_t *seen;	/* per edge: the sample (+ 1) that last tried it */
};

/* Below this many edges trying them all is as fast as the grid. */
#define MEDIAL_GRID_MIN_EDGES 64
/* About this many cells per edge. */
#define MEDIAL_GRID_CELLS_PER_EDGE 4.0
/* More (edge, cell) entries than this per edge (long edges across a fine
 * grid) and the edges are tried one by one instead. */
#define MEDIAL_GRID_MAX_ENTRIES_PER_EDGE 16
/* Rounding allowance of the distance bound, nm (coordinates are whole nm). */
#define MEDIAL_GRID_SLACK_NM 1.0

/* The cell of coordinate v (from the grid's origin), clamped to [0, n). */
static size_t cell_of(double v, double cell, size_t n)
{
	double k = floor(v / cell);

	if (!(k >= 0.0))
		return 0;
	return k >= (double)n ? n - 1 : (size_t)k;
}

static void edge_cells(const struct edge_grid *g, const struct edge *e, size_t *i0, size_t *i1,
		       size_t *j0, size_t *j1)
{
	*i0 = cell_of(fmin(e->ax, e->bx) - g->x0, g->cell, g->ncx);
	*i1 = cell_of(fmax(e->ax, e->bx) - g->x0, g->cell, g->ncx);
	*j0 = cell_of(fmin(e->ay, e->by) - g->y0, g->cell, g->ncy);
	*j1 = cell_of(fmax(e->ay, e->by) - g->y0, g->cell, g->ncy);
}

static void grid_free(struct edge_grid *g)
{
	free(g->start);
	free(g->idx);
	free(g->seen);
	memset(g, 0, sizeof(*g));
}

/* g over edges[0..ne); without memory or for few edges, no grid (ncx 0):
 * the search then tries every edge, with the same result. */
static void grid_build(struct edge_grid *g, const struct edge *edges, size_t ne)
{
	double x1 = -INFINITY, y1 = -INFINITY, wx, wy, most;
	size_t total = 0, ncells, i0, i1, j0, j1;

	memset(g, 0, sizeof(*g));
	if (ne < MEDIAL_GRID_MIN_EDGES)
		return;
	g->x0 = g->y0 = INFINITY;
	for (size_t i = 0; i < ne; i++) {
		g->x0 = fmin(g->x0, fmin(edges[i].ax, edges[i].bx));
		g->y0 = fmin(g->y0, fmin(edges[i].ay, edges[i].by));
		x1 = fmax(x1, fmax(edges[i].ax, edges[i].bx));
		y1 = fmax(y1, fmax(edges[i].ay, edges[i].by));
	}
	wx = x1 - g->x0;
	wy = y1 - g->y0;
	most = MEDIAL_GRID_CELLS_PER_EDGE * (double)ne;
	g->cell = fmax(sqrt(wx * wy / most), fmax(wx, wy) / most);
	if (!(g->cell > 0.0))
		return;
	g->ncx = (size_t)(wx / g->cell) + 1;
	g->ncy = (size_t)(wy / g->cell) + 1;
	ncells = g->ncx * g->ncy;
	for (size_t i = 0; i < ne; i++) {
		edge_cells(g, &edges[i], &i0, &i1, &j0, &j1);
		total += (i1 - i0 + 1) * (j1 - j0 + 1);
	}
	if (total > MEDIAL_GRID_MAX_ENTRIES_PER_EDGE * ne ||
	    !(g->start = calloc(ncells + 1, sizeof(*g->start))) ||
	    !(g->idx = malloc(total * sizeof(*g->idx))) ||
	    !(g->seen = calloc(ne, sizeof(*g->seen)))) {
		grid_free(g);
		return;
	}
	/* Counts, their running sums (the end of each cell), then each edge
	 * placed before its cell's end: start[c] ends as the cell's first. */
	for (size_t i = 0; i < ne; i++) {
		edge_cells(g, &edges[i], &i0, &i1, &j0, &j1);
		for (size_t j = j0; j <= j1; j++)
			for (size_t k = i0; k <= i1; k++)
				g->start[j * g->ncx + k]++;
	}
	for (size_t c = 1; c < ncells; c++)
		g->start[c] += g->start[c - 1];
	g->start[ncells] = total;
	for (size_t i = 0; i < ne; i++) {
		edge_cells(g, &edges[i], &i0, &i1, &j0, &j1);
		for (size_t j = j0; j <= j1; j++)
			for (size_t k = i0; k <= i1; k++)
				g->idx[--g->start[j * g->ncx + k]] = i;
	}
}

/* The smallest disk tangent at s so far: edge i tried, ties to the lowest i. */
struct disk_best {
	double r, lam;
	size_t partner;
};

static void try_edge(const struct edge *edges, size_t i, const struct sample *s,
		     struct disk_best *b)
{
	double l = 0.0, f = touch(&edges[i], s->px, s->py, s->nx, s->ny, &l);

	if (f < b->r || (f == b->r && isfinite(f) && i < b->partner)) {
		b->r = f;
		b->lam = l;
		b->partner = i;
	}
}

/* The cells at Chebyshev distance r from cell (ci, cj), their edges tried
 * once per sample (stamp). */
static void try_ring(const struct edge_grid *g, const struct edge *edges, size_t own,
		     size_t stamp, size_t ci, size_t cj, size_t r, const struct sample *s,
		     struct disk_best *b)
{
	size_t ilo = ci >= r ? ci - r : 0, ihi = ci + r < g->ncx ? ci + r : g->ncx - 1;
	size_t jlo = cj >= r ? cj - r : 0, jhi = cj + r < g->ncy ? cj + r : g->ncy - 1;

	for (size_t j = jlo; j <= jhi; j++) {
		bool row_edge = j + r == cj || j == cj + r;
		for (size_t i = ilo; i <= ihi; i++) {
			if (!row_edge && i + r != ci && i != ci + r) {
				i = ci + r - 1; /* jump over the inside of the ring */
				continue;
			}
			for (size_t k = g->start[j * g->ncx + i]; k < g->start[j * g->ncx + i + 1]; k++) {
				size_t e = g->idx[k];
				if (e == own || g->seen[e] == stamp)
					continue;
				g->seen[e] = stamp;
				try_edge(edges, e, s, b);
			}
		}
	}
}

/* The smallest disk tangent at sample s (number stamp - 1) through any edge
 * but its own. */
static void nearest_disk(const struct edge_grid *g, const struct edge *edges, size_t ne,
			 size_t own, size_t stamp, const struct sample *s, struct disk_best *b)
{
	*b = (struct disk_best){.r = INFINITY, .partner = SIZE_MAX};
	if (!g->ncx) {
		for (size_t i = 0; i < ne; i++)
			if (i != own)
				try_edge(edges, i, s, b);
		return;
	}
	size_t ci = cell_of(s->px - g->x0, g->cell, g->ncx);
	size_t cj = cell_of(s->py - g->y0, g->cell, g->ncy);
	for (size_t r = 0;; r++) {
		if (r > 0) {
			/* Every cell not yet tried lies beyond the block of rings
			 * 0..r-1: at least this far from the sample. */
			double d = INFINITY;
			if (ci >= r)
				d = fmin(d, s->px - (g->x0 + (double)(ci - r + 1) * g->cell));
			if (ci + r < g->ncx)
				d = fmin(d, g->x0 + (double)(ci + r) * g->cell - s->px);
			if (cj >= r)
				d = fmin(d, s->py - (g->y0 + (double)(cj - r + 1) * g->cell));
			if (cj + r < g->ncy)
				d = fmin(d, g->y0 + (double)(cj + r) * g->cell - s->py);
			if (d == INFINITY || (d - MEDIAL_GRID_SLACK_NM) / 2.0 > b->r)
				return;
		}
		try_ring(g, edges, own, stamp, ci, cj, r, s, b);
	}
}

/*
 * The maximal disk tangent at sample s (number stamp - 1) and whether its
 * centre is kept: contacts facing each other, wide enough, and this side
 * the earlier one in boundary order (contour, then arc length) so each
 * line is found once.
 */
static void grow_disk(const struct edge_grid *g, const struct edge *edges, size_t ne,
		      size_t own, size_t stamp, struct sample *s, double min_width)
{
	struct disk_best b;

	nearest_disk(g, edges, ne, own, stamp, s, &b);
	double best = b.r, lam = b.lam;
	size_t partner = b.partner;
	s->r = best;
	s->ok = false;
	if (partner == SIZE_MAX || !isfinite(best))
		return;
	const struct edge *q = &edges[partner];
	double qx = q->ax + lam * (q->bx - q->ax), qy = q->ay + lam * (q->by - q->ay);
	s->cx = s->px + best * s->nx;
	s->cy = s->py + best * s->ny;
	double cosang = ((s->px - s->cx) * (qx - s->cx) + (s->py - s->cy) * (qy - s->cy)) /
			(best * best);
	double qpos = q->pos0 + lam * q->len;
	bool first = s->contour < q->contour || (s->contour == q->contour && s->pos < qpos);
	s->ok = cosang <= MEDIAL_COS_MIN_ANGLE && 2.0 * best >= min_width && first;
}

/* Append to lines the runs of kept samples of one contour, samples[0..n). */
static int contour_runs(const struct sample *smp, size_t n, double jump, struct line **lines,
			size_t *nl, size_t *capl, struct st_error *err)
{
	size_t start = 0;
	bool all = true;

	for (size_t i = 0; i < n; i++)
		if (!smp[i].ok) {
			start = i;
			all = false;
			break;
		}
	struct line cur = {0};
	for (size_t k = 0; k <= n; k++) {
		const struct sample *s = &smp[(start + k) % n];
		bool keep = k < n && s->ok;
		if (keep && cur.n) {
			const double *last = &cur.p[3 * (cur.n - 1)];
			if (hypot(s->cx - last[0], s->cy - last[1]) > jump)
				keep = false, k--; /* close this run; revisit s */
		}
		if (keep) {
			int rc = line_push(&cur, s->cx, s->cy, 2.0 * s->r, err);
			if (rc) {
				free(cur.p);
				return rc;
			}
			continue;
		}
		if (cur.n >= 2) {
			struct line *grown = slice_grow(*lines, capl, *nl + 1, sizeof(*grown));
			if (!grown) {
				free(cur.p);
				return st_error_set(err, ST_ERR_NOMEM, "medial: out of memory");
			}
			*lines = grown;
			(*lines)[(*nl)++] = cur;
		} else {
			free(cur.p);
		}
		cur = (struct line){0};
		if (k == n)
			break;
	}
	/* Every sample kept and continuous all round: a loop (a ring's centre). */
	if (all && *nl && n >= 3) {
		struct line *l = &(*lines)[*nl - 1];
		if (l->n == n && pdist(&l->p[0], &l->p[3 * (l->n - 1)]) <= jump)
			l->closed = true;
	}
	return 0;
}

/* Join open lines whose ends are within dmax, nearest pairs first. */
static int join_lines(struct line *ls, size_t *nl, double dmax, struct st_error *err)
{
	for (;;) {
		double bd = dmax;
		size_t bi = 0, bj = 0;
		int bend = -1;
		for (size_t i = 0; i < *nl; i++)
			for (size_t j = i + 1; j < *nl; j++) {
				if (ls[i].closed || ls[j].closed)
					continue;
				/* end: bit 1 = i's start, bit 0 = j's end */
				for (int k = 0; k < 4; k++) {
					const double *a = &ls[i].p[k & 2 ? 0 : 3 * (ls[i].n - 1)];
					const double *b = &ls[j].p[k & 1 ? 3 * (ls[j].n - 1) : 0];
					double d = pdist(a, b);
					if (d <= bd) {
						bd = d;
						bi = i;
						bj = j;
						bend = k;
					}
				}
			}
		if (bend < 0)
			return 0;
		struct line *a = &ls[bi], *b = &ls[bj];
		if (bend & 2)
			line_reverse(a); /* now a ends where it started */
		if (bend & 1)
			line_reverse(b); /* now b starts at the joined end */
		for (size_t k = 0; k < b->n; k++) {
			int rc = line_push(a, b->p[3 * k], b->p[3 * k + 1], b->p[3 * k + 2], err);
			if (rc)
				return rc;
		}
		free(b->p);
		ls[bj] = ls[--*nl];
	}
}

/*
 * Lengthen an open line at its end (the last point) along its last
 * direction up to where a bead of the end width touches the boundary,
 * by at most cap: the runs stop up to one sample short of the true end
 * of the centre line.
 */
static int extend_end(struct line *l, const struct edge *edges, size_t ne, double cap,
		      struct st_error *err)
{
	const double *a = &l->p[3 * (l->n - 2)], *b = &l->p[3 * (l->n - 1)];
	double len = pdist(a, b);

	if (len == 0.0)
		return 0;
	double ux = (b[0] - a[0]) / len, uy = (b[1] - a[1]) / len;
	double ext = fmin(ray_hit(edges, ne, b[0], b[1], ux, uy) - b[2] / 2.0, cap);
	if (!(ext > 0.0))
		return 0;
	return line_push(l, b[0] + ext * ux, b[1] + ext * uy, b[2], err);
}

/*
 * Douglas-Peucker on points [i0, i1] of l, marking kept points in keep[]:
 * a point may go when both its distance to the chord and its width's
 * difference from the interpolated width are within tol.
 */
static int simplify(const struct line *l, size_t i0, size_t i1, double tol, bool *keep,
		    struct st_error *err)
{
	size_t *stack = malloc(2 * (l->n + 1) * sizeof(*stack)), top = 0;

	if (!stack)
		return st_error_set(err, ST_ERR_NOMEM, "medial: out of memory simplifying");
	stack[top++] = i0;
	stack[top++] = i1;
	while (top) {
		size_t b = stack[--top], a = stack[--top];
		const double *pa = &l->p[3 * a], *pb = &l->p[3 * b];
		double dx = pb[0] - pa[0], dy = pb[1] - pa[1], len = hypot(dx, dy);
		double worst = -1.0;
		size_t wi = a;
		for (size_t k = a + 1; k < b; k++) {
			const double *pk = &l->p[3 * k];
			double t = len > 0.0 ? ((pk[0] - pa[0]) * dx + (pk[1] - pa[1]) * dy) / (len * len)
					     : 0.0;
			t = fmin(1.0, fmax(0.0, t));
			double ex = hypot(pa[0] + t * dx - pk[0], pa[1] + t * dy - pk[1]);
			double ew = fabs(pa[2] + t * (pb[2] - pa[2]) - pk[2]) / 2.0;
			double e = fmax(ex, ew);
			if (e > worst) {
				worst = e;
				wi = k;
			}
		}
		if (worst > tol) {
			keep[wi] = true;
			stack[top++] = a;
			stack[top++] = wi;
			stack[top++] = wi;
			stack[top++] = b;
		}
	}
	free(stack);
	return 0;
}

/*
 * The points p[0..m) (each with the width there) as segments of constant
 * width: each segment cut into pieces over which the width changes by at
 * most MEDIAL_WIDTH_STEP, each piece as wide as the width at its middle.
 * A closed line's last segment (back to the first point) too.  Returns the
 * new array (*nout points; p is freed) or NULL when out of memory.
 */
static struct path_point *constant_widths(struct path_point *p, size_t m, bool closed,
					  size_t *nout)
{
	size_t nseg = closed ? m : m - 1, total = closed ? 0 : 1;
	struct path_point *q;

	for (size_t i = 0; i < nseg; i++)
		total += (size_t)fmax(1.0, ceil(fabs((double)(p[(i + 1) % m].width - p[i].width)) /
						 MEDIAL_WIDTH_STEP));
	q = malloc(total * sizeof(*q));
	if (!q) {
		free(p);
		return NULL;
	}
	*nout = 0;
	for (size_t i = 0; i < nseg; i++) {
		const struct path_point *a = &p[i], *b = &p[(i + 1) % m];
		double dw = (double)(b->width - a->width);
		size_t k = (size_t)fmax(1.0, ceil(fabs(dw) / MEDIAL_WIDTH_STEP));
		for (size_t j = 0; j < k; j++) {
			double t = (double)j / (double)k;
			q[(*nout)++] = (struct path_point){
			    .x = llround((double)a->x + t * (double)(b->x - a->x)),
			    .y = llround((double)a->y + t * (double)(b->y - a->y)),
			    .width = llround((double)a->width + (j + 0.5) / (double)k * dw)};
		}
	}
	if (!closed)
		q[(*nout)++] = p[m - 1];
	free(p);
	return q;
}

/* Turn l into a medial_line appended to out (simplified, integer nm). */
static int emit_line(const struct line *l, double tol, struct medial_lines *out,
		     struct st_error *err)
{
	bool *keep = calloc(l->n, sizeof(*keep));
	struct path_point *pts = NULL;
	size_t m = 0;
	int rc;

	if (!keep)
		return st_error_set(err, ST_ERR_NOMEM, "medial: out of memory");
	keep[0] = keep[l->n - 1] = true;
	if (l->closed) {
		/* A loop: split it at the point farthest from the start. */
		size_t far = 0;
		for (size_t k = 1; k < l->n; k++)
			if (pdist(&l->p[0], &l->p[3 * k]) > pdist(&l->p[0], &l->p[3 * far]))
				far = k;
		keep[far] = true;
		rc = simplify(l, 0, far, tol, keep, err);
		if (!rc)
			rc = simplify(l, far, l->n - 1, tol, keep, err);
	} else {
		rc = simplify(l, 0, l->n - 1, tol, keep, err);
	}
	if (!rc && !(pts = malloc(l->n * sizeof(*pts))))
		rc = st_error_set(err, ST_ERR_NOMEM, "medial: out of memory");
	for (size_t k = 0; k < l->n && !rc; k++) {
		if (!keep[k])
			continue;
		struct path_point p = {.x = llround(l->p[3 * k]), .y = llround(l->p[3 * k + 1]),
				       .width = llround(l->p[3 * k + 2])};
		if (m && pts[m - 1].x == p.x && pts[m - 1].y == p.y)
			continue;
		pts[m++] = p;
	}
	free(keep);
	if (!rc && m >= (l->closed ? 3u : 2u) && !(pts = constant_widths(pts, m, l->closed, &m)))
		return st_error_set(err, ST_ERR_NOMEM, "medial: out of memory");
	if (!rc && m >= (l->closed ? 3u : 2u)) {
		struct medial_line *grown = slice_grow(out->v, &out->cap, out->n + 1, sizeof(*grown));
		if (!grown) {
			free(pts);
			return st_error_set(err, ST_ERR_NOMEM, "medial: out of memory");
		}
		out->v = grown;
		out->v[out->n++] = (struct medial_line){.closed = l->closed, .n = m, .pts = pts};
		return 0;
	}
	free(pts);
	return rc;
}

int perim_medial_axis(const struct clip_paths *piece, double min_width, double step, double tol,
		      struct medial_lines *out, struct st_error *err)
{
	struct edge *edges = NULL;
	struct sample *smp = NULL;
	struct line *lines = NULL;
	struct edge_grid grid;
	size_t ne, ns = 0, nl = 0, capl = 0;
	double perimeter = 0.0;
	int rc = 0;

	if (!piece || !out || !(step > 0.0) || !(tol >= 0.0) || !(min_width >= 0.0))
		return st_error_set(err, ST_ERR_ARG, "medial: bad arguments");
	ne = build_edges(piece, &edges);
	if (ne == SIZE_MAX)
		return st_error_set(err, ST_ERR_NOMEM, "medial: out of memory for edges");
	for (size_t i = 0; i < ne; i++)
		perimeter += edges[i].len;
	if (perimeter / step + (double)ne > MEDIAL_MAX_SAMPLES)
		step = perimeter / (MEDIAL_MAX_SAMPLES - (double)ne);
	size_t cap = (size_t)(perimeter / step) + ne + 1;
	smp = malloc(cap * sizeof(*smp));
	if (!smp) {
		rc = st_error_set(err, ST_ERR_NOMEM, "medial: out of memory for samples");
		goto out_free;
	}
	grid_build(&grid, edges, ne);
	/* Samples at the middles of equal sub-edges, never on a vertex. */
	for (size_t i = 0; i < ne; i++) {
		const struct edge *e = &edges[i];
		size_t k = (size_t)ceil(e->len / step);
		if (k < 1)
			k = 1;
		for (size_t j = 0; j < k && ns < cap; j++) {
			double t = (j + 0.5) / (double)k;
			struct sample *s = &smp[ns++];
			*s = (struct sample){.px = e->ax + t * (e->bx - e->ax),
					     .py = e->ay + t * (e->by - e->ay),
					     .nx = e->nx, .ny = e->ny, .contour = e->contour,
					     .pos = e->pos0 + t * e->len};
			grow_disk(&grid, edges, ne, i, ns, s, min_width);
		}
	}
	/* Runs per contour (samples are grouped by contour in edge order). */
	double jump = fmax(4.0 * step, min_width);
	for (size_t a = 0; a < ns && !rc;) {
		size_t b = a;
		while (b < ns && smp[b].contour == smp[a].contour)
			b++;
		rc = contour_runs(&smp[a], b - a, jump, &lines, &nl, &capl, err);
		a = b;
	}
	if (!rc)
		rc = join_lines(lines, &nl, jump, err);
	for (size_t i = 0; i < nl && !rc; i++) {
		struct line *l = &lines[i];
		if (!l->closed && l->n >= 2) {
			rc = extend_end(l, edges, ne, 2.0 * step, err);
			line_reverse(l);
			if (!rc)
				rc = extend_end(l, edges, ne, 2.0 * step, err);
			line_reverse(l);
		}
		if (!rc && l->n >= 2 && line_length(l) > 0.0)
			rc = emit_line(l, tol, out, err);
	}
	grid_free(&grid);
out_free:
	for (size_t i = 0; i < nl; i++)
		free(lines[i].p);
	free(lines);
	free(smp);
	free(edges);
	return rc;
}

void perim_medial_free(struct medial_lines *ls)
{
	if (!ls)
		return;
	for (size_t i = 0; i < ls->n; i++)
		free(ls->v[i].pts);
	free(ls->v);
	memset(ls, 0, sizeof(*ls));
}
