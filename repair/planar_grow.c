/*
 * planar_grow.c - the clusters of planar simplification (planar_impl.h):
 * which facets are neighbours, which vertex stars are plain disks, how
 * clusters grow under seed 001 §4.2's angle and flatness criteria, and
 * which vertices may go.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "exact.h"
#include "planar_impl.h"
#include "vec3.h"

int planar_corner(const uint32_t *t, uint32_t v)
{
	return t[0] == v ? 0 : t[1] == v ? 1 : 2;
}

static int edge_compare(const void *pa, const void *pb)
{
	const struct planar_edge *a = pa, *b = pb;

	if (a->a != b->a)
		return a->a < b->a ? -1 : 1;
	if (a->b != b->b)
		return a->b < b->b ? -1 : 1;
	return 0;
}

uint32_t planar_edge_count(const struct planar_ctx *x, uint32_t a, uint32_t b)
{
	struct planar_edge key = {a < b ? a : b, a < b ? b : a, 0};
	const struct planar_edge *e =
	    bsearch(&key, x->edges, x->nedges, sizeof(*x->edges), edge_compare);

	return e ? e->count : 0;
}

/* One directed edge of a facet, for pairing neighbours. */
struct half {
	uint32_t a, b; /* smaller vertex first */
	uint32_t t;
	uint8_t k;     /* edge k runs from corner k to k+1 */
};

static int half_compare(const void *pa, const void *pb)
{
	const struct half *a = pa, *b = pb;

	if (a->a != b->a)
		return a->a < b->a ? -1 : 1;
	if (a->b != b->b)
		return a->b < b->b ? -1 : 1;
	return a->t < b->t ? -1 : a->t > b->t;
}

/*
 * Facet geometry, the input's edges with their counts, and neighbours
 * across edges with exactly two consistently oriented usable facets.
 */
static int build_adjacency(struct planar_ctx *x, struct st_error *err)
{
	const struct mesh *m = x->m;
	struct half *h = malloc((3 * m->ntris + 1) * sizeof(*h));
	size_t nh = 0;

	x->edges = malloc((3 * m->ntris + 1) * sizeof(*x->edges));
	if (!h || !x->edges) {
		free(h);
		return st_error_set(err, ST_ERR_NOMEM, "planar simplification: out of memory");
	}
	for (size_t t = 0; t < m->ntris; t++) {
		const uint32_t *v = m->tris[t];
		const double *a = m->verts[v[0]], *b = m->verts[v[1]], *c = m->verts[v[2]];
		double n[3], len;

		for (int k = 0; k < 3; k++)
			x->nb[t][k] = PLANAR_NONE;
		if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2] || exact_collinear(a, b, c))
			continue;
		vec3_area_normal(a, b, c, n);
		len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
		if (!(len > 0))
			continue; /* collinear in doubles though not exactly: too thin to use */
		x->usable[t] = 1;
		x->area[t] = len / 2;
		for (int k = 0; k < 3; k++)
			x->unit[t][k] = n[k] / len;
		for (int k = 0; k < 3; k++) {
			uint32_t p = v[k], q = v[(k + 1) % 3];
			h[nh++] = (struct half){p < q ? p : q, p < q ? q : p, (uint32_t)t, (uint8_t)k};
		}
	}
	qsort(h, nh, sizeof(*h), half_compare);
	for (size_t i = 0; i < nh;) {
		size_t j = i;

		while (j < nh && h[j].a == h[i].a && h[j].b == h[i].b)
			j++;
		x->edges[x->nedges++] = (struct planar_edge){h[i].a, h[i].b, (uint32_t)(j - i)};
		if (j - i == 2) {
			const struct half *p = &h[i], *q = &h[i + 1];
			/* consistently oriented: p's a->b is q's b->a */
			if (m->tris[p->t][p->k] == m->tris[q->t][(q->k + 1) % 3]) {
				x->nb[p->t][p->k] = q->t;
				x->nb[q->t][q->k] = p->t;
			}
		}
		i = j;
	}
	free(h);
	return 0;
}

/* Vertex -> triangles, and whether each star is one closed fan. */
static int build_stars(struct planar_ctx *x, struct st_error *err)
{
	const struct mesh *m = x->m;

	x->vt_start = calloc(m->nverts + 2, sizeof(*x->vt_start));
	x->vt = malloc((3 * m->ntris + 1) * sizeof(*x->vt));
	if (!x->vt_start || !x->vt)
		return st_error_set(err, ST_ERR_NOMEM, "planar simplification: out of memory");
	for (size_t t = 0; t < m->ntris; t++)
		for (int k = 0; k < 3; k++)
			x->vt_start[m->tris[t][k] + 2]++;
	for (size_t v = 0; v < m->nverts; v++)
		x->vt_start[v + 2] += x->vt_start[v + 1];
	for (size_t t = 0; t < m->ntris; t++)
		for (int k = 0; k < 3; k++)
			x->vt[x->vt_start[m->tris[t][k] + 1]++] = (uint32_t)t;
	for (size_t v = 0; v < m->nverts; v++) {
		const size_t first = x->vt_start[v], deg = x->vt_start[v + 1] - first;
		uint32_t t = x->vt[first];
		size_t steps = 0;
		bool ok = deg >= 3;

		for (size_t i = 0; ok && i < deg; i++)
			ok = x->usable[x->vt[first + i]];
		/* Walk across the edge leaving v in each facet, back to the start. */
		while (ok) {
			t = x->nb[t][planar_corner(m->tris[t], (uint32_t)v)];
			steps++;
			if (t == PLANAR_NONE || steps > deg)
				ok = false;
			else if (t == x->vt[first])
				break;
		}
		x->clean[v] = ok && steps == deg;
	}
	return 0;
}

/* Areas for the seed order (qsort has no context argument). */
struct seed {
	double area;
	uint32_t t;
};

static int seed_compare(const void *pa, const void *pb)
{
	const struct seed *a = pa, *b = pb;

	if (a->area != b->area)
		return a->area > b->area ? -1 : 1;
	return a->t < b->t ? -1 : a->t > b->t;
}

/* A growing cluster: plane sums, its vertices, the flatness bound's state. */
struct grow {
	double sum_n[3];	/* sum of area vectors (2 * area * unit normal) */
	double sum_p[3];	/* sum of area * centroid */
	double sum_a;
	double n[3], p[3];	/* the plane now */
	double ref_n[3], ref_p[3]; /* plane the distances below refer to */
	double ref_dist;	/* largest |ref_n . (v - ref_p)| over the vertices */
	double ref_radius;	/* largest |v - ref_p| */
	uint32_t *verts;
	size_t nverts;
	uint32_t seed;
	bool exact;
};

static void plane_of(const double sum_n[3], const double sum_p[3], double sum_a, double n[3],
		     double p[3])
{
	const double len = sqrt(sum_n[0] * sum_n[0] + sum_n[1] * sum_n[1] + sum_n[2] * sum_n[2]);

	for (int k = 0; k < 3; k++) {
		n[k] = len > 0 ? sum_n[k] / len : 0;
		p[k] = sum_p[k] / sum_a;
	}
}

static double plane_dist(const double n[3], const double p[3], const double *v)
{
	return fabs(n[0] * (v[0] - p[0]) + n[1] * (v[1] - p[1]) + n[2] * (v[2] - p[2]));
}

/* Measure every vertex against the current plane and make it the reference. */
static void rebase(const struct mesh *m, struct grow *g)
{
	memcpy(g->ref_n, g->n, sizeof(g->n));
	memcpy(g->ref_p, g->p, sizeof(g->p));
	g->ref_dist = g->ref_radius = 0;
	for (size_t i = 0; i < g->nverts; i++) {
		const double *v = m->verts[g->verts[i]];
		double d[3] = {v[0] - g->p[0], v[1] - g->p[1], v[2] - g->p[2]};

		g->ref_dist = fmax(g->ref_dist, plane_dist(g->n, g->p, v));
		g->ref_radius = fmax(g->ref_radius, sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]));
	}
}

/* Add facet t's share to the plane sums (or, with sign -1, take it back). */
static void sums_add(const struct planar_ctx *x, struct grow *g, uint32_t t, double sign)
{
	const uint32_t *v = x->m->tris[t];
	const double a = x->area[t] * sign;

	for (int k = 0; k < 3; k++) {
		g->sum_n[k] += 2 * a * x->unit[t][k];
		g->sum_p[k] += a * (x->m->verts[v[0]][k] + x->m->verts[v[1]][k] +
				    x->m->verts[v[2]][k]) / 3;
	}
	g->sum_a += a;
}

/*
 * Seed 001 §4.2, criteria 1 and 2: may facet t (next to the cluster
 * across an edge) join?  Exactly coplanar facets join an exactly planar
 * cluster outright; otherwise t's normal must lie within the angle of
 * the cluster plane and every vertex within flatness of the plane grown
 * by t.  The cluster's own vertices are measured only when a bound from
 * the last measurement (the plane moved by so much over so wide a
 * cluster) cannot settle it.  On success the sums include t.
 */
static bool may_join(const struct planar_ctx *x, struct grow *g, uint32_t t, double cos_angle,
		     bool *coplanar)
{
	const struct mesh *m = x->m;
	const uint32_t *s = m->tris[g->seed], *v = m->tris[t];
	const double eps = x->opt->flatness;
	double n1[3], p1[3], dn[3], bound;

	*coplanar = false;
	if (g->exact) {
		*coplanar = true;
		for (int k = 0; k < 3 && *coplanar; k++)
			*coplanar = exact_orient3d(m->verts[s[0]], m->verts[s[1]], m->verts[s[2]],
						   m->verts[v[k]]) == 0;
	}
	if (!*coplanar) {
		const double *u = x->unit[t];
		if (!(u[0] * g->n[0] + u[1] * g->n[1] + u[2] * g->n[2] > cos_angle))
			return false;
	}
	sums_add(x, g, t, 1);
	if (*coplanar)
		return true;
	plane_of(g->sum_n, g->sum_p, g->sum_a, n1, p1);
	for (int k = 0; k < 3; k++) {
		if (plane_dist(n1, p1, m->verts[v[k]]) > eps)
			goto refuse;
		dn[k] = n1[k] - g->ref_n[k];
	}
	bound = g->ref_dist + sqrt(dn[0] * dn[0] + dn[1] * dn[1] + dn[2] * dn[2]) * g->ref_radius +
		plane_dist(n1, p1, g->ref_p);
	if (bound > eps) {
		for (size_t i = 0; i < g->nverts; i++)
			if (plane_dist(n1, p1, m->verts[g->verts[i]]) > eps)
				goto refuse;
		/* measured: distances now refer to the grown plane */
		memcpy(g->n, n1, sizeof(n1));
		memcpy(g->p, p1, sizeof(p1));
		rebase(m, g);
	}
	return true;

refuse:
	sums_add(x, g, t, -1);
	return false;
}

/* Add t's vertices the cluster has not got yet (stamp marks them). */
static void take_vertices(const struct planar_ctx *x, struct grow *g, uint32_t t, uint32_t mark)
{
	for (int k = 0; k < 3; k++) {
		const uint32_t v = x->m->tris[t][k];
		if (x->stamp[v] == mark)
			continue;
		x->stamp[v] = mark;
		g->verts[g->nverts++] = v;
		{
			const double *p = x->m->verts[v];
			double d[3] = {p[0] - g->ref_p[0], p[1] - g->ref_p[1], p[2] - g->ref_p[2]};
			g->ref_dist = fmax(g->ref_dist, plane_dist(g->ref_n, g->ref_p, p));
			g->ref_radius =
			    fmax(g->ref_radius, sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]));
		}
	}
}

/* Seed 001 §4.1: grow clusters from the largest facets outwards. */
static int grow_clusters(struct planar_ctx *x, struct st_error *err)
{
	const struct mesh *m = x->m;
	const double cos_angle = cos(x->opt->angle * M_PI / 180);
	struct seed *seeds = malloc((m->ntris + 1) * sizeof(*seeds));
	uint32_t *queue = malloc((m->ntris + 1) * sizeof(*queue));
	struct grow g = {0};
	size_t ns = 0, nfill = 0;
	int rc = 0;

	g.verts = malloc((m->nverts + 1) * sizeof(*g.verts));
	x->cl = calloc(m->ntris + 1, sizeof(*x->cl));
	if (!seeds || !queue || !g.verts || !x->cl) {
		rc = st_error_set(err, ST_ERR_NOMEM, "planar simplification: out of memory");
		goto out;
	}
	for (size_t t = 0; t < m->ntris; t++) {
		x->cluster[t] = PLANAR_NONE;
		if (x->usable[t])
			seeds[ns++] = (struct seed){x->area[t], (uint32_t)t};
	}
	qsort(seeds, ns, sizeof(*seeds), seed_compare);
	for (size_t i = 0; i < ns; i++) {
		const uint32_t s = seeds[i].t, c = (uint32_t)x->ncl;
		struct planar_cluster *cl = &x->cl[c];
		size_t head = 0, tail = 0;
		double nrm[3];

		if (x->cluster[s] != PLANAR_NONE)
			continue;
		memset(g.sum_n, 0, sizeof(g.sum_n));
		memset(g.sum_p, 0, sizeof(g.sum_p));
		g.sum_a = 0;
		g.nverts = 0;
		g.seed = s;
		g.exact = true;
		sums_add(x, &g, s, 1);
		plane_of(g.sum_n, g.sum_p, g.sum_a, g.n, g.p);
		rebase(m, &g);
		take_vertices(x, &g, s, ++x->stamp_gen);
		x->cluster[s] = c;
		cl->first = nfill;
		x->cl_tris[nfill++] = s;
		queue[tail++] = s;
		while (head < tail) {
			const uint32_t t = queue[head++];
			for (int k = 0; k < 3; k++) {
				const uint32_t u = x->nb[t][k];
				bool coplanar;
				if (u == PLANAR_NONE || x->cluster[u] != PLANAR_NONE ||
				    !may_join(x, &g, u, cos_angle, &coplanar))
					continue;
				g.exact = g.exact && coplanar;
				plane_of(g.sum_n, g.sum_p, g.sum_a, g.n, g.p);
				take_vertices(x, &g, u, x->stamp_gen);
				x->cluster[u] = c;
				x->cl_tris[nfill++] = u;
				queue[tail++] = u;
			}
		}
		cl->n = nfill - cl->first;
		cl->exact = g.exact;
		plane_of(g.sum_n, g.sum_p, g.sum_a, nrm, g.p);
		memcpy(cl->normal, nrm, sizeof(nrm));
		x->ncl++;
	}
out:
	free(seeds);
	free(queue);
	free(g.verts);
	return rc;
}

/*
 * What may happen to each vertex: walking round a clean star, the number
 * of times the cluster changes tells interior (0) from a seam between two
 * clusters (2); a seam vertex goes only when its two seam edges run
 * straight on (exact), so both clusters drop it and no T-junction is left.
 */
static void classify(struct planar_ctx *x)
{
	const struct mesh *m = x->m;

	for (size_t v = 0; v < m->nverts; v++) {
		const size_t first = x->vt_start[v], deg = x->vt_start[v + 1] - first;
		uint32_t ends[2] = {0, 0};
		int changes = 0;

		x->role[v] = PLANAR_KEEP;
		if (!x->clean[v])
			continue;
		uint32_t t = x->vt[first];
		for (size_t i = 0; i < deg; i++) {
			const int k = planar_corner(m->tris[t], (uint32_t)v);
			const uint32_t u = x->nb[t][k];
			if (x->cluster[u] != x->cluster[t]) {
				if (changes < 2)
					ends[changes] = m->tris[t][(k + 1) % 3];
				changes++;
			}
			t = u;
		}
		if (changes == 0) {
			x->role[v] = PLANAR_INTERIOR;
		} else if (changes == 2) {
			const double *p = m->verts[v], *a = m->verts[ends[0]], *b = m->verts[ends[1]];
			const double dot = (a[0] - p[0]) * (b[0] - p[0]) + (a[1] - p[1]) * (b[1] - p[1]) +
					   (a[2] - p[2]) * (b[2] - p[2]);
			if (dot < 0 && exact_collinear(a, p, b))
				x->role[v] = PLANAR_SEAM;
		}
	}
}

int planar_grow(struct planar_ctx *x, struct st_error *err)
{
	const struct mesh *m = x->m;
	int rc;

	x->usable = calloc(m->ntris + 1, 1);
	x->nb = malloc((m->ntris + 1) * sizeof(*x->nb));
	x->area = calloc(m->ntris + 1, sizeof(*x->area));
	x->unit = calloc(m->ntris + 1, sizeof(*x->unit));
	x->clean = calloc(m->nverts + 1, 1);
	x->cluster = malloc((m->ntris + 1) * sizeof(*x->cluster));
	x->cl_tris = malloc((m->ntris + 1) * sizeof(*x->cl_tris));
	x->role = calloc(m->nverts + 1, 1);
	x->kept = calloc(m->nverts + 1, 1);
	x->next = calloc(m->nverts + 1, sizeof(*x->next));
	x->stamp = calloc(m->nverts + 1, sizeof(*x->stamp));
	x->seen = calloc(m->nverts + 1, sizeof(*x->seen));
	if (!x->usable || !x->nb || !x->area || !x->unit || !x->clean || !x->cluster ||
	    !x->cl_tris || !x->role || !x->kept || !x->next || !x->stamp || !x->seen)
		return st_error_set(err, ST_ERR_NOMEM, "planar simplification: out of memory");
	if ((rc = build_adjacency(x, err)) || (rc = build_stars(x, err)) ||
	    (rc = grow_clusters(x, err)))
		return rc;
	classify(x);
	return 0;
}
