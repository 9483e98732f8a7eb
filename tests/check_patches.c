/*
 * check_patches.c - the flat patches of the self-intersection count
 * (repair/exact/patches.hpp), as test cases of the exact suite: surfaces
 * that turn counterclockwise under one projection everywhere, and are
 * still not one-to-one on it, so the count must not trust the patch.
 * Each case fails if the certificate wrongly accepts (docs/check.md).
 */
#include <check.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>

#include "exact.h"
#include "suites.h"

#define CVERTS(v) ((const double(*)[3])(v))
#define CTRIS(t) ((const uint32_t(*)[3])(t))

static uint64_t count(double (*v)[3], size_t nv, uint32_t (*t)[3], size_t nt, int threads)
{
	struct st_error err = {0};
	uint64_t n = 12345;

	ck_assert_msg(exact_count_self_intersections(CVERTS(v), nv, CTRIS(t), nt, NULL, threads, &n,
						     &err) == 0,
		      "exact_count_self_intersections: %s", err.msg);
	return n;
}

/*
 * A square at z = 0 and a smaller square inside its shadow, tilted so that
 * it crosses the first along y = 0 (z = 0.2 y), shifted by 0.25 in x.  All
 * four triangles face up, each vertex fan is fine and neither boundary
 * crosses the other seen from above: only the count of boundary loops
 * (two, where a flat patch has one) tells that the patch is not a disk.
 * On y = 0 the big square's lower triangle covers x >= 0 and its upper
 * one x <= 0; the small square's lower triangle x in [0.25, 0.75] and its
 * upper one [-0.25, 0.25]: three crossing pairs.
 */
START_TEST(two_loops_not_trusted)
{
	double v[8][3] = {{-2, -2, 0},	    {2, -2, 0},		 {2, 2, 0},
			  {-2, 2, 0},	    {-0.25, -0.5, -0.1}, {0.75, -0.5, -0.1},
			  {0.75, 0.5, 0.1}, {-0.25, 0.5, 0.1}};
	uint32_t t[4][3] = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}};

	for (int threads = 1; threads <= 2; threads++)
		ck_assert_uint_eq(count(v, 8, t, 4, threads), 3);
}
END_TEST

/*
 * A strip between radii 1 and 2 wound 1.3 times around the z axis, every
 * triangle facing up: one patch, a disk with one boundary loop and fans
 * once around, but the last 0.3 turn lies over the first.  Its slope
 * across the strip grows with the angle (z = 0.1 (r - 1.5) a / 2 pi), so
 * the two layers cross along r = 1.5: only the boundary's projection,
 * which is not simple, tells.  The expected count is what the pair test
 * finds with no patches at all (the count before patches.hpp).
 */
START_TEST(spiral_strip_not_trusted)
{
	enum { STEPS = 47, SPIRAL_PAIRS = 43 };
	const double turns = 1.3, da = 2 * M_PI * turns / STEPS;
	double v[2 * (STEPS + 1)][3];
	uint32_t t[2 * STEPS][3];

	for (int i = 0; i <= STEPS; i++)
		for (int j = 0; j < 2; j++) {
			const double a = i * da, r = 1 + j;
			/* floats, as in an STL file */
			v[2 * i + j][0] = (float)(r * cos(a));
			v[2 * i + j][1] = (float)(r * sin(a));
			v[2 * i + j][2] = (float)(0.1 * (r - 1.5) * a / (2 * M_PI));
		}
	for (int i = 0; i < STEPS; i++) {
		const uint32_t in = (uint32_t)(2 * i), out = in + 1, in2 = in + 2, out2 = in + 3;
		t[2 * i][0] = in;
		t[2 * i][1] = out;
		t[2 * i][2] = out2;
		t[2 * i + 1][0] = in;
		t[2 * i + 1][1] = out2;
		t[2 * i + 1][2] = in2;
	}
	for (int threads = 1; threads <= 2; threads++)
		ck_assert_uint_eq(count(v, 2 * (STEPS + 1), t, 2 * STEPS, threads), SPIRAL_PAIRS);
}
END_TEST

void exact_patches_tcases(Suite *s)
{
	TCase *tc = tcase_create("patches");

	tcase_add_test(tc, two_loops_not_trusted);
	tcase_add_test(tc, spiral_strip_not_trusted);
	suite_add_tcase(s, tc);
}
