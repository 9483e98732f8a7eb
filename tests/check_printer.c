/*
 * check_printer.c - serial/printer.h: one suite of adapter tests run
 * against both dialects through the interface, each on its simulator
 * (loop index 0: Marlin on the simulated Marlin printer, 1: Sailfish on the
 * simulated Sailfish printer): stream a layered job, hold and go on,
 * cancel and print again on the same link, stop, safe stop, a board reset
 * and an unplugged cable mid-job, and a resume from a layer with the
 * dialect's preamble.
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "printer.h"
#include "printer_profile.h"
#include "profile.h"
#include "resume.h"
#include "sim/marlin_sim.h"
#include "sim/sailfish_sim.h"
#include "suites.h"
#include "testutil.h"

#define PT_SPEEDUP 100.0
#define PT_LAYERS 8
#define PT_PER_LAYER 40

static const char *const pt_profiles[] = {"generic-marlin", "flashforge-creator-pro"};

/* One dialect's simulator and an open printer on it. */
struct rig {
	int dialect; /* loop index */
	struct sim_marlin *sm;
	struct sim_sailfish *ss;
	struct profile *prof;
	const struct printer_ops *ops;
	struct printer_options o;
	struct printer *p;
	char log[512], gcode[512];
};

/* A layered job under Cura-style layer comments, heating first. */
static void write_job(const char *path)
{
	FILE *f = fopen(path, "w");

	ck_assert(f);
	/* M73 P0 starts a Sailfish build (its state "running"), as sliced files do */
	fprintf(f, "; layered test part\nM73 P0\nM140 S60\nM104 S210\nG28\nM190 S60\nM109 S210\n"
		   "G92 E0\n");
	for (int l = 0, i = 0; l < PT_LAYERS; l++) {
		fprintf(f, ";LAYER:%d\nG1 Z%.2f F600\n", l, 0.2 * (l + 1));
		for (int k = 0; k < PT_PER_LAYER; k++, i++)
			fprintf(f, "G1 X%d Y%d E%.3f F300\n", 10 + i % 2, 10 + k, 0.05 * (i + 1));
	}
	fprintf(f, "M104 S0\nM140 S0\nM73 P100\n");
	fclose(f);
}

/* Start the simulator of dialect (fault at command/line `at`, 0 none) and open it. */
static void rig_open(struct rig *r, int dialect, long reset_at, long unplug_at)
{
	struct st_error err = {0};
	const char *path;

	memset(r, 0, sizeof(*r));
	r->dialect = dialect;
	snprintf(r->log, sizeof(r->log), "%s", tu_path(dialect ? "pt-sf.log" : "pt-m.log"));
	snprintf(r->gcode, sizeof(r->gcode), "%s", tu_path("pt-job.gcode"));
	write_job(r->gcode);
	ck_assert_msg(profile_find(pt_profiles[dialect], &r->prof, &err) == 0, "%s", err.msg);
	if (dialect == 0) {
		struct sim_marlin_options so;

		sim_marlin_options_init(&so);
		so.speedup = PT_SPEEDUP;
		so.boot_s = 0; /* booted before we open: the first M110 is answered */
		so.baud = 4000000;
		so.log_path = r->log;
		so.reset_at_line = reset_at;
		so.unplug_at_line = unplug_at;
		ck_assert_msg(sim_marlin_new(&so, &r->sm, &err) == 0, "%s", err.msg);
		ck_assert_msg(sim_marlin_start_thread(r->sm, &err) == 0, "%s", err.msg);
		path = sim_marlin_slave_path(r->sm);
	} else {
		struct sim_sailfish_options so;

		sim_sailfish_options_init(&so);
		so.speedup = PT_SPEEDUP;
		so.baud = 4000000;
		so.log_path = r->log;
		so.reset_at = reset_at;
		so.unplug_at = unplug_at;
		ck_assert_msg(sim_sailfish_new(&so, &r->ss, &err) == 0, "%s", err.msg);
		ck_assert_msg(sim_sailfish_start_thread(r->ss, &err) == 0, "%s", err.msg);
		path = sim_sailfish_slave_path(r->ss);
	}
	ck_assert_msg(printer_profile_options(r->prof, path, 4000000, &r->o, &r->ops, &err) == 0,
		      "%s", err.msg);
	/* the simulator is not reset by DTR; it boots once, before we open */
	r->o.dtr_reset = false;
	ck_assert_msg(printer_open(r->ops, &r->o, &r->p, &err) == 0, "%s", err.msg);
}

static void rig_close(struct rig *r)
{
	printer_close(r->p);
	sim_marlin_free(r->sm);
	sim_sailfish_free(r->ss);
	profile_free(r->prof);
}

/* Commands the simulator executed of the jobs (the connect's left out). */
static size_t executed(const struct rig *r, bool *homed_xy)
{
	char line[512];
	size_t n = 0;
	FILE *f;

	if (r->sm)
		sim_marlin_stop(r->sm);
	if (r->ss)
		sim_sailfish_stop(r->ss);
	f = fopen(r->log, "r");
	ck_assert_msg(f, "no log %s", r->log);
	*homed_xy = false;
	while (fgets(line, sizeof(line), f)) {
		unsigned long long seq;
		unsigned code;

		if (r->dialect == 0) {
			const char *cmd = strchr(line, ' ');

			if (line[0] == '-' || !cmd)
				continue; /* the safe stop's M410/M108 past the queue */
			cmd++;
			if (!strncmp(cmd, "M110", 4) || !strncmp(cmd, "M115", 4) ||
			    !strncmp(cmd, "M155", 4))
				continue;
			*homed_xy = *homed_xy || !strncmp(cmd, "G28 X Y", 7);
		} else if (sscanf(line, "%llu %u", &seq, &code) == 2) {
			*homed_xy = *homed_xy || code == 144; /* M132: recall home positions */
		}
		n++;
	}
	fclose(f);
	return n;
}

/* Control hook behaviour for a test. */
struct plan {
	enum printer_control after;  /* asked once done >= at */
	uint64_t at;
	uint64_t done;		     /* latest progress */
	bool saw_paused, released;
	int held_calls;		     /* progress calls while paused */
	long max_layer;
	long layer_jump;	     /* largest step between two reported layers */
	long layers_told;	     /* distinct layers the hook reported */
};

static enum printer_control plan_control(void *ctx)
{
	struct plan *p = ctx;

	if (p->after == PRINTER_GO || p->done < p->at || p->released)
		return PRINTER_GO;
	if (p->after == PRINTER_HOLD && p->held_calls > 3) {
		p->released = true;
		return PRINTER_GO;
	}
	return p->after;
}

static void plan_progress(void *ctx, const struct printer_progress *pr)
{
	struct plan *p = ctx;

	p->done = pr->done;
	if (p->max_layer >= 0 && pr->layer - p->max_layer > p->layer_jump)
		p->layer_jump = pr->layer - p->max_layer;
	if (pr->layer > p->max_layer) {
		p->max_layer = pr->layer;
		p->layers_told++;
	}
	if (pr->paused) {
		p->saw_paused = true;
		p->held_calls++;
	}
}

/* Check and stream r's job with plan; the result. */
static void run(struct rig *r, struct plan *pl, struct printer_job *job,
		struct printer_file_info *info, struct printer_result *res, struct st_error *err)
{
	job->path = r->gcode;
	job->control = plan_control;
	job->progress = plan_progress;
	job->ctx = pl;
	pl->max_layer = -1;
	ck_assert_msg(printer_check(r->ops, &r->o, job, NULL, NULL, info, err) == 0, "%s",
		      err->msg);
	job->total = info->commands;
	ck_assert_msg(printer_stream(r->p, job, res, err) == 0, "%s", err->msg);
}

static int64_t file_size(const char *path)
{
	struct stat sb;

	ck_assert(stat(path, &sb) == 0);
	return (int64_t)sb.st_size;
}

/* One test's printer, plan and outcome. */
struct trial {
	struct rig r;
	struct plan pl;
	struct printer_job job;
	struct printer_file_info info;
	struct printer_result res;
	struct st_error err;
	bool homed;
};

/* Open dialect's printer (faults as rig_open) and stream the job under a
 * plan: ask `after` once `at` commands are done. */
static void trial_run(struct trial *t, int dialect, enum printer_control after, uint64_t at,
		      long reset_at, long unplug_at)
{
	memset(t, 0, sizeof(*t));
	t->pl.after = after;
	t->pl.at = at;
	rig_open(&t->r, dialect, reset_at, unplug_at);
	run(&t->r, &t->pl, &t->job, &t->info, &t->res, &t->err);
}

START_TEST(stream_whole_job)
{
	struct trial t;

	trial_run(&t, _i, PRINTER_GO, 0, 0, 0);
	ck_assert_msg(t.res.end == PRINTER_END_DONE, "end %d: %s", t.res.end, t.err.msg);
	ck_assert(!t.res.safe_stop);
	ck_assert_int_eq(t.res.last.filepos, file_size(t.r.gcode));
	ck_assert_uint_eq(t.res.last.done, t.info.commands);
	ck_assert_int_eq(t.pl.max_layer, PT_LAYERS - 1);
	ck_assert(t.res.last.tool && t.res.last.bed);
	ck_assert_uint_eq(executed(&t.r, &t.homed), t.info.commands);
	rig_close(&t.r);
}
END_TEST

/* Thin layers printed fast (15 short moves each): every layer change is
 * reported, not one call per 200 ms, so the journal `stratum print` keeps
 * from these calls never lags the printer by layers (issue 17 defect 4). */
START_TEST(every_layer_reported)
{
	struct trial t;
	FILE *f;

	memset(&t, 0, sizeof(t));
	rig_open(&t.r, _i, 0, 0);
	f = fopen(t.r.gcode, "w");
	ck_assert(f);
	fprintf(f, "M73 P0\nG28\nG92 E0\n");
	for (int l = 0; l < 60; l++) {
		fprintf(f, ";LAYER:%d\nG1 Z%.2f F6000\n", l, 0.2 * (l + 1));
		for (int k = 0; k < 15; k++)
			fprintf(f, "G1 X%d Y%d F6000\n", 10 + (k + l) % 2, 10 + k);
	}
	fprintf(f, "M73 P100\n");
	fclose(f);
	run(&t.r, &t.pl, &t.job, &t.info, &t.res, &t.err);
	ck_assert_msg(t.res.end == PRINTER_END_DONE, "end %d: %s", t.res.end, t.err.msg);
	ck_assert_int_eq(t.pl.max_layer, 59);
	/* Every layer is told, also when one driver step confirms several
	 * short layers at once (the 200 ms sampling told about one in six). */
	ck_assert_msg(t.pl.layers_told == 60 && t.pl.layer_jump <= 1,
		      "dialect %d: the hook told %ld of 60 layers, skipping up to %ld at once",
		      _i, t.pl.layers_told, t.pl.layer_jump - 1);
	rig_close(&t.r);
}
END_TEST

START_TEST(hold_then_go_on)
{
	struct trial t;

	trial_run(&t, _i, PRINTER_HOLD, 40, 0, 0);
	ck_assert_msg(t.res.end == PRINTER_END_DONE, "end %d: %s", t.res.end, t.err.msg);
	ck_assert_msg(t.pl.saw_paused && t.pl.released, "the hold was never reported");
	ck_assert_uint_eq(executed(&t.r, &t.homed), t.info.commands);
	rig_close(&t.r);
}
END_TEST

/* Cancel, safe stop, then the same printer takes a whole job. */
START_TEST(cancel_safe_stop_then_next_job)
{
	struct trial t;
	struct plan go = {.after = PRINTER_GO};
	struct printer_job job2 = {0};

	trial_run(&t, _i, PRINTER_CANCEL, 40, 0, 0);
	ck_assert_int_eq(t.res.end, PRINTER_END_CANCELLED);
	ck_assert(t.res.safe_stop);
	ck_assert_uint_lt(t.res.last.done, t.info.commands);
	ck_assert_msg(printer_safe_stop(t.r.p, &t.err) == 0, "%s", t.err.msg);
	memset(&t.err, 0, sizeof(t.err));
	run(&t.r, &go, &job2, &t.info, &t.res, &t.err);
	ck_assert_msg(t.res.end == PRINTER_END_DONE, "the next job: end %d: %s", t.res.end,
		      t.err.msg);
	ck_assert_uint_eq(t.res.last.done, t.info.commands);
	ck_assert_uint_gt(executed(&t.r, &t.homed), t.info.commands);
	rig_close(&t.r);
}
END_TEST

START_TEST(stop_is_not_cancel)
{
	struct trial t;

	trial_run(&t, _i, PRINTER_STOP, 40, 0, 0);
	ck_assert_int_eq(t.res.end, PRINTER_END_STOPPED);
	ck_assert(t.res.safe_stop);
	ck_assert_int_gt(t.res.last.filepos, 0);
	ck_assert_int_lt(t.res.last.filepos, file_size(t.r.gcode));
	ck_assert_msg(printer_safe_stop(t.r.p, &t.err) == 0, "%s", t.err.msg);
	rig_close(&t.r);
}
END_TEST

/* A board reset and an unplugged cable mid-job: the link is lost, where it
 * got is kept.  Not too early: Sailfish shows a reset only once the driver
 * has seen the build running (its build statistics, every second). */
START_TEST(reset_and_unplug_lose_the_link)
{
	for (int fault = 0; fault < 2; fault++) {
		struct trial t;

		trial_run(&t, _i, PRINTER_GO, 0, fault ? 0 : 150, fault ? 150 : 0);
		ck_assert_msg(t.res.end == PRINTER_END_LINK_LOST, "%s: end %d: %s",
			      fault ? "unplug" : "reset", t.res.end, t.err.msg);
		ck_assert(!t.res.safe_stop);
		ck_assert_int_lt(t.res.last.filepos, file_size(t.r.gcode));
		ck_assert_msg(strstr(t.err.msg, "link was lost"), "%s", t.err.msg);
		rig_close(&t.r);
	}
}
END_TEST

/* A resume from layer 4: the preamble homes X and Y only, then the rest runs once. */
START_TEST(resume_from_a_layer)
{
	struct rig r;
	struct plan pl = {.after = PRINTER_GO};
	struct printer_job job = {0};
	struct printer_file_info info, rest;
	struct printer_result res;
	struct st_error err = {0};
	int64_t offset;
	long layer;
	bool homed;

	rig_open(&r, _i, 0, 0);
	/* the layer holding a position in the middle of layer 4 */
	ck_assert_msg(resume_layer_start(r.gcode, file_size(r.gcode) * 5 / 9, &offset, &layer,
					 &err) == 0, "%s", err.msg);
	ck_assert_int_ge(layer, 3);
	job.path = r.gcode;
	job.offset = offset;
	ck_assert_msg(printer_check(r.ops, &r.o, &job, NULL, NULL, &rest, &err) == 0, "%s",
		      err.msg);
	job.resume = true;
	run(&r, &pl, &job, &info, &res, &err);
	ck_assert_msg(res.end == PRINTER_END_DONE, "end %d: %s", res.end, err.msg);
	ck_assert_uint_gt(info.commands, rest.commands); /* the preamble came first */
	ck_assert_int_eq(res.last.filepos, file_size(r.gcode));
	ck_assert_uint_eq(executed(&r, &homed), info.commands);
	ck_assert_msg(homed, "the preamble did not home X and Y");
	rig_close(&r);
}
END_TEST

/* An X3G file is one dialect's only; a bad line is refused before anything is sent. */
START_TEST(check_refuses_bad_files)
{
	struct rig r;
	struct printer_job job = {0};
	struct printer_file_info info;
	struct st_error err = {0};
	const char *bad = tu_path("pt-bad.gcode");

	rig_open(&r, _i, 0, 0);
	tu_write_str(bad, "G28\nG1 X10 Y10 F3000\nG1 X1.2.3\n");
	job.path = bad;
	ck_assert_int_eq(printer_check(r.ops, &r.o, &job, NULL, NULL, &info, &err), ST_ERR_PARSE);
	ck_assert_msg(strstr(err.msg, "line 3") && strstr(err.msg, "nothing was sent"), "%s",
		      err.msg);
	ck_assert(r.ops->takes_x3g == (_i == 1));
	rig_close(&r);
}
END_TEST

Suite *printer_suite(void)
{
	Suite *s = suite_create("printer");
	TCase *tc = tcase_create("adapters");

	tcase_set_timeout(tc, 60);
	tcase_add_loop_test(tc, stream_whole_job, 0, 2);
	tcase_add_loop_test(tc, every_layer_reported, 0, 2);
	tcase_add_loop_test(tc, hold_then_go_on, 0, 2);
	tcase_add_loop_test(tc, cancel_safe_stop_then_next_job, 0, 2);
	tcase_add_loop_test(tc, stop_is_not_cancel, 0, 2);
	tcase_add_loop_test(tc, reset_and_unplug_lose_the_link, 0, 2);
	tcase_add_loop_test(tc, resume_from_a_layer, 0, 2);
	tcase_add_loop_test(tc, check_refuses_bad_files, 0, 2);
	suite_add_tcase(s, tc);
	return s;
}
