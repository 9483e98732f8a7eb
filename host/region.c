/*
 * region.c - printed region of a G-code file against the model's
 * cross-sections (region.h): G-code reading and bead sweeping, then the
 * per-layer comparison with a nearest-segment grid for the distances.
 */
#include "region.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gcwalk.h"
#include "seg_grid.h"
#include "section.h"
#include "st_grow.h"
#include "toolpath.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define NM SLICE_UNITS_PER_MM
/* Layers whose Z differ by less than this are one layer, mm. */
#define REGION_Z_EPS 1e-4
/* Bead widths are rounded to this before grouping, nm (1 um). */
#define REGION_WIDTH_QUANTUM 1000.0
/* Open contour ends joined when cutting the model, mm (section.h default). */
#define REGION_CLOSE_GAP 0.05

/* One extruding move of the part, mm; de in mm of filament. */
struct bead {
	double x0, y0, x1, y1, z, de;
	size_t layer;
};

struct bead_vec {
	size_t n, cap;
	struct bead *v;
};

static int area_mm2(const struct clip_paths *ps, double *a, struct st_error *err);

void region_opts_init(struct region_opts *o)
{
	o->filament_diameter = 0.0;
	o->arc_tolerance = 0.001;
	o->sample_step = 0.01;
	o->has_center = false;
	o->center_x = 0.0;
	o->center_y = 0.0;
}

double region_bead_width(double area, double h)
{
	if (!(area > 0.0) || !(h > 0.0))
		return 0.0;
	/* Narrower than high: a round bead is the flow model's limit. */
	if (area < M_PI * h * h / 4.0)
		return sqrt(4.0 * area / M_PI);
	return area / h + h * (1.0 - M_PI / 4.0);
}

/* ---- reading ---- */

/* Feature types that are not the part (both slicers' ;TYPE: names). */
static bool type_skipped(const char *t)
{
	static const char *const skip[] = {"Skirt", "Brim", "Support material", "Wipe tower",
					   "Custom"};
	for (size_t i = 0; i < sizeof(skip) / sizeof(skip[0]); i++)
		if (!strncmp(t, skip[i], strlen(skip[i])))
			return true;
	return false;
}

/* Read every move of fp into beads; fills p's counts and diameter. */
static int read_beads(FILE *fp, const char *name, struct bead_vec *beads, struct region_print *p,
		      struct st_error *err)
{
	struct gcwalk *w;
	struct gcwalk_move m;
	int rc = gcwalk_new(fp, name, &w, err);

	if (rc)
		return rc;
	while ((rc = gcwalk_next(w, &m, err)) == 1) {
		if (!(m.de > 0.0) || (m.to[0] == m.from[0] && m.to[1] == m.from[1]))
			continue;
		/* Moves before the first ;TYPE: are start G-code and prime lines. */
		if (!*m.type || type_skipped(m.type)) {
			p->skipped++;
			continue;
		}
		if (st_grow_at((void **)&beads->v, &beads->cap, beads->n + 1, sizeof(*beads->v))) {
			rc = st_error_set(err, ST_ERR_NOMEM, "%s: out of memory", name);
			break;
		}
		beads->v[beads->n++] =
			(struct bead){m.from[0], m.from[1], m.to[0], m.to[1], m.to[2], m.de, 0};
	}
	p->filament_diameter = gcwalk_filament_diameter(w);
	gcwalk_free(w);
	return rc < 0 ? rc : 0;
}

static int cmp_double(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

/* Sorted distinct layer Zs of the beads into zs (n returned); beads get their layer. */
static size_t assign_layers(struct bead_vec *beads, double *zs)
{
	size_t n = 0;

	for (size_t i = 0; i < beads->n; i++)
		zs[i] = beads->v[i].z;
	qsort(zs, beads->n, sizeof(*zs), cmp_double);
	for (size_t i = 0; i < beads->n; i++)
		if (!n || zs[i] - zs[n - 1] > REGION_Z_EPS)
			zs[n++] = zs[i];
	for (size_t i = 0; i < beads->n; i++) {
		size_t lo = 0, hi = n - 1;
		while (lo < hi) {
			size_t mid = (lo + hi + 1) / 2;
			if (zs[mid] <= beads->v[i].z + REGION_Z_EPS / 2)
				lo = mid;
			else
				hi = mid - 1;
		}
		beads->v[i].layer = lo;
	}
	return n;
}

/* Bead width of b in nm, quantised, on a layer h mm high. */
static double bead_width_nm(const struct bead *b, double h, double fil_area)
{
	double len = hypot(b->x1 - b->x0, b->y1 - b->y0);
	double w = region_bead_width(b->de * fil_area / len, h);
	return fmax(REGION_WIDTH_QUANTUM, round(w * NM / REGION_WIDTH_QUANTUM) * REGION_WIDTH_QUANTUM);
}

/*
 * Add to l->runs_mm2 the swept area of lines[from..) (one continuous run of
 * extrusion, its pieces of different widths united, so they do not count
 * as overlapping one another).
 */
static int add_run(const struct clip_paths *lines, const double *delta, size_t from,
		   double tol_nm, struct region_layer *l, struct st_error *err)
{
	struct clip_paths run = {0}, swept = {0};
	double a = 0;
	int rc = 0;

	for (size_t i = from; i < lines->n && !rc; i++)
		rc = clip_paths_add(&run, clip_path_xy(lines, i), clip_path_len(lines, i), err);
	if (!rc && run.n)
		rc = clip_sweep(&run, delta + from, tol_nm, &swept, err);
	if (!rc && run.n)
		rc = area_mm2(&swept, &a, err);
	l->runs_mm2 += a;
	clip_paths_free(&run);
	clip_paths_free(&swept);
	return rc;
}

/*
 * Sweep the beads of one layer (indices idx[0..n), print order) into
 * l->printed, and each continuous run alone into l->runs_mm2.
 */
static int sweep_layer(const struct bead_vec *beads, const size_t *idx, size_t n,
		       struct region_layer *l, double fil_area, double tol_nm,
		       struct region_print *p, struct st_error *err)
{
	struct clip_paths lines = {0};
	double *delta = NULL;
	int64_t *pts = NULL;
	size_t cap_delta = 0, cap_pts = 0, npts = 0, run_from = 0;
	double cur_w = 0.0;
	int rc = 0;

	for (size_t k = 0; k <= n; k++) {
		const struct bead *b = k < n ? &beads->v[idx[k]] : NULL;
		double w = b ? bead_width_nm(b, l->height, fil_area) : 0.0;
		int64_t x0 = 0, y0 = 0;
		if (b) {
			x0 = llround(b->x0 * NM);
			y0 = llround(b->y0 * NM);
			p->width_min = fmin(p->width_min, w / NM);
			p->width_max = fmax(p->width_max, w / NM);
		}
		/* A polyline goes on while beads join end to start at one width;
		 * a run, while they join at any width. */
		bool touches = b && npts && pts[2 * npts - 2] == x0 && pts[2 * npts - 1] == y0;
		bool joins = touches && w == cur_w;
		if (!joins && npts) {
			if (st_grow_at((void **)&delta, &cap_delta, lines.n + 1, sizeof(*delta)))
				goto out_nomem;
			if ((rc = clip_paths_add(&lines, pts, npts, err)))
				goto out;
			delta[lines.n - 1] = cur_w / 2.0;
			npts = 0;
			if (touches) { /* the run goes on at another width */
				pts[0] = x0;
				pts[1] = y0;
				npts = 1;
			} else {
				if ((rc = add_run(&lines, delta, run_from, tol_nm, l, err)))
					goto out;
				run_from = lines.n;
			}
		}
		if (!b)
			break;
		if (st_grow_at((void **)&pts, &cap_pts, 2 * (npts + 2), sizeof(*pts)))
			goto out_nomem;
		if (!npts) {
			pts[0] = x0;
			pts[1] = y0;
			npts = 1;
		}
		pts[2 * npts] = llround(b->x1 * NM);
		pts[2 * npts + 1] = llround(b->y1 * NM);
		npts++;
		cur_w = w;
	}
	rc = clip_sweep(&lines, delta, tol_nm, &l->printed, err);
	goto out;
out_nomem:
	rc = st_error_set(err, ST_ERR_NOMEM, "region: out of memory sweeping beads");
out:
	clip_paths_free(&lines);
	free(delta);
	free(pts);
	return rc;
}

/* Layers, bead grouping and sweeping, once every bead is read. */
static int build_layers(struct bead_vec *beads, const struct region_opts *o,
			struct region_print *p, struct st_error *err)
{
	double fil_area = M_PI * p->filament_diameter * p->filament_diameter / 4.0;
	double *zs = malloc(beads->n * sizeof(*zs));
	size_t *idx = malloc(beads->n * sizeof(*idx)), *first = NULL;
	int rc = 0;

	if (!zs || !idx)
		goto out_nomem;
	p->n = assign_layers(beads, zs);
	p->layers = calloc(p->n, sizeof(*p->layers));
	first = calloc(p->n + 1, sizeof(*first));
	if (!p->layers || !first)
		goto out_nomem;
	/* Counting sort by layer, file order kept within a layer. */
	for (size_t i = 0; i < beads->n; i++)
		first[beads->v[i].layer + 1]++;
	for (size_t i = 0; i < p->n; i++)
		first[i + 1] += first[i];
	for (size_t i = 0; i < beads->n; i++)
		idx[first[beads->v[i].layer]++] = i;
	for (size_t i = p->n; i > 0; i--)
		first[i] = first[i - 1];
	first[0] = 0;
	p->width_min = INFINITY;
	p->width_max = 0.0;
	p->min[0] = p->min[1] = INFINITY;
	p->max[0] = p->max[1] = -INFINITY;
	for (size_t i = 0; i < p->n; i++) {
		struct region_layer *l = &p->layers[i];
		l->z = zs[i];
		l->height = i ? zs[i] - zs[i - 1] : zs[i];
		if (!(l->height > 0.0)) {
			rc = st_error_set(err, ST_ERR_RANGE,
					  "region: the part is extruded at Z %g mm, not above the bed",
					  l->z);
			goto out;
		}
		l->beads = first[i + 1] - first[i];
		rc = sweep_layer(beads, idx + first[i], l->beads, l, fil_area,
				 o->arc_tolerance * NM, p, err);
		if (rc)
			goto out;
		const struct clip_paths *pr = &l->printed;
		for (size_t k = 0; k < clip_paths_points(pr); k++) {
			for (int a = 0; a < 2; a++) {
				double c = pr->xy[2 * k + a] / NM;
				p->min[a] = fmin(p->min[a], c);
				p->max[a] = fmax(p->max[a], c);
			}
		}
	}
	goto out;
out_nomem:
	rc = st_error_set(err, ST_ERR_NOMEM, "region: out of memory grouping %zu beads", beads->n);
out:
	free(zs);
	free(idx);
	free(first);
	return rc;
}

int region_read(const char *path, const struct region_opts *o, struct region_print **out,
		struct st_error *err)
{
	struct region_opts defaults;
	struct bead_vec beads = {0};
	struct region_print *p;
	FILE *fp;
	int rc;

	if (out)
		*out = NULL;
	if (!path || !out)
		return st_error_set(err, ST_ERR_ARG, "region: region_read needs a path and out");
	if (!o) {
		region_opts_init(&defaults);
		o = &defaults;
	}
	if (!(o->arc_tolerance > 0.0) || !(o->filament_diameter >= 0.0))
		return st_error_set(err, ST_ERR_ARG,
				    "region: arc tolerance must be > 0 and filament diameter >= 0 mm");
	p = calloc(1, sizeof(*p));
	if (!p)
		return st_error_set(err, ST_ERR_NOMEM, "region: out of memory");
	fp = fopen(path, "rb");
	if (!fp) {
		free(p);
		return st_error_set(err, ST_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
	}
	rc = read_beads(fp, path, &beads, p, err);
	fclose(fp);
	if (rc)
		goto out_free;
	if (o->filament_diameter > 0.0)
		p->filament_diameter = o->filament_diameter;
	if (p->filament_diameter == 0.0) {
		rc = st_error_set(err, ST_ERR_PARSE,
				  "%s: no '; filament_diameter = ' comment; give the diameter", path);
		goto out_free;
	}
	if (!beads.n) {
		rc = st_error_set(err, ST_ERR_RANGE,
				  "%s: nothing of the part is extruded (%zu moves of skirt, support "
				  "or custom G-code)",
				  path, p->skipped);
		goto out_free;
	}
	p->beads = beads.n;
	rc = build_layers(&beads, o, p, err);
	if (rc)
		goto out_free;
	free(beads.v);
	*out = p;
	return 0;
out_free:
	free(beads.v);
	region_print_free(p);
	return rc;
}

void region_print_free(struct region_print *p)
{
	if (!p)
		return;
	for (size_t i = 0; i < p->n; i++)
		clip_paths_free(&p->layers[i].printed);
	free(p->layers);
	free(p);
}

/* ---- comparing ---- */

struct samples {
	size_t n, cap;
	double *v; /* mm */
};

static int samples_push(struct samples *s, double d)
{
	if (st_grow_at((void **)&s->v, &s->cap, s->n + 1, sizeof(*s->v)))
		return ST_ERR_NOMEM;
	s->v[s->n++] = d;
	return 0;
}

/* What one direction of the distance measurement adds to the report. */
struct dir_stats {
	struct samples *all, *mine;
	double layer_max;
	double outside, inside; /* only with a sign grid */
};

/*
 * Sample the boundary of from every step nm and measure each point's
 * distance to to's segments; with sign set, points inside sign's region
 * count as inside (negative), others as outside.
 */
static int measure(const struct clip_paths *from, const struct seg_grid *to,
		   const struct seg_grid *sign, double step, struct dir_stats *st)
{
	for (size_t i = 0; i < from->n; i++) {
		size_t m = clip_path_len(from, i);
		const int64_t *xy = clip_path_xy(from, i);
		for (size_t j = 0; j < m; j++) {
			size_t q = (j + 1) % m;
			double ax = (double)xy[2 * j], ay = (double)xy[2 * j + 1];
			double bx = (double)xy[2 * q], by = (double)xy[2 * q + 1];
			double len = hypot(bx - ax, by - ay);
			size_t ns = (size_t)ceil(len / step);
			for (size_t k = 0; k < ns; k++) {
				double t = (double)k / (double)ns;
				double px = ax + t * (bx - ax), py = ay + t * (by - ay);
				double d = seg_grid_dist(to, px, py) / NM;
				if (samples_push(st->all, d) || samples_push(st->mine, d))
					return ST_ERR_NOMEM;
				st->layer_max = fmax(st->layer_max, d);
				if (sign) {
					if (seg_grid_inside(sign, px, py))
						st->inside = fmax(st->inside, d);
					else
						st->outside = fmax(st->outside, d);
				}
			}
		}
	}
	return 0;
}

/* 95th percentile of s (sorted in place); 0 when empty. */
static double p95(struct samples *s)
{
	if (!s->n)
		return 0.0;
	qsort(s->v, s->n, sizeof(*s->v), cmp_double);
	size_t k = (size_t)ceil(0.95 * (double)s->n);
	return s->v[k ? k - 1 : 0];
}

/* Net area of ps, mm^2. */
static int area_mm2(const struct clip_paths *ps, double *a, struct st_error *err)
{
	int rc = clip_paths_area(ps, a, err);
	*a /= NM * NM;
	return rc;
}

/*
 * The envelope of one printed layer: the printed region with the holes
 * that lie mostly inside the section filled (interior voids).
 */
static int envelope(const struct clip_paths *printed, const struct clip_paths *sec,
		    struct clip_paths *env, struct st_error *err)
{
	struct clip_expolys ex = {0};
	struct clip_paths hole = {0}, cut = {0};
	int rc = clip_boolean_ex(CLIP_UNION, printed, NULL, CLIP_NONZERO, &ex, err);

	clip_paths_clear(env);
	for (size_t e = 0; !rc && e < ex.n; e++) {
		for (size_t k = ex.first[e]; !rc && k < ex.first[e + 1]; k++) {
			const int64_t *xy = clip_path_xy(&ex.paths, k);
			size_t m = clip_path_len(&ex.paths, k);
			if (k > ex.first[e]) {
				double ha, ca;
				clip_paths_clear(&hole);
				if ((rc = clip_paths_add(&hole, xy, m, err)) ||
				    (rc = clip_boolean(CLIP_INTERSECTION, &hole, sec, CLIP_NONZERO,
						       &cut, err)) ||
				    (rc = clip_area(xy, m, &ha, err)) ||
				    (rc = clip_paths_area(&cut, &ca, err)))
					break;
				if (ca > 0.5 * fabs(ha))
					continue; /* a void inside the part: filled */
			}
			rc = clip_paths_add(env, xy, m, err);
		}
	}
	clip_expolys_free(&ex);
	clip_paths_free(&hole);
	clip_paths_free(&cut);
	return rc;
}

int region_section(const struct mesh *m, double zm, int64_t dx, int64_t dy,
		   struct clip_paths *sec, struct st_error *err)
{
	struct clip_paths loops = {0};
	int rc = slice_plane(m, zm, REGION_CLOSE_GAP, &loops, NULL, err);

	if (!rc) {
		size_t n = clip_paths_points(&loops);
		for (size_t k = 0; k < n; k++) {
			loops.xy[2 * k] += dx;
			loops.xy[2 * k + 1] += dy;
		}
		rc = clip_boolean(CLIP_UNION, &loops, NULL, CLIP_NONZERO, sec, err);
	}
	clip_paths_free(&loops);
	return rc;
}

/* Compare layer i; adds to the sums and sample sets. */
static int compare_layer(const struct mesh *m, const struct region_layer *l, double zmin,
			 const int64_t d[2], double step, struct region_report *r,
			 struct region_layer_result *lr, struct samples s[3],
			 struct st_error *err)
{
	struct clip_paths sec = {0}, env = {0}, x = {0};
	struct seg_grid gs = {0}, ge = {0};
	double printed_mm2 = 0;
	int rc;

	lr->z = l->z;
	lr->height = l->height;
	if ((rc = region_section(m, zmin + l->z - l->height / 2, d[0], d[1], &sec, err)) ||
	    (rc = envelope(&l->printed, &sec, &env, err)) ||
	    (rc = area_mm2(&sec, &lr->section_mm2, err)) ||
	    (rc = area_mm2(&env, &lr->envelope_mm2, err)) ||
	    (rc = clip_boolean(CLIP_XOR, &env, &sec, CLIP_NONZERO, &x, err)) ||
	    (rc = area_mm2(&x, &lr->xor_mm2, err)) ||
	    (rc = clip_boolean(CLIP_XOR, &l->printed, &sec, CLIP_NONZERO, &x, err)) ||
	    (rc = area_mm2(&x, &lr->xor_raw_mm2, err)) ||
	    (rc = clip_boolean(CLIP_DIFFERENCE, &sec, &l->printed, CLIP_NONZERO, &x, err)) ||
	    (rc = area_mm2(&x, &lr->gap_mm2, err)) ||
	    (rc = area_mm2(&l->printed, &printed_mm2, err)))
		goto out;
	lr->overlap_mm2 = fmax(0.0, l->runs_mm2 - printed_mm2);
	if (!sec.n) {
		r->empty_sections++;
		goto out;
	}
	if (seg_grid_build(&gs, &sec) || seg_grid_build(&ge, &env)) {
		rc = st_error_set(err, ST_ERR_NOMEM, "region: out of memory measuring layer %g", l->z);
		goto out;
	}
	struct dir_stats a = {&s[0], &s[1], 0, r->outside_max, r->inside_max};
	struct dir_stats b = {&s[0], &s[2], 0, 0, 0};
	if (measure(&env, &gs, &gs, step * NM, &a) || measure(&sec, &ge, NULL, step * NM, &b)) {
		rc = st_error_set(err, ST_ERR_NOMEM, "region: out of memory measuring layer %g", l->z);
		goto out;
	}
	r->outside_max = a.outside;
	r->inside_max = a.inside;
	lr->dev_max = fmax(a.layer_max, b.layer_max);
out:
	seg_grid_free(&gs);
	seg_grid_free(&ge);
	clip_paths_free(&sec);
	clip_paths_free(&env);
	clip_paths_free(&x);
	return rc;
}

void region_place(const struct mesh *m, const struct region_opts *o, const double pmin[2],
		  const double pmax[2], double offset[3])
{
	double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};

	for (size_t i = 0; i < m->nverts; i++)
		for (int a = 0; a < 3; a++) {
			lo[a] = fmin(lo[a], m->verts[i][a]);
			hi[a] = fmax(hi[a], m->verts[i][a]);
		}
	double cx = o && o->has_center ? o->center_x : (pmin[0] + pmax[0]) / 2;
	double cy = o && o->has_center ? o->center_y : (pmin[1] + pmax[1]) / 2;
	offset[0] = cx - (lo[0] + hi[0]) / 2;
	offset[1] = cy - (lo[1] + hi[1]) / 2;
	offset[2] = -lo[2];
}

int region_compare(const struct mesh *m, const struct region_print *p,
		   const struct region_opts *o, struct region_report **out, struct st_error *err)
{
	struct region_opts defaults;
	struct samples s[3] = {{0}};
	double sec_sum = 0, xor_sum = 0, raw_sum = 0, gap_sum = 0, over_sum = 0;
	struct region_report *r;
	int rc = 0;

	if (out)
		*out = NULL;
	if (!m || !p || !out || !m->nverts || !p->n)
		return st_error_set(err, ST_ERR_ARG, "region: region_compare needs a mesh and a print");
	if (!o) {
		region_opts_init(&defaults);
		o = &defaults;
	}
	if (!(o->sample_step > 0.0))
		return st_error_set(err, ST_ERR_ARG, "region: sample step must be > 0 mm, got %g",
				    o->sample_step);
	r = calloc(1, sizeof(*r));
	if (!r || !(r->per_layer = calloc(p->n, sizeof(*r->per_layer)))) {
		free(r);
		return st_error_set(err, ST_ERR_NOMEM, "region: out of memory");
	}
	region_place(m, o, p->min, p->max, r->offset);
	const int64_t d[2] = {llround(r->offset[0] * NM), llround(r->offset[1] * NM)};
	for (size_t i = 0; i < p->n; i++) {
		struct region_layer_result *lr = &r->per_layer[i];
		rc = compare_layer(m, &p->layers[i], -r->offset[2], d, o->sample_step, r, lr, s, err);
		if (rc)
			goto out;
		sec_sum += lr->section_mm2;
		xor_sum += lr->xor_mm2;
		raw_sum += lr->xor_raw_mm2;
		gap_sum += lr->gap_mm2;
		over_sum += lr->overlap_mm2;
		if (lr->section_mm2 > 0)
			r->layer_area_error_max =
				fmax(r->layer_area_error_max, lr->xor_mm2 / lr->section_mm2);
		r->dev_max = fmax(r->dev_max, lr->dev_max);
	}
	r->layers = p->n;
	r->samples = s[0].n;
	r->area_error = sec_sum > 0 ? xor_sum / sec_sum : INFINITY;
	r->area_error_raw = sec_sum > 0 ? raw_sum / sec_sum : INFINITY;
	r->gap = sec_sum > 0 ? gap_sum / sec_sum : INFINITY;
	r->overlap = sec_sum > 0 ? over_sum / sec_sum : INFINITY;
	r->dev_p95 = p95(&s[0]);
	r->dev_p95_printed = p95(&s[1]);
	r->dev_p95_model = p95(&s[2]);
out:
	for (int k = 0; k < 3; k++)
		free(s[k].v);
	if (rc) {
		region_report_free(r);
		return rc;
	}
	*out = r;
	return 0;
}

void region_report_free(struct region_report *r)
{
	if (!r)
		return;
	free(r->per_layer);
	free(r);
}
