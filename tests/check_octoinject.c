/*
 * check_octoinject.c - an operator's commands inside a print (docs/serve.md,
 * "Commands during a print"), part of the octoapi suite: on the simulated
 * Creator Pro (Sailfish) a command posted while the job streams is
 * translated with the job's own translator and runs once between two of
 * the job's commands, which all run once, in order, at the positions a
 * translation of the file alone gives; temperature offsets reach the
 * file's heater targets; and on both dialects commands posted while the
 * job is paused run, after which the head goes back where the job left
 * it and the job continues, whole and in order.
 */
#include <check.h>
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "servetest.h"
#include "sfcheck.h"
#include "suites.h"
#include "testutil.h"

#define CTL "X-Api-Key: " KEY_CTL
#define CREATOR "[printer cp]\nprofile = " SFC_PRINTER "\nport = sim\nsim_speedup = 40\n"
#define MK3S "[printer mk3s]\nprofile = prusa-i3-mk3s\nport = sim\nsim_speedup = 40\n"
#define JOB_MOVES 60

/* A job of slow moves with relative extrusion (M83, as PrusaSlicer writes). */
static char *moves_job(void)
{
	size_t cap = 16 * 1024, len = 0;
	char *job = malloc(cap);

	ck_assert_ptr_nonnull(job);
	len += (size_t)snprintf(job + len, cap - len,
				"M117 job start\nG90\nM83\nG92 X0 Y0 Z0 E0\nG1 Z0.3 F600\n");
	for (int k = 0; k < JOB_MOVES; k++)
		len += (size_t)snprintf(job + len, cap - len, "G1 X%d Y%d E0.05 F60\n",
					10 + k % 2, 10 + k / 2);
	snprintf(job + len, cap - len, "M117 job end\n");
	return job;
}

/* Start printing job as name on the node's only printer; wait until it streams. */
static void print_started(struct node_proc *np, const char *name, const char *job)
{
	double pos = 0;
	json_t *o;

	ck_assert(sv_print_text(np->port, "", name, job) == 1);
	sv_wait_state(np->port, "", 1, "printing", 10);
	for (int i = 0; i < 250 && pos <= 0; i++) {
		o = sv_get_json(np->port, "/api/job");
		pos = json_number_value(json_object_get(json_object_get(o, "progress"), "filepos"));
		json_decref(o);
		usleep(20000);
	}
	ck_assert_msg(pos > 0, "the job did not start streaming");
}

/* Pause the job and wait until the printer holds (OctoPrint's "Paused"). */
static void paused(int port)
{
	char state[64] = "";
	json_t *o;

	sv_expect(port, "POST", "/api/job", CTL, "{\"command\":\"pause\",\"action\":\"pause\"}", 204);
	for (int i = 0; i < 500 && strcmp(state, "Paused"); i++) {
		o = sv_get_json(port, "/api/job");
		snprintf(state, sizeof(state), "%s", sv_str(o, "state"));
		json_decref(o);
		usleep(20000);
	}
	ck_assert_str_eq(state, "Paused");
}

/* What an operator does while a job is paused: a jog, an extrusion (which
 * leaves absolute extrusion behind, as OctoPrint's does) and a target. */
static void operate_paused(int port)
{
	sv_expect(port, "POST", "/api/printer/printhead", CTL,
		  "{\"command\":\"jog\",\"x\":10,\"y\":5,\"speed\":3000}", 204);
	sv_expect(port, "POST", "/api/printer/tool", CTL,
		  "{\"command\":\"extrude\",\"amount\":2}", 204);
	sv_expect(port, "POST", "/api/printer/tool", CTL,
		  "{\"command\":\"target\",\"targets\":{\"tool0\":190}}", 204);
}

/* Start a node of the one printer printers, print job as name, pause,
 * operate, resume, and wait until the job is done. */
static void print_paused_operated(struct node_proc *np, const char *printers, const char *name,
				  const char *job)
{
	sv_write_config(np, printers, 8);
	sv_start(np);
	sv_operational(np->port, "");
	print_started(np, name, job);
	paused(np->port);
	operate_paused(np->port);
	usleep(300000);
	sv_expect(np->port, "POST", "/api/job", CTL,
		  "{\"command\":\"pause\",\"action\":\"resume\"}", 204);
	sv_wait_state(np->port, "", 1, "done", 30);
}

/* ---- Sailfish ---------------------------------------------------------------- */

/* One command of the simulator's log: code, the five axes in steps, rate. */
struct sf_logged {
	unsigned code;
	bool has_pos;
	long pos[5], rate;
	char text[160];
};

static bool sf_read(FILE *f, struct sf_logged *c)
{
	char line[512];
	const char *p;

	do {
		if (!fgets(line, sizeof(line), f))
			return false;
	} while (line[0] < '0' || line[0] > '9'); /* "- ..." and "# ..." notes */
	memset(c, 0, sizeof(*c));
	snprintf(c->text, sizeof(c->text), "%.150s", line);
	ck_assert_msg(sscanf(line, "%*u %u", &c->code) == 1, "log line: %s", line);
	if ((p = strstr(line, " X=")))
		c->has_pos = sscanf(p, " X=%ld Y=%ld Z=%ld A=%ld B=%ld", &c->pos[0], &c->pos[1],
				    &c->pos[2], &c->pos[3], &c->pos[4]) == 5;
	if ((p = strstr(line, " rate=")))
		c->rate = atol(p + 6);
	return true;
}

/* Whether logged command c is reference command r, positions and rate alike. */
static bool sf_same(const struct sf_logged *c, json_t *r)
{
	static const char *const axes[] = {"x", "y", "z", "a", "b"};
	json_t *fields = json_object_get(r, "fields");

	if (c->code != json_integer_value(json_object_get(r, "code")))
		return false;
	/* X, Y, Z exact; the extruders' relative steps within one, as their
	 * fractions carry over an operator's extrusion */
	for (int i = 0; c->has_pos && i < 5; i++)
		if (labs(c->pos[i] - (long)json_number_value(json_object_get(fields, axes[i]))) >
		    (i < 3 ? 0 : 1))
			return false;
	return c->code != 155 ||
	       c->rate == (long)json_number_value(json_object_get(fields, "dda_rate"));
}

/*
 * Read the simulator's log f against cmds, the file's commands as `stratum
 * x3g` translates it: every one once, in order, the same; whatever else ran
 * ran between two of them, copied into extra (at most cap), in *blocks
 * runs; *before is the index of the job's command right before the first.
 * Returns how many ran.
 */
static size_t sf_job_and_extra(FILE *f, json_t *cmds, struct sf_logged *extra, size_t cap,
			       size_t *blocks, size_t *before)
{
	size_t n = json_array_size(cmds), i = 0, k = 0, at = SIZE_MAX;
	struct sf_logged c;

	*blocks = 0;
	*before = SIZE_MAX;
	while (sf_read(f, &c)) {
		if (i < n && sf_same(&c, json_array_get(cmds, i))) {
			i++;
			continue;
		}
		if ((c.code == 153 && i == 0) || (c.code == 154 && i == n))
			continue; /* the build the node frames a file without one in */
		ck_assert_msg(i > 0 && i < n && k < cap, "command %zu of the job: '%s' ran, not one of "
			      "the job's, and not between two of them", i, c.text);
		if (!k)
			*before = i - 1;
		*blocks += at != i;
		at = i;
		extra[k++] = c;
	}
	ck_assert_msg(i == n, "%zu of the job's %zu commands ran in order", i, n);
	return k;
}

/* The job's commands as the stream's translator gives them, from the file. */
static json_t *sf_reference(const char *job)
{
	tu_write_str(tu_path("inject.gcode"), job);
	return sfc_reference(tu_path("inject.gcode"), tu_path("inject.x3g"),
			     tu_path("inject.json"), JOB_MOVES);
}

static FILE *sf_log(const struct node_proc *np)
{
	char path[600];
	FILE *f;

	snprintf(path, sizeof(path), "%s/data/sim/cp.log", np->dir);
	f = fopen(path, "r");
	ck_assert_msg(f, "no %s", path);
	return f;
}

/*
 * Targets posted while a Creator Pro prints: each becomes one tool action
 * between two of the job's commands (tool 1's target for tool 1, the file's
 * tool left as it was), the job's commands once each, in order, at the
 * positions and rates of the file alone; the print head stays 409.
 */
START_TEST(test_sailfish_command_during_print)
{
	struct node_proc np;
	struct sf_logged extra[8];
	char *job = moves_job();
	json_t *cmds = sf_reference(job);
	size_t n, blocks, before;
	FILE *f;

	sv_write_config(&np, CREATOR, 8);
	sv_start(&np);
	sv_operational(np.port, "");
	print_started(&np, "inject.gcode", job);
	sv_expect(np.port, "POST", "/api/printer/tool", CTL,
		  "{\"command\":\"target\",\"targets\":{\"tool1\":150}}", 204);
	sv_expect(np.port, "POST", "/api/printer/command", CTL, "{\"command\":\"M140 S50\"}", 204);
	sv_expect(np.port, "POST", "/api/printer/printhead", CTL,
		  "{\"command\":\"jog\",\"x\":10}", 409);
	sv_wait_state(np.port, "", 1, "done", 30);
	f = sf_log(&np);
	n = sf_job_and_extra(f, cmds, extra, 8, &blocks, &before);
	fclose(f);
	/* the two may land in one gap or two; each ran once */
	ck_assert_msg(n == 2 && strstr(extra[0].text, " 136 tool action tool=1 cmd=3 ") &&
		      strstr(extra[0].text, " value=150") &&
		      strstr(extra[1].text, " 136 tool action tool=0 cmd=31 ") &&
		      strstr(extra[1].text, " value=50"), "%zu: %s%s", n, extra[0].text,
		      n > 1 ? extra[1].text : "");
	json_decref(cmds);
	free(job);
	sv_stop(&np);
}
END_TEST

/* The Creator Pro's offsets reach the file's targets; a heater the file
 * turns off stays off. */
START_TEST(test_sailfish_temperature_offsets)
{
	struct node_proc np;
	char path[600], *log;
	size_t len;

	sv_write_config(&np, "[printer cp]\nprofile = " SFC_PRINTER "\nport = sim\n"
			     "sim_speedup = 1000\n", 8);
	sv_start(&np);
	sv_operational(np.port, "");
	sv_expect(np.port, "POST", "/api/printer/tool", CTL,
		  "{\"command\":\"offset\",\"offsets\":{\"tool0\":10}}", 204);
	sv_expect(np.port, "POST", "/api/printer/bed", CTL, "{\"command\":\"offset\",\"offset\":-5}",
		  204);
	ck_assert(sv_print_text(np.port, "", "temps.gcode",
				"M104 S200 T0\nM140 S60\nG4 P10\nM104 S0 T0\nM140 S0\n") == 1);
	sv_wait_state(np.port, "", 1, "done", 20);
	snprintf(path, sizeof(path), "%s/data/sim/cp.log", np.dir);
	log = tu_slurp(path, &len);
	ck_assert_msg(strstr(log, " tool=0 cmd=3 len=2 value=210\n") &&
		      strstr(log, " tool=0 cmd=31 len=2 value=55\n") &&
		      strstr(log, " tool=0 cmd=3 len=2 value=0\n") &&
		      strstr(log, " tool=0 cmd=31 len=2 value=0\n") &&
		      !strstr(log, " value=200\n") && !strstr(log, " value=60\n"),
		      "the offsets were not applied: %s", log);
	free(log);
	sv_stop(&np);
}
END_TEST

/*
 * Commands while a Creator Pro's job is paused run then, and the job goes
 * on from where it was: its commands once each, in order, at the positions
 * and rates of the file alone (its relative extrusion kept; the extruders
 * within a step), and the last move before them ends where the job's
 * command before the block did.
 */
START_TEST(test_sailfish_paused_commands)
{
	struct node_proc np;
	struct sf_logged extra[64], *last = NULL;
	char *job = moves_job();
	json_t *cmds = sf_reference(job), *prev;
	size_t n, blocks, before, moves = 0;
	FILE *f;

	print_paused_operated(&np, CREATOR, "inject.gcode", job);
	f = sf_log(&np);
	n = sf_job_and_extra(f, cmds, extra, 64, &blocks, &before);
	ck_assert_msg(blocks == 1, "what ran while paused ran in %zu places", blocks);
	fclose(f);
	for (size_t i = 0; i < n; i++)
		if (extra[i].code == 155) {
			moves++;
			last = &extra[i];
		}
	/* the jog, the extrusion, and the way back: up, over, down */
	ck_assert_msg(moves == 5 && last == &extra[n - 1], "%zu moves, the last: %s", moves,
		      extra[n - 1].text);
	prev = json_object_get(json_array_get(cmds, before), "fields");
	ck_assert_msg(last->pos[0] == (long)json_number_value(json_object_get(prev, "x")) &&
		      last->pos[1] == (long)json_number_value(json_object_get(prev, "y")) &&
		      last->pos[2] == (long)json_number_value(json_object_get(prev, "z")),
		      "the head went back to %ld %ld %ld, not where the job left it", last->pos[0],
		      last->pos[1], last->pos[2]);
	json_decref(cmds);
	free(job);
	sv_stop(&np);
}
END_TEST

/* ---- Marlin ------------------------------------------------------------------ */

/*
 * The same on a Marlin printer: the simulator's log holds the job's lines
 * once each and in order; between two of them, the operator's lines and
 * then the way back to the X and Y of the job's line before them, with the
 * job's relative extrusion (M83) and feed rate restored.
 */
/* The log walk of test_marlin_paused_commands: the job's lines, once
 * each and in order, and what else ran, in one block between two of them. */
struct job_and_block {
	const char *job, *rest; /* the job's text, and its lines still due */
	char prev[96];		/* the job's line before the block */
	char block[4096];
	size_t blen;
	bool closed;		/* a job line ran after the block */
};

static void job_and_block_line(void *ctx, const char *text)
{
	struct job_and_block *w = ctx;
	size_t tl = strlen(text);

	if (*w->rest && !strncmp(w->rest, text, tl) && w->rest[tl] == '\n') {
		w->closed = w->blen > 0;
		if (!w->blen)
			snprintf(w->prev, sizeof(w->prev), "%s", text);
		w->rest += tl + 1;
		return;
	}
	ck_assert_msg(!w->closed && w->rest != w->job && *w->rest,
		      "'%s' ran outside one block between two of the job's lines", text);
	w->blen += (size_t)snprintf(w->block + w->blen, sizeof(w->block) - w->blen, "%s\n", text);
}

START_TEST(test_marlin_paused_commands)
{
	struct node_proc np;
	struct job_and_block *w = calloc(1, sizeof(*w));
	char path[600], *job = moves_job(), want[256];
	int x = 0, y = 0;

	ck_assert_ptr_nonnull(w);
	print_paused_operated(&np, MK3S, "moves.gcode", job);
	snprintf(path, sizeof(path), "%s/data/sim/mk3s.log", np.dir);
	w->job = w->rest = job;
	sv_marlin_log(path, "M117 job start", job_and_block_line, w);
	ck_assert_msg(!*w->rest, "the job's lines from '%.40s' did not run", w->rest);
	ck_assert_msg(w->closed, "nothing ran between two of the job's lines");
	ck_assert_msg(sscanf(w->prev, "G1 X%d Y%d", &x, &y) == 2, "the job's line before: %s",
		      w->prev);
	/* the operator's lines, as OctoPrint sends them, then the way back */
	snprintf(want, sizeof(want), "G91\nG1 X10 Y5 F3000\nG90\nG91\nM83\nG1 E2 F300\nM82\nG90\n"
		 "M104 S190\nG91\nG1 Z2 F600\nG90\nG1 X%d.000 Y%d.000 F6000\nG1 Z0.300 F600\n"
		 "M83\nG92 E0.00000\nG1 F60\n", x, y);
	ck_assert_str_eq(w->block, want);
	free(w);
	free(job);
	sv_stop(&np);
}
END_TEST

void octoapi_inject_tcases(Suite *s)
{
	TCase *tc = tcase_create("inject");

	tcase_set_timeout(tc, 60);
	tcase_add_test(tc, test_sailfish_command_during_print);
	tcase_add_test(tc, test_sailfish_temperature_offsets);
	tcase_add_test(tc, test_sailfish_paused_commands);
	tcase_add_test(tc, test_marlin_paused_commands);
	suite_add_tcase(s, tc);
}
