/*
 * check_multimodel.c - several models in one `stratum slice` (issue 18
 * item 7, docs/slicing.md "Several models"): two cubes arranged print as
 * two islands on every layer, duplicate_distance apart, inside one skirt;
 * a model that does not fit with the others is refused by name; 3MF files
 * keep their build placement unless they overlap; one model is placed as
 * it always was.  The G-code is read back with serial/gcode.h.
 */
#include <check.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fixtures.h"
#include "gcode.h"
#include "meshio.h"
#include "suites.h"
#include "testutil.h"

#define MK3S "--printer prusa-i3-mk3s"
#define GAP 6.0	      /* duplicate_distance's default, mm */
#define MAX_BOXES 4
#define PATH_CAP 512

static char out[1 << 16];

/* A footprint on the bed, mm. */
struct box {
	double lo[2], hi[2];
};

/* An fx_box of w x d x h at the origin as the binary STL path. */
static void cube_stl(char *path, const char *name, double w, double d, double h)
{
	struct mesh *m = fx_box(0, 0, 0, w, d, h);
	struct st_error err = {0};

	snprintf(path, PATH_CAP, "%s", tu_path(name));
	ck_assert_msg(meshio_write_stl(path, m, MESHIO_STL_BINARY, &err) == 0, "%s", err.msg);
	mesh_free(m);
}

/* A 3MF scratch file named name with the boxes of cubes (tu_write_3mf_boxes). */
static void cubes_3mf(char *path, const char *name, const double (*cubes)[5], int n)
{
	snprintf(path, PATH_CAP, "%s", tu_path(name));
	tu_write_3mf_boxes(path, cubes, n);
}

/* `stratum slice ARGS --json`, the exit status checked; the summary. */
static json_t *slice_json(const char *args, int want)
{
	char jpath[PATH_CAP];
	json_error_t jerr;
	json_t *o;
	int status;

	snprintf(jpath, sizeof(jpath), "%s", tu_path("multi.json"));
	status = tu_run(out, sizeof(out), "slice %s --json 2>&1 >'%s' || exit $?", args, jpath);
	ck_assert_msg(status == want, "exit %d, wanted %d: %s", status, want, out);
	o = json_load_file(jpath, 0, &jerr);
	ck_assert_msg(o != NULL, "not JSON (%s): %s", jerr.text, out);
	return o;
}

/* Model i's offset from the summary. */
static void model_offset(json_t *o, size_t i, double off[3])
{
	json_t *m = json_array_get(json_object_get(o, "models"), i);
	json_t *v = json_object_get(m, "offset");

	ck_assert_msg(json_array_size(v) == 3, "models[%zu].offset missing", i);
	for (size_t k = 0; k < 3; k++)
		off[k] = json_number_value(json_array_get(v, k));
}

/* The least distance between two boxes along X or Y (negative: overlap). */
static double box_gap(const struct box *a, const struct box *b)
{
	return fmax(fmax(b->lo[0] - a->hi[0], a->lo[0] - b->hi[0]),
		    fmax(b->lo[1] - a->hi[1], a->lo[1] - b->hi[1]));
}

static bool inside(const struct box *b, double x, double y)
{
	return x >= b->lo[0] - 1e-3 && x <= b->hi[0] + 1e-3 && y >= b->lo[1] - 1e-3 &&
	       y <= b->hi[1] + 1e-3;
}

/*
 * Read the G-code at path: every extrusion of the part lies in one of the
 * nb boxes and every box gets extrusions on each of the layers; the skirt's
 * extent goes to *skirt.  Returns the number of layers.
 */
static long check_islands(const char *path, const struct box *b, size_t nb, struct box *skirt)
{
	FILE *f = fopen(path, "r");
	struct gcode_reader *r = NULL;
	struct gcode_line l;
	struct st_error err = {0};
	double x = 0, y = 0, v;
	long layers = 0, count[MAX_BOXES] = {0};
	bool in_skirt = false;
	int rc;

	ck_assert_msg(f != NULL, "cannot open %s", path);
	ck_assert_int_eq(gcode_reader_new(f, path, &r, &err), 0);
	*skirt = (struct box){{INFINITY, INFINITY}, {-INFINITY, -INFINITY}};
	while ((rc = gcode_reader_next(r, 0, &l, &err)) != 0) {
		long layer;
		double z, e = 0, nx = x, ny = y;

		ck_assert_msg(rc > 0, "our parser rejects the G-code: %s", err.msg);
		if (gcode_layer_comment(&l, &layer, &z) == GCODE_LAYER_START) {
			for (size_t i = 0; layers && i < nb; i++)
				ck_assert_msg(count[i] > 0, "layer %ld: no extrusion in island %zu",
					      layers, i);
			memset(count, 0, sizeof(count));
			layers++;
		}
		if (!strncmp(l.comment, "TYPE:", 5))
			in_skirt = !strcmp(l.comment + 5, "Skirt/Brim");
		if (l.letter != 'G' || (l.number != 0 && l.number != 1))
			continue;
		if (gcode_word_value(&l, 'X', &v))
			nx = v;
		if (gcode_word_value(&l, 'Y', &v))
			ny = v;
		if (layers && gcode_word_value(&l, 'E', &e) && e > 0 && (nx != x || ny != y)) {
			if (in_skirt) {
				skirt->lo[0] = fmin(skirt->lo[0], nx), skirt->hi[0] = fmax(skirt->hi[0], nx);
				skirt->lo[1] = fmin(skirt->lo[1], ny), skirt->hi[1] = fmax(skirt->hi[1], ny);
			} else {
				size_t i = 0;
				while (i < nb && !(inside(&b[i], x, y) && inside(&b[i], nx, ny)))
					i++;
				ck_assert_msg(i < nb, "layer %ld: extrusion %.3f,%.3f to %.3f,%.3f "
					      "outside every island", layers, x, y, nx, ny);
				count[i]++;
			}
		}
		x = nx;
		y = ny;
	}
	for (size_t i = 0; i < nb; i++)
		ck_assert_msg(count[i] > 0, "last layer: no extrusion in island %zu", i);
	gcode_reader_free(r);
	fclose(f);
	return layers;
}

/* Whether the file at path has the line text. */
static bool has_line(const char *path, const char *text)
{
	size_t n;
	char *s = tu_slurp(path, &n), *p = s;
	size_t len = strlen(text);
	bool found = false;

	for (; p && !found; p = strchr(p, '\n') ? strchr(p, '\n') + 1 : NULL)
		found = !strncmp(p, text, len) && (p[len] == '\n' || p[len] == '\0');
	free(s);
	return found;
}

START_TEST(two_cubes_two_islands)
{
	char a[PATH_CAP], b[PATH_CAP], gc[PATH_CAP], args[2048], line[PATH_CAP + 32];
	struct box isl[2], skirt;
	json_t *o;

	cube_stl(a, "cube-a.stl", 20, 20, 10);
	cube_stl(b, "cube-b.stl", 20, 20, 10);
	snprintf(gc, sizeof(gc), "%s", tu_path("two.gcode"));
	snprintf(args, sizeof(args), "'%s' '%s' -o '%s' " MK3S, a, b, gc);
	o = slice_json(args, 0);
	ck_assert(json_is_true(json_object_get(o, "arranged")));
	for (size_t i = 0; i < 2; i++) {
		double off[3];
		model_offset(o, i, off);
		ck_assert_double_eq_tol(off[2], 0.0, 1e-9);
		isl[i] = (struct box){{off[0], off[1]}, {off[0] + 20, off[1] + 20}};
	}
	/* Apart by the spacing, the pair centred on the bed (125, 105). */
	ck_assert_double_ge(box_gap(&isl[0], &isl[1]), GAP - 1e-6);
	ck_assert_double_eq_tol((fmin(isl[0].lo[0], isl[1].lo[0]) + fmax(isl[0].hi[0], isl[1].hi[0])) / 2,
				125.0, 1e-6);
	ck_assert_double_eq_tol((fmin(isl[0].lo[1], isl[1].lo[1]) + fmax(isl[0].hi[1], isl[1].hi[1])) / 2,
				105.0, 1e-6);
	ck_assert_int_eq(check_islands(gc, isl, 2, &skirt), 50);
	/* One skirt around both. */
	for (size_t i = 0; i < 2; i++)
		ck_assert_msg(skirt.lo[0] < isl[i].lo[0] && skirt.hi[0] > isl[i].hi[0] &&
			      skirt.lo[1] < isl[i].lo[1] && skirt.hi[1] > isl[i].hi[1],
			      "the skirt does not go around island %zu", i);
	/* The header names both files. */
	snprintf(line, sizeof(line), "; input file = %s", a);
	ck_assert_msg(has_line(gc, line), "no '%s' in the header", line);
	snprintf(line, sizeof(line), "; input file = %s", b);
	ck_assert_msg(has_line(gc, line), "no '%s' in the header", line);
	json_decref(o);

	/* A wider spacing from the settings (duplicate_distance). */
	snprintf(args, sizeof(args), "'%s' '%s' -o '%s' " MK3S " --set duplicate_distance=15", a,
		 b, gc);
	o = slice_json(args, 0);
	for (size_t i = 0; i < 2; i++) {
		double off[3];
		model_offset(o, i, off);
		isl[i] = (struct box){{off[0], off[1]}, {off[0] + 20, off[1] + 20}};
	}
	ck_assert_double_eq_tol(box_gap(&isl[0], &isl[1]), 15.0, 1e-6);
	json_decref(o);
}
END_TEST

/* `stratum print` takes several models as slice does: its --dry-run G-code
 * is slice's, byte for byte; G-code among models is refused. */
START_TEST(print_takes_several_models)
{
	char a[PATH_CAP], b[PATH_CAP], gs[PATH_CAP], gp[PATH_CAP];
	int rc;

	cube_stl(a, "print-a.stl", 20, 20, 5);
	cube_stl(b, "print-b.stl", 10, 30, 5);
	snprintf(gs, sizeof(gs), "%s", tu_path("print-slice.gcode"));
	snprintf(gp, sizeof(gp), "%s", tu_path("print-dry.gcode"));
	rc = tu_run(out, sizeof(out), "slice '%s' '%s' -o '%s' " MK3S, a, b, gs);
	ck_assert_msg(rc == 0, "exit %d: %s", rc, out);
	rc = tu_run(out, sizeof(out), "print '%s' '%s' " MK3S " --dry-run -o '%s' && cmp '%s' '%s'",
		    a, b, gp, gs, gp);
	ck_assert_msg(rc == 0, "exit %d: %s", rc, out);
	rc = tu_run(out, sizeof(out), "print '%s' '%s' " MK3S " --dry-run -o '%s'", a, gs, gp);
	ck_assert_msg(rc == 2 && strstr(out, "is already G-code or X3G: only models are printed "
					     "together"),
		      "exit %d: %s", rc, out);
}
END_TEST

START_TEST(model_that_does_not_fit_is_named)
{
	char wide[PATH_CAP], plate[PATH_CAP], cube[PATH_CAP], gc[PATH_CAP];
	int rc;

	cube_stl(wide, "wide.stl", 300, 20, 5);
	cube_stl(plate, "plate.stl", 240, 200, 5);
	cube_stl(cube, "cube.stl", 20, 20, 5);
	snprintf(gc, sizeof(gc), "%s", tu_path("refused.gcode"));
	/* Too large alone: named with the bed's size. */
	rc = tu_run(out, sizeof(out), "slice '%s' '%s' -o '%s' " MK3S, cube, wide, gc);
	ck_assert_msg(rc == 1, "exit %d: %s", rc, out);
	ck_assert_msg(strstr(out, "wide.stl: the model is 300.00 x 20.00 mm but the bed is "
				  "250.00 x 210.00 mm"), "%s", out);
	ck_assert(!tu_file_exists(gc));
	/* Fits alone, not beside the plate: the one left without room is named. */
	rc = tu_run(out, sizeof(out), "slice '%s' '%s' -o '%s' " MK3S, plate, cube, gc);
	ck_assert_msg(rc == 1, "exit %d: %s", rc, out);
	ck_assert_msg(strstr(out, "cube.stl: the 20.00 x 20.00 mm model finds no room beside the "
				  "others"), "%s", out);
	ck_assert_msg(strstr(out, "nothing was written"), "%s", out);
	ck_assert(!tu_file_exists(gc));
}
END_TEST

START_TEST(one_model_placed_as_before)
{
	char a[PATH_CAP], gc[PATH_CAP], twice[PATH_CAP], args[2048];
	struct box isl, skirt;
	json_t *o;
	double off[3];

	cube_stl(a, "one.stl", 20, 20, 10);
	snprintf(gc, sizeof(gc), "%s", tu_path("one.gcode"));
	snprintf(twice, sizeof(twice), "%s", tu_path("one-again.gcode"));
	snprintf(args, sizeof(args), "'%s' -o '%s' " MK3S " --set duplicate_distance=40", a, gc);
	o = slice_json(args, 0);
	ck_assert(json_is_false(json_object_get(o, "arranged")));
	model_offset(o, 0, off);
	/* Centred on the bed as slicer_place puts it, whatever the spacing. */
	ck_assert_double_eq_tol(off[0], 115.0, 1e-9);
	ck_assert_double_eq_tol(off[1], 95.0, 1e-9);
	isl = (struct box){{115, 95}, {135, 115}};
	ck_assert_int_eq(check_islands(gc, &isl, 1, &skirt), 50);
	json_decref(o);
	/* The spacing does not touch one model's G-code, which names no input file. */
	ck_assert_int_eq(tu_run(out, sizeof(out), "slice '%s' -o '%s' " MK3S " 2>&1", a, twice), 0);
	{
		size_t n1, n2;
		char *g1 = tu_slurp(gc, &n1), *g2 = tu_slurp(twice, &n2);
		ck_assert_msg(n1 == n2 && !memcmp(g1, g2, n1), "the spacing changed the G-code");
		ck_assert_msg(!strstr(g1, "; input file"), "one model lists no input file");
		free(g1);
		free(g2);
	}
}
END_TEST

START_TEST(threemf_placement_kept)
{
	/* Two objects in one file and one in another, laid out as a plate. */
	static const double plate[2][5] = {{20, 20, 10, 30, 40}, {10, 10, 10, 180, 150}};
	static const double third[1][5] = {{15, 15, 10, 30, 180}};
	char a[PATH_CAP], b[PATH_CAP], gc[PATH_CAP], args[2048];
	struct box isl[3], skirt;
	double oa[3], ob[3];
	json_t *o;

	cubes_3mf(a, "plate.3mf", plate, 2);
	cubes_3mf(b, "third.3mf", third, 1);
	snprintf(gc, sizeof(gc), "%s", tu_path("plate.gcode"));
	snprintf(args, sizeof(args), "'%s' '%s' -o '%s' " MK3S, a, b, gc);
	o = slice_json(args, 0);
	ck_assert(json_is_false(json_object_get(o, "arranged")));
	model_offset(o, 0, oa);
	model_offset(o, 1, ob);
	/* One shift for all: the files' layout kept, the whole centred. */
	ck_assert_double_eq_tol(oa[0], ob[0], 1e-9);
	ck_assert_double_eq_tol(oa[1], ob[1], 1e-9);
	ck_assert_double_eq_tol(oa[0], 125.0 - (30 + 190) / 2.0, 1e-6);
	ck_assert_double_eq_tol(oa[1], 105.0 - (40 + 195) / 2.0, 1e-6);
	isl[0] = (struct box){{30 + oa[0], 40 + oa[1]}, {50 + oa[0], 60 + oa[1]}};
	isl[1] = (struct box){{180 + oa[0], 150 + oa[1]}, {190 + oa[0], 160 + oa[1]}};
	isl[2] = (struct box){{30 + oa[0], 180 + oa[1]}, {45 + oa[0], 195 + oa[1]}};
	ck_assert_int_eq(check_islands(gc, isl, 3, &skirt), 50);
	json_decref(o);

	/* Two files placing their parts on the same spot are arranged instead. */
	snprintf(args, sizeof(args), "'%s' '%s' -o '%s' " MK3S, b, b, gc);
	o = slice_json(args, 0);
	ck_assert(json_is_true(json_object_get(o, "arranged")));
	model_offset(o, 0, oa);
	model_offset(o, 1, ob);
	isl[0] = (struct box){{30 + oa[0], 180 + oa[1]}, {45 + oa[0], 195 + oa[1]}};
	isl[1] = (struct box){{30 + ob[0], 180 + ob[1]}, {45 + ob[0], 195 + ob[1]}};
	ck_assert_double_ge(box_gap(&isl[0], &isl[1]), GAP - 1e-6);
	ck_assert_int_eq(check_islands(gc, isl, 2, &skirt), 50);
	json_decref(o);
}
END_TEST

Suite *multimodel_suite(void)
{
	Suite *s = suite_create("multimodel");
	TCase *tc = tcase_create("multimodel");

	tcase_set_timeout(tc, 120);
	tcase_add_test(tc, two_cubes_two_islands);
	tcase_add_test(tc, model_that_does_not_fit_is_named);
	tcase_add_test(tc, print_takes_several_models);
	tcase_add_test(tc, one_model_placed_as_before);
	tcase_add_test(tc, threemf_placement_kept);
	suite_add_tcase(s, tc);
	return s;
}
