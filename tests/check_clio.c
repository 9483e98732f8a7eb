/*
 * check_clio.c - "-" for stdin and stdout (host/clio.h) through the
 * binary: `repair - -o -` gives the bytes `repair IN -o OUT` writes, a
 * failing command writes nothing on stdout, binary data is refused for a
 * terminal; `print --json` answers with its object on early failures; and
 * `print --preview` without a port previews and stops.  Part of the cli
 * suite.
 */
#include <check.h>
#include <fcntl.h>
#include <jansson.h>
#include <limits.h>
#include <poll.h>
#include <pty.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "fixtures.h"
#include "meshio.h"
#include "suites.h"
#include "testutil.h"

static char out[1 << 16];

/* A 20 x 10 x 5 mm box as binary STL in the scratch directory. */
static const char *cube_stl(const char *name)
{
	const char *path = tu_path(name);
	struct mesh *m = fx_box(0, 0, 0, 20, 10, 5);
	struct st_error err = {0};

	ck_assert_msg(meshio_write_stl(path, m, MESHIO_STL_BINARY, &err) == 0, "%s", err.msg);
	mesh_free(m);
	return path;
}

/* Whether files a and b hold the same bytes (both must exist). */
static bool same_bytes(const char *a, const char *b)
{
	size_t na, nb;
	char *x = tu_slurp(a, &na), *y = tu_slurp(b, &nb);
	bool same = na == nb && !memcmp(x, y, na);

	free(x);
	free(y);
	return same;
}

static size_t file_size(const char *path)
{
	size_t n;
	free(tu_slurp(path, &n));
	return n;
}

START_TEST(repair_stdin_stdout_equals_file)
{
	char in[512], a[512], b[512], err[512];
	int rc;

	snprintf(in, sizeof(in), "%s", cube_stl("rio-in.stl"));
	snprintf(a, sizeof(a), "%s", tu_path("rio-a.stl"));
	snprintf(b, sizeof(b), "%s", tu_path("rio-b.stl"));
	snprintf(err, sizeof(err), "%s", tu_path("rio-b.err"));
	rc = tu_run(out, sizeof(out), "repair %s -o %s", in, a);
	ck_assert_msg(rc == 0, "exit %d: %s", rc, out);
	rc = tu_sh(out, sizeof(out), "{ '%s' repair - -o - <%s >%s 2>%s; }", tu_bin(), in, b, err);
	ck_assert_msg(rc == 0, "exit %d: %s", rc, out);
	ck_assert_msg(same_bytes(a, b), "repair - -o - wrote other bytes than repair IN -o OUT");
	/* the report moved to stderr and names stdout */
	ck_assert_int_eq(tu_sh(out, sizeof(out), "grep -q '^written: -$' %s", err), 0);
}
END_TEST

START_TEST(repair_failing_writes_nothing_on_stdout)
{
	char bad[512], o[512];
	int rc;

	snprintf(bad, sizeof(bad), "%s", tu_path("rio-bad.stl"));
	snprintf(o, sizeof(o), "%s", tu_path("rio-bad.out"));
	tu_write_str(bad, "solid x\n  facet normal 0 0 1\n    outer loop\n      vertex 0 0 zero\n");
	rc = tu_sh(out, sizeof(out), "{ '%s' repair - -o - <%s >%s; }", tu_bin(), bad, o);
	ck_assert_msg(rc == 65, "exit %d: %s", rc, out);
	ck_assert_uint_eq(file_size(o), 0);
	/* --json's answer goes to stderr too: stdout stays the data's */
	rc = tu_sh(out, sizeof(out), "{ '%s' repair - -o - --json <%s >%s 2>/dev/null; }",
		   tu_bin(), bad, o);
	ck_assert_int_eq(rc, 65);
	ck_assert_uint_eq(file_size(o), 0);
}
END_TEST

/* Run "stratum ARGS" with stdin from in, stdout a terminal, stderr into
 * err; its exit status, and whether anything reached the terminal. */
static int run_stdout_tty(const char *args, const char *in, const char *err, bool *wrote)
{
	int master, slave, status;
	char cmd[2048], buf[256];
	struct pollfd p;
	pid_t pid;

	ck_assert_int_eq(openpty(&master, &slave, NULL, NULL, NULL), 0);
	snprintf(cmd, sizeof(cmd), "exec '%s' %s <%s 2>%s", tu_bin(), args, in, err);
	pid = fork();
	ck_assert_int_ge(pid, 0);
	if (pid == 0) {
		dup2(slave, STDOUT_FILENO);
		close(master);
		close(slave);
		execl("/bin/sh", "sh", "-c", cmd, (char *)NULL);
		_exit(127);
	}
	close(slave);
	ck_assert_int_eq(waitpid(pid, &status, 0), pid);
	p.fd = master;
	p.events = POLLIN;
	*wrote = poll(&p, 1, 200) == 1 && read(master, buf, sizeof(buf)) > 0;
	close(master);
	return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

START_TEST(binary_to_terminal_refused)
{
	char in[512], err[512];
	bool wrote;
	int rc;

	snprintf(in, sizeof(in), "%s", cube_stl("rio-tty.stl"));
	snprintf(err, sizeof(err), "%s", tu_path("rio-tty.err"));
	rc = run_stdout_tty("repair - -o -", in, err, &wrote);
	ck_assert_int_eq(rc, 2);
	ck_assert(!wrote);
	ck_assert_int_eq(tu_sh(out, sizeof(out), "grep -q 'binary data to the terminal' %s", err),
			 0);
}
END_TEST

START_TEST(check_reads_stdin)
{
	json_t *o;
	int rc = tu_sh(out, sizeof(out), "{ '%s' check - --json <%s 2>/dev/null; }", tu_bin(),
		       cube_stl("rio-check.stl"));

	ck_assert_msg(rc == 0, "exit %d: %s", rc, out);
	o = json_loads(out, 0, NULL);
	ck_assert_msg(o != NULL, "not JSON: %s", out);
	ck_assert_int_eq(json_integer_value(json_object_get(o, "triangles")), 12);
	json_decref(o);
	/* stdin is read once */
	rc = tu_sh(out, sizeof(out), "'%s' slice - - -o - --printer generic-marlin </dev/null",
		   tu_bin());
	ck_assert_int_eq(rc, 2);
	ck_assert_ptr_nonnull(strstr(out, "given twice"));
}
END_TEST

START_TEST(slice_stdin_stdout)
{
	char in[512], a[512], b[512], err[512];
	size_t na, nb;
	char *x, *y;
	int rc;

	snprintf(in, sizeof(in), "%s", cube_stl("rio-slice.stl"));
	snprintf(a, sizeof(a), "%s", tu_path("rio-slice-a.gcode"));
	snprintf(b, sizeof(b), "%s", tu_path("rio-slice-b.gcode"));
	snprintf(err, sizeof(err), "%s", tu_path("rio-slice.err"));
	rc = tu_run(out, sizeof(out), "slice %s -o %s --printer generic-marlin", in, a);
	ck_assert_msg(rc == 0, "exit %d: %s", rc, out);
	rc = tu_sh(out, sizeof(out), "{ '%s' slice - -o - --printer generic-marlin <%s >%s 2>%s; }",
		   tu_bin(), in, b, err);
	ck_assert_msg(rc == 0, "exit %d: %s", rc, out);
	/* the same moves: the files differ at most in the names in the header */
	x = tu_slurp(a, &na);
	y = tu_slurp(b, &nb);
	ck_assert_ptr_nonnull(strstr(y, ";LAYER_CHANGE"));
	ck_assert_str_eq(strstr(x, ";LAYER_CHANGE"), strstr(y, ";LAYER_CHANGE"));
	free(x);
	free(y);
	ck_assert_int_eq(tu_sh(out, sizeof(out), "grep -q 'written: -' %s", err), 0);
	/* and preview draws a layer of the G-code on stdin */
	rc = tu_sh(out, sizeof(out), "{ '%s' preview - --layer 2 -o %s <%s; }", tu_bin(),
		   tu_path("rio-slice.svg"), b);
	ck_assert_msg(rc == 0, "exit %d: %s", rc, out);
	ck_assert(tu_file_exists(tu_path("rio-slice.svg")));
}
END_TEST

/* The last line of text that parses as a JSON object (NULL when none). */
static json_t *json_answer(char *text)
{
	char *line = NULL, *save = NULL;

	for (char *t = strtok_r(text, "\n", &save); t; t = strtok_r(NULL, "\n", &save))
		if (t[0] == '{')
			line = t;
	return line ? json_loads(line, 0, NULL) : NULL;
}

/* `print ARGS --json` with stderr dropped: the object, its exit status checked. */
static json_t *print_json_fails(const char *args, int want)
{
	json_t *o;
	int rc = tu_run(out, sizeof(out), "print %s --json 2>/dev/null", args);

	ck_assert_msg(rc == want, "print %s: exit %d, wanted %d: %s", args, rc, want, out);
	o = json_answer(out);
	ck_assert_msg(o != NULL, "print %s --json printed no object: '%s'", args, out);
	ck_assert(json_is_false(json_object_get(o, "ok")));
	ck_assert_int_eq(json_integer_value(json_object_get(o, "exit")), want);
	ck_assert_msg(json_string_length(json_object_get(o, "error")) > 0, "no error text");
	return o;
}

START_TEST(print_json_on_early_failures)
{
	json_t *o;

	setenv("STRATUM_STATE_DIR", tu_path("rio-state"), 1);
	o = print_json_fails("/nonexistent/model.stl --printer generic-marlin", 65);
	ck_assert_msg(strstr(json_string_value(json_object_get(o, "error")), "/nonexistent/model.stl"),
		      "error: %s", json_string_value(json_object_get(o, "error")));
	json_decref(o);
	o = print_json_fails("docs/examples/bracket.stl --printer no-such-printer", 2);
	ck_assert_ptr_nonnull(strstr(json_string_value(json_object_get(o, "error")), "no-such-printer"));
	json_decref(o);
	json_decref(print_json_fails("docs/examples/bracket.stl", 2));		/* no printer */
	json_decref(print_json_fails("docs/examples/bracket.stl --printer generic-marlin "
				     "--dry-run", 2));			/* no -o */
	json_decref(print_json_fails("--bogus", 2));				/* parser */
}
END_TEST

START_TEST(print_preview_stops_without_port)
{
	char dir[512], state[512], bin[PATH_MAX];
	json_t *o;
	int rc;

	ck_assert_ptr_nonnull(realpath(tu_bin(), bin)); /* the test runs it elsewhere */
	snprintf(dir, sizeof(dir), "%s", tu_path("rio-pv"));
	snprintf(state, sizeof(state), "%s", tu_path("rio-pv-state"));
	setenv("STRATUM_STATE_DIR", state, 1);
	ck_assert_int_eq(tu_sh(out, sizeof(out), "mkdir -p %s && cp %s %s/cube.stl", dir,
			       cube_stl("rio-pv.stl"), dir), 0);
	rc = tu_sh(out, sizeof(out), "cd %s && '%s' print cube.stl --printer generic-marlin "
		   "--preview --json 2>/dev/null", dir, bin);
	ck_assert_msg(rc == 0, "exit %d: %s", rc, out);
	o = json_answer(out);
	ck_assert_ptr_nonnull(o);
	ck_assert(json_is_false(json_object_get(o, "printed")));
	json_decref(o);
	ck_assert_int_eq(tu_sh(out, sizeof(out), "test -s %s/cube-layer1.png", dir), 0);
	/* a look keeps no job */
	ck_assert_int_eq(tu_sh(out, sizeof(out), "ls %s/jobs 2>/dev/null | wc -l", state), 0);
	ck_assert_int_eq(atoi(out), 0);
	/* --dry-run --preview draws what it wrote */
	ck_assert_int_eq(tu_sh(out, sizeof(out), "rm -f %s/*.png && cd %s && '%s' print cube.stl "
			       "--printer generic-marlin --dry-run -o cube.gcode --preview", dir, dir,
			       bin), 0);
	ck_assert_int_eq(tu_sh(out, sizeof(out), "test -s %s/cube-layer2.png", dir), 0);
}
END_TEST

START_TEST(print_model_from_stdin)
{
	char in[512], a[512], b[512];
	char *x, *y;
	int rc;

	setenv("STRATUM_STATE_DIR", tu_path("rio-pstate"), 1);
	snprintf(in, sizeof(in), "%s", cube_stl("rio-print.stl"));
	{ /* a header that starts like a word of G-code is still a model */
		size_t n;
		char *stl = tu_slurp(in, &n);
		memcpy(stl, "MeshLab", 7);
		tu_write(in, stl, n);
		free(stl);
	}
	snprintf(a, sizeof(a), "%s", tu_path("rio-print-a.gcode"));
	snprintf(b, sizeof(b), "%s", tu_path("rio-print-b.gcode"));
	rc = tu_run(out, sizeof(out), "print %s --printer generic-marlin --dry-run -o %s", in, a);
	ck_assert_msg(rc == 0, "exit %d: %s", rc, out);
	rc = tu_sh(out, sizeof(out), "'%s' print - --printer generic-marlin --dry-run -o %s <%s",
		   tu_bin(), b, in);
	ck_assert_msg(rc == 0, "exit %d: %s", rc, out);
	x = tu_slurp(a, &(size_t){0});
	y = tu_slurp(b, &(size_t){0});
	ck_assert_str_eq(strstr(x, ";LAYER_CHANGE"), strstr(y, ";LAYER_CHANGE"));
	free(x);
	free(y);
	/* G-code on stdin could not be resumed: refused */
	rc = tu_sh(out, sizeof(out), "'%s' print - --printer generic-marlin <%s", tu_bin(), a);
	ck_assert_msg(rc == 2 && strstr(out, "stdin holds G-code"), "exit %d: %s", rc, out);
}
END_TEST

void cli_stdio_tcases(Suite *s)
{
	TCase *tc = tcase_create("stdio");

	tcase_set_timeout(tc, 120);
	tcase_add_test(tc, repair_stdin_stdout_equals_file);
	tcase_add_test(tc, repair_failing_writes_nothing_on_stdout);
	tcase_add_test(tc, binary_to_terminal_refused);
	tcase_add_test(tc, check_reads_stdin);
	tcase_add_test(tc, slice_stdin_stdout);
	tcase_add_test(tc, print_json_on_early_failures);
	tcase_add_test(tc, print_preview_stops_without_port);
	tcase_add_test(tc, print_model_from_stdin);
	suite_add_tcase(s, tc);
}
