/*
 * check_progress.c - remaining_times (slicer/gcode_writer_progress.c): the
 * M73 lines against the estimate of a print of equal layers, and the
 * output without the key byte for byte the output with it less its lines.
 * Part of the gcodewriter suite.
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gcode_writer.h"
#include "suites.h"
#include "testutil.h"

#define NM 1000000.0 /* nm per mm */
#define LAYERS 20

/* LAYERS layers of one 100 mm square wall printed at 5 mm/s: about 80 s
 * each, so the minutes left fall across the print. */
static struct layer_stack *slow_tower(struct gcodew_settings *s)
{
	struct layer_stack *st = layer_stack_new(LAYERS, NULL);

	ck_assert_ptr_nonnull(st);
	for (size_t i = 0; i < LAYERS; i++) {
		struct path_point p[4] = {{10 * NM, 10 * NM, 0.45 * NM}, {110 * NM, 10 * NM, 0.45 * NM},
					  {110 * NM, 110 * NM, 0.45 * NM}, {10 * NM, 110 * NM, 0.45 * NM}};
		st->layers[i].z = 0.2 * (double)(i + 1);
		st->layers[i].height = 0.2;
		ck_assert_int_eq(layer_add_path(&st->layers[i], PATH_OUTER_PERIMETER, true, p, 4, NULL),
				 0);
	}
	gcodew_settings_init(s);
	s->external_perimeter_speed = 5;
	s->first_layer_speed = 0;
	return st;
}

/* The text without its M73 lines and the header's remaining_times line. */
static char *without_m73(const char *g)
{
	char *out = malloc(strlen(g) + 1), *o = out;

	ck_assert_ptr_nonnull(out);
	while (*g) {
		const char *nl = strchr(g, '\n');
		size_t n = nl ? (size_t)(nl - g + 1) : strlen(g);
		if (strncmp(g, "M73 ", 4) && strncmp(g, "; remaining_times = ", 20)) {
			memcpy(o, g, n);
			o += n;
		}
		g += n;
	}
	*o = '\0';
	return out;
}

START_TEST(test_m73_follows_the_estimate)
{
	struct gcodew_settings s;
	struct layer_stack *st = slow_tower(&s);
	struct gcodew_summary sum;
	char *plain, *g, *stripped;
	int np = 0, last_p = -1, last_r = 1 << 30, layer = 0;
	bool first_seen = false;

	plain = tu_gcode_mem(st, &s, NULL);
	ck_assert_ptr_null(strstr(plain, "M73"));
	s.remaining_times = true;
	g = tu_gcode_mem(st, &s, &sum);
	ck_assert_msg(sum.time_s > 1200, "%g s", sum.time_s);
	for (const char *l = g; *l; l = strchr(l, '\n') ? strchr(l, '\n') + 1 : l + strlen(l)) {
		int p, r;

		if (!strncmp(l, ";LAYER_CHANGE", 13)) {
			layer++;
			continue;
		}
		if (sscanf(l, "M73 P%d R%d", &p, &r) != 2)
			continue;
		np++;
		if (!first_seen) { /* the whole print left, before anything moves */
			ck_assert_int_eq(p, 0);
			ck_assert_int_eq(r, (int)((sum.time_s + 0.5) / 60));
			ck_assert_ptr_eq(strstr(g, "G1") > l ? l : NULL, l);
			first_seen = true;
		} else if (p != 100) { /* before layer `layer`, of equal layers */
			double left = sum.time_s * (LAYERS - layer) / LAYERS;
			ck_assert_msg(abs(p - 100 * layer / LAYERS) <= 1, "layer %d: P%d", layer, p);
			ck_assert_msg(abs(r - (int)(left / 60)) <= 1, "layer %d: R%d", layer, r);
			ck_assert_msg(p != last_p || r != last_r, "layer %d: repeated", layer);
		}
		ck_assert_int_ge(p, last_p);
		ck_assert_int_le(r, last_r);
		last_p = p;
		last_r = r;
	}
	ck_assert_int_eq(last_p, 100);
	ck_assert_int_eq(last_r, 0);
	ck_assert_int_ge(np, LAYERS / 2);
	ck_assert_ptr_null(strstr(g, "M73 Q"));
	ck_assert_ptr_nonnull(strstr(g, "; remaining_times = 1\n"));
	/* Nothing else changes. */
	stripped = without_m73(g);
	ck_assert_str_eq(stripped, plain);
	free(stripped);
	free(g);
	free(plain);
	layer_stack_free(st);
}
END_TEST

/* remaining_times_silent: every M73 P R is followed by Q S, same figures. */
START_TEST(test_m73_silent_mode)
{
	struct gcodew_settings s;
	struct layer_stack *st = slow_tower(&s);
	char *g;
	int pairs = 0;

	s.remaining_times = true;
	s.remaining_times_silent = true;
	g = tu_gcode_mem(st, &s, NULL);
	for (const char *l = strstr(g, "M73 P"); l; l = strstr(l + 1, "M73 P")) {
		int p, r, q, t;
		const char *next = strchr(l, '\n') + 1;
		ck_assert_int_eq(sscanf(l, "M73 P%d R%d", &p, &r), 2);
		ck_assert_msg(sscanf(next, "M73 Q%d S%d", &q, &t) == 2, "%.30s", next);
		ck_assert_int_eq(q, p);
		ck_assert_int_eq(t, r);
		pairs++;
	}
	ck_assert_int_ge(pairs, 3);
	free(g);
	layer_stack_free(st);
}
END_TEST

void gcodewriter_progress_tcases(Suite *s)
{
	TCase *tc = tcase_create("progress");

	tcase_set_timeout(tc, 30);
	tcase_add_test(tc, test_m73_follows_the_estimate);
	tcase_add_test(tc, test_m73_silent_mode);
	suite_add_tcase(s, tc);
}
