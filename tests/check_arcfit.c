/*
 * check_arcfit.c - arc_fitting (part of the gcodewriter suite):
 * slicer/arcfit.h's bound both ways, checked apart from arcfit.c's own
 * arithmetic on circles, non-arcs and random paths; and the writer's use
 * of it: G2/G3 lines within the tolerance of the paths, each arc's
 * filament its length times the flow, the estimate as with lines, off =
 * the output byte for byte as before the key (tests/data/
 * gcodew-dense-default.gcode), and arcs only for a flavour that takes them.
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "arcfit.h"
#include "gcode_writer.h"
#include "suites.h"
#include "testutil.h"

#define NM 1000000.0 /* nm per mm */
#define RES 0.0125   /* mm, the default gcode_resolution */
#define TOL (RES * NM)
#define GOLDEN "tests/data/gcodew-dense-default.gcode"
#define SAMPLES 24 /* per segment, on the segments and on the arc */

/* ---------------------------------------------------------------------------
 * The bound, checked by dense sampling in long double
 */

/* Distance from (px, py) to the segment a-b. */
static long double seg_dist(long double px, long double py, long double ax, long double ay,
			    long double bx, long double by)
{
	long double dx = bx - ax, dy = by - ay, l2 = dx * dx + dy * dy;
	long double t = l2 > 0 ? ((px - ax) * dx + (py - ay) * dy) / l2 : 0;

	t = t < 0 ? 0 : t > 1 ? 1 : t;
	return hypotl(px - ax - t * dx, py - ay - t * dy);
}

/* Distance from (px, py) to the arc a of the polyline xy. */
static long double arc_dist(const int64_t *xy, const struct arcfit_arc *a, long double px,
			    long double py)
{
	long double sx = xy[2 * a->first] - a->cx, sy = xy[2 * a->first + 1] - a->cy;
	long double a0 = atan2l(sy, sx), ang = atan2l(py - a->cy, px - a->cx) - a0;
	long double r = hypotl(sx, sy), sweep = fabsl((long double)a->sweep);
	long double ex = a->cx + r * cosl(a0 + a->sweep), ey = a->cy + r * sinl(a0 + a->sweep);

	if (a->sweep < 0)
		ang = -ang;
	while (ang < 0)
		ang += 2 * M_PI;
	while (ang >= 2 * M_PI)
		ang -= 2 * M_PI;
	if (ang <= sweep)
		return fabsl(hypotl(px - a->cx, py - a->cy) - r);
	return fminl(hypotl(px - a->cx - sx, py - a->cy - sy), hypotl(px - ex, py - ey));
}

/* The largest distance either way between arc a and its stretch of xy. */
static long double arc_gap(const int64_t *xy, const struct arcfit_arc *a)
{
	long double worst = 0, r = a->radius, a0;

	size_t arc_samples = SAMPLES * (a->last - a->first);

	for (size_t k = a->first; k < a->last; k++)
		for (int i = 0; i <= SAMPLES; i++) {
			long double t = (long double)i / SAMPLES;
			long double px = xy[2 * k] + t * (xy[2 * k + 2] - xy[2 * k]);
			long double py = xy[2 * k + 1] + t * (xy[2 * k + 3] - xy[2 * k + 1]);
			worst = fmaxl(worst, arc_dist(xy, a, px, py));
		}
	a0 = atan2l((long double)xy[2 * a->first + 1] - a->cy,
		    (long double)xy[2 * a->first] - a->cx);
	for (size_t i = 0; i <= arc_samples; i++) {
		long double t = a0 + a->sweep * (long double)i / arc_samples, best = INFINITY;
		long double px = a->cx + r * cosl(t), py = a->cy + r * sinl(t);
		for (size_t k = a->first; k < a->last; k++)
			best = fminl(best, seg_dist(px, py, xy[2 * k], xy[2 * k + 1], xy[2 * k + 2],
						    xy[2 * k + 3]));
		worst = fmaxl(worst, best);
	}
	return worst;
}

/* Fit xy[0 .. 2n) at tol; every arc in order, over 3 points or more,
 * within tol both ways (tol less the slack: arcfit.h).  The count. */
static size_t fit_and_check(struct arcfit_work *wk, const int64_t *xy, size_t n, double tol)
{
	size_t count, prev = 0;

	ck_assert_int_eq(arcfit_find(wk, xy, n, tol, &count, NULL), 0);
	for (size_t i = 0; i < count; i++) {
		const struct arcfit_arc *a = &wk->arcs[i];
		long double gap = arc_gap(xy, a);

		ck_assert_msg(a->first >= prev && a->last >= a->first + 2 && a->last < n,
			      "arc %zu spans points %zu to %zu after %zu", i, a->first, a->last,
			      prev);
		ck_assert_msg(gap <= tol - ARCFIT_SLACK_NM,
			      "arc %zu (points %zu to %zu, radius %.0f nm) is %.1Lf nm from its "
			      "polyline (tolerance %.0f nm)",
			      i, a->first, a->last, a->radius, gap, tol);
		prev = a->last;
	}
	return count;
}

/* A fixed generator, the same sequence everywhere. */
static uint64_t rnd_next(uint64_t *st)
{
	*st = *st * 6364136223846793005ull + 1442695040888963407ull;
	return *st >> 33;
}

/* A uniform double in [lo, hi). */
static double rnd_in(uint64_t *st, double lo, double hi)
{
	return lo + (hi - lo) * (double)rnd_next(st) / 2147483648.0;
}

/* n points of the circle of radius r nm around (cx, cy), from angle a0
 * turning sweep in all (the last point at a0 + sweep). */
static void circle_points(int64_t *xy, size_t n, double cx, double cy, double r, double a0,
			  double sweep)
{
	for (size_t k = 0; k < n; k++) {
		double a = a0 + sweep * (double)k / (double)(n - 1);
		xy[2 * k] = llround(cx + r * cos(a));
		xy[2 * k + 1] = llround(cy + r * sin(a));
	}
}

/* A 256-gon of 10 mm radius, closed (the seam repeated), becomes at most
 * three arcs covering it all but perhaps its last segment; and a quarter of it one arc, turning the
 * way it goes, either way. */
START_TEST(circle_becomes_few_arcs)
{
	struct arcfit_work wk = {0};
	int64_t xy[2 * 257];
	size_t count;

	circle_points(xy, 257, 100 * NM, 100 * NM, 10 * NM, 0.3, 2 * M_PI);
	count = fit_and_check(&wk, xy, 257, TOL);
	ck_assert_msg(count >= 1 && count <= 3, "%zu arcs", count);
	ck_assert_uint_eq(wk.arcs[0].first, 0);
	/* the seam's chord is too short for a whole circle: a line may end it */
	ck_assert_uint_ge(wk.arcs[count - 1].last, 255);
	for (size_t i = 0; i + 1 < count; i++)
		ck_assert_uint_eq(wk.arcs[i].last, wk.arcs[i + 1].first);
	for (int dir = -1; dir <= 1; dir += 2) {
		circle_points(xy, 65, 50 * NM, 70 * NM, 10 * NM, 1, dir * M_PI / 2);
		ck_assert_uint_eq(fit_and_check(&wk, xy, 65, TOL), 1);
		ck_assert_uint_eq(wk.arcs[0].first, 0);
		ck_assert_uint_eq(wk.arcs[0].last, 64);
		ck_assert_msg(fabs(wk.arcs[0].sweep - dir * M_PI / 2) < 1e-3, "sweep %g",
			      wk.arcs[0].sweep);
		ck_assert_msg(fabs(wk.arcs[0].radius - 10 * NM) < 2000, "radius %.0f nm",
			      wk.arcs[0].radius);
	}
	arcfit_work_free(&wk);
}
END_TEST

/* What is not an arc stays lines: a zigzag, a square's corners, points on
 * one straight line, a polygon too coarse for the tolerance; and an S
 * bend is two arcs, never one across the turn. */
START_TEST(non_arcs_stay_lines)
{
	struct arcfit_work wk = {0};
	int64_t xy[2 * 81];
	size_t count;

	for (size_t k = 0; k < 40; k++) { /* zigzag, 1 mm teeth */
		xy[2 * k] = (int64_t)k * 1000000;
		xy[2 * k + 1] = k % 2 ? 1000000 : 0;
	}
	ck_assert_uint_eq(fit_and_check(&wk, xy, 40, TOL), 0);
	for (size_t k = 0; k < 41; k++) { /* a 10 mm square, 10 points a side */
		size_t side = k / 10 % 4, t = k % 10;
		int64_t u = (int64_t)t * 1000000;
		xy[2 * k] = side == 0 ? u : side == 1 ? 10000000 : side == 2 ? 10000000 - u : 0;
		xy[2 * k + 1] = side == 0 ? 0 : side == 1 ? u : side == 2 ? 10000000 : 10000000 - u;
	}
	ck_assert_uint_eq(fit_and_check(&wk, xy, 41, TOL), 0);
	for (size_t k = 0; k < 30; k++) { /* collinear */
		xy[2 * k] = (int64_t)k * 300000;
		xy[2 * k + 1] = (int64_t)k * 170000;
	}
	ck_assert_uint_eq(fit_and_check(&wk, xy, 30, TOL), 0);
	/* a 12-gon of 10 mm: its chords are 340 um from the circle */
	circle_points(xy, 13, 0, 0, 10 * NM, 0, 2 * M_PI);
	ck_assert_uint_eq(fit_and_check(&wk, xy, 13, TOL), 0);
	/* S bend: a half circle one way, then one the other way */
	circle_points(xy, 41, 0, 0, 5 * NM, M_PI, -M_PI);
	circle_points(xy + 80, 41, 10 * NM, 0, 5 * NM, M_PI, M_PI);
	count = fit_and_check(&wk, xy, 81, TOL);
	ck_assert_uint_eq(count, 2);
	ck_assert_uint_eq(wk.arcs[0].last, 40);
	ck_assert(wk.arcs[0].sweep < 0 && wk.arcs[1].sweep > 0);
	arcfit_work_free(&wk);
}
END_TEST

/* Random paths: arcs of 0.3 to 60 mm radius with noise up to twice the
 * tolerance, joined by kinks and straight stretches, steps of 20 um to
 * 2 mm, some points repeated; tolerances from the slack to 0.1 mm.  Every
 * arc found holds the bound, and the noiseless arcs are found. */
START_TEST(bound_on_random_paths)
{
	static const double tols[] = {ARCFIT_SLACK_NM + 500, TOL / 2, TOL, 0.1 * NM};
	struct arcfit_work wk = {0};
	uint64_t st = 4242;
	size_t n = 600, found = 0;
	int64_t *xy = malloc(2 * n * sizeof(*xy));

	ck_assert_ptr_nonnull(xy);
	for (int round = 0; round < 12; round++) {
		double x = 100 * NM, y = 100 * NM, heading = rnd_in(&st, 0, 2 * M_PI);
		size_t k = 0;
		while (k < n) {
			size_t len = 3 + rnd_next(&st) % 60;
			double r = rnd_in(&st, 0.3, 60) * NM, step = rnd_in(&st, 0.02, 2) * NM;
			double turn = (rnd_next(&st) % 2 ? 1 : -1) * step / r;
			double noise = round % 3 == 0 ? 0 : rnd_in(&st, 0, 2 * TOL);
			bool straight = rnd_next(&st) % 5 == 0;
			heading += rnd_in(&st, -1.5, 1.5); /* a kink */
			for (size_t i = 0; i < len && k < n; i++, k++) {
				xy[2 * k] = llround(x + rnd_in(&st, -noise, noise));
				xy[2 * k + 1] = llround(y + rnd_in(&st, -noise, noise));
				if (rnd_next(&st) % 17 == 0)
					continue; /* the point again */
				if (!straight)
					heading += turn;
				x += step * cos(heading);
				y += step * sin(heading);
			}
		}
		for (size_t t = 0; t < sizeof(tols) / sizeof(tols[0]); t++)
			found += fit_and_check(&wk, xy, n, tols[t]);
	}
	ck_assert_uint_gt(found, 50);
	free(xy);
	arcfit_work_free(&wk);
}
END_TEST

/* A tolerance at most the slack finds nothing; a stretch shorter than
 * the shortest chord is left alone. */
START_TEST(tiny_tolerance_or_chord_finds_none)
{
	struct arcfit_work wk = {0};
	int64_t xy[2 * 33];

	circle_points(xy, 33, 0, 0, 10 * NM, 0, M_PI);
	ck_assert_uint_eq(fit_and_check(&wk, xy, 33, ARCFIT_SLACK_NM), 0);
	ck_assert_uint_eq(fit_and_check(&wk, xy, 33, 0), 0);
	circle_points(xy, 33, 0, 0, 4000, 0, M_PI); /* a chord of 8 um */
	ck_assert_uint_eq(fit_and_check(&wk, xy, 33, TOL), 0);
	arcfit_work_free(&wk);
}
END_TEST

/* ---------------------------------------------------------------------------
 * The writer
 */

/* The length (mm) of move g: its arc's, or its chord's. */
static double mv_length(const struct tu_move *g)
{
	double a;

	if (!g->arc)
		return hypot(g->x1 - g->x0, g->y1 - g->y0);
	a = atan2(g->y1 - g->cy, g->x1 - g->cx) - atan2(g->y0 - g->cy, g->x0 - g->cx);
	if (g->ccw && a <= 0)
		a += 2 * M_PI;
	if (!g->ccw && a >= 0)
		a -= 2 * M_PI;
	return fabs(a) * hypot(g->x0 - g->cx, g->y0 - g->cy);
}

/* The distance (mm) from (px, py) to move g, as the firmware reads it:
 * the circle around the centre with the radius from the start. */
static double mv_dist(const struct tu_move *g, double px, double py)
{
	struct arcfit_arc a;
	int64_t xy[2];

	if (!g->arc)
		return (double)seg_dist(px, py, g->x0, g->y0, g->x1, g->y1);
	xy[0] = llround(g->x0 * NM);
	xy[1] = llround(g->y0 * NM);
	a = (struct arcfit_arc){.first = 0,
				.cx = g->cx * NM,
				.cy = g->cy * NM,
				.sweep = (g->ccw ? 1 : -1) * mv_length(g) /
					 hypot(g->x0 - g->cx, g->y0 - g->cy)};
	return (double)arc_dist(xy, &a, px * NM, py * NM) / NM;
}

/* With arc_fitting the dense stack's round walls become arcs: far fewer
 * lines; every point of every path within the tolerance (half on the
 * outer wall) of the arcs and lines printed for it; each role's filament
 * as without arcs; each arc's filament its length times the flow of the
 * lines of its role; the estimate within 3 % of the lines' (the arcs are
 * timed in Marlin's 1 mm chords, whose corners are sharper than the
 * sliced points'). */
START_TEST(writer_arcs_bound_filament_time)
{
	static const char *const roles[] = {"Perimeter", "External perimeter", "Internal infill",
					    "Solid infill", "Thin wall"};
	struct layer_stack *st = dense_stack();
	struct gcodew_settings s;
	struct gcodew_summary s0, s1;
	char *off, *on;
	struct tu_moves r0, r1;

	gcodew_settings_init(&s);
	ck_assert(!s.arc_fitting);
	off = tu_gcode_mem(st, &s, &s0);
	s.arc_fitting = true;
	on = tu_gcode_mem(st, &s, &s1);
	r0 = tu_read_moves(off);
	r1 = tu_read_moves(on);
	ck_assert(strstr(on, "\n; arc_fitting = emit_center\n") && !strstr(off, "arc_fitting"));
	ck_assert_msg(r1.arcs >= 4 && 2 * (r1.g1 + r1.arcs) < r0.g1,
		      "%zu G1 and %zu G2/G3 lines, %zu G1 without", r1.g1, r1.arcs, r0.g1);
	for (size_t i = 0; i < sizeof(roles) / sizeof(roles[0]); i++) {
		double e0 = tu_moves_e(&r0, roles[i]), e1 = tu_moves_e(&r1, roles[i]);
		ck_assert_msg(e0 > 0 && fabs(e1 - e0) < 1e-4,
			      "%s: %.6f mm of filament, %.6f "
			      "without arcs",
			      roles[i], e1, e0);
	}
	for (size_t k = 0; k < r1.n; k++) { /* 0.45 mm beads 0.2 mm high: flow per mm */
		const struct tu_move *g = &r1.m[k];
		double flow = ((0.45 - 0.2) * 0.2 + M_PI * 0.01) / (M_PI * 1.75 * 1.75 / 4);
		if (g->arc)
			ck_assert_msg(fabs(g->e - mv_length(g) * flow) <= 0.002 * g->e + 2e-5,
				      "arc %zu: %.5f mm of filament for %.4f mm", k, g->e,
				      mv_length(g));
	}
	for (size_t li = 0; li < st->nlayers; li++)
		for (size_t pi = 0; pi < st->layers[li].n; pi++) {
			const struct toolpath *p = &st->layers[li].paths[pi];
			const char *role = path_role_name(p->role);
			double tol = p->role == PATH_OUTER_PERIMETER ? RES / 2 : RES;
			for (size_t k = 0; k < p->n; k++) {
				double best = INFINITY, px = p->pts[k].x / NM,
				       py = p->pts[k].y / NM;
				for (size_t m = 0; m < r1.n; m++)
					if (r1.m[m].layer == (int)li + 1 &&
					    !strcmp(r1.m[m].role, role))
						best = fmin(best, mv_dist(&r1.m[m], px, py));
				ck_assert_msg(best <= tol + 0.0007,
					      "layer %zu %s point %zu: %.5f mm off", li + 1, role,
					      k, best);
			}
		}
	ck_assert_msg(fabs(s1.time_s - s0.time_s) < 0.03 * s0.time_s,
		      "%.1f s with arcs, %.1f s "
		      "without",
		      s1.time_s, s0.time_s);
	free(r0.m);
	free(r1.m);
	free(on);
	free(off);
	layer_stack_free(st);
}
END_TEST

/* The golden file is the writer's output for dense_stack() at the
 * default settings from the commit before arc_fitting existed; with the
 * key off (its default) not a byte differs.  A change meant to alter the
 * writer's output replaces it with this test's output, in the same
 * commit. */
START_TEST(off_is_output_before)
{
	struct gcodew_settings s;

	gcodew_settings_init(&s);
	dense_stack_matches(&s, GOLDEN);
}
END_TEST

/* The last "arc_fitting" in text. */
static const char *strrstr_arc(const char *text)
{
	const char *last = NULL;

	for (const char *at = strstr(text, "arc_fitting"); at; at = strstr(at + 1, "arc_fitting"))
		last = at;
	return last;
}

/* A Marlin printer gets G2/G3 with the key set; a Sailfish one (X3G has
 * no arcs) gets lines and one warning naming the key and the flavour. */
START_TEST(arcs_only_where_the_firmware_takes_them)
{
	static char out[1 << 14];
	char *marlin = slice_cylinder_for(3, "generic-marlin", "--set arc_fitting=emit_center", out,
					  sizeof(out));
	char *sailfish;

	ck_assert(strstr(marlin, "\nG3 ") || strstr(marlin, "\nG2 "));
	ck_assert(!strstr(out, "arc_fitting"));
	free(marlin);
	sailfish = slice_cylinder_for(3, "flashforge-creator-pro", "--set arc_fitting=emit_center",
				      out, sizeof(out));
	ck_assert(!strstr(sailfish, "\nG3 ") && !strstr(sailfish, "\nG2 "));
	ck_assert(!strstr(sailfish, "arc_fitting"));
	ck_assert_msg(strstr(out, "warning: not supported, ignored: arc_fitting=emit_center "
				  "(gcode_flavor = sailfish has no G2/G3: lines written)"),
		      "%s", out);
	ck_assert_msg(strstr(out, "arc_fitting") == strrstr_arc(out), "more than one warning: %s",
		      out);
	free(sailfish);
}
END_TEST

/* A spiral vase gets one helical arc a layer, but its transition layer,
 * whose flow rises from nothing along the loop, stays lines: the filament
 * is the same as without arcs (an arc there would carry full flow). */
START_TEST(spiral_vase_arcs_keep_the_ramp)
{
	static char out[1 << 14];
	char *on = slice_cylinder_for(6, "generic-marlin",
				      "--set spiral_vase=1 --set arc_fitting=emit_center "
				      "--set use_relative_e_distances=0",
				      out, sizeof(out));
	char *off = slice_cylinder_for(6, "generic-marlin",
				       "--set spiral_vase=1 --set use_relative_e_distances=0", out,
				       sizeof(out));
	struct tu_moves r1 = tu_read_moves(on), r0 = tu_read_moves(off);
	double e1 = tu_moves_e(&r1, NULL), e0 = tu_moves_e(&r0, NULL);

	ck_assert_msg(r1.arcs >= 10 && r1.g1 + r1.arcs < r0.g1 / 2, "%zu arcs, %zu G1, %zu without",
		      r1.arcs, r1.g1, r0.g1);
	ck_assert_msg(fabs(e1 - e0) < 1e-4 * e0, "%.4f mm of filament, %.4f without arcs", e1, e0);
	free(r0.m);
	free(r1.m);
	free(on);
	free(off);
}
END_TEST

void gcodewriter_arcfit_tcases(Suite *s)
{
	TCase *tc = tcase_create("arcfit");

	tcase_add_test(tc, circle_becomes_few_arcs);
	tcase_add_test(tc, non_arcs_stay_lines);
	tcase_add_test(tc, bound_on_random_paths);
	tcase_add_test(tc, tiny_tolerance_or_chord_finds_none);
	tcase_add_test(tc, writer_arcs_bound_filament_time);
	tcase_add_test(tc, off_is_output_before);
	tcase_add_test(tc, arcs_only_where_the_firmware_takes_them);
	tcase_add_test(tc, spiral_vase_arcs_keep_the_ramp);
	tcase_set_timeout(tc, 60);
	suite_add_tcase(s, tc);
}
