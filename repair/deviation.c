/*
 * deviation.c - symmetric surface distance and chordal error
 * (deviation.h).  Samples go to the tree in chunks, so memory stays at a
 * few bytes per sample for the statistics.
 */
#include "deviation.h"

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "st_grow.h"
#include "surfdist.h"
#include "surfsample.h"
#include "vec3.h"

#define CHUNK (1u << 18) /* samples per batch of queries */
#define P_SHARE 0.95	 /* the percentile reported */

static double longest_edge(const double a[3], const double b[3], const double c[3])
{
	return fmax(vec3_dist(a, b), fmax(vec3_dist(b, c), vec3_dist(c, a)));
}

/* The spacing that gives about `samples` samples on m: a triangle whose
 * longest edge is L gets (L / spacing)^2. */
static double spacing_for(const struct mesh *m, size_t samples)
{
	double sum = 0;

	for (size_t t = 0; t < m->ntris; t++) {
		double l = longest_edge(m->verts[m->tris[t][0]], m->verts[m->tris[t][1]],
					m->verts[m->tris[t][2]]);
		sum += l * l;
	}
	return sqrt(sum / (double)(samples ? samples : 1));
}

static int tree_of(const struct mesh *m, struct surfdist **t, struct st_error *err)
{
	return surfdist_new((const double (*)[3])m->verts, m->nverts,
			    (const uint32_t (*)[3])m->tris, m->ntris, t, err);
}

/* A sample's distance and the area it stands for. */
struct weighted {
	double d, w;
};

static int cmp_weighted(const void *x, const void *y)
{
	double a = ((const struct weighted *)x)->d, b = ((const struct weighted *)y)->d;

	return a < b ? -1 : a > b;
}

/* Samples waiting for their queries, with where each result goes. */
struct batch {
	double (*pts)[3];
	double (*dirs)[3];
	uint32_t *facet;
	double *w;
	double *dist;
	size_t n;
};

static int batch_init(struct batch *b, bool dirs, struct st_error *err)
{
	memset(b, 0, sizeof(*b));
	b->pts = malloc(CHUNK * sizeof(*b->pts));
	b->dirs = dirs ? malloc(CHUNK * sizeof(*b->dirs)) : NULL;
	b->facet = malloc(CHUNK * sizeof(*b->facet));
	b->w = malloc(CHUNK * sizeof(*b->w));
	b->dist = malloc(CHUNK * sizeof(*b->dist));
	if (!b->pts || (dirs && !b->dirs) || !b->facet || !b->w || !b->dist)
		return st_error_set(err, ST_ERR_NOMEM, "surface distance: out of memory");
	return 0;
}

static void batch_free(struct batch *b)
{
	free(b->pts);
	free(b->dirs);
	free(b->facet);
	free(b->w);
	free(b->dist);
}

/* ---- symmetric distance ---- */

struct side_work {
	struct deviation_side *side;
	struct weighted *all; /* every sample of both sides */
	size_t nall, cap_all;
	float *facet_max;     /* or NULL */
};

static int side_flush(struct side_work *sw, struct batch *b, const struct surfdist *other,
		      struct st_error *err)
{
	int rc = surfdist_nearest(other, (const double (*)[3])b->pts, b->n, b->dist, NULL, err);

	if (rc)
		return rc;
	for (size_t i = 0; i < b->n; i++) {
		double d = b->dist[i];
		sw->side->max = fmax(sw->side->max, d);
		sw->side->mean += d * b->w[i]; /* a sum until the end */
		sw->all[sw->nall].d = d;
		sw->all[sw->nall++].w = b->w[i];
		if (sw->facet_max && d > sw->facet_max[b->facet[i]])
			sw->facet_max[b->facet[i]] = (float)d;
	}
	b->n = 0;
	return 0;
}

/* Samples on m, their distances to other, into sw. */
static int measure_side(const struct mesh *m, const struct surfdist *other, double spacing,
			struct side_work *sw, struct batch *b, struct st_error *err)
{
	int rc;
	double (*tmp)[3] = malloc((size_t)SURFSAMPLE_K_MAX * SURFSAMPLE_K_MAX * sizeof(*tmp));

	if (!tmp)
		return st_error_set(err, ST_ERR_NOMEM, "surface distance: out of memory");
	for (size_t t = 0; t < m->ntris; t++) {
		const double *p = m->verts[m->tris[t][0]], *q = m->verts[m->tris[t][1]],
			     *r = m->verts[m->tris[t][2]];
		double n[3], area;
		size_t k = surfsample_k(p, q, r, spacing);

		if (!surfsample_normal(p, q, r, n, &area))
			continue;
		sw->side->area += area;
		struct weighted *grown = st_grow(sw->all, &sw->cap_all, sw->nall + b->n + k * k,
						 sizeof(*grown));
		if (!grown) {
			free(tmp);
			return st_error_set(err, ST_ERR_NOMEM, "surface distance: out of memory");
		}
		sw->all = grown;
		surfsample_centroids(p, q, r, k, tmp);
		for (size_t i = 0; i < k * k; i++) {
			if (b->n == CHUNK && (rc = side_flush(sw, b, other, err))) {
				free(tmp);
				return rc;
			}
			memcpy(b->pts[b->n], tmp[i], sizeof(tmp[i]));
			b->facet[b->n] = (uint32_t)t;
			b->w[b->n++] = area / (double)(k * k);
		}
		sw->side->samples += k * k;
	}
	free(tmp);
	if (b->n && (rc = side_flush(sw, b, other, err)))
		return rc;
	if (sw->side->area > 0)
		sw->side->mean /= sw->side->area;
	return 0;
}

/* Percentile, histogram and overall figures from every sample. */
static void summarize(struct deviation_report *r, struct weighted *all, size_t n)
{
	double total = 0, acc = 0;

	r->max = fmax(r->a_to_b.max, r->b_to_a.max);
	total = r->a_to_b.area + r->b_to_a.area;
	r->mean = total > 0 ? (r->a_to_b.mean * r->a_to_b.area + r->b_to_a.mean * r->b_to_a.area) /
				  total
			    : 0;
	qsort(all, n, sizeof(*all), cmp_weighted);
	for (size_t i = 0; i < n; i++) {
		acc += all[i].w;
		if (acc >= P_SHARE * total) {
			r->p95 = all[i].d;
			break;
		}
	}
	r->bin_width = r->max / DEVIATION_BINS;
	for (size_t i = 0; i < n && total > 0; i++) {
		int bin = r->bin_width > 0 ? (int)(all[i].d / r->bin_width) : 0;
		r->hist[bin >= DEVIATION_BINS ? DEVIATION_BINS - 1 : bin] += all[i].w / total;
	}
}

int deviation_measure(const struct mesh *a, const struct mesh *b, size_t samples,
		      struct deviation_report *r, struct st_error *err)
{
	struct surfdist *ta = NULL, *tb = NULL;
	struct side_work sw = {0};
	struct batch bt;
	int rc;

	memset(r, 0, sizeof(*r));
	if (!(r->facet_a = calloc(a->ntris ? a->ntris : 1, sizeof(*r->facet_a))))
		return st_error_set(err, ST_ERR_NOMEM, "surface distance: out of memory");
	if (!(rc = batch_init(&bt, false, err)) && !(rc = tree_of(a, &ta, err)) &&
	    !(rc = tree_of(b, &tb, err))) {
		sw.side = &r->a_to_b;
		sw.facet_max = r->facet_a;
		rc = measure_side(a, tb, spacing_for(a, samples), &sw, &bt, err);
		if (!rc) {
			sw.side = &r->b_to_a;
			sw.facet_max = NULL;
			rc = measure_side(b, ta, spacing_for(b, samples), &sw, &bt, err);
		}
		if (!rc)
			summarize(r, sw.all, sw.nall);
	}
	batch_free(&bt);
	free(sw.all);
	surfdist_free(ta);
	surfdist_free(tb);
	if (rc)
		deviation_report_free(r);
	return rc;
}

void deviation_report_free(struct deviation_report *r)
{
	free(r->facet_a);
	memset(r, 0, sizeof(*r));
}

/* ---- chordal error ---- */

/* Farther along the normal than this many times the nearest point, the
 * line has missed the part of the reference the facet stands for (it
 * passed a tip the finer surface rounds off, or grazed a bump) and met
 * another.  Beside a crease (a cylinder's rim) the nearest point is on the
 * cap while the side is a sagitta away along the normal: the reference's
 * points find that sagitta (back_flush). */
#define CHORDAL_REACH 3.0
/* The nearer crossing counts only where the reference there faces the
 * facet's way within acos(1/3) = 70.5 degrees: the far side of a thin part
 * faces away, as does the surface under a facet turned over on it, and a
 * line that grazes a surface (a facet standing across a scan's bump)
 * overstates the distance to it there by more than CHORDAL_REACH times
 * (1 / cos of the angle). */
#define CHORDAL_MIN_COS (1.0 / CHORDAL_REACH)
/* At least this grid on each facet of a, so points inside it too, where a
 * curved surface strays furthest from a small facet; and on each facet of
 * the reference at least its centroid and two points on each edge besides
 * its corners (fewer let the elephant of docs/accuracy.md end 9 % over
 * the tolerance by the surface distance). */
#define FACET_K_MIN 6
#define BACK_K_MIN 3

static int chordal_flush(struct chordal_report *r, struct batch *b, const struct surfdist *ref,
			 double *near, double *sum, struct st_error *err)
{
	int rc = surfdist_along(ref, (const double (*)[3])b->pts, (const double (*)[3])b->dirs,
				b->n, CHORDAL_MIN_COS, b->dist, err);

	if (!rc)
		rc = surfdist_nearest(ref, (const double (*)[3])b->pts, b->n, near, NULL, err);
	if (rc)
		return rc;
	for (size_t i = 0; i < b->n; i++) {
		double d = b->dist[i];
		if (d < 0 || d > CHORDAL_REACH * near[i])
			d = near[i];
		*sum += d;
		if (d > r->facet[b->facet[i]])
			r->facet[b->facet[i]] = (float)d;
	}
	b->n = 0;
	return 0;
}

/* From a's facets: the distance along each facet's normal, on a grid. */
static int chordal_points(const struct mesh *a, const struct surfdist *ref, double spacing,
			  struct chordal_report *r, struct batch *b, struct st_error *err)
{
	double sum = 0, *near = malloc(CHUNK * sizeof(*near));
	int rc;
	double (*tmp)[3] = malloc(((size_t)SURFSAMPLE_K_MAX + 1) * (SURFSAMPLE_K_MAX + 2) / 2 *
				  sizeof(*tmp));

	if (!tmp || !near) {
		free(tmp);
		free(near);
		return st_error_set(err, ST_ERR_NOMEM, "chordal error: out of memory");
	}
	for (size_t t = 0; t < a->ntris; t++) {
		const double *p = a->verts[a->tris[t][0]], *q = a->verts[a->tris[t][1]],
			     *s = a->verts[a->tris[t][2]];
		double n[3], area;
		/* even, so the grid holds every edge's midpoint, where a chord
		 * strays furthest from an arc */
		size_t k = surfsample_k(p, q, s, spacing), npts;

		if (!surfsample_normal(p, q, s, n, &area))
			continue;
		k += k % 2;
		if (k < FACET_K_MIN)
			k = FACET_K_MIN;
		if (k > SURFSAMPLE_K_MAX)
			k = SURFSAMPLE_K_MAX;
		npts = (k + 1) * (k + 2) / 2;
		surfsample_grid(p, q, s, k, tmp);
		for (size_t i = 0; i < npts; i++) {
			if (b->n == CHUNK && (rc = chordal_flush(r, b, ref, near, &sum, err))) {
				free(tmp);
				free(near);
				return rc;
			}
			memcpy(b->pts[b->n], tmp[i], sizeof(tmp[i]));
			memcpy(b->dirs[b->n], n, sizeof(n));
			b->facet[b->n++] = (uint32_t)t;
		}
		r->points += npts;
	}
	free(tmp);
	rc = b->n ? chordal_flush(r, b, ref, near, &sum, err) : 0;
	free(near);
	if (rc)
		return rc;
	r->mean = r->points ? sum / (double)r->points : 0;
	return 0;
}

/* The queued points of ref: each raises its nearest facet of a to how far
 * it lies from that facet's plane (along its normal, as seed 003 measures:
 * where the nearest point is on an edge shared with a facet at an angle, a
 * cylinder's rim, the offset sideways is the other facet's error). */
static int back_flush(const struct mesh *a, struct batch *b, const struct surfdist *ta,
		      double (*at)[3], float *facet, struct st_error *err)
{
	int rc = surfdist_closest(ta, (const double (*)[3])b->pts, b->n, at, b->facet, err);

	for (size_t i = 0; !rc && i < b->n; i++) {
		const uint32_t *c = a->tris[b->facet[i]];
		double n[3], area, d = 0;
		surfsample_normal(a->verts[c[0]], a->verts[c[1]], a->verts[c[2]], n, &area);
		for (int k = 0; k < 3; k++)
			d += (b->pts[i][k] - at[i][k]) * n[k];
		d = fabs(d);
		if (d > facet[b->facet[i]])
			facet[b->facet[i]] = (float)d;
	}
	b->n = 0;
	return rc;
}

/* From ref's facets: points on a grid over each, each raising the facet of
 * a nearest to it (ta, the tree over a), as back_flush says. */
static int back_points(const struct mesh *a, const struct mesh *ref, const struct surfdist *ta,
		       double spacing, float *facet, struct batch *b, struct st_error *err)
{
	double (*tmp)[3] = malloc(((size_t)SURFSAMPLE_K_MAX + 1) * (SURFSAMPLE_K_MAX + 2) / 2 *
				  sizeof(*tmp));
	double (*at)[3] = malloc(CHUNK * sizeof(*at));
	int rc = tmp && at ? 0 : st_error_set(err, ST_ERR_NOMEM, "chordal error: out of memory");

	for (size_t t = 0; !rc && t < ref->ntris; t++) {
		const double *p = ref->verts[ref->tris[t][0]], *q = ref->verts[ref->tris[t][1]],
			     *s = ref->verts[ref->tris[t][2]];
		size_t k = surfsample_k(p, q, s, spacing);
		k = k < BACK_K_MIN ? BACK_K_MIN : k;
		size_t npts = (k + 1) * (k + 2) / 2;

		surfsample_grid(p, q, s, k, tmp);
		for (size_t i = 0; i < npts && !rc; i++) {
			if (b->n == CHUNK)
				rc = back_flush(a, b, ta, at, facet, err);
			memcpy(b->pts[b->n++], tmp[i], sizeof(tmp[i]));
		}
	}
	if (!rc && b->n)
		rc = back_flush(a, b, ta, at, facet, err);
	free(tmp);
	free(at);
	return rc;
}

/* An edge of a facet over the tolerance, by its welded corners. */
struct over_edge {
	uint32_t lo, hi, slot; /* slot: index into r->over */
};

static int cmp_edge(const void *x, const void *y)
{
	const struct over_edge *a = x, *b = y;

	if (a->lo != b->lo)
		return a->lo < b->lo ? -1 : 1;
	return a->hi < b->hi ? -1 : a->hi > b->hi;
}

static uint32_t find_root(uint32_t *parent, uint32_t i)
{
	while (parent[i] != i)
		i = parent[i] = parent[parent[i]];
	return i;
}

/* Seed 003's facet isolation: the facets over the tolerance, grouped into
 * regions that share edges. */
static int isolate(const struct mesh *a, struct chordal_report *r, struct st_error *err)
{
	struct over_edge *edges;
	uint32_t *parent;

	for (size_t t = 0; t < a->ntris; t++)
		r->nover += r->facet[t] > r->tolerance;
	r->over = malloc((r->nover ? r->nover : 1) * sizeof(*r->over));
	edges = malloc((r->nover ? 3 * r->nover : 1) * sizeof(*edges));
	parent = malloc((r->nover ? r->nover : 1) * sizeof(*parent));
	if (!r->over || !edges || !parent) {
		free(edges);
		free(parent);
		return st_error_set(err, ST_ERR_NOMEM, "chordal error: out of memory");
	}
	size_t n = 0;
	for (size_t t = 0; t < a->ntris; t++) {
		if (!(r->facet[t] > r->tolerance))
			continue;
		const uint32_t *c = a->tris[t];
		r->over_area += vec3_tri_area(a->verts[c[0]], a->verts[c[1]], a->verts[c[2]]);
		for (int e = 0; e < 3; e++) {
			uint32_t u = c[e], v = c[(e + 1) % 3];
			edges[3 * n + e] = (struct over_edge){u < v ? u : v, u < v ? v : u, (uint32_t)n};
		}
		parent[n] = (uint32_t)n;
		r->over[n++] = (uint32_t)t;
	}
	qsort(edges, 3 * n, sizeof(*edges), cmp_edge);
	for (size_t i = 1; i < 3 * n; i++)
		if (!cmp_edge(&edges[i - 1], &edges[i]))
			parent[find_root(parent, edges[i].slot)] =
			    find_root(parent, edges[i - 1].slot);
	for (size_t i = 0; i < n; i++)
		r->regions += find_root(parent, (uint32_t)i) == i;
	free(edges);
	free(parent);
	return 0;
}

int chordal_measure(const struct mesh *a, const struct mesh *ref, size_t samples,
		    double tolerance, struct chordal_report *r, struct st_error *err)
{
	struct surfdist *tr = NULL, *ta = NULL;
	struct batch bt;
	int rc;

	memset(r, 0, sizeof(*r));
	r->tolerance = tolerance;
	if (!(r->facet = calloc(a->ntris ? a->ntris : 1, sizeof(*r->facet))))
		return st_error_set(err, ST_ERR_NOMEM, "chordal error: out of memory");
	if (!(rc = batch_init(&bt, true, err)) && !(rc = tree_of(ref, &tr, err)) &&
	    !(rc = chordal_points(a, tr, spacing_for(a, samples), r, &bt, err)) &&
	    !(rc = tree_of(a, &ta, err)) &&
	    !(rc = back_points(a, ref, ta, spacing_for(ref, samples), r->facet, &bt, err))) {
		for (size_t t = 0; t < a->ntris; t++)
			r->max = fmax(r->max, r->facet[t]);
		rc = isolate(a, r, err);
	}
	batch_free(&bt);
	surfdist_free(tr);
	surfdist_free(ta);
	if (rc)
		chordal_report_free(r);
	return rc;
}

void chordal_report_free(struct chordal_report *r)
{
	free(r->facet);
	free(r->over);
	memset(r, 0, sizeof(*r));
}
