/*
 * preview.c - one layer of a G-code file as paths (preview.h): a first
 * walk builds the layer table and the frame, a second collects the chosen
 * layer's beads and travels.
 */
#include "preview.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clip.h"
#include "gcwalk.h"
#include "region.h"
#include "section.h"
#include "st_grow.h"
#include "toolpath.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* Layers whose Z differ by less than this are one layer, mm (as region.c). */
#define PV_Z_EPS 1e-4
/* Open contour ends joined when cutting the model, mm (section.h default). */
#define PV_CLOSE_GAP 0.05
/* Margin around the frame, mm: holds half of any usual bead. */
#define PV_MARGIN 1.0

static const struct {
	const char *name, *id;
} features[PREVIEW_FEATURES] = {
	[PREVIEW_SKIRT] = {"skirt/brim", "skirt"},
	[PREVIEW_SUPPORT] = {"support", "support"},
	[PREVIEW_INFILL] = {"sparse infill", "infill"},
	[PREVIEW_SKIN] = {"solid infill/skin", "skin"},
	[PREVIEW_BRIDGE] = {"bridge", "bridge"},
	[PREVIEW_THIN] = {"gap fill/thin wall", "thin"},
	[PREVIEW_INNER_PERIMETER] = {"inner perimeter", "inner-perimeter"},
	[PREVIEW_OUTER_PERIMETER] = {"outer perimeter", "outer-perimeter"},
	[PREVIEW_OTHER] = {"other", "other"},
	[PREVIEW_TRAVEL] = {"travel", "travel"},
};

const char *preview_feature_name(enum preview_feature f)
{
	return (unsigned)f < PREVIEW_FEATURES ? features[f].name : "unknown";
}

const char *preview_feature_id(enum preview_feature f)
{
	return (unsigned)f < PREVIEW_FEATURES ? features[f].id : "unknown";
}

/* The feature of a ";TYPE:" text ("" gives OTHER). */
static enum preview_feature preview_feature_of(const char *type)
{
	/* Stratum's and PrusaSlicer's ;TYPE: names; prefixes catch the
	 * "Support material interface" and "Skirt/Brim" variants. */
	static const struct {
		const char *prefix;
		enum preview_feature f;
	} map[] = {
	    {"External perimeter", PREVIEW_OUTER_PERIMETER},
	    {"Overhang perimeter", PREVIEW_OUTER_PERIMETER},
	    {"Perimeter", PREVIEW_INNER_PERIMETER},
	    {"Gap fill", PREVIEW_THIN},
	    {"Thin wall", PREVIEW_THIN},
	    {"Internal infill", PREVIEW_INFILL},
	    {"Solid infill", PREVIEW_SKIN},
	    {"Top solid infill", PREVIEW_SKIN},
	    {"Bottom solid infill", PREVIEW_SKIN},
	    {"Ironing", PREVIEW_SKIN},
	    {"Bridge infill", PREVIEW_BRIDGE},
	    {"Skirt", PREVIEW_SKIRT},
	    {"Brim", PREVIEW_SKIRT},
	    {"Support material", PREVIEW_SUPPORT},
	};
	for (size_t i = 0; type && i < sizeof(map) / sizeof(map[0]); i++)
		if (!strncmp(type, map[i].prefix, strlen(map[i].prefix)))
			return map[i].f;
	return PREVIEW_OTHER;
}

void preview_opts_init(struct preview_opts *o)
{
	memset(o, 0, sizeof(*o));
	o->layer = 1;
}

static void box_add(double min[2], double max[2], const double p[2])
{
	for (int a = 0; a < 2; a++) {
		min[a] = fmin(min[a], p[a]);
		max[a] = fmax(max[a], p[a]);
	}
}

static bool is_bead(const struct gcwalk_move *m)
{
	return m->de > 0.0 && (m->to[0] != m->from[0] || m->to[1] != m->from[1]);
}

static bool is_part(enum preview_feature f)
{
	return f != PREVIEW_SKIRT && f != PREVIEW_SUPPORT && f != PREVIEW_OTHER;
}

/* One layer of the table. */
struct row {
	double z, height; /* mm; NAN until known */
};

/* What the first walk learns. */
struct table {
	size_t n, cap;
	struct row *v;	    /* layers, in file order (comments) or by Z */
	size_t nz, capz;
	double *zs;	    /* bead Zs, for layers by Z */
	/* Beads and boxes, [0] before any layer comment, [1] after: with
	 * comments, beads before the first are start G-code and prime lines. */
	size_t beads[2];
	double fmin[2][2], fmax[2][2], pmin[2][2], pmax[2][2];
	long marks;
	double filament;
};

/* Row of comment layer l, created (NAN) when new. */
static struct row *table_row(struct table *t, long l)
{
	if (st_grow_at((void **)&t->v, &t->cap, (size_t)l + 1, sizeof(*t->v)))
		return NULL;
	while (t->n <= (size_t)l)
		t->v[t->n++] = (struct row){NAN, NAN};
	return &t->v[l];
}

/* First walk, one move. */
static int table_move(struct table *t, const struct gcwalk_move *m, struct st_error *err)
{
	struct row *r = NULL;
	bool bead = is_bead(m);

	if (m->layer >= 0) {
		if (!(r = table_row(t, m->layer)))
			return st_error_set(err, ST_ERR_NOMEM, "preview: out of memory");
		if (!isnan(m->layer_z))
			r->z = m->layer_z;
		if (!isnan(m->layer_height))
			r->height = m->layer_height;
	}
	if (!bead)
		return 0;
	if (r && isnan(r->z))
		r->z = m->to[2];
	if (!t->nz || t->zs[t->nz - 1] != m->to[2]) {
		if (st_grow_at((void **)&t->zs, &t->capz, t->nz + 1, sizeof(*t->zs)))
			return st_error_set(err, ST_ERR_NOMEM, "preview: out of memory");
		t->zs[t->nz++] = m->to[2];
	}
	int s = m->layer >= 0;
	t->beads[s]++;
	box_add(t->fmin[s], t->fmax[s], m->from);
	box_add(t->fmin[s], t->fmax[s], m->to);
	if (*m->type && is_part(preview_feature_of(m->type))) {
		box_add(t->pmin[s], t->pmax[s], m->from);
		box_add(t->pmin[s], t->pmax[s], m->to);
	}
	return 0;
}

static int cmp_double(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

/* Layers by Z when the file has no layer comments. */
static int table_by_z(struct table *t, struct st_error *err)
{
	size_t n = 0;

	qsort(t->zs, t->nz, sizeof(*t->zs), cmp_double);
	for (size_t i = 0; i < t->nz; i++)
		if (!n || t->zs[i] - t->zs[n - 1] > PV_Z_EPS)
			t->zs[n++] = t->zs[i];
	t->v = calloc(n ? n : 1, sizeof(*t->v));
	if (!t->v)
		return st_error_set(err, ST_ERR_NOMEM, "preview: out of memory");
	for (size_t i = 0; i < n; i++)
		t->v[i] = (struct row){t->zs[i], NAN};
	t->n = t->cap = n;
	return 0;
}

/* Heights missing from comments: the Z step from the layer below. */
static void table_heights(struct table *t)
{
	double below = 0.0;

	for (size_t i = 0; i < t->n; i++) {
		struct row *r = &t->v[i];
		if (isnan(r->z))
			continue;
		if (isnan(r->height) || !(r->height > 0.0))
			r->height = r->z - below;
		below = r->z;
	}
}

/* Walk the whole file once; fills t. */
static int build_table(FILE *fp, const char *path, struct table *t, struct st_error *err)
{
	struct gcwalk *w;
	struct gcwalk_move m;
	int rc = gcwalk_new(fp, path, &w, err);

	if (rc)
		return rc;
	for (int s = 0; s < 2; s++)
		for (int a = 0; a < 2; a++) {
			t->fmin[s][a] = t->pmin[s][a] = INFINITY;
			t->fmax[s][a] = t->pmax[s][a] = -INFINITY;
		}
	while ((rc = gcwalk_next(w, &m, err)) == 1)
		if ((rc = table_move(t, &m, err)))
			break;
	t->marks = gcwalk_layer_marks(w);
	t->filament = gcwalk_filament_diameter(w);
	gcwalk_free(w);
	if (rc < 0)
		return rc;
	if (!t->beads[t->marks > 0])
		return st_error_set(err, ST_ERR_RANGE, "%s: nothing is extruded in any layer", path);
	if (!t->marks) {
		rc = table_by_z(t, err);
		if (rc)
			return rc;
	} else if (table_row(t, t->marks - 1) == NULL) {
		return st_error_set(err, ST_ERR_NOMEM, "preview: out of memory");
	}
	table_heights(t);
	return 0;
}

/* Lowest and highest known layer Z. */
static void z_range(const struct table *t, double *lo, double *hi)
{
	*lo = INFINITY;
	*hi = -INFINITY;
	for (size_t i = 0; i < t->n; i++) {
		if (isnan(t->v[i].z))
			continue;
		*lo = fmin(*lo, t->v[i].z);
		*hi = fmax(*hi, t->v[i].z);
	}
}

/* The row index asked for by o; ST_ERR_ARG naming the range when none. */
static int choose(const struct table *t, const struct preview_opts *o, const char *path,
		  size_t *out, struct st_error *err)
{
	double lo, hi;

	z_range(t, &lo, &hi);
	if (o->layer > 0) {
		if ((size_t)o->layer <= t->n) {
			*out = (size_t)o->layer - 1;
			return 0;
		}
		return st_error_set(err, ST_ERR_ARG,
				    "%s: no layer %ld: the file has layers 1 to %zu (Z %g to %g mm)",
				    path, o->layer, t->n, lo, hi);
	}
	/* The first layer whose slab (z - height, z] holds the height asked. */
	for (size_t i = 0; i < t->n; i++) {
		const struct row *r = &t->v[i];
		if (!isnan(r->z) && o->z <= r->z + PV_Z_EPS && o->z > r->z - r->height + PV_Z_EPS) {
			*out = i;
			return 0;
		}
	}
	return st_error_set(err, ST_ERR_ARG,
			    "%s: no layer at Z %g mm: the file has layers 1 to %zu at Z %g to %g mm",
			    path, o->z, t->n, lo, hi);
}

/* Second walk: the path being built. */
struct builder {
	struct preview *pv;
	size_t pcap; /* of pv->paths */
	enum preview_feature feature;
	double *xy;
	size_t n, cap;
	double w0, wsum, lsum;
};

/* End the current path, keeping it when it has a segment. */
static int flush(struct builder *b)
{
	struct preview *pv = b->pv;
	size_t n = b->n;

	if (n < 2) {
		b->n = 0;
		return 0;
	}
	struct preview_path path = {.feature = b->feature,
				    .width = b->lsum > 0 ? b->wsum / b->lsum : 0.0};
	if (n > 3 && b->xy[0] == b->xy[2 * n - 2] && b->xy[1] == b->xy[2 * n - 1]) {
		path.closed = true;
		n--;
	}
	path.n = n;
	path.xy = malloc(2 * n * sizeof(*path.xy));
	if (!path.xy)
		return ST_ERR_NOMEM;
	memcpy(path.xy, b->xy, 2 * n * sizeof(*path.xy));
	if (st_grow_at((void **)&pv->paths, &b->pcap, pv->n + 1, sizeof(*pv->paths))) {
		free(path.xy);
		return ST_ERR_NOMEM;
	}
	pv->paths[pv->n++] = path;
	pv->count[path.feature]++;
	b->n = 0;
	return 0;
}

/* Add one move of the shown layer (width 0 for travel). */
static int add_move(struct builder *b, enum preview_feature f, const double from[2],
		    const double to[2], double w, double len)
{
	bool joins = b->n && f == b->feature && b->xy[2 * b->n - 2] == from[0] &&
		     b->xy[2 * b->n - 1] == from[1] && fabs(w - b->w0) <= PREVIEW_WIDTH_JOIN * b->w0;

	if (!joins) {
		if (flush(b))
			return ST_ERR_NOMEM;
		b->feature = f;
		b->w0 = w;
		b->wsum = b->lsum = 0.0;
	}
	if (st_grow_at((void **)&b->xy, &b->cap, 2 * (b->n + 2), sizeof(*b->xy)))
		return ST_ERR_NOMEM;
	if (!b->n) {
		b->xy[0] = from[0];
		b->xy[1] = from[1];
		b->n = 1;
	}
	b->xy[2 * b->n] = to[0];
	b->xy[2 * b->n + 1] = to[1];
	b->n++;
	b->wsum += w * len;
	b->lsum += len;
	return 0;
}

/* Row of a move when layers go by Z: the layer at its target Z, else cur. */
static long z_row(const struct table *t, double z, long cur)
{
	size_t lo = 0, hi = t->n;

	while (lo < hi) {
		size_t mid = (lo + hi) / 2;
		if (t->v[mid].z < z - PV_Z_EPS / 2)
			lo = mid + 1;
		else
			hi = mid;
	}
	return lo < t->n && fabs(t->v[lo].z - z) <= PV_Z_EPS / 2 ? (long)lo : cur;
}

/* Second walk: the chosen layer's moves into pv->paths. */
static int collect(FILE *fp, const char *path, const struct table *t, size_t chosen,
		   struct preview *pv, struct st_error *err)
{
	double fil_area = M_PI * pv->filament_diameter * pv->filament_diameter / 4.0;
	struct builder b = {.pv = pv};
	struct gcwalk *w;
	struct gcwalk_move m;
	long cur = -1;
	int rc;

	if (fseek(fp, 0, SEEK_SET))
		return st_error_set(err, ST_ERR_IO, "%s: cannot read it again: %s", path,
				    strerror(errno));
	if ((rc = gcwalk_new(fp, path, &w, err)))
		return rc;
	while ((rc = gcwalk_next(w, &m, err)) == 1) {
		cur = t->marks ? m.layer : z_row(t, m.to[2], cur);
		if (cur != (long)chosen || (m.to[0] == m.from[0] && m.to[1] == m.from[1]))
			continue;
		double len = hypot(m.to[0] - m.from[0], m.to[1] - m.from[1]);
		if (m.de > 0.0)
			rc = add_move(&b, preview_feature_of(m.type), m.from, m.to,
				      region_bead_width(m.de * fil_area / len, pv->height), len);
		else
			rc = add_move(&b, PREVIEW_TRAVEL, m.from, m.to, 0.0, len);
		if (rc)
			break;
	}
	gcwalk_free(w);
	if (rc == 0 && flush(&b))
		rc = ST_ERR_NOMEM;
	free(b.xy);
	if (rc == ST_ERR_NOMEM)
		return st_error_set(err, ST_ERR_NOMEM, "preview: out of memory reading layer %zu",
				    chosen + 1);
	return rc < 0 ? rc : 0;
}

int preview_load(const char *path, const struct preview_opts *o, struct preview **out,
		 struct st_error *err)
{
	struct table t = {0};
	struct preview *pv = NULL;
	size_t chosen = 0;
	FILE *fp;
	int rc;

	if (out)
		*out = NULL;
	if (!path || !o || !out)
		return st_error_set(err, ST_ERR_ARG, "preview: preview_load needs a path, opts and out");
	if (!(o->filament_diameter >= 0.0) || o->layer < 0 || (o->layer == 0 && !isfinite(o->z)))
		return st_error_set(err, ST_ERR_ARG, "preview: bad layer, Z or filament diameter");
	fp = fopen(path, "rb");
	if (!fp)
		return st_error_set(err, ST_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
	if ((rc = build_table(fp, path, &t, err)) || (rc = choose(&t, o, path, &chosen, err)))
		goto out;
	pv = calloc(1, sizeof(*pv));
	if (!pv) {
		rc = st_error_set(err, ST_ERR_NOMEM, "preview: out of memory");
		goto out;
	}
	pv->filament_diameter = o->filament_diameter > 0.0 ? o->filament_diameter : t.filament;
	if (pv->filament_diameter == 0.0) {
		rc = st_error_set(err, ST_ERR_PARSE,
				  "%s: no '; filament_diameter = ' comment; give --filament-diameter",
				  path);
		goto out;
	}
	pv->layer = chosen + 1;
	pv->layers = t.n;
	pv->by_comments = t.marks > 0;
	pv->z = t.v[chosen].z;
	pv->height = t.v[chosen].height;
	for (int a = 0, s = t.marks > 0; a < 2; a++) {
		pv->min[a] = t.fmin[s][a] - PV_MARGIN;
		pv->max[a] = t.fmax[s][a] + PV_MARGIN;
		pv->part_min[a] = t.pmin[s][a];
		pv->part_max[a] = t.pmax[s][a];
	}
	if (isnan(pv->z)) {
		/* A layer comment with nothing under it: travels only, if any. */
		pv->z = pv->height = 0.0;
	}
	rc = collect(fp, path, &t, chosen, pv, err);
out:
	fclose(fp);
	free(t.v);
	free(t.zs);
	if (rc) {
		preview_free(pv);
		return rc;
	}
	*out = pv;
	return 0;
}

int preview_add_model(struct preview *pv, const struct mesh *m, const struct preview_opts *o,
		      struct st_error *err)
{
	struct region_opts ro;
	struct clip_paths loops = {0};
	const double *pmin = pv->part_min, *pmax = pv->part_max;
	int rc;

	if (!m || !m->nverts)
		return st_error_set(err, ST_ERR_ARG, "preview: the model has no vertices");
	region_opts_init(&ro);
	ro.has_center = o && o->has_center;
	ro.center_x = o ? o->center_x : 0.0;
	ro.center_y = o ? o->center_y : 0.0;
	if (pmin[0] > pmax[0]) { /* only skirt/support/other printed: the frame's centre */
		pmin = pv->min;
		pmax = pv->max;
	}
	region_place(m, &ro, pmin, pmax, pv->model_offset);
	rc = slice_plane(m, pv->z - pv->height / 2 - pv->model_offset[2], PV_CLOSE_GAP, &loops,
			 NULL, err);
	if (rc)
		goto out;
	pv->outline = calloc(loops.n ? loops.n : 1, sizeof(*pv->outline));
	if (!pv->outline)
		goto out_nomem;
	for (size_t i = 0; i < loops.n; i++) {
		struct preview_path *p = &pv->outline[i];
		const int64_t *xy = clip_path_xy(&loops, i);
		p->n = clip_path_len(&loops, i);
		p->feature = PREVIEW_OTHER;
		p->closed = true;
		if (!(p->xy = malloc(2 * p->n * sizeof(*p->xy))))
			goto out_nomem;
		pv->noutline++;
		for (size_t k = 0; k < p->n; k++) {
			for (int a = 0; a < 2; a++)
				p->xy[2 * k + a] = xy[2 * k + a] / SLICE_UNITS_PER_MM +
						   pv->model_offset[a];
			box_add(pv->min, pv->max, p->xy + 2 * k);
		}
	}
	pv->has_model = true;
	goto out;
out_nomem:
	rc = st_error_set(err, ST_ERR_NOMEM, "preview: out of memory cutting the model");
out:
	clip_paths_free(&loops);
	return rc;
}

void preview_free(struct preview *pv)
{
	if (!pv)
		return;
	for (size_t i = 0; i < pv->n; i++)
		free(pv->paths[i].xy);
	for (size_t i = 0; i < pv->noutline; i++)
		free(pv->outline[i].xy);
	free(pv->paths);
	free(pv->outline);
	free(pv);
}
