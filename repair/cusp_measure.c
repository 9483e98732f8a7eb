/*
 * cusp_measure.c - seed 004's bounding-box cusp height (cusp_measure.h).
 *
 * The boxes of all layers go into one sorted table keyed by (layer, grid
 * cell in XY), a box under every cell its footprint covers; each cloud
 * point then looks at the boxes of its own layer and cell only.  The cloud
 * is made one facet at a time and never stored whole.
 */
#include "cusp_measure.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "st_grow.h"
#include "surfsample.h"

/* The cloud's size limit: beyond it the run would take many minutes. */
#define CUSP_POINTS_MAX 500000000.0
#define CELL_BITS 20 /* per axis in the table key; the layer above them */

struct box {
	double p1[2];	/* segment start, mm */
	double u[2];	/* unit, along the segment */
	double side[2]; /* unit, across it towards the box */
	double len;	/* segment length */
	double nf[3];	/* the cut facet's unit normal */
	double best;	/* largest cusp height of its points so far */
	double at[3];	/* the point that has it */
	uint32_t facet; /* and its facet */
	uint32_t layer;
	uint32_t npts;
};

struct entry {
	uint64_t key;
	uint32_t box;
};

struct measure {
	const struct mesh *m;
	double h, z0, cell, xmin, ymin;
	size_t nlayers;
	struct box *boxes;
	size_t nboxes, cap_boxes;
	struct entry *table;
	size_t ntable, cap_table;
};

static uint64_t key_of(uint32_t layer, uint64_t cx, uint64_t cy)
{
	return (uint64_t)layer << (2 * CELL_BITS) | cx << CELL_BITS | cy;
}

static uint64_t cell_of(double v, double lo, double cell)
{
	double c = floor((v - lo) / cell);
	double top = (double)((1u << CELL_BITS) - 1);

	return c < 0 ? 0 : c > top ? (uint64_t)top : (uint64_t)c;
}

static int cmp_entry(const void *a, const void *b)
{
	uint64_t x = ((const struct entry *)a)->key, y = ((const struct entry *)b)->key;

	return x < y ? -1 : x > y;
}

/* The box on one side of segment p q (mm, at layer) and its table entries. */
static int add_box(struct measure *ms, const double p[2], const double q[2], const double nf[3],
		   uint32_t layer, double sign, struct st_error *err)
{
	struct box *b;
	double len = hypot(q[0] - p[0], q[1] - p[1]);
	double lo[2], hi[2];

	if (!(len > 0))
		return 0;
	if (!(b = st_grow(ms->boxes, &ms->cap_boxes, ms->nboxes + 1, sizeof(*b))))
		return st_error_set(err, ST_ERR_NOMEM, "cusp height: out of memory for the boxes");
	ms->boxes = b;
	b += ms->nboxes;
	memset(b, 0, sizeof(*b));
	b->p1[0] = p[0];
	b->p1[1] = p[1];
	b->u[0] = (q[0] - p[0]) / len;
	b->u[1] = (q[1] - p[1]) / len;
	b->side[0] = -sign * b->u[1];
	b->side[1] = sign * b->u[0];
	b->len = len;
	memcpy(b->nf, nf, sizeof(b->nf));
	b->layer = layer;
	/* The footprint's corners: p, q, and both moved a layer height across. */
	for (int d = 0; d < 2; d++) {
		double a = p[d], c = q[d], e = p[d] + ms->h * b->side[d], f = q[d] + ms->h * b->side[d];
		lo[d] = fmin(fmin(a, c), fmin(e, f));
		hi[d] = fmax(fmax(a, c), fmax(e, f));
	}
	uint64_t cx0 = cell_of(lo[0], ms->xmin, ms->cell), cx1 = cell_of(hi[0], ms->xmin, ms->cell);
	uint64_t cy0 = cell_of(lo[1], ms->ymin, ms->cell), cy1 = cell_of(hi[1], ms->ymin, ms->cell);
	for (uint64_t cx = cx0; cx <= cx1; cx++)
		for (uint64_t cy = cy0; cy <= cy1; cy++) {
			struct entry *t = st_grow(ms->table, &ms->cap_table, ms->ntable + 1,
						  sizeof(*t));
			if (!t)
				return st_error_set(err, ST_ERR_NOMEM,
						    "cusp height: out of memory for the box table");
			ms->table = t;
			ms->table[ms->ntable].key = key_of(layer, cx, cy);
			ms->table[ms->ntable++].box = (uint32_t)ms->nboxes;
		}
	ms->nboxes++;
	return 0;
}

/* Steps 2 and 3: every facet crossing every plane gives its two boxes.  A
 * vertex on a plane counts as above it, as the slicer takes it. */
static int make_boxes(struct measure *ms, struct st_error *err)
{
	const struct mesh *m = ms->m;

	for (size_t t = 0; t < m->ntris; t++) {
		const double *v[3] = {m->verts[m->tris[t][0]], m->verts[m->tris[t][1]],
				      m->verts[m->tris[t][2]]};
		double nf[3], area, zlo = fmin(v[0][2], fmin(v[1][2], v[2][2]));
		double zhi = fmax(v[0][2], fmax(v[1][2], v[2][2]));
		int rc;

		if (!surfsample_normal(v[0], v[1], v[2], nf, &area))
			continue;
		/* planes z0 + (i + 1/2) h with zlo <= plane < zhi */
		double first = ceil((zlo - ms->z0) / ms->h - 0.5);
		for (double i = first < 0 ? 0 : first; i < (double)ms->nlayers; i++) {
			double plane = ms->z0 + (i + 0.5) * ms->h, pts[2][2];
			int n = 0;

			if (plane >= zhi)
				break;
			if (plane < zlo)
				continue;
			for (int e = 0; e < 3; e++) {
				const double *a = v[e], *b = v[(e + 1) % 3];
				if ((a[2] >= plane) == (b[2] >= plane) || n == 2)
					continue;
				double s = (plane - a[2]) / (b[2] - a[2]);
				pts[n][0] = a[0] + s * (b[0] - a[0]);
				pts[n][1] = a[1] + s * (b[1] - a[1]);
				n++;
			}
			if (n < 2)
				continue;
			if ((rc = add_box(ms, pts[0], pts[1], nf, (uint32_t)i, 1.0, err)) ||
			    (rc = add_box(ms, pts[0], pts[1], nf, (uint32_t)i, -1.0, err)))
				return rc;
		}
	}
	qsort(ms->table, ms->ntable, sizeof(*ms->table), cmp_entry);
	return 0;
}

/* How far p goes along d inside box b of a layer from zb to zb + h: the
 * first of its faces the ray leaves through. */
static double exit_length(const struct box *b, const double q[2], double zrel, double h,
			  const double d[3])
{
	const double x[3] = {q[0] * b->u[0] + q[1] * b->u[1], q[0] * b->side[0] + q[1] * b->side[1],
			     zrel};
	const double hi[3] = {b->len, h, h};
	const double rate[3] = {d[0] * b->u[0] + d[1] * b->u[1],
				d[0] * b->side[0] + d[1] * b->side[1], d[2]};
	double t = INFINITY;

	for (int k = 0; k < 3; k++) {
		if (rate[k] > 0)
			t = fmin(t, (hi[k] - x[k]) / rate[k]);
		else if (rate[k] < 0)
			t = fmin(t, -x[k] / rate[k]);
	}
	return t < 0 ? 0 : t;
}

/* Step 4 for point p with normal n in box b: its cusp height, or -1 when
 * the point is outside the box or on a facet facing away from b's. */
static double box_cusp(const struct measure *ms, const struct box *b, const double p[3],
		       const double n[3])
{
	const double q[2] = {p[0] - b->p1[0], p[1] - b->p1[1]};
	double along = q[0] * b->u[0] + q[1] * b->u[1];
	double across = q[0] * b->side[0] + q[1] * b->side[1];
	double zrel = p[2] - (ms->z0 + (double)b->layer * ms->h);

	if (along < 0 || along > b->len || across < 0 || across > ms->h || zrel < 0 || zrel > ms->h)
		return -1;
	if (n[0] * b->nf[0] + n[1] * b->nf[1] + n[2] * b->nf[2] <= 0)
		return -1; /* another wall within reach, facing away */
	/* The ray runs towards the wall: the normal or its reverse. */
	double towards = n[0] * b->side[0] + n[1] * b->side[1];
	const double rev[3] = {-n[0], -n[1], -n[2]};
	if (towards < 0)
		return exit_length(b, q, zrel, ms->h, n);
	if (towards > 0)
		return exit_length(b, q, zrel, ms->h, rev);
	return fmin(exit_length(b, q, zrel, ms->h, n), exit_length(b, q, zrel, ms->h, rev));
}

/* Step 4 for one cloud point p of facet t: every box of its layer and cell. */
static void measure_point(struct measure *ms, const double p[3], const double n[3], uint32_t t)
{
	double lz = floor((p[2] - ms->z0) / ms->h);

	if (lz < 0 || lz >= (double)ms->nlayers)
		return;
	uint64_t key = key_of((uint32_t)lz, cell_of(p[0], ms->xmin, ms->cell),
			      cell_of(p[1], ms->ymin, ms->cell));
	size_t lo = 0, hi = ms->ntable;

	while (lo < hi) {
		size_t mid = lo + (hi - lo) / 2;
		if (ms->table[mid].key < key)
			lo = mid + 1;
		else
			hi = mid;
	}
	for (; lo < ms->ntable && ms->table[lo].key == key; lo++) {
		struct box *b = &ms->boxes[ms->table[lo].box];
		double c = box_cusp(ms, b, p, n);

		if (c < 0)
			continue;
		if (c > b->best || !b->npts) {
			b->best = c;
			memcpy(b->at, p, sizeof(b->at));
			b->facet = t;
		}
		b->npts++;
	}
}

/*
 * The cloud's best point of box b sits within a spacing of the box's
 * largest value on that facet (the value is a minimum of linear functions
 * there, so it has no other peak): search a grid of REFINE_STEPS^2 points
 * around it, REFINE_ROUNDS times, each round's grid a REFINE_SHRINK-th of
 * the last, keeping the points inside the facet.
 */
#define REFINE_STEPS 7
#define REFINE_ROUNDS 3
#define REFINE_SHRINK 3.0
static void refine_box(const struct measure *ms, struct box *b, double spacing)
{
	const struct mesh *m = ms->m;
	const double *v[3] = {m->verts[m->tris[b->facet][0]], m->verts[m->tris[b->facet][1]],
			      m->verts[m->tris[b->facet][2]]};
	double n[3], area, e1[3], e2[3], len = 0;

	if (!surfsample_normal(v[0], v[1], v[2], n, &area))
		return;
	for (int d = 0; d < 3; d++)
		e1[d] = v[1][d] - v[0][d], len += e1[d] * e1[d];
	len = sqrt(len);
	for (int d = 0; d < 3; d++)
		e1[d] /= len;
	e2[0] = n[1] * e1[2] - n[2] * e1[1];
	e2[1] = n[2] * e1[0] - n[0] * e1[2];
	e2[2] = n[0] * e1[1] - n[1] * e1[0];
	double step = 2 * spacing / (REFINE_STEPS - 1);
	for (int round = 0; round < REFINE_ROUNDS; round++, step /= REFINE_SHRINK) {
		double centre[3];
		memcpy(centre, b->at, sizeof(centre));
		for (int i = 0; i < REFINE_STEPS; i++)
			for (int j = 0; j < REFINE_STEPS; j++) {
				double s = (i - (REFINE_STEPS - 1) / 2) * step;
				double r = (j - (REFINE_STEPS - 1) / 2) * step, p[3];
				for (int d = 0; d < 3; d++)
					p[d] = centre[d] + s * e1[d] + r * e2[d];
				if (!surfsample_inside(v[0], v[1], v[2], n, p))
					continue;
				double c = box_cusp(ms, b, p, n);
				if (c > b->best) {
					b->best = c;
					memcpy(b->at, p, sizeof(b->at));
				}
			}
	}
}

/* Step 1, one facet at a time, each point measured as it is made; then
 * each box's best point refined. */
static int sample_cloud(struct measure *ms, double spacing, size_t *npoints, struct st_error *err)
{
	const struct mesh *m = ms->m;
	double total = 0;
	double (*pts)[3] = NULL;
	size_t cap = 0;

	for (size_t t = 0; t < m->ntris; t++) {
		size_t k = surfsample_k(m->verts[m->tris[t][0]], m->verts[m->tris[t][1]],
					m->verts[m->tris[t][2]], spacing);
		total += (double)k * (double)k;
	}
	if (total > CUSP_POINTS_MAX)
		return st_error_set(err, ST_ERR_RANGE,
				    "cusp height: a cloud %g mm apart would have %.3g points, more "
				    "than %.3g; give a larger spacing",
				    spacing, total, CUSP_POINTS_MAX);
	for (size_t t = 0; t < m->ntris; t++) {
		const double *a = m->verts[m->tris[t][0]], *b = m->verts[m->tris[t][1]],
			     *c = m->verts[m->tris[t][2]];
		double n[3], area;
		size_t k = surfsample_k(a, b, c, spacing);

		if (!surfsample_normal(a, b, c, n, &area))
			continue;
		if (k * k > cap) {
			free(pts);
			cap = k * k;
			if (!(pts = malloc(cap * sizeof(*pts))))
				return st_error_set(err, ST_ERR_NOMEM,
						    "cusp height: out of memory for the cloud");
		}
		surfsample_centroids(a, b, c, k, pts);
		for (size_t i = 0; i < k * k; i++)
			measure_point(ms, pts[i], n, (uint32_t)t);
		*npoints += k * k;
	}
	free(pts);
	for (size_t i = 0; i < ms->nboxes; i++)
		if (ms->boxes[i].npts)
			refine_box(ms, &ms->boxes[i], spacing);
	return 0;
}

/* The figures per layer and overall from the boxes that hold points. */
static int summarize(const struct measure *ms, struct cusp_report *r, struct st_error *err)
{
	double sum = 0;

	r->nslices = ms->nlayers;
	r->slices = calloc(ms->nlayers, sizeof(*r->slices));
	r->boxes = malloc((ms->nboxes ? ms->nboxes : 1) * sizeof(*r->boxes));
	if (!r->slices || !r->boxes)
		return st_error_set(err, ST_ERR_NOMEM, "cusp height: out of memory for the report");
	for (size_t i = 0; i < ms->nlayers; i++)
		r->slices[i].z = ((double)i + 0.5) * ms->h;
	for (size_t i = 0; i < ms->nboxes; i++) {
		const struct box *b = &ms->boxes[i];
		struct cusp_slice *s = &r->slices[b->layer];

		if (!b->npts)
			continue;
		s->max = fmax(s->max, b->best);
		s->mean += b->best; /* a sum until the end */
		s->boxes++;
		if (b->best > r->max || !r->nboxes) {
			r->max = b->best;
			r->max_z = s->z;
		}
		sum += b->best;
		r->boxes[r->nboxes].z = (float)s->z;
		r->boxes[r->nboxes++].cusp = (float)b->best;
	}
	for (size_t i = 0; i < ms->nlayers; i++)
		if (r->slices[i].boxes)
			r->slices[i].mean /= (double)r->slices[i].boxes;
	r->mean = r->nboxes ? sum / (double)r->nboxes : 0;
	return 0;
}

int cusp_measure(const struct mesh *m, double layer_height, double spacing,
		 struct cusp_report *r, struct st_error *err)
{
	struct measure ms = {.m = m, .h = layer_height};
	double lo[3], hi[3], layers;
	int rc;

	memset(r, 0, sizeof(*r));
	if (!(layer_height > 0) || !(spacing > 0))
		return st_error_set(err, ST_ERR_ARG,
				    "cusp height: the layer height and the spacing must be above 0");
	if (!m->ntris)
		return st_error_set(err, ST_ERR_ARG, "cusp height: the mesh has no triangles");
	mesh_bbox(m, lo, hi);
	layers = ceil((hi[2] - lo[2]) / layer_height - 0.5);
	if (!(layers <= CUSP_MEASURE_LAYERS_MAX))
		return st_error_set(err, ST_ERR_RANGE,
				    "cusp height: %g mm layers over %g mm make more than %d layers",
				    layer_height, hi[2] - lo[2], CUSP_MEASURE_LAYERS_MAX);
	ms.nlayers = layers < 1 ? 1 : (size_t)layers;
	ms.z0 = lo[2];
	ms.xmin = lo[0] - layer_height;
	ms.ymin = lo[1] - layer_height;
	/* a cell as wide as a box, unless the key's bits cannot cover the part */
	ms.cell = fmax(layer_height, fmax(hi[0] - lo[0], hi[1] - lo[1]) / (double)(1u << (CELL_BITS - 1)));
	r->layer_height = layer_height;
	r->spacing = spacing;
	if (!(rc = make_boxes(&ms, err)) && !(rc = sample_cloud(&ms, spacing, &r->points, err)))
		rc = summarize(&ms, r, err);
	free(ms.boxes);
	free(ms.table);
	if (rc)
		cusp_report_free(r);
	return rc;
}

void cusp_report_free(struct cusp_report *r)
{
	free(r->slices);
	free(r->boxes);
	memset(r, 0, sizeof(*r));
}
