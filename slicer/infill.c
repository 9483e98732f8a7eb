/*
 * infill.c - classification of the region inside the walls into skins,
 * bridges, solid and sparse infill, and their lines (see infill.h).
 */
#include "infill.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "medial.h"
#include "patterns.h"
#include "perimeters.h"
#include "st_grow.h"

/* Chord error of round offsets, nm. */
#define INFILL_ARC_NM 2000.0
/* Heights closer than this are equal, mm. */
#define INFILL_EPS_MM 1e-6
/* Gap between bridge threads beyond their diameter, mm. */
#define INFILL_BRIDGE_GAP_MM 0.05
/* Bridges reach this many solid widths into the supported area. */
#define INFILL_ANCHOR_WIDTHS 3.0
/* Bridge directions tried: every 180 / this many degrees (5, the step of
 * PrusaSlicer's bridge detector; every degree cost a sixth of the infill
 * stage on the scan model and chose the same bridges within a few degrees). */
#define INFILL_BRIDGE_DIRS 36
/* Directions anchoring within this fraction of the best compete on length. */
#define INFILL_BRIDGE_SCORE_SLACK 0.01
/* Solid lines on an island's edge parallel to them stay this far inside, nm. */
#define INFILL_EDGE_MARGIN_NM 10000.0
/* The region inside the walls loses vertices that move its boundary less
 * than this, nm: its round joins (arcs within 2 um) give it four times the
 * section's vertices, and every class is cut from it. */
#define INFILL_CLEAN_NM 2000.0
/* Clipped pieces of lines shorter than this are dropped, nm. */
#define INFILL_MIN_SEGMENT_NM 10000.0

/*
 * One step of a layer's infill as planned: lines to be ordered nearest
 * first from wherever the nozzle is by then, or a path to append as it is
 * (gap fill).  Planning needs no nozzle position, so layers can be planned
 * in parallel and emitted in order.
 */
struct item {
	bool fixed;		/* a path as it is, else lines to order */
	enum path_role role;
	double w;		/* nm, bead width of the lines */
	struct clip_paths segs; /* the lines */
	bool closed;		/* the path's */
	size_t n;
	struct path_point *pts; /* the path's n points */
};

struct infill_plan {
	size_t n, cap;
	struct item *v;
};

/* What infill_job_new works out once for every layer. */
struct infill_job {
	struct infill_settings s;
	const struct slice_stack *st;
	double overlap;	     /* nm, how far infill reaches into the walls */
	double t_top, t_bot; /* mm, shell thicknesses */
	int64_t lx, ly;	     /* nm, where the last emitted path ended */
};

/* Everything the planning of one layer works with; lengths nm unless named. */
struct ctx {
	const struct infill_settings *s;
	const struct slice_stack *st;
	const struct clip_paths *R;	  /* this layer's region inside the walls */
	struct infill_plan *plan;
	struct st_error *err;
	size_t layer;	    /* index of the layer being filled */
	double h;	    /* mm, its height */
	double overlap;	    /* how far infill reaches into the walls */
	double t_top, t_bot; /* mm, shell thicknesses */
};

/* The lines of one solid class: width, flow spacing, role. */
struct bead {
	double w, sp;
	enum path_role role;
	bool gap_fill;
};

/* The patterns printed, for messages. */
#define PATTERNS_PRINTED "rectilinear, grid, gyroid, triangles, stars or cubic"

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
	{"alignedrectilinear", -1},
	{"monotonic", -1},
	{"monotoniclines", -1},
	{"line", -1},
	{"concentric", -1},
	{"honeycomb", -1},
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
	    (rc = check_width(s, "top_infill_extrusion_width", s->top_infill_extrusion_width, err)))
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

/* z of the bottom of layer i, mm. */
static double z_bottom(const struct slice_stack *st, size_t i)
{
	return st->layers[i].z - st->layers[i].height;
}

/*
 * out = R_i minus the intersection of the solid regions of the k layers
 * next to layer i in direction dir (+1 up, -1 down), k = 1 .. count; a
 * layer beyond the stack is empty.  count 0 gives an empty out: the part
 * of R_i within count layers of a top (dir +1) or bottom surface.
 */
static int shell(struct ctx *c, int dir, size_t count, struct clip_paths *out)
{
	const struct clip_paths *R = c->R;
	struct clip_paths inter = {0};
	int rc = 0;

	clip_paths_clear(out);
	if (!count)
		return 0;
	for (size_t k = 1; k <= count && !rc; k++) {
		if (dir < 0 ? k > c->layer : c->layer + k >= c->st->n) {
			clip_paths_clear(&inter);
			break;
		}
		const struct clip_paths *S = &c->st->layers[c->layer + (size_t)dir * k].regions.paths;
		if (k == 1)
			rc = clip_paths_append(&inter, S, c->err);
		else
			rc = clip_boolean(CLIP_INTERSECTION, &inter, S, CLIP_NONZERO, &inter, c->err);
	}
	if (!rc)
		rc = clip_boolean(CLIP_DIFFERENCE, R, &inter, CLIP_NONZERO, out, c->err);
	clip_paths_free(&inter);
	return rc;
}

/* A new empty item at the end of the plan, NULL when out of memory. */
static struct item *plan_item(struct ctx *c)
{
	struct infill_plan *p = c->plan;

	struct item *grown = st_grow(p->v, &p->cap, p->n + 1, sizeof(*grown));

	if (!grown) {
		st_error_set(c->err, ST_ERR_NOMEM, "infill: out of memory planning a layer");
		return NULL;
	}
	p->v = grown;
	p->v[p->n] = (struct item){0};
	return &p->v[p->n++];
}

/* Plan segs as open paths of role and width w (nm), to be ordered nearest
 * first when the layer is emitted. */
static int emit_segments(struct ctx *c, const struct clip_paths *segs, enum path_role role,
			 double w)
{
	struct item *it = plan_item(c);

	if (!it)
		return ST_ERR_NOMEM;
	it->role = role;
	it->w = w;
	return clip_paths_append(&it->segs, segs, c->err);
}

/* Plan a path of role to be appended as it is. */
static int emit_path(struct ctx *c, enum path_role role, bool closed,
		     const struct path_point *pts, size_t n)
{
	struct item *it = plan_item(c);

	if (!it)
		return ST_ERR_NOMEM;
	it->fixed = true;
	it->role = role;
	it->closed = closed;
	if (!n)
		return 0;
	it->pts = malloc(n * sizeof(*pts));
	if (!it->pts)
		return st_error_set(c->err, ST_ERR_NOMEM, "infill: out of memory planning a path");
	memcpy(it->pts, pts, n * sizeof(*pts));
	it->n = n;
	return 0;
}

/* Append the lines of it to out, nearest first from (*lx, *ly). */
static int order_segments(const struct item *it, int64_t *lx, int64_t *ly,
			  struct layer_paths *out, struct st_error *err)
{
	const struct clip_paths *segs = &it->segs;
	size_t n = segs->n, maxlen = 0;
	bool *used = calloc(n ? n : 1, sizeof(*used));
	struct path_point *pts;
	int rc = 0;

	for (size_t i = 0; i < n; i++)
		maxlen = clip_path_len(segs, i) > maxlen ? clip_path_len(segs, i) : maxlen;
	pts = malloc((maxlen ? maxlen : 1) * sizeof(*pts));
	if (!used || !pts) {
		rc = st_error_set(err, ST_ERR_NOMEM, "infill: out of memory ordering %zu lines", n);
		goto out_free;
	}
	for (size_t left = n; left && !rc; left--) {
		size_t best = n;
		bool rev = false;
		double bd = INFINITY;
		for (size_t i = 0; i < n; i++) {
			if (used[i])
				continue;
			const int64_t *xy = clip_path_xy(segs, i);
			size_t m = clip_path_len(segs, i);
			double d0 = hypot((double)(xy[0] - *lx), (double)(xy[1] - *ly));
			double d1 = hypot((double)(xy[2 * m - 2] - *lx), (double)(xy[2 * m - 1] - *ly));
			if (fmin(d0, d1) < bd) {
				bd = fmin(d0, d1);
				best = i;
				rev = d1 < d0;
			}
		}
		used[best] = true;
		const int64_t *xy = clip_path_xy(segs, best);
		size_t m = clip_path_len(segs, best);
		double len = 0;
		for (size_t k = 0; k < m; k++) {
			size_t j = rev ? m - 1 - k : k;
			pts[k] = (struct path_point){xy[2 * j], xy[2 * j + 1], llround(it->w)};
			if (k)
				len += hypot((double)(pts[k].x - pts[k - 1].x),
					     (double)(pts[k].y - pts[k - 1].y));
		}
		if (m < 2 || len < INFILL_MIN_SEGMENT_NM)
			continue;
		rc = layer_add_path(out, it->role, false, pts, m, err);
		*lx = pts[m - 1].x;
		*ly = pts[m - 1].y;
	}
out_free:
	free(used);
	free(pts);
	return rc;
}

/*
 * One region grown by delta nm (round joins), kept while the same region is
 * clipped against again: the bridge directions all grow their island by
 * the same distance but for the smallest islands.
 */
struct grown {
	bool valid;
	double delta;
	struct clip_paths g;
};

/* Lines clipped to the region grown by delta nm (round joins) into segs;
 * memo (may be NULL) holds the growth of this same region. */
static int clip_to(struct ctx *c, const struct clip_paths *lines, const struct clip_paths *region,
		   double delta, struct grown *memo, struct clip_paths *segs)
{
	struct grown local = {0}, *m = memo ? memo : &local;
	int rc = 0;

	if (!m->valid || m->delta != delta) {
		m->valid = false;
		rc = clip_offset(region, delta, CLIP_JOIN_ROUND, 0.0, INFILL_ARC_NM, &m->g, c->err);
		m->valid = !rc;
		m->delta = delta;
	}
	if (!rc)
		rc = clip_lines(CLIP_INTERSECTION, lines, &m->g, CLIP_NONZERO, segs, c->err);
	clip_paths_free(&local.g);
	return rc;
}

/*
 * Lines of direction a across one island P, a whole number of beads at
 * about spacing sp spanning it, clipped so their ends stop sp/2 inside P
 * grown by the overlap, into segs; *fit is the spacing used.  memo (may be
 * NULL) carries P's growth between calls on the same island.
 */
static int fitted_lines(struct ctx *c, const struct clip_paths *P, double a, double sp,
			struct grown *memo, struct clip_paths *segs, double *fit)
{
	struct clip_paths lines = {0};
	struct pat_box box;
	double vmin, vmax;
	int rc;

	clip_paths_clear(segs);
	*fit = 0;
	if (!pat_box_of(P, &box))
		return 0;
	pat_extent(P, a, &vmin, &vmax);
	double n = fmax(1.0, round((vmax - vmin) / sp));
	*fit = (vmax - vmin) / n;
	if (!(*fit > 0))
		return 0;
	rc = pat_lines(a, *fit, vmin + *fit / 2.0, &box, &lines, c->err);
	if (!rc)
		rc = clip_to(c, &lines, P,
			     fmax(c->overlap - sp / 2.0, INFILL_EDGE_MARGIN_NM - *fit / 2.0), memo,
			     segs);
	clip_paths_free(&lines);
	return rc;
}

/*
 * Gap fill of one solid island P: what beads of width fit along segs leave
 * uncovered, where at least gap_fill_min (and the layer height) wide, as
 * centre-line beads of the local width.
 */
static int gap_fill(struct ctx *c, const struct clip_paths *P, const struct clip_paths *segs,
		    double fit)
{
	double minw = fmax(c->s->gap_fill_min, c->h) * SLICE_UNITS_PER_MM;
	struct clip_paths cover = {0}, piece = {0};
	struct clip_expolys gaps = {0};
	struct medial_lines ml = {0};
	int rc = segs->n ? clip_offset_open(segs, fit / 2.0, CLIP_JOIN_ROUND, CLIP_END_ROUND,
					    2.0, INFILL_ARC_NM, &cover, c->err)
			 : 0;

	if (!rc)
		rc = clip_boolean_ex(CLIP_DIFFERENCE, P, &cover, CLIP_NONZERO, &gaps, c->err);
	for (size_t i = 0; i < gaps.n && !rc; i++) {
		double area = 0;
		rc = clip_expolys_get(&gaps, i, &piece, c->err);
		if (!rc)
			rc = clip_paths_area(&piece, &area, c->err);
		if (rc || area < M_PI / 4.0 * minw * minw)
			continue;
		rc = perim_medial_axis(&piece, minw, fmax(minw / 4.0, 1000.0), INFILL_ARC_NM, &ml,
				       c->err);
		for (size_t k = 0; k < ml.n && !rc; k++) {
			struct medial_line *l = &ml.v[k];
			rc = emit_path(c, PATH_GAP_FILL, l->closed, l->pts, l->n);
		}
		perim_medial_free(&ml);
	}
	clip_paths_free(&cover);
	clip_paths_free(&piece);
	clip_expolys_free(&gaps);
	return rc;
}

/*
 * Bridge direction of island P over the anchors A (the layer below): of
 * the directions tried, those whose lines end on A at both ends for the
 * largest share of their length (within INFILL_BRIDGE_SCORE_SLACK) compete
 * on the mean length of those anchored lines; the shortest wins.
 */
static int bridge_direction(struct ctx *c, const struct clip_paths *P,
			    const struct clip_locator *A, double sp, double *angle)
{
	enum { N = INFILL_BRIDGE_DIRS };
	double score[N], mean[N], best = -1.0, fit;
	struct clip_paths segs = {0};
	struct grown memo = {0};
	int rc = 0;

	*angle = 0.0;
	for (int k = 0; k < N && !rc; k++) {
		double a = k * M_PI / N, total = 0, held = 0;
		size_t nheld = 0;
		rc = fitted_lines(c, P, a, sp, &memo, &segs, &fit);
		for (size_t i = 0; i < segs.n && !rc; i++) {
			const int64_t *xy = clip_path_xy(&segs, i);
			size_t m = clip_path_len(&segs, i);
			double dx = (double)(xy[2 * m - 2] - xy[0]), dy = (double)(xy[2 * m - 1] - xy[1]);
			double len = hypot(dx, dy);
			if (len < INFILL_MIN_SEGMENT_NM)
				continue;
			/* Ends nudged 1 um inward, off the boundary they were clipped at. */
			double ux = dx / len * 1000.0, uy = dy / len * 1000.0;
			total += len;
			if (clip_locator_inside(A, xy[0] + llround(ux), xy[1] + llround(uy)) &&
			    clip_locator_inside(A, xy[2 * m - 2] - llround(ux),
						xy[2 * m - 1] - llround(uy))) {
				held += len;
				nheld++;
			}
		}
		score[k] = total > 0 ? held / total : 0;
		mean[k] = nheld ? held / (double)nheld : INFINITY;
		best = fmax(best, score[k]);
	}
	double shortest = INFINITY;
	for (int k = 0; k < N && !rc; k++)
		if (score[k] >= best - INFILL_BRIDGE_SCORE_SLACK && mean[k] < shortest) {
			shortest = mean[k];
			*angle = k * M_PI / N;
		}
	clip_paths_free(&segs);
	clip_paths_free(&memo.g);
	return rc;
}

/*
 * Whether island P is narrower than the line spacing sp everywhere (P
 * shrunk by sp/2 is empty).  Lines of any direction would cross such a
 * strip as short dashes with voids between them (1 % of the section of a
 * 2 mm wall between its walls); its centre line carries it instead.
 */
static int too_narrow(struct ctx *c, const struct clip_paths *P, double sp, bool *narrow)
{
	struct clip_paths core = {0};
	int rc = clip_offset(P, -sp / 2.0, CLIP_JOIN_ROUND, 0.0, INFILL_ARC_NM, &core, c->err);

	*narrow = !rc && core.n == 0;
	clip_paths_free(&core);
	return rc;
}

/*
 * Solid lines over every island of X: direction a, or per island the
 * detected bridge direction over anchors when anchors is not NULL.
 */
static int fill_solid(struct ctx *c, const struct clip_paths *X, double a,
		      const struct bead *b, const struct clip_paths *anchors)
{
	struct clip_expolys ex = {0};
	struct clip_paths P = {0}, segs = {0};
	struct clip_locator *A = NULL;
	double fit;
	int rc = clip_boolean_ex(CLIP_UNION, X, NULL, CLIP_NONZERO, &ex, c->err);

	if (!rc && anchors && ex.n && !(A = clip_locator_new(anchors, c->err)))
		rc = c->err ? c->err->code : ST_ERR_NOMEM;

	for (size_t i = 0; i < ex.n && !rc; i++) {
		double ai = a;
		bool narrow = false;
		rc = clip_expolys_get(&ex, i, &P, c->err);
		if (!rc && b->gap_fill)
			rc = too_narrow(c, &P, b->sp, &narrow);
		if (!rc && narrow) { /* one bead along it, as wide as it is */
			clip_paths_clear(&segs);
			rc = gap_fill(c, &P, &segs, 0.0);
			continue;
		}
		if (!rc && anchors)
			rc = bridge_direction(c, &P, A, b->sp, &ai);
		if (!rc)
			rc = fitted_lines(c, &P, ai, b->sp, NULL, &segs, &fit);
		if (!rc)
			rc = emit_segments(c, &segs, b->role, b->w);
		if (!rc && b->gap_fill && segs.n)
			rc = gap_fill(c, &P, &segs, fit);
	}
	clip_locator_free(A);
	clip_expolys_free(&ex);
	clip_paths_free(&P);
	clip_paths_free(&segs);
	return rc;
}

/*
 * Triangles, stars and cubic, PrusaSlicer's way (FillRectilinear.cpp): three
 * sets of lines at the fill angle plus 0, 60 and 120 degrees on every layer
 * (no alternation), each 3 S apart so the density is that of lines S apart.
 * Stars shifts the third set by half its period; cubic shifts the sets by
 * +-sqrt(1/2) z, so that the layers stack into tilted cubes.
 */
static int three_line_sets(struct ctx *c, double S, const struct pat_box *box,
			   struct clip_paths *lines)
{
	const struct infill_settings *s = c->s;
	double a = s->fill_angle * M_PI / 180.0;
	double dz = sqrt(0.5) * c->st->layers[c->layer].z * SLICE_UNITS_PER_MM;
	int rc = 0;

	for (int k = 0; k < 3 && !rc; k++) {
		double phase = 0.0;

		if (s->fill_pattern == INFILL_STARS && k == 2)
			phase = 1.5 * S;
		else if (s->fill_pattern == INFILL_CUBIC)
			phase = k == 1 ? -dz : dz;
		rc = pat_lines(a + k * M_PI / 3.0, 3.0 * S, phase, box, lines, c->err);
	}
	return rc;
}

/* Sparse infill of X at fill_density with the chosen pattern. */
static int fill_sparse(struct ctx *c, const struct clip_paths *X, double a)
{
	const struct infill_settings *s = c->s;
	double w = s->infill_extrusion_width * SLICE_UNITS_PER_MM;
	double sp = perim_spacing(s->infill_extrusion_width, c->h) * SLICE_UNITS_PER_MM;
	double d = s->fill_density / 100.0, S = sp / d;
	struct clip_paths lines = {0}, segs = {0};
	struct pat_box box;
	int rc = 0;

	if (!pat_box_of(X, &box))
		return 0;
	switch (s->fill_pattern) {
	case INFILL_RECTILINEAR:
		rc = pat_lines(a, S, 0.0, &box, &lines, c->err);
		break;
	case INFILL_GRID:
		rc = pat_lines(a, 2.0 * S, 0.0, &box, &lines, c->err);
		if (!rc)
			rc = pat_lines(a + M_PI / 2.0, 2.0 * S, 0.0, &box, &lines, c->err);
		break;
	case INFILL_TRIANGLES:
	case INFILL_STARS:
	case INFILL_CUBIC:
		rc = three_line_sets(c, S, &box, &lines);
		break;
	default: { /* INFILL_GYROID, at the layer's mid-height */
		double z = (c->st->layers[c->layer].z - c->h / 2.0) * SLICE_UNITS_PER_MM;
		rc = pat_gyroid(d / (sp * PAT_GYROID_LENGTH), z, &box, &lines, c->err);
		break;
	}
	}
	if (!rc)
		rc = clip_to(c, &lines, X, c->overlap - sp / 2.0, NULL, &segs);
	if (!rc)
		rc = emit_segments(c, &segs, PATH_SPARSE_INFILL, w);
	clip_paths_free(&lines);
	clip_paths_free(&segs);
	return rc;
}

/*
 * Split X into the islands smaller than solid_infill_below_area (appended
 * to small) and the rest (appended to big).
 */
static int split_small(struct ctx *c, const struct clip_paths *X, struct clip_paths *small,
		       struct clip_paths *big)
{
	struct clip_expolys ex = {0};
	struct clip_paths P = {0};
	double lim = c->s->solid_infill_below_area * SLICE_UNITS_PER_MM * SLICE_UNITS_PER_MM;
	int rc = clip_boolean_ex(CLIP_UNION, X, NULL, CLIP_NONZERO, &ex, c->err);

	for (size_t i = 0; i < ex.n && !rc; i++) {
		double area = 0;
		rc = clip_expolys_get(&ex, i, &P, c->err);
		if (!rc)
			rc = clip_paths_area(&P, &area, c->err);
		if (!rc)
			rc = clip_paths_append(area < lim ? small : big, &P, c->err);
	}
	clip_expolys_free(&ex);
	clip_paths_free(&P);
	return rc;
}

/* Number of layers of the shell of thickness t (mm) seen from layer i. */
static size_t shell_count(const struct slice_stack *st, size_t i, int dir, double t)
{
	size_t n = 0;

	if (dir > 0)
		for (size_t j = i; j < st->n && st->layers[j].z - st->layers[i].z < t - INFILL_EPS_MM;
		     j++)
			n++;
	else
		for (size_t j = i + 1; j-- > 0 && z_bottom(st, i) - z_bottom(st, j) < t - INFILL_EPS_MM;)
			n++;
	return n;
}

/* Classes of one layer, in printing order (see infill.h). */
enum { CL_BOTTOM, CL_BRIDGE, CL_SOLID, CL_SPARSE, CL_TOP, CL_N };

/*
 * Regions of layer c->layer by class (see infill.h for the rules).
 * cl[CL_BRIDGE] is the bridges grown into their anchors.
 */
static int classify(struct ctx *c, struct clip_paths cl[CL_N])
{
	const struct slice_stack *st = c->st;
	size_t i = c->layer;
	const struct clip_paths *R = c->R;
	double sw = perim_spacing(c->s->solid_infill_extrusion_width, c->h) * SLICE_UNITS_PER_MM;
	struct clip_paths t = {0}, taken = {0}, rest = {0};
	int rc = 0;

	if (i > 0) { /* over air, opened by half a line so slivers do not count */
		rc = clip_boolean(CLIP_DIFFERENCE, R, &st->layers[i - 1].regions.paths,
				  CLIP_NONZERO, &t, c->err);
		if (!rc)
			rc = clip_offset(&t, -sw / 2.0, CLIP_JOIN_ROUND, 0.0, INFILL_ARC_NM, &t,
					 c->err);
		if (!rc)
			rc = clip_offset(&t, sw / 2.0 + INFILL_ANCHOR_WIDTHS * c->s->solid_infill_extrusion_width *
						     SLICE_UNITS_PER_MM,
					 CLIP_JOIN_ROUND, 0.0, INFILL_ARC_NM, &t, c->err);
		if (!rc)
			rc = clip_boolean(CLIP_INTERSECTION, &t, R, CLIP_NONZERO, &cl[CL_BRIDGE],
					  c->err);
	}
	if (!rc)
		rc = clip_paths_append(&taken, &cl[CL_BRIDGE], c->err);
	if (!rc && i == 0)
		rc = clip_boolean(CLIP_DIFFERENCE, R, &taken, CLIP_NONZERO, &cl[CL_BOTTOM], c->err);
	if (!rc && i > 0) {
		rc = shell(c, +1, shell_count(st, i, +1, c->t_top), &t);
		if (!rc)
			rc = clip_boolean(CLIP_DIFFERENCE, &t, &taken, CLIP_NONZERO, &cl[CL_TOP],
					  c->err);
		if (!rc)
			rc = clip_paths_append(&taken, &cl[CL_TOP], c->err);
		/* The bottom shell: skin when it rests on the bed (or on a raft,
		 * which lifts the whole stack), else solid over bridges. */
		bool on_bed = z_bottom(st, i) - z_bottom(st, 0) < c->t_bot - INFILL_EPS_MM;
		if (!rc)
			rc = shell(c, -1, shell_count(st, i, -1, c->t_bot), &t);
		if (!rc)
			rc = clip_boolean(CLIP_DIFFERENCE, &t, &taken, CLIP_NONZERO,
					  &cl[on_bed ? CL_BOTTOM : CL_SOLID], c->err);
	}
	if (!rc)
		rc = clip_paths_append(&taken, &cl[CL_BOTTOM], c->err);
	if (!rc)
		rc = clip_paths_append(&taken, &cl[CL_SOLID], c->err);
	if (!rc)
		rc = clip_boolean(CLIP_DIFFERENCE, R, &taken, CLIP_NONZERO, &rest, c->err);
	if (!rc && c->s->fill_density >= 100.0)
		rc = clip_paths_append(&cl[CL_SOLID], &rest, c->err);
	else if (!rc && c->s->fill_density > 0.0)
		rc = split_small(c, &rest, &cl[CL_SOLID], &cl[CL_SPARSE]);
	clip_paths_free(&t);
	clip_paths_free(&taken);
	clip_paths_free(&rest);
	return rc;
}

/*
 * Ironing of the layer (ironing.h) after its top skin, at the skin's angle
 * a plus 45 degrees; cl are the layer's classes (empty without infill).
 */
static int plan_ironing(struct ctx *c, const struct clip_paths cl[CL_N], double a)
{
	const struct infill_settings *s = c->s;
	double sp = s->ironing_spacing * SLICE_UNITS_PER_MM;
	struct clip_paths solid = {0}, area = {0}, segs = {0};
	int rc = 0;

	/* Sparse infill above 95 % counts as solid, as in PrusaSlicer. */
	if (s->ironing_type == IRON_SOLID)
		for (int k = CL_BOTTOM; k < CL_N && !rc; k++)
			if (k != CL_BRIDGE && (k != CL_SPARSE || s->fill_density > 95.0))
				rc = clip_paths_append(&solid, &cl[k], c->err);
	if (!rc)
		rc = iron_area(s->ironing_type, s->top_solid_layers > 0, c->st, c->layer, c->R,
			       &solid, s->nozzle_diameter, &area, c->err);
	if (!rc)
		rc = iron_lines(&area, a + M_PI / 4.0, sp, &segs, c->err);
	if (!rc && segs.n)
		rc = emit_segments(c, &segs, PATH_IRONING, sp);
	clip_paths_free(&solid);
	clip_paths_free(&area);
	clip_paths_free(&segs);
	return rc;
}

/* Classify and fill one layer. */
static int fill_layer(struct ctx *c)
{
	const struct infill_settings *s = c->s;
	struct clip_paths cl[CL_N] = {{0}};
	double a = (s->fill_angle + 90.0 * (double)(c->layer % 2)) * M_PI / 180.0;
	double solid_w = s->solid_infill_extrusion_width, top_w = s->top_infill_extrusion_width;
	/* Bridge flow: a round thread; the bead of equal cross-section. */
	double thread = s->nozzle_diameter * sqrt(s->bridge_flow_ratio);
	double bridge_w = fmax(c->h, c->h + M_PI * (thread * thread - c->h * c->h) / (4.0 * c->h));
	const double U = SLICE_UNITS_PER_MM;
	const struct bead solid = {solid_w * U, perim_spacing(solid_w, c->h) * U, PATH_SOLID_INFILL,
				   true};
	const struct bead bottom = {solid_w * U, solid.sp, PATH_BOTTOM_SKIN, true};
	const struct bead top = {top_w * U, perim_spacing(top_w, c->h) * U, PATH_TOP_SKIN, true};
	const struct bead bridge = {bridge_w * U, (thread + INFILL_BRIDGE_GAP_MM) * U, PATH_BRIDGE,
				    false};
	int rc = 0;

	if (!clip_paths_points(c->R))
		goto out_iron;
	rc = classify(c, cl);
	if (!rc)
		rc = fill_solid(c, &cl[CL_BOTTOM], a, &bottom, NULL);
	if (!rc && s->bridge_angle != 0.0)
		rc = fill_solid(c, &cl[CL_BRIDGE], s->bridge_angle * M_PI / 180.0, &bridge, NULL);
	else if (!rc)
		rc = fill_solid(c, &cl[CL_BRIDGE], 0.0, &bridge,
				&c->st->layers[c->layer - (c->layer > 0)].regions.paths);
	if (!rc)
		rc = fill_solid(c, &cl[CL_SOLID], a, &solid, NULL);
	if (!rc)
		rc = fill_sparse(c, &cl[CL_SPARSE], a);
	if (!rc)
		rc = fill_solid(c, &cl[CL_TOP], a, &top, NULL);
out_iron:
	if (!rc && s->ironing)
		rc = plan_ironing(c, cl, a);
	for (int k = 0; k < CL_N; k++)
		clip_paths_free(&cl[k]);
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
	c = (struct ctx){.s = &job->s,
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
	rc = fill_layer(&c);
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
			rc = order_segments(it, &job->lx, &job->ly, out, err);
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
