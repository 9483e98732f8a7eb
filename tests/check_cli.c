/*
 * check_cli.c - the built `stratum` binary end to end: exit statuses, the
 * `check --json` report on generated files, and one clear message naming
 * file and offset for every kind of bad input; `stratum repair` outputs
 * judged by `stratum check`.
 */
#include <check.h>
#include <jansson.h>
#include <math.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>
#include <stdio.h>
#include <string.h>

#include "fixtures.h"
#include "meshio.h"
#include "suites.h"
#include "testutil.h"

static char out[1 << 16];

/* Write m to a scratch file as binary STL and return its path. */
static const char *write_mesh(struct mesh *m, const char *name)
{
	const char *path = tu_path(name);
	struct st_error err = {0};

	ck_assert_msg(meshio_write_stl(path, m, MESHIO_STL_BINARY, &err) == 0, "%s", err.msg);
	mesh_free(m);
	return path;
}

/* Run `check --json` on path, expect the exit status, return the parsed report. */
static json_t *check_json(const char *path, int want_status)
{
	json_error_t jerr;
	json_t *o;
	int status = tu_run(out, sizeof(out), "check --json '%s'", path);

	ck_assert_msg(status == want_status, "exit %d, wanted %d: %s", status, want_status, out);
	o = json_loads(out, 0, &jerr);
	ck_assert_msg(o != NULL, "not JSON (%s): %s", jerr.text, out);
	return o;
}

static json_int_t field(json_t *o, const char *key)
{
	json_t *v = json_object_get(o, key);

	ck_assert_msg(json_is_integer(v), "field %s missing or not an integer", key);
	return json_integer_value(v);
}

static int has_reason(json_t *o, const char *list, const char *code)
{
	json_t *arr = json_object_get(o, list), *item;
	size_t i;

	json_array_foreach(arr, i, item)
		if (!strcmp(json_string_value(json_object_get(item, "code")), code))
			return 1;
	return 0;
}

START_TEST(json_cube)
{
	json_t *o = check_json(write_mesh(fx_box(0, 0, 0, 20, 10, 5), "cube.stl"), 0);
	static const char *const keys[] = {
		"vertices", "edges", "triangles", "boundary_edges", "singular_edges",
		"nonmanifold_vertices", "components", "boundary_loops", "euler", "genus",
		"degenerate", "duplicates", "self_intersections", "orientable",
		"consistently_oriented", "volume", "bbox", "printable", "reasons", "parts",
		"cavities", "misnested_shells", "unpaired_singular_edges", "warnings"};

	for (size_t i = 0; i < sizeof(keys) / sizeof(keys[0]); i++)
		ck_assert_msg(json_object_get(o, keys[i]) != NULL, "missing %s", keys[i]);
	ck_assert_int_eq(field(o, "vertices"), 8);
	ck_assert_int_eq(field(o, "edges"), 18);
	ck_assert_int_eq(field(o, "triangles"), 12);
	ck_assert_int_eq(field(o, "euler"), 2);
	ck_assert_int_eq(field(o, "genus"), 0);
	ck_assert_int_eq(field(o, "self_intersections"), 0);
	ck_assert_int_eq(field(o, "parts"), 1);
	ck_assert_int_eq(field(o, "cavities"), 0);
	ck_assert(json_is_true(json_object_get(o, "printable")));
	ck_assert(json_is_true(json_object_get(o, "orientable")));
	ck_assert_double_eq_tol(json_real_value(json_object_get(o, "volume")), 1000.0, 1e-6);
	ck_assert_double_eq(json_number_value(json_array_get(
				    json_object_get(json_object_get(o, "bbox"), "max"), 0)),
			    20.0);
	ck_assert_uint_eq(json_array_size(json_object_get(o, "reasons")), 0);
	json_decref(o);
}
END_TEST

START_TEST(json_torus_genus)
{
	json_t *o = check_json(write_mesh(fx_torus(20, 5, 40, 16), "torus.stl"), 0);

	ck_assert_int_eq(field(o, "euler"), 0);
	ck_assert_int_eq(field(o, "genus"), 1);
	json_decref(o);
}
END_TEST

START_TEST(json_open_cube_exit_1)
{
	struct mesh *m = fx_box(0, 0, 0, 10, 10, 10);
	json_t *o;

	fx_drop(m, 0);
	o = check_json(write_mesh(m, "open.stl"), 1);
	ck_assert_int_eq(field(o, "boundary_edges"), 3);
	ck_assert_int_eq(field(o, "boundary_loops"), 1);
	ck_assert(json_is_null(json_object_get(o, "genus")));
	ck_assert(json_is_false(json_object_get(o, "printable")));
	ck_assert(has_reason(o, "reasons", "open"));
	json_decref(o);
}
END_TEST

START_TEST(json_edge_sharing_cubes)
{
	struct mesh *a = fx_box(0, 0, 0, 1, 1, 1), *b = fx_box(1, 1, 0, 2, 2, 1);
	json_t *o = check_json(write_mesh(fx_concat(a, b), "edge.stl"), 0);

	/* Two closed parts touching along an edge print as they are. */
	ck_assert_int_eq(field(o, "singular_edges"), 1);
	ck_assert_int_eq(field(o, "parts"), 2);
	ck_assert(has_reason(o, "warnings", "not_manifold_connected"));
	ck_assert_uint_eq(json_array_size(json_object_get(o, "reasons")), 0);
	json_decref(o);
	mesh_free(a);
	mesh_free(b);
}
END_TEST

START_TEST(json_overlapping_cubes)
{
	struct mesh *a = fx_box(0, 0, 0, 10, 10, 10), *b = fx_box(5, 5, 5, 15, 15, 15);
	json_t *o = check_json(write_mesh(fx_concat(a, b), "overlap.stl"), 1);

	ck_assert(field(o, "self_intersections") > 0);
	ck_assert(has_reason(o, "reasons", "self_intersection"));
	json_decref(o);
	mesh_free(a);
	mesh_free(b);
}
END_TEST

START_TEST(text_report)
{
	const char *path = write_mesh(fx_box(0, 0, 0, 10, 10, 10), "text.stl");

	ck_assert_int_eq(tu_run(out, sizeof(out), "check '%s'", path), 0);
	ck_assert_ptr_nonnull(strstr(out, "printable: yes"));
	ck_assert_ptr_nonnull(strstr(out, "Euler characteristic 2"));
}
END_TEST

START_TEST(usage_errors_exit_2)
{
	ck_assert_int_eq(tu_run(out, sizeof(out), "check"), 2);
	ck_assert_int_eq(tu_run(out, sizeof(out), "check --bogus x.stl"), 2);
	ck_assert_ptr_nonnull(strstr(out, "--bogus"));
	ck_assert_int_eq(tu_run(out, sizeof(out), "check --threads zero x.stl"), 2);
	ck_assert_int_eq(tu_run(out, sizeof(out), "frobnicate"), 2);
	ck_assert_int_eq(tu_run(out, sizeof(out), "--help"), 0);
}
END_TEST

/* Every command reads its options through one table (host/cmd_opts.c):
 * NAME VALUE and NAME=VALUE alike, a refusal naming the option with the
 * range the help prints. */
START_TEST(options_one_table)
{
	const char *path = write_mesh(fx_box(0, 0, 0, 10, 10, 10), "opts.stl");

	ck_assert_int_eq(tu_run(out, sizeof(out), "check --threads=2 '%s'", path), 0);
	ck_assert_int_eq(tu_run(out, sizeof(out), "check --threads=300 '%s'", path), 2);
	ck_assert_msg(strstr(out, "--threads wants a number from 1 to 256, not '300'"), "%s", out);
	ck_assert_int_eq(tu_run(out, sizeof(out), "sim --dialect=marlin --bufsize=0"), 2);
	ck_assert_msg(strstr(out, "--bufsize wants a number from 1 to 1024, not '0'"), "%s", out);
	ck_assert_int_eq(tu_run(out, sizeof(out), "repair --help"), 0);
	ck_assert_msg(strstr(out, "--epsilon MM      thickness for sheets and wires, 0 < MM <= 10\n"),
		      "%s", out);
	ck_assert_int_eq(tu_run(out, sizeof(out), "preview --help"), 0);
	ck_assert_msg(strstr(out, "picture width, 200 to 8192 px (default 1000)"), "%s", out);
}
END_TEST

/* Every malformed input: exit 65, one message naming the file and where. */
static void expect_bad(const char *name, const void *data, size_t len, const char *where)
{
	const char *path = tu_path(name);

	tu_write(path, data, len);
	ck_assert_int_eq(tu_run(out, sizeof(out), "check '%s'", path), 65);
	ck_assert_msg(strstr(out, name) != NULL, "message does not name %s: %s", name, out);
	if (where)
		ck_assert_msg(strstr(out, where) != NULL, "message lacks '%s': %s", where, out);
	ck_assert_msg(strchr(out, '\n') == out + strlen(out) - 1, "not one line: %s", out);
}

/* An 84-byte binary STL header announcing n facets. */
static void binary_header(unsigned char *buf, uint32_t n)
{
	memset(buf, ' ', 80);
	memcpy(buf, "generated", 9);
	for (int i = 0; i < 4; i++)
		buf[80 + i] = (unsigned char)(n >> (8 * i));
}

START_TEST(bad_inputs_exit_65)
{
	unsigned char bin[84 + 50 * 2];
	const unsigned char png[] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n', 0, 0, 0, 13};
	const float nan_bits = NAN;

	expect_bad("empty.stl", "", 0, NULL);
	/* Header says 1000 facets, file holds 2. */
	memset(bin, 0, sizeof(bin));
	binary_header(bin, 1000);
	expect_bad("truncated.stl", bin, sizeof(bin), "byte");
	/* Absurd count: about 4e9 facets in a small file. */
	binary_header(bin, 0xfffffff0u);
	expect_bad("absurd.stl", bin, sizeof(bin), "byte");
	/* A NaN coordinate in the second facet's first vertex. */
	binary_header(bin, 2);
	memcpy(bin + 84 + 50 + 12, &nan_bits, 4);
	expect_bad("nan.stl", bin, sizeof(bin), "byte");
	expect_bad("ascii.stl",
		   "solid x\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n"
		   "   vertex 1 0 zero\n   vertex 0 1 0\n  endloop\n endfacet\nendsolid x\n",
		   strlen("solid x\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n"
			  "   vertex 1 0 zero\n   vertex 0 1 0\n  endloop\n endfacet\nendsolid x\n"),
		   "line 5");
	expect_bad("inf.stl",
		   "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex inf 0 0\n"
		   "vertex 0 1 0\nendloop\nendfacet\nendsolid x\n",
		   strlen("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex inf 0 0\n"
			  "vertex 0 1 0\nendloop\nendfacet\nendsolid x\n"),
		   "line 5");
	expect_bad("picture.stl", png, sizeof(png), NULL);
	expect_bad("faces.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n",
		   strlen("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"), "line 4");
	expect_bad("counts.off", "OFF\n2000000000 1 0\n0 0 0\n",
		   strlen("OFF\n2000000000 1 0\n0 0 0\n"), "line 2");
	ck_assert_int_eq(tu_run(out, sizeof(out), "check '%s'", tu_path("does-not-exist.stl")),
			 65);
	ck_assert_ptr_nonnull(strstr(out, "does-not-exist.stl"));
}
END_TEST

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
START_TEST(ports_json)
{
	json_error_t jerr;
	json_t *arr, *item;
	size_t i;

	ck_assert_int_eq(tu_run(out, sizeof(out), "ports --json"), 0);
	arr = json_loads(out, 0, &jerr);
	ck_assert_msg(json_is_array(arr), "not a JSON array (%s): %s", jerr.text, out);
	json_array_foreach(arr, i, item) {
		ck_assert(json_is_string(json_object_get(item, "name")));
		ck_assert(json_is_array(json_object_get(item, "printers")));
	}
	json_decref(arr);
	ck_assert_int_eq(tu_run(out, sizeof(out), "ports --bogus"), 2);
}
END_TEST

/* Read from fd into buf until want appears or ms pass; 1 if it appeared. */
static int read_until(int fd, char *buf, size_t cap, const char *want, int ms)
{
	size_t n = strlen(buf);
	struct pollfd p = {.fd = fd, .events = POLLIN};

	while (ms > 0 && !strstr(buf, want)) {
		ssize_t got;

		if (poll(&p, 1, 100) > 0) {
			got = read(fd, buf + n, cap - 1 - n);
			if (got > 0)
				n += (size_t)got;
			buf[n] = '\0';
		}
		ms -= 100;
	}
	return strstr(buf, want) != NULL;
}

/* `stratum sim` end to end: the link appears, the firmware answers, SIGTERM
 * stops it cleanly and removes the link. */
START_TEST(sim_command_runs_and_cleans_up)
{
	const char *bin = getenv("STRATUM_BIN");
	char link[512], buf[4096] = "";
	struct termios tio;
	struct stat st;
	int fd = -1, status;
	pid_t pid;

	snprintf(link, sizeof(link), "%s", tu_path("printer"));
	pid = fork();
	ck_assert_int_ge(pid, 0);
	if (pid == 0) {
		int devnull = open("/dev/null", O_WRONLY);
		dup2(devnull, 1);
		execl(bin ? bin : "build/stratum", "stratum", "sim", "--dialect", "marlin", "--link",
		      link, "--speedup", "50", (char *)NULL);
		_exit(127);
	}
	for (int i = 0; i < 50 && fd < 0; i++) {
		fd = open(link, O_RDWR | O_NOCTTY);
		if (fd < 0)
			usleep(100 * 1000);
	}
	ck_assert_msg(fd >= 0, "the --link symlink never appeared");
	ck_assert_int_eq(tcgetattr(fd, &tio), 0);
	cfmakeraw(&tio);
	ck_assert_int_eq(tcsetattr(fd, TCSANOW, &tio), 0);
	ck_assert_msg(read_until(fd, buf, sizeof(buf), "start", 5000), "no boot banner: %s", buf);
	usleep(2000 * 1000); /* the board ignores input while it boots */
	buf[0] = '\0';
	ck_assert_int_eq(write(fd, "M105\n", 5), 5);
	ck_assert_msg(read_until(fd, buf, sizeof(buf), "ok T:", 5000), "no M105 reply: %s", buf);
	close(fd);
	ck_assert_int_eq(kill(pid, SIGTERM), 0);
	ck_assert_int_eq(waitpid(pid, &status, 0), pid);
	ck_assert_msg(WIFEXITED(status) && WEXITSTATUS(status) == 0, "status %d", status);
	ck_assert_msg(lstat(link, &st) != 0, "the symlink is still there");
}
END_TEST

/* `stratum send` end to end against `stratum sim --link` in the
 * background: the JSON report the benchmark reads, and the log equals the
 * file. */
START_TEST(send_json_to_sim)
{
	const char *gc = tu_path("send.gcode"), *link = tu_path("send-tty");
	const char *log = tu_path("send-sim.log");
	const char *bin = getenv("STRATUM_BIN") ? getenv("STRATUM_BIN") : "build/stratum";
	FILE *f = fopen(gc, "w");
	ck_assert_ptr_nonnull(f);
	fputs("; test job\nG21\nG90\n;LAYER:0\n", f);
	for (int i = 0; i < 2000; i++)
		fprintf(f, "G1 X%d.%d Y%d E0.01 ; move\n", 10 + i % 90, i % 10, 20 + i % 70);
	fclose(f);
	int rc = tu_run(out, sizeof(out),
			"sim --dialect marlin --baud 1000000 --speedup 100000 --link %s --log %s "
			">/dev/null & P=$!; for i in 1 2 3 4 5 6 7 8 9 10; do [ -e %s ] && break; "
			"sleep 0.1; done; %s send %s --port %s --printer generic-marlin --json; "
			"r=$?; kill $P; wait $P; exit $r",
			link, log, link, bin, gc, link);
	ck_assert_msg(rc == 0, "exit %d: %s", rc, out);
	json_error_t je;
	const char *brace = strchr(out, '{');
	ck_assert_msg(brace != NULL, "%s", out);
	json_t *o = json_loads(brace, JSON_DISABLE_EOF_CHECK, &je);
	ck_assert_msg(o != NULL, "bad JSON: %s", out);
	ck_assert(json_is_true(json_object_get(o, "ok")));
	ck_assert_int_eq(json_integer_value(json_object_get(o, "lines")), 2002);
	ck_assert_int_eq(json_integer_value(json_object_get(o, "resends")), 0);
	ck_assert_int_eq(json_integer_value(json_object_get(o, "errors")), 0);
	const char *keys[] = {"seconds", "bytes", "lines_per_s", "bytes_per_s", "link_fraction"};
	for (size_t i = 0; i < sizeof(keys) / sizeof(keys[0]); i++)
		ck_assert_msg(json_number_value(json_object_get(o, keys[i])) > 0, "%s", keys[i]);
	json_decref(o);
	/* every command once, in order, no comment sent */
	f = fopen(log, "r");
	ck_assert_ptr_nonnull(f);
	char line[256];
	int moves = 0, other = 0;
	while (fgets(line, sizeof(line), f)) {
		if (strstr(line, " G1 X"))
			moves++;
		else
			other++;
		ck_assert_msg(!strchr(line, ';'), "a comment reached the printer: %s", line);
	}
	fclose(f);
	ck_assert_int_eq(moves, 2000);
}
END_TEST

START_TEST(send_exit_codes)
{
	const char *gc = tu_path("ok.gcode"), *bad = tu_path("bad.gcode");
	tu_write_str(gc, "G28\nG1 X10\n");
	tu_write_str(bad, "G28\nG1 X10\nG1 X1.2.3\n");
	ck_assert_int_eq(tu_run(out, sizeof(out), "send %s --printer generic-marlin", gc), 2);
	ck_assert_int_eq(tu_run(out, sizeof(out), "send %s --port /dev/null --printer nosuch", gc),
			 2);
	ck_assert_int_eq(tu_run(out, sizeof(out),
				"send %s --port %s --printer generic-marlin", gc,
				tu_path("no-such-port")),
			 69);
	ck_assert_msg(strstr(out, "no-such-port"), "%s", out);
	ck_assert_int_eq(tu_run(out, sizeof(out), "send %s --port %s --printer generic-marlin",
				bad, tu_path("no-such-port")),
			 65);
	ck_assert_msg(strstr(out, "line 3") && strstr(out, "nothing was sent"), "%s", out);
	ck_assert_int_eq(tu_run(out, sizeof(out), "send %s --port %s --printer generic-marlin",
				tu_path("missing.gcode"), tu_path("no-such-port")),
			 65);
}
END_TEST

Suite *cli_suite(void)
{
	Suite *s = suite_create("cli");
	TCase *tc = tcase_create("check");

	tcase_set_timeout(tc, 60);
	tcase_add_test(tc, json_cube);
	tcase_add_test(tc, json_torus_genus);
	tcase_add_test(tc, json_open_cube_exit_1);
	tcase_add_test(tc, json_edge_sharing_cubes);
	tcase_add_test(tc, json_overlapping_cubes);
	tcase_add_test(tc, text_report);
	tcase_add_test(tc, usage_errors_exit_2);
	tcase_add_test(tc, options_one_table);
	tcase_add_test(tc, bad_inputs_exit_65);
	tcase_add_test(tc, ports_json);
	tcase_add_test(tc, sim_command_runs_and_cleans_up);
	tcase_add_test(tc, send_json_to_sim);
	tcase_add_test(tc, send_exit_codes);
	suite_add_tcase(s, tc);

	tc = tcase_create("repair");
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
	cli_stdio_tcases(s);
	return s;
}
