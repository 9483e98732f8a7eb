/*
 * check_cli.c - the built `stratum` binary end to end: exit statuses, the
 * `check --json` report on generated files, and one clear message naming
 * file and offset for every kind of bad input; ports, sim and send
 * (`stratum repair`, its outputs judged by `stratum check`: check_cli_repair.c).
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

#include "clitest.h"
#include "fixtures.h"
#include "meshio.h"
#include "suites.h"
#include "testutil.h"

static char out[1 << 16];

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

	cli_repair_tcases(s);
	cli_stdio_tcases(s);
	return s;
}
