/*
 * check_jobs.c - `stratum jobs` on a state directory of made-up jobs: list
 * and show read the journals; prune removes the old and, over the size
 * cap, the oldest jobs, but never a running one and a resumable one only
 * with --resumable; `stratum print` keeps the directory under the cap.
 */
#include <check.h>
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "jobs.h"
#include "suites.h"
#include "testutil.h"

static char out[1 << 16];
static char state[512], jobs[600];

/* A fresh state directory for this test ($STRATUM_STATE_DIR). */
static void fresh_state(const char *name)
{
	snprintf(state, sizeof(state), "%s", tu_path(name));
	snprintf(jobs, sizeof(jobs), "%s/jobs", state);
	ck_assert_int_eq(tu_sh(out, sizeof(out), "rm -rf %s && mkdir -p %s", state, jobs), 0);
	setenv("STRATUM_STATE_DIR", state, 1);
	unsetenv(JOBS_MAX_ENV);
}

/* A job ID of the given state, last updated days ago, with a G-code of
 * gcode_bytes beside its journal (none when 0). */
static void make_job(const char *id, const char *st, double days, size_t gcode_bytes)
{
	char path[1024], gpath[1024];
	json_t *o;

	snprintf(gpath, sizeof(gpath), "%s/%s.gcode", jobs, id);
	o = json_pack("{s:s, s:s, s:s, s:s, s:s, s:s, s:i, s:i, s:i, s:n, s:I}", "id", id, "gcode",
		      gpath, "sha256", "00", "printer", "printers/generic-marlin.ini", "port", "sim",
		      "state", st, "lines", 100, "last_line", 40, "layer", 3, "z",
		      "updated", (json_int_t)(time(NULL) - (time_t)(days * 86400)));
	snprintf(path, sizeof(path), "%s/%s.json", jobs, id);
	ck_assert_int_eq(json_dump_file(o, path, 0), 0);
	json_decref(o);
	if (gcode_bytes) {
		char *g = malloc(gcode_bytes);
		memset(g, ';', gcode_bytes);
		tu_write(gpath, g, gcode_bytes);
		free(g);
	}
}

static bool job_exists(const char *id)
{
	char path[1024];

	snprintf(path, sizeof(path), "%s/%s.json", jobs, id);
	return tu_file_exists(path);
}

START_TEST(prune_by_age_keeps_running_and_resumable)
{
	char running[64];
	int rc;

	fresh_state("jobs-age");
	snprintf(running, sizeof(running), "20260101-000000-%ld", (long)getpid());
	make_job("20260101-000000-1", "done", 40, 1000);
	make_job("20260102-000000-2", "link-lost", 39, 1000);
	make_job("20260103-000000-3", "done", 2, 1000);
	make_job(running, "printing", 35, 1000); /* this process: alive */
	rc = tu_run(out, sizeof(out), "jobs prune --older-than 30d");
	ck_assert_msg(rc == 0, "exit %d: %s", rc, out);
	ck_assert_msg(!job_exists("20260101-000000-1"), "the old done job was kept: %s", out);
	ck_assert_msg(tu_file_exists(tu_path("jobs-age/jobs/20260101-000000-1.gcode")) == 0,
		      "its G-code was kept");
	ck_assert_msg(job_exists("20260102-000000-2"), "a resumable job was removed: %s", out);
	ck_assert(job_exists("20260103-000000-3"));
	ck_assert_msg(job_exists(running), "a running job was removed");
	ck_assert_ptr_nonnull(strstr(out, "--resumable"));
	/* asked: the resumable one goes too, the running one never */
	rc = tu_run(out, sizeof(out), "jobs prune --older-than 30d --resumable");
	ck_assert_msg(rc == 0, "exit %d: %s", rc, out);
	ck_assert(!job_exists("20260102-000000-2"));
	ck_assert(job_exists(running));
}
END_TEST

START_TEST(prune_to_the_cap_oldest_first)
{
	json_t *o;
	int rc;

	fresh_state("jobs-cap");
	make_job("20260101-000000-11", "done", 5, 3000);
	make_job("20260102-000000-12", "done", 4, 3000);
	make_job("20260103-000000-13", "done", 3, 3000);
	/* --dry-run names them and removes nothing */
	rc = tu_run(out, sizeof(out), "jobs prune --max-size 0.004 --dry-run --json");
	ck_assert_msg(rc == 0, "exit %d: %s", rc, out);
	o = json_loads(out, 0, NULL);
	ck_assert_msg(o != NULL, "not JSON: %s", out);
	ck_assert_int_eq(json_array_size(json_object_get(o, "removed")), 2);
	ck_assert_str_eq(json_string_value(json_array_get(json_object_get(o, "removed"), 0)),
			 "20260101-000000-11");
	json_decref(o);
	ck_assert(job_exists("20260101-000000-11"));
	rc = tu_run(out, sizeof(out), "jobs prune --max-size 0.004");
	ck_assert_msg(rc == 0, "exit %d: %s", rc, out);
	ck_assert(!job_exists("20260101-000000-11"));
	ck_assert(!job_exists("20260102-000000-12"));
	ck_assert(job_exists("20260103-000000-13"));
	/* print trims to the cap ($STRATUM_JOBS_MAX_MB) before a new job */
	make_job("20260104-000000-14", "done", 2, 3000);
	tu_write_str(tu_path("jobs-cap.gcode"), "G28\nG1 X10 Y10 F3000\nG1 X20\n");
	setenv(JOBS_MAX_ENV, "0.005", 1);
	rc = tu_run(out, sizeof(out), "print %s --printer generic-marlin", tu_path("jobs-cap.gcode"));
	unsetenv(JOBS_MAX_ENV);
	ck_assert_msg(rc == 0, "exit %d: %s", rc, out);
	ck_assert_msg(!job_exists("20260103-000000-13"), "print kept the jobs over the cap: %s", out);
	ck_assert(job_exists("20260104-000000-14"));
	ck_assert_ptr_nonnull(strstr(out, "removed 1 old job"));
}
END_TEST

START_TEST(list_and_show)
{
	json_t *o, *arr;
	int rc;

	fresh_state("jobs-list");
	make_job("20260101-000000-21", "done", 3, 500);
	make_job("20260102-000000-22", "cancelled", 1, 500);
	tu_write_str(tu_path("jobs-list/jobs/print-2147483646.gcode"), "G1 X1\n"); /* no journal */
	rc = tu_run(out, sizeof(out), "jobs list --json");
	ck_assert_msg(rc == 0, "exit %d: %s", rc, out);
	o = json_loads(out, 0, NULL);
	ck_assert_msg(o != NULL, "not JSON: %s", out);
	arr = json_object_get(o, "jobs");
	ck_assert_int_eq(json_array_size(arr), 3);
	ck_assert_str_eq(json_string_value(json_object_get(json_array_get(arr, 0), "kind")), "done");
	ck_assert_str_eq(json_string_value(json_object_get(json_array_get(arr, 1), "kind")),
			 "resumable");
	ck_assert_int_eq(json_integer_value(json_object_get(o, "cap_bytes")),
			 (json_int_t)JOBS_MAX_MB_DEFAULT * 1000000);
	json_decref(o);
	rc = tu_run(out, sizeof(out), "jobs show 20260102-000000-22");
	ck_assert_msg(rc == 0, "exit %d: %s", rc, out);
	ck_assert_ptr_nonnull(strstr(out, "stratum print --resume 20260102-000000-22"));
	ck_assert_int_eq(tu_run(out, sizeof(out), "jobs show 20990101-000000-9"), 2);
	ck_assert_ptr_nonnull(strstr(out, "no job 20990101-000000-9"));
	ck_assert_int_eq(tu_run(out, sizeof(out), "jobs list --older-than 3d"), 2);
	ck_assert_int_eq(tu_run(out, sizeof(out), "jobs prune --older-than 30"), 2);
	ck_assert_int_eq(tu_run(out, sizeof(out), "jobs frobnicate"), 2);
	/* a leftover G-code (its process is gone) goes by its age, as a done job */
	ck_assert_int_eq(tu_sh(out, sizeof(out), "touch -d '10 days ago' %s",
			       tu_path("jobs-list/jobs/print-2147483646.gcode")), 0);
	ck_assert_int_eq(tu_run(out, sizeof(out), "jobs prune --older-than 2d"), 0);
	ck_assert(!tu_file_exists(tu_path("jobs-list/jobs/print-2147483646.gcode")));
	ck_assert(!job_exists("20260101-000000-21"));
	ck_assert(job_exists("20260102-000000-22"));
}
END_TEST

START_TEST(parse_age)
{
	int64_t s;

	ck_assert(jobs_parse_age("30d", &s) && s == 30 * 86400);
	ck_assert(jobs_parse_age("12h", &s) && s == 12 * 3600);
	ck_assert(jobs_parse_age("2w", &s) && s == 14 * 86400);
	ck_assert(jobs_parse_age("90s", &s) && s == 90);
	ck_assert(!jobs_parse_age("30", &s));
	ck_assert(!jobs_parse_age("-3d", &s));
	ck_assert(!jobs_parse_age("3dd", &s));
	ck_assert(!jobs_parse_age("", &s));
}
END_TEST

Suite *jobs_suite(void)
{
	Suite *s = suite_create("jobs");
	TCase *tc = tcase_create("jobs");

	tcase_set_timeout(tc, 60);
	tcase_add_test(tc, parse_age);
	tcase_add_test(tc, prune_by_age_keeps_running_and_resumable);
	tcase_add_test(tc, prune_to_the_cap_oldest_first);
	tcase_add_test(tc, list_and_show);
	suite_add_tcase(s, tc);
	return s;
}
