/*
 * planar_retri.c - one cluster re-triangulated (planar_impl.h): its
 * boundary loops (seed 001 §4.3: the outer one encloses the largest
 * area), the vertices that go, the constrained triangulation of the rest
 * (planar_cdt.h), and the checks that decide whether the cluster may
 * change: a disk with holes, removed vertices and the volume within the
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
		for (size_t i = 0; i < l.nprobe; i++) {
			const uint32_t *t = tris[located[i]];
			deviation = fmax(deviation,
					 vec3_point_triangle_distance(m->verts[l.probe[i]],
								      m->verts[t[0]], m->verts[t[1]],
								      m->verts[t[2]]));
		}
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
