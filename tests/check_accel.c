/*
 * check_accel.c - default_acceleration and the per-role accelerations
 * (slicer/gcode_writer_plan.c path_accel): the M204 before each path's
 * ;TYPE, the reset after it, the cap where the limits are written, and the
 * estimate taking them.  Part of the gcodewriter suite.
 */
#include <check.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gcode_writer.h"
#include "suites.h"
#include "testutil.h"

#define NM 1000000.0 /* nm per mm */

static const enum path_role roles[] = {PATH_SKIRT, PATH_OUTER_PERIMETER, PATH_SPARSE_INFILL,
				       PATH_BRIDGE, PATH_GAP_FILL};
#define NROLES (sizeof(roles) / sizeof(roles[0]))

/* Two layers, one 10 mm square of each role in roles, 20 mm apart. */
static struct layer_stack *stack(struct gcodew_settings *s)
{
	struct layer_stack *st = layer_stack_new(2, NULL);

	ck_assert_ptr_nonnull(st);
	for (size_t i = 0; i < 2; i++) {
		st->layers[i].z = 0.2 * (double)(i + 1);
		st->layers[i].height = 0.2;
		for (size_t r = 0; r < NROLES; r++) {
			double x = 10 + 20.0 * (double)r;
			struct path_point p[4] = {{x * NM, 10 * NM, 0.45 * NM},
						  {(x + 10) * NM, 10 * NM, 0.45 * NM},
						  {(x + 10) * NM, 20 * NM, 0.45 * NM},
						  {x * NM, 20 * NM, 0.45 * NM}};
			ck_assert_int_eq(layer_add_path(&st->layers[i], roles[r], true, p, 4, NULL), 0);
		}
	}
	gcodew_settings_init(s);
	return st;
}

/* The last M204 S value before each ;TYPE line of layer 2 (layer 1 when
 * first), in the order of roles; and how many M204 lines there are. */
static int accels(const char *g, bool first, int out[NROLES])
{
	int last = 0, layer = 0, n = 0;
	size_t k = 0;

	for (const char *l = g; *l; l = strchr(l, '\n') ? strchr(l, '\n') + 1 : l + strlen(l)) {
		int v;

		if (!strncmp(l, ";LAYER_CHANGE", 13))
			layer++;
		if (sscanf(l, "M204 S%d", &v) == 1) {
			last = v;
			n++;
		}
		if (!strncmp(l, ";TYPE:", 6) && layer == (first ? 1 : 2) && k < NROLES)
			out[k++] = last;
	}
	ck_assert_uint_eq(k, NROLES);
	return n;
}

START_TEST(test_accel_per_role)
{
	struct gcodew_settings s;
	struct layer_stack *st = stack(&s);
	struct gcodew_summary plain_sum, sum;
	int got[NROLES];
	/* skirt, wall, infill, bridge, gap fill (not infill in PrusaSlicer) */
	static const int want[NROLES] = {1000, 800, 2000, 1500, 1000};
	char *g;

	s.perimeter_acceleration = 800;
	s.infill_acceleration = 2000;
	s.bridge_acceleration = 1500;
	s.first_layer_acceleration = 600;
	g = tu_gcode_mem(st, &s, &plain_sum);
	ck_assert_ptr_null(strstr(g, "M204")); /* no default: nothing written */
	free(g);
	s.default_acceleration = 1000;
	g = tu_gcode_mem(st, &s, &sum);
	accels(g, false, got);
	for (size_t r = 0; r < NROLES; r++)
		ck_assert_msg(got[r] == want[r], "%s: M204 S%d, %d expected",
			      path_role_name(roles[r]), got[r], want[r]);
	accels(g, true, got);
	for (size_t r = 0; r < NROLES; r++)
		ck_assert_int_eq(got[r], 600);
	/* After each path the default again, before the travel. */
	ck_assert_ptr_nonnull(strstr(g, "M204 S1000\nG1 "));
	free(g);
	/* Low accelerations take longer; above the machine's extruding limit
	 * (1500 by default) they are capped where the limits are written. */
	s.default_acceleration = s.perimeter_acceleration = s.infill_acceleration = 100;
	s.bridge_acceleration = s.first_layer_acceleration = 100;
	g = tu_gcode_mem(st, &s, &sum);
	ck_assert_msg(sum.time_s > plain_sum.time_s + 1, "%g s, %g s without", sum.time_s,
		      plain_sum.time_s);
	free(g);
	s.default_acceleration = 5000;
	s.limits_form = GCODEW_LIMITS_MARLIN2;
	g = tu_gcode_mem(st, &s, NULL);
	ck_assert_ptr_nonnull(strstr(g, "\nM204 S1500\n"));
	ck_assert_ptr_null(strstr(g, "\nM204 S5000\n"));
	free(g);
	layer_stack_free(st);
}
END_TEST

void gcodewriter_accel_tcases(Suite *s)
{
	TCase *tc = tcase_create("accel");

	tcase_add_test(tc, test_accel_per_role);
	suite_add_tcase(s, tc);
}
