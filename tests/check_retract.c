/*
 * check_retract.c - retract_layer_change, the retract_lift_above /
 * retract_lift_below range and retract_before_wipe (slicer/gcode_writer_plan.c), read back from
 * the written G-code in relative E.  Part of the gcodewriter suite.
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
#define LAYERS 5

/* A 20 mm square wall at (x0, y0), seam at its corner. */
static void square(struct layer_paths *l, double x0, double y0)
{
	struct path_point p[4] = {{x0 * NM, y0 * NM, 0.45 * NM}, {(x0 + 20) * NM, y0 * NM, 0.45 * NM},
				  {(x0 + 20) * NM, (y0 + 20) * NM, 0.45 * NM},
				  {x0 * NM, (y0 + 20) * NM, 0.45 * NM}};

	ck_assert_int_eq(layer_add_path(l, PATH_OUTER_PERIMETER, true, p, 4, NULL), 0);
}

/* LAYERS layers 0.2 mm apart of one square (two, 60 mm apart, with two). */
static struct layer_stack *tower(bool two, struct gcodew_settings *s)
{
	struct layer_stack *st = layer_stack_new(LAYERS, NULL);

	ck_assert_ptr_nonnull(st);
	for (size_t i = 0; i < LAYERS; i++) {
		st->layers[i].z = 0.2 * (double)(i + 1);
		st->layers[i].height = 0.2;
		square(&st->layers[i], 10, 10);
		if (two)
			square(&st->layers[i], 70, 10);
	}
	gcodew_settings_init(s);
	s->use_relative_e_distances = true;
	s->retract_length = 0.8;
	s->retract_before_travel = 2;
	s->only_retract_when_crossing_perimeters = false;
	return st;
}

/* What a replay of the moves from the first layer on saw. */
struct seen {
	int retracts;		       /* moves with E < 0 */
	int layer_retracts;	       /* ... of a layer before its first extrusion */
	double pre_zmax[LAYERS];       /* highest Z of layer k's moves before its first extrusion */
	double in_zmax[LAYERS];	       /* ... of its other moves that do not extrude */
	double e_before_first[LAYERS]; /* E pushed back on layer k before its first extrusion */
};

/* The number after " <c>" on line l (up to end), or 0 with *has false. */
static double field(const char *l, const char *end, const char *c, bool *has)
{
	const char *f = strstr(l, c);

	*has = f && (!end || f < end);
	return *has ? atof(f + 2) : 0;
}

static void replay(const char *g, struct seen *v)
{
	double z = 0;
	int layer = -1;
	bool extruded = false;

	memset(v, 0, sizeof(*v));
	for (const char *l = strstr(g, ";LAYER_CHANGE"); l && *l;
	     l = strchr(l, '\n') ? strchr(l, '\n') + 1 : l + strlen(l)) {
		const char *end = strchr(l, '\n');
		bool hz, he, hx, hy;
		double nz, e;

		if (!strncmp(l, ";LAYER_CHANGE", 13)) {
			layer++;
			extruded = false;
			continue;
		}
		if (strncmp(l, "G1 ", 3) || layer >= LAYERS)
			continue;
		nz = field(l, end, " Z", &hz);
		e = field(l, end, " E", &he);
		field(l, end, " X", &hx);
		field(l, end, " Y", &hy);
		if (hz)
			z = nz;
		if (e < 0)
			v->retracts++;
		if (e > 0 && (hx || hy)) {
			extruded = true;
		} else if (!extruded) {
			v->layer_retracts += e < 0;
			v->e_before_first[layer] += fmax(e, 0);
			v->pre_zmax[layer] = fmax(v->pre_zmax[layer], z);
		} else {
			v->in_zmax[layer] = fmax(v->in_zmax[layer], z);
		}
	}
}

START_TEST(test_retract_layer_change)
{
	struct gcodew_settings s;
	struct layer_stack *st = tower(false, &s);
	struct seen off, on;
	char *g;

	g = tu_gcode_mem(st, &s, NULL);
	replay(g, &off);
	free(g);
	s.retract_layer_change = true;
	g = tu_gcode_mem(st, &s, NULL);
	replay(g, &on);
	free(g);
	/* Each layer starts where the last ended: no travel retracts. */
	ck_assert_int_eq(off.layer_retracts, 0);
	ck_assert_int_eq(on.layer_retracts, LAYERS - 1);
	for (int k = 1; k < LAYERS; k++) /* ... and the first travel puts it back */
		ck_assert_double_eq_tol(on.e_before_first[k], 0.8, 1e-9);
	ck_assert_double_eq_tol(off.e_before_first[1], 0, 1e-9);
	layer_stack_free(st);
}
END_TEST

/* Lifts with retract_lift_below = 0.5: from layers at Z 0.2 and 0.4 only,
 * at the layer change (one square per layer) and on the travels (two);
 * retract_lift_above = 0.5 the other way round. */
START_TEST(test_lift_range)
{
	for (int two = 0; two < 2; two++) {
		for (int above = 0; above < 2; above++) {
			struct gcodew_settings s;
			struct layer_stack *st = tower(two, &s);
			struct seen v;
			char *g;

			s.retract_layer_change = !two;
			s.retract_lift = 0.5;
			if (above)
				s.retract_lift_above = 0.5;
			else
				s.retract_lift_below = 0.5;
			g = tu_gcode_mem(st, &s, NULL);
			replay(g, &v);
			free(g);
			for (int k = 1; k < LAYERS; k++) {
				double zk = 0.2 * (k + 1), zfrom = two ? zk : zk - 0.2;
				bool lifts = above ? zfrom >= 0.5 - 1e-9 : zfrom <= 0.5 + 1e-9;
				double want = lifts ? zfrom + 0.5 : zk;

				ck_assert_msg(fabs(v.pre_zmax[k] - want) < 1e-6,
					      "two %d above %d, layer %d: Z %g before its first "
					      "extrusion, %g expected", two, above, k + 1,
					      v.pre_zmax[k], want);
				if (two) /* the travel between the squares */
					ck_assert_msg(fabs(v.in_zmax[k] - want) < 1e-6,
						      "above %d, layer %d: travel at Z %g, %g expected",
						      above, k + 1, v.in_zmax[k], want);
			}
			layer_stack_free(st);
		}
	}
}
END_TEST

/* Each retraction of g (a run of moves with E < 0): how many there are,
 * how many start standing with first_e, and whether each takes 0.8 mm. */
static void retractions(const char *g, double first_e, int *runs, int *standing)
{
	double sum = 0;
	bool in_run = false;

	*runs = *standing = 0;
	for (const char *l = strstr(g, ";LAYER_CHANGE"); l && *l;
	     l = strchr(l, '\n') ? strchr(l, '\n') + 1 : l + strlen(l)) {
		const char *end = strchr(l, '\n');
		bool he, hx, hy;
		double e = strncmp(l, "G1 ", 3) ? 0 : field(l, end, " E", &he);

		field(l, end, " X", &hx);
		field(l, end, " Y", &hy);
		if (e < 0 && !in_run) {
			(*runs)++;
			if (!hx && !hy && fabs(e - first_e) < 1e-9)
				(*standing)++;
			sum = 0;
		}
		if (e < 0)
			sum += e;
		else if (in_run)
			ck_assert_msg(fabs(sum + 0.8) < 2e-5, "a retraction of %g mm", -sum);
		in_run = e < 0;
	}
}

/* retract_before_wipe = 50%: every wiping retraction starts with 0.4 mm
 * standing, and still takes 0.8 mm in all. */
START_TEST(test_retract_before_wipe)
{
	struct gcodew_settings s;
	struct layer_stack *st = tower(true, &s);
	int runs, standing;
	char *g;

	s.wipe = true;
	g = tu_gcode_mem(st, &s, NULL);
	retractions(g, -0.4, &runs, &standing);
	free(g);
	ck_assert_int_ge(runs, LAYERS);
	ck_assert_int_eq(standing, 0);
	s.retract_before_wipe = 50;
	g = tu_gcode_mem(st, &s, NULL);
	retractions(g, -0.4, &runs, &standing);
	free(g);
	ck_assert_int_ge(runs, LAYERS);
	ck_assert_int_eq(standing, runs);
	layer_stack_free(st);
}
END_TEST

void gcodewriter_retract_tcases(Suite *s)
{
	TCase *tc = tcase_create("retract_keys");

	tcase_add_test(tc, test_retract_layer_change);
	tcase_add_test(tc, test_lift_range);
	tcase_add_test(tc, test_retract_before_wipe);
	suite_add_tcase(s, tc);
}
