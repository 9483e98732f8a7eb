/*
 * check_gcodewriter.c - slicer/gcode_writer*.c and slicer/estimate.c: the
 * written G-code is parsed back with serial/gcode.h and replayed like a
 * printer would: extruded amounts per layer against the bead model,
 * retractions matched by unretractions, travel retraction and z-hop, layer
 * comments, placeholders, number format, the header's estimates, safe file
 * output.  Temperatures, fan and slow-down, and the planner against analytic
 * trapezoids are in check_gcodewriter_cooling.c, the replay in
 * gcodewritertest.c.
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
#include "gcodewritertest.h"
#include "settings.h"
#include "suites.h"
#include "testutil.h"

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

Suite *gcodewriter_suite(void)
{
	Suite *s = suite_create("gcodewriter");
	TCase *out = tcase_create("output");

	tcase_add_loop_test(out, test_square_tower, 0, 2);
	tcase_add_test(out, test_thin_wall);
	tcase_add_loop_test(out, test_retraction, 0, 4);
	tcase_add_test(out, test_loops_keep_order);
	tcase_add_test(out, test_number_format);
	tcase_add_test(out, test_placeholders);
	tcase_add_test(out, test_header_estimate);
	tcase_add_test(out, test_file_output);
	tcase_add_test(out, test_layer_at_a_time);
	suite_add_tcase(s, out);
	gcodewriter_cooling_tcases(s);
	gcodewriter_simplify_tcases(s);
	gcodewriter_arcfit_tcases(s);
	gcodewriter_progress_tcases(s);
	gcodewriter_retract_tcases(s);
	gcodewriter_accel_tcases(s);
	return s;
}
