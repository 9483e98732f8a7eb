/*
 * check_octoqueue.c - the job calls and the queue (docs/serve.md, "The
 * queue API"), part of the octoapi suite: POST /api/job as OctoPrint
 * answers it (start once, restart, 409s), Stratum's queue API (positions,
 * move, cancel, requeue, kept across kill -9), the bed-clear gate in the
 * state text, the flags and the push API, and a job that never moved the
 * printer leaving the bed clear.
 */
#include <check.h>
#include <jansson.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "servetest.h"
#include "suites.h"
#include "testutil.h"

#define CTL "X-Api-Key: " KEY_CTL
#define RO "X-Api-Key: " KEY_READ

/* Start a node of two test-instant printers and wait until mk3s is connected. */
static void start_node(struct node_proc *np)
{
	struct resp r;
	int status = 0;

	sv_write_config(np, TWO_PRINTERS, 8);
	sv_start(np);
	for (int i = 0; i < 500 && status != 200; i++) {
		sv_http(np->port, "GET", "/api/printer", RO, NULL, &r);
		status = r.status;
		sv_resp_free(&r);
		if (status != 200)
			usleep(20000);
	}
	ck_assert_msg(status == 200, "mk3s is not operational");
}

/* The names of mk3s's queued jobs in order, "a.gcode,b.gcode"; their
 * positions must be 1, 2, ... and the gate and state as the answer says. */
static const char *waiting(int port, bool *bed_clear, char *state, size_t cap)
{
	static char names[512];
	json_t *q = sv_get_json(port, "/api/stratum/queue"), *j;
	size_t i, len = 0;

	names[0] = '\0';
	json_array_foreach(json_object_get(q, "waiting"), i, j) {
		ck_assert_int_eq(json_integer_value(json_object_get(j, "position")), (json_int_t)i + 1);
		len += (size_t)snprintf(names + len, sizeof(names) - len, "%s%s", i ? "," : "",
					sv_str(j, "name"));
	}
	if (bed_clear)
		*bed_clear = json_is_true(json_object_get(q, "bedClear"));
	if (state)
		snprintf(state, cap, "%s", sv_str(q, "state"));
	json_decref(q);
	return names;
}

/* POST a queue command for job id; the answer's status must be want. */
static void queue_cmd(int port, long long id, const char *body, int want)
{
	char path[64];

	snprintf(path, sizeof(path), "/api/stratum/queue/%lld", id);
	sv_expect(port, "POST", path, CTL, body, want);
}

/* GET /api/printer's state flag name. */
static bool flag(int port, const char *name)
{
	json_t *o = sv_get_json(port, "/api/printer");
	bool v = json_is_true(json_object_get(json_object_get(json_object_get(o, "state"), "flags"),
					      name));

	json_decref(o);
	return v;
}

/* Leave mk3s's bed waiting for an operator: a print that moves it, done. */
static long long bed_taken(int port)
{
	long long id = sv_print_text(port, "", "moved.gcode", "G28\nG1 X5 Y5\n");

	sv_wait_state(port, "", id, "done", 10);
	return id;
}

/* start prints the selected file once: a second start while it prints,
 * or while it waits in the queue, is 409, as is a start on a printer that
 * is not operational. */
START_TEST(test_job_start_once)
{
	struct node_proc np;
	struct resp r;
	char state[64] = "";

	start_node(&np);
	sv_upload(np.port, "", KEY_UP, "hold.gcode", 10, "", 0, "false", "G1 X1\nG4 S20\n", 13,
		  NULL, true, &r);
	ck_assert_int_eq(r.status, 201);
	sv_resp_free(&r);
	sv_expect(np.port, "POST", "/api/files/local/hold.gcode", CTL, "{\"command\":\"select\"}",
		  204);
	sv_expect(np.port, "POST", "/api/job", CTL, "{\"command\":\"start\"}", 204);
	sv_wait_state(np.port, "", 1, "printing", 10);
	sv_call(np.port, "POST", "/api/job", CTL, "{\"command\":\"start\"}", 409, &r);
	ck_assert_msg(strstr(r.body, "active print job"), "%s", r.body);
	sv_resp_free(&r);
	sv_expect(np.port, "POST", "/api/job", CTL, "{\"command\":\"start\"}", 409);
	ck_assert_str_eq(waiting(np.port, NULL, NULL, 0), "");
	sv_expect(np.port, "POST", "/api/job", CTL, "{\"command\":\"cancel\"}", 204);
	sv_wait_state(np.port, "", 1, "cancelled", 10);
	/* it moved: the next start waits for the bed, and a second start is 409 */
	sv_expect(np.port, "POST", "/api/job", CTL, "{\"command\":\"start\"}", 204);
	sv_expect(np.port, "POST", "/api/job", CTL, "{\"command\":\"start\"}", 409);
	ck_assert_str_eq(waiting(np.port, NULL, NULL, 0), "hold.gcode");
	queue_cmd(np.port, 2, "{\"command\":\"cancel\"}", 204);
	sv_expect(np.port, "POST", "/api/connection", CTL, "{\"command\":\"disconnect\"}", 204);
	for (int i = 0; i < 250 && strcmp(state, "Offline"); i++) {
		waiting(np.port, NULL, state, sizeof(state));
		usleep(20000);
	}
	sv_call(np.port, "POST", "/api/job", CTL, "{\"command\":\"start\"}", 409, &r);
	ck_assert_msg(strstr(r.body, "not operational"), "%s", r.body);
	sv_resp_free(&r);
	sv_stop(&np);
}
END_TEST

/* restart (OctoPrint: only while paused, 409 otherwise): the paused job
 * is cancelled and its file queued first, to print from the start once the
 * bed is confirmed clear. */
START_TEST(test_job_restart)
{
	struct node_proc np;
	char state[64] = "";
	json_t *q;

	start_node(&np);
	sv_expect(np.port, "POST", "/api/job", CTL, "{\"command\":\"restart\"}", 409);
	sv_bed_clear(np.port, "", 204);
	ck_assert(sv_print_text(np.port, "", "part.gcode", "G1 X1\nG4 S20\nG1 X2\n") == 1);
	sv_wait_state(np.port, "", 1, "printing", 10);
	sv_expect(np.port, "POST", "/api/job", CTL, "{\"command\":\"restart\"}", 409);
	sv_expect(np.port, "POST", "/api/job", CTL, "{\"command\":\"pause\",\"action\":\"pause\"}",
		  204);
	sv_expect(np.port, "POST", "/api/job", CTL, "{\"command\":\"restart\"}", 204);
	sv_wait_state(np.port, "", 1, "cancelled", 10);
	/* the new job is the same file, first in the queue, behind the gate */
	ck_assert(sv_print_text(np.port, "", "later.gcode", "G1 X3\n") == 3);
	for (int i = 0; i < 250 && strcmp(state, "Waiting for bed clear"); i++) {
		waiting(np.port, NULL, state, sizeof(state));
		usleep(20000);
	}
	ck_assert_str_eq(waiting(np.port, NULL, state, sizeof(state)), "part.gcode,later.gcode");
	ck_assert_str_eq(state, "Waiting for bed clear");
	sv_bed_clear(np.port, "", 204);
	sv_wait_state(np.port, "", 2, "printing", 10);
	q = sv_get_json(np.port, "/api/stratum/queue/2");
	ck_assert_str_eq(sv_str(q, "name"), "part.gcode");
	json_decref(q);
	ck_assert_str_eq(sv_job_state(np.port, "", 3, NULL), "queued");
	sv_expect(np.port, "POST", "/api/job", CTL, "{\"command\":\"cancel\"}", 204);
	sv_stop(&np);
}
END_TEST

/* The queue API: positions, move, cancel a queued job, requeue a finished
 * one, keys and roles, 404 for another printer's job; the order is kept
 * across kill -9, and the worker prints in that order. */
START_TEST(test_queue_api)
{
	struct node_proc np;
	struct resp r;
	bool clear = true;
	char state[64], path[64];
	long long a, b, c, b2;
	int st;

	start_node(&np);
	bed_taken(np.port);
	a = sv_print_text(np.port, "", "a.gcode", "G1 X1\n");
	b = sv_print_text(np.port, "", "b.gcode", "G1 X2\n");
	c = sv_print_text(np.port, "", "c.gcode", "G1 X3\nG4 S20\n");
	ck_assert_str_eq(waiting(np.port, &clear, state, sizeof(state)), "a.gcode,b.gcode,c.gcode");
	ck_assert(!clear);
	ck_assert_str_eq(state, "Waiting for bed clear");
	ck_assert(flag(np.port, "operational") && !flag(np.port, "ready"));
	/* move */
	queue_cmd(np.port, c, "{\"command\":\"move\",\"position\":1}", 204);
	ck_assert_str_eq(waiting(np.port, NULL, NULL, 0), "c.gcode,a.gcode,b.gcode");
	queue_cmd(np.port, a, "{\"command\":\"move\",\"position\":99}", 204);
	ck_assert_str_eq(waiting(np.port, NULL, NULL, 0), "c.gcode,b.gcode,a.gcode");
	queue_cmd(np.port, a, "{\"command\":\"move\",\"position\":0}", 400);
	queue_cmd(np.port, a, "{\"command\":\"move\"}", 400);
	queue_cmd(np.port, 1, "{\"command\":\"move\",\"position\":1}", 409); /* done */
	queue_cmd(np.port, a, "{\"command\":\"fly\"}", 400);
	/* cancel a queued job; requeue it */
	queue_cmd(np.port, b, "{\"command\":\"cancel\"}", 204);
	ck_assert_str_eq(sv_job_state(np.port, "", b, NULL), "cancelled");
	queue_cmd(np.port, b, "{\"command\":\"cancel\"}", 409);
	queue_cmd(np.port, a, "{\"command\":\"requeue\"}", 409); /* still queued */
	snprintf(path, sizeof(path), "/api/stratum/queue/%lld", b);
	sv_call(np.port, "POST", path, CTL, "{\"command\":\"requeue\"}", 201, &r);
	b2 = (long long)json_integer_value(json_object_get(r.json, "id"));
	ck_assert(b2 > c);
	ck_assert_str_eq(sv_str(r.json, "name"), "b.gcode");
	ck_assert_str_eq(sv_str(r.json, "state"), "queued");
	ck_assert_msg(sv_has_text(r.head, "Location: http://"), "%s", r.head);
	sv_resp_free(&r);
	ck_assert_str_eq(sv_job_state(np.port, "", b, NULL), "cancelled");
	ck_assert_str_eq(waiting(np.port, NULL, NULL, 0), "c.gcode,a.gcode,b.gcode");
	/* one job, keys and roles, another printer's job, no such job */
	ck_assert_int_eq(c, 4);
	sv_call(np.port, "GET", "/api/stratum/queue/4", RO, NULL, 200, &r);
	ck_assert_str_eq(sv_str(r.json, "name"), "c.gcode");
	sv_resp_free(&r);
	sv_expect(np.port, "GET", "/api/stratum/queue/4", NULL, NULL, 403);
	sv_expect(np.port, "POST", "/api/stratum/queue/4", RO, "{\"command\":\"cancel\"}", 403);
	sv_expect(np.port, "POST", "/api/stratum/queue/4", "X-Api-Key: " KEY_UP,
		  "{\"command\":\"cancel\"}", 403);
	sv_expect(np.port, "GET", "/p/ender/api/stratum/queue/4", RO, NULL, 404);
	sv_expect(np.port, "POST", "/p/ender/api/stratum/queue/4", CTL, "{\"command\":\"cancel\"}",
		  404);
	sv_expect(np.port, "GET", "/api/stratum/queue/999", RO, NULL, 404);
	sv_expect(np.port, "GET", "/api/stratum/queue/x1", RO, NULL, 404);
	/* kept across kill -9 */
	ck_assert(kill(np.pid, SIGKILL) == 0);
	ck_assert(waitpid(np.pid, &st, 0) == np.pid);
	sv_start(&np);
	ck_assert_str_eq(waiting(np.port, &clear, NULL, 0), "c.gcode,a.gcode,b.gcode");
	ck_assert(!clear);
	/* the worker takes them in that order */
	sv_bed_clear(np.port, "", 204);
	sv_wait_state(np.port, "", c, "printing", 10);
	ck_assert_str_eq(sv_job_state(np.port, "", a, NULL), "queued");
	ck_assert_str_eq(waiting(np.port, NULL, NULL, 0), "a.gcode,b.gcode");
	sv_expect(np.port, "POST", "/api/job", CTL, "{\"command\":\"cancel\"}", 204);
	sv_stop(&np);
}
END_TEST

/* A job that never moved the printer leaves the bed clear: one cancelled
 * while it heats, one that fails on a bad line before anything is sent;
 * the next job prints without a bed-clear confirmation.  One that moved
 * makes the next wait, and the state text, flags and push API say so. */
START_TEST(test_bed_untouched)
{
	struct node_proc np;
	bool clear = false;
	char state[64];
	long long id;

	start_node(&np);
	id = sv_print_text(np.port, "", "heat.gcode", "M104 S200\nG4 S20\nG1 X1\n");
	sv_wait_state(np.port, "", id, "printing", 10);
	sv_expect(np.port, "POST", "/api/job", CTL, "{\"command\":\"cancel\"}", 204);
	sv_wait_state(np.port, "", id, "cancelled", 10);
	waiting(np.port, &clear, state, sizeof(state));
	ck_assert(clear);
	ck_assert_str_eq(state, "Operational");
	ck_assert(flag(np.port, "ready"));
	id = sv_print_text(np.port, "", "bad.gcode", "G1 X1.2.3\n");
	sv_wait_state(np.port, "", id, "failed", 10);
	id = sv_print_text(np.port, "", "next.gcode", "M104 S200\n");
	sv_wait_state(np.port, "", id, "done", 10);
	/* a job that moved it: the next one waits */
	bed_taken(np.port);
	id = sv_print_text(np.port, "", "after.gcode", "M104 S200\n");
	usleep(1200000);
	ck_assert_str_eq(sv_job_state(np.port, "", id, NULL), "queued");
	waiting(np.port, &clear, state, sizeof(state));
	ck_assert(!clear);
	ck_assert_str_eq(state, "Waiting for bed clear");
	sv_bed_clear(np.port, "", 204);
	sv_wait_state(np.port, "", id, "done", 10);
	sv_stop(&np);
}
END_TEST

/* Cancel mk3s's job id (a sim Marlin) while it waits for its bed to heat. */
static void cancel_in_heat_wait(int port, long long id)
{
	sv_wait_state(port, "", id, "printing", 10);
	usleep(800000); /* in M190: the bed needs several seconds at this speed-up */
	sv_expect(port, "POST", "/api/job", CTL, "{\"command\":\"cancel\"}", 204);
	sv_wait_state(port, "", id, "cancelled", 10);
}

/* The Marlin driver: what a cancel leaves in flight still runs (its safe
 * stop breaks the heat wait), so a move written after the wait counts,
 * confirmed or not; one never written does not. */
START_TEST(test_bed_untouched_marlin)
{
	struct node_proc np;
	char text[2048], log[1024], *ran;
	size_t len = 0;
	bool clear = false;

	sv_write_config(&np, "[printer mk3s]\nprofile = prusa-i3-mk3s\nport = sim\n"
			  "sim_speedup = 10\n", 8);
	sv_start(&np);
	/* the move lies beyond what the driver writes ahead of the wait */
	len = (size_t)snprintf(text, sizeof(text), "M140 S90\nM190 S90\n");
	for (int i = 0; i < 40; i++)
		len += (size_t)snprintf(text + len, sizeof(text) - len, "M117 warming %d\n", i);
	snprintf(text + len, sizeof(text) - len, "G28\nG1 X10 F3000\n");
	cancel_in_heat_wait(np.port, sv_print_text(np.port, "", "far.gcode", text));
	waiting(np.port, &clear, NULL, 0);
	ck_assert_msg(clear, "a job whose moves were never sent asks for the bed");
	/* right after the wait: written with it, and run by the safe stop */
	cancel_in_heat_wait(np.port, sv_print_text(np.port, "", "near.gcode",
						   "M140 S90\nM190 S90\nG28\nG1 X10 F3000\n"));
	waiting(np.port, &clear, NULL, 0);
	snprintf(log, sizeof(log), "%s/data/sim/mk3s.log", np.dir);
	ran = tu_slurp(log, &len);
	ck_assert(ran);
	ck_assert_msg(strstr(ran, " G28\n"), "%s", ran);
	ck_assert_msg(!clear, "the printer homed, yet the bed counts as clear");
	free(ran);
	sv_stop(&np);
}
END_TEST

void octoapi_queue_tcases(Suite *s)
{
	TCase *tc = tcase_create("queue");

	tcase_set_timeout(tc, 60);
	tcase_add_test(tc, test_job_start_once);
	tcase_add_test(tc, test_job_restart);
	tcase_add_test(tc, test_queue_api);
	tcase_add_test(tc, test_bed_untouched);
	tcase_add_test(tc, test_bed_untouched_marlin);
	suite_add_tcase(s, tc);
}
