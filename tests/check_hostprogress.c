/*
 * check_hostprogress.c - honest progress (the "progress" suite): h:mm:ss,
 * the print ETA from the slicer's estimate corrected by the pace, lines
 * that fit 60 columns, layers counted from 1, the simulated printer's own
 * clock, and repair phases that report real fractions.
 */
#include <check.h>
#include <math.h>
#include <regex.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fixtures.h"
#include "mesh.h"
#include "print_job.h"
#include "printer.h"
#include "printer_profile.h"
#include "profile.h"
#include "progress.h"
#include "repair.h"
#include "send.h"
#include "suites.h"
#include "testutil.h"

START_TEST(hms_is_hours_minutes_seconds)
{
	char b[32];

	progress_hms(b, sizeof(b), 0);
	ck_assert_str_eq(b, "0:00:00");
	progress_hms(b, sizeof(b), 45 * 60 + 38); /* the bracket's estimate */
	ck_assert_str_eq(b, "0:45:38");
	progress_hms(b, sizeof(b), 227 * 60 + 32); /* not "227:32" */
	ck_assert_str_eq(b, "3:47:32");
	progress_hms(b, sizeof(b), 59.6);
	ck_assert_str_eq(b, "0:01:00");
	progress_hms(b, sizeof(b), NAN);
	ck_assert_str_eq(b, "-:--:--");
	progress_hms(b, sizeof(b), -3);
	ck_assert_str_eq(b, "-:--:--");
}
END_TEST

START_TEST(eta_follows_the_estimate_then_the_pace)
{
	const double total = 45 * 60 + 38;

	/* Nothing printed yet: the estimate itself, over the prior pace. */
	ck_assert_double_eq_tol(progress_eta(0, total, 0, 1), total, 1e-9);
	ck_assert_double_eq_tol(progress_eta(0, total, 0, 1000), total / 1000, 1e-9);
	/* Three minutes in on pace: 42:38 left, not a line-rate guess. */
	ck_assert_double_eq_tol(progress_eta(180, total - 180, 180, 1), total - 180, 1e-6);
	/* Past a tenth of the print at half the estimated pace: twice the rest. */
	ck_assert_double_eq_tol(progress_eta(600, total - 600, 1200, 1), 2 * (total - 600), 1e-6);
	/* Early on a slow pace counts only in part: between the two. */
	double early = progress_eta(60, total - 60, 120, 1);
	ck_assert_msg(early > total - 60 && early < 2 * (total - 60), "%g", early);
	/* The simulator at 1000x: wall seconds, not printing seconds. */
	ck_assert_double_eq_tol(progress_eta(1000, total - 1000, 1, 1000), (total - 1000) / 1000,
				1e-6);
	ck_assert_double_eq_tol(progress_eta(total, 0, 100, 1), 0, 1e-9);
}
END_TEST

START_TEST(fit_drops_fields_to_the_width)
{
	char out[256];
	const struct progress_field f[] = {
	    {"[print]", 3}, {" 37%", 0}, {"layer 12/80", 1}, {"line 3456/39450", 2},
	    {"T 215/215 B 60/60", 5}, {"0:01:02 elapsed", 4}, {"ETA 0:28:41", 0},
	};
	size_t n = progress_fit(out, sizeof(out), 160, f, 7);

	ck_assert_uint_eq(n, strlen(out));
	ck_assert_str_eq(out, "[print]  37% layer 12/80 line 3456/39450 T 215/215 B 60/60 0:01:02 "
			      "elapsed ETA 0:28:41");
	n = progress_fit(out, sizeof(out), 60, f, 7);
	ck_assert_msg(n <= 59 && strlen(out) == n, "%zu: %s", n, out);
	ck_assert_str_eq(out, "[print]  37% layer 12/80 line 3456/39450 ETA 0:28:41");
	n = progress_fit(out, sizeof(out), 20, f, 7);
	ck_assert_msg(n <= 19, "%zu: %s", n, out);
	ck_assert_str_eq(out, " 37% ETA 0:28:41");
	n = progress_fit(out, sizeof(out), 10, f, 7); /* what is left is cut */
	ck_assert_str_eq(out, " 37% ETA ");
}
END_TEST

/* Whether s matches the extended regular expression re. */
static bool matches(const char *s, const char *re)
{
	regex_t r;
	bool m;

	ck_assert_int_eq(regcomp(&r, re, REG_EXTENDED | REG_NOSUB), 0);
	m = regexec(&r, s, 0, NULL, 0) == 0;
	regfree(&r);
	return m;
}

START_TEST(print_line_fits_and_counts_layers_from_one)
{
	struct send_progress p;
	struct printer_progress v = {.unit = "line", .done = 3456, .total = 39450, .layer = 11,
				     .tool = true, .tool_actual = 215, .tool_target = 215,
				     .bed = true, .bed_actual = 60, .bed_target = 60};
	char line[512];
	size_t n;

	send_progress_start(&p);
	p.tag = "print";
	p.layers = 80;
	p.est_total = 45 * 60 + 38;
	p.est_done = 180;
	p.t_moving = p.t0 + 1; /* moving since 1 s in */
	n = send_progress_line(&p, &v, p.t0 + 181, 160, line, sizeof(line));
	ck_assert_msg(n <= 159, "%s", line);
	ck_assert_msg(strstr(line, "layer 12/80"), "%s", line); /* layer 11 0-based */
	ck_assert_msg(strstr(line, "T 215/215 B 60/60"), "%s", line);
	ck_assert_msg(strstr(line, "ETA 0:42:38"), "on pace: the estimate less 3 min: %s", line);
	ck_assert_msg(strstr(line, "0:03:01 elapsed"), "%s", line);
	n = send_progress_line(&p, &v, p.t0 + 181, 60, line, sizeof(line));
	ck_assert_msg(n <= 59 && strlen(line) == n, "%zu: %s", n, line);
	ck_assert_msg(matches(line, "ETA [0-9]+:[0-5][0-9]:[0-5][0-9]$"), "%s", line);
	ck_assert_msg(strstr(line, "layer 12/80"), "%s", line);
	/* Heating: the temperatures stay at 60 columns. */
	v.tool_actual = 150;
	send_progress_line(&p, &v, p.t0 + 181, 60, line, sizeof(line));
	ck_assert_msg(strstr(line, "T 150/215"), "%s", line);
	/* The first layer is layer 1, whatever the dialect. */
	v.layer = 0;
	send_progress_line(&p, &v, p.t0 + 181, 160, line, sizeof(line));
	ck_assert_msg(strstr(line, "layer 1/80"), "%s", line);
	/* No estimate: the line rate, still h:mm:ss. */
	p.est_total = 0;
	v.done = 3945;
	send_progress_line(&p, &v, p.t0 + 60, 160, line, sizeof(line));
	ck_assert_msg(strstr(line, "ETA 0:09:00"), "%s", line);
}
END_TEST

START_TEST(time_comments_of_slicers)
{
	ck_assert_double_eq(print_time_comment(" estimated printing time = 1h 2m 3s"), 3723);
	ck_assert_double_eq(print_time_comment(" estimated printing time (normal mode) = 45m 38s"),
			    2738);
	ck_assert_double_eq(print_time_comment(" estimated printing time = 1d 0h 0m 1s"), 86401);
	ck_assert(isnan(print_time_comment(" estimated printing time (silent mode) = 47m 1s")));
	ck_assert(isnan(print_time_comment(" estimated first layer printing time = 1m")));
	ck_assert(isnan(print_time_comment(" filament used [mm] = 12")));
}
END_TEST

/* Layers of two 50 mm moves at 10 mm/s (10 s each), then one twice as long. */
static void write_timed_gcode(const char *path, const char *header)
{
	FILE *f = fopen(path, "w");

	ck_assert_ptr_nonnull(f);
	fprintf(f, "%sG28\nG90\nM82\nM104 S200\n", header);
	for (int l = 0; l < 4; l++) {
		fprintf(f, ";LAYER_CHANGE\n;Z:%.1f\nG1 Z%.1f F600\n", 0.2 * (l + 1), 0.2 * (l + 1));
		for (int k = 0; k < (l == 3 ? 4 : 2); k++)
			fprintf(f, "G1 X%d Y0 E%d F600\n", k % 2 ? 0 : 50, l * 10 + k + 1);
	}
	fclose(f);
}

START_TEST(layers_carry_the_estimate)
{
	const char *path = tu_path("eta.gcode");
	struct print_layers L;

	write_timed_gcode(path, "");
	ck_assert_int_eq(print_scan(path, &L), 0);
	ck_assert_uint_eq(L.n, 4);
	ck_assert_msg(L.est_total > 40 && L.est_total < 60, "%g", L.est_total);
	for (size_t i = 1; i < L.n; i++)
		ck_assert_msg(L.v[i].est > L.v[i - 1].est, "layer %zu", i);
	/* The last layer holds twice the moves of the others. */
	double last = L.est_total - L.v[3].est, second = L.v[2].est - L.v[1].est;
	ck_assert_msg(fabs(last / second - 2) < 0.1, "%g vs %g", last, second);
	/* Half through a layer's lines: about half its time. */
	double mid = print_est_done(&L, 1, (L.v[1].line + L.v[2].line) / 2);
	ck_assert_msg(mid > L.v[1].est && mid < L.v[2].est, "%g", mid);
	ck_assert_double_eq(print_est_done(&L, -1, 3), 0);
	free(L.v);
	/* The slicer's stated total wins; the layers keep their shares. */
	write_timed_gcode(path, "; estimated printing time = 0h 1m 40s\n");
	ck_assert_int_eq(print_scan(path, &L), 0);
	ck_assert_double_eq_tol(L.est_total, 100, 1e-9);
	ck_assert_msg(fabs((L.est_total - L.v[3].est) / (L.v[2].est - L.v[1].est) - 2) < 0.1,
		      "scaled layers");
	free(L.v);
	/* Or the first M73's minutes. */
	write_timed_gcode(path, "M73 P0 R2\n");
	ck_assert_int_eq(print_scan(path, &L), 0);
	ck_assert_double_eq_tol(L.est_total, 120, 1e-9);
	free(L.v);
}
END_TEST

/* The machine clock of a simulated stream of path on profile prof at speedup k. */
static double machine_clock(const char *prof_name, const char *path, double k)
{
	struct profile *prof = NULL;
	struct printer_options o;
	const struct printer_ops *ops;
	struct printer *pr = NULL;
	struct printer_file_info info;
	struct printer_result res;
	struct printer_job job = {.path = path};
	struct st_error err = {0};

	ck_assert_msg(profile_find(prof_name, &prof, &err) == 0, "%s", err.msg);
	ck_assert_msg(printer_profile_options(prof, "sim", 0, &o, &ops, &err) == 0, "%s", err.msg);
	o.sim_speedup = k;
	ck_assert_msg(printer_check(ops, &o, &job, NULL, NULL, &info, &err) == 0, "%s", err.msg);
	job.total = info.commands;
	ck_assert_msg(printer_open(ops, &o, &pr, &err) == 0, "%s", err.msg);
	ck_assert_msg(printer_stream(pr, &job, &res, &err) == 0, "%s", err.msg);
	ck_assert_int_eq(res.end, PRINTER_END_DONE);
	printer_close(pr);
	profile_free(prof);
	return res.machine_s;
}

START_TEST(printer_time_is_the_simulators_clock)
{
	const char *path = tu_path("clock.gcode");
	double a, b;

	/* Homing 5 s, two 100 mm moves at 10 mm/s (10.01 s each with
	 * acceleration 1000 mm/s^2), a 5 s dwell: 30.02 s on the machine. */
	tu_write_str(path, "G28\nG90\nG1 X100 F600\nG1 X0\nG4 S5\n");
	a = machine_clock("generic-marlin", path, 100);
	b = machine_clock("generic-marlin", path, 1000);
	ck_assert_msg(fabs(a - 30.02) < 0.01, "Marlin at 100x: %g s", a);
	ck_assert_msg(fabs(b - 30.02) < 0.01, "Marlin at 1000x: %g s", b);
	/* Sailfish: the same figure whatever the speed-up. */
	a = machine_clock("flashforge-creator-pro", path, 100);
	b = machine_clock("flashforge-creator-pro", path, 1000);
	ck_assert_msg(a > 20 && fabs(a - b) < 0.01 * a, "Sailfish: %g s at 100x, %g s at 1000x", a,
		      b);
}
END_TEST

/* What a repair's progress hook saw. */
#define SEEN_MAX 4096
struct seen {
	char stage[SEEN_MAX][96];
	double done[SEEN_MAX];
	size_t n;
};

static void record(void *ctx, const char *stage, double done)
{
	struct seen *s = ctx; /* one call at a time, by the contract */

	if (s->n < SEEN_MAX) {
		snprintf(s->stage[s->n], sizeof(s->stage[0]), "%s", stage);
		s->done[s->n++] = done;
	}
}

START_TEST(repair_reports_real_fractions)
{
	struct mesh *soup = fx_soup(1, 2000, 10 * cbrt(2000.0) / 2, 10); /* gen_mesh soup 2000 10 1 */
	struct repair_options opt;
	struct repair_report rep;
	struct mesh *out = NULL;
	struct st_error err = {0};
	struct seen *s = calloc(1, sizeof(*s));
	size_t best = 0;

	ck_assert_ptr_nonnull(soup);
	ck_assert_ptr_nonnull(s);
	repair_options_init(&opt);
	opt.progress = record;
	opt.progress_ctx = s;
	ck_assert_msg(repair_mesh(soup, &opt, &out, NULL, &rep, &err) == 0, "%s", err.msg);
	ck_assert_uint_gt(s->n, 0);
	for (size_t i = 0; i < s->n; i++) {
		size_t inside = 0;

		/* phases read as sentences, never a bare "done" */
		ck_assert_msg(strchr(s->stage[i], ' '), "phase '%s'", s->stage[i]);
		ck_assert_msg(s->done[i] >= 0 && s->done[i] <= 1, "%s %g", s->stage[i], s->done[i]);
		for (size_t j = i; j < s->n && !strcmp(s->stage[j], s->stage[i]); j++)
			inside += s->done[j] > 0 && s->done[j] < 1;
		if (inside > best)
			best = inside;
	}
	/* Some phase moved through its work, not one figure per phase. */
	ck_assert_msg(best >= 3, "the most fractions one phase reported inside (0, 1): %zu", best);
	mesh_free(out);
	mesh_free(soup);
	free(s);
}
END_TEST

Suite *progress_suite(void)
{
	Suite *s = suite_create("progress");
	TCase *tc = tcase_create("lines");

	tcase_add_test(tc, hms_is_hours_minutes_seconds);
	tcase_add_test(tc, eta_follows_the_estimate_then_the_pace);
	tcase_add_test(tc, fit_drops_fields_to_the_width);
	tcase_add_test(tc, print_line_fits_and_counts_layers_from_one);
	tcase_add_test(tc, time_comments_of_slicers);
	tcase_add_test(tc, layers_carry_the_estimate);
	suite_add_tcase(s, tc);
	tc = tcase_create("sources");
	tcase_set_timeout(tc, 300);
	tcase_add_test(tc, printer_time_is_the_simulators_clock);
	tcase_add_test(tc, repair_reports_real_fractions);
	suite_add_tcase(s, tc);
	return s;
}
