/*
 * skirt.c - skirt and brim loops around the first layer (see skirt.h).
 */
#include "skirt.h"

#include <math.h>
#include <stdlib.h>

#include "emit.h"
#include "grow.h"
#include "perimeters.h"
#include "support.h"

/* Loops added for min_skirt_length stop here (a guard against a length
 * that no sane skirt reaches). */
#define SKIRT_MAX_LOOPS 1000

/* Everything one skirt_generate call works with, lengths in nm. */
struct ctx {
	const struct skirt_settings *s;
	double w, sp, arc;
	int64_t lx, ly;	/* where the last loop started */
	bool have_last;
	struct st_error *err;
};

void skirt_settings_init(struct skirt_settings *s, double nozzle_diameter)
{
	s->skirts = 1;
	s->skirt_distance = 6.0;
	s->skirt_height = 1;
	s->min_skirt_length = 0.0;
	s->brim_width = 0.0;
	s->brim_separation = 0.0;
	s->extrusion_width = 1.125 * nozzle_diameter;
	s->filament_diameter = 1.75;
	s->arc_tolerance = 0.002;
}

int skirt_settings_check(const struct skirt_settings *s, struct st_error *err)
{
	if (!s)
		return st_error_set(err, ST_ERR_ARG, "skirt: no settings given");
	if (s->skirts < 0 || s->skirts > SKIRT_MAX_LOOPS)
		return st_error_set(err, ST_ERR_RANGE,
				    "skirt: skirts = %d loops is out of range; use 0 to %d",
				    s->skirts, SKIRT_MAX_LOOPS);
	if (!(s->skirt_distance >= 0.0 && s->skirt_distance <= 1000.0))
		return st_error_set(err, ST_ERR_RANGE,
				    "skirt: skirt_distance = %g mm is out of range; use 0 to 1000 mm",
				    s->skirt_distance);
	if (s->skirt_height < 0 || (s->skirts > 0 && s->skirt_height < 1))
		return st_error_set(err, ST_ERR_RANGE,
				    "skirt: skirt_height = %d layers is out of range; use 1 or more "
				    "(or skirts = 0 for no skirt)",
				    s->skirt_height);
	if (!(s->min_skirt_length >= 0.0 && s->min_skirt_length <= 1e6))
		return st_error_set(err, ST_ERR_RANGE,
				    "skirt: min_skirt_length = %g mm is out of range; use 0 to 1e6 mm",
				    s->min_skirt_length);
	if (!(s->brim_width >= 0.0 && s->brim_width <= 1000.0))
		return st_error_set(err, ST_ERR_RANGE,
				    "skirt: brim_width = %g mm is out of range; use 0 to 1000 mm",
				    s->brim_width);
	if (!(s->brim_separation >= 0.0 && s->brim_separation <= 1000.0))
		return st_error_set(err, ST_ERR_RANGE,
				    "skirt: brim_separation = %g mm is out of range; use 0 to 1000 mm",
				    s->brim_separation);
	if (!(s->extrusion_width > 0.0 && s->extrusion_width <= 20.0))
		return st_error_set(err, ST_ERR_RANGE,
				    "skirt: first-layer extrusion width %g mm is out of range; use "
				    "(0, 20] mm",
				    s->extrusion_width);
	if (!(s->filament_diameter > 0.0 && s->filament_diameter <= 10.0))
		return st_error_set(err, ST_ERR_RANGE,
				    "skirt: filament_diameter = %g mm is out of range; use (0, 10] mm",
				    s->filament_diameter);
	if (!(s->arc_tolerance > 0.0 && s->arc_tolerance <= s->extrusion_width / 4.0))
		return st_error_set(err, ST_ERR_RANGE,
				    "skirt: arc tolerance %g mm is out of range; use (0, %g] mm (a "
				    "quarter of the extrusion width)",
				    s->arc_tolerance, s->extrusion_width / 4.0);
	return 0;
}

/* out = the counter-clockwise (outer) contours of in, holes dropped. */
static int outer_contours(const struct clip_paths *in, struct clip_paths *out,
			  struct st_error *err)
{
	double a;
	int rc = 0;

	clip_paths_clear(out);
	for (size_t i = 0; i < in->n && !rc; i++) {
		rc = clip_area(clip_path_xy(in, i), clip_path_len(in, i), &a, err);
		if (!rc && a > 0.0)
			rc = clip_paths_add(out, clip_path_xy(in, i), clip_path_len(in, i), err);
	}
	return rc;
}

/* out = the union of the outer contours of every region of ex, no holes. */
static int footprint(const struct clip_expolys *ex, struct clip_paths *out, struct st_error *err)
{
	struct clip_paths outer = {0};
	int rc = 0;

	for (size_t i = 0; i < ex->n && !rc; i++) {
		const struct clip_paths *p = &ex->paths;
		size_t k = ex->first[i];
		rc = clip_paths_add(&outer, clip_path_xy(p, k), clip_path_len(p, k), err);
	}
	if (!rc)
		rc = clip_boolean(CLIP_UNION, &outer, NULL, CLIP_NONZERO, out, err);
	if (!rc)
		rc = outer_contours(out, &outer, err);
	clip_paths_clear(out);
	if (!rc)
		rc = clip_paths_append(out, &outer, err);
	clip_paths_free(&outer);
	return rc;
}

/* Index of the point of a closed path nearest the last loop's start. */
static size_t nearest_start(const struct ctx *c, const int64_t *xy, size_t n)
{
	size_t best = 0;
	double bd = INFINITY;

	if (!c->have_last)
		return 0;
	for (size_t i = 0; i < n; i++) {
		double dx = (double)xy[2 * i] - (double)c->lx, dy = (double)xy[2 * i + 1] - (double)c->ly;
		if (dx * dx + dy * dy < bd) {
			bd = dx * dx + dy * dy;
			best = i;
		}
	}
	return best;
}

/* Append every contour of loops (a set of closed loops) to l as role. */
static int emit_loops(struct ctx *c, const struct clip_paths *loops, struct layer_paths *l,
		      enum path_role role)
{
	int rc = 0;

	for (size_t i = 0; i < loops->n && !rc; i++) {
		const int64_t *xy = clip_path_xy(loops, i);
		size_t n = clip_path_len(loops, i), k = nearest_start(c, xy, n);
		rc = slice_emit_xy(l, role, true, xy, n, llround(c->w), k, false, c->err);
		if (!rc && n >= 3) {
			c->lx = xy[2 * k];
			c->ly = xy[2 * k + 1];
			c->have_last = true;
		}
	}
	return rc;
}

/* The outer contours of base grown by d (round joins) into loop. */
static int loop_at(struct ctx *c, const struct clip_paths *base, double d,
		   struct clip_paths *loop)
{
	int rc = clip_offset(base, d, CLIP_JOIN_ROUND, 2.0, c->arc, loop, c->err);
	struct clip_paths outer = {0};

	if (!rc)
		rc = outer_contours(loop, &outer, c->err);
	if (!rc) {
		clip_paths_clear(loop);
		rc = clip_paths_append(loop, &outer, c->err);
	}
	clip_paths_free(&outer);
	return rc;
}

/* Total length of the closed loops of ps, nm. */
static double loops_length(const struct clip_paths *ps)
{
	double len = 0.0;

	for (size_t i = 0; i < ps->n; i++) {
		const int64_t *xy = clip_path_xy(ps, i);
		size_t n = clip_path_len(ps, i);
		for (size_t k = 0; k < n; k++) {
			size_t j = (k + 1) % n;
			len += hypot((double)(xy[2 * j] - xy[2 * k]),
				     (double)(xy[2 * j + 1] - xy[2 * k + 1]));
		}
	}
	return len;
}

/*
 * Concentric loops around base: loop k at d0 + k sp, count of them (more
 * while min_len nm of filament is not reached, when min_len > 0), each
 * appended to every layer of out[0 .. nl) from the outermost inwards.
 */
static int concentric(struct ctx *c, const struct clip_paths *base, double d0, int count,
		      double min_len, struct layer_paths *out, size_t nl, enum path_role role)
{
	struct clip_paths *loops = NULL;
	size_t cap = 0, made = 0;
	double used = 0.0, h = out[0].height * SLICE_UNITS_PER_MM;
	double per_nm = perim_bead_area(c->w, h) /
			(M_PI * pow(c->s->filament_diameter * SLICE_UNITS_PER_MM / 2.0, 2));
	int rc = 0;

	while (!rc && ((int)made < count || (min_len > 0.0 && used < min_len)) &&
	       made < SKIRT_MAX_LOOPS) {
		struct clip_paths *grown = slice_grow(loops, &cap, made + 1, sizeof(*loops));
		if (!grown) {
			rc = st_error_set(c->err, ST_ERR_NOMEM, "skirt: out of memory for loops");
			break;
		}
		loops = grown;
		loops[made] = (struct clip_paths){0};
		rc = loop_at(c, base, d0 + (double)made * c->sp, &loops[made]);
		used += loops_length(&loops[made]) * per_nm;
		made++;
	}
	for (size_t l = 0; l < nl && !rc; l++)
		for (size_t k = made; k-- > 0 && !rc;)
			rc = emit_loops(c, &loops[k], &out[l], role);
	for (size_t k = 0; k < made; k++)
		clip_paths_free(&loops[k]);
	free(loops);
	return rc;
}

int skirt_generate(const struct skirt_settings *s, const struct slice_stack *st,
		   const struct layer_stack *support, struct layer_stack *out,
		   struct st_error *err)
{
	struct clip_paths model = {0}, base = {0}, beads = {0};
	struct ctx c = {.s = s, .err = err};
	int brims = 0, rc = skirt_settings_check(s, err);
	double ext = 0.0;

	if (rc)
		return rc;
	if (!st || !out || out->nlayers != st->n || (support && support->nlayers != st->n))
		return st_error_set(err, ST_ERR_ARG,
				    "skirt: the output and support stacks must have one layer per "
				    "sliced layer");
	if (!st->n || !st->layers[0].regions.n)
		return 0;
	c.w = s->extrusion_width * SLICE_UNITS_PER_MM;
	c.sp = perim_spacing(s->extrusion_width, st->layers[0].height) * SLICE_UNITS_PER_MM;
	c.arc = s->arc_tolerance * SLICE_UNITS_PER_MM;
	if (s->extrusion_width < st->layers[0].height)
		return st_error_set(err, ST_ERR_RANGE,
				    "skirt: first-layer extrusion width %g mm is narrower than the "
				    "%g mm first layer; use at least the layer height",
				    s->extrusion_width, st->layers[0].height);
	rc = footprint(&st->layers[0].regions, &model, err);
	if (s->brim_width > 0.0) {
		brims = (int)ceil(s->brim_width * SLICE_UNITS_PER_MM / c.sp - 1e-9);
		ext = s->brim_separation * SLICE_UNITS_PER_MM + c.w + (brims - 1) * c.sp;
	}
	/* The skirt goes around the part, its brim and the support's first layer. */
	if (!rc)
		rc = clip_offset(&model, ext, CLIP_JOIN_ROUND, 2.0, c.arc, &base, err);
	if (!rc && support)
		rc = support_beads(&support->layers[0], c.arc, &beads, err);
	if (!rc && beads.n)
		rc = clip_boolean(CLIP_UNION, &base, &beads, CLIP_NONZERO, &base, err);
	if (!rc && s->skirts > 0) {
		size_t nl = (size_t)s->skirt_height < st->n ? (size_t)s->skirt_height : st->n;
		rc = concentric(&c, &base, s->skirt_distance * SLICE_UNITS_PER_MM + c.w / 2.0,
				s->skirts, s->min_skirt_length * SLICE_UNITS_PER_MM, out->layers,
				nl, PATH_SKIRT);
	}
	if (!rc && brims > 0)
		rc = concentric(&c, &model, s->brim_separation * SLICE_UNITS_PER_MM + c.w / 2.0,
				brims, 0.0, out->layers, 1, PATH_BRIM);
	clip_paths_free(&model);
	clip_paths_free(&base);
	clip_paths_free(&beads);
	return rc;
}
