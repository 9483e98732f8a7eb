/*
 * seg_grid.c - the edges of a polygon set on a uniform grid, for the
 * nearest-edge distances of the region check (seg_grid.h).
 */
#include "seg_grid.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "st_error.h"

void seg_grid_free(struct seg_grid *g)
{
	free(g->seg);
	free(g->start);
	free(g->items);
	memset(g, 0, sizeof(*g));
}

static double seg_dist2(const double *s, double px, double py)
{
	double dx = s[2] - s[0], dy = s[3] - s[1], l2 = dx * dx + dy * dy;
	double t = l2 > 0 ? ((px - s[0]) * dx + (py - s[1]) * dy) / l2 : 0;
	t = t < 0 ? 0 : t > 1 ? 1 : t;
	double ex = s[0] + t * dx - px, ey = s[1] + t * dy - py;
	return ex * ex + ey * ey;
}

/* Does segment s come within the circumcircle of cell (i, j)? */
static bool seg_near_cell(const struct seg_grid *g, const double *s, long i, long j)
{
	double cx = g->x0 + (i + 0.5) * g->cell, cy = g->y0 + (j + 0.5) * g->cell;
	double r = g->cell * 0.7072;
	return seg_dist2(s, cx, cy) <= r * r;
}

int seg_grid_build(struct seg_grid *g, const struct clip_paths *ps)
{
	double minx = INFINITY, miny = INFINITY, maxx = -INFINITY, maxy = -INFINITY;
	size_t n = clip_paths_points(ps), k = 0, total = 0;

	memset(g, 0, sizeof(*g));
	if (!n)
		return 0;
	g->seg = malloc(4 * n * sizeof(*g->seg));
	if (!g->seg)
		return ST_ERR_NOMEM;
	for (size_t i = 0; i < ps->n; i++) {
		size_t m = clip_path_len(ps, i);
		const int64_t *xy = clip_path_xy(ps, i);
		for (size_t j = 0; j < m; j++) {
			size_t q = (j + 1) % m;
			double *s = g->seg + 4 * k++;
			s[0] = (double)xy[2 * j];
			s[1] = (double)xy[2 * j + 1];
			s[2] = (double)xy[2 * q];
			s[3] = (double)xy[2 * q + 1];
			minx = fmin(minx, s[0]);
			maxx = fmax(maxx, s[0]);
			miny = fmin(miny, s[1]);
			maxy = fmax(maxy, s[1]);
		}
	}
	g->nseg = k;
	double ex = fmax(maxx - minx, 1.0), ey = fmax(maxy - miny, 1.0);
	/* About one segment per cell, at most 1024 cells a side. */
	g->cell = fmax(sqrt(ex * ey / (double)k), fmax(ex, ey) / 1024.0);
	g->x0 = minx;
	g->y0 = miny;
	g->nx = (long)(ex / g->cell) + 1;
	g->ny = (long)(ey / g->cell) + 1;
	g->start = calloc((size_t)(g->nx * g->ny) + 1, sizeof(*g->start));
	if (!g->start)
		return ST_ERR_NOMEM;
	/* Two passes: count, then fill. */
	for (int pass = 0; pass < 2; pass++) {
		for (size_t s = 0; s < g->nseg; s++) {
			const double *q = g->seg + 4 * s;
			long i0 = (long)((fmin(q[0], q[2]) - g->x0) / g->cell);
			long i1 = (long)((fmax(q[0], q[2]) - g->x0) / g->cell);
			long j0 = (long)((fmin(q[1], q[3]) - g->y0) / g->cell);
			long j1 = (long)((fmax(q[1], q[3]) - g->y0) / g->cell);
			for (long j = j0; j <= j1 && j < g->ny; j++)
				for (long i = i0; i <= i1 && i < g->nx; i++) {
					if (!seg_near_cell(g, q, i, j))
						continue;
					size_t c = (size_t)(j * g->nx + i);
					if (pass == 0)
						g->start[c + 1]++;
					else
						g->items[g->start[c]++] = (uint32_t)s;
				}
		}
		if (pass == 0) {
			for (long c = 0; c < g->nx * g->ny; c++)
				g->start[c + 1] += g->start[c];
			total = g->start[g->nx * g->ny];
			g->items = malloc((total ? total : 1) * sizeof(*g->items));
			if (!g->items)
				return ST_ERR_NOMEM;
		} else {
			for (long c = g->nx * g->ny; c > 0; c--)
				g->start[c] = g->start[c - 1];
			g->start[0] = 0;
		}
	}
	return 0;
}

/* Squared distance from (px, py) to the cells (i, j) of ring r's row/column, folded into best. */
static void scan_cell(const struct seg_grid *g, long i, long j, double px, double py,
		      double *best)
{
	size_t c = (size_t)(j * g->nx + i);
	for (size_t k = g->start[c]; k < g->start[c + 1]; k++) {
		double d = seg_dist2(g->seg + 4 * g->items[k], px, py);
		if (d < *best)
			*best = d;
	}
}

double seg_grid_dist(const struct seg_grid *g, double px, double py)
{
	if (!g->nseg)
		return INFINITY;
	long ci = (long)floor((px - g->x0) / g->cell), cj = (long)floor((py - g->y0) / g->cell);
	long dx = ci < 0 ? -ci : ci >= g->nx ? ci - g->nx + 1 : 0;
	long dy = cj < 0 ? -cj : cj >= g->ny ? cj - g->ny + 1 : 0;
	long r0 = dx > dy ? dx : dy;
	long rmax = labs(ci) > labs(ci - g->nx + 1) ? labs(ci) : labs(ci - g->nx + 1);
	long ry = labs(cj) > labs(cj - g->ny + 1) ? labs(cj) : labs(cj - g->ny + 1);
	double best = INFINITY;

	rmax = rmax > ry ? rmax : ry;
	for (long r = r0; r <= rmax; r++) {
		long ilo = ci - r < 0 ? 0 : ci - r, ihi = ci + r >= g->nx ? g->nx - 1 : ci + r;
		long jlo = cj - r < 0 ? 0 : cj - r, jhi = cj + r >= g->ny ? g->ny - 1 : cj + r;
		for (long i = ilo; i <= ihi; i++) {
			if (cj - r >= 0)
				scan_cell(g, i, cj - r, px, py, &best);
			if (r && cj + r < g->ny)
				scan_cell(g, i, cj + r, px, py, &best);
		}
		for (long j = jlo; j <= jhi; j++) {
			if (j == cj - r || j == cj + r)
				continue;
			if (ci - r >= 0)
				scan_cell(g, ci - r, j, px, py, &best);
			if (r && ci + r < g->nx)
				scan_cell(g, ci + r, j, px, py, &best);
		}
		/* Cells beyond ring r are at least r cells away. */
		double reach = (double)r * g->cell;
		if (best <= reach * reach)
			break;
	}
	return sqrt(best);
}

bool seg_grid_inside(const struct seg_grid *g, double px, double py)
{
	bool in = false;
	for (size_t s = 0; s < g->nseg; s++) {
		const double *q = g->seg + 4 * s;
		if ((q[1] > py) != (q[3] > py)) {
			double x = q[0] + (py - q[1]) * (q[2] - q[0]) / (q[3] - q[1]);
			if (x > px)
				in = !in;
		}
	}
	return in;
}
