/*
 * gcodewritertest.c - the helpers of gcodewritertest.h.
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "estimate.h"
#include "gcode.h"
#include "gcode_writer.h"
#include "gcodewritertest.h"
#include "settings.h"
#include "testutil.h"

/* ---------------------------------------------------------------------------
 * Building layer stacks
 */

/* A stack of n layers of height h (first at Z = h). */
struct layer_stack *stack_new(size_t n, double h)
{
	struct layer_stack *s = layer_stack_new(n, NULL);

	ck_assert_ptr_nonnull(s);
	for (size_t i = 0; i < n; i++) {
		s->layers[i].z = h * (double)(i + 1);
		s->layers[i].height = h;
	}
	return s;
}

/* A closed square of side mm, seam at (x0, y0), bead width w mm. */
void add_square(struct layer_paths *l, enum path_role role, double x0, double y0,
		double side, double w)
{
	struct path_point p[4] = {
	    {llround(x0 * NM), llround(y0 * NM), llround(w * NM)},
	    {llround((x0 + side) * NM), llround(y0 * NM), llround(w * NM)},
	    {llround((x0 + side) * NM), llround((y0 + side) * NM), llround(w * NM)},
	    {llround(x0 * NM), llround((y0 + side) * NM), llround(w * NM)},
	};

	ck_assert_int_eq(layer_add_path(l, role, true, p, 4, NULL), 0);
}

/* An open polyline of n points xy[2n] (mm), widths w[n] (mm). */
void add_line(struct layer_paths *l, enum path_role role, const double *xy,
	      const double *w, size_t n)
{
	struct path_point p[16];

	ck_assert_uint_le(n, 16);
	for (size_t i = 0; i < n; i++)
		p[i] = (struct path_point){llround(xy[2 * i] * NM), llround(xy[2 * i + 1] * NM),
					   llround(w[i] * NM)};
	ck_assert_int_eq(layer_add_path(l, role, false, p, n, NULL), 0);
}

/* Filament (mm) the bead model needs for layer l: independent of the order
 * the writer prints in (segment i -> i+1 has the width of point i). */
double expected_e(const struct layer_paths *l, const struct gcodew_settings *s)
{
	double h = l->height, fil = M_PI * s->filament_diameter * s->filament_diameter / 4, e = 0;

	for (size_t pi = 0; pi < l->n; pi++) {
		const struct toolpath *p = &l->paths[pi];
		size_t segs = p->closed ? p->n : p->n - 1;
		for (size_t k = 0; k < segs; k++) {
			const struct path_point *a = &p->pts[k], *b = &p->pts[(k + 1) % p->n];
			double len = hypot((double)(b->x - a->x), (double)(b->y - a->y)) / NM;
			double w = a->width / NM;
			e += ((w - h) * h + M_PI * (h / 2) * (h / 2)) * len / fil;
		}
	}
	return e * s->extrusion_multiplier;
}

/* Replay text; asserts that every line parses. */
void replay(const char *text, struct replay *r)
{
	double x = 0, y = 0, z = 0, e = 0, f = 0, em = 0;
	int64_t retracted = 0; /* 1e-5 mm units */
	int fan = 0, layer = -1, line_no = 0;
	bool extruded_any = false, in_bridge = false, after_bridge = false;
	const char *p = text;

	r->e_ok = true;
	r->fan_bridge = r->fan_after_bridge = -1;
	for (int i = 0; i < MAXL; i++) {
		r->fmin[i] = r->zmin[i] = INFINITY;
		r->fmax[i] = r->zmax[i] = -INFINITY;
		r->fan_first[i] = -1;
	}
	while (*p) {
		const char *nl = strchr(p, '\n');
		size_t n = nl ? (size_t)(nl - p) : strlen(p);
		struct gcode_line l;
		struct st_error err = {0};
		double v, zv;
		long ln;

		line_no++;
		ck_assert_msg(gcode_parse(p, n, 0, &l, &err) == 0, "line %d \"%.*s\": %s", line_no,
			      (int)n, p, err.msg);
		p += n + (nl ? 1 : 0);
		if (l.letter == 0) {
			enum gcode_layer_mark m = gcode_layer_comment(&l, &ln, &zv);
			if (m == GCODE_LAYER_START) {
				layer = ++r->layers - 1;
				ck_assert_int_lt(layer, MAXL);
			} else if (m == GCODE_LAYER_Z) {
				r->zc[layer] = zv;
			} else if (l.has_comment && strncmp(l.comment, "HEIGHT:", 7) == 0) {
				r->hc[layer] = atof(l.comment + 7);
			} else if (l.has_comment && strncmp(l.comment, "TYPE:", 5) == 0) {
				after_bridge = in_bridge;
				in_bridge = strcmp(l.comment + 5, "Bridge infill") == 0;
			}
			continue;
		}
		if (l.letter == 'M' && l.number == 82)
			r->relative = false;
		if (l.letter == 'M' && l.number == 83)
			r->relative = true;
		if (l.letter == 'M' && l.number == 106)
			fan = gcode_word_value(&l, 'S', &v) ? (int)v : 255;
		if (l.letter == 'M' && l.number == 107)
			fan = 0;
		if (l.letter == 'G' && l.number == 92 && gcode_word_value(&l, 'E', &v))
			e = v;
		if (l.letter != 'G' || (l.number != 0 && l.number != 1))
			continue;
		if (layer >= 0)
			r->g1_lines++;
		double nx = x, ny = y, nz = z, ne = e, de, dxy;
		gcode_word_value(&l, 'X', &nx);
		gcode_word_value(&l, 'Y', &ny);
		gcode_word_value(&l, 'Z', &nz);
		gcode_word_value(&l, 'F', &f);
		if (gcode_word_value(&l, 'E', &v))
			ne = r->relative ? e + v : v;
		de = ne - e;
		dxy = hypot(nx - x, ny - y);
		int64_t du = llround(de * 1e5);
		if (du < 0) {
			retracted -= du;
			r->retracts++;
			if (dxy > 0)
				r->wipes++;
		} else if (du > 0 && dxy == 0) {
			r->unretracts++;
			if (du != retracted && r->e_ok) {
				r->e_ok = false;
				snprintf(r->why, sizeof(r->why),
					 "line %d: unretract of %lld units, %lld retracted", line_no,
					 (long long)du, (long long)retracted);
			}
			retracted = 0;
		} else if (du > 0) {
			if (retracted && r->e_ok) {
				r->e_ok = false;
				snprintf(r->why, sizeof(r->why), "line %d: extrusion while retracted",
					 line_no);
			}
			ck_assert_int_ge(layer, 0);
			extruded_any = true;
			r->e[layer] += de;
			r->fmin[layer] = fmin(r->fmin[layer], f);
			r->fmax[layer] = fmax(r->fmax[layer], f);
			r->zmin[layer] = fmin(r->zmin[layer], nz);
			r->zmax[layer] = fmax(r->zmax[layer], nz);
			if (r->fan_first[layer] < 0)
				r->fan_first[layer] = fan;
			if (in_bridge && r->fan_bridge < 0)
				r->fan_bridge = fan;
			if (after_bridge && !in_bridge && r->fan_after_bridge < 0)
				r->fan_after_bridge = fan;
		} else if (dxy > 0 && extruded_any) {
			bool is_long = dxy > r->retract_before_travel;
			if (retracted)
				is_long ? r->long_wet++ : r->short_wet++;
			else
				is_long ? r->long_dry++ : r->short_dry++;
			if (layer >= 0)
				r->travel_dz_max = fmax(r->travel_dz_max, nz - r->zc[layer]);
		}
		x = nx, y = ny, z = nz, e = ne, em += de;
		if (r->nmoves == r->capmoves) {
			r->capmoves = r->capmoves ? 2 * r->capmoves : 1024;
			r->moves = realloc(r->moves, r->capmoves * sizeof(*r->moves));
			ck_assert_ptr_nonnull(r->moves);
		}
		r->moves[r->nmoves++] = (struct est_move){x, y, z, em, f / 60};
	}
}

/* Write the stack, replay it into *r (zeroed first) and check that E only
 * runs backwards in retractions that are exactly undone.  Returns the text. */
char *write_replay(const struct layer_stack *st, const struct gcodew_settings *s,
		   struct gcodew_summary *sum, struct replay *r)
{
	char *g = tu_gcode_mem(st, s, sum);

	memset(r, 0, sizeof(*r));
	r->retract_before_travel = s->retract_before_travel;
	replay(g, r);
	ck_assert_msg(r->e_ok, "%s", r->why);
	return g;
}

/* G1 lines of text before the first occurrence of mark (asserted present). */
size_t g1_before(const char *text, const char *mark)
{
	const char *end = strstr(text, mark);
	size_t n = 0;

	ck_assert_msg(end != NULL, "\"%s\" not in the output", mark);
	for (const char *p = text; p < end; p = strchr(p, '\n') + 1)
		if (strncmp(p, "G1 ", 3) == 0)
			n++;
	return n;
}

/* Count occurrences of needle in text. */
int count(const char *text, const char *needle)
{
	int n = 0;

	for (const char *p = text; (p = strstr(p, needle)); p += strlen(needle))
		n++;
	return n;
}

/* Offset of needle in text (asserted present). */
long at(const char *text, const char *needle)
{
	const char *p = strstr(text, needle);

	ck_assert_msg(p != NULL, "\"%s\" not in the output", needle);
	return (long)(p - text);
}

/* Offset of the k-th (from 1) occurrence of needle. */
long nth(const char *text, const char *needle, int k)
{
	const char *p = text;

	for (int i = 0; i < k; i++) {
		p = strstr(i ? p + 1 : p, needle);
		ck_assert_msg(p != NULL, "\"%s\" occurs fewer than %d times", needle, k);
	}
	return (long)(p - text);
}

/* Planner time of the replayed moves [a, b), from rest at move a-1. */
double moves_time(const struct replay *r, const struct gcodew_settings *s, size_t a,
		  size_t b)
{
	struct est_result res;
	double start[EST_AXES] = {0, 0, 0, 0};

	if (a > 0) {
		start[EST_X] = r->moves[a - 1].x;
		start[EST_Y] = r->moves[a - 1].y;
		start[EST_Z] = r->moves[a - 1].z;
		start[EST_E] = r->moves[a - 1].e;
	}
	ck_assert_int_eq(est_moves(&s->limits, start, r->moves + a, b - a, &res, NULL), 0);
	return res.time_s;
}
