/*
 * refine_place.c - the edges of the mesh being refined, and where the new
 * vertex of a split edge goes on the reference surface (refine_impl.h).
 *
 * Nearest-point projection alone slides a vertex on a crease (a
 * cylinder's rim) onto whichever face is nearer and cuts the corner; so a
 * vertex on an edge whose facets meet at a sharp angle goes onto the line
 * where the reference's two faces meet there, found by a ray from each
 * facet, and any other vertex along the facets' normal.  The distances are
 * doubles: they place points, the exact checks (refine.c) decide.
 */
#include "refine_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "vec3.h"

/* Farther along a line than this many times the nearest point (and than
 * the edge), the line has met another part of the reference, as in the
 * chordal measurement (deviation.c). */
#define PLACE_REACH 3.0
/* A crease's ray starts this share of the way from the edge's midpoint to
 * its facet's centroid: inside the facet, near the edge. */
#define CREASE_STEP 0.1

struct half {
	uint32_t lo, hi, tri;
	uint8_t k;
};

static int cmp_half(const void *x, const void *y)
{
	const struct half *a = x, *b = y;

	if (a->lo != b->lo)
		return a->lo < b->lo ? -1 : 1;
	if (a->hi != b->hi)
		return a->hi < b->hi ? -1 : 1;
	return a->tri < b->tri ? -1 : a->tri > b->tri;
}

int refine_edges_build(const struct mesh *m, struct refine_edges *e, struct st_error *err)
{
	size_t nh = 3 * m->ntris;
	struct half *h = malloc((nh ? nh : 1) * sizeof(*h));

	memset(e, 0, sizeof(*e));
	e->ends = malloc((nh ? nh : 1) * sizeof(*e->ends));
	e->faces = malloc((nh ? nh : 1) * sizeof(*e->faces));
	e->of_tri = malloc((m->ntris ? m->ntris : 1) * sizeof(*e->of_tri));
	if (!h || !e->ends || !e->faces || !e->of_tri) {
		free(h);
		refine_edges_free(e);
		return st_error_set(err, ST_ERR_NOMEM, "refine: out of memory");
	}
	for (size_t t = 0; t < m->ntris; t++)
		for (uint8_t k = 0; k < 3; k++) {
			uint32_t u = m->tris[t][k], v = m->tris[t][(k + 1) % 3];
			h[3 * t + k] = (struct half){u < v ? u : v, u < v ? v : u, (uint32_t)t, k};
		}
	qsort(h, nh, sizeof(*h), cmp_half);
	for (size_t i = 0, j; i < nh; i = j) {
		for (j = i + 1; j < nh && h[j].lo == h[i].lo && h[j].hi == h[i].hi; j++)
			;
		e->ends[e->n][0] = h[i].lo;
		e->ends[e->n][1] = h[i].hi;
		e->faces[e->n][0] = j - i == 2 ? h[i].tri : REFINE_NONE;
		e->faces[e->n][1] = j - i == 2 ? h[i + 1].tri : REFINE_NONE;
		for (size_t k = i; k < j; k++)
			e->of_tri[h[k].tri][h[k].k] = (uint32_t)e->n;
		e->n++;
	}
	free(h);
	return 0;
}

void refine_edges_free(struct refine_edges *e)
{
	free(e->ends);
	free(e->faces);
	free(e->of_tri);
	memset(e, 0, sizeof(*e));
}

void refine_unit_normal(const struct mesh *m, uint32_t t, double n[3])
{
	const uint32_t *c = m->tris[t];
	double len;

	vec3_area_normal(m->verts[c[0]], m->verts[c[1]], m->verts[c[2]], n);
	len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
	for (int k = 0; k < 3; k++)
		n[k] = len > 0 ? n[k] / len : 0;
}

void refine_midpoint(const struct mesh *m, const struct refine_edges *e, size_t i, double mid[3])
{
	for (int k = 0; k < 3; k++)
		mid[k] = (m->verts[e->ends[i][0]][k] + m->verts[e->ends[i][1]][k]) / 2;
}

static double dot(const double a[3], const double b[3])
{
	return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* The queries of one batch: per edge the nearest point and the line along
 * the facets' normal; per crease edge a line from each facet. */
struct queries {
	double (*mid)[3], (*near)[3], (*along)[3], (*dir)[3], *dnear, *dalong;
	uint32_t *talong, *tnear;
	double (*cpts)[3], (*cdirs)[3], (*chit)[3], *dcrease;
	uint32_t *tcrease;
	size_t *crease_of; /* per edge: its first crease line, or SIZE_MAX */
	size_t ncrease;
};

static void queries_free(struct queries *q)
{
	free(q->mid), free(q->near), free(q->along), free(q->dir), free(q->dnear);
	free(q->dalong), free(q->talong), free(q->tnear), free(q->cpts), free(q->cdirs), free(q->chit);
	free(q->dcrease), free(q->tcrease), free(q->crease_of);
}

static int queries_alloc(struct queries *q, size_t n)
{
	size_t c = n ? 2 * n : 1;

	n = n ? n : 1;
	memset(q, 0, sizeof(*q));
	q->mid = malloc(n * sizeof(*q->mid)), q->near = malloc(n * sizeof(*q->near));
	q->along = malloc(n * sizeof(*q->along)), q->dir = malloc(n * sizeof(*q->dir));
	q->dnear = malloc(n * sizeof(*q->dnear)), q->dalong = malloc(n * sizeof(*q->dalong));
	q->talong = malloc(n * sizeof(*q->talong)), q->crease_of = malloc(n * sizeof(size_t));
	q->tnear = malloc(n * sizeof(*q->tnear));
	q->cpts = malloc(c * sizeof(*q->cpts)), q->cdirs = malloc(c * sizeof(*q->cdirs));
	q->chit = malloc(c * sizeof(*q->chit)), q->dcrease = malloc(c * sizeof(*q->dcrease));
	q->tcrease = malloc(c * sizeof(*q->tcrease));
	return q->mid && q->near && q->along && q->dir && q->dnear && q->dalong && q->talong &&
	       q->tnear &&
	       q->crease_of && q->cpts && q->cdirs && q->chit && q->dcrease && q->tcrease;
}

/* The crease line's start in facet f: a step from mid towards its centroid. */
static void crease_start(const struct mesh *m, uint32_t f, const double mid[3], double p[3])
{
	for (int k = 0; k < 3; k++) {
		double c = (m->verts[m->tris[f][0]][k] + m->verts[m->tris[f][1]][k] +
			    m->verts[m->tris[f][2]][k]) / 3;
		p[k] = mid[k] + CREASE_STEP * (c - mid[k]);
	}
}

/* Where the planes of reference triangles ra (through pa) and rb (through
 * pb) meet, the point nearest mid into out; false when they do not meet
 * at the feature angle or more. */
static bool crease_point(const struct refine_target *tg, uint32_t ra, const double pa[3],
			 uint32_t rb, const double pb[3], const double mid[3], double out[3])
{
	double na[3], nb[3], d[3], x0[3];

	refine_unit_normal(tg->ref, ra, na);
	refine_unit_normal(tg->ref, rb, nb);
	double k = dot(na, nb), ca = dot(na, pa), cb = dot(nb, pb), det = 1 - k * k;
	if (!(fabs(k) < tg->crease_cos) || det <= 0)
		return false;
	d[0] = na[1] * nb[2] - na[2] * nb[1];
	d[1] = na[2] * nb[0] - na[0] * nb[2];
	d[2] = na[0] * nb[1] - na[1] * nb[0];
	double len = sqrt(dot(d, d)), a = (ca - cb * k) / det, b = (cb - ca * k) / det;
	for (int i = 0; i < 3; i++) {
		d[i] /= len;
		x0[i] = a * na[i] + b * nb[i];
	}
	double t = (mid[0] - x0[0]) * d[0] + (mid[1] - x0[1]) * d[1] + (mid[2] - x0[2]) * d[2];
	for (int i = 0; i < 3; i++)
		out[i] = x0[i] + t * d[i];
	return true;
}

/* Whether a point reached along a line at distance d is on the part of the
 * surface the edge stands for. */
static bool within_reach(double d, double near, double edge)
{
	return d >= 0 && d <= fmax(PLACE_REACH * near, edge);
}

/* Whether a vertex placed at distance d from the edge's midpoint stays
 * near: a line that grazes a curved surface meets it far off, and a
 * vertex put there would stand out as a spike. */
static bool close_enough(double d, double near)
{
	return d >= 0 && d <= PLACE_REACH * near;
}

/* Whether reference triangle t faces the way of dir, the facets' normal:
 * where the coarse surface runs inside a thin part (an ear of a scan), the
 * nearer crossing may be the far side, facing away, and a vertex moved
 * there would cross the facets on that side. */
static bool facing(const struct refine_target *tg, uint32_t t, const double dir[3])
{
	double n[3];

	if (t == REFINE_NONE)
		return false;
	refine_unit_normal(tg->ref, t, n);
	return dot(n, dir) > 0;
}

/* The lines and points of the batch, before asking the tree. */
static void pose_queries(const struct mesh *m, const struct refine_edges *e, const uint32_t *which,
			 size_t n, const struct refine_target *tg, struct queries *q)
{
	for (size_t i = 0; i < n; i++) {
		const uint32_t *f = e->faces[which[i]];
		double n1[3] = {0, 0, 0}, n2[3] = {0, 0, 0};

		refine_midpoint(m, e, which[i], q->mid[i]);
		q->crease_of[i] = SIZE_MAX;
		if (f[0] != REFINE_NONE) {
			refine_unit_normal(m, f[0], n1);
			refine_unit_normal(m, f[1], n2);
		}
		for (int k = 0; k < 3; k++)
			q->dir[i][k] = n1[k] + n2[k];
		if (dot(q->dir[i], q->dir[i]) < 1e-12)
			memcpy(q->dir[i], n1, sizeof(n1));
		if (f[0] == REFINE_NONE || !(dot(n1, n2) < tg->crease_cos))
			continue;
		q->crease_of[i] = q->ncrease;
		for (int s = 0; s < 2; s++) {
			crease_start(m, f[s], q->mid[i], q->cpts[q->ncrease]);
			memcpy(q->cdirs[q->ncrease++], s ? n2 : n1, sizeof(n1));
		}
	}
}

int refine_place(const struct mesh *m, const struct refine_edges *e, const uint32_t *which,
		 size_t n, const struct refine_target *tg, double (*pos)[3], uint8_t *kind,
		 struct st_error *err)
{
	struct queries q;
	int rc;

	if (!queries_alloc(&q, n)) {
		queries_free(&q);
		return st_error_set(err, ST_ERR_NOMEM, "refine: out of memory");
	}
	pose_queries(m, e, which, n, tg, &q);
	rc = surfdist_closest(tg->tree, (const double (*)[3])q.mid, n, q.near, q.tnear, err);
	if (!rc)
		rc = surfdist_hit(tg->tree, (const double (*)[3])q.mid, (const double (*)[3])q.dir, n,
				  q.along, q.talong, q.dalong, err);
	if (!rc && q.ncrease)
		rc = surfdist_hit(tg->tree, (const double (*)[3])q.cpts, (const double (*)[3])q.cdirs,
				  q.ncrease, q.chit, q.tcrease, q.dcrease, err);
	for (size_t i = 0; !rc && i < n; i++) {
		double near = vec3_dist(q.mid[i], q.near[i]);
		double edge = vec3_dist(m->verts[e->ends[which[i]][0]], m->verts[e->ends[which[i]][1]]);
		size_t c = q.crease_of[i];

		if (e->faces[which[i]][0] == REFINE_NONE) {
			memcpy(pos[i], q.mid[i], sizeof(pos[i]));
			kind[i] = PLACE_ON_EDGE;
		} else if (c != SIZE_MAX && q.tcrease[c] != REFINE_NONE &&
			   q.tcrease[c + 1] != REFINE_NONE &&
			   within_reach(q.dcrease[c], near, edge) &&
			   within_reach(q.dcrease[c + 1], near, edge) &&
			   crease_point(tg, q.tcrease[c], q.chit[c], q.tcrease[c + 1], q.chit[c + 1],
					q.mid[i], pos[i]) &&
			   /* mid lies on one face (near 0); the lines tell the scale */
			   close_enough(vec3_dist(pos[i], q.mid[i]),
					fmax(near, fmax(q.dcrease[c], q.dcrease[c + 1])))) {
			kind[i] = PLACE_ON_CREASE;
		} else if (close_enough(q.dalong[i], near) && facing(tg, q.talong[i], q.dir[i])) {
			memcpy(pos[i], q.along[i], sizeof(pos[i]));
			kind[i] = PLACE_ALONG;
		} else if (facing(tg, q.tnear[i], q.dir[i])) {
			memcpy(pos[i], q.near[i], sizeof(pos[i]));
			kind[i] = PLACE_NEAREST;
		} else {
			memcpy(pos[i], q.mid[i], sizeof(pos[i]));
			kind[i] = PLACE_ON_EDGE;
		}
	}
	queries_free(&q);
	return rc;
}
