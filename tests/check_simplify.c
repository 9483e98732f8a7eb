/*
 * check_simplify.c - gcode_resolution (part of the gcodewriter suite):
 * slicer/simplify.h's deviation bound on random and circle-like
 * polylines, and the writer's output for a dense stack of paths, byte for
 * byte tests/data/gcodew-dense-r0.gcode (written before gcode_resolution
 * existed).
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gcode_writer.h"
#include "simplify.h"
#include "suites.h"
#include "testutil.h"

#define NM 1000000.0 /* nm per mm */
#define GOLDEN "tests/data/gcodew-dense-r0.gcode"
#define RES 0.0125 /* mm, the default gcode_resolution */

/* ---------------------------------------------------------------------------
 * The bound, checked apart from simplify.c's own arithmetic
 */

/* Distance (nm) from p to the segment a-b, in long double. */
static long double seg_dist(const int64_t *p, const int64_t *a, const int64_t *b)
{
	long double dx = (long double)(b[0] - a[0]), dy = (long double)(b[1] - a[1]);
	long double qx = (long double)(p[0] - a[0]), qy = (long double)(p[1] - a[1]);
	long double l2 = dx * dx + dy * dy, t = l2 > 0 ? (qx * dx + qy * dy) / l2 : 0;

	t = t < 0 ? 0 : t > 1 ? 1 : t;
	return hypotl(qx - t * dx, qy - t * dy);
}

/* Mark xy[0 .. 2n) within tol nm; every dropped point within tol of the
 * segment between its kept neighbours.  Returns the points kept. */
static size_t mark_and_check(const int64_t *xy, size_t n, double tol)
{
	struct simplify_work wk = {0};
	bool *keep = calloc(n, sizeof(*keep));
	size_t kept = 0, prev = 0;

	ck_assert_ptr_nonnull(keep);
	ck_assert_int_eq(simplify_mark(&wk, xy, n, tol, keep, NULL), 0);
	ck_assert(keep[0] && keep[n - 1]);
	for (size_t k = 1; k < n; k++) {
		if (!keep[k])
			continue;
		for (size_t d = prev + 1; d < k; d++) {
			long double dev = seg_dist(xy + 2 * d, xy + 2 * prev, xy + 2 * k);
			ck_assert_msg(dev <= tol, "point %zu is %.3Lf nm from the simplified line "
				      "(tolerance %.0f nm)", d, dev, tol);
		}
		prev = k;
	}
	for (size_t k = 0; k < n; k++)
		kept += keep[k];
	free(keep);
	simplify_work_free(&wk);
	return kept;
}

/* A fixed generator, the same sequence everywhere. */
static uint64_t rnd_next(uint64_t *st)
{
	*st = *st * 6364136223846793005ull + 1442695040888963407ull;
	return *st >> 33;
}

/* Random walks: steps up to 0.5 mm in any direction, turns of any angle
 * (hairpins included), some points repeated; tolerances from 2 nm to
 * 0.2 mm. */
START_TEST(bound_on_random_polylines)
{
	static const double tols[] = {2, 1000, RES * NM, 0.2 * NM};
	uint64_t st = 12345;
	size_t n = 400, dropped = 0;
	int64_t *xy = malloc(2 * n * sizeof(*xy));

	ck_assert_ptr_nonnull(xy);
	for (int round = 0; round < 50; round++) {
		xy[0] = 100000000;
		xy[1] = 100000000;
		for (size_t k = 1; k < n; k++) {
			int64_t step = (int64_t)(rnd_next(&st) % 500000), r = (int64_t)(rnd_next(&st) % 8);
			xy[2 * k] = xy[2 * k - 2] + (r == 0 ? 0 : (int64_t)(rnd_next(&st) % (2 * step + 1)) - step);
			xy[2 * k + 1] = xy[2 * k - 1] + (r == 0 ? 0 : (int64_t)(rnd_next(&st) % (2 * step + 1)) - step);
		}
		for (size_t t = 0; t < sizeof(tols) / sizeof(tols[0]); t++)
			dropped += n - mark_and_check(xy, n, tols[t]);
	}
	ck_assert_uint_gt(dropped, 0);
	free(xy);
}
END_TEST

/* Circles and arcs of 0.2 to 100 mm radius, 8 to 4000 points, closed as
 * polylines (first point repeated), with and without 1 um of noise: within
 * the bound, and about the chords a circle needs at that tolerance. */
START_TEST(bound_on_circles)
{
	static const double radii[] = {0.2, 1, 6.5, 10, 37, 100};
	static const size_t counts[] = {8, 64, 360, 4000};
	uint64_t st = 99;

	for (size_t ri = 0; ri < sizeof(radii) / sizeof(radii[0]); ri++)
		for (size_t ci = 0; ci < sizeof(counts) / sizeof(counts[0]); ci++)
			for (int noise = 0; noise < 2; noise++) {
				size_t n = counts[ci] + 1, kept;
				double r = radii[ri] * NM;
				int64_t *xy = malloc(2 * n * sizeof(*xy));
				ck_assert_ptr_nonnull(xy);
				for (size_t k = 0; k < n; k++) {
					double a = 2 * M_PI * (double)(k % counts[ci]) / (double)counts[ci];
					int64_t jx = noise ? (int64_t)(rnd_next(&st) % 2001) - 1000 : 0;
					int64_t jy = noise ? (int64_t)(rnd_next(&st) % 2001) - 1000 : 0;
					xy[2 * k] = llround(150 * NM + r * cos(a)) + (k % counts[ci] ? jx : 0);
					xy[2 * k + 1] = llround(150 * NM + r * sin(a)) + (k % counts[ci] ? jy : 0);
				}
				kept = mark_and_check(xy, n, RES * NM);
				/* A chord of sagitta RES spans 2 acos(1 - RES / r). */
				double need = 2 * M_PI / (2 * acos(1 - RES * NM / r));
				if (counts[ci] > 2 * need)
					ck_assert_msg(kept <= 2 * need + 3,
						      "r %g mm, %zu points: %zu kept, %g chords suffice",
						      radii[ri], counts[ci], kept, need);
				free(xy);
			}
}
END_TEST

/* At most the slack, nothing is dropped: even collinear points stay. */
START_TEST(tiny_tolerance_keeps_everything)
{
	int64_t xy[20];

	for (int k = 0; k < 10; k++) {
		xy[2 * k] = k * 1000;
		xy[2 * k + 1] = 0;
	}
	ck_assert_uint_eq(mark_and_check(xy, 10, SIMPLIFY_SLACK_NM), 10);
	ck_assert_uint_eq(mark_and_check(xy, 10, 0), 10);
	ck_assert_uint_eq(mark_and_check(xy, 10, SIMPLIFY_SLACK_NM + 1), 2);
}
END_TEST

/* ---------------------------------------------------------------------------
 * A dense stack: what a slicer hands the writer for round walls, a gyroid
 * and a thin wall of varying width.
 */

/* A closed circle of n points, radius r mm around (cx, cy), bead w mm. */
static void add_circle(struct layer_paths *l, enum path_role role, double cx, double cy,
		       double r, size_t n, double w)
{
	struct path_point *p = calloc(n, sizeof(*p));

	ck_assert_ptr_nonnull(p);
	for (size_t k = 0; k < n; k++) {
		double a = 2 * M_PI * (double)k / (double)n;
		p[k] = (struct path_point){llround((cx + r * cos(a)) * NM),
					   llround((cy + r * sin(a)) * NM), llround(w * NM)};
	}
	ck_assert_int_eq(layer_add_path(l, role, true, p, n, NULL), 0);
	free(p);
}

/* An open wave y = cy + amp sin(x) from x0 to x1 mm in n points; width
 * w mm, or, when steps is set, w + 0.05 mm * (k / steps % 3) at point k. */
static void add_wave(struct layer_paths *l, enum path_role role, double x0, double x1,
		     double cy, double amp, size_t n, double w, size_t steps)
{
	struct path_point *p = calloc(n, sizeof(*p));

	ck_assert_ptr_nonnull(p);
	for (size_t k = 0; k < n; k++) {
		double x = x0 + (x1 - x0) * (double)k / (double)(n - 1);
		double wk = steps ? w + 0.05 * (double)(k / steps % 3) : w;
		p[k] = (struct path_point){llround(x * NM), llround((cy + amp * sin(x)) * NM),
					   llround(wk * NM)};
	}
	ck_assert_int_eq(layer_add_path(l, role, false, p, n, NULL), 0);
	free(p);
}

/* Two layers of 0.2 mm: round walls, a gyroid-like wave, a straight
 * line of collinear points, a thin wall whose width steps every 7 points. */
static struct layer_stack *dense_stack(void)
{
	struct layer_stack *st = layer_stack_new(2, NULL);

	ck_assert_ptr_nonnull(st);
	for (size_t i = 0; i < 2; i++) {
		struct layer_paths *l = &st->layers[i];
		l->z = 0.2 * (double)(i + 1);
		l->height = 0.2;
		add_circle(l, PATH_INNER_PERIMETER, 100, 100, 9.55, 120, 0.45);
		add_circle(l, PATH_OUTER_PERIMETER, 100, 100, 10, 120, 0.45);
		add_wave(l, PATH_SPARSE_INFILL, 92, 108, 100, 3, 161, 0.45, 0);
		add_wave(l, PATH_SOLID_INFILL, 92, 108, 104, 0, 33, 0.45, 0);
		add_wave(l, PATH_THIN_WALL, 93, 107, 96, 0.02, 57, 0.3, 7);
	}
	return st;
}

/* ---------------------------------------------------------------------------
 * 0 = off
 */

/* The golden file is the writer's output for dense_stack() at the commit
 * before gcode_resolution existed; with the key at 0 not a byte differs. */
START_TEST(resolution_zero_is_output_before)
{
	struct layer_stack *st = dense_stack();
	struct gcodew_settings s;
	size_t glen;
	char *golden = tu_slurp(GOLDEN, &glen), *text;

	gcodew_settings_init(&s);
	text = tu_gcode_mem(st, &s, NULL);
	tu_write_str(tu_path("dense-r0.gcode"), text);
	ck_assert_msg(strlen(text) == glen && memcmp(text, golden, glen) == 0,
		      "output differs from " GOLDEN " (written to %s)", tu_path("dense-r0.gcode"));
	free(text);
	free(golden);
	layer_stack_free(st);
}
END_TEST

void gcodewriter_simplify_tcases(Suite *s)
{
	TCase *tc = tcase_create("simplify");

	tcase_add_test(tc, bound_on_random_polylines);
	tcase_add_test(tc, bound_on_circles);
	tcase_add_test(tc, tiny_tolerance_keeps_everything);
	tcase_add_test(tc, resolution_zero_is_output_before);
	suite_add_tcase(s, tc);
}
