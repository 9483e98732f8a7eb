/*
 * check_gcodewriter.c - slicer/gcode_writer*.c and slicer/estimate.c: the
 * written G-code is parsed back with serial/gcode.h and replayed like a
 * printer would: extruded amounts per layer against the bead model,
 * retractions matched by unretractions, travel retraction and z-hop, layer
 * comments, temperatures, fan, slow-down, placeholders, number format,
 * safe file output; the planner against analytic trapezoids.
 */
#include <check.h>
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "estimate.h"
#include "gcode.h"
#include "gcode_writer.h"
#include "settings.h"
#include "suites.h"
#include "testutil.h"

#define MAXL 64	     /* layers a replay tracks */
#define NM 1000000.0 /* nm per mm */

/* ---------------------------------------------------------------------------
 * Building layer stacks
 */

/* A stack of n layers of height h (first at Z = h). */
static struct layer_stack *stack_new(size_t n, double h)
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
static void add_square(struct layer_paths *l, enum path_role role, double x0, double y0,
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
static void add_line(struct layer_paths *l, enum path_role role, const double *xy,
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
static double expected_e(const struct layer_paths *l, const struct gcodew_settings *s)
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

/* ---------------------------------------------------------------------------
 * Replaying G-code like a printer
 */

struct replay {
	double retract_before_travel; /* in: travels longer than this must retract */
	bool relative;		      /* M83 seen last */
	int layers;		      /* ;LAYER_CHANGE count */
	double zc[MAXL], hc[MAXL];    /* ;Z: and ;HEIGHT: per layer */
	double e[MAXL];		      /* extruded per layer */
	double fmin[MAXL], fmax[MAXL]; /* F of extrusions, mm/min */
	double zmin[MAXL], zmax[MAXL]; /* Z of extrusions */
	int fan_first[MAXL];	       /* fan (0-255) at the layer's first extrusion */
	int fan_bridge;		       /* fan at the first extrusion after ;TYPE:Bridge infill */
	int fan_after_bridge;	       /* fan at the first extrusion of the next type */
	int retracts, unretracts, wipes; /* moves pulling back / restoring / wiping */
	int long_wet, long_dry, short_wet, short_dry; /* travels: retracted or not */
	double travel_dz_max;			      /* highest Z above the layer while travelling */
	int g1_lines; /* G1 lines from the first layer on (the start G-code's are the user's) */
	bool e_ok;
	char why[256];
	struct est_move *moves;
	size_t nmoves, capmoves;
};

/* Replay text; asserts that every line parses. */
static void replay(const char *text, struct replay *r)
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
static char *write_replay(const struct layer_stack *st, const struct gcodew_settings *s,
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
static size_t g1_before(const char *text, const char *mark)
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
static int count(const char *text, const char *needle)
{
	int n = 0;

	for (const char *p = text; (p = strstr(p, needle)); p += strlen(needle))
		n++;
	return n;
}

/* Offset of needle in text (asserted present). */
static long at(const char *text, const char *needle)
{
	const char *p = strstr(text, needle);

	ck_assert_msg(p != NULL, "\"%s\" not in the output", needle);
	return (long)(p - text);
}

/* Offset of the k-th (from 1) occurrence of needle. */
static long nth(const char *text, const char *needle, int k)
{
	const char *p = text;

	for (int i = 0; i < k; i++) {
		p = strstr(i ? p + 1 : p, needle);
		ck_assert_msg(p != NULL, "\"%s\" occurs fewer than %d times", needle, k);
	}
	return (long)(p - text);
}

/* ---------------------------------------------------------------------------
 * Output and flow
 */

/* 10 layers of a 20 mm square loop at 0.2 mm, absolute and relative E. */
START_TEST(test_square_tower)
{
	struct layer_stack *st = stack_new(10, 0.2);
	struct gcodew_settings s;
	struct gcodew_summary sum;
	struct replay r = {0};
	double total = 0;
	char *g;

	for (int i = 0; i < 10; i++)
		add_square(&st->layers[i], PATH_INNER_PERIMETER, 50, 50, 20, 0.45);
	gcodew_settings_init(&s);
	s.use_relative_e_distances = _i == 1;
	g = write_replay(st, &s, &sum, &r);
	ck_assert(r.relative == s.use_relative_e_distances);
	ck_assert_int_eq(r.layers, 10);
	ck_assert_uint_eq(sum.layers, 10);
	ck_assert_uint_eq(sum.moves, (size_t)r.g1_lines);
	for (int i = 0; i < 10; i++) {
		double want = expected_e(&st->layers[i], &s);
		ck_assert_msg(fabs(r.e[i] - want) <= 1e-4 * want, "layer %d: E %.6f, model %.6f", i,
			      r.e[i], want);
		ck_assert_double_eq_tol(r.zc[i], 0.2 * (i + 1), 1e-9);
		ck_assert_double_eq_tol(r.hc[i], 0.2, 1e-9);
		ck_assert_double_eq_tol(r.zmin[i], 0.2 * (i + 1), 1e-9);
		ck_assert_double_eq_tol(r.zmax[i], 0.2 * (i + 1), 1e-9);
		total += want;
	}
	ck_assert_double_eq_tol(sum.filament_mm, total, 1e-6 * total);
	ck_assert_double_eq_tol(sum.filament_cm3, total * M_PI * 1.75 * 1.75 / 4 / 1000, 1e-9);
	ck_assert_double_eq_tol(sum.filament_g, sum.filament_cm3 * 1.24, 1e-9);
	/* Every layer but the first resets E in absolute mode. */
	ck_assert_int_eq(count(g, "G92 E0\n"), s.use_relative_e_distances ? 1 : 10);
	ck_assert_int_eq(count(g, "\n;TYPE:Perimeter\n"), 10);
	free(g);
	free(r.moves);
	layer_stack_free(st);
}
END_TEST

/* A thin wall whose width varies along it: the flow follows the width,
 * whichever end the writer starts from. */
START_TEST(test_thin_wall)
{
	static const double xy[] = {10, 10, 15, 10, 20, 12, 30, 12, 40, 10};
	static const double w[] = {0.3, 0.45, 0.6, 0.35, 0.5};
	struct layer_stack *st = stack_new(4, 0.2);
	struct gcodew_settings s;
	struct replay r = {0};
	char *g;

	for (int i = 0; i < 4; i++)
		add_line(&st->layers[i], PATH_THIN_WALL, xy, w, 5);
	gcodew_settings_init(&s);
	g = write_replay(st, &s, NULL, &r);
	for (int i = 0; i < 4; i++) {
		double want = expected_e(&st->layers[i], &s);
		ck_assert_msg(fabs(r.e[i] - want) <= 1e-4 * want, "layer %d: E %.6f, model %.6f", i,
			      r.e[i], want);
	}
	/* Layer 2 starts at the near end (X40), so it runs backwards. */
	ck_assert_msg(strstr(g, ";LAYER_CHANGE\n;Z:0.4\n"), "no layer 2");
	ck_assert_msg(strstr(strstr(g, ";Z:0.4"), "\nG1 X10 E"), "layer 2 does not end at X10");
	/* A width below the layer height is refused, naming the layer. */
	{
		struct st_error err = {0};
		FILE *fp = fopen("/dev/null", "w");
		st->layers[2].height = 0.32;
		ck_assert_int_eq(gcodew_write_stream(st, &s, fp, NULL, &err), ST_ERR_RANGE);
		ck_assert_msg(strstr(err.msg, "layer 3") && strstr(err.msg, "Thin wall"), "%s",
			      err.msg);
		fclose(fp);
	}
	free(g);
	free(r.moves);
	layer_stack_free(st);
}
END_TEST

/* Two islands: a long travel retracts (and hops), a short one does not. */
START_TEST(test_retraction)
{
	static const double line[] = {0.5, 0.5, 9.5, 0.5};
	static const double lw[] = {0.45, 0.45};
	struct layer_stack *st = stack_new(3, 0.2);
	struct gcodew_settings s;
	struct replay r = {0};
	char *g;

	for (int i = 0; i < 3; i++) {
		add_square(&st->layers[i], PATH_OUTER_PERIMETER, 0, 0, 10, 0.45);
		add_line(&st->layers[i], PATH_SPARSE_INFILL, line, lw, 2);
		add_square(&st->layers[i], PATH_OUTER_PERIMETER, 40, 0, 10, 0.45);
	}
	gcodew_settings_init(&s);
	s.use_relative_e_distances = _i & 1;
	s.wipe = _i & 2;
	s.retract_lift = 0.4;
	g = write_replay(st, &s, NULL, &r);
	/* Per layer: island A -> line (0.7 mm) dry, line -> island B (30.5 mm)
	 * retracted; B -> A of the next layer (40 mm) retracted. */
	ck_assert_int_eq(r.short_dry, 3);
	ck_assert_int_eq(r.short_wet, 0);
	ck_assert_int_eq(r.long_dry, 0);
	ck_assert_int_eq(r.long_wet, 5);
	ck_assert_int_eq(r.unretracts, 5);
	if (s.wipe)
		ck_assert_int_gt(r.wipes, 0);
	else
		ck_assert_int_eq(r.retracts, 6); /* 5 travels + the final one */
	ck_assert_double_eq_tol(r.travel_dz_max, 0.4, 1e-9);
	for (int i = 0; i < 3; i++) {
		ck_assert_double_eq_tol(r.zmin[i], 0.2 * (i + 1), 1e-9);
		ck_assert_double_eq_tol(r.zmax[i], 0.2 * (i + 1), 1e-9);
		ck_assert_double_eq_tol(r.e[i], expected_e(&st->layers[i], &s), 1e-4 * r.e[i]);
	}
	/* The hop goes up after the retraction and down before the unretraction. */
	if (!s.wipe && !s.use_relative_e_distances) {
		long hop = at(g, "G1 Z.6 F720\n"), retract = at(g, " F2400\n");
		ck_assert_int_lt(retract, hop);
		ck_assert_int_lt(hop, at(g + hop, "G1 Z.2 F720\n") + hop);
	}
	free(g);
	free(r.moves);
	layer_stack_free(st);
}
END_TEST

/* Closed sparse infill (concentric loops) keeps the infill stage's order,
 * outermost first, though the inner loop starts nearer the nozzle; open
 * sparse lines still go nearest first. */
START_TEST(test_loops_keep_order)
{
	static const double far[] = {60, 60, 70, 60}, near[] = {31, 31, 39, 31};
	static const double lw[] = {0.45, 0.45};
	struct layer_stack *st = stack_new(1, 0.2);
	struct gcodew_settings s;
	char *g;

	add_square(&st->layers[0], PATH_OUTER_PERIMETER, 30.5, 30.5, 1, 0.45);
	add_square(&st->layers[0], PATH_SPARSE_INFILL, 20, 20, 20, 0.45);
	add_square(&st->layers[0], PATH_SPARSE_INFILL, 29, 29, 2, 0.45);
	add_line(&st->layers[0], PATH_SOLID_INFILL, far, lw, 2);
	add_line(&st->layers[0], PATH_SOLID_INFILL, near, lw, 2);
	gcodew_settings_init(&s);
	g = tu_gcode_mem(st, &s, NULL);
	ck_assert_int_lt(at(g, "X20 Y20"), at(g, "X29 Y29"));
	ck_assert_int_lt(at(g, "X31 Y31"), at(g, "X60 Y60"));
	free(g);
	layer_stack_free(st);
}
END_TEST

/* Numbers: fixed decimals at most, no exponent, no "-0", F an integer. */
START_TEST(test_number_format)
{
	static const double xy[] = {-0.0001, 5, -0.0004, 15, 3.0000004, 25};
	static const double w[] = {0.45, 0.45, 0.45};
	struct layer_stack *st = stack_new(2, 0.2);
	struct gcodew_settings s;
	char *g;

	for (int i = 0; i < 2; i++)
		add_line(&st->layers[i], PATH_GAP_FILL, xy, w, 3);
	gcodew_settings_init(&s);
	g = tu_gcode_mem(st, &s, NULL);
	ck_assert_ptr_null(strstr(g, "X-0 "));
	ck_assert_ptr_nonnull(strstr(g, "X0 Y5"));
	ck_assert_ptr_nonnull(strstr(g, "X3 Y25"));
	for (const char *p = strstr(g, ";LAYER_CHANGE"); *p; p = strchr(p, '\n') + 1) {
		if (strncmp(p, "G1 ", 3) == 0) {
			const char *end = strchr(p, '\n');
			for (const char *q = p + 3; q < end; q++) {
				char letter = *q++;
				const char *num = q, *dot = NULL;
				while (q < end && *q != ' ') {
					ck_assert_msg(strchr("-0123456789.", *q), "bad number in %.*s",
						      (int)(end - p), p);
					if (*q == '.')
						dot = q;
					q++;
				}
				size_t dec = dot ? (size_t)(q - dot - 1) : 0;
				size_t maxdec = letter == 'E' ? 5 : letter == 'F' ? 0 : 3;
				ck_assert_msg(dec <= maxdec, "%c has %zu decimals: %.*s", letter, dec,
					      (int)(end - p), p);
				ck_assert_msg(!(num[0] == '-' && strspn(num + 1, "0.") == (size_t)(q - num - 1)),
					      "negative zero: %.*s", (int)(end - p), p);
			}
		}
		if (!strchr(p, '\n'))
			break;
	}
	free(g);
	layer_stack_free(st);
}
END_TEST

/* ---------------------------------------------------------------------------
 * Start/end G-code, temperatures, cooling
 */

START_TEST(test_placeholders)
{
	struct layer_stack *st = stack_new(2, 0.2);
	struct gcodew_settings s;
	struct st_error err = {0};
	char *out = NULL, *g;

	gcodew_settings_init(&s);
	s.first_layer_temperature = 215;
	s.temperature = 205;
	s.first_layer_bed_temperature = 60;
	s.bed_temperature = 55;
	s.first_layer_height = 0.25;
	ck_assert_int_eq(gcodew_expand("M117 [first_layer_temperature] {first_layer_bed_temperature[0]} "
				       "[nozzle_diameter] [layer_height] [first_layer_height] "
				       "[temperature] [bed_temperature] "
				       "{ temperature[initial_extruder] } [total_layer_count] [not a key]",
				       "start_gcode", &s, 7, &out, &err),
			 0);
	ck_assert_str_eq(out, "M117 215 60 0.4 0.2 0.25 205 55 205 7 [not a key]");
	free(out);

	ck_assert_int_eq(gcodew_expand("G1 Z[bogus_key]", "start_gcode", &s, 2, &out, &err),
			 ST_ERR_PARSE);
	ck_assert_ptr_null(out);
	ck_assert_msg(strstr(err.msg, "start_gcode") && strstr(err.msg, "[bogus_key]"), "%s", err.msg);
	ck_assert_int_eq(gcodew_expand("M104 S{foo_temp[0]}", "end_gcode", &s, 2, &out, &err),
			 ST_ERR_PARSE);
	ck_assert_msg(strstr(err.msg, "foo_temp"), "%s", err.msg);
	ck_assert_int_eq(gcodew_expand("M104 S{temperature[1]}", "x", &s, 2, &out, &err),
			 ST_ERR_UNSUPPORTED);

	/* PrusaSlicer's legacy [key_N] for per-extruder values: index 0 only. */
	ck_assert_int_eq(gcodew_expand("M104 S[first_layer_temperature_0] Z[nozzle_diameter_0]",
				       "start_gcode", &s, 2, &out, &err),
			 0);
	ck_assert_str_eq(out, "M104 S215 Z0.4");
	free(out);
	ck_assert_int_eq(gcodew_expand("M104 S[first_layer_temperature_1]", "start_gcode", &s, 2,
				       &out, &err),
			 ST_ERR_UNSUPPORTED);
	ck_assert_ptr_null(out);
	ck_assert_msg(strstr(err.msg, "[first_layer_temperature_1]") &&
			      strstr(err.msg, "index 1") &&
			      strstr(err.msg, "[first_layer_temperature_0]"),
		      "%s", err.msg);
	/* Not a vector, or no such key: unknown as before. */
	ck_assert_int_eq(gcodew_expand("G1 Z[layer_height_0]", "x", &s, 2, &out, &err),
			 ST_ERR_PARSE);
	ck_assert_int_eq(gcodew_expand("G1 Z[bogus_0]", "x", &s, 2, &out, &err), ST_ERR_PARSE);
	/* PrusaSlicer's conditions (slicer/placeholder.h; refused before it). */
	ck_assert_int_eq(gcodew_expand("{if layer_height > 0}G28{endif}", "x", &s, 2, &out, &err),
			 0);
	ck_assert_str_eq(out, "G28");
	free(out);
	ck_assert_int_eq(gcodew_expand("M104 {temperature", "x", &s, 2, &out, &err), ST_ERR_PARSE);

	/* In a written file, and refused there with no file left behind. */
	add_square(&st->layers[0], PATH_OUTER_PERIMETER, 0, 0, 10, 0.45);
	add_square(&st->layers[1], PATH_OUTER_PERIMETER, 0, 0, 10, 0.45);
	s.start_gcode = "G28\nM117 nozzle {nozzle_diameter[0]} layer [layer_height]\n";
	s.end_gcode = "M104 S0\nM117 done at [temperature]";
	g = tu_gcode_mem(st, &s, NULL);
	ck_assert_ptr_nonnull(strstr(g, "\nM117 nozzle 0.4 layer 0.2\n"));
	ck_assert_ptr_nonnull(strstr(g, "\nM117 done at 205\n"));
	free(g);
	s.end_gcode = "M104 S0\nM117 [unknown_thing]\n";
	ck_assert_int_eq(gcodew_write_file(st, &s, tu_path("ph.gcode"), NULL, &err), ST_ERR_PARSE);
	ck_assert_msg(strstr(err.msg, "end_gcode") && strstr(err.msg, "unknown_thing"), "%s", err.msg);
	ck_assert(!tu_file_exists(tu_path("ph.gcode")));
	layer_stack_free(st);
}
END_TEST

START_TEST(test_temperatures)
{
	struct layer_stack *st = stack_new(3, 0.2);
	struct gcodew_settings s;
	char *g;

	for (int i = 0; i < 3; i++)
		add_square(&st->layers[i], PATH_OUTER_PERIMETER, 0, 0, 10, 0.45);
	gcodew_settings_init(&s);
	s.first_layer_temperature = 215;
	s.temperature = 205;
	s.first_layer_bed_temperature = 60;
	s.bed_temperature = 55;
	g = tu_gcode_mem(st, &s, NULL);
	/* Default start G-code sets no temperature: waits around it. */
	ck_assert_int_lt(at(g, "\nM190 S60"), at(g, "\nG28"));
	ck_assert_int_lt(at(g, "\nM104 S215"), at(g, "\nG28"));
	ck_assert_int_lt(at(g, "\nG28"), at(g, "\nM109 S215"));
	ck_assert_int_lt(at(g, "\nM109 S215"), at(g, ";LAYER_CHANGE"));
	/* The other temperatures at layer 2, once. */
	ck_assert_int_lt(nth(g, ";LAYER_CHANGE", 2), at(g, "\nM104 S205"));
	ck_assert_int_lt(at(g, "\nM104 S205"), nth(g, ";LAYER_CHANGE", 3));
	ck_assert_int_lt(nth(g, ";LAYER_CHANGE", 2), at(g, "\nM140 S55"));
	ck_assert_int_lt(at(g, "\nM140 S55"), nth(g, ";LAYER_CHANGE", 3));
	ck_assert_int_eq(count(g, "\nM104 S205"), 1);
	ck_assert_int_eq(count(g, "\nM140 "), 1);
	free(g);

	/* A start G-code that heats itself gets no extra waits. */
	s.start_gcode = "M140 S[first_layer_bed_temperature]\nM104 S[first_layer_temperature]\n"
			"G28\nM190 S{first_layer_bed_temperature[0]}\nM109 S[first_layer_temperature]\n";
	g = tu_gcode_mem(st, &s, NULL);
	ck_assert_int_eq(count(g, "\nM109 "), 1);
	ck_assert_int_eq(count(g, "\nM190 "), 1);
	ck_assert_int_eq(count(g, "\nM104 S215"), 1);
	ck_assert_int_lt(at(g, "\nM140 S60\n"), at(g, "\nG28"));
	free(g);
	layer_stack_free(st);
}
END_TEST

/* Fan percent PrusaSlicer's rule gives for layer time t (test's own copy). */
static double want_fan_s(const struct gcodew_settings *s, double t)
{
	double pct = 0;

	if (t < s->slowdown_below_layer_time)
		pct = s->max_fan_speed;
	else if (t < s->fan_below_layer_time) {
		double k = (t - s->slowdown_below_layer_time) /
			   (s->fan_below_layer_time - s->slowdown_below_layer_time);
		pct = k * s->min_fan_speed + (1 - k) * s->max_fan_speed;
	}
	return pct * 255 / 100;
}

/* Planner time of the replayed moves [a, b), from rest at move a-1. */
static double moves_time(const struct replay *r, const struct gcodew_settings *s, size_t a,
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

START_TEST(test_fan)
{
	static const double bridge[] = {20, 20, 40, 20};
	static const double bw[] = {0.45, 0.45};
	struct layer_stack *st = stack_new(5, 0.2);
	struct gcodew_settings s;
	struct replay r = {0};
	char *g;

	/* Layers: tiny, tiny, ~30 s, ~67 s, tiny with a bridge. */
	add_square(&st->layers[0], PATH_INNER_PERIMETER, 0, 0, 10, 0.45);
	add_square(&st->layers[1], PATH_INNER_PERIMETER, 0, 0, 10, 0.45);
	add_square(&st->layers[2], PATH_INNER_PERIMETER, 0, 0, 450, 0.45);
	add_square(&st->layers[3], PATH_INNER_PERIMETER, 0, 0, 1000, 0.45);
	add_square(&st->layers[4], PATH_INNER_PERIMETER, 0, 0, 10, 0.45);
	add_line(&st->layers[4], PATH_BRIDGE, bridge, bw, 2);
	add_square(&st->layers[4], PATH_SOLID_INFILL, 0, 0, 10, 0.45);
	gcodew_settings_init(&s);
	s.disable_fan_first_layers = 1;
	s.bridge_fan_speed = 80;
	s.min_print_speed = 1000; /* no slow-down can happen: fan only */
	s.small_perimeter_speed = s.perimeter_speed; /* the tiny squares' times as planned */
	g = write_replay(st, &s, NULL, &r);
	ck_assert_int_eq(r.fan_first[0], 0);
	ck_assert_int_lt(at(g, "\nM107\n"), at(g, ";LAYER_CHANGE"));
	ck_assert_int_eq(r.fan_first[1], 255);
	/* Layer 3: interpolated by its planned time. */
	{
		double t = moves_time(&r, &s, g1_before(g, ";Z:0.6\n"), g1_before(g, ";Z:0.8\n"));
		double want = want_fan_s(&s, t);
		ck_assert_msg(t > 20 && t < 40, "layer 3 takes %g s", t);
		ck_assert_msg(fabs(r.fan_first[2] - want) <= 1.5, "layer 3 (%.2f s): fan %d, want %.1f",
			      t, r.fan_first[2], want);
	}
	ck_assert_int_eq(r.fan_first[3], 0); /* longer than fan_below_layer_time */
	ck_assert_int_eq(r.fan_first[4], 255);
	ck_assert_int_eq(r.fan_bridge, 204);
	ck_assert_int_eq(r.fan_after_bridge, 255);
	free(g);
	free(r.moves);
	layer_stack_free(st);
}
END_TEST

START_TEST(test_slowdown)
{
	struct layer_stack *st = stack_new(3, 0.2);
	struct gcodew_settings s;
	struct replay r = {0};
	char *g;

	/* Layer 1 plain; layer 2 a 5 mm loop (0.33 s at 60 mm/s); layer 3 a
	 * 100 mm loop (6.7 s). */
	add_square(&st->layers[0], PATH_INNER_PERIMETER, 0, 0, 100, 0.45);
	add_square(&st->layers[1], PATH_INNER_PERIMETER, 0, 0, 5, 0.45);
	add_square(&st->layers[2], PATH_INNER_PERIMETER, 0, 0, 100, 0.45);
	gcodew_settings_init(&s);
	s.first_layer_speed = 0;
	g = write_replay(st, &s, NULL, &r);
	/* 20 mm in 5 s wants 4 mm/s: held at min_print_speed, 10 mm/s. */
	ck_assert_double_eq(r.fmin[1], 600);
	ck_assert_double_eq(r.fmax[1], 600);
	ck_assert_double_eq(r.fmin[2], 3600);
	ck_assert_double_eq(r.fmax[2], 3600);
	free(g);
	free(r.moves);

	/* With a lower floor the layer is stretched to 5 s exactly. */
	s.min_print_speed = 1;
	g = write_replay(st, &s, NULL, &r);
	ck_assert_msg(r.fmin[1] > 60 && r.fmax[1] < 600, "F %g..%g", r.fmin[1], r.fmax[1]);
	{
		double t = moves_time(&r, &s, g1_before(g, ";Z:0.4\n"), g1_before(g, ";Z:0.6\n"));
		ck_assert_msg(fabs(t - 5) < 0.05, "slowed layer takes %g s", t);
	}
	free(g);
	free(r.moves);
	layer_stack_free(st);
}
END_TEST

/* Header: settings used and estimates, which agree with re-estimating the
 * parsed-back file. */
START_TEST(test_header_estimate)
{
	struct layer_stack *st = stack_new(10, 0.2);
	struct gcodew_settings s;
	struct gcodew_summary sum;
	struct replay r = {0};
	char *g, line[128];

	for (int i = 0; i < 10; i++) {
		add_square(&st->layers[i], PATH_OUTER_PERIMETER, 50, 50, 20, 0.45);
		add_square(&st->layers[i], PATH_SPARSE_INFILL, 10, 10, 20, 0.45);
	}
	gcodew_settings_init(&s);
	s.start_gcode = "G28 ; home all axes, nothing else moves\n";
	g = write_replay(st, &s, &sum, &r);
	double t = moves_time(&r, &s, 0, r.nmoves);
	ck_assert_msg(fabs(t - sum.time_s) <= 1e-9 * t, "summary %.9f s, parsed back %.9f s",
		      sum.time_s, t);
	ck_assert_msg(sum.time_s > 10, "%g s", sum.time_s);
	/* The header comes first. */
	ck_assert_int_lt(at(g, "; filament_diameter = 1.75\n"), at(g, "\nG28"));
	ck_assert_ptr_nonnull(strstr(g, "; layer_height = 0.2\n"));
	ck_assert_ptr_nonnull(strstr(g, "; first_layer_height = 0.2\n"));
	ck_assert_ptr_nonnull(strstr(g, "; nozzle_diameter = 0.4\n"));
	ck_assert_ptr_nonnull(strstr(g, "; perimeter_speed = 60\n"));
	ck_assert_ptr_nonnull(strstr(g, "; first_layer_temperature = 200\n"));
	ck_assert_ptr_nonnull(strstr(g, "; extrusion width (External perimeter) = 0.45 mm\n"));
	long secs = lround(sum.time_s);
	if (secs >= 60)
		snprintf(line, sizeof(line), "; estimated printing time = %ldm %lds\n", secs / 60,
			 secs % 60);
	else
		snprintf(line, sizeof(line), "; estimated printing time = %lds\n", secs);
	ck_assert_msg(strstr(g, line), "no \"%s\"", line);
	snprintf(line, sizeof(line), "; filament used [mm] = %.2f", sum.filament_mm);
	ck_assert_msg(strstr(g, line), "no \"%s\"", line);
	ck_assert_ptr_nonnull(strstr(g, "; filament used [cm3] = "));
	ck_assert_ptr_nonnull(strstr(g, "; filament used [g] = "));
	free(g);
	free(r.moves);
	layer_stack_free(st);
}
END_TEST

/* The whole file at path, NUL-terminated (free it); *len its length. */
static char *read_whole(const char *path, size_t *len)
{
	FILE *fp = fopen(path, "rb");
	char *buf;

	ck_assert_ptr_nonnull(fp);
	ck_assert_int_eq(fseek(fp, 0, SEEK_END), 0);
	*len = (size_t)ftell(fp);
	rewind(fp);
	buf = malloc(*len + 1);
	ck_assert_ptr_nonnull(buf);
	ck_assert_uint_eq(fread(buf, 1, *len, fp), *len);
	buf[*len] = '\0';
	fclose(fp);
	return buf;
}

/* Count the temporary files beside path: the writer's ".NAME.XXXXXX". */
static int temporaries_beside(const char *path)
{
	char dir[512], *slash;
	const char *base;
	int n = 0;
	DIR *d;
	struct dirent *de;

	snprintf(dir, sizeof(dir), "%s", path);
	slash = strrchr(dir, '/');
	ck_assert_ptr_nonnull(slash);
	*slash = '\0';
	base = strrchr(path, '/') + 1;
	d = opendir(dir);
	ck_assert_ptr_nonnull(d);
	while ((de = readdir(d)))
		if (de->d_name[0] == '.' && !strncmp(de->d_name + 1, base, strlen(base)) &&
		    de->d_name[strlen(base) + 1] == '.')
			n++;
	closedir(d);
	return n;
}

/*
 * A layer at a time (gcodew_begin_file, gcodew_layer, gcodew_finish_file)
 * writes the very bytes of the whole-stack call; too many or too few layers
 * are refused, and a writer freed unfinished leaves no file behind.
 */
START_TEST(test_layer_at_a_time)
{
	struct layer_stack *st = stack_new(3, 0.2);
	struct gcodew_settings s;
	struct gcodew_summary sum, sum2;
	struct st_error err = {0};
	struct gcodew *w = NULL;
	const char *path = tu_path("layers.gcode"), *path2 = tu_path("never.gcode");
	char *whole, *text;
	size_t len;

	add_square(&st->layers[0], PATH_OUTER_PERIMETER, 0, 0, 10, 0.45);
	add_square(&st->layers[1], PATH_INNER_PERIMETER, 1, 1, 8, 0.45);
	add_square(&st->layers[2], PATH_SPARSE_INFILL, 20, 0, 5, 0.45);
	gcodew_settings_init(&s);
	s.start_gcode = "M117 [total_layer_count] layers\n";
	whole = tu_gcode_mem(st, &s, &sum);

	ck_assert_int_eq(gcodew_begin_file(&s, 3, path, &w, &err), 0);
	ck_assert_int_eq(gcodew_finish_file(w, NULL, &err), ST_ERR_ARG); /* 0 of 3 layers */
	gcodew_free(w);
	ck_assert_int_eq(gcodew_begin_file(&s, 3, path, &w, &err), 0);
	for (size_t i = 0; i < 3; i++)
		ck_assert_int_eq(gcodew_layer(w, &st->layers[i], &err), 0);
	ck_assert_int_eq(gcodew_layer(w, &st->layers[2], &err), ST_ERR_ARG); /* a 4th */
	ck_assert_int_eq(gcodew_finish_file(w, &sum2, &err), 0);
	gcodew_free(w);
	text = read_whole(path, &len);
	ck_assert_str_eq(text, whole);
	ck_assert_uint_eq(sum2.moves, sum.moves);
	ck_assert_double_eq(sum2.time_s, sum.time_s);

	/* Begun, given a layer, freed: neither the file nor a temporary. */
	ck_assert_int_eq(gcodew_begin_file(&s, 3, path2, &w, &err), 0);
	ck_assert_int_eq(gcodew_layer(w, &st->layers[0], &err), 0);
	ck_assert_int_eq(temporaries_beside(path2), 1);
	gcodew_free(w);
	ck_assert(!tu_file_exists(path2));
	ck_assert_int_eq(temporaries_beside(path2), 0);
	free(text);
	free(whole);
	layer_stack_free(st);
}
END_TEST

/* No file, and no temporary, after a failure. */
START_TEST(test_file_output)
{
	struct layer_stack *st = stack_new(2, 0.2);
	struct gcodew_settings s;
	struct gcodew_summary sum;
	struct st_error err = {0};
	const char *path = tu_path("out.gcode");

	add_square(&st->layers[0], PATH_OUTER_PERIMETER, 0, 0, 10, 0.45);
	add_square(&st->layers[1], PATH_OUTER_PERIMETER, 0, 0, 10, 0.45);
	gcodew_settings_init(&s);
	ck_assert_int_eq(gcodew_write_file(st, &s, "/nonexistent-stratum-dir/out.gcode", NULL, &err),
			 ST_ERR_IO);
	ck_assert_msg(strstr(err.msg, "/nonexistent-stratum-dir/out.gcode"), "%s", err.msg);

	/* A write that works, then one that fails half-way: the good file stays. */
	ck_assert_int_eq(gcodew_write_file(st, &s, path, &sum, &err), 0);
	ck_assert(tu_file_exists(path));
	st->layers[1].paths[0].pts[2].width = 1000; /* 1 um < layer height */
	ck_assert_int_eq(gcodew_write_file(st, &s, path, NULL, &err), ST_ERR_RANGE);
	ck_assert(tu_file_exists(path));
	ck_assert_int_eq(temporaries_beside(path), 0);
	/* Bad settings are refused by name. */
	s.retract_speed = 0;
	ck_assert_int_eq(gcodew_write_file(st, &s, path, NULL, &err), ST_ERR_RANGE);
	ck_assert_msg(strstr(err.msg, "retract_speed"), "%s", err.msg);
	layer_stack_free(st);
}
END_TEST

/* ---------------------------------------------------------------------------
 * The planner against analytic profiles
 */

/* Trapezoid time written out for the test: accelerate from vi to vc,
 * cruise, decelerate to vo; a triangle when the distance is too short. */
static double analytic(double d, double vi, double vc, double vo, double a)
{
	double da = (vc * vc - vi * vi) / (2 * a), dd = (vc * vc - vo * vo) / (2 * a);
	if (da + dd <= d)
		return (vc - vi) / a + (d - da - dd) / vc + (vc - vo) / a;
	double vp = sqrt((2 * a * d + vi * vi + vo * vo) / 2);
	return (vp - vi) / a + (vp - vo) / a;
}

/* Limits with one acceleration for every move and generous axes. */
static void plain_limits(struct est_limits *lim, double accel, double jerk_xy)
{
	est_limits_init(lim);
	for (int a = 0; a < EST_AXES; a++) {
		lim->max_feedrate[a] = 1000;
		lim->max_acceleration[a] = 100000;
	}
	lim->accel_extruding = lim->accel_retracting = lim->accel_travel = accel;
	lim->max_jerk[EST_X] = lim->max_jerk[EST_Y] = jerk_xy;
}

static double run_moves(const struct est_limits *lim, const struct est_move *m, size_t n)
{
	struct est_result res;
	struct st_error err = {0};

	ck_assert_msg(est_moves(lim, NULL, m, n, &res, &err) == 0, "%s", err.msg);
	ck_assert_uint_eq(res.moves, n);
	return res.time_s;
}

#define REL_EQ(got, want) \
	ck_assert_msg(fabs((got) - (want)) <= 1e-6 * (want), "%.12f s, analytic %.12f s", (got), (want))

/* The estimator's default limits are the declared machine_max_* defaults
 * (PrusaSlicer's MK3 normal mode), every one of them found. */
START_TEST(test_est_limits_are_declared)
{
	static const char axis[EST_AXES] = {'x', 'y', 'z', 'e'};
	struct est_limits lim;
	struct est_planner *p;
	struct st_error err = {0};
	char name[64];
	double v;

	est_limits_init(&lim);
	for (int a = 0; a < EST_AXES; a++) {
		snprintf(name, sizeof(name), "machine_max_feedrate_%c", axis[a]);
		ck_assert(setting_default_number(name, false, &v));
		ck_assert_double_eq(lim.max_feedrate[a], v);
		snprintf(name, sizeof(name), "machine_max_acceleration_%c", axis[a]);
		ck_assert(setting_default_number(name, false, &v));
		ck_assert_double_eq(lim.max_acceleration[a], v);
		snprintf(name, sizeof(name), "machine_max_jerk_%c", axis[a]);
		ck_assert(setting_default_number(name, false, &v));
		ck_assert_double_eq(lim.max_jerk[a], v);
	}
	ck_assert(setting_default_number("machine_max_acceleration_travel", false, &v));
	ck_assert_double_eq(lim.accel_travel, v);
	ck_assert_double_eq(lim.max_feedrate[EST_Z], 12);
	ck_assert_double_eq(lim.max_acceleration[EST_E], 10000);
	ck_assert_double_eq(lim.max_jerk[EST_E], 2.5);
	ck_assert_double_eq(lim.accel_extruding, 1500);
	ck_assert_double_eq(lim.accel_retracting, 1500);
	p = est_planner_new(&lim, NULL, &err);
	ck_assert_msg(p != NULL, "%s", err.msg);
	est_planner_free(p);
}
END_TEST

START_TEST(test_est_trapezoid)
{
	struct est_limits lim;
	struct est_move one = {100, 0, 0, 0, 100};
	double t;

	plain_limits(&lim, 1000, 0);
	t = run_moves(&lim, &one, 1);
	REL_EQ(t, analytic(100, 0, 100, 0, 1000));
	REL_EQ(t, 1.1); /* 0.1 s up, 0.9 s at 100 mm/s, 0.1 s down */
	/* With jerk the move starts and stops at the jerk speed. */
	plain_limits(&lim, 1000, 10);
	REL_EQ(run_moves(&lim, &one, 1), analytic(100, 10, 100, 10, 1000));
	/* Axis feedrate limit: X capped at 50 mm/s. */
	lim.max_feedrate[EST_X] = 50;
	REL_EQ(run_moves(&lim, &one, 1), analytic(100, 10, 50, 10, 1000));
	/* Axis acceleration limit on a diagonal: a = 300 / cos 45. */
	plain_limits(&lim, 1000, 0);
	lim.max_acceleration[EST_Y] = 300;
	struct est_move diag = {60, 60, 0, 0, 100};
	REL_EQ(run_moves(&lim, &diag, 1), analytic(60 * sqrt(2), 0, 100, 0, 300 * sqrt(2)));
}
END_TEST

START_TEST(test_est_triangle)
{
	struct est_limits lim;
	struct est_move m = {2, 0, 0, 0, 100};
	double t;

	plain_limits(&lim, 1000, 0);
	t = run_moves(&lim, &m, 1);
	/* Peak sqrt(a d) = 44.7 mm/s < 100: up and straight down. */
	REL_EQ(t, 2 * sqrt(2.0 / 1000));
	REL_EQ(t, analytic(2, 0, 100, 0, 1000));
}
END_TEST

START_TEST(test_est_corner)
{
	struct est_limits lim;
	struct est_move corner[2] = {{50, 0, 0, 0, 100}, {50, 50, 0, 0, 100}};
	struct est_move straight[2] = {{50, 0, 0, 0, 100}, {100, 0, 0, 0, 100}};
	struct est_move one = {100, 0, 0, 0, 100};

	/* X jerk allows a full-speed start; the Y jump at the corner does not:
	 * the junction runs at Y's jerk, 10 mm/s. */
	plain_limits(&lim, 1000, 10);
	lim.max_jerk[EST_X] = 100;
	REL_EQ(run_moves(&lim, corner, 2),
	       analytic(50, 100, 100, 10, 1000) + analytic(50, 10, 100, 10, 1000));
	/* The same corner with a generous jerk goes through faster. */
	lim.max_jerk[EST_Y] = 40;
	REL_EQ(run_moves(&lim, corner, 2),
	       analytic(50, 100, 100, 40, 1000) + analytic(50, 40, 100, 40, 1000));
	/* Straight on: no slow-down at the joint. */
	plain_limits(&lim, 1000, 10);
	REL_EQ(run_moves(&lim, straight, 2), run_moves(&lim, &one, 1));
	/* A reversal counts the larger speed, not the sum (Marlin): 100 -> -100
	 * on X with jerk 10 joins at 10 mm/s. */
	struct est_move back[2] = {{50, 0, 0, 0, 100}, {0, 0, 0, 0, 100}};
	REL_EQ(run_moves(&lim, back, 2),
	       analytic(50, 10, 100, 10, 1000) + analytic(50, 10, 100, 10, 1000));
}
END_TEST

/* Many short collinear moves plan like one long one, across the window. */
START_TEST(test_est_window)
{
	struct est_limits lim;
	size_t n = 5 * EST_WINDOW;
	struct est_move *m = calloc(n, sizeof(*m));
	struct est_move one = {0, 0, 0, 0, 100};
	struct est_planner *p;
	struct est_result res;

	ck_assert_ptr_nonnull(m);
	for (size_t i = 0; i < n; i++)
		m[i] = (struct est_move){0.1 * (double)(i + 1), 0, 0, 0.01 * (double)(i + 1), 100};
	one.x = m[n - 1].x;
	one.e = m[n - 1].e;
	plain_limits(&lim, 1000, 10);
	REL_EQ(run_moves(&lim, m, n), run_moves(&lim, &one, 1));
	/* A dwell stops the machine and adds its time. */
	p = est_planner_new(&lim, NULL, NULL);
	ck_assert_ptr_nonnull(p);
	ck_assert_int_eq(est_planner_add(p, &m[0], NULL), 0);
	ck_assert_int_eq(est_planner_dwell(p, 2.5, NULL), 0);
	est_planner_result(p, &res);
	REL_EQ(res.time_s, 2.5 + analytic(0.1, 10, 100, 10, 1000));
	ck_assert_double_eq_tol(res.extruded_mm, 0.01, 1e-12);
	/* Bad input is refused. */
	struct est_move bad = {1, 0, 0, 0, 0};
	struct st_error err = {0};
	ck_assert_int_eq(est_planner_add(p, &bad, &err), ST_ERR_ARG);
	ck_assert_msg(strstr(err.msg, "feedrate"), "%s", err.msg);
	est_planner_free(p);
	lim.max_acceleration[EST_Z] = 0;
	ck_assert_ptr_null(est_planner_new(&lim, NULL, &err));
	ck_assert_msg(strstr(err.msg, "machine_max_acceleration_z"), "%s", err.msg);
	free(m);
}
END_TEST

Suite *gcodewriter_suite(void)
{
	Suite *s = suite_create("gcodewriter");
	TCase *out = tcase_create("output");
	TCase *cool = tcase_create("cooling");
	TCase *est = tcase_create("estimate");

	tcase_add_loop_test(out, test_square_tower, 0, 2);
	tcase_add_test(out, test_thin_wall);
	tcase_add_loop_test(out, test_retraction, 0, 4);
	tcase_add_test(out, test_loops_keep_order);
	tcase_add_test(out, test_number_format);
	tcase_add_test(out, test_placeholders);
	tcase_add_test(out, test_header_estimate);
	tcase_add_test(out, test_file_output);
	tcase_add_test(out, test_layer_at_a_time);
	tcase_add_test(cool, test_temperatures);
	tcase_add_test(cool, test_fan);
	tcase_add_test(cool, test_slowdown);
	tcase_add_test(est, test_est_limits_are_declared);
	tcase_add_test(est, test_est_trapezoid);
	tcase_add_test(est, test_est_triangle);
	tcase_add_test(est, test_est_corner);
	tcase_add_test(est, test_est_window);
	suite_add_tcase(s, out);
	suite_add_tcase(s, cool);
	suite_add_tcase(s, est);
	gcodewriter_simplify_tcases(s);
	gcodewriter_arcfit_tcases(s);
	gcodewriter_progress_tcases(s);
	gcodewriter_retract_tcases(s);
	gcodewriter_accel_tcases(s);
	return s;
}
