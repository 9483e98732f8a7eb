/*
 * check_adaptive_3mf.c - a PrusaSlicer project's layer height profile
 * (its variable layer height tool), as test cases of the adaptive suite:
 * the reader (meshio_3mf_layer_profile) on good and broken entries, the
 * plan a profile gives (adaptive_plan_profile), and `stratum slice` of a
 * 3MF that carries one: its layers against PrusaSlicer's for the same
 * file, and the notes when the profile is not used.
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "adaptive.h"
#include "fixtures.h"
#include "meshio.h"
#include "suites.h"
#include "testutil.h"

#define ENTRY MESHIO_3MF_LAYER_PROFILE_ENTRY
/* A 10 x 10 x 20 mm box's profile: 0.1 mm up to 8 mm, 0.25 mm from 12 mm. */
#define BOX_PROFILE "object_id=1|0.000000;0.100000;8.000000;0.100000;12.000000;0.250000;20.000000;0.250000\n"

/* A 3MF of the 10 x 10 x 20 mm box at the scratch path name, with profile
 * as its layer height entry unless NULL.  Returns a private copy of the path. */
static char *box_project(const char *name, const char *profile)
{
	struct mesh *m = fx_box(0, 0, 0, 10, 10, 20);
	char *path = strdup(tu_path(name));

	ck_assert_ptr_nonnull(path);
	tu_write_3mf_mesh(path, m);
	if (profile)
		tu_zip_add(path, ENTRY, profile);
	mesh_free(m);
	return path;
}

/* The ";Z:" values of the G-code file at path into z (cap), their count. */
static size_t gcode_layer_z(const char *path, double *z, size_t cap)
{
	size_t len, n = 0;
	char *text = tu_slurp(path, &len);

	for (const char *p = text; (p = strstr(p, "\n;Z:")) != NULL; p += 4) {
		ck_assert_uint_lt(n, cap);
		z[n++] = strtod(p + 4, NULL);
	}
	free(text);
	return n;
}

START_TEST(profile_entry_read)
{
	struct st_error err = {0};
	char *path = box_project("lp-read.3mf", "object_id=2|0;0.2;10;0.2\r\n"
						"object_id=1|0.000000;0.100000;5;0.1;10;3e-1\n\n");
	double *zh = NULL;
	size_t pairs = 0, profiles = 0;

	ck_assert_msg(meshio_3mf_layer_profile(path, 1, &zh, &pairs, &profiles, &err) == 0, "%s",
		      err.msg);
	ck_assert_uint_eq(pairs, 3);
	ck_assert_uint_eq(profiles, 2);
	ck_assert_double_eq(zh[0], 0.0);
	ck_assert_double_eq(zh[1], 0.1);
	ck_assert_double_eq(zh[4], 10.0);
	ck_assert_double_eq(zh[5], 0.3);
	free(zh);
	/* an object without one */
	ck_assert_int_eq(meshio_3mf_layer_profile(path, 3, &zh, &pairs, &profiles, &err), 0);
	ck_assert_ptr_null(zh);
	ck_assert_uint_eq(pairs, 0);
	ck_assert_uint_eq(profiles, 2);
	free(path);
	/* blank lines alone, a lone carriage return among them (once a loop) */
	path = box_project("lp-blank.3mf", "\r");
	ck_assert_int_eq(meshio_3mf_layer_profile(path, 1, &zh, &pairs, &profiles, &err), 0);
	ck_assert_ptr_null(zh);
	ck_assert_uint_eq(profiles, 0);
	free(path);
	/* a file with no profile at all */
	path = box_project("lp-none.3mf", NULL);
	ck_assert_int_eq(meshio_3mf_layer_profile(path, 1, &zh, &pairs, &profiles, &err), 0);
	ck_assert_ptr_null(zh);
	ck_assert_uint_eq(profiles, 0);
	free(path);
}
END_TEST

/* Every broken line is an error naming the entry and the line, whichever
 * object is asked for, and nothing is returned. */
START_TEST(profile_entry_broken)
{
	static const struct {
		const char *text, *needle;
	} cases[] = {
	    {"object_id=1|0;0.1;5\n", ENTRY " line 1: 3 values"},
	    {"object_id=1|0;0.1;5;0.2\nobject_id=x|0;0.1;1;0.1\n", ENTRY " line 2: not of the form"},
	    {"object_id=1|0;0.1;5;0.2;4;0.2\n", ENTRY " line 1: Z 4 mm (pair 3) is below"},
	    {"object_id=1|0;0.1;5;0\n", ENTRY " line 1: layer height 0 mm (pair 2)"},
	    {"object_id=1|0;0.1;5;abc\n", ENTRY " line 1: value 4 (\"abc\") is not a number"},
	    {"object_id=1|0;0.1;5;0.2\nobject_id=1|0;0.1;5;0.2\n",
	     ENTRY " line 2: a second profile for object 1"},
	    {"object_id=2|0;nan;5;0.2\n", ENTRY " line 1: value 2 (\"nan\")"},
	    {"object_id=0|0;0.1;5;0.2\n", ENTRY " line 1: not of the form"},
	};

	for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
		struct st_error err = {0};
		char *path = box_project("lp-broken.3mf", cases[i].text);
		double *zh = NULL;
		size_t pairs = 7;

		ck_assert_int_eq(meshio_3mf_layer_profile(path, 1, &zh, &pairs, NULL, &err),
				 ST_ERR_PARSE);
		ck_assert_msg(strstr(err.msg, cases[i].needle), "case %zu: %s", i, err.msg);
		ck_assert_ptr_null(zh);
		ck_assert_uint_eq(pairs, 0);
		free(path);
	}
}
END_TEST

/* The profile's height, linear between its pairs (the test's own reading
 * of PrusaSlicer's rule). */
static double lerp_profile(const double *zh, size_t pairs, double z)
{
	if (z <= zh[0])
		return zh[1];
	for (size_t i = 0; i + 1 < pairs; i++)
		if (z < zh[2 * i + 2])
			return zh[2 * i + 1] +
			       (zh[2 * i + 3] - zh[2 * i + 1]) * (z - zh[2 * i]) / (zh[2 * i + 2] - zh[2 * i]);
	return zh[2 * pairs - 1];
}

START_TEST(profile_plan_follows_the_profile)
{
	static const double zh[] = {0, 0.1, 8, 0.1, 12, 0.3, 20, 0.3};
	struct adaptive_settings s = {
	    .first_height = 0.2, .min_height = 0.07, .max_height = 0.3, .max_cusp = 0.1};
	struct st_error err = {0};
	struct layer_span *plan;
	size_t n, clamped, over = 0;

	ck_assert_int_eq(adaptive_plan_profile(20, &s, zh, 4, &plan, &n, &clamped, &err), 0);
	ck_assert_double_eq_tol(plan[0].z, 0.2, 1e-12);
	ck_assert_uint_eq(clamped, 0);
	for (size_t i = 1; i < n; i++) {
		double want = lerp_profile(zh, 4, plan[i - 1].z + s.min_height / 2);

		ck_assert_double_eq_tol(plan[i].z - plan[i - 1].z, plan[i].height, 1e-9);
		ck_assert_msg(fabs(plan[i].height - want) <= 0.0006, "layer %zu: %g, profile %g", i,
			      plan[i].height, want);
		ck_assert_double_eq_tol(plan[i].z * 1000, round(plan[i].z * 1000), 1e-6);
	}
	ck_assert(plan[n - 1].z - plan[n - 1].height / 2 < 20);
	ck_assert(plan[n - 1].z + 0.3 / 2 >= 20); /* no room for one more */
	free(plan);
	/* a lower ceiling: the thick part is held to it and counted */
	s.max_height = 0.25;
	ck_assert_int_eq(adaptive_plan_profile(20, &s, zh, 4, &plan, &n, &clamped, &err), 0);
	for (size_t i = 1; i < n; i++) {
		ck_assert(plan[i].height <= 0.25 + 1e-9);
		over += lerp_profile(zh, 4, plan[i - 1].z + s.min_height / 2) > 0.25 + 1e-9;
	}
	ck_assert_uint_gt(clamped, 20);
	ck_assert_uint_eq(clamped, over);
	free(plan);
	ck_assert_int_eq(adaptive_plan_profile(20, &s, zh, 0, &plan, &n, NULL, &err), ST_ERR_ARG);
	ck_assert_ptr_null(plan);
}
END_TEST

/* `stratum slice` of a project with a profile prints its layers, as
 * PrusaSlicer 2.5 does with the same file (when it is installed). */
START_TEST(slice_3mf_profile_as_prusaslicer)
{
	char *path = box_project("lp-box.3mf", BOX_PROFILE);
	char out[16384], gc[4096], ps[4096];
	double z[400], zp[400];
	size_t n, np;
	int rc;

	snprintf(gc, sizeof(gc), "%s", tu_path("lp-box.gcode"));
	snprintf(ps, sizeof(ps), "%s", tu_path("lp-box-prusa.gcode"));
	rc = tu_run(out, sizeof(out),
		    "slice %s -o %s --printer prusa-i3-mk3s --first-layer-height 0.2 --threads 1", path,
		    gc);
	ck_assert_msg(rc == 0, "%s", out);
	ck_assert_msg(strstr(out, "then as the 3MF's profile"), "%s", out);
	ck_assert_msg(strstr(out, "layer height profile (" ENTRY "): "), "%s", out);
	n = gcode_layer_z(gc, z, 400);
	ck_assert_uint_gt(n, 100);
	for (size_t i = 1; i < n; i++) {
		if (z[i] < 8)
			ck_assert_msg(fabs(z[i] - z[i - 1] - 0.1) < 0.0011, "Z %g after %g", z[i], z[i - 1]);
		if (z[i - 1] > 12.1)
			ck_assert_msg(fabs(z[i] - z[i - 1] - 0.25) < 0.0011, "Z %g after %g", z[i],
				      z[i - 1]);
	}
	rc = tu_run(out, sizeof(out),
		    "slice %s -o %s --printer prusa-i3-mk3s --first-layer-height 0.2 --json "
		    "--threads 1 2>/dev/null",
		    path, gc);
	ck_assert_msg(rc == 0, "%s", out);
	ck_assert_msg(strstr(out, "\"layer_heights\": \"3mf_profile\""), "%s", out);
	ck_assert_msg(strstr(out, "\"profile_clamped_layers\": 0"), "%s", out);
	if (access("/usr/bin/prusa-slicer", X_OK)) {
		fprintf(stderr, "slice_3mf_profile_as_prusaslicer: PrusaSlicer part skipped, no "
				"prusa-slicer\n");
		free(path);
		return;
	}
	rc = tu_sh(out, sizeof(out),
		   "prusa-slicer --export-gcode %s --first-layer-height 0.2 -o %s >/dev/null 2>&1",
		   path, ps);
	ck_assert_msg(rc == 0, "prusa-slicer: %s", out);
	np = gcode_layer_z(ps, zp, 400);
	ck_assert_uint_eq(n, np);
	for (size_t i = 0; i < n; i++)
		ck_assert_msg(fabs(z[i] - zp[i]) < 0.005, "layer %zu: Z %g, PrusaSlicer's %g", i, z[i],
			      zp[i]);
	free(path);
}
END_TEST

/* A profile the job cannot use is named in a note and the layers are the
 * profile's uniform ones; a broken one stops the job before any work. */
START_TEST(slice_3mf_profile_not_used)
{
	static const double two[][5] = {{10, 10, 20, 0, 0}, {10, 10, 20, 20, 0}};
	char *stale = box_project("lp-stale.3mf", "object_id=1|0;0.1;15;0.1\n");
	char *good = box_project("lp-good.3mf", BOX_PROFILE);
	char *broken = box_project("lp-bad.3mf", "object_id=1|0;0.1;20\n");
	char *several = strdup(tu_path("lp-two.3mf"));
	char out[16384], gc[4096];
	double z[400];
	int rc;

	snprintf(gc, sizeof(gc), "%s", tu_path("lp-not.gcode"));
	rc = tu_run(out, sizeof(out), "slice %s -o %s --printer prusa-i3-mk3s --threads 1", stale, gc);
	ck_assert_msg(rc == 0, "%s", out);
	ck_assert_msg(strstr(out, "not used: it ends at Z 15 mm, not at the object's top, 20 mm"),
		      "%s", out);
	ck_assert_msg(strstr(out, "then 0.2 mm)"), "%s", out);
	ck_assert_uint_eq(gcode_layer_z(gc, z, 400), 100);
	rc = tu_run(out, sizeof(out), "slice %s -o %s --printer prusa-i3-mk3s --adaptive --threads 1",
		    good, gc);
	ck_assert_msg(rc == 0 && strstr(out, "not used: adaptive layers were asked for"), "%s", out);
	rc = tu_run(out, sizeof(out),
		    "slice %s -o %s --printer prusa-i3-mk3s --set variable_layer_height=0 --threads 1",
		    good, gc);
	ck_assert_msg(rc == 0 && strstr(out, "not used: the printer allows no variable layer heights"),
		      "%s", out);
	tu_write_3mf_boxes(several, two, 2);
	tu_zip_add(several, ENTRY, BOX_PROFILE);
	rc = tu_run(out, sizeof(out), "slice %s -o %s --printer prusa-i3-mk3s --threads 1", several,
		    gc);
	ck_assert_msg(rc == 0 && strstr(out, "not used: it is one object's, and the plate holds "
					     "several"),
		      "%s", out);
	remove(gc);
	rc = tu_run(out, sizeof(out), "slice %s -o %s --printer prusa-i3-mk3s --threads 1", broken,
		    gc);
	ck_assert_int_eq(rc, ST_EXIT_DATAERR);
	ck_assert_msg(strstr(out, ENTRY " line 1: 3 values"), "%s", out);
	ck_assert_msg(!strstr(out, "repairing"), "the profile is read before the repair: %s", out);
	ck_assert(!tu_file_exists(gc));
	free(stale);
	free(good);
	free(broken);
	free(several);
}
END_TEST

void adaptive_3mf_tcases(Suite *s)
{
	TCase *tc = tcase_create("3mf_profile");

	tcase_set_timeout(tc, 120);
	tcase_add_test(tc, profile_entry_read);
	tcase_add_test(tc, profile_entry_broken);
	tcase_add_test(tc, profile_plan_follows_the_profile);
	tcase_add_test(tc, slice_3mf_profile_as_prusaslicer);
	tcase_add_test(tc, slice_3mf_profile_not_used);
	suite_add_tcase(s, tc);
}
