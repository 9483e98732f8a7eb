/*
 * check_clip_kept.c - clip_erosion_kept, the area test that lets the
 * slicer skip an erosion done only to see whether anything is left: never
 * "kept" where Clipper's erosion is empty, and "kept" for the plain wide
 * shapes it is there to spare (part of the slicer suite).
 */
#include <check.h>
#include <math.h>
#include <stdlib.h>

#include "clip.h"
#include "suites.h"

/* Whether Clipper's round erosion of ps by r leaves anything. */
static bool eroded_nonempty(const struct clip_paths *ps, double r)
{
	struct clip_paths out = {0};
	struct st_error err = {0};

	ck_assert_int_eq(clip_offset(ps, -r, CLIP_JOIN_ROUND, 0.0, 2000.0, &out, &err), 0);
	bool any = out.n > 0;
	clip_paths_free(&out);
	return any;
}

/* A rectangle w x h nm (CCW), with a square hole of side hole (CW) when > 0. */
static void rect(struct clip_paths *ps, int64_t w, int64_t h, int64_t hole)
{
	const int64_t r[] = {0, 0, w, 0, w, h, 0, h};
	struct st_error err = {0};

	clip_paths_clear(ps);
	ck_assert_int_eq(clip_paths_add(ps, r, 4, &err), 0);
	if (hole > 0) {
		int64_t x = (w - hole) / 2, y = (h - hole) / 2;
		const int64_t q[] = {x, y, x, y + hole, x + hole, y + hole, x + hole, y};
		ck_assert_int_eq(clip_paths_add(ps, q, 4, &err), 0);
	}
}

START_TEST(erosion_kept_plain_shapes)
{
	struct clip_paths ps = {0};

	/* 10 mm square, 0.225 mm erosion: kept without an offset. */
	rect(&ps, 10000000, 10000000, 0);
	ck_assert(clip_erosion_kept(&ps, 225000.0));
	/* A 0.4 mm strip eroded by 0.225 mm on each side: nothing left. */
	rect(&ps, 20000000, 400000, 0);
	ck_assert(!eroded_nonempty(&ps, 225000.0));
	ck_assert(!clip_erosion_kept(&ps, 225000.0));
	/* A 2 mm frame (6 mm square, 2 mm hole) keeps its ring at 0.5 mm... */
	rect(&ps, 6000000, 6000000, 2000000);
	ck_assert(clip_erosion_kept(&ps, 500000.0));
	/* ...and is not called kept at 1.2 mm, where even its corners (1.17 mm deep) are gone. */
	ck_assert(!eroded_nonempty(&ps, 1200000.0));
	ck_assert(!clip_erosion_kept(&ps, 1200000.0));
	clip_paths_free(&ps);
}
END_TEST

/* Random star polygons (many reflex vertices): kept implies non-empty. */
START_TEST(erosion_kept_never_wrong)
{
	struct clip_paths ps = {0};
	struct st_error err = {0};
	unsigned seed = 19;
	int kept = 0;

	for (int t = 0; t < 200; t++) {
		int n = 5 + rand_r(&seed) % 40;
		int64_t xy[2 * 44];
		for (int k = 0; k < n; k++) {
			double a = 2.0 * M_PI * k / n;
			double rad = 1e6 + (double)(rand_r(&seed) % 3000000);
			xy[2 * k] = llround(rad * cos(a));
			xy[2 * k + 1] = llround(rad * sin(a));
		}
		clip_paths_clear(&ps);
		ck_assert_int_eq(clip_paths_add(&ps, xy, (size_t)n, &err), 0);
		double r = 1e4 + (double)(rand_r(&seed) % 1500000);
		if (clip_erosion_kept(&ps, r)) {
			kept++;
			ck_assert_msg(eroded_nonempty(&ps, r), "star %d called kept at r %g", t, r);
		}
	}
	ck_assert_int_gt(kept, 20); /* the test reaches the "kept" answer */
	clip_paths_free(&ps);
}
END_TEST

void slicer_clip_tcases(Suite *s)
{
	TCase *tc = tcase_create("erosion_kept");

	tcase_add_test(tc, erosion_kept_plain_shapes);
	tcase_add_test(tc, erosion_kept_never_wrong);
	suite_add_tcase(s, tc);
}
