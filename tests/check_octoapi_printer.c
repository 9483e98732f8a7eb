/*
 * check_octoapi_printer.c - the OctoPrint calls of `stratum serve` on the
 * printer, part of the octoapi suite (check_octoapi.c, the same "calls"
 * case): tool, bed and print head, commands and temperature offsets during
 * a print (checked in the simulator's log), the Creator Pro's second tool,
 * and /api/job's estimate, time left and filament.
 */
#include <check.h>
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "octoapitest.h"
#include "servetest.h"
#include "suites.h"
#include "testutil.h"

/* ---- printer components ------------------------------------------------------ */

START_TEST(test_printer_tool)
{
	struct node_proc np;
	struct resp r;
	json_t *t;

	oa_start(&np, MK3S_AND_CREATOR);
	sv_operational(np.port, "");
	sv_operational(np.port, "/p/cp");
	sv_call(np.port, "GET", "/api/printer/tool", RO, NULL, 200, &r);
	ck_assert(json_is_number(json_object_get(json_object_get(r.json, "tool0"), "actual")));
	ck_assert(!json_object_get(r.json, "tool1"));
	ck_assert(!json_object_get(r.json, "bed"));
	sv_resp_free(&r);
	/* the Creator Pro has two extruders: tool1 is there */
	sv_call(np.port, "GET", "/p/cp/api/printer/tool", RO, NULL, 200, &r);
	ck_assert(json_is_object(json_object_get(r.json, "tool1")));
	sv_resp_free(&r);
	sv_call(np.port, "GET", "/p/cp/api/printer", RO, NULL, 200, &r);
	ck_assert(json_object_get(json_object_get(r.json, "temperature"), "tool1"));
	sv_resp_free(&r);
	sv_call(np.port, "GET", "/p/cp/api/printer?exclude=sd,temperature", RO, NULL, 200, &r);
	ck_assert(!json_object_get(r.json, "temperature") && !json_object_get(r.json, "sd"));
	ck_assert(json_object_get(r.json, "state"));
	sv_resp_free(&r);
	sv_expect(np.port, "POST", "/api/printer/tool", CTL,
		  "{\"command\":\"target\",\"targets\":{\"tool0\":205}}", 204);
	/* the test double reaches a target at once: it was sent */
	for (int i = 0; i < 100; i++) {
		sv_call(np.port, "GET", "/api/printer/tool", RO, NULL, 200, &r);
		t = json_object_get(r.json, "tool0");
		if (json_number_value(json_object_get(t, "target")) == 205)
			break;
		sv_resp_free(&r);
		usleep(20000);
	}
	ck_assert_msg(json_number_value(json_object_get(t, "target")) == 205, "%s", r.body);
	sv_resp_free(&r);
	sv_expect(np.port, "POST", "/api/printer/tool", CTL,
		  "{\"command\":\"target\",\"targets\":{\"tool1\":205}}", 400);
	sv_expect(np.port, "POST", "/api/printer/tool", CTL,
		  "{\"command\":\"target\",\"targets\":{\"tool0\":9999}}", 400);
	sv_expect(np.port, "POST", "/p/cp/api/printer/tool", CTL,
		  "{\"command\":\"target\",\"targets\":{\"tool1\":210}}", 204);
	sv_expect(np.port, "POST", "/p/cp/api/printer/tool", CTL,
		  "{\"command\":\"select\",\"tool\":\"tool1\"}", 204);
	sv_expect(np.port, "POST", "/api/printer/tool", CTL,
		  "{\"command\":\"extrude\",\"amount\":5}", 204);
	sv_expect(np.port, "POST", "/api/printer/tool", CTL,
		  "{\"command\":\"flowrate\",\"factor\":95}", 204);
	sv_expect(np.port, "POST", "/api/printer/tool", CTL,
		  "{\"command\":\"flowrate\",\"factor\":300}", 400);
	sv_expect(np.port, "POST", "/api/printer/tool", CTL,
		  "{\"command\":\"offset\",\"offsets\":{\"tool0\":5}}", 400);
	sv_expect(np.port, "POST", "/api/printer/tool", UP,
		  "{\"command\":\"target\",\"targets\":{\"tool0\":205}}", 403);
	/* not operational: 409 */
	sv_expect(np.port, "POST", "/api/connection", CTL, "{\"command\":\"disconnect\"}", 204);
	usleep(300000);
	sv_expect(np.port, "GET", "/api/printer/tool", RO, NULL, 409);
	sv_expect(np.port, "POST", "/api/printer/tool", CTL,
		  "{\"command\":\"target\",\"targets\":{\"tool0\":205}}", 409);
	sv_stop(&np);
}
END_TEST

START_TEST(test_printer_bed)
{
	struct node_proc np;
	struct resp r;

	oa_start(&np, TWO_PRINTERS);
	sv_operational(np.port, "");
	sv_call(np.port, "GET", "/api/printer/bed", RO, NULL, 200, &r);
	ck_assert(json_is_number(json_object_get(json_object_get(r.json, "bed"), "target")));
	ck_assert(!json_object_get(r.json, "tool0"));
	sv_resp_free(&r);
	sv_expect(np.port, "POST", "/api/printer/bed", CTL, "{\"command\":\"target\",\"target\":60}",
		  204);
	/* the history: samples every 2 s, the last `limit` of them, oldest first */
	for (int i = 0; i < 80; i++) {
		json_t *h, *last;

		sv_call(np.port, "GET", "/api/printer/bed?history=true&limit=2", RO, NULL, 200, &r);
		h = json_object_get(r.json, "history");
		ck_assert_msg(json_is_array(h) && json_array_size(h) <= 2, "%s", r.body);
		last = json_array_get(h, json_array_size(h) - 1);
		if (json_number_value(json_object_get(json_object_get(last, "bed"), "target")) == 60)
			break;
		sv_resp_free(&r);
		usleep(100000);
	}
	ck_assert_msg(r.json, "no sample with the bed's target");
	ck_assert(json_integer_value(json_object_get(json_array_get(json_object_get(r.json,
											  "history"),
								    0), "time")) > 0);
	sv_resp_free(&r);
	sv_call(np.port, "GET", "/api/printer/tool?history=true", RO, NULL, 200, &r);
	ck_assert(!json_object_get(json_array_get(json_object_get(r.json, "history"), 0), "bed"));
	ck_assert(json_object_get(json_array_get(json_object_get(r.json, "history"), 0), "tool0"));
	sv_resp_free(&r);
	sv_call(np.port, "GET", "/api/printer", RO, NULL, 200, &r);
	ck_assert(!json_object_get(json_object_get(r.json, "temperature"), "history"));
	sv_resp_free(&r);
	sv_call(np.port, "GET", "/api/printer?history=true&limit=1", RO, NULL, 200, &r);
	ck_assert_int_eq(json_array_size(json_object_get(json_object_get(r.json, "temperature"),
							 "history")), 1);
	sv_resp_free(&r);
	sv_expect(np.port, "POST", "/api/printer/bed", CTL, "{\"command\":\"target\"}", 400);
	sv_expect(np.port, "POST", "/api/printer/bed", CTL, "{\"command\":\"offset\",\"offset\":5}",
		  400);
	/* no printer of the node has a heated chamber or an SD card */
	sv_expect(np.port, "GET", "/api/printer/chamber", RO, NULL, 409);
	sv_expect(np.port, "POST", "/api/printer/chamber", CTL,
		  "{\"command\":\"target\",\"target\":40}", 409);
	sv_call(np.port, "GET", "/api/printer/sd", RO, NULL, 404, &r);
	ck_assert_str_eq(sv_str(r.json, "error"), "SD support is disabled");
	sv_resp_free(&r);
	sv_expect(np.port, "POST", "/api/printer/sd", CTL, "{\"command\":\"init\"}", 404);
	sv_stop(&np);
}
END_TEST

/* Jog, home and feed rate reach the simulated Marlin printer as OctoPrint
 * sends them; refused while printing. */
START_TEST(test_printer_printhead)
{
	struct node_proc np;
	char path[600], *log = NULL;
	size_t len;

	oa_start(&np, "[printer mk3s]\nprofile = prusa-i3-mk3s\nport = sim\nsim_speedup = 1000\n");
	sv_operational(np.port, ""); /* the sim's boot done */
	sv_expect(np.port, "POST", "/api/printer/printhead", CTL,
		  "{\"command\":\"home\",\"axes\":[\"x\",\"y\"]}", 204);
	sv_expect(np.port, "POST", "/api/printer/printhead", CTL,
		  "{\"command\":\"jog\",\"x\":10,\"y\":-5,\"speed\":3000}", 204);
	sv_expect(np.port, "POST", "/api/printer/printhead", CTL,
		  "{\"command\":\"feedrate\",\"factor\":90}", 204);
	sv_expect(np.port, "POST", "/api/printer/printhead", CTL,
		  "{\"command\":\"jog\",\"x\":\"far\"}", 400);
	sv_expect(np.port, "POST", "/api/printer/printhead", CTL,
		  "{\"command\":\"home\",\"axes\":[\"q\"]}", 400);
	snprintf(path, sizeof(path), "%s/data/sim/mk3s.log", np.dir);
	for (int i = 0; i < 250; i++) {
		free(log);
		log = access(path, R_OK) ? NULL : tu_slurp(path, &len);
		if (log && strstr(log, "M220 S90"))
			break;
		usleep(20000);
	}
	ck_assert_msg(log && strstr(log, "G28 X0 Y0") && strstr(log, "G1 X10 Y-5 F3000") &&
		      strstr(log, "M220 S90"), "%s", log ? log : "(no log)");
	free(log);
	/* while printing, OctoPrint refuses the print head: 409 */
	sv_bed_clear(np.port, "", 204);
	ck_assert(sv_print_text(np.port, "", "long.gcode", "G4 S30\n") == 1);
	sv_wait_state(np.port, "", 1, "printing", 10);
	sv_expect(np.port, "POST", "/api/printer/printhead", CTL,
		  "{\"command\":\"home\",\"axes\":[\"z\"]}", 409);
	sv_expect(np.port, "POST", "/api/job", CTL, "{\"command\":\"cancel\"}", 204);
	sv_stop(&np);
}
END_TEST

/*
 * Commands during a print (OctoPrint queues them between the job's lines):
 * on a Marlin printer (`port = sim`) a command and a tool target posted
 * while the job streams run once each, between two lines of the job, whose
 * lines all run once and in order (the simulator's log: every line number
 * once, in order); the print head's jog and a tool select stay 409.
 */
/* The log walk of test_command_during_print: the job's lines and ours. */
struct ours_in_job {
	const char *const *ours;
	const char *job, *rest; /* the job's text, and its lines still due */
	int seen[2], inside[2];
};

static void ours_in_job_line(void *ctx, const char *text)
{
	struct ours_in_job *w = ctx;
	size_t tl = strlen(text);

	for (int i = 0; i < 2; i++) {
		if (!strcmp(text, w->ours[i])) {
			w->seen[i]++;
			/* after the first job line, before the last */
			w->inside[i] = w->rest != w->job && *w->rest;
			return;
		}
	}
	ck_assert_msg(!strncmp(w->rest, text, tl) && w->rest[tl] == '\n',
		      "the job ran '%s' where '%.40s' was due", text, w->rest);
	w->rest += tl + 1;
}

START_TEST(test_command_during_print)
{
	static const char *const ours[] = {"M117 sent during the print", "M104 S205"};
	struct node_proc np;
	struct ours_in_job w = {.ours = ours};
	char path[600], *job;
	size_t cap = 64 * 1024, len = 0;
	json_t *o;
	double pos = 0;

	job = malloc(cap);
	ck_assert(job);
	len += (size_t)snprintf(job + len, cap - len, "M117 job start\nG28\n");
	for (int k = 0; k < 160; k++)
		len += (size_t)snprintf(job + len, cap - len, "G1 X%d Y%d F60\n", 10 + k % 2, 10 + k);
	snprintf(job + len, cap - len, "M117 job end\n");
	oa_start(&np, "[printer mk3s]\nprofile = prusa-i3-mk3s\nport = sim\nsim_speedup = 40\n");
	sv_operational(np.port, "");
	ck_assert(sv_print_text(np.port, "", "moves.gcode", job) == 1);
	sv_wait_state(np.port, "", 1, "printing", 10);
	for (int i = 0; i < 250 && pos <= 0; i++) {
		o = sv_get_json(np.port, "/api/job");
		pos = json_number_value(json_object_get(json_object_get(o, "progress"), "filepos"));
		json_decref(o);
		usleep(20000);
	}
	ck_assert_msg(pos > 0, "the job did not start streaming");
	sv_expect(np.port, "POST", "/api/printer/command", CTL,
		  "{\"command\":\"M117 sent during the print\"}", 204);
	sv_expect(np.port, "POST", "/api/printer/tool", CTL,
		  "{\"command\":\"target\",\"targets\":{\"tool0\":205}}", 204);
	/* as OctoPrint: no jog, home, tool select or extrusion while printing */
	sv_expect(np.port, "POST", "/api/printer/printhead", CTL,
		  "{\"command\":\"jog\",\"x\":10}", 409);
	sv_expect(np.port, "POST", "/api/printer/tool", CTL,
		  "{\"command\":\"extrude\",\"amount\":5}", 409);
	sv_wait_state(np.port, "", 1, "done", 30);
	/* The simulator's log from the job's first line: the job whole, in
	 * order, with each command once inside it. */
	snprintf(path, sizeof(path), "%s/data/sim/mk3s.log", np.dir);
	w.job = w.rest = job;
	sv_marlin_log(path, "M117 job start", ours_in_job_line, &w);
	ck_assert_msg(!*w.rest, "the job's lines from '%.40s' did not run", w.rest);
	for (int i = 0; i < 2; i++)
		ck_assert_msg(w.seen[i] == 1 && w.inside[i], "'%s' ran %d times%s", ours[i], w.seen[i],
			      w.inside[i] ? "" : ", not between two lines of the job");
	free(job);
	sv_stop(&np);
}
END_TEST

/*
 * Temperature offsets (OctoPrint's "offset" of the tool and the bed): on a
 * Marlin printer they are reported and added to the file's targets as it
 * streams (a heater turned off stays off); test-instant printers refuse
 * them (400, test_printer_tool).
 */
START_TEST(test_temperature_offsets)
{
	struct node_proc np;
	struct resp r;
	char path[600], *log = NULL;
	json_t *temp;
	size_t len;

	oa_start(&np, "[printer mk3s]\nprofile = prusa-i3-mk3s\nport = sim\nsim_speedup = 1000\n");
	sv_operational(np.port, "");
	sv_expect(np.port, "POST", "/api/printer/tool", CTL,
		  "{\"command\":\"offset\",\"offsets\":{\"tool0\":10}}", 204);
	sv_expect(np.port, "POST", "/api/printer/bed", CTL, "{\"command\":\"offset\",\"offset\":-5}",
		  204);
	sv_expect(np.port, "POST", "/api/printer/tool", CTL,
		  "{\"command\":\"offset\",\"offsets\":{\"tool0\":60}}", 400);
	sv_expect(np.port, "POST", "/api/printer/tool", CTL,
		  "{\"command\":\"offset\",\"offsets\":{\"tool3\":5}}", 400);
	sv_expect(np.port, "POST", "/api/printer/tool", UP,
		  "{\"command\":\"offset\",\"offsets\":{\"tool0\":5}}", 403);
	sv_call(np.port, "GET", "/api/printer", RO, NULL, 200, &r);
	temp = json_object_get(r.json, "temperature");
	ck_assert_msg(json_number_value(json_object_get(json_object_get(temp, "tool0"), "offset")) ==
			      10 &&
		      json_number_value(json_object_get(json_object_get(temp, "bed"), "offset")) ==
			      -5, "%s", r.body);
	sv_resp_free(&r);
	sv_bed_clear(np.port, "", 204);
	ck_assert(sv_print_text(np.port, "", "temps.gcode",
				"M104 S200\nM140 S60\nG1 X5 F600\nM104 S0\nM140 S0\n") == 1);
	sv_wait_state(np.port, "", 1, "done", 20);
	snprintf(path, sizeof(path), "%s/data/sim/mk3s.log", np.dir);
	log = tu_slurp(path, &len);
	ck_assert_msg(strstr(log, " M104 S210\n") && strstr(log, " M140 S55\n") &&
		      strstr(log, " M104 S0\n") && strstr(log, " M140 S0\n") &&
		      !strstr(log, " M104 S200\n") && !strstr(log, " M140 S60\n"),
		      "the offsets were not applied: %s", log);
	free(log);
	sv_stop(&np);
}
END_TEST

/*
 * The Creator Pro's second extruder (issue 20): the Sailfish driver reads
 * tool 1 too, so /api/printer/tool has its temperatures, and a target set
 * for it shows (the simulated printer heats it); a one-extruder printer
 * has no tool1.
 */
START_TEST(test_sailfish_tool1)
{
	struct node_proc np;
	struct resp r;
	json_t *t1 = NULL;
	double target = 0;

	oa_start(&np, "[printer cp]\nprofile = flashforge-creator-pro\nport = sim\n"
		   "sim_speedup = 1000\n");
	sv_operational(np.port, "");
	sv_expect(np.port, "POST", "/api/printer/tool", CTL,
		  "{\"command\":\"target\",\"targets\":{\"tool1\":150}}", 204);
	/* temperatures are read every 2 s between jobs */
	for (int i = 0; i < 300 && target != 150; i++) {
		sv_call(np.port, "GET", "/api/printer/tool", RO, NULL, 200, &r);
		t1 = json_object_get(r.json, "tool1");
		target = json_number_value(json_object_get(t1, "target"));
		if (target == 150) {
			ck_assert_msg(json_is_number(json_object_get(t1, "actual")), "%s", r.body);
			ck_assert_msg(json_number_value(json_object_get(json_object_get(r.json,
				      "tool0"), "target")) == 0, "%s", r.body);
		}
		sv_resp_free(&r);
		if (target != 150)
			usleep(20000);
	}
	ck_assert_msg(target == 150, "tool1's target never showed");
	sv_stop(&np);
}
END_TEST

/* ---- job ---------------------------------------------------------------------- */

/* /api/job: the file's estimate and filament, the time left by its M73
 * marks; flags.ready false while a job holds the printer. */
START_TEST(test_job_estimates)
{
	struct node_proc np;
	struct resp r;
	json_t *job, *prog, *fil;

	oa_start(&np, TWO_PRINTERS);
	oa_store(np.port, "", "a.gcode", oa_dwell(4));
	sv_expect(np.port, "POST", "/api/files/local/a.gcode", UP, "{\"command\":\"select\"}", 204);
	sv_call(np.port, "GET", "/api/job", RO, NULL, 200, &r);
	job = json_object_get(r.json, "job");
	ck_assert_int_eq(json_integer_value(json_object_get(job, "estimatedPrintTime")), 602);
	fil = json_object_get(json_object_get(job, "filament"), "tool0");
	ck_assert(json_real_value(json_object_get(fil, "length")) == 812.5);
	ck_assert(json_real_value(json_object_get(fil, "volume")) == 1.95);
	ck_assert(json_is_null(json_object_get(json_object_get(r.json, "progress"),
					       "printTimeLeft")));
	sv_resp_free(&r);
	sv_bed_clear(np.port, "", 204);
	sv_expect(np.port, "POST", "/api/job", CTL, "{\"command\":\"start\"}", 204);
	sv_wait_state(np.port, "", 1, "printing", 10);
	/* past "M73 P50 R5" within the 4 s dwell */
	for (int i = 0; i < 150; i++) {
		sv_call(np.port, "GET", "/api/job", RO, NULL, 200, &r);
		prog = json_object_get(r.json, "progress");
		if (json_integer_value(json_object_get(prog, "printTimeLeft")) == 300)
			break;
		sv_resp_free(&r);
		usleep(20000);
	}
	ck_assert_msg(json_integer_value(json_object_get(prog, "printTimeLeft")) == 300, "%s",
		      r.body);
	ck_assert_str_eq(sv_str(prog, "printTimeLeftOrigin"), "estimate");
	sv_resp_free(&r);
	sv_expect(np.port, "POST", "/api/job", CTL, "{\"command\":\"pause\",\"action\":\"pause\"}",
		  204);
	sv_call(np.port, "GET", "/api/printer", RO, NULL, 200, &r);
	ck_assert(json_is_false(json_object_get(json_object_get(json_object_get(r.json, "state"),
								"flags"), "ready")));
	sv_resp_free(&r);
	sv_expect(np.port, "POST", "/api/job", CTL, "{\"command\":\"cancel\"}", 204);
	sv_wait_state(np.port, "", 1, "cancelled", 10);
	sv_call(np.port, "GET", "/api/printer", RO, NULL, 200, &r);
	ck_assert(json_is_true(json_object_get(json_object_get(json_object_get(r.json, "state"),
							       "flags"), "ready")));
	sv_resp_free(&r);
	sv_stop(&np);
}
END_TEST

/* The tests of the "calls" case on the printer and the job, after the others. */
void octoapi_printer_tests(TCase *tc)
{
	tcase_add_test(tc, test_printer_tool);
	tcase_add_test(tc, test_printer_bed);
	tcase_add_test(tc, test_printer_printhead);
	tcase_add_test(tc, test_command_during_print);
	tcase_add_test(tc, test_temperature_offsets);
	tcase_add_test(tc, test_sailfish_tool1);
	tcase_add_test(tc, test_job_estimates);
}
