/*
 * check_gcodewriter_cooling.c - slicer/gcode_writer*.c and slicer/estimate.c,
 * part of the gcodewriter suite (check_gcodewriter.c): temperatures, the fan
 * by layer time and bridges, slow-down, and the planner against analytic
 * trapezoids, triangles and corners.
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "estimate.h"
#include "gcode.h"
#include "gcode_writer.h"
#include "gcodewritertest.h"
#include "settings.h"
#include "suites.h"
#include "testutil.h"

START_TEST(test_temperatures)
{
	struct layer_stack *st = stack_new(3, 0.2);
	struct gcodew_settings s;
	char *g;

	for (int i = 0; i < 3; i++)
		add_square(&st->layers[i], PATH_OUTER_PERIMETER, 0, 0, 10, 0.45);
	gcodew_settings_init(&s);
	s.first_layer_temperature = 215;
	s.temperature = 205;
	s.first_layer_bed_temperature = 60;
	s.bed_temperature = 55;
	g = tu_gcode_mem(st, &s, NULL);
	/* Default start G-code sets no temperature: waits around it. */
	ck_assert_int_lt(at(g, "\nM190 S60"), at(g, "\nG28"));
	ck_assert_int_lt(at(g, "\nM104 S215"), at(g, "\nG28"));
	ck_assert_int_lt(at(g, "\nG28"), at(g, "\nM109 S215"));
	ck_assert_int_lt(at(g, "\nM109 S215"), at(g, ";LAYER_CHANGE"));
	/* The other temperatures at layer 2, once. */
	ck_assert_int_lt(nth(g, ";LAYER_CHANGE", 2), at(g, "\nM104 S205"));
	ck_assert_int_lt(at(g, "\nM104 S205"), nth(g, ";LAYER_CHANGE", 3));
	ck_assert_int_lt(nth(g, ";LAYER_CHANGE", 2), at(g, "\nM140 S55"));
	ck_assert_int_lt(at(g, "\nM140 S55"), nth(g, ";LAYER_CHANGE", 3));
	ck_assert_int_eq(count(g, "\nM104 S205"), 1);
	ck_assert_int_eq(count(g, "\nM140 "), 1);
	free(g);

	/* A start G-code that heats itself gets no extra waits. */
	s.start_gcode = "M140 S[first_layer_bed_temperature]\nM104 S[first_layer_temperature]\n"
			"G28\nM190 S{first_layer_bed_temperature[0]}\nM109 S[first_layer_temperature]\n";
	g = tu_gcode_mem(st, &s, NULL);
	ck_assert_int_eq(count(g, "\nM109 "), 1);
	ck_assert_int_eq(count(g, "\nM190 "), 1);
	ck_assert_int_eq(count(g, "\nM104 S215"), 1);
	ck_assert_int_lt(at(g, "\nM140 S60\n"), at(g, "\nG28"));
	free(g);
	layer_stack_free(st);
}
END_TEST

/* Fan percent PrusaSlicer's rule gives for layer time t (test's own copy). */
static double want_fan_s(const struct gcodew_settings *s, double t)
{
	double pct = 0;

	if (t < s->slowdown_below_layer_time)
		pct = s->max_fan_speed;
	else if (t < s->fan_below_layer_time) {
		double k = (t - s->slowdown_below_layer_time) /
			   (s->fan_below_layer_time - s->slowdown_below_layer_time);
		pct = k * s->min_fan_speed + (1 - k) * s->max_fan_speed;
	}
	return pct * 255 / 100;
}


START_TEST(test_fan)
{
	static const double bridge[] = {20, 20, 40, 20};
	static const double bw[] = {0.45, 0.45};
	struct layer_stack *st = stack_new(5, 0.2);
	struct gcodew_settings s;
	struct replay r = {0};
	char *g;

	/* Layers: tiny, tiny, ~30 s, ~67 s, tiny with a bridge. */
	add_square(&st->layers[0], PATH_INNER_PERIMETER, 0, 0, 10, 0.45);
	add_square(&st->layers[1], PATH_INNER_PERIMETER, 0, 0, 10, 0.45);
	add_square(&st->layers[2], PATH_INNER_PERIMETER, 0, 0, 450, 0.45);
	add_square(&st->layers[3], PATH_INNER_PERIMETER, 0, 0, 1000, 0.45);
	add_square(&st->layers[4], PATH_INNER_PERIMETER, 0, 0, 10, 0.45);
	add_line(&st->layers[4], PATH_BRIDGE, bridge, bw, 2);
	add_square(&st->layers[4], PATH_SOLID_INFILL, 0, 0, 10, 0.45);
	gcodew_settings_init(&s);
	s.disable_fan_first_layers = 1;
	s.bridge_fan_speed = 80;
	s.min_print_speed = 1000; /* no slow-down can happen: fan only */
	s.small_perimeter_speed = s.perimeter_speed; /* the tiny squares' times as planned */
	g = write_replay(st, &s, NULL, &r);
	ck_assert_int_eq(r.fan_first[0], 0);
	ck_assert_int_lt(at(g, "\nM107\n"), at(g, ";LAYER_CHANGE"));
	ck_assert_int_eq(r.fan_first[1], 255);
	/* Layer 3: interpolated by its planned time. */
	{
		double t = moves_time(&r, &s, g1_before(g, ";Z:0.6\n"), g1_before(g, ";Z:0.8\n"));
		double want = want_fan_s(&s, t);
		ck_assert_msg(t > 20 && t < 40, "layer 3 takes %g s", t);
		ck_assert_msg(fabs(r.fan_first[2] - want) <= 1.5, "layer 3 (%.2f s): fan %d, want %.1f",
			      t, r.fan_first[2], want);
	}
	ck_assert_int_eq(r.fan_first[3], 0); /* longer than fan_below_layer_time */
	ck_assert_int_eq(r.fan_first[4], 255);
	ck_assert_int_eq(r.fan_bridge, 204);
	ck_assert_int_eq(r.fan_after_bridge, 255);
	free(g);
	free(r.moves);
	layer_stack_free(st);
}
END_TEST

START_TEST(test_slowdown)
{
	struct layer_stack *st = stack_new(3, 0.2);
	struct gcodew_settings s;
	struct replay r = {0};
	char *g;

	/* Layer 1 plain; layer 2 a 5 mm loop (0.33 s at 60 mm/s); layer 3 a
	 * 100 mm loop (6.7 s). */
	add_square(&st->layers[0], PATH_INNER_PERIMETER, 0, 0, 100, 0.45);
	add_square(&st->layers[1], PATH_INNER_PERIMETER, 0, 0, 5, 0.45);
	add_square(&st->layers[2], PATH_INNER_PERIMETER, 0, 0, 100, 0.45);
	gcodew_settings_init(&s);
	s.first_layer_speed = 0;
	g = write_replay(st, &s, NULL, &r);
	/* 20 mm in 5 s wants 4 mm/s: held at min_print_speed, 10 mm/s. */
	ck_assert_double_eq(r.fmin[1], 600);
	ck_assert_double_eq(r.fmax[1], 600);
	ck_assert_double_eq(r.fmin[2], 3600);
	ck_assert_double_eq(r.fmax[2], 3600);
	free(g);
	free(r.moves);

	/* With a lower floor the layer is stretched to 5 s exactly. */
	s.min_print_speed = 1;
	g = write_replay(st, &s, NULL, &r);
	ck_assert_msg(r.fmin[1] > 60 && r.fmax[1] < 600, "F %g..%g", r.fmin[1], r.fmax[1]);
	{
		double t = moves_time(&r, &s, g1_before(g, ";Z:0.4\n"), g1_before(g, ";Z:0.6\n"));
		ck_assert_msg(fabs(t - 5) < 0.05, "slowed layer takes %g s", t);
	}
	free(g);
	free(r.moves);
	layer_stack_free(st);
}
END_TEST

/* ---------------------------------------------------------------------------
 * The planner against analytic profiles
 */

/* Trapezoid time written out for the test: accelerate from vi to vc,
 * cruise, decelerate to vo; a triangle when the distance is too short. */
static double analytic(double d, double vi, double vc, double vo, double a)
{
	double da = (vc * vc - vi * vi) / (2 * a), dd = (vc * vc - vo * vo) / (2 * a);
	if (da + dd <= d)
		return (vc - vi) / a + (d - da - dd) / vc + (vc - vo) / a;
	double vp = sqrt((2 * a * d + vi * vi + vo * vo) / 2);
	return (vp - vi) / a + (vp - vo) / a;
}

/* Limits with one acceleration for every move and generous axes. */
static void plain_limits(struct est_limits *lim, double accel, double jerk_xy)
{
	est_limits_init(lim);
	for (int a = 0; a < EST_AXES; a++) {
		lim->max_feedrate[a] = 1000;
		lim->max_acceleration[a] = 100000;
	}
	lim->accel_extruding = lim->accel_retracting = lim->accel_travel = accel;
	lim->max_jerk[EST_X] = lim->max_jerk[EST_Y] = jerk_xy;
}

static double run_moves(const struct est_limits *lim, const struct est_move *m, size_t n)
{
	struct est_result res;
	struct st_error err = {0};

	ck_assert_msg(est_moves(lim, NULL, m, n, &res, &err) == 0, "%s", err.msg);
	ck_assert_uint_eq(res.moves, n);
	return res.time_s;
}

#define REL_EQ(got, want) \
	ck_assert_msg(fabs((got) - (want)) <= 1e-6 * (want), "%.12f s, analytic %.12f s", (got), (want))

/* The estimator's default limits are the declared machine_max_* defaults
 * (PrusaSlicer's MK3 normal mode), every one of them found. */
START_TEST(test_est_limits_are_declared)
{
	static const char axis[EST_AXES] = {'x', 'y', 'z', 'e'};
	struct est_limits lim;
	struct est_planner *p;
	struct st_error err = {0};
	char name[64];
	double v;

	est_limits_init(&lim);
	for (int a = 0; a < EST_AXES; a++) {
		snprintf(name, sizeof(name), "machine_max_feedrate_%c", axis[a]);
		ck_assert(setting_default_number(name, false, &v));
		ck_assert_double_eq(lim.max_feedrate[a], v);
		snprintf(name, sizeof(name), "machine_max_acceleration_%c", axis[a]);
		ck_assert(setting_default_number(name, false, &v));
		ck_assert_double_eq(lim.max_acceleration[a], v);
		snprintf(name, sizeof(name), "machine_max_jerk_%c", axis[a]);
		ck_assert(setting_default_number(name, false, &v));
		ck_assert_double_eq(lim.max_jerk[a], v);
	}
	ck_assert(setting_default_number("machine_max_acceleration_travel", false, &v));
	ck_assert_double_eq(lim.accel_travel, v);
	ck_assert_double_eq(lim.max_feedrate[EST_Z], 12);
	ck_assert_double_eq(lim.max_acceleration[EST_E], 10000);
	ck_assert_double_eq(lim.max_jerk[EST_E], 2.5);
	ck_assert_double_eq(lim.accel_extruding, 1500);
	ck_assert_double_eq(lim.accel_retracting, 1500);
	p = est_planner_new(&lim, NULL, &err);
	ck_assert_msg(p != NULL, "%s", err.msg);
	est_planner_free(p);
}
END_TEST

START_TEST(test_est_trapezoid)
{
	struct est_limits lim;
	struct est_move one = {100, 0, 0, 0, 100};
	double t;

	plain_limits(&lim, 1000, 0);
	t = run_moves(&lim, &one, 1);
	REL_EQ(t, analytic(100, 0, 100, 0, 1000));
	REL_EQ(t, 1.1); /* 0.1 s up, 0.9 s at 100 mm/s, 0.1 s down */
	/* With jerk the move starts and stops at the jerk speed. */
	plain_limits(&lim, 1000, 10);
	REL_EQ(run_moves(&lim, &one, 1), analytic(100, 10, 100, 10, 1000));
	/* Axis feedrate limit: X capped at 50 mm/s. */
	lim.max_feedrate[EST_X] = 50;
	REL_EQ(run_moves(&lim, &one, 1), analytic(100, 10, 50, 10, 1000));
	/* Axis acceleration limit on a diagonal: a = 300 / cos 45. */
	plain_limits(&lim, 1000, 0);
	lim.max_acceleration[EST_Y] = 300;
	struct est_move diag = {60, 60, 0, 0, 100};
	REL_EQ(run_moves(&lim, &diag, 1), analytic(60 * sqrt(2), 0, 100, 0, 300 * sqrt(2)));
}
END_TEST

START_TEST(test_est_triangle)
{
	struct est_limits lim;
	struct est_move m = {2, 0, 0, 0, 100};
	double t;

	plain_limits(&lim, 1000, 0);
	t = run_moves(&lim, &m, 1);
	/* Peak sqrt(a d) = 44.7 mm/s < 100: up and straight down. */
	REL_EQ(t, 2 * sqrt(2.0 / 1000));
	REL_EQ(t, analytic(2, 0, 100, 0, 1000));
}
END_TEST

START_TEST(test_est_corner)
{
	struct est_limits lim;
	struct est_move corner[2] = {{50, 0, 0, 0, 100}, {50, 50, 0, 0, 100}};
	struct est_move straight[2] = {{50, 0, 0, 0, 100}, {100, 0, 0, 0, 100}};
	struct est_move one = {100, 0, 0, 0, 100};

	/* X jerk allows a full-speed start; the Y jump at the corner does not:
	 * the junction runs at Y's jerk, 10 mm/s. */
	plain_limits(&lim, 1000, 10);
	lim.max_jerk[EST_X] = 100;
	REL_EQ(run_moves(&lim, corner, 2),
	       analytic(50, 100, 100, 10, 1000) + analytic(50, 10, 100, 10, 1000));
	/* The same corner with a generous jerk goes through faster. */
	lim.max_jerk[EST_Y] = 40;
	REL_EQ(run_moves(&lim, corner, 2),
	       analytic(50, 100, 100, 40, 1000) + analytic(50, 40, 100, 40, 1000));
	/* Straight on: no slow-down at the joint. */
	plain_limits(&lim, 1000, 10);
	REL_EQ(run_moves(&lim, straight, 2), run_moves(&lim, &one, 1));
	/* A reversal counts the larger speed, not the sum (Marlin): 100 -> -100
	 * on X with jerk 10 joins at 10 mm/s. */
	struct est_move back[2] = {{50, 0, 0, 0, 100}, {0, 0, 0, 0, 100}};
	REL_EQ(run_moves(&lim, back, 2),
	       analytic(50, 10, 100, 10, 1000) + analytic(50, 10, 100, 10, 1000));
}
END_TEST

/* Many short collinear moves plan like one long one, across the window. */
START_TEST(test_est_window)
{
	struct est_limits lim;
	size_t n = 5 * EST_WINDOW;
	struct est_move *m = calloc(n, sizeof(*m));
	struct est_move one = {0, 0, 0, 0, 100};
	struct est_planner *p;
	struct est_result res;

	ck_assert_ptr_nonnull(m);
	for (size_t i = 0; i < n; i++)
		m[i] = (struct est_move){0.1 * (double)(i + 1), 0, 0, 0.01 * (double)(i + 1), 100};
	one.x = m[n - 1].x;
	one.e = m[n - 1].e;
	plain_limits(&lim, 1000, 10);
	REL_EQ(run_moves(&lim, m, n), run_moves(&lim, &one, 1));
	/* A dwell stops the machine and adds its time. */
	p = est_planner_new(&lim, NULL, NULL);
	ck_assert_ptr_nonnull(p);
	ck_assert_int_eq(est_planner_add(p, &m[0], NULL), 0);
	ck_assert_int_eq(est_planner_dwell(p, 2.5, NULL), 0);
	est_planner_result(p, &res);
	REL_EQ(res.time_s, 2.5 + analytic(0.1, 10, 100, 10, 1000));
	ck_assert_double_eq_tol(res.extruded_mm, 0.01, 1e-12);
	/* Bad input is refused. */
	struct est_move bad = {1, 0, 0, 0, 0};
	struct st_error err = {0};
	ck_assert_int_eq(est_planner_add(p, &bad, &err), ST_ERR_ARG);
	ck_assert_msg(strstr(err.msg, "feedrate"), "%s", err.msg);
	est_planner_free(p);
	lim.max_acceleration[EST_Z] = 0;
	ck_assert_ptr_null(est_planner_new(&lim, NULL, &err));
	ck_assert_msg(strstr(err.msg, "machine_max_acceleration_z"), "%s", err.msg);
	free(m);
}
END_TEST

void gcodewriter_cooling_tcases(Suite *s)
{
	TCase *cool = tcase_create("cooling");
	TCase *est = tcase_create("estimate");

	tcase_add_test(cool, test_temperatures);
	tcase_add_test(cool, test_fan);
	tcase_add_test(cool, test_slowdown);
	tcase_add_test(est, test_est_limits_are_declared);
	tcase_add_test(est, test_est_trapezoid);
	tcase_add_test(est, test_est_triangle);
	tcase_add_test(est, test_est_corner);
	tcase_add_test(est, test_est_window);
	suite_add_tcase(s, cool);
	suite_add_tcase(s, est);
}
