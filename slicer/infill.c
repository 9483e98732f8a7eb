/*
 * infill.c - the infill's settings, its job over a stack, the plan of a
 * layer and its emission nearest first (see infill.h).  The region inside
 * the walls is classified in infill_classify.c and filled in
 * infill_fill.c; what they share is infill_int.h.
 */
#include "infill_int.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The region inside the walls loses vertices that move its boundary less
 * than this, nm: its round joins (arcs within 2 um) give it four times the
 * section's vertices, and every class is cut from it. */
#define INFILL_CLEAN_NM 2000.0

/* What infill_job_new works out once for every layer. */
struct infill_job {
	struct infill_settings s;
	const struct slice_stack *st;
	double overlap;	     /* nm, how far infill reaches into the walls */
	double t_top, t_bot; /* mm, shell thicknesses */
	int64_t lx, ly;	     /* nm, where the last emitted path ended */
};

/* The patterns printed, for messages. */
#define PATTERNS_PRINTED                                                                   \
	"rectilinear, grid, gyroid, triangles, stars, cubic, line, concentric or honeycomb"

/* PrusaSlicer's fill_pattern values; pattern -1: known there, not printed here. */
static const struct {
	const char *name;
	int pattern;
} pattern_names[] = {
	{"rectilinear", INFILL_RECTILINEAR},
	{"grid", INFILL_GRID},
	{"gyroid", INFILL_GYROID},
	{"triangles", INFILL_TRIANGLES},
	{"stars", INFILL_STARS},
	{"cubic", INFILL_CUBIC},
	{"line", INFILL_LINE},
	{"concentric", INFILL_CONCENTRIC},
	{"honeycomb", INFILL_HONEYCOMB},
	{"alignedrectilinear", -1},
	{"monotonic", -1},
	{"monotoniclines", -1},
	{"3dhoneycomb", -1},
	{"hilbertcurve", -1},
	{"archimedeanchords", -1},
	{"octagramspiral", -1},
	{"adaptivecubic", -1},
	{"supportcubic", -1},
	{"lightning", -1},
};

void infill_settings_init(struct infill_settings *s, double nozzle_diameter)
{
	double w = 1.125 * nozzle_diameter;

	*s = (struct infill_settings){
		.nozzle_diameter = nozzle_diameter,
		.fill_density = 20.0,
		.fill_pattern = INFILL_GRID,
		.fill_angle = 45.0,
		.bridge_angle = 0.0,
		.top_solid_layers = 3,
		.bottom_solid_layers = 3,
		.top_solid_min_thickness = 0.0,
		.bottom_solid_min_thickness = 0.0,
		.layer_height = 0.0,
		.perimeter_extrusion_width = w,
		.infill_extrusion_width = w,
		.solid_infill_extrusion_width = w,
		.top_infill_extrusion_width = w,
		.infill_overlap = 25.0,
		.solid_infill_below_area = 70.0,
		.bridge_flow_ratio = 1.0,
		.thick_bridges = true,
		.gap_fill_min = 0.1,
		.ironing = false,
		.ironing_type = IRON_TOP,
		.ironing_spacing = 0.1,
	};
}

int infill_pattern_parse(const char *name, enum infill_pattern *out, struct st_error *err)
{
	for (size_t i = 0; name && i < sizeof(pattern_names) / sizeof(pattern_names[0]); i++) {
		if (strcmp(name, pattern_names[i].name))
			continue;
		if (pattern_names[i].pattern < 0)
			return st_error_set(err, ST_ERR_UNSUPPORTED,
					    "infill: fill_pattern \"%s\" is not supported; use "
					    PATTERNS_PRINTED,
					    name);
		*out = (enum infill_pattern)pattern_names[i].pattern;
		return 0;
	}
	return st_error_set(err, ST_ERR_ARG,
			    "infill: fill_pattern \"%.64s\" is unknown; use " PATTERNS_PRINTED,
			    name ? name : "(none)");
}

const char *infill_pattern_name(enum infill_pattern p)
{
	for (size_t i = 0; i < sizeof(pattern_names) / sizeof(pattern_names[0]); i++)
		if (pattern_names[i].pattern == (int)p)
			return pattern_names[i].name;
	return "unknown";
}

/* Refuse a width (mm) that is not in (0, 4 x nozzle]. */
static int check_width(const struct infill_settings *s, const char *key, double w,
		       struct st_error *err)
{
	if (!(w > 0.0 && w <= 4.0 * s->nozzle_diameter))
		return st_error_set(err, ST_ERR_RANGE,
				    "infill: %s %g mm is out of range; use (0, %g] mm (4 x the "
				    "nozzle diameter)",
				    key, w, 4.0 * s->nozzle_diameter);
	return 0;
}

int infill_settings_check(const struct infill_settings *s, struct st_error *err)
{
	int rc;

	if (!s)
		return st_error_set(err, ST_ERR_ARG, "infill: no settings given");
	if (!(s->nozzle_diameter > 0.0 && s->nozzle_diameter <= 5.0))
		return st_error_set(err, ST_ERR_RANGE,
				    "infill: nozzle diameter %g mm is out of range; use (0, 5] mm",
				    s->nozzle_diameter);
	if (!(s->fill_density >= 0.0 && s->fill_density <= 100.0))
		return st_error_set(err, ST_ERR_RANGE,
				    "infill: fill_density %g %% is out of range; use 0 to 100 %% "
				    "(100 %% is solid)",
				    s->fill_density);
	if ((unsigned)s->fill_pattern >= INFILL_PATTERNS)
		return st_error_set(err, ST_ERR_ARG,
				    "infill: fill_pattern %d is unknown; use " PATTERNS_PRINTED,
				    (int)s->fill_pattern);
	if (!isfinite(s->fill_angle) || !isfinite(s->bridge_angle))
		return st_error_set(err, ST_ERR_RANGE,
				    "infill: fill_angle and bridge_angle must be finite degrees");
	if (s->top_solid_layers < 0 || s->bottom_solid_layers < 0 ||
	    s->top_solid_layers > 10000 || s->bottom_solid_layers > 10000)
		return st_error_set(err, ST_ERR_RANGE,
				    "infill: top_solid_layers %d / bottom_solid_layers %d out of "
				    "range; use 0 to 10000",
				    s->top_solid_layers, s->bottom_solid_layers);
	if (!(s->top_solid_min_thickness >= 0.0 && s->top_solid_min_thickness <= 1000.0) ||
	    !(s->bottom_solid_min_thickness >= 0.0 && s->bottom_solid_min_thickness <= 1000.0))
		return st_error_set(err, ST_ERR_RANGE,
				    "infill: top_solid_min_thickness %g mm / "
				    "bottom_solid_min_thickness %g mm out of range; use 0 to 1000 mm",
				    s->top_solid_min_thickness, s->bottom_solid_min_thickness);
	if (!(s->layer_height >= 0.0 && s->layer_height <= s->nozzle_diameter))
		return st_error_set(err, ST_ERR_RANGE,
				    "infill: layer_height %g mm is out of range; use 0 (the most "
				    "common layer height) up to the nozzle diameter %g mm",
				    s->layer_height, s->nozzle_diameter);
	if ((rc = check_width(s, "perimeter_extrusion_width", s->perimeter_extrusion_width, err)) ||
	    (rc = check_width(s, "infill_extrusion_width", s->infill_extrusion_width, err)) ||
	    (rc = check_width(s, "solid_infill_extrusion_width", s->solid_infill_extrusion_width,
			      err)) ||
	    (rc = check_width(s, "top_infill_extrusion_width", s->top_infill_extrusion_width, err)) ||
	    (s->first_layer_extrusion_width != 0.0 &&
	     (rc = check_width(s, "first_layer_extrusion_width", s->first_layer_extrusion_width,
			       err))))
		return rc;
	if (!(s->infill_overlap >= 0.0 && s->infill_overlap <= 100.0))
		return st_error_set(err, ST_ERR_RANGE,
				    "infill: infill_overlap %g %% is out of range; use 0 to 100 %% "
				    "of the perimeter width",
				    s->infill_overlap);
	if (!(s->solid_infill_below_area >= 0.0 && s->solid_infill_below_area <= 1e6))
		return st_error_set(err, ST_ERR_RANGE,
				    "infill: solid_infill_below_area %g mm^2 is out of range; use 0 "
				    "to 1e6 mm^2",
				    s->solid_infill_below_area);
	if (!(s->bridge_flow_ratio > 0.0 && s->bridge_flow_ratio <= 2.0))
		return st_error_set(err, ST_ERR_RANGE,
				    "infill: bridge_flow_ratio %g is out of range; use (0, 2]",
				    s->bridge_flow_ratio);
	if (s->ironing && !(s->ironing_spacing > 0.0 && s->ironing_spacing <= 10.0 &&
			    (unsigned)s->ironing_type <= IRON_SOLID))
		return st_error_set(err, ST_ERR_RANGE,
				    "infill: ironing_spacing %g mm or ironing type %d is out of "
				    "range; use (0, 10] mm and top, topmost or solid",
				    s->ironing_spacing, (int)s->ironing_type);
	if (!(s->gap_fill_min >= 0.0 && s->gap_fill_min <= 10.0))
		return st_error_set(err, ST_ERR_RANGE,
				    "infill: gap_fill_min %g mm is out of range; use 0 to 10 mm",
				    s->gap_fill_min);
	return 0;
}

static int cmp_double(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

/* The most common layer height of the stack above the first layer, mm. */
static double common_height(const struct slice_stack *st, struct st_error *err)
{
	size_t from = st->n > 1 ? 1 : 0, n = st->n - from;
	double *h = malloc(n * sizeof(*h)), best;
	size_t run = 0, best_run = 0;

	if (!h) {
		st_error_set(err, ST_ERR_NOMEM, "infill: out of memory for %zu heights", n);
		return -1.0;
	}
	for (size_t i = 0; i < n; i++)
		h[i] = st->layers[from + i].height;
	qsort(h, n, sizeof(*h), cmp_double);
	best = h[0];
	for (size_t i = 0; i < n; i++) {
		run = i && h[i] - h[i - 1] < INFILL_EPS_MM ? run + 1 : 1;
		if (run > best_run) {
			best_run = run;
			best = h[i];
		}
	}
	free(h);
	return best;
}

/* A line of a monotonic sweep: where it lies across and along the lines. */
struct swept {
	double across, along;
	size_t i;
};

static int by_sweep(const void *a, const void *b)
{
	const struct swept *p = a, *q = b;

	if (p->across != q->across)
		return p->across < q->across ? -1 : 1;
	return (p->along > q->along) - (p->along < q->along);
}

/* Distance from (x, y) to the nearer end of line i. */
static double end_dist(const struct clip_paths *segs, size_t i, int64_t x, int64_t y)
{
	const int64_t *xy = clip_path_xy(segs, i);
	size_t m = clip_path_len(segs, i);
	double a = hypot((double)(xy[0] - x), (double)(xy[1] - y));
	double b = hypot((double)(xy[2 * m - 2] - x), (double)(xy[2 * m - 1] - y));

	return fmin(a, b);
}

/*
 * The monotonic order of the parallel lines segs (n > 0): by their
 * midpoints' offset across the lines' direction, then along it, the sweep
 * starting on the side nearer (x, y).  NULL when out of memory.
 */
static size_t *sweep_order(const struct clip_paths *segs, int64_t x, int64_t y)
{
	size_t n = segs->n;
	struct swept *sw = malloc(n * sizeof(*sw));
	size_t *ord = malloc(n * sizeof(*ord));
	double dx = 1, dy = 0;

	if (!sw || !ord) {
		free(sw);
		free(ord);
		return NULL;
	}
	for (size_t i = 0; i < n; i++) { /* the direction of the first line with a length */
		const int64_t *xy = clip_path_xy(segs, i);
		size_t m = clip_path_len(segs, i);
		double ex = (double)(xy[2 * m - 2] - xy[0]), ey = (double)(xy[2 * m - 1] - xy[1]);
		if (m >= 2 && hypot(ex, ey) > 0) {
			dx = ex / hypot(ex, ey);
			dy = ey / hypot(ex, ey);
			break;
		}
	}
	for (size_t i = 0; i < n; i++) {
		const int64_t *xy = clip_path_xy(segs, i);
		size_t m = clip_path_len(segs, i);
		double mx = ((double)xy[0] + (double)xy[2 * m - 2]) / 2;
		double my = ((double)xy[1] + (double)xy[2 * m - 1]) / 2;
		sw[i] = (struct swept){-dy * mx + dx * my, dx * mx + dy * my, i};
	}
	qsort(sw, n, sizeof(*sw), by_sweep);
	bool back = end_dist(segs, sw[n - 1].i, x, y) < end_dist(segs, sw[0].i, x, y);
	for (size_t k = 0; k < n; k++)
		ord[k] = sw[back ? n - 1 - k : k].i;
	free(sw);
	return ord;
}

/*
 * Append the paths of it to out, nearest first from (*lx, *ly): lines from
 * their nearer end, closed loops (it->loops) from their nearest vertex (a
 * loop ends where it starts); monotonic lines in their sweep order
 * (sweep_order), each from its end nearer the last.
 */
static int order_paths(const struct item *it, int64_t *lx, int64_t *ly, struct layer_paths *out,
		       struct st_error *err)
{
	const struct clip_paths *segs = &it->segs;
	size_t n = segs->n, maxlen = 0, next = 0;
	bool *used = calloc(n ? n : 1, sizeof(*used));
	size_t *ord = it->monotonic && n ? sweep_order(segs, *lx, *ly) : NULL;
	struct path_point *pts;
	int rc = 0;

	for (size_t i = 0; i < n; i++)
		maxlen = clip_path_len(segs, i) > maxlen ? clip_path_len(segs, i) : maxlen;
	pts = malloc((maxlen ? maxlen : 1) * sizeof(*pts));
	if (!used || !pts || (it->monotonic && n && !ord)) {
		rc = st_error_set(err, ST_ERR_NOMEM, "infill: out of memory ordering %zu paths", n);
		goto out_free;
	}
	for (size_t left = n; left && !rc; left--) {
		size_t best = n, start = 0;
		bool rev = false;
		double bd = INFINITY;
		if (ord) { /* the next of the sweep, from its end nearer the last */
			const int64_t *xy = clip_path_xy(segs, ord[next]);
			size_t m = clip_path_len(segs, ord[next]);
			best = ord[next++];
			rev = hypot((double)(xy[2 * m - 2] - *lx), (double)(xy[2 * m - 1] - *ly)) <
			      hypot((double)(xy[0] - *lx), (double)(xy[1] - *ly));
			start = rev ? m - 1 : 0;
		}
		for (size_t i = 0; !ord && i < n; i++) {
			const int64_t *xy = clip_path_xy(segs, i);
			size_t m = clip_path_len(segs, i);
			/* starts tried: every vertex of a loop, both ends of a line */
			for (size_t k = 0; !used[i] && k < m; k += it->loops || m < 2 ? 1 : m - 1) {
				double d = hypot((double)(xy[2 * k] - *lx), (double)(xy[2 * k + 1] - *ly));
				if (d < bd) {
					bd = d;
					best = i;
					start = k;
					rev = !it->loops && k > 0;
				}
			}
		}
		if (best == n)
			break;
		used[best] = true;
		const int64_t *xy = clip_path_xy(segs, best);
		size_t m = clip_path_len(segs, best);
		double len = 0;
		for (size_t k = 0; k < m; k++) {
			size_t j = it->loops ? (start + k) % m : rev ? m - 1 - k : k;
			pts[k] = (struct path_point){xy[2 * j], xy[2 * j + 1], llround(it->w)};
			if (k)
				len += hypot((double)(pts[k].x - pts[k - 1].x),
					     (double)(pts[k].y - pts[k - 1].y));
		}
		if (m < (it->loops ? 3u : 2u) || len < INFILL_MIN_SEGMENT_NM)
			continue;
		rc = layer_add_path(out, it->role, it->loops, pts, m, err);
		if (!rc && ord)
			out->paths[out->n - 1].ordered = true;
		*lx = pts[it->loops ? 0 : m - 1].x;
		*ly = pts[it->loops ? 0 : m - 1].y;
	}
out_free:
	free(used);
	free(ord);
	free(pts);
	return rc;
}

int infill_job_new(const struct infill_settings *s, const struct slice_stack *st,
		   struct infill_job **out, struct st_error *err)
{
	struct infill_job *job;
	int rc;

	if (!out)
		return st_error_set(err, ST_ERR_ARG, "infill: infill_job_new needs an out pointer");
	*out = NULL;
	rc = infill_settings_check(s, err);
	if (rc)
		return rc;
	if (!st)
		return st_error_set(err, ST_ERR_ARG, "infill: no layers given");
	for (size_t i = 0; i < st->n; i++)
		if (!(st->layers[i].height > 0.0 && st->layers[i].height <= s->nozzle_diameter))
			return st_error_set(err, ST_ERR_RANGE,
					    "infill: layer %zu is %g mm thick; use layers thicker "
					    "than 0 and at most the nozzle diameter %g mm",
					    i, st->layers[i].height, s->nozzle_diameter);
	job = calloc(1, sizeof(*job));
	if (!job)
		return st_error_set(err, ST_ERR_NOMEM, "infill: out of memory");
	job->s = *s;
	job->st = st;
	if (st->n) {
		double href = s->layer_height > 0.0 ? s->layer_height : common_height(st, err);
		if (href < 0.0) {
			free(job);
			return ST_ERR_NOMEM;
		}
		job->t_top = fmax(s->top_solid_min_thickness, s->top_solid_layers * href);
		job->t_bot = fmax(s->bottom_solid_min_thickness, s->bottom_solid_layers * href);
	}
	job->overlap = s->infill_overlap / 100.0 * s->perimeter_extrusion_width * SLICE_UNITS_PER_MM;
	*out = job;
	return 0;
}

void infill_job_free(struct infill_job *job)
{
	free(job);
}

void infill_plan_free(struct infill_plan *p)
{
	if (!p)
		return;
	for (size_t i = 0; i < p->n; i++) {
		clip_paths_free(&p->v[i].segs);
		free(p->v[i].pts);
	}
	free(p->v);
	free(p);
}

int infill_plan_layer(const struct infill_job *job, size_t i, const struct clip_expolys *inner,
		      struct infill_plan **out, struct st_error *err)
{
	struct clip_paths R = {0};
	struct infill_settings first;
	struct ctx c;
	int rc;

	if (!out)
		return st_error_set(err, ST_ERR_ARG, "infill: infill_plan_layer needs an out pointer");
	*out = NULL;
	if (!job || !inner || i >= job->st->n)
		return st_error_set(err, ST_ERR_ARG, "infill: no layer %zu to plan", i);
	rc = clip_paths_append(&R, &inner->paths, err);
	if (!rc)
		rc = clip_clean(&R, INFILL_CLEAN_NM, err);
	if (rc) {
		clip_paths_free(&R);
		return rc;
	}
	/* Layer 0 at the first layer's width, every class (PrusaSlicer's flow). */
	first = job->s;
	if (i == 0 && first.first_layer_extrusion_width > 0.0) {
		first.infill_extrusion_width = first.first_layer_extrusion_width;
		first.solid_infill_extrusion_width = first.first_layer_extrusion_width;
		first.top_infill_extrusion_width = first.first_layer_extrusion_width;
	}
	c = (struct ctx){.s = i == 0 ? &first : &job->s,
			 .st = job->st,
			 .R = &R,
			 .err = err,
			 .layer = i,
			 .h = job->st->layers[i].height,
			 .overlap = job->overlap,
			 .t_top = job->t_top,
			 .t_bot = job->t_bot};
	c.plan = calloc(1, sizeof(*c.plan));
	if (!c.plan) {
		clip_paths_free(&R);
		return st_error_set(err, ST_ERR_NOMEM, "infill: out of memory planning layer %zu", i);
	}
	rc = infill_fill_layer(&c);
	clip_paths_free(&R);
	if (rc) {
		infill_plan_free(c.plan);
		return rc;
	}
	*out = c.plan;
	return 0;
}

int infill_emit_layer(struct infill_job *job, const struct infill_plan *plan,
		      struct layer_paths *out, struct st_error *err)
{
	int rc = 0;

	if (!job || !plan || !out)
		return st_error_set(err, ST_ERR_ARG, "infill: no plan or layer to emit into");
	for (size_t i = 0; i < plan->n && !rc; i++) {
		const struct item *it = &plan->v[i];
		if (!it->fixed) {
			rc = order_paths(it, &job->lx, &job->ly, out, err);
			continue;
		}
		rc = layer_add_path(out, it->role, it->closed, it->pts, it->n, err);
		if (it->n) {
			job->lx = it->pts[it->n - 1].x;
			job->ly = it->pts[it->n - 1].y;
		}
	}
	return rc;
}

int infill_generate(const struct infill_settings *s, const struct slice_stack *st,
		    const struct clip_expolys *inner, struct layer_stack *out,
		    struct st_error *err)
{
	struct infill_job *job = NULL;
	int rc = infill_settings_check(s, err);

	if (rc)
		return rc;
	if (!st || !out || (st->n && !inner))
		return st_error_set(err, ST_ERR_ARG, "infill: no layers, regions or output given");
	if (out->nlayers != st->n)
		return st_error_set(err, ST_ERR_ARG,
				    "infill: the output has %zu layers but the slices %zu",
				    out->nlayers, st->n);
	if (!st->n)
		return 0;
	rc = infill_job_new(s, st, &job, err);
	for (size_t i = 0; i < st->n && !rc; i++) {
		struct infill_plan *plan;
		rc = infill_plan_layer(job, i, &inner[i], &plan, err);
		if (!rc)
			rc = infill_emit_layer(job, plan, &out->layers[i], err);
		infill_plan_free(plan);
	}
	infill_job_free(job);
	return rc;
}
