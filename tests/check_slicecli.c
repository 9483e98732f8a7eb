/*
 * check_slicecli.c - `stratum slice` end to end: the G-code it writes is
 * read back with our own parser (serial/gcode.h) and measured (layers,
 * first-layer Z, where the extrusions lie, filament), the --json summary,
 * and every refusal (model too big, bad settings, unreadable model) with its
 * exit status and no output file.  PrusaSlicer's configs (--load, bundles,
 * --set) are in check_slicecli_config.c.
 */
#include <check.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "fixtures.h"
#include "gcode.h"
#include "meshio.h"
#include "sliceclitest.h"
#include "suites.h"
#include "testutil.h"

#define MK3S_CX 125.0 /* bed centre of printers/prusa-i3-mk3s.ini, mm */
#define MK3S_CY 105.0
#define MK3S_W 0.45 /* its extrusion_width, mm */

static char out[1 << 16];

/* What the G-code of a print says, measured from the layers on. */
struct gstats {
	long layers;		  /* ;LAYER_CHANGE comments */
	double first_z;		  /* the ;Z: of the first layer */
	double first_move_z;	  /* the first G1 Z after it */
	double lo[2], hi[2];	  /* extent of the extrusion moves, mm */
	double extruded;	  /* E of the extrusion moves, mm */
	long extrusions;
};

/* Read path with gcode_reader; fail the test on any line it rejects. */
static void read_gcode(const char *path, struct gstats *g)
{
	FILE *f = fopen(path, "r");
	struct gcode_reader *r = NULL;
	struct gcode_line l;
	struct st_error err = {0};
	double x = 0, y = 0, v;
	bool relative_e = false, in_layers = false, in_skirt = false;
	int rc;

	ck_assert_msg(f != NULL, "cannot open %s", path);
	ck_assert_int_eq(gcode_reader_new(f, path, &r, &err), 0);
	*g = (struct gstats){.first_z = NAN, .first_move_z = NAN, .lo = {INFINITY, INFINITY},
			     .hi = {-INFINITY, -INFINITY}};
	while ((rc = gcode_reader_next(r, 0, &l, &err)) != 0) {
		long layer;
		double z;
		enum gcode_layer_mark mark;

		ck_assert_msg(rc > 0, "our parser rejects the G-code: %s", err.msg);
		mark = gcode_layer_comment(&l, &layer, &z);
		if (mark == GCODE_LAYER_START) {
			g->layers++;
			in_layers = true;
		} else if (mark == GCODE_LAYER_Z && g->layers == 1 && isnan(g->first_z)) {
			g->first_z = z;
		}
		/* The part's extent: the skirt lies skirt_distance outside it. */
		if (!strncmp(l.comment, "TYPE:", 5))
			in_skirt = !strcmp(l.comment + 5, "Skirt/Brim");
		if (l.letter == 'M' && (l.number == 82 || l.number == 83))
			relative_e = l.number == 83;
		if (l.letter != 'G' || (l.number != 0 && l.number != 1))
			continue;
		double nx = x, ny = y, e = 0;
		bool has_e = gcode_word_value(&l, 'E', &e), has_xy = false;

		if (gcode_word_value(&l, 'X', &v))
			nx = v, has_xy = true;
		if (gcode_word_value(&l, 'Y', &v))
			ny = v, has_xy = true;
		if (in_layers && gcode_word_value(&l, 'Z', &v) && isnan(g->first_move_z))
			g->first_move_z = v;
		if (in_layers && has_e && has_xy && e > 0) {
			ck_assert_msg(relative_e, "the MK3S profile prints with relative E");
			if (!in_skirt) {
				g->lo[0] = fmin(g->lo[0], fmin(x, nx));
				g->hi[0] = fmax(g->hi[0], fmax(x, nx));
				g->lo[1] = fmin(g->lo[1], fmin(y, ny));
				g->hi[1] = fmax(g->hi[1], fmax(y, ny));
			}
			g->extruded += e;
			g->extrusions++;
		}
		x = nx;
		y = ny;
	}
	gcode_reader_free(r);
	fclose(f);
}

/* Run `stratum slice ARGS --json` with stdout to a file; the parsed summary. */
static json_t *slice_json(const char *args, int want_status)
{
	const char *jpath = tu_path("summary.json");
	json_error_t jerr;
	json_t *o;
	/* stderr (progress, messages) to out, stdout to the file; tu_run's own
	 * trailing "2>&1" then applies to the exit alone. */
	int status = tu_run(out, sizeof(out), "slice %s --json 2>&1 >'%s' || exit $?", args,
			    jpath);

	ck_assert_msg(status == want_status, "exit %d, wanted %d: %s", status, want_status, out);
	o = json_load_file(jpath, 0, &jerr);
	ck_assert_msg(o != NULL, "not JSON (%s): %s", jerr.text, out);
	return o;
}

static double num(json_t *o, const char *key)
{
	json_t *v = json_object_get(o, key);

	ck_assert_msg(json_is_number(v), "field %s missing or not a number", key);
	return json_number_value(v);
}

START_TEST(cube_gcode_reads_back)
{
	const char *cube = stl_file(fx_box(0, 0, 0, 20, 20, 20), "cube.stl");
	const char *gc = tu_path("cube.gcode");
	struct gstats g;
	int status;

	/* First layer 0.3: layer mid-planes 0.15, then 0.4, 0.6 ... 19.8 -> 99 layers. */
	status = tu_run(out, sizeof(out), "slice '%s' -o '%s' " MK3S " --first-layer-height 0.3",
			cube, gc);
	ck_assert_msg(status == 0, "exit %d: %s", status, out);
	ck_assert_msg(strstr(out, "layers: 99 (first 0.3 mm, then 0.2 mm)"), "%s", out);
	read_gcode(gc, &g);
	ck_assert_int_eq(g.layers, 99);
	ck_assert_double_eq_tol(g.first_z, 0.3, 1e-9);
	ck_assert_double_eq_tol(g.first_move_z, 0.3, 1e-9);
	ck_assert_int_gt(g.extrusions, 99 * 8 - 1); /* two square loops per layer at least */
	/* Centred on the bed ... */
	ck_assert_double_eq_tol((g.lo[0] + g.hi[0]) / 2, MK3S_CX, MK3S_W);
	ck_assert_double_eq_tol((g.lo[1] + g.hi[1]) / 2, MK3S_CY, MK3S_W);
	/* ... with the outer wall's centre line w/2 inside the 20 mm faces. */
	ck_assert_double_eq_tol(g.lo[0], MK3S_CX - 10 + MK3S_W / 2, 2e-3);
	ck_assert_double_eq_tol(g.hi[0], MK3S_CX + 10 - MK3S_W / 2, 2e-3);
	ck_assert_double_eq_tol(g.lo[1], MK3S_CY - 10 + MK3S_W / 2, 2e-3);
	ck_assert_double_eq_tol(g.hi[1], MK3S_CY + 10 - MK3S_W / 2, 2e-3);
}
END_TEST

START_TEST(json_summary_matches_gcode)
{
	const char *cube = stl_file(fx_box(0, 0, 0, 20, 20, 20), "cube.stl");
	const char *gc = tu_path("cube.gcode");
	char args[1024];
	struct gstats g;
	json_t *o, *place, *stages, *paths;

	snprintf(args, sizeof(args), "'%s' -o '%s' " MK3S, cube, gc);
	o = slice_json(args, 0);
	read_gcode(gc, &g);
	ck_assert_int_eq((long)num(o, "layers"), 100);
	ck_assert_int_eq((long)num(o, "raft_layers"), 0);
	ck_assert_int_eq(g.layers, 100);
	ck_assert_double_eq_tol(num(o, "first_layer_height"), 0.2, 1e-12);
	ck_assert_double_eq_tol(g.first_z, 0.2, 1e-9);
	ck_assert_msg(num(o, "time_s") > 60, "a 100-layer cube takes minutes, not %g s",
		      num(o, "time_s"));
	/* The summary's filament is what the extrusion moves push. */
	ck_assert_double_eq_tol(num(o, "filament_mm"), g.extruded, 1e-3 * g.extruded);
	ck_assert_double_eq_tol(num(o, "filament_g"),
				num(o, "filament_cm3") * 1.24, 1e-6 * num(o, "filament_g"));
	ck_assert_str_eq(json_string_value(json_object_get(o, "printer")), "prusa-i3-mk3s");
	ck_assert(json_is_object(json_object_get(o, "repair")));
	place = json_object_get(o, "placement");
	ck_assert_double_eq_tol(json_number_value(json_array_get(json_object_get(place, "min"), 0)),
				MK3S_CX - 10, 1e-9);
	ck_assert_double_eq_tol(json_number_value(json_array_get(json_object_get(place, "max"), 1)),
				MK3S_CY + 10, 1e-9);
	stages = json_object_get(o, "stages");
	ck_assert(json_is_true(json_object_get(stages, "walls")));
	ck_assert(json_is_true(json_object_get(stages, "infill")));
	ck_assert(json_is_true(json_object_get(stages, "skirt")));
	ck_assert(json_is_false(json_object_get(stages, "support"))); /* MK3S: support off */
	paths = json_object_get(o, "paths");
	ck_assert_int_eq(json_integer_value(json_object_get(paths, "outer_perimeter")), 100);
	ck_assert_int_eq(json_integer_value(json_object_get(paths, "inner_perimeter")), 100);
	json_decref(o);
}
END_TEST

/* machine_limits_usage = emit_to_gcode writes PrusaSlicer 2.5's lines (as
 * its --export-gcode wrote them for this config): legacy Marlin's M204 T is
 * the printing acceleration, Marlin 2's the travel one. */
START_TEST(machine_limits_written_as_prusaslicer)
{
	const char *cube = stl_file(fx_box(0, 0, 0, 10, 10, 10), "cube.stl");
	const char *gc = tu_path("cube.gcode");
	static const char *const flavor[] = {"marlin", "marlin2"}, *const t[] = {"T1500", "T1300"};

	for (int k = 0; k < 2; k++) {
		char want[160];
		int status = tu_run(out, sizeof(out),
				    "slice '%s' -o '%s' " MK3S " --set gcode_flavor=%s --set "
				    "machine_limits_usage=emit_to_gcode --set "
				    "machine_max_acceleration_extruding=1500 --set "
				    "machine_max_acceleration_retracting=1100 --set "
				    "machine_max_acceleration_travel=1300",
				    cube, gc, flavor[k]);
		ck_assert_msg(status == 0, "exit %d: %s", status, out);
		size_t len;
		char *text = tu_slurp(gc, &len);
		snprintf(want, sizeof(want),
			 "\nM204 P1500 R1100 %s ; sets acceleration (P, T) and retract "
			 "acceleration (R), mm/sec^2\n",
			 t[k]);
		ck_assert_msg(strstr(text, want), "%s: no %s", flavor[k], want);
		ck_assert_msg(strstr(text, "\nM205 S0 T0 ; sets the minimum extruding"), "no M205 S T");
		free(text);
	}
}
END_TEST

START_TEST(center_option_moves_the_part)
{
	const char *cube = stl_file(fx_box(-3, 7, 5, 17, 27, 25), "cube.stl");
	const char *gc = tu_path("cube.gcode");
	struct gstats g;
	int status = tu_run(out, sizeof(out), "slice '%s' -o '%s' " MK3S " --center 60,50.5", cube,
			    gc);

	ck_assert_msg(status == 0, "exit %d: %s", status, out);
	read_gcode(gc, &g);
	ck_assert_int_eq(g.layers, 100); /* lifted from z = 5 onto the bed */
	ck_assert_double_eq_tol((g.lo[0] + g.hi[0]) / 2, 60, 1e-3);
	ck_assert_double_eq_tol((g.lo[1] + g.hi[1]) / 2, 50.5, 1e-3);
}
END_TEST

START_TEST(thin_plate_prints_thin_walls)
{
	/* 0.6 mm: wider than the nozzle, narrower than two 0.45 mm walls. */
	const char *plate = stl_file(fx_box(0, 0, 0, 30, 0.6, 4), "plate.stl");
	char args[1024];
	json_t *o, *paths;

	snprintf(args, sizeof(args), "'%s' -o '%s' " MK3S, plate, tu_path("plate.gcode"));
	o = slice_json(args, 0);
	paths = json_object_get(o, "paths");
	ck_assert_int_eq((long)num(o, "layers"), 20);
	ck_assert_int_ge(json_integer_value(json_object_get(paths, "thin_wall")), 20);
	ck_assert_int_eq(json_integer_value(json_object_get(paths, "inner_perimeter")), 0);
	json_decref(o);
}
END_TEST

START_TEST(threads_give_the_same_gcode)
{
	/* 25 mm tall: 125 layers, four chunks of walls. */
	const char *ball = stl_file(fx_sphere(0, 0, 0, 12.5, 48, 64), "ball.stl");
	const char *a = tu_path("ball1.gcode"), *b = tu_path("ball2.gcode");
	char cmd[2048];
	int status;

	status = tu_run(out, sizeof(out), "slice '%s' -o '%s' " MK3S " --threads 1", ball, a);
	ck_assert_msg(status == 0, "exit %d: %s", status, out);
	status = tu_run(out, sizeof(out), "slice '%s' -o '%s' " MK3S " --threads 3", ball, b);
	ck_assert_msg(status == 0, "exit %d: %s", status, out);
	snprintf(cmd, sizeof(cmd), "cmp -s '%s' '%s'", a, b);
	ck_assert_msg(system(cmd) == 0, "1 and 3 threads wrote different G-code");
}
END_TEST

START_TEST(no_repair_slices_as_read)
{
	const char *cube = stl_file(fx_box(0, 0, 0, 20, 20, 20), "cube.stl");
	const char *gc = tu_path("cube.gcode");
	char args[1024];
	struct gstats g;
	json_t *o;

	snprintf(args, sizeof(args), "'%s' -o '%s' " MK3S " --no-repair", cube, gc);
	o = slice_json(args, 0);
	ck_assert(json_is_null(json_object_get(o, "repair")));
	ck_assert_int_eq((long)num(o, "layers"), 100);
	read_gcode(gc, &g);
	ck_assert_int_eq(g.layers, 100);
	json_decref(o);
}
END_TEST

/* Filament of slicing m (written as name) with the MK3S profile, mm. */
static double filament_of(struct mesh *m, const char *name)
{
	char args[1024];
	json_t *o;
	double f;

	snprintf(args, sizeof(args), "'%s' -o '%s' " MK3S, stl_file(m, name),
		 tu_path("parts.gcode"));
	o = slice_json(args, 0);
	f = num(o, "filament_mm");
	json_decref(o);
	return f;
}

/*
 * Proves that parts touching along an edge or at a corner slice as the
 * two parts they are: the repaired file holds two 10 mm cubes sharing
 * vertices, and the filament is that of two cubes apart (within 1 %: the
 * walls meet at the shared corner line).  A cube with an inward 4 mm
 * cube inside is sliced with its cavity (walls around it instead of
 * infill there), so its filament differs from the plain cube's.
 */
START_TEST(touching_parts_slice_as_parts)
{
	struct mesh *a = fx_box(0, 0, 0, 10, 10, 10), *apart = fx_box(20, 20, 0, 30, 30, 10);
	struct mesh *edge = fx_box(10, 10, 0, 20, 20, 10), *corner = fx_box(10, 10, 10, 20, 20, 20);
	struct mesh *hole = fx_box(3, 3, 3, 7, 7, 7), *hollow;
	double two, f;

	two = filament_of(fx_concat(a, apart), "parts-apart.stl");
	f = filament_of(fx_concat(a, edge), "parts-edge.stl");
	ck_assert_msg(fabs(f - two) <= 0.01 * two, "edge-touching cubes %g mm, apart %g mm", f,
		      two);
	/* The corner pair is twice as tall: compare with a stacked pair apart. */
	mesh_free(apart);
	apart = fx_box(20, 20, 10, 30, 30, 20);
	two = filament_of(fx_concat(a, apart), "parts-apart2.stl");
	f = filament_of(fx_concat(a, corner), "parts-corner.stl");
	ck_assert_msg(fabs(f - two) <= 0.01 * two, "corner-touching cubes %g mm, apart %g mm", f,
		      two);
	for (size_t t = 0; t < hole->ntris; t++)
		fx_flip(hole, t);
	hollow = fx_concat(a, hole);
	f = filament_of(hollow, "parts-hollow.stl");
	two = filament_of(a, "parts-solid.stl");
	ck_assert_msg(fabs(f - two) > 0.01 * two, "the cavity changed nothing: %g mm vs %g mm", f,
		      two);
	mesh_free(apart);
	mesh_free(edge);
	mesh_free(corner);
	mesh_free(hole);
}
END_TEST

/* Proves that slice refuses to write its G-code over the model (exit 2). */
START_TEST(output_over_the_model_refused)
{
	const char *cube = stl_file(fx_box(0, 0, 0, 10, 10, 10), "own.stl");
	int status = tu_run(out, sizeof(out), "slice '%s' -o '%s' " MK3S, cube, cube);

	ck_assert_msg(status == 2, "exit %d: %s", status, out);
	ck_assert_msg(strstr(out, "is the input file"), "%s", out);
	ck_assert_int_eq(tu_run(out, sizeof(out), "check '%s'", cube), 0);
}
END_TEST

/* Run slice with extra args on model, expect status and a message, and no file. */
static void expect_refused(const char *model, const char *extra, int want, const char *msg)
{
	const char *gc = tu_path("refused.gcode");
	int status = tu_run(out, sizeof(out), "slice '%s' -o '%s' %s", model, gc, extra);

	ck_assert_msg(status == want, "%s: exit %d, wanted %d: %s", extra, status, want, out);
	ck_assert_msg(strstr(out, msg), "%s: message lacks '%s': %s", extra, msg, out);
	ck_assert_msg(!tu_file_exists(gc), "%s: a G-code file was written", extra);
}

START_TEST(flashforge_profile_slices)
{
	const char *cube = stl_file(fx_box(0, 0, 0, 20, 20, 5), "ffcube.stl");
	const char *gc = tu_path("ff.gcode"), *ini = tu_path("ff1.ini");
	static char text[1 << 16], gcode[1 << 20];
	const char *key = "[first_layer_temperature_0]";
	char *at;
	size_t n;
	FILE *f;
	int status;

	/* The shipped profile's start G-code uses [first_layer_temperature_0]. */
	status = tu_run(out, sizeof(out), "slice '%s' -o '%s' --printer flashforge-creator-pro",
			cube, gc);
	ck_assert_msg(status == 0, "exit %d: %s", status, out);
	f = fopen(gc, "r");
	ck_assert_ptr_nonnull(f);
	n = fread(gcode, 1, sizeof(gcode) - 1, f);
	fclose(f);
	gcode[n] = '\0';
	ck_assert_msg(strstr(gcode, "\nM104 S215 T0 ; nozzle to printing temperature\n"),
		      "first-layer temperature not substituted");

	/* The same profile asking for the second extruder is refused. */
	f = fopen("printers/flashforge-creator-pro.ini", "r");
	ck_assert_ptr_nonnull(f);
	n = fread(text, 1, sizeof(text) - 1, f);
	fclose(f);
	text[n] = '\0';
	at = strstr(text, key);
	ck_assert_ptr_nonnull(at);
	at[strlen(key) - 2] = '1';
	tu_write_str(ini, text);
	{
		char extra[512];
		snprintf(extra, sizeof(extra), "--printer '%s'", ini);
		expect_refused(cube, extra, 65, "extruder index 1 is out of range");
	}
}
END_TEST

START_TEST(too_big_for_the_bed_exit_1)
{
	const char *wide = stl_file(fx_box(0, 0, 0, 260, 20, 10), "wide.stl");
	const char *tall = stl_file(fx_box(0, 0, 0, 10, 10, 215), "tall.stl");
	const char *cube = stl_file(fx_box(0, 0, 0, 20, 20, 20), "cube.stl");

	expect_refused(wide, MK3S, 1, "the model is 260.00 x 20.00 mm but the bed is 250.00 x "
				      "210.00 mm (bed_shape)");
	expect_refused(tall, MK3S, 1, "the model is 215.00 mm tall but the printer builds at most "
				      "210.00 mm (max_print_height)");
	/* Fits the bed, but not where --center puts it. */
	expect_refused(cube, MK3S " --center 245,100", 1, "beyond the bed");
}
END_TEST

START_TEST(bad_settings_exit_2)
{
	const char *cube = stl_file(fx_box(0, 0, 0, 20, 20, 20), "cube.stl");

	expect_refused(cube, MK3S " --layer-height 0.5", 2,
		       "layer height 0.5 mm is out of range; it must be > 0 and at most the "
		       "nozzle diameter 0.4 mm");
	expect_refused(cube, MK3S " --first-layer-height 0.45", 2, "first layer height 0.45 mm");
	expect_refused(cube, MK3S " --infill 150", 2, "fill_density = 150% is out of range");
	expect_refused(cube, MK3S " --infill 101%", 2, "fill_density = 101% is out of range");
	expect_refused(cube, MK3S " --perimeters -1", 2, "perimeter count -1 is negative");
	expect_refused(cube, MK3S " --perimeters 1.5", 2, "--perimeters wants a whole number");
	expect_refused(cube, MK3S " --layer-height abc", 2, "--layer-height wants a height in mm");
	expect_refused(cube, MK3S " --center 10", 2, "--center wants X,Y");
	expect_refused(cube, MK3S " --threads 0", 2, "--threads wants a number from 1 to 256");
	expect_refused(cube, "", 2, "no printer given");
	expect_refused(cube, "--printer no-such-printer", 2, "no-such-printer");
	expect_refused(cube, MK3S " --bogus", 2, "unknown option '--bogus'");

	/* A pattern Stratum does not print (3dhoneycomb): the profile slices
	 * with rectilinear and says so in its one warning line (issue 18: a
	 * default PrusaSlicer config, then with stars, was refused here). */
	static const char stars[] = "nozzle_diameter = 0.4\nfill_pattern = 3dhoneycomb\n";
	char model[4096], ini[4096], gc[4096];
	int status;
	snprintf(model, sizeof(model), "%s", stl_file(fx_box(0, 0, 0, 20, 20, 20), "cube.stl"));
	snprintf(ini, sizeof(ini), "%s", tu_path("stars.ini"));
	snprintf(gc, sizeof(gc), "%s", tu_path("stars.gcode"));
	tu_write(ini, stars, sizeof(stars) - 1);
	status = tu_run(out, sizeof(out), "slice '%s' -o '%s' --printer '%s'", model, gc, ini);
	ck_assert_msg(status == 0, "exit %d: %s", status, out);
	ck_assert_msg(strstr(out, "warning: not supported, ignored: fill_pattern=3dhoneycomb "
				  "(rectilinear used)"),
		      "%s", out);
	/* line, concentric and honeycomb are printed: no warning */
	static const char *const printed[] = {"line", "concentric", "honeycomb"};
	for (size_t i = 0; i < 3; i++) {
		char text[128];
		int n = snprintf(text, sizeof(text), "nozzle_diameter = 0.4\nfill_pattern = %s\n",
				 printed[i]);
		tu_write(ini, text, (size_t)n);
		status = tu_run(out, sizeof(out), "slice '%s' -o '%s' --printer '%s'", model, gc, ini);
		ck_assert_msg(status == 0, "%s: exit %d: %s", printed[i], status, out);
		ck_assert_msg(!strstr(out, "fill_pattern"), "%s: %s", printed[i], out);
	}
}
END_TEST

/* The smallest profile slices on the documented defaults (issue 17: the
 * default fill_pattern was "stars", which the slicer refuses). */
START_TEST(minimal_profile_slices)
{
	static const char minimal[] = "nozzle_diameter = 0.4\n";
	const char *cube = stl_file(fx_box(0, 0, 0, 20, 20, 20), "cube.stl");
	const char *ini = tu_path("minimal.ini"), *gc = tu_path("minimal.gcode");
	int status;

	tu_write(ini, minimal, sizeof(minimal) - 1);
	status = tu_run(out, sizeof(out), "slice '%s' -o '%s' --printer '%s'", cube, gc, ini);
	ck_assert_msg(status == 0, "exit %d: %s", status, out);
	ck_assert(tu_file_exists(gc));
}
END_TEST

START_TEST(unreadable_model_exit_65)
{
	const char *bad = tu_path("bad.stl");

	/* A binary STL header announcing 10 facets, and 3 bytes of them. */
	unsigned char buf[87] = {0};
	buf[80] = 10;
	tu_write(bad, buf, sizeof(buf));
	expect_refused(bad, MK3S, 65, "truncated or not an STL file");
	expect_refused(tu_path("missing.stl"), MK3S, 65, "cannot open");
	bad = tu_path("bad.3mf");
	tu_write_3mf(bad, "<model xmlns=\"http://schemas.microsoft.com/3dmanufacturing/core/"
			  "2015/02\"><resources/></model>");
	expect_refused(bad, MK3S, 65, "3D/3dmodel.model has no <build>");
}
END_TEST

/* slice a and b with the MK3S profile; their G-code must be byte for byte the same. */
static void same_gcode(const char *a, const char *b, const char *what)
{
	char ga[512], gb[512], cmd[1200];
	int status;

	snprintf(ga, sizeof(ga), "%s.gcode", a);
	snprintf(gb, sizeof(gb), "%s.gcode", b);
	status = tu_run(out, sizeof(out), "slice '%s' -o '%s' " MK3S, a, ga);
	ck_assert_msg(status == 0, "exit %d: %s", status, out);
	status = tu_run(out, sizeof(out), "slice '%s' -o '%s' " MK3S, b, gb);
	ck_assert_msg(status == 0, "exit %d: %s", status, out);
	snprintf(cmd, sizeof(cmd), "cmp -s '%s' '%s'", ga, gb);
	ck_assert_msg(system(cmd) == 0, "%s: the 3MF and the STL slice differently", what);
}

/* A 3MF slices as the STL of the same triangles: our own, and PrusaSlicer's export. */
START_TEST(slice_3mf_same_as_stl)
{
	struct mesh *ball = fx_sphere(0, 0, 0, 10, 24, 32);
	struct mesh *stl = tu_round_trip(ball, "ball3.stl", MESHIO_STL_BINARY);
	char in[512], own[512], prusa[512], cmd[2048];

	snprintf(in, sizeof(in), "%s", tu_path("ball3.stl"));
	snprintf(own, sizeof(own), "%s", tu_path("ball3.3mf"));
	snprintf(prusa, sizeof(prusa), "%s", tu_path("ball3-prusaslicer.3mf"));
	tu_write_3mf_mesh(own, stl);
	same_gcode(in, own, "hand-built 3MF");
	if (system("command -v prusa-slicer >/dev/null 2>&1") == 0) {
		snprintf(cmd, sizeof(cmd), "timeout 120 prusa-slicer --export-3mf -o '%s' '%s' "
			 ">/dev/null 2>&1", prusa, in);
		ck_assert_msg(system(cmd) == 0, "%s failed", cmd);
		same_gcode(in, prusa, "prusa-slicer --export-3mf");
	} else {
		fprintf(stderr, "slicecli: prusa-slicer not installed, its 3MF export not sliced\n");
	}
	mesh_free(stl);
	mesh_free(ball);
}
END_TEST

Suite *slicecli_suite(void)
{
	Suite *s = suite_create("slicecli");
	TCase *tc = tcase_create("slice");

	tcase_set_timeout(tc, 120);
	tcase_add_test(tc, cube_gcode_reads_back);
	tcase_add_test(tc, json_summary_matches_gcode);
	tcase_add_test(tc, center_option_moves_the_part);
	tcase_add_test(tc, machine_limits_written_as_prusaslicer);
	tcase_add_test(tc, thin_plate_prints_thin_walls);
	tcase_add_test(tc, threads_give_the_same_gcode);
	tcase_add_test(tc, no_repair_slices_as_read);
	tcase_add_test(tc, too_big_for_the_bed_exit_1);
	tcase_add_test(tc, bad_settings_exit_2);
	tcase_add_test(tc, minimal_profile_slices);
	tcase_add_test(tc, unreadable_model_exit_65);
	tcase_add_test(tc, flashforge_profile_slices);
	tcase_add_test(tc, touching_parts_slice_as_parts);
	tcase_add_test(tc, output_over_the_model_refused);
	slicecli_config_tests(tc);
	tcase_add_test(tc, slice_3mf_same_as_stl);
	suite_add_tcase(s, tc);
	slicecli_settings_tcases(s);
	slicecli_widths_tcases(s);
	slicecli_thumbnail_tcases(s);
	return s;
}
