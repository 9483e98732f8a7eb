/*
 * check_print.c - `stratum print` end to end (issue 8): the binary prints
 * the bundled bracket on the built-in simulated Marlin and Sailfish
 * printers, whose execution logs (--sim-log) must hold every command of
 * the G-code once and in order; Ctrl-C ends with the stop sequence and
 * exit 130; an unplugged or reset printer (an external `stratum sim`)
 * gives exit 69 and a saved journal; a host killed mid-print resumes with
 * only the remaining layers, after reheating (on Marlin and on Sailfish,
 * where the X3G stream after the preamble must be the tail of the file's
 * own translation); --dry-run writes what
 * `stratum slice` writes.
 */
#include <check.h>
#include <dirent.h>
#include <jansson.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"
#include "fixtures.h"
#include "gcode.h"
#include "meshio.h"
#include "profile.h"
#include "resume.h"
#include "sfcheck.h"
#include "suites.h"
#include "testutil.h"
#include "x3g.h"

#define MODEL "docs/examples/bracket.stl"
#define MARLIN_PRINTER "generic-marlin"
#define SF_PRINTER "flashforge-creator-pro"

static char out[1 << 16];

/* A fresh state directory for this test's journals; its path in dir. */
static void state_dir(const char *name, char *dir, size_t cap)
{
	snprintf(dir, cap, "%s", tu_path(name));
	setenv("STRATUM_STATE_DIR", dir, 1);
}

/* A growing list of strings. */
struct strs {
	char **v;
	long *n; /* a number per string (line numbers) */
	size_t len, cap;
};

static void strs_add(struct strs *s, const char *text, long n)
{
	if (s->len == s->cap) {
		s->cap = s->cap ? 2 * s->cap : 1024;
		s->v = realloc(s->v, s->cap * sizeof(*s->v));
		s->n = realloc(s->n, s->cap * sizeof(*s->n));
		ck_assert(s->v && s->n);
	}
	s->v[s->len] = strdup(text);
	ck_assert_ptr_nonnull(s->v[s->len]);
	s->n[s->len++] = n;
}

static void strs_free(struct strs *s)
{
	for (size_t i = 0; i < s->len; i++)
		free(s->v[i]);
	free(s->v);
	free(s->n);
}

/*
 * The commands of a G-code file as the driver sends them (cleaned text),
 * with their file lines; only from file line `from` on.  *layer_line (may
 * be NULL) gets the file line where 0-based layer `layer` starts.
 */
static void gcode_commands(const char *path, uint64_t from, struct strs *s, long layer,
			   uint64_t *layer_line)
{
	FILE *f = fopen(path, "rb");
	struct gcode_reader *r;
	struct gcode_line g;
	struct st_error err = {0};
	long cur = -1;
	int rc;

	ck_assert_msg(f != NULL, "%s", path);
	ck_assert_int_eq(gcode_reader_new(f, path, &r, &err), 0);
	while ((rc = gcode_reader_next(r, 0, &g, &err)) == 1) {
		long l;
		if (gcode_layer_comment(&g, &l, NULL) == GCODE_LAYER_START) {
			cur = l >= 0 ? l : cur + 1;
			if (layer_line && cur == layer)
				*layer_line = gcode_reader_line(r);
		}
		if (g.kind == GCODE_KIND_HOST_ONLY || !g.text_len || gcode_reader_line(r) < from)
			continue;
		strs_add(s, g.text, (long)gcode_reader_line(r));
	}
	ck_assert_msg(rc == 0, "%s", err.msg);
	gcode_reader_free(r);
	fclose(f);
}

/* The simulated Marlin's execution log: "N text" (n) or "- text" (-1),
 * without the driver's own M105 probes (tu_marlin_log_next). */
static void marlin_log(const char *path, struct strs *s)
{
	FILE *f = fopen(path, "r");
	char line[512];
	const char *text;
	long n;

	ck_assert_msg(f != NULL, "%s", path);
	while (tu_marlin_log_next(f, line, sizeof(line), &n, &text))
		strs_add(s, text, n);
	fclose(f);
}

/* Index of the first log entry with text t at or after i, or len. */
static size_t strs_find(const struct strs *s, size_t i, const char *t)
{
	while (i < s->len && strcmp(s->v[i], t))
		i++;
	return i;
}

/*
 * log[k..] is exactly cmds, every line numbered one after the other (each
 * executed once, in order).
 */
static void check_tail(const struct strs *log, size_t k, const struct strs *cmds)
{
	ck_assert_msg(log->len - k == cmds->len, "%zu commands executed after the start, %zu "
		      "in the file", log->len - k, cmds->len);
	for (size_t i = 0; i < cmds->len; i++) {
		ck_assert_msg(!strcmp(log->v[k + i], cmds->v[i]), "command %zu (file line %ld): "
			      "executed '%s', the file has '%s'", i, cmds->n[i], log->v[k + i],
			      cmds->v[i]);
		ck_assert_msg(log->n[k + i] == log->n[k] + (long)i, "log entry %zu: line number "
			      "%ld, expected %ld", k + i, log->n[k + i], log->n[k] + (long)i);
	}
}

/* The one journal in the state directory dir. */
static json_t *load_journal(const char *dir, char *path, size_t cap)
{
	char jobs[600];
	struct dirent *e;
	DIR *d;
	json_error_t je;
	json_t *o;

	snprintf(jobs, sizeof(jobs), "%s/jobs", dir);
	d = opendir(jobs);
	ck_assert_msg(d != NULL, "%s", jobs);
	path[0] = '\0';
	while ((e = readdir(d)))
		if (strstr(e->d_name, ".json") && !strstr(e->d_name, ".tmp")) {
			ck_assert_msg(!path[0], "more than one journal in %s", jobs);
			snprintf(path, cap, "%s/%s", jobs, e->d_name);
		}
	closedir(d);
	ck_assert_msg(path[0], "no journal in %s", jobs);
	o = json_load_file(path, 0, &je);
	ck_assert_msg(o != NULL, "%s: %s", path, je.text);
	return o;
}

static const char *jstr(json_t *o, const char *k)
{
	const char *s = json_string_value(json_object_get(o, k));
	ck_assert_msg(s != NULL, "no string %s", k);
	return s;
}

static long jint(json_t *o, const char *k)
{
	json_t *v = json_object_get(o, k);
	ck_assert_msg(json_is_integer(v), "no integer %s", k);
	return (long)json_integer_value(v);
}

/* The last line of out that starts with '{', parsed. */
static json_t *last_json(void)
{
	const char *p = NULL;
	json_error_t je;
	json_t *o;

	for (const char *l = out; l && *l; l = strchr(l, '\n') ? strchr(l, '\n') + 1 : NULL)
		if (*l == '{')
			p = l;
	ck_assert_msg(p != NULL, "no JSON in: %s", out);
	o = json_loadb(p, strcspn(p, "\n"), 0, &je);
	ck_assert_msg(o != NULL, "%s: %s", je.text, p);
	return o;
}

/*
 * Proves that a profile that cannot slice stops `stratum print` at load
 * with exit 2, as it stops `stratum slice`, before anything is repaired
 * or sent (it used to give 65).
 */
START_TEST(test_unsliceable_profile_exit_2)
{
	char said[4096];
	const char *ini = tu_path("mps0.ini");

	tu_write_str(ini, "nozzle_diameter = 0.4\nmin_print_speed = 0\n");
	int rc = tu_run(said, sizeof(said), "print " MODEL " --printer %s", ini);
	ck_assert_msg(rc == 2, "exit %d: %s", rc, said);
	ck_assert_msg(strstr(said, "min_print_speed"), "%s", said);
	ck_assert_msg(!strstr(said, "repair"), "%s", said);
}
END_TEST

/* Two models print together on the simulated Marlin: one arranged job,
 * its log holding every command of the G-code once and in order. */
START_TEST(test_two_models_print_together)
{
	char dir[512], log[512], a[512], b[512];
	struct strs lg = {0}, cmds = {0};
	struct st_error err = {0};
	struct mesh *m;
	json_t *o;
	int rc;

	state_dir("st-two", dir, sizeof(dir));
	snprintf(log, sizeof(log), "%s", tu_path("two.log"));
	snprintf(a, sizeof(a), "%s", tu_path("two-a.stl"));
	snprintf(b, sizeof(b), "%s", tu_path("two-b.stl"));
	m = fx_box(0, 0, 0, 12, 12, 2);
	ck_assert_int_eq(meshio_write_stl(a, m, MESHIO_STL_BINARY, &err), 0);
	ck_assert_int_eq(meshio_write_stl(b, m, MESHIO_STL_BINARY, &err), 0);
	mesh_free(m);
	rc = tu_run(out, sizeof(out), "print %s %s --printer " MARLIN_PRINTER " --json "
		    "--sim-log %s 2>/dev/null", a, b, log);
	ck_assert_msg(rc == 0, "exit %d: %s", rc, out);
	o = last_json();
	ck_assert(json_is_true(json_object_get(o, "ok")));
	ck_assert_int_eq(json_array_size(json_object_get(o, "models")), 2);
	ck_assert_int_eq(jint(o, "last_line"), jint(o, "total"));
	gcode_commands(jstr(o, "gcode"), 0, &cmds, -1, NULL);
	marlin_log(log, &lg);
	check_tail(&lg, strs_find(&lg, 0, cmds.v[0]), &cmds);
	strs_free(&lg);
	strs_free(&cmds);
	json_decref(o);
}
END_TEST

START_TEST(test_marlin_prints_every_line_once)
{
	char dir[512], log[512], jpath[1024];
	struct strs lg = {0}, cmds = {0};
	json_t *o, *j;
	size_t k;
	int rc;

	state_dir("st-marlin", dir, sizeof(dir));
	snprintf(log, sizeof(log), "%s", tu_path("marlin.log"));
	rc = tu_run(out, sizeof(out), "print " MODEL " --printer " MARLIN_PRINTER " --json "
		    "--sim-log %s 2>/dev/null", log);
	ck_assert_msg(rc == 0, "exit %d: %s", rc, out);
	o = last_json();
	ck_assert(json_is_true(json_object_get(o, "ok")));
	ck_assert(json_is_true(json_object_get(o, "simulated")));
	ck_assert_int_eq(jint(o, "layers"), 150);
	ck_assert_int_eq(jint(o, "last_line"), jint(o, "total"));
	gcode_commands(jstr(o, "gcode"), 0, &cmds, -1, NULL);
	marlin_log(log, &lg);
	/* connecting (M110, M115, M155), then the file */
	k = strs_find(&lg, 0, cmds.v[0]);
	ck_assert_uint_le(k, 3);
	for (size_t i = 0; i < k; i++)
		ck_assert_msg(!strncmp(lg.v[i], "M11", 3) || !strncmp(lg.v[i], "M155", 4), "%s",
			      lg.v[i]);
	check_tail(&lg, k, &cmds);
	j = load_journal(dir, jpath, sizeof(jpath));
	ck_assert_str_eq(jstr(j, "state"), "done");
	ck_assert_int_eq(jint(j, "last_line"), jint(o, "total"));
	ck_assert_int_eq(strlen(jstr(j, "sha256")), 64);

	/* A finished job has nothing to resume; a changed file is refused. */
	rc = tu_run(out, sizeof(out), "print --resume %s --yes", jstr(j, "id"));
	ck_assert_msg(rc == 2 && strstr(out, "nothing to resume"), "exit %d: %s", rc, out);
	json_object_set_new(j, "state", json_string("cancelled"));
	ck_assert_int_eq(json_dump_file(j, jpath, 0), 0);
	FILE *f = fopen(jstr(o, "gcode"), "a");
	ck_assert_ptr_nonnull(f);
	fputs("; edited\n", f);
	fclose(f);
	rc = tu_run(out, sizeof(out), "print --resume %s --yes", jstr(j, "id"));
	ck_assert_msg(rc == 65 && strstr(out, "changed since the print started"), "exit %d: %s",
		      rc, out);
	json_decref(j);
	json_decref(o);
	strs_free(&lg);
	strs_free(&cmds);
}
END_TEST

/* The bundled model sliced for the Creator Pro into gc. */
static void sf_gcode(const char *gc)
{
	int rc = tu_run(out, sizeof(out), "print " MODEL " --printer " SF_PRINTER " --dry-run "
			"-o %s", gc);
	ck_assert_msg(rc == 0, "dry run: exit %d: %s", rc, out);
}

START_TEST(test_sailfish_prints_every_command_once)
{
	char dir[512], gc[512], x3g[512], dec[512], log[512], line[512];
	json_error_t je;
	size_t i = 0;
	int rc;

	state_dir("st-sf", dir, sizeof(dir));
	snprintf(gc, sizeof(gc), "%s", tu_path("sf.gcode"));
	snprintf(x3g, sizeof(x3g), "%s", tu_path("sf.x3g"));
	snprintf(dec, sizeof(dec), "%s", tu_path("sf.json"));
	snprintf(log, sizeof(log), "%s", tu_path("sf.log"));
	sf_gcode(gc);
	rc = tu_run(out, sizeof(out), "print %s --printer " SF_PRINTER " --sim-log %s", gc, log);
	ck_assert_msg(rc == 0, "exit %d: %s", rc, out);
	ck_assert_msg(strstr(out, "SIMULATION") && strstr(out, "printed "), "%s", out);
	rc = tu_run(out, sizeof(out), "x3g %s -o %s --printer " SF_PRINTER " && %s x3g --decode "
		    "%s --json >%s", gc, x3g, tu_bin(), x3g, dec);
	ck_assert_msg(rc == 0, "x3g: exit %d: %s", rc, out);
	json_t *o = json_load_file(dec, 0, &je);
	ck_assert_msg(o != NULL, "%s", je.text);
	json_t *cmds = json_object_get(o, "commands");
	ck_assert_uint_gt(json_array_size(cmds), 1000);
	FILE *f = fopen(log, "r");
	ck_assert_ptr_nonnull(f);
	while (fgets(line, sizeof(line), f)) {
		unsigned long long seq;
		unsigned code;
		ck_assert_msg(sscanf(line, "%llu %u", &seq, &code) == 2, "log: %s", line);
		ck_assert_msg(i < json_array_size(cmds), "more executed than sent: %s", line);
		ck_assert_uint_eq(seq, i + 1);
		ck_assert_int_eq(code, json_integer_value(json_object_get(json_array_get(cmds, i),
									  "code")));
		i++;
	}
	fclose(f);
	ck_assert_uint_eq(i, json_array_size(cmds));
	json_decref(o);
}
END_TEST

START_TEST(test_ctrl_c_stops_safely)
{
	char dir[512], log[512], jpath[1024];
	struct strs lg = {0};
	size_t k;
	int rc;

	state_dir("st-int", dir, sizeof(dir));
	snprintf(log, sizeof(log), "%s", tu_path("int.log"));
	rc = tu_run(out, sizeof(out), "print " MODEL " --printer " MARLIN_PRINTER " --speedup 200 "
		    "--sim-log %s >%s 2>&1 & P=$!; for i in $(seq 200); do grep -qs "
		    "'\"layer\": [2-9]' %s/jobs/*.json && break; sleep 0.05; done; "
		    "kill -INT $P; wait $P", log, tu_path("int.out"), dir);
	ck_assert_msg(rc == 130, "exit %d", rc);
	marlin_log(log, &lg);
	/* the stop sequence ends the log: quick stop, heaters, fan, motors off */
	k = strs_find(&lg, 0, "M410");
	ck_assert_msg(k < lg.len, "no M410 in the log");
	ck_assert_uint_lt(strs_find(&lg, k, "M104 S0"), lg.len);
	ck_assert_uint_lt(strs_find(&lg, k, "M140 S0"), lg.len);
	ck_assert_str_eq(lg.v[lg.len - 1], "M84");
	json_t *j = load_journal(dir, jpath, sizeof(jpath));
	ck_assert_str_eq(jstr(j, "state"), "cancelled");
	ck_assert_int_ge(jint(j, "layer"), 2);
	json_decref(j);
	strs_free(&lg);
}
END_TEST

/*
 * The simulated Marlin's log after a Ctrl-C during the heat-up (issue 17
 * defect 3): both waits (M190, then the M109 queued behind it) were broken,
 * each by its own M108 (Marlin's M108 ends only the wait that runs), and
 * the stop sequence ran after them: heaters off, fan off, motors off.
 */
static void check_heatup_stopped(const char *log)
{
	struct strs lg = {0};
	size_t k, n108 = 0;

	marlin_log(log, &lg);
	k = strs_find(&lg, 0, "M190 S60");
	ck_assert_msg(k < lg.len, "no M190 in the log");
	ck_assert_msg(strs_find(&lg, k, "M109 S210") < lg.len, "the M109 never ran");
	for (size_t i = k; i < lg.len; i++)
		n108 += !strcmp(lg.v[i], "M108");
	ck_assert_uint_ge(n108, 2);
	k = strs_find(&lg, k, "M104 S0");
	ck_assert_msg(k < lg.len, "the heaters were not switched off");
	ck_assert_uint_lt(strs_find(&lg, k, "M140 S0"), lg.len);
	ck_assert_uint_lt(strs_find(&lg, k, "M107"), lg.len);
	ck_assert_str_eq(lg.v[lg.len - 1], "M84");
	strs_free(&lg);
}

/* Ctrl-C while the bed heats, the nozzle's M109 queued behind (the bracket's
 * start G-code): every wait is broken, the stop confirmed, exit 130.  Heating
 * runs at twice real speed, so an unbroken M109 outlasts the 10 s stop. */
START_TEST(test_ctrl_c_during_heatup)
{
	char dir[512], log[512];
	int rc;

	state_dir("st-heat", dir, sizeof(dir));
	snprintf(log, sizeof(log), "%s", tu_path("heat.log"));
	rc = tu_run(out, sizeof(out), "print " MODEL " --printer " MARLIN_PRINTER " --speedup 2 "
		    "--sim-log %s >%s 2>&1 & P=$!; for i in $(seq 600); do grep -qs M190 %s "
		    "&& break; sleep 0.1; done; sleep 1; kill -INT $P; wait $P; r=$?; cat %s; "
		    "exit $r", log, tu_path("heat.out"), log, tu_path("heat.out"));
	ck_assert_msg(rc == 130, "exit %d: %s", rc, out);
	ck_assert_msg(strstr(out, "stopped safely"), "%s", out);
	check_heatup_stopped(log);
}
END_TEST

/* Print against an external `stratum sim FAULT`; returns print's status. */
static int print_external(const char *fault, const char *dir)
{
	char link[512];

	snprintf(link, sizeof(link), "%s", tu_path("tty-fault"));
	(void)dir;
	return tu_run(out, sizeof(out),
		      "sim --dialect marlin %s --speedup 1000 --baud 4000000 --link %s >/dev/null "
		      "2>&1 & S=$!; for i in $(seq 50); do [ -e %s ] && break; sleep 0.1; done; "
		      "%s print " MODEL " --printer " MARLIN_PRINTER " --port %s 2>&1; r=$?; "
		      "kill $S 2>/dev/null; wait $S; exit $r", fault, link, link, tu_bin(), link);
}

START_TEST(test_unplug_and_reset_exit_69)
{
	const char *faults[] = {"--unplug-at 2000", "--reset-at 2000"};

	for (int f = 0; f < 2; f++) {
		char dir[512], jpath[1024];
		state_dir(f ? "st-reset" : "st-unplug", dir, sizeof(dir));
		int rc = print_external(faults[f], dir);
		ck_assert_msg(rc == 69, "%s: exit %d: %s", faults[f], rc, out);
		ck_assert_msg(strstr(out, "the printer confirmed line") &&
				      strstr(out, "--resume"), "%s", out);
		json_t *j = load_journal(dir, jpath, sizeof(jpath));
		ck_assert_str_eq(jstr(j, "state"), "link-lost");
		ck_assert_int_gt(jint(j, "last_line"), 1000);
		ck_assert_int_gt(jint(j, "layer"), 5);
		json_decref(j);
	}
}
END_TEST

/*
 * Relative moves add up to positions no line can carry (issue 17, found by
 * fuzzing): the preamble once wrote "G1 X1800000000000000.000 ..." that our
 * own parser refuses.  resume_scan refuses such a state; below the bound,
 * every line of both preambles parses.
 */
START_TEST(test_resume_absurd_coordinates)
{
	static const char *const absurd[] = {
		"G91\nG1 X900000000000000\nG1 X900000000000000\nG1 X1\n",
		"G92 Z999999999.999\nG91\nG1 Z1\n",
		"M83\nG1 E999999999999999\nG1 E999999999999999\n",
		"G1 F999999999999999\n",
	};
	const char *path = tu_path("resume-absurd.gcode");
	char pre[RESUME_LINES][RESUME_LINE_MAX + 1];
	struct resume_state rs;
	struct st_error err = {0};

	for (size_t i = 0; i < sizeof(absurd) / sizeof(absurd[0]); i++) {
		tu_write_str(path, absurd[i]);
		ck_assert_int_eq(resume_scan(path, (int64_t)strlen(absurd[i]), &rs, &err),
				 ST_ERR_RANGE);
		ck_assert_msg(strstr(err.msg, "cannot be resumed"), "%s", err.msg);
	}
	/* The largest a resume takes: every line of both forms parses. */
	tu_write_str(path, "M140 S999999\nM104 S999999\nM106 S255\nG1 X-999999999.999 "
			   "Y999999999.999 Z999999997.5 E999999999.99999 F99999999\n");
	ck_assert_int_eq(resume_scan(path, 200, &rs, &err), 0);
	for (int form = 0; form < 3; form++) {
		size_t n = form == 2 ? resume_return(&rs, true, pre, RESUME_LINES)
			   : form ? resume_preamble_x3g(&rs, pre, RESUME_LINES)
				  : resume_preamble(&rs, pre, RESUME_LINES);

		ck_assert_uint_gt(n, 5);
		for (size_t k = 0; k < n; k++) {
			struct gcode_line g;

			ck_assert_msg(strlen(pre[k]) < RESUME_LINE_MAX, "%s", pre[k]);
			ck_assert_msg(!gcode_parse(pre[k], strlen(pre[k]), 0, &g, &err), "%s: %s",
				      pre[k], err.msg);
		}
	}
}
END_TEST

/* The way back after an operator's commands in a hold, before the file's
 * first move: no move (no place to go back to), only the file's modes,
 * E, feed rate (the default, 1500) and fan. */
START_TEST(test_resume_return_before_first_move)
{
	const char *path = tu_path("return.gcode");
	char back[RESUME_LINES][RESUME_LINE_MAX + 1], all[512] = "";
	struct resume_state rs;
	struct st_error err = {0};
	size_t n, len = 0;

	tu_write_str(path, "M83\nM106 S255\n");
	ck_assert_int_eq(resume_scan(path, 100, &rs, &err), 0);
	n = resume_return(&rs, true, back, RESUME_LINES);
	for (size_t i = 0; i < n; i++)
		len += (size_t)snprintf(all + len, sizeof(all) - len, "%s\n", back[i]);
	ck_assert_str_eq(all, "G90\nM83\nG92 E0.00000\nG1 F1500\nM106 S255\n");
}
END_TEST

/* The Z of the last G0/G1 with Z (absolute, as the slicer writes) at or
 * before file line `line` of path: where the nozzle stands once the
 * printer ran that line. */
static double nozzle_z_at(const char *path, uint64_t line)
{
	FILE *f = fopen(path, "rb");
	struct gcode_reader *r;
	struct gcode_line g;
	struct st_error err = {0};
	double z = NAN, v;

	ck_assert_ptr_nonnull(f);
	ck_assert_int_eq(gcode_reader_new(f, path, &r, &err), 0);
	while (gcode_reader_line(r) < line && gcode_reader_next(r, 0, &g, &err) == 1)
		if (g.letter == 'G' && (g.number == 0 || g.number == 1) &&
		    gcode_word_value(&g, 'Z', &v))
			z = v;
	gcode_reader_free(r);
	fclose(f);
	return z;
}

/* A resume from a layer start while the nozzle is already in that layer:
 * both preambles set Z where the nozzle is (its last move), not at the
 * layer below, and never go lower than it (issue 17 defect 4). */
START_TEST(test_resume_z_is_the_nozzles)
{
	static const char gc[] = "G90\nG1 Z0.3 F600\nG1 X5 E1\n;LAYER_CHANGE\n;Z:0.6\n"
				 "G1 Z0.6\nG1 X10 E2\n";
	const char *path = tu_path("resume-z.gcode");
	char pre[RESUME_LINES][RESUME_LINE_MAX + 1], text[RESUME_TEXT_MAX];
	struct resume_state rs;
	struct st_error err = {0};
	int64_t layer = (int64_t)(strstr(gc, ";LAYER") - gc);

	tu_write_str(path, gc);
	ck_assert_int_eq(resume_locate(path, layer, (int64_t)strlen(gc), &rs, &err), 0);
	ck_assert(fabs(rs.z - 0.3) < 1e-9 && fabs(rs.z_nozzle - 0.6) < 1e-9);
	size_t n = resume_preamble(&rs, pre, RESUME_LINES), g92 = n, down = n;
	for (size_t i = 0; i < n; i++) {
		g92 = !strcmp(pre[i], "G92 Z0.600") ? i : g92;
		down = !strcmp(pre[i], "G1 Z0.600 F600") ? i : down;
	}
	ck_assert_msg(g92 < n && down < n && g92 < down, "G92 Z or the way down is wrong");
	ck_assert_int_eq(resume_x3g_text(path, layer, (int64_t)strlen(gc), text, &err), 0);
	ck_assert_msg(strstr(text, "G92 X0 Y0 Z0.600 A0 B0\n") && strstr(text, "G1 Z0.600 F600\n"),
		      "%s", text);
	/* nothing executed past the layer start: the Z there */
	ck_assert_int_eq(resume_locate(path, layer, 0, &rs, &err), 0);
	ck_assert(fabs(rs.z_nozzle - 0.3) < 1e-9);
}
END_TEST

START_TEST(test_resume_after_kill)
{
	char dir[512], log[512], log2[512], jpath[1024];
	struct strs lg = {0}, cmds = {0};
	uint64_t start = 0;
	long layer;
	size_t k, pre;
	int rc;

	state_dir("st-kill", dir, sizeof(dir));
	snprintf(log, sizeof(log), "%s", tu_path("kill.log"));
	snprintf(log2, sizeof(log2), "%s", tu_path("resume.log"));
	rc = tu_run(out, sizeof(out), "print " MODEL " --printer " MARLIN_PRINTER " --speedup 200 "
		    "--sim-log %s >/dev/null 2>&1 & P=$!; for i in $(seq 200); do grep -qs "
		    "'\"layer\": [5-9]' %s/jobs/*.json && break; sleep 0.05; done; "
		    "kill -KILL $P; wait $P", log, dir);
	ck_assert_msg(rc == 137, "exit %d", rc);
	json_t *j = load_journal(dir, jpath, sizeof(jpath));
	ck_assert_str_eq(jstr(j, "state"), "printing");
	layer = jint(j, "layer");
	ck_assert_int_ge(layer, 5);

	/* without an answer nothing is sent */
	rc = tu_run(out, sizeof(out), "print --resume %s </dev/null", jstr(j, "id"));
	ck_assert_msg(rc == 1 && strstr(out, "--yes"), "exit %d: %s", rc, out);
	rc = tu_run(out, sizeof(out), "print --resume %s --yes --json --sim-log %s 2>/dev/null",
		    jstr(j, "id"), log2);
	ck_assert_msg(rc == 0, "exit %d: %s", rc, out);
	json_t *o = last_json();
	ck_assert_int_eq(jint(o, "resumed_from_layer"), layer + 1);

	/* the simulator saw: connect, reheat and home X/Y, then the file from
	 * the start of the last confirmed layer on, once each, in order */
	gcode_commands(jstr(j, "gcode"), 0, &cmds, layer, &start);
	ck_assert_uint_gt(start, 0);
	strs_free(&cmds);
	memset(&cmds, 0, sizeof(cmds));
	gcode_commands(jstr(j, "gcode"), start, &cmds, -1, NULL);
	marlin_log(log2, &lg);
	pre = strs_find(&lg, 0, "G28 X Y");
	ck_assert_uint_lt(pre, lg.len);
	ck_assert_uint_lt(strs_find(&lg, 0, "M190 S60"), pre);
	for (size_t i = 0; i < lg.len; i++)
		ck_assert_msg(strcmp(lg.v[i], "G28") && strncmp(lg.v[i], "G28 Z", 5),
			      "Z was homed: %s", lg.v[i]);
	k = strs_find(&lg, pre, "M109 S205");
	ck_assert_uint_lt(k, lg.len);
	/* Z is set where the nozzle stands, the last move it ran (issue 17
	 * defect 4: it was the layer below's, and every later layer printed
	 * one layer high) */
	double zn = nozzle_z_at(jstr(j, "gcode"), (uint64_t)jint(j, "last_line")), zset = NAN;
	for (size_t i = 0; i < pre; i++)
		if (!strncmp(lg.v[i], "G92 Z", 5))
			zset = atof(lg.v[i] + 5);
	ck_assert_msg(fabs(zset - zn) < 1e-6, "G92 Z%.3f while the nozzle is at %.3f", zset, zn);
	/* the preamble ends with the modes, E, feed rate and fan; the file follows */
	while (k < lg.len && lg.len - k > cmds.len)
		k++;
	check_tail(&lg, k, &cmds);
	json_decref(o);
	json_decref(j);
	strs_free(&lg);
	strs_free(&cmds);
}
END_TEST

START_TEST(test_sailfish_resume_after_kill)
{
	char dir[512], gc[512], tty[512], log[512], log2[512], jpath[1024];
	uint64_t first = 0;
	struct strs none = {0};
	long layer;
	double z;
	int rc;

	state_dir("st-sfkill", dir, sizeof(dir));
	snprintf(gc, sizeof(gc), "%s", tu_path("sfk.gcode"));
	snprintf(tty, sizeof(tty), "%s", tu_path("tty-sfk"));
	snprintf(log, sizeof(log), "%s", tu_path("sfk1.log"));
	snprintf(log2, sizeof(log2), "%s", tu_path("sfk2.log"));
	sf_gcode(gc);
	/* print to an external simulator; kill -9 the host at layer 5 or later */
	rc = tu_run(out, sizeof(out),
		    "sim --dialect sailfish --speedup 200 --baud 4000000 --link %s --log %s "
		    ">/dev/null 2>&1 & S=$!; for i in $(seq 50); do [ -e %s ] && break; sleep 0.1; "
		    "done; %s print %s --printer " SF_PRINTER " --port %s >/dev/null 2>&1 & P=$!; "
		    "for i in $(seq 600); do grep -qs '\"layer\": [5-9]' %s/jobs/*.json && break; "
		    "sleep 0.05; done; kill -KILL $P; wait $P; r=$?; kill $S; wait $S; exit $r",
		    tty, log, tty, tu_bin(), gc, tty, dir);
	ck_assert_msg(rc == 137, "exit %d: %s", rc, out);
	json_t *j = load_journal(dir, jpath, sizeof(jpath));
	ck_assert_str_eq(jstr(j, "state"), "printing");
	layer = jint(j, "layer");
	ck_assert_int_ge(layer, 5);

	/* resume on a fresh simulator */
	rc = tu_run(out, sizeof(out),
		    "sim --dialect sailfish --speedup 1000 --baud 4000000 --link %s --log %s "
		    ">/dev/null 2>&1 & S=$!; for i in $(seq 50); do [ -e %s ] && break; sleep 0.1; "
		    "done; %s print --resume %s --yes --json --port %s 2>/dev/null; r=$?; kill $S; "
		    "wait $S; exit $r", tty, log2, tty, tu_bin(), jstr(j, "id"), tty);
	ck_assert_msg(rc == 0, "resume: exit %d: %s", rc, out);
	json_t *o = last_json();
	ck_assert_int_eq(jint(o, "resumed_from_layer"), layer + 1);

	/* the file's translation from the start of that layer on ... */
	gcode_commands(gc, 0, &none, layer, &first);
	ck_assert_uint_gt(first, 0);
	z = sfc_check_resumed(gc, first, log2);
	ck_assert_msg(z > 0 && z <= jint(j, "layer") * 0.2 + 0.25 + 1e-9, "Z set to %g", z);
	json_decref(o);
	json_decref(j);
	strs_free(&none);
}
END_TEST

START_TEST(test_dry_run_is_slice)
{
	char a[512], b[512];
	int rc;

	state_dir("st-dry", a, sizeof(a));
	snprintf(a, sizeof(a), "%s", tu_path("slice.gcode"));
	snprintf(b, sizeof(b), "%s", tu_path("dry.gcode"));
	rc = tu_run(out, sizeof(out), "slice " MODEL " -o %s --printer " MARLIN_PRINTER, a);
	ck_assert_msg(rc == 0, "slice: exit %d: %s", rc, out);
	rc = tu_run(out, sizeof(out), "print " MODEL " --printer " MARLIN_PRINTER " --dry-run -o %s",
		    b);
	ck_assert_msg(rc == 0 && strstr(out, "nothing was printed"), "exit %d: %s", rc, out);
	rc = tu_run(out, sizeof(out), "print " MODEL " --printer " MARLIN_PRINTER " --dry-run "
		    "2>&1; cmp %s %s", a, b);
	ck_assert_msg(rc == 0 && strstr(out, "--dry-run needs -o OUT"), "exit %d: %s", rc, out);
}
END_TEST

/* The settings options of `stratum slice` take effect on print too (issue 18
 * item 5): the G-code is what slice writes with the same options. */
START_TEST(test_settings_options_as_slice)
{
	char a[512], b[512];
	int rc;

	snprintf(a, sizeof(a), "%s", tu_path("slice-set.gcode"));
	snprintf(b, sizeof(b), "%s", tu_path("dry-set.gcode"));
	rc = tu_run(out, sizeof(out), "slice " MODEL " -o %s --printer " MARLIN_PRINTER
		    " --layer-height 0.3 --set bed_temperature=55 --brim-width 3", a);
	ck_assert_msg(rc == 0, "slice: exit %d: %s", rc, out);
	rc = tu_run(out, sizeof(out), "print " MODEL " --printer " MARLIN_PRINTER " --dry-run -o %s"
		    " --layer-height 0.3 --set bed_temperature=55 --brim-width 3 && cmp %s %s",
		    b, a, b);
	ck_assert_msg(rc == 0, "exit %d: %s", rc, out);
	size_t len;
	char *text = tu_slurp(b, &len);
	ck_assert(strstr(text, "\n; layer_height = 0.3\n") &&
		  strstr(text, "\nM140 S55 ; set bed temperature"));
	free(text);
	rc = tu_run(out, sizeof(out), "print " MODEL " --printer " MARLIN_PRINTER " --dry-run -o %s"
		    " --layer-height 5", b);
	ck_assert_msg(rc == 2 && strstr(out, "stratum print: --layer-height: layer_height: 5 is "
					     "out of range"),
		      "exit %d: %s", rc, out);
}
END_TEST

Suite *print_suite(void)
{
	Suite *s = suite_create("print");
	TCase *tc = tcase_create("end to end");

	tcase_set_timeout(tc, 120);
	tcase_add_test(tc, test_dry_run_is_slice);
	tcase_add_test(tc, test_settings_options_as_slice);
	tcase_add_test(tc, test_unsliceable_profile_exit_2);
	tcase_add_test(tc, test_marlin_prints_every_line_once);
	tcase_add_test(tc, test_two_models_print_together);
	tcase_add_test(tc, test_sailfish_prints_every_command_once);
	tcase_add_test(tc, test_ctrl_c_stops_safely);
	tcase_add_test(tc, test_ctrl_c_during_heatup);
	tcase_add_test(tc, test_unplug_and_reset_exit_69);
	tcase_add_test(tc, test_resume_absurd_coordinates);
	tcase_add_test(tc, test_resume_z_is_the_nozzles);
	tcase_add_test(tc, test_resume_return_before_first_move);
	tcase_add_test(tc, test_resume_after_kill);
	tcase_add_test(tc, test_sailfish_resume_after_kill);
	suite_add_tcase(s, tc);
	return s;
}
