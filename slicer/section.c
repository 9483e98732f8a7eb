/*
 * section.c - triangle/plane intersection, contour chaining by mesh edge
 * identity, regions by fill rule (see section.h).
 */
#include "section.h"

#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "grow.h"
#include "toolpath.h"

/* Largest |coordinate| we accept, mm: keeps nm values far inside int64. */
#define SLICE_MAX_COORD 1e6

/*
 * One cut segment: it enters the triangle through mesh edge `from` and
 * leaves through `to` (keys of welded vertex index pairs), with the solid on
 * its left for an outward-oriented triangle.
 */
struct seg {
	uint64_t from, to;
	int64_t x0, y0; /* crossing point on edge from, nm */
	int64_t x1, y1; /* crossing point on edge to, nm */
};

struct seg_list {
	struct seg *v;
	size_t n, cap;
};

void slice_settings_init(struct slice_settings *s)
{
	s->nozzle_diameter = 0.4;
	s->close_gap = 0.05;
	s->fill = CLIP_NONZERO;
}

int slice_settings_check(const struct slice_settings *s, double first_layer_height,
			 double layer_height, struct st_error *err)
{
	if (!s)
		return st_error_set(err, ST_ERR_ARG, "slice: no settings given");
	if (!(s->nozzle_diameter > 0.0 && s->nozzle_diameter <= 5.0))
		return st_error_set(err, ST_ERR_RANGE,
				    "slice: nozzle diameter %g mm is out of range; use (0, 5] mm",
				    s->nozzle_diameter);
	if (!(first_layer_height > 0.0 && first_layer_height <= s->nozzle_diameter))
		return st_error_set(err, ST_ERR_RANGE,
				    "slice: first layer height %g mm is out of range; it must be "
				    "> 0 and at most the nozzle diameter %g mm",
				    first_layer_height, s->nozzle_diameter);
	if (!(layer_height > 0.0 && layer_height <= s->nozzle_diameter))
		return st_error_set(err, ST_ERR_RANGE,
				    "slice: layer height %g mm is out of range; it must be > 0 and "
				    "at most the nozzle diameter %g mm",
				    layer_height, s->nozzle_diameter);
	if (!(s->close_gap >= 0.0 && s->close_gap <= 10.0))
		return st_error_set(err, ST_ERR_RANGE,
				    "slice: contour gap tolerance %g mm is out of range; use [0, 10] mm",
				    s->close_gap);
	if ((unsigned)s->fill >= CLIP_FILLS)
		return st_error_set(err, ST_ERR_ARG, "slice: fill rule %d is not a clip_fill value",
				    (int)s->fill);
	return 0;
}

/* Key of the undirected mesh edge a-b. */
static uint64_t edge_key(uint32_t a, uint32_t b)
{
	return a < b ? ((uint64_t)a << 32) | b : ((uint64_t)b << 32) | a;
}

static int64_t to_nm(double mm)
{
	return (int64_t)llround(mm * SLICE_UNITS_PER_MM);
}

/*
 * Where edge lo-hi crosses plane zp, lo strictly below and hi on or above
 * it.  Computed from (below, above) whichever way the triangle walks the
 * edge, so both triangles of an edge get bit-identical points; a vertex on
 * the plane is returned as itself.
 */
static void crossing(const double *lo, const double *hi, double zp, int64_t *x, int64_t *y)
{
	if (hi[2] == zp) {
		*x = to_nm(hi[0]);
		*y = to_nm(hi[1]);
		return;
	}
	double t = (zp - lo[2]) / (hi[2] - lo[2]);
	*x = to_nm(lo[0] + t * (hi[0] - lo[0]));
	*y = to_nm(lo[1] + t * (hi[1] - lo[1]));
}

/*
 * The segment where triangle t meets plane zp, if any (returns true).
 * A vertex counts as above when z >= zp (symbolic perturbation: the plane
 * is infinitesimally lower than zp), so exactly zero or two of the edges
 * change side.  Walking the triangle a->b->c, the edge leaving the upper
 * side starts the segment and the edge entering it ends it: for an
 * outward normal n, that direction is z x n, which keeps the solid on the
 * segment's left, i.e. outer contours come out counter-clockwise.
 */
static bool tri_segment(const struct mesh *m, size_t t, double zp, struct seg *s)
{
	const uint32_t *v = m->tris[t];
	bool above[3];
	int down = -1, up = -1;

	for (int k = 0; k < 3; k++)
		above[k] = m->verts[v[k]][2] >= zp;
	for (int k = 0; k < 3; k++) {
		int k1 = (k + 1) % 3;
		if (above[k] && !above[k1])
			down = k;
		else if (!above[k] && above[k1])
			up = k;
	}
	if (down < 0 || up < 0)
		return false;
	uint32_t da = v[down], db = v[(down + 1) % 3]; /* da above, db below */
	uint32_t ua = v[up], ub = v[(up + 1) % 3];     /* ua below, ub above */
	s->from = edge_key(da, db);
	s->to = edge_key(ua, ub);
	if (s->from == s->to) /* irregular triangle: both crossings on one edge */
		return false;
	crossing(m->verts[db], m->verts[da], zp, &s->x0, &s->y0);
	crossing(m->verts[ua], m->verts[ub], zp, &s->x1, &s->y1);
	return true;
}

static int seg_push(struct seg_list *l, const struct seg *s, struct st_error *err)
{
	struct seg *grown = slice_grow(l->v, &l->cap, l->n + 1, sizeof(*grown));

	if (!grown)
		return st_error_set(err, ST_ERR_NOMEM, "slice: out of memory for segments");
	l->v = grown;
	l->v[l->n++] = *s;
	return 0;
}

static int seg_cmp_from(const void *a, const void *b)
{
	uint64_t x = ((const struct seg *)a)->from, y = ((const struct seg *)b)->from;
	return (x > y) - (x < y);
}

/* Index of an unused segment starting on edge key, or SIZE_MAX (segs sorted by from). */
static size_t find_from(const struct seg *segs, size_t n, const bool *used, uint64_t key)
{
	size_t lo = 0, hi = n;

	while (lo < hi) {
		size_t mid = lo + (hi - lo) / 2;
		if (segs[mid].from < key)
			lo = mid + 1;
		else
			hi = mid;
	}
	for (; lo < n && segs[lo].from == key; lo++)
		if (!used[lo])
			return lo;
	return SIZE_MAX;
}

/* A growing list of points (x, y pairs) for one contour under construction. */
struct pts {
	int64_t *xy;
	size_t n, cap;
};

static int pts_push(struct pts *p, int64_t x, int64_t y, struct st_error *err)
{
	int64_t *grown;

	if (p->n && p->xy[2 * p->n - 2] == x && p->xy[2 * p->n - 1] == y)
		return 0; /* a vertex on the plane repeats a point: keep one */
	grown = slice_grow(p->xy, &p->cap, p->n + 1, 2 * sizeof(*grown));
	if (!grown)
		return st_error_set(err, ST_ERR_NOMEM, "slice: out of memory for a contour");
	p->xy = grown;
	p->xy[2 * p->n] = x;
	p->xy[2 * p->n + 1] = y;
	p->n++;
	return 0;
}

/* Add a finished closed contour to loops, without a repeated closing point. */
static int emit_loop(struct pts *p, struct clip_paths *loops, struct st_error *err)
{
	size_t n = p->n;

	while (n > 1 && p->xy[0] == p->xy[2 * n - 2] && p->xy[1] == p->xy[2 * n - 1])
		n--;
	if (n < 3)
		return 0; /* a contour of no area (a plane touching an edge) */
	return clip_paths_add(loops, p->xy, n, err);
}

/* An open chain: its points and where it ends. */
struct open_chain {
	struct pts p;
	bool done;
};

static double gap2(const struct pts *a, const struct pts *b)
{
	double dx = (double)b->xy[0] - (double)a->xy[2 * a->n - 2];
	double dy = (double)b->xy[1] - (double)a->xy[2 * a->n - 1];
	return dx * dx + dy * dy;
}

/*
 * Join open chains end to start while the nearest start (its own included,
 * which closes it) is within tol nm; chains left open are dropped and
 * counted.  A chain that found no partner for its end stays available as
 * the continuation of another.  Chains split only because chaining began
 * mid-way join at distance 0: both sides computed the point of one edge.
 */
static int close_gaps(struct open_chain *oc, size_t n, double tol, struct clip_paths *loops,
		      size_t *dropped, struct st_error *err)
{
	for (size_t i = 0; i < n; i++) {
		while (!oc[i].done) {
			size_t best = i;
			double bd = gap2(&oc[i].p, &oc[i].p);
			for (size_t j = 0; j < n; j++) {
				if (j == i || oc[j].done)
					continue;
				double d = gap2(&oc[i].p, &oc[j].p);
				if (d < bd) {
					bd = d;
					best = j;
				}
			}
			if (bd > tol * tol)
				break;
			if (best == i) {
				oc[i].done = true;
				int rc = emit_loop(&oc[i].p, loops, err);
				if (rc)
					return rc;
				break;
			}
			for (size_t k = 0; k < oc[best].p.n; k++) {
				int rc = pts_push(&oc[i].p, oc[best].p.xy[2 * k],
						  oc[best].p.xy[2 * k + 1], err);
				if (rc)
					return rc;
			}
			oc[best].done = true;
		}
	}
	for (size_t i = 0; i < n; i++)
		*dropped += !oc[i].done;
	return 0;
}

/*
 * Chain one layer's segments into closed contours (appended to loops):
 * the segment after s is the one starting on the edge s ends on.  Sorting
 * by edge key makes this O(n log n).
 */
static int chain_layer(struct seg *segs, size_t n, double tol, struct clip_paths *loops,
		       size_t *dropped, struct st_error *err)
{
	bool *used = calloc(n ? n : 1, sizeof(*used));
	struct open_chain *oc = NULL;
	size_t noc = 0, capoc = 0;
	struct pts cur = {0};
	int rc = 0;

	if (!used)
		return st_error_set(err, ST_ERR_NOMEM, "slice: out of memory chaining contours");
	if (n)
		qsort(segs, n, sizeof(*segs), seg_cmp_from);
	for (size_t s0 = 0; s0 < n && !rc; s0++) {
		if (used[s0])
			continue;
		size_t s = s0;
		bool closed = false;
		cur.n = 0;
		used[s0] = true;
		rc = pts_push(&cur, segs[s0].x0, segs[s0].y0, err);
		while (!rc) {
			if (segs[s].to == segs[s0].from) {
				closed = true;
				break;
			}
			size_t next = find_from(segs, n, used, segs[s].to);
			if (next == SIZE_MAX)
				break;
			used[next] = true;
			s = next;
			rc = pts_push(&cur, segs[s].x0, segs[s].y0, err);
		}
		if (rc)
			break;
		if (closed) {
			rc = emit_loop(&cur, loops, err);
			continue;
		}
		/* Open: keep its end point too and try to close it later. */
		rc = pts_push(&cur, segs[s].x1, segs[s].y1, err);
		if (rc)
			break;
		struct open_chain *grown = slice_grow(oc, &capoc, noc + 1, sizeof(*grown));
		if (!grown) {
			rc = st_error_set(err, ST_ERR_NOMEM, "slice: out of memory chaining");
			break;
		}
		oc = grown;
		oc[noc++] = (struct open_chain){.p = cur, .done = false};
		cur = (struct pts){0};
	}
	if (!rc)
		rc = close_gaps(oc, noc, tol, loops, dropped, err);
	for (size_t i = 0; i < noc; i++)
		free(oc[i].p.xy);
	free(oc);
	free(cur.xy);
	free(used);
	return rc;
}

/* Refuse meshes whose coordinates are not finite or beyond SLICE_MAX_COORD. */
static int check_mesh(const struct mesh *m, struct st_error *err)
{
	if (!m || !m->ntris)
		return st_error_set(err, ST_ERR_ARG, "slice: the mesh has no triangles to slice");
	for (size_t i = 0; i < m->nverts; i++)
		for (int k = 0; k < 3; k++)
			if (!(fabs(m->verts[i][k]) <= SLICE_MAX_COORD))
				return st_error_set(err, ST_ERR_RANGE,
						    "slice: vertex %zu has coordinate %g mm; "
						    "coordinates must be finite and within +-%g mm",
						    i, m->verts[i][k], SLICE_MAX_COORD);
	return 0;
}

int slice_plane(const struct mesh *m, double z, double close_gap, struct clip_paths *loops,
		size_t *open_dropped, struct st_error *err)
{
	struct seg_list segs = {0};
	size_t dropped = 0;
	int rc;

	if (!loops || !(close_gap >= 0.0) || !isfinite(z))
		return st_error_set(err, ST_ERR_ARG,
				    "slice: slice_plane needs a finite z, a gap >= 0 and loops");
	rc = check_mesh(m, err);
	if (rc)
		return rc;
	clip_paths_clear(loops);
	for (size_t t = 0; t < m->ntris && !rc; t++) {
		struct seg s;
		if (tri_segment(m, t, z, &s))
			rc = seg_push(&segs, &s, err);
	}
	if (!rc)
		rc = chain_layer(segs.v, segs.n, close_gap * SLICE_UNITS_PER_MM, loops, &dropped,
				 err);
	free(segs.v);
	if (open_dropped)
		*open_dropped = dropped;
	return rc;
}

/* Mid-height of layer i above the bed, mm. */
static double layer_mid(size_t i, double first, double h)
{
	return i == 0 ? first / 2 : first + (double)i * h - h / 2;
}

void slice_stack_free(struct slice_stack *st)
{
	if (!st)
		return;
	for (size_t i = 0; i < st->n; i++)
		clip_expolys_free(&st->layers[i].regions);
	free(st->layers);
	free(st);
}

/* First layer whose plane is above zlo (planes increase with the index). */
static size_t first_plane_above(const struct slice_stack *st, double zlo)
{
	size_t lo = 0, hi = st->n;

	while (lo < hi) {
		size_t mid = lo + (hi - lo) / 2;
		if (st->layers[mid].slice_z > zlo)
			hi = mid;
		else
			lo = mid + 1;
	}
	return lo;
}

/* Cut every triangle by every plane of st it spans, into per-layer lists. */
static int cut_all(const struct mesh *m, const struct slice_stack *st, struct seg_list *lists,
		   struct st_error *err)
{
	for (size_t t = 0; t < m->ntris; t++) {
		const uint32_t *v = m->tris[t];
		double lo = m->verts[v[0]][2], hi = lo;
		for (int k = 1; k < 3; k++) {
			lo = fmin(lo, m->verts[v[k]][2]);
			hi = fmax(hi, m->verts[v[k]][2]);
		}
		/* Crossed planes: lo < zp <= hi (a vertex on a plane counts as above). */
		for (size_t i = first_plane_above(st, lo); i < st->n && st->layers[i].slice_z <= hi;
		     i++) {
			struct seg s;
			if (tri_segment(m, t, st->layers[i].slice_z, &s)) {
				int rc = seg_push(&lists[i], &s, err);
				if (rc)
					return rc;
			}
		}
	}
	return 0;
}

int slice_plan_uniform(double height, double first_layer_height, double layer_height,
		       struct layer_span **plan, size_t *n, struct st_error *err)
{
	size_t count = 0;

	*plan = NULL;
	*n = 0;
	if (height / fmin(first_layer_height, layer_height) > SLICE_MAX_LAYERS)
		return st_error_set(err, ST_ERR_RANGE,
				    "slice: a %g mm tall mesh in %g mm layers needs more than %u "
				    "layers; use thicker layers",
				    height, layer_height, SLICE_MAX_LAYERS);
	while (layer_mid(count, first_layer_height, layer_height) < height)
		count++;
	if (count && !(*plan = calloc(count, sizeof(**plan))))
		return st_error_set(err, ST_ERR_NOMEM, "slice: out of memory for %zu layers", count);
	for (size_t i = 0; i < count; i++)
		(*plan)[i] = (struct layer_span){
		    .z = i == 0 ? first_layer_height : first_layer_height + (double)i * layer_height,
		    .height = i == 0 ? first_layer_height : layer_height};
	*n = count;
	return 0;
}

/* Heights within (0, nozzle] and tops rising: what cut_all and the stages rely on. */
static int check_plan(const struct layer_span *plan, size_t n, double nozzle,
		      struct st_error *err)
{
	if (n > SLICE_MAX_LAYERS)
		return st_error_set(err, ST_ERR_RANGE, "slice: %zu layers are more than %u", n,
				    SLICE_MAX_LAYERS);
	for (size_t i = 0; i < n; i++) {
		if (!(plan[i].height > 0.0 && plan[i].height <= nozzle))
			return st_error_set(err, ST_ERR_RANGE,
					    "slice: layer %zu is %g mm thick; it must be > 0 and "
					    "at most the nozzle diameter %g mm",
					    i + 1, plan[i].height, nozzle);
		if (!(plan[i].z >= plan[i].height) || (i > 0 && !(plan[i].z > plan[i - 1].z)))
			return st_error_set(err, ST_ERR_ARG,
					    "slice: layer %zu's top %g mm is below its height or "
					    "the layer under it",
					    i + 1, plan[i].z);
	}
	return 0;
}

int slice_mesh(const struct mesh *m, double first_layer_height, double layer_height,
	       const struct slice_settings *s, struct slice_stack **out, struct st_error *err)
{
	struct slice_settings defaults;
	struct layer_span *plan = NULL;
	double zmin[3], zmax[3];
	size_t n = 0;
	int rc;

	if (!out)
		return st_error_set(err, ST_ERR_ARG, "slice: slice_mesh needs an out pointer");
	*out = NULL;
	if (!s) {
		slice_settings_init(&defaults);
		s = &defaults;
	}
	rc = slice_settings_check(s, first_layer_height, layer_height, err);
	if (!rc)
		rc = check_mesh(m, err);
	if (rc)
		return rc;
	mesh_bbox(m, zmin, zmax);
	rc = slice_plan_uniform(zmax[2] - zmin[2], first_layer_height, layer_height, &plan, &n,
				err);
	if (!rc)
		rc = slice_mesh_plan(m, plan, n, s, out, err);
	free(plan);
	return rc;
}

int slice_mesh_plan(const struct mesh *m, const struct layer_span *plan, size_t n,
		    const struct slice_settings *s, struct slice_stack **out, struct st_error *err)
{
	struct slice_settings defaults;
	struct slice_stack *st;
	struct seg_list *lists = NULL;
	struct clip_paths loops = {0};
	double zmin[3], zmax[3];
	int rc;

	if (!out)
		return st_error_set(err, ST_ERR_ARG, "slice: slice_mesh_plan needs an out pointer");
	*out = NULL;
	if (!s) {
		slice_settings_init(&defaults);
		s = &defaults;
	}
	rc = check_mesh(m, err);
	if (!rc)
		rc = check_plan(plan, n, s->nozzle_diameter, err);
	if (rc)
		return rc;
	mesh_bbox(m, zmin, zmax);
	st = calloc(1, sizeof(*st));
	if (!st || (n && !(st->layers = calloc(n, sizeof(*st->layers)))) ||
	    !(lists = calloc(n ? n : 1, sizeof(*lists)))) {
		rc = st_error_set(err, ST_ERR_NOMEM, "slice: out of memory for %zu layers", n);
		goto out_free;
	}
	st->n = n;
	for (size_t i = 0; i < n; i++) {
		struct slice_layer *l = &st->layers[i];
		l->height = plan[i].height;
		l->z = plan[i].z;
		l->slice_z = zmin[2] + (plan[i].z - plan[i].height / 2);
	}
	rc = cut_all(m, st, lists, err);
	for (size_t i = 0; i < n && !rc; i++) {
		rc = chain_layer(lists[i].v, lists[i].n, s->close_gap * SLICE_UNITS_PER_MM, &loops,
				 &st->layers[i].open_dropped, err);
		if (!rc)
			rc = clip_boolean_ex(CLIP_UNION, &loops, NULL, s->fill,
					     &st->layers[i].regions, err);
		clip_paths_clear(&loops);
		free(lists[i].v);
		lists[i].v = NULL;
	}
out_free:
	if (lists)
		for (size_t i = 0; i < n; i++)
			free(lists[i].v);
	free(lists);
	clip_paths_free(&loops);
	if (rc) {
		slice_stack_free(st);
		return rc;
	}
	*out = st;
	return 0;
}

/* An island the shrink removes keeps its outline (section.h). */
int slice_layer_shrink(struct slice_layer *l, double mm, double tolerance, struct st_error *err)
{
	struct clip_paths island = {0}, shrunk = {0}, all = {0};
	struct clip_expolys out = {0};
	int rc = 0;

	for (size_t i = 0; i < l->regions.n && !rc; i++) {
		rc = clip_expolys_get(&l->regions, i, &island, err);
		if (!rc)
			rc = clip_offset(&island, -mm * SLICE_UNITS_PER_MM, CLIP_JOIN_MITER, 3.0,
					 tolerance, &shrunk, err);
		if (!rc)
			rc = clip_paths_append(&all, shrunk.n ? &shrunk : &island, err);
	}
	if (!rc)
		rc = clip_boolean_ex(CLIP_UNION, &all, NULL, CLIP_NONZERO, &out, err);
	if (!rc) {
		clip_expolys_free(&l->regions);
		l->regions = out;
	} else {
		clip_expolys_free(&out);
	}
	clip_paths_free(&island);
	clip_paths_free(&shrunk);
	clip_paths_free(&all);
	return rc;
}
