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

/* Triangles of a strip of quads between columns of two vertices each
 * (2i, 2i + 1), turning counterclockwise when 2i + 1 lies to the right
 * of the way from 2i to 2i + 2. */
static void strip(uint32_t (*t)[3], int quads)
{
	for (int i = 0; i < quads; i++) {
		const uint32_t in = (uint32_t)(2 * i), out = in + 1, in2 = in + 2, out2 = in + 3;
		t[2 * i][0] = in;
		t[2 * i][1] = out;
		t[2 * i][2] = out2;
		t[2 * i + 1][0] = in;
		t[2 * i + 1][1] = out2;
		t[2 * i + 1][2] = in2;
	}
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
	strip(t, STEPS);
	for (int threads = 1; threads <= 2; threads++)
		ck_assert_uint_eq(count(v, 2 * (STEPS + 1), t, 2 * STEPS, threads), SPIRAL_PAIRS);
}
END_TEST

/*
 * A polar cap: a pole and RINGS rings of SPOKES vertices at radius 1, 2,
 * ... on the dome z = -0.1 r^2, every triangle facing up; then the pole
 * pushed to (px, py, pz).  Returns the triangle count.
 */
enum { SPOKES = 24, RINGS = 3, CAP_VERTS = 1 + SPOKES * RINGS };
static size_t cap(double (*v)[3], uint32_t (*t)[3], double px, double py, double pz)
{
	size_t nt = 0;

	v[0][0] = px;
	v[0][1] = py;
	v[0][2] = pz;
	for (int j = 0; j < RINGS; j++)
		for (int i = 0; i < SPOKES; i++) {
			const double a = 2 * M_PI * i / SPOKES, r = j + 1;
			double *p = v[1 + j * SPOKES + i];
			p[0] = (float)(r * cos(a));
			p[1] = (float)(r * sin(a));
			p[2] = (float)(-0.1 * r * r);
		}
	for (int i = 0; i < SPOKES; i++) {
		const uint32_t i2 = (uint32_t)((i + 1) % SPOKES);
		t[nt][0] = 0;
		t[nt][1] = 1 + (uint32_t)i;
		t[nt++][2] = 1 + i2;
		for (uint32_t j = 0; j + 1 < RINGS; j++) {
			const uint32_t in = 1 + j * SPOKES, out = in + SPOKES;
			t[nt][0] = in + (uint32_t)i;
			t[nt][1] = out + (uint32_t)i;
			t[nt++][2] = out + i2;
			t[nt][0] = in + (uint32_t)i;
			t[nt][1] = out + i2;
			t[nt++][2] = in + i2;
		}
	}
	return nt;
}

/*
 * The cap as made is one patch and crosses nothing.  Its pole pushed
 * sideways past the second ring and just below the dome there, the
 * pole's fan leaves the first ring under the dome and comes up through
 * the rings.  Seen from above the fan's triangles on the far side still
 * turn counterclockwise, those on the near side clockwise: the near ones
 * go to another patch (condition 1), and the pole's star does not go
 * once around (condition 2); the test fails when both are skipped.  The
 * count is the one the pair test finds with no patches at all.
 */
START_TEST(cap_with_pole_pushed_through)
{
	enum { PUSHED_PAIRS = 28 };
	double v[CAP_VERTS][3];
	uint32_t t[SPOKES * (2 * RINGS - 1)][3];
	size_t nt = cap(v, t, 0, 0, 0);

	for (int threads = 1; threads <= 2; threads++)
		ck_assert_uint_eq(count(v, CAP_VERTS, t, nt, threads), 0);
	nt = cap(v, t, 2.5, 0.1, -0.5);
	for (int threads = 1; threads <= 2; threads++)
		ck_assert_uint_eq(count(v, CAP_VERTS, t, nt, threads), PUSHED_PAIRS);
}
END_TEST

/*
 * A strip two units wide along x, folded back at x = 4 over itself: the
 * returning layer rises to z = 0.2 and then sinks to z = -0.2, crossing
 * the first layer near x = 2.25.  Seen from above the returning layer
 * turns clockwise (condition 1), the fans along the fold turn both ways
 * (condition 2) and the boundary overlaps itself (condition 3); the test
 * fails when all three are skipped.  The count is the pair test's with
 * no patches.
 */
START_TEST(folded_strip)
{
	enum { STEPS = 8, FOLD_PAIRS = 4 };
	double v[2 * (2 * STEPS + 1)][3];
	uint32_t t[2 * 2 * STEPS][3];

	/* Column c (0 .. 2 STEPS) has vertices 2c (y = 2) and 2c + 1 (y = 0). */
	for (int c = 0; c <= 2 * STEPS; c++) {
		const int back = c > STEPS ? c - STEPS : 0;
		const double x = c <= STEPS ? 4.0 * c / STEPS : 4 - 4.0 * back / STEPS;
		const double z = back == 0 ? 0 : back <= 3 ? 0.2 : -0.2;
		for (int k = 0; k < 2; k++) {
			v[2 * c + k][0] = x;
			v[2 * c + k][1] = 2 - 2 * k;
			v[2 * c + k][2] = z;
		}
	}
	strip(t, 2 * STEPS);
	for (int threads = 1; threads <= 2; threads++)
		ck_assert_uint_eq(count(v, 2 * (2 * STEPS + 1), t, 4 * STEPS, threads), FOLD_PAIRS);
}
END_TEST

void exact_patches_tcases(Suite *s)
{
	TCase *tc = tcase_create("patches");

	tcase_add_test(tc, two_loops_not_trusted);
	tcase_add_test(tc, spiral_strip_not_trusted);
	tcase_add_test(tc, cap_with_pole_pushed_through);
	tcase_add_test(tc, folded_strip);
	suite_add_tcase(s, tc);
}
