/*
 * check_cli_repair.c - `stratum repair` end to end, part of the cli suite
 * (check_cli.c): its outputs judged by `stratum check`, 3MF, bad input and
 * usage, the JSON report on every exit, epsilon from the printer, split
 * parts, overlapping and touching cubes, and refusals to overwrite.
 */
#include <check.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "clitest.h"
#include "fixtures.h"
#include "meshio.h"
#include "suites.h"
#include "testutil.h"

static char out[1 << 16];

/* `stratum check` on path: its exit status (0 = printable). */
static int check_status(const char *path)
{
	static char buf[1 << 14];

	return tu_run(buf, sizeof(buf), "check '%s'", path);
}

/* Run `repair --json IN -o OUT [extra]`, expect want_status, return the report. */
static json_t *repair_json(const char *in, const char *outp, const char *extra, int want_status)
{
	json_error_t jerr;
	json_t *o;
	int status = tu_run(out, sizeof(out), "repair --json '%s' -o '%s' %s", in, outp, extra);
	const char *start;

	ck_assert_msg(status == want_status, "exit %d, wanted %d: %s", status, want_status, out);
	/* Messages on stderr (mixed in by tu_run) come before the report. */
	start = out[0] == '{' ? out : strstr(out, "\n{");
	ck_assert_msg(start != NULL, "no JSON object: %s", out);
	o = json_loads(start, 0, &jerr);
	ck_assert_msg(o != NULL, "not JSON (%s): %s", jerr.text, out);
	return o;
}

START_TEST(repair_cube_checks_printable)
{
	const char *in = write_mesh(fx_box(0, 0, 0, 20, 10, 5), "r-cube.stl");
	char outp[512];

	snprintf(outp, sizeof(outp), "%s", tu_path("r-cube-out.stl"));
	ck_assert_msg(tu_run(out, sizeof(out), "repair '%s' -o '%s'", in, outp) == 0, "%s", out);
	ck_assert_ptr_nonnull(strstr(out, "printable: yes"));
	ck_assert_ptr_nonnull(strstr(out, outp));
	ck_assert_msg(tu_file_exists(outp), "%s was not written", outp);
	ck_assert_int_eq(check_status(outp), 0);
}
END_TEST

/* check and repair take a 3MF as they take an STL; a broken one exits 65. */
START_TEST(check_and_repair_3mf)
{
	struct mesh *cube = fx_box(0, 0, 0, 10, 10, 10);
	const char *in = tu_path("c3.3mf");
	char outp[512];
	struct st_error err = {0};
	struct mesh *back = NULL;
	json_t *o;

	tu_write_3mf_mesh(in, cube);
	o = check_json(in, 0);
	ck_assert_str_eq(json_string_value(json_object_get(o, "format")), "3MF");
	ck_assert_int_eq(field(o, "input_triangles"), 12);
	json_decref(o);
	snprintf(outp, sizeof(outp), "%s", tu_path("c3-out.stl"));
	ck_assert_int_eq(tu_run(out, sizeof(out), "repair '%s' -o '%s'", in, outp), 0);
	ck_assert_msg(meshio_read(outp, MESHIO_AUTO, &back, NULL, &err) == 0, "%s", err.msg);
	ck_assert_uint_eq(back->ntris, 12);
	mesh_free(back);

	in = tu_path("c3-bad.3mf");
	tu_write_3mf(in, "<model xmlns=\"http://schemas.microsoft.com/3dmanufacturing/core/"
			 "2015/02\"><resources><object id=\"1\"><mesh><vertices/><triangles>"
			 "<triangle v1=\"0\" v2=\"1\" v3=\"2\"/></triangles></mesh></object>"
			 "</resources><build><item objectid=\"1\"/></build></model>");
	ck_assert_int_eq(tu_run(out, sizeof(out), "check '%s'", in), 65);
	ck_assert_msg(strstr(out, "3D/3dmodel.model line 1: triangle 0 of object 1 refers to "
			      "vertex 0"),
		      "%s", out);
	snprintf(outp, sizeof(outp), "%s", tu_path("c3-bad-out.stl"));
	ck_assert_int_eq(tu_run(out, sizeof(out), "repair '%s' -o '%s'", in, outp), 65);
	ck_assert_msg(!tu_file_exists(outp), "%s was written", outp);
	mesh_free(cube);
}
END_TEST

START_TEST(repair_bad_input_exit_65_writes_nothing)
{
	const char *in = tu_path("r-truncated.stl");
	unsigned char bin[84 + 50 * 2];
	char outp[512];

	memset(bin, 0, sizeof(bin));
	binary_header(bin, 1000); /* says 1000 facets, holds 2 */
	tu_write(in, bin, sizeof(bin));
	snprintf(outp, sizeof(outp), "%s", tu_path("r-truncated-out.stl"));
	ck_assert_int_eq(tu_run(out, sizeof(out), "repair '%s' -o '%s'", in, outp), 65);
	ck_assert_msg(strstr(out, "r-truncated.stl") && strstr(out, "byte"), "%s", out);
	ck_assert_msg(!tu_file_exists(outp), "%s was written", outp);

	in = tu_path("r-garbage.stl");
	tu_write_str(in, "this is not a mesh at all\n\x01\x02\x03");
	ck_assert_int_eq(tu_run(out, sizeof(out), "repair '%s' -o '%s'", in, outp), 65);
	ck_assert_msg(!tu_file_exists(outp), "%s was written", outp);
}
END_TEST

START_TEST(repair_usage_errors_exit_2)
{
	const char *in = write_mesh(fx_box(0, 0, 0, 1, 1, 1), "r-usage.stl");
	char outp[512];

	snprintf(outp, sizeof(outp), "%s", tu_path("r-usage-out.stl"));
	ck_assert_int_eq(tu_run(out, sizeof(out), "repair '%s'", in), 2); /* no -o */
	ck_assert_ptr_nonnull(strstr(out, "-o"));
	ck_assert_int_eq(tu_run(out, sizeof(out), "repair -o '%s'", outp), 2); /* no IN */
	ck_assert_int_eq(tu_run(out, sizeof(out), "repair '%s' -o", in), 2);
	ck_assert_int_eq(tu_run(out, sizeof(out), "repair '%s' -o '%s' --epsilon -1", in, outp), 2);
	ck_assert_ptr_nonnull(strstr(out, "--epsilon"));
	ck_assert_int_eq(tu_run(out, sizeof(out), "repair '%s' -o '%s' --epsilon 0", in, outp), 2);
	ck_assert_int_eq(tu_run(out, sizeof(out), "repair '%s' -o '%s' --epsilon nan", in, outp), 2);
	ck_assert_int_eq(tu_run(out, sizeof(out), "repair '%s' -o '%s' --epsilon 10.5", in, outp), 2);
	ck_assert_int_eq(tu_run(out, sizeof(out), "repair '%s' -o '%s' --bogus", in, outp), 2);
	ck_assert_ptr_nonnull(strstr(out, "--bogus"));
	ck_assert_int_eq(tu_run(out, sizeof(out), "repair '%s' -o '%s' --threads 0", in, outp), 2);
	ck_assert_int_eq(tu_run(out, sizeof(out), "repair '%s' -o '%s' --printer no-such-printer",
				in, outp), 2);
	ck_assert_msg(!tu_file_exists(outp), "%s was written by a rejected command", outp);
	ck_assert_int_eq(tu_run(out, sizeof(out), "repair --help"), 0);
	ck_assert_ptr_nonnull(strstr(out, "usage: stratum repair"));
}
END_TEST

START_TEST(repair_json_report)
{
	const char *in = write_mesh(fx_box(0, 0, 0, 10, 10, 10), "r-json.stl");
	char outp[512];
	json_t *o, *outs;
	static const char *const keys[] = {
		"input", "epsilon", "input_triangles", "irregular_removed", "degenerate_removed",
		"duplicates_removed", "intersecting_pairs", "triangles_split", "interior_deleted",
		"enclosed_deleted", "enclosed_components", "cavities", "parts_dropped",
		"dropped_triangles", "ok", "exit", "error", "stage", "sheet_triangles", "sheet_area", "sheet_components", "wires",
		"wire_length", "wires_discarded", "second_pass", "thickened_triangles",
		"second_sheet_triangles", "batches", "batch_fallback", "rounding_rounds",
		"rounding_merged", "solid_deviation",
		"rounding_deviation", "sheet_deviation", "output_triangles", "output_vertices",
		"components", "printable", "outputs"};

	snprintf(outp, sizeof(outp), "%s", tu_path("r-json-out.stl"));
	o = repair_json(in, outp, "", 0);
	for (size_t i = 0; i < sizeof(keys) / sizeof(keys[0]); i++)
		ck_assert_msg(json_object_get(o, keys[i]) != NULL, "missing %s", keys[i]);
	ck_assert(json_is_true(json_object_get(o, "printable")));
	ck_assert_int_eq(field(o, "input_triangles"), 12);
	ck_assert_int_eq(field(o, "components"), 1);
	ck_assert_int_eq(field(o, "intersecting_pairs"), 0);
	ck_assert_double_eq(json_number_value(json_object_get(o, "epsilon")), 0.4);
	ck_assert_double_eq(json_number_value(json_object_get(o, "solid_deviation")), 0.0);
	outs = json_object_get(o, "outputs");
	ck_assert_uint_eq(json_array_size(outs), 1);
	ck_assert_str_eq(json_string_value(json_array_get(outs, 0)), outp);
	json_decref(o);
}
END_TEST

/* epsilon: the printer's nozzle; --epsilon wins over --printer. */
START_TEST(repair_epsilon_from_printer)
{
	const char *in = write_mesh(fx_box(0, 0, 0, 10, 10, 10), "r-eps.stl");
	char ini[512], outp[512], extra[600];
	json_t *o;

	snprintf(ini, sizeof(ini), "%s", tu_path("r-nozzle06.ini"));
	tu_write_str(ini, "name = test\nnozzle_diameter = 0.6\n");
	snprintf(outp, sizeof(outp), "%s", tu_path("r-eps-out.stl"));
	snprintf(extra, sizeof(extra), "--printer '%s'", ini);
	o = repair_json(in, outp, extra, 0);
	ck_assert_double_eq(json_number_value(json_object_get(o, "epsilon")), 0.6);
	json_decref(o);
	snprintf(extra, sizeof(extra), "--printer '%s' --epsilon 1.5", ini);
	o = repair_json(in, outp, extra, 0);
	ck_assert_double_eq(json_number_value(json_object_get(o, "epsilon")), 1.5);
	json_decref(o);
}
END_TEST

START_TEST(repair_split_two_cubes)
{
	struct mesh *a = fx_box(0, 0, 0, 10, 10, 10), *b = fx_box(20, 0, 0, 30, 10, 10);
	const char *in = write_mesh(fx_concat(a, b), "r-two.stl");
	char outp[512], p1[512], p2[512], p3[512];
	json_t *o;

	mesh_free(a);
	mesh_free(b);
	snprintf(outp, sizeof(outp), "%s", tu_path("r-part.stl"));
	snprintf(p1, sizeof(p1), "%s", tu_path("r-part-1.stl"));
	snprintf(p2, sizeof(p2), "%s", tu_path("r-part-2.stl"));
	snprintf(p3, sizeof(p3), "%s", tu_path("r-part-3.stl"));
	o = repair_json(in, outp, "--split", 0);
	ck_assert_int_eq(field(o, "components"), 2);
	ck_assert_uint_eq(json_array_size(json_object_get(o, "outputs")), 2);
	ck_assert_str_eq(json_string_value(json_array_get(json_object_get(o, "outputs"), 0)), p1);
	json_decref(o);
	ck_assert_msg(tu_file_exists(p1) && tu_file_exists(p2), "parts not written");
	ck_assert_msg(!tu_file_exists(p3) && !tu_file_exists(outp), "unexpected files");
	ck_assert_int_eq(check_status(p1), 0);
	ck_assert_int_eq(check_status(p2), 0);
}
END_TEST

/* --split with one part writes OUT itself. */
START_TEST(repair_split_one_part)
{
	const char *in = write_mesh(fx_box(0, 0, 0, 10, 10, 10), "r-one.stl");
	char outp[512], p1[512];

	snprintf(outp, sizeof(outp), "%s", tu_path("r-one-out.stl"));
	snprintf(p1, sizeof(p1), "%s", tu_path("r-one-out-1.stl"));
	ck_assert_msg(tu_run(out, sizeof(out), "repair '%s' -o '%s' --split", in, outp) == 0, "%s",
		      out);
	ck_assert(tu_file_exists(outp));
	ck_assert(!tu_file_exists(p1));
}
END_TEST

START_TEST(repair_overlapping_cubes)
{
	struct mesh *a = fx_box(0, 0, 0, 10, 10, 10), *b = fx_box(5, 5, 5, 15, 15, 15);
	const char *in = write_mesh(fx_concat(a, b), "r-overlap.stl");
	char outp[512];
	json_t *o;

	mesh_free(a);
	mesh_free(b);
	snprintf(outp, sizeof(outp), "%s", tu_path("r-overlap-out.stl"));
	o = repair_json(in, outp, "", 0);
	ck_assert(field(o, "intersecting_pairs") > 0);
	ck_assert(field(o, "interior_deleted") > 0);
	ck_assert_int_eq(field(o, "components"), 1);
	json_decref(o);
	ck_assert_int_eq(check_status(outp), 0);
	o = check_json(outp, 0);
	/* The union of two 10 mm cubes overlapping by a 5 mm cube. */
	ck_assert_double_eq_tol(json_real_value(json_object_get(o, "volume")), 1875.0, 1e-6);
	json_decref(o);
}
END_TEST

/* An output that cannot be created: exit 1, the message names it. */
START_TEST(repair_unwritable_output_exit_1)
{
	const char *in = write_mesh(fx_box(0, 0, 0, 10, 10, 10), "r-unwritable.stl");
	char outp[512];

	snprintf(outp, sizeof(outp), "%s", tu_path("no-such-dir/out.stl"));
	ck_assert_int_eq(tu_run(out, sizeof(out), "repair '%s' -o '%s'", in, outp), 1);
	ck_assert_msg(strstr(out, outp) != NULL, "message does not name %s: %s", outp, out);
}
END_TEST

/* Two 10 mm cubes touching along an edge (i = 0) or at a vertex (i = 1). */
static struct mesh *touching_cubes(int i)
{
	struct mesh *a = fx_box(0, 0, 0, 10, 10, 10);
	struct mesh *b = i == 0 ? fx_box(10, 10, 0, 20, 20, 10) : fx_box(10, 10, 10, 20, 20, 20);
	struct mesh *m = fx_concat(a, b);

	mesh_free(a);
	mesh_free(b);
	return m;
}

/*
 * Proves that repair and check agree on touching parts: the one output
 * file holds two parts sharing an edge or a vertex (equal coordinates
 * weld in STL), `stratum check` exits 0 on it and counts 2 parts, and
 * each --split part passes check too.
 */
START_TEST(repair_touching_cubes_check_exit_0)
{
	const char *in = write_mesh(touching_cubes(_i), _i ? "r-touch-v.stl" : "r-touch-e.stl");
	char outp[512], p1[512], p2[512];
	json_t *o;

	snprintf(outp, sizeof(outp), "%s", tu_path("r-touch-out.stl"));
	o = repair_json(in, outp, "", 0);
	ck_assert_int_eq(field(o, "components"), 2);
	json_decref(o);
	o = check_json(outp, 0);
	ck_assert_int_eq(field(o, "parts"), 2);
	ck_assert(has_reason(o, "warnings", "several_parts"));
	json_decref(o);
	snprintf(outp, sizeof(outp), "%s", tu_path("r-touch-split.stl"));
	snprintf(p1, sizeof(p1), "%s", tu_path("r-touch-split-1.stl"));
	snprintf(p2, sizeof(p2), "%s", tu_path("r-touch-split-2.stl"));
	o = repair_json(in, outp, "--split", 0);
	json_decref(o);
	ck_assert_int_eq(check_status(p1), 0);
	ck_assert_int_eq(check_status(p2), 0);
}
END_TEST

/* The bytes of path, malloc'd, with their count in *n. */
static unsigned char *slurp(const char *path, size_t *n)
{
	FILE *f = fopen(path, "rb");
	unsigned char *buf = malloc(1 << 16);

	ck_assert_ptr_nonnull(f);
	ck_assert_ptr_nonnull(buf);
	*n = fread(buf, 1, 1 << 16, f);
	fclose(f);
	return buf;
}

/* Run repair with json and the given output; it must refuse with exit 2. */
static void assert_refused(const char *in, const char *outp, const char *extra)
{
	json_t *o = repair_json(in, outp, extra, 2);

	ck_assert(json_is_false(json_object_get(o, "ok")));
	ck_assert_int_eq(field(o, "exit"), 2);
	ck_assert_msg(strstr(json_string_value(json_object_get(o, "error")), "is the input") ||
			      strstr(json_string_value(json_object_get(o, "error")), "like a part"),
		      "error: %s", json_string_value(json_object_get(o, "error")));
	json_decref(o);
}

/*
 * Proves that -o never overwrites the input: the same path, another
 * spelling of it, a symlink to it, and with --split an input named like
 * one of the parts are all refused with exit 2 before any work, and the
 * input's bytes are unchanged.
 */
START_TEST(repair_refuses_to_overwrite_input)
{
	const char *in = write_mesh(fx_box(0, 0, 0, 10, 10, 10), "r-own.stl");
	char other[512], link[512], part_in[512], part_out[512], cmd[1600];
	unsigned char *before, *after;
	size_t nb, na;

	before = slurp(in, &nb);
	/* dir/name spelled dir/./name */
	snprintf(other, sizeof(other), "%.*s/.%s", (int)(strrchr(in, '/') - in), in,
		 strrchr(in, '/'));
	snprintf(link, sizeof(link), "%s", tu_path("r-own-link.stl"));
	unlink(link);
	ck_assert_int_eq(symlink(in, link), 0);
	assert_refused(in, in, "");
	assert_refused(in, other, "");
	assert_refused(in, link, "");
	assert_refused(link, in, "");
	snprintf(part_in, sizeof(part_in), "%s", tu_path("r-ownpart-2.stl"));
	snprintf(part_out, sizeof(part_out), "%s", tu_path("r-ownpart.stl"));
	snprintf(cmd, sizeof(cmd), "cp '%s' '%s'", in, part_in);
	ck_assert_int_eq(system(cmd), 0);
	assert_refused(part_in, part_out, "--split");
	after = slurp(in, &na);
	ck_assert_uint_eq(na, nb);
	ck_assert_int_eq(memcmp(before, after, nb), 0);
	free(before);
	free(after);
}
END_TEST

/*
 * Proves that every exit prints the report: a missing output directory
 * (exit 1, found before the input is read), an unreadable input (65) and
 * a result with nothing printable left (1: a 0.1 mm cube, smaller than
 * epsilon) each give a JSON object with ok, exit, error and what was
 * measured so far.
 */
START_TEST(repair_json_on_every_exit)
{
	const char *in = write_mesh(fx_box(0, 0, 0, 10, 10, 10), "r-every.stl");
	const char *tiny = write_mesh(fx_box(0, 0, 0, 0.1, 0.1, 0.1), "r-tiny.stl");
	char outp[512], bad[512];
	FILE *f;
	json_t *o;

	snprintf(outp, sizeof(outp), "%s", tu_path("no-such-dir/out.stl"));
	o = repair_json(in, outp, "", 1);
	ck_assert(json_is_false(json_object_get(o, "ok")));
	ck_assert_int_eq(field(o, "exit"), 1);
	ck_assert_str_eq(json_string_value(json_object_get(o, "stage")), "checking the output");
	ck_assert(strstr(json_string_value(json_object_get(o, "error")), "does not exist"));
	json_decref(o);

	snprintf(bad, sizeof(bad), "%s", tu_path("r-garbage.stl"));
	f = fopen(bad, "w");
	ck_assert_ptr_nonnull(f);
	fputs("not a mesh\n", f);
	fclose(f);
	snprintf(outp, sizeof(outp), "%s", tu_path("r-every-out.stl"));
	o = repair_json(bad, outp, "", 65);
	ck_assert_int_eq(field(o, "exit"), 65);
	ck_assert_str_eq(json_string_value(json_object_get(o, "stage")), "reading");
	ck_assert(json_is_null(json_object_get(o, "input_triangles")));
	json_decref(o);

	o = repair_json(tiny, outp, "", 1);
	ck_assert(json_is_false(json_object_get(o, "ok")));
	ck_assert_int_eq(field(o, "exit"), 1);
	ck_assert_int_eq(field(o, "input_triangles"), 12);
	ck_assert_int_eq(field(o, "parts_dropped"), 1);
	ck_assert(json_is_false(json_object_get(o, "printable")));
	ck_assert_uint_eq(json_array_size(json_object_get(o, "outputs")), 0);
	json_decref(o);
	ck_assert(!tu_file_exists(outp));
}
END_TEST

/* --ascii writes ASCII STL that reads back printable. */
START_TEST(repair_ascii_output)
{
	const char *in = write_mesh(fx_torus(20, 5, 40, 16), "r-torus.stl");
	char outp[512];
	json_t *o;

	snprintf(outp, sizeof(outp), "%s", tu_path("r-torus-out.stl"));
	ck_assert_msg(tu_run(out, sizeof(out), "repair '%s' -o '%s' --ascii", in, outp) == 0, "%s",
		      out);
	o = check_json(outp, 0);
	ck_assert_str_eq(json_string_value(json_object_get(o, "format")), "ASCII STL");
	ck_assert_int_eq(field(o, "genus"), 1);
	json_decref(o);
}
END_TEST

/* The ports list is machine-dependent: check its shape, not its content. */

void cli_repair_tcases(Suite *s)
{
	TCase *tc = tcase_create("repair");

	tcase_set_timeout(tc, 120); /* the exact passes run slowly under ASan */
	tcase_add_test(tc, repair_cube_checks_printable);
	tcase_add_test(tc, repair_bad_input_exit_65_writes_nothing);
	tcase_add_test(tc, check_and_repair_3mf);
	tcase_add_test(tc, repair_usage_errors_exit_2);
	tcase_add_test(tc, repair_json_report);
	tcase_add_test(tc, repair_epsilon_from_printer);
	tcase_add_test(tc, repair_split_two_cubes);
	tcase_add_test(tc, repair_split_one_part);
	tcase_add_test(tc, repair_overlapping_cubes);
	tcase_add_test(tc, repair_ascii_output);
	tcase_add_test(tc, repair_unwritable_output_exit_1);
	tcase_add_loop_test(tc, repair_touching_cubes_check_exit_0, 0, 2);
	tcase_add_test(tc, repair_refuses_to_overwrite_input);
	tcase_add_test(tc, repair_json_on_every_exit);
	suite_add_tcase(s, tc);
}
