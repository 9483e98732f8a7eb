/*
 * planar_retri.c - one cluster re-triangulated (planar_impl.h): its
 * boundary loops (seed 001 §4.3: the outer one encloses the largest
 * area), the vertices that go, the constrained triangulation of the rest
 * (planar_cdt.h), and the checks that decide whether the cluster may
 * change: a disk with holes, the old and new surfaces and the volume within the
 * flatness tolerance.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "planar_cdt.h"
#include "planar_impl.h"
#include "vec3.h"

/* The loops of one cluster, with the vertices that go left out. */
struct loops {
	uint32_t *vert;		/* kept loop vertices, loop after loop */
	size_t *end;		/* loop i ends before vert[end[i]] */
	size_t n, nvert;
	uint32_t *probe;	/* removed vertices: interior and seam */
	size_t nprobe;
	uint32_t *start;	/* scratch: tails of boundary edges */
};

static void loops_free(struct loops *l)
{
	free(l->vert);
	free(l->end);
	free(l->probe);
	free(l->start);
}

/* Signed area of a loop seen along n (positive: counter-clockwise). */
static double loop_area(const struct mesh *m, const uint32_t *v, size_t n, const double nrm[3])
{
	double s[3] = {0, 0, 0};

	for (size_t i = 0; i < n; i++) {
		const double *a = m->verts[v[i]], *b = m->verts[v[(i + 1) % n]];
		s[0] += a[1] * b[2] - a[2] * b[1];
		s[1] += a[2] * b[0] - a[0] * b[2];
		s[2] += a[0] * b[1] - a[1] * b[0];
	}
	return (s[0] * nrm[0] + s[1] * nrm[1] + s[2] * nrm[2]) / 2;
}

/* Six times the signed volume the triangles enclose with point o. */
static double volume6(const struct mesh *m, const uint32_t (*t)[3], size_t n, const double *o)
{
	double v = 0;

	for (size_t i = 0; i < n; i++) {
		const double *a = m->verts[t[i][0]], *b = m->verts[t[i][1]], *c = m->verts[t[i][2]];
		const double p[3] = {a[0] - o[0], a[1] - o[1], a[2] - o[2]};
		const double q[3] = {b[0] - o[0], b[1] - o[1], b[2] - o[2]};
		const double r[3] = {c[0] - o[0], c[1] - o[1], c[2] - o[2]};
		v += p[0] * (q[1] * r[2] - q[2] * r[1]) - p[1] * (q[0] * r[2] - q[2] * r[0]) +
		     p[2] * (q[0] * r[1] - q[1] * r[0]);
	}
	return v;
}

/*
 * The gap between the old facets and the new triangles is measured along
 * the cluster's normal n.  Both are height fields over the same outline
 * seen along n (every old facet faces along it, the new ones are
 * triangulated in that view), so a point of either surface lies at most
 * that gap from the other, and the gap is linear on each cell of the two
 * triangulations overlaid: its largest value is at a removed vertex or
 * where an old edge crosses a new one (kept vertices are on both).
 */
struct view {
	double u[3], v[3], n[3];
};

static void view_init(struct view *w, const double n[3])
{
	const double *axis =
	    fabs(n[0]) < 0.6 ? (const double[3]){1, 0, 0} : (const double[3]){0, 1, 0};

	memcpy(w->n, n, sizeof(w->n));
	w->u[0] = axis[1] * n[2] - axis[2] * n[1];
	w->u[1] = axis[2] * n[0] - axis[0] * n[2];
	w->u[2] = axis[0] * n[1] - axis[1] * n[0];
	const double len = sqrt(w->u[0] * w->u[0] + w->u[1] * w->u[1] + w->u[2] * w->u[2]);
	for (int k = 0; k < 3; k++)
		w->u[k] /= len;
	w->v[0] = n[1] * w->u[2] - n[2] * w->u[1];
	w->v[1] = n[2] * w->u[0] - n[0] * w->u[2];
	w->v[2] = n[0] * w->u[1] - n[1] * w->u[0];
}

static double dot3(const double a[3], const double b[3])
{
	return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* A point seen along n: its place in the view and its height. */
struct seen {
	double x, y, h;
};

static struct seen see(const struct view *w, const double p[3])
{
	return (struct seen){dot3(p, w->u), dot3(p, w->v), dot3(p, w->n)};
}

/* Removed vertex p against the new triangle abc it lies over. */
static double vertex_gap(const struct view *w, const double p[3], const double a[3],
			 const double b[3], const double c[3])
{
	double nt[3];

	vec3_area_normal(a, b, c, nt);
	const double d[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};
	return fabs(dot3(d, nt) / dot3(w->n, nt));
}

/* Old edge pq against new edge ab: the gap where they cross, else 0. */
static double crossing_gap(struct seen p, struct seen q, struct seen a, struct seen b)
{
	const double rx = q.x - p.x, ry = q.y - p.y, sx = b.x - a.x, sy = b.y - a.y;
	const double den = rx * sy - ry * sx;
	const double ex = a.x - p.x, ey = a.y - p.y;

	if (den == 0)
		return 0;
	const double t = (ex * sy - ey * sx) / den, s = (ex * ry - ey * rx) / den;
	if (!(t > 0 && t < 1 && s > 0 && s < 1))
		return 0;
	return fabs(p.h + t * (q.h - p.h) - (a.h + s * (b.h - a.h)));
}

/*
 * The new edges in a grid of buckets over the view, each in the buckets
 * its segment passes through, so an old edge meets only the new edges
 * near it.
 */
struct edge_grid {
	double x0, y0, cell;
	size_t side;
	size_t *first; /* bucket b holds edge[first[b] .. first[b + 1]) */
	size_t *edge;
	size_t *cells; /* scratch: one segment's buckets, 3 * side at most */
};

static size_t bucket_index(double f, size_t side)
{
	if (!(f > 0))
		return 0;
	return f >= (double)(side - 1) ? side - 1 : (size_t)f;
}

/* The buckets segment ab passes through, column by column, into g->cells. */
static size_t segment_buckets(const struct edge_grid *g, struct seen a, struct seen b)
{
	const double ax = (a.x - g->x0) / g->cell, bx = (b.x - g->x0) / g->cell;
	const double ay = (a.y - g->y0) / g->cell, by = (b.y - g->y0) / g->cell;
	const size_t c1 = bucket_index(fmax(ax, bx), g->side);
	size_t n = 0;

	for (size_t c = bucket_index(fmin(ax, bx), g->side); c <= c1; c++) {
		double lo = fmin(ay, by), hi = fmax(ay, by);
		if (ax != bx) { /* the segment's y over this column's x range */
			const double xl = fmax((double)c, fmin(ax, bx));
			const double xh = fmin((double)c + 1, fmax(ax, bx));
			const double yl = ay + (xl - ax) / (bx - ax) * (by - ay);
			const double yh = ay + (xh - ax) / (bx - ax) * (by - ay);
			lo = fmin(yl, yh);
			hi = fmax(yl, yh);
		}
		const size_t r1 = bucket_index(hi, g->side);
		for (size_t r = bucket_index(lo, g->side); r <= r1; r++)
			g->cells[n++] = r * g->side + c;
	}
	return n;
}

static void edge_grid_free(struct edge_grid *g)
{
	free(g->first);
	free(g->edge);
	free(g->cells);
}

/* Buckets the n segments ends[2i], ends[2i + 1]; false when out of memory. */
static bool edge_grid_build(struct edge_grid *g, const struct seen *ends, size_t n)
{
	double x1 = -INFINITY, y1 = -INFINITY;
	size_t *fill;

	g->x0 = g->y0 = INFINITY;
	for (size_t i = 0; i < 2 * n; i++) {
		g->x0 = fmin(g->x0, ends[i].x);
		g->y0 = fmin(g->y0, ends[i].y);
		x1 = fmax(x1, ends[i].x);
		y1 = fmax(y1, ends[i].y);
	}
	g->side = (size_t)sqrt((double)n) + 1;
	g->cell = fmax(x1 - g->x0, y1 - g->y0) / (double)g->side;
	if (!(g->cell > 0))
		g->cell = 1;
	g->first = calloc(g->side * g->side + 1, sizeof(*g->first));
	g->cells = malloc(3 * g->side * sizeof(*g->cells));
	if (!g->first || !g->cells)
		return false;
	for (size_t e = 0; e < n; e++) {
		const size_t k = segment_buckets(g, ends[2 * e], ends[2 * e + 1]);
		for (size_t i = 0; i < k; i++)
			g->first[g->cells[i] + 1]++;
	}
	for (size_t b = 0; b < g->side * g->side; b++)
		g->first[b + 1] += g->first[b];
	g->edge = malloc((g->first[g->side * g->side] + 1) * sizeof(*g->edge));
	fill = malloc((g->side * g->side + 1) * sizeof(*fill));
	if (!g->edge || !fill) {
		free(fill);
		return false;
	}
	memcpy(fill, g->first, g->side * g->side * sizeof(*fill));
	for (size_t e = 0; e < n; e++) {
		const size_t k = segment_buckets(g, ends[2 * e], ends[2 * e + 1]);
		for (size_t i = 0; i < k; i++)
			g->edge[fill[g->cells[i]]++] = e;
	}
	free(fill);
	return true;
}

/*
 * The largest gap along the normal between the old facets and the new
 * triangles of a cluster, at its removed vertices and at every crossing
 * of an old edge with a new one.  Returns a negative value when out of
 * memory.
 */
static double overlay_gap(const struct mesh *m, const double n[3], const uint32_t (*old)[3],
			  size_t nold, const uint32_t (*tris)[3], size_t ntris,
			  const uint32_t *probe, const uint32_t *located, size_t nprobe)
{
	const size_t nedges = 3 * ntris;
	struct view w;
	struct edge_grid g = {0};
	struct seen *ends = malloc((2 * nedges + 1) * sizeof(*ends));
	double gap = 0;

	view_init(&w, n);
	for (size_t i = 0; i < nprobe; i++) {
		const uint32_t *t = tris[located[i]];
		gap = fmax(gap, vertex_gap(&w, m->verts[probe[i]], m->verts[t[0]], m->verts[t[1]],
					   m->verts[t[2]]));
	}
	for (size_t e = 0; ends && e < nedges; e++) {
		const uint32_t *t = tris[e / 3];
		ends[2 * e] = see(&w, m->verts[t[e % 3]]);
		ends[2 * e + 1] = see(&w, m->verts[t[(e + 1) % 3]]);
	}
	if (!ends || !edge_grid_build(&g, ends, nedges)) {
		gap = -1;
		goto out;
	}
	for (size_t i = 0; i < 3 * nold; i++) {
		const uint32_t *t = old[i / 3];
		const struct seen p = see(&w, m->verts[t[i % 3]]);
		const struct seen q = see(&w, m->verts[t[(i + 1) % 3]]);
		const size_t k = segment_buckets(&g, p, q);
		for (size_t c = 0; c < k; c++)
			for (size_t j = g.first[g.cells[c]]; j < g.first[g.cells[c] + 1]; j++) {
				const size_t e = g.edge[j];
				gap = fmax(gap, crossing_gap(p, q, ends[2 * e], ends[2 * e + 1]));
			}
	}
out:
	edge_grid_free(&g);
	free(ends);
	return gap;
}

/*
 * Cluster c's loops from its boundary edges (facet edges whose neighbour
 * is in another cluster or none), the removed vertices, and the shape
 * check: the cluster must be a disk with holes (each boundary vertex on
 * one loop, Euler characteristic 2 - loops, inner vertices interior).
 * Returns 0, <0, or 1 when the shape is refused.
 */
static int find_loops(struct planar_ctx *x, const struct planar_cluster *cl, struct loops *l)
{
	const struct mesh *m = x->m;
	const uint32_t mark = ++x->stamp_gen, walked = ++x->stamp_gen;
	size_t nverts = 0, nbound = 0;

	l->start = malloc((3 * cl->n + 1) * sizeof(*l->start));
	l->probe = malloc((3 * cl->n + 1) * sizeof(*l->probe));
	if (!l->start || !l->probe)
		return ST_ERR_NOMEM;
	for (size_t i = 0; i < cl->n; i++) {
		const uint32_t t = x->cl_tris[cl->first + i], *v = m->tris[t];
		for (int k = 0; k < 3; k++) {
			const uint32_t u = x->nb[t][k];
			if (x->seen[v[k]] != mark) {
				x->seen[v[k]] = mark;
				nverts++;
			}
			if (u != PLANAR_NONE && x->cluster[u] == x->cluster[t])
				continue;
			if (x->stamp[v[k]] == mark)
				return 1; /* the cluster touches itself at v[k] */
			x->stamp[v[k]] = mark;
			x->next[v[k]] = v[(k + 1) % 3];
			l->start[nbound++] = v[k];
		}
	}
	/* Vertices with no boundary edge must be interior ones. */
	for (size_t i = 0; i < cl->n; i++) {
		const uint32_t *v = m->tris[x->cl_tris[cl->first + i]];
		for (int k = 0; k < 3; k++) {
			if (x->stamp[v[k]] == mark || x->seen[v[k]] == walked)
				continue;
			if (x->role[v[k]] != PLANAR_INTERIOR)
				return 1;
			x->seen[v[k]] = walked;
			l->probe[l->nprobe++] = v[k];
		}
	}
	l->vert = malloc((nbound + 1) * sizeof(*l->vert));
	l->end = malloc((nbound + 1) * sizeof(*l->end));
	if (!l->vert || !l->end)
		return ST_ERR_NOMEM;
	for (size_t i = 0; i < nbound; i++) {
		uint32_t v = l->start[i];
		size_t begin = l->nvert;
		if (x->seen[v] == walked)
			continue;
		do {
			x->seen[v] = walked;
			if (x->role[v] == PLANAR_SEAM && !x->kept[v])
				l->probe[l->nprobe++] = v;
			else
				l->vert[l->nvert++] = v;
			v = x->next[v];
			if (x->stamp[v] != mark)
				return 1; /* open chain: cannot happen on oriented facets */
		} while (x->seen[v] != walked);
		if (v != l->start[i] || l->nvert - begin < 3)
			return 1;
		l->end[l->n++] = l->nvert;
	}
	if (l->n == 0)
		return 1; /* closed: a flat pillow, two faces on each other */
	/* A disk with h holes: V - E + F = 1 - h, E = (3F + boundary) / 2. */
	if ((long long)nverts - (long long)(3 * cl->n + nbound) / 2 + (long long)cl->n !=
	    2 - (long long)l->n)
		return 1;
	return 0;
}

/* Seed 001 §4.3: the loop enclosing the largest area is the outer one and
 * runs counter-clockwise; every other loop is a hole, clockwise. */
static bool loops_nest(const struct mesh *m, const struct loops *l, const double nrm[3])
{
	size_t outer = 0, begin = 0;
	double best = 0;

	for (size_t i = 0; i < l->n; i++) {
		const double a = loop_area(m, l->vert + begin, l->end[i] - begin, nrm);
		if (fabs(a) > best) {
			best = fabs(a);
			outer = i;
		}
		begin = l->end[i];
	}
	begin = 0;
	for (size_t i = 0; i < l->n; i++) {
		const double a = loop_area(m, l->vert + begin, l->end[i] - begin, nrm);
		if (i == outer ? !(a > 0) : !(a < 0))
			return false;
		begin = l->end[i];
	}
	return true;
}

int planar_retriangulate(struct planar_ctx *x, uint32_t c, size_t **refusal,
			 struct planar_report *rep, struct st_error *err)
{
	const struct mesh *m = x->m;
	struct planar_cluster *cl = &x->cl[c];
	struct loops l = {0};
	uint32_t (*tris)[3] = NULL, *located = NULL;
	const uint32_t(*old)[3] = NULL;
	uint32_t (*old_copy)[3] = NULL;
	const char *why = NULL;
	size_t ntris = 0, cap;
	double deviation = 0;
	int rc;

	*refusal = NULL;
	free(cl->tris);
	cl->tris = NULL;
	cl->ntris = 0;
	cl->state = PLANAR_AS_IS;
	rc = find_loops(x, cl, &l);
	if (rc < 0)
		goto out_nomem;
	if (rc > 0 || (l.nprobe && !loops_nest(m, &l, cl->normal))) {
		*refusal = &rep->refused_shape;
		rc = 0;
		goto out;
	}
	if (l.nprobe == 0)
		goto out; /* nothing to remove: stays as it is */

	cap = l.nvert + 2 * (l.n - 1) - 2;
	tris = malloc((cap + 1) * sizeof(*tris));
	located = malloc((l.nprobe + 1) * sizeof(*located));
	old_copy = malloc((cl->n + 1) * sizeof(*old_copy));
	if (!tris || !located || !old_copy)
		goto out_nomem;
	for (size_t i = 0; i < cl->n; i++)
		memcpy(old_copy[i], m->tris[x->cl_tris[cl->first + i]], sizeof(old_copy[i]));
	old = (const uint32_t(*)[3])old_copy;
	{
		struct planar_cdt_cluster in = {
		    (const double(*)[3])m->verts, m->nverts, l.vert, l.end, l.n, old, cl->n,
		    l.probe, l.nprobe, {cl->normal[0], cl->normal[1], cl->normal[2]}};
		rc = planar_cdt_triangulate(&in, tris, cap, &ntris, located, &why, err);
	}
	if (rc)
		goto out;
	if (why) {
		*refusal = &rep->refused_shape;
		goto out;
	}
	/* An exactly planar cluster keeps its plane: nothing deviates. */
	if (!cl->exact) {
		double area = 0, dv;
		deviation = overlay_gap(m, cl->normal, old, cl->n, (const uint32_t(*)[3])tris,
					ntris, l.probe, located, l.nprobe);
		if (deviation < 0)
			goto out_nomem;
		for (size_t i = 0; i < cl->n; i++)
			area += x->area[x->cl_tris[cl->first + i]];
		dv = (volume6(m, (const uint32_t(*)[3])tris, ntris, m->verts[l.vert[0]]) -
		      volume6(m, old, cl->n, m->verts[l.vert[0]])) / 6;
		if (deviation > x->opt->flatness || fabs(dv) > x->opt->flatness * area) {
			*refusal = &rep->refused_deviation;
			goto out;
		}
	}
	cl->tris = tris;
	cl->ntris = ntris;
	cl->deviation = deviation;
	cl->state = PLANAR_NEW;
	tris = NULL;
	goto out;

out_nomem:
	rc = st_error_set(err, ST_ERR_NOMEM, "planar simplification: out of memory");
out:
	free(tris);
	free(located);
	free(old_copy);
	loops_free(&l);
	return rc;
}
