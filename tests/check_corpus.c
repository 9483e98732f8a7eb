/*
 * check_corpus.c - the repair on the defects downloaded models have, judged
 * as the user's slicer and `stratum check` would judge the written file.
 *
 * Every case is generated (tests/fixtures.c), deterministic, and knows its
 * intended solid where there is one: a cube missing facets is the cube, a
 * sphere exported in two halves with a seam is the sphere.  Each result is
 * written as binary STL and read back, and mesh_analyze (the verdict of
 * `stratum check`) must call that file printable; where an intended solid
 * exists its volume must be within 1 % of it.  No case may end in an error
 * (exit 70 in the CLI).  Larger corpora (CGAL's data meshes, big soups) are
 * in `make bench` (docs/benchmarks.md).
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fixtures.h"
#include "mesh.h"
#include "meshio.h"
#include "repair.h"
#include "suites.h"
#include "testutil.h"

#define EPS 0.4 /* mm */

/* A case's repair report and the analysis of its written file. */
struct outcome {
	struct repair_report rep;
	struct mesh_report file;	/* the written file, as `stratum check` sees it */
};

static double volume_of(const struct mesh *m)
{
	struct mesh_report r;
	struct st_error err = {0};

	ck_assert_msg(mesh_analyze(m, 2, &r, &err) == 0, "mesh_analyze: %s", err.msg);
	return r.volume;
}

/*
 * Repair in with default options, write the result as binary STL, read it
 * back and analyze it; the file must be printable and, when want is not
 * NAN, enclose want mm^3 within 1 %.
 */
static struct outcome repair_case(const struct mesh *in, double want, const char *name)
{
	struct repair_options opt;
	struct outcome o;
	struct st_error err = {0};
	struct mesh *out = NULL, *back = NULL;
	char file[96], why[256] = "";
	int rc;

	repair_options_init(&opt);
	opt.epsilon = EPS;
	rc = repair_mesh(in, &opt, &out, NULL, &o.rep, &err);
	ck_assert_msg(rc == 0, "%s: repair_mesh returned %d: %s", name, rc, err.msg);
	ck_assert_msg(o.rep.printable, "%s: repair says not printable: %s", name, o.rep.why);
	snprintf(file, sizeof(file), "%s.stl", name);
	back = tu_round_trip(out, file, MESHIO_STL_BINARY);
	ck_assert_msg(mesh_analyze(back, 2, &o.file, &err) == 0, "%s: mesh_analyze: %s", name,
		      err.msg);
	for (int r = 0; r < MESH_REASON_COUNT && !o.file.printable; r++)
		if (o.file.reasons[r])
			snprintf(why + strlen(why), sizeof(why) - strlen(why), " %s",
				 mesh_reason_code((enum mesh_reason)r));
	ck_assert_msg(o.file.printable, "%s: the written file is not printable:%s", name, why);
	if (!isnan(want))
		ck_assert_msg(fabs(o.file.volume - want) <= 0.01 * want,
			      "%s: volume %.6g mm^3, intended %.6g (%+.2f %%)", name, o.file.volume,
			      want, 100 * (o.file.volume - want) / want);
	mesh_free(out);
	mesh_free(back);
	return o;
}

/*
 * Proves that every 10 mm cube with one facet or two facets missing (78
 * cases) comes back as the solid cube: the holes are small against the
 * shell, so they are filled, not thickened into a skin.
 */
START_TEST(cubes_missing_facets)
{
	for (int i = 0; i < 12; i++)
		for (int j = i; j < 12; j++) {
			struct mesh *m = fx_cube_without(10, (1u << i) | (1u << j));
			char name[32];
			snprintf(name, sizeof(name), "cube-%d-%d", i, j);
			repair_case(m, 1000, name);
			mesh_free(m);
		}
}
END_TEST

/*
 * Proves that open surfaces with large boundaries stay sheets and are
 * thickened by epsilon: three faces of a cube (an open corner, 300 mm^2)
 * and a 10 x 10 mm flag become printable thin walls of about area x
 * epsilon, not filled solids.
 */
START_TEST(open_surfaces_thickened)
{
	const double o[3] = {0, 0, 0}, u[3] = {10, 0, 0}, v[3] = {0, 0, 10};
	struct mesh *m[2] = {fx_cube_without(10, 0xccc), fx_grid(o, u, v, 4, 4)};
	const double area[2] = {300, 100};

	for (int i = 0; i < 2; i++) {
		char name[32];
		snprintf(name, sizeof(name), "open-%d", i);
		struct outcome r = repair_case(m[i], NAN, name);
		ck_assert_uint_gt(r.rep.sheet_triangles, 0);
		ck_assert_msg(r.file.volume > 0.5 * area[i] * EPS && r.file.volume < 2 * area[i] * EPS,
			      "%s: volume %g, a wall of %g mm^2 x %g mm is about %g", name,
			      r.file.volume, area[i], EPS, area[i] * EPS);
		mesh_free(m[i]);
	}
}
END_TEST

/* Proves that Klein bottles (non-orientable, self-crossing) at several scales repair. */
START_TEST(klein_bottles)
{
	const double scales[4] = {0.3, 1, 2.5, 10};
	struct mesh *m = fx_klein_bottle(3, scales[_i], 24, 12);
	char name[32];

	snprintf(name, sizeof(name), "klein-%d", _i);
	repair_case(m, NAN, name);
	mesh_free(m);
}
END_TEST

/*
 * Proves that corners exported with rounding noise (1e-6 .. 1e-3 mm, so
 * the copies of a vertex do not weld) give the solid back: a 10 mm cube and
 * a sphere of radius 10, within 1 % of their closed volumes.
 */
START_TEST(jittered_solids)
{
	const double amp = pow(10, -6 + _i);
	struct mesh *cube = fx_box(0, 0, 0, 10, 10, 10);
	struct mesh *sphere = fx_sphere(0, 0, 0, 10, 16, 32);
	struct mesh *jc = fx_jitter(cube, amp, 11u + (unsigned)_i);
	struct mesh *js = fx_jitter(sphere, amp, 23u + (unsigned)_i);
	char name[32];

	snprintf(name, sizeof(name), "jcube-%d", _i);
	repair_case(jc, 1000, name);
	snprintf(name, sizeof(name), "jsphere-%d", _i);
	repair_case(js, volume_of(sphere), name);
	mesh_free(cube);
	mesh_free(sphere);
	mesh_free(jc);
	mesh_free(js);
}
END_TEST

/*
 * Proves that a sphere exported as two halves with a seam gap of 0.001,
 * 0.01 and 0.1 mm is stitched into one solid sphere (volume within 1 % of
 * the closed one), not grown by epsilon everywhere: with the same vertices
 * on both sides of the seam, and with halves tessellated apart.
 */
START_TEST(seamed_spheres)
{
	const double gaps[3] = {0.001, 0.01, 0.1};
	struct mesh *closed = fx_sphere(0, 0, 0, 10, 16, 32);
	struct mesh *m = fx_split_gap(closed, 0, gaps[_i]);
	char name[32];

	snprintf(name, sizeof(name), "seam-%d", _i);
	repair_case(m, volume_of(closed), name);
	/* The halves tessellated apart: 32 and 27 sectors, turned. */
	struct mesh *up = fx_hemisphere(10, 16, 32, 1, gaps[_i], 0);
	struct mesh *down = fx_hemisphere(10, 16, 27, 0, 0, 0.05);
	struct mesh *both = fx_concat(up, down);
	snprintf(name, sizeof(name), "seam-apart-%d", _i);
	repair_case(both, volume_of(closed), name);
	mesh_free(up);
	mesh_free(down);
	mesh_free(both);
	mesh_free(closed);
	mesh_free(m);
}
END_TEST

/*
 * Proves that one missing triangle does not turn a solid into a skin: a
 * sphere and a cylinder with one hole each come back solid.
 */
START_TEST(small_holes_filled)
{
	struct mesh *sphere = fx_sphere(0, 0, 0, 10, 16, 32);
	struct mesh *cyl = fx_cylinder(0, 0, 20, 63, 64);
	const double vs = volume_of(sphere), vc = volume_of(cyl);

	fx_drop(sphere, 40);
	fx_drop(cyl, 70);
	repair_case(sphere, vs, "holed-sphere");
	repair_case(cyl, vc, "holed-cylinder");
	mesh_free(sphere);
	mesh_free(cyl);
}
END_TEST

/*
 * Proves the two kinds of nested shells: an inner shell facing outward is
 * enclosed material and is deleted (volume of the outer cube); one facing
 * inward is a designed cavity and is kept (outer minus inner).
 */
START_TEST(nested_shells)
{
	struct mesh *outer = fx_box(0, 0, 0, 20, 20, 20);
	struct mesh *inner = fx_box(5, 5, 5, 15, 15, 15);
	struct mesh *solid = fx_concat(outer, inner);

	repair_case(solid, 8000, "nested-outward");
	for (size_t t = 0; t < inner->ntris; t++)
		fx_flip(inner, t);
	struct mesh *cavity = fx_concat(outer, inner);
	struct outcome o = repair_case(cavity, 8000 - 1000, "nested-inward");
	ck_assert_uint_eq(o.rep.enclosed_deleted, 0);
	mesh_free(outer);
	mesh_free(inner);
	mesh_free(solid);
	mesh_free(cavity);
}
END_TEST

/*
 * Proves that cubes touching along a face (they merge), an edge or a
 * vertex (they stay two parts) are written as one printable file of the
 * right volume.
 */
START_TEST(touching_cubes)
{
	const double at[3][3] = {{10, 0, 0}, {10, 10, 0}, {10, 10, 10}};
	struct mesh *a = fx_box(0, 0, 0, 10, 10, 10);
	struct mesh *b = fx_box(at[_i][0], at[_i][1], at[_i][2], at[_i][0] + 10, at[_i][1] + 10,
				at[_i][2] + 10);
	struct mesh *m = fx_concat(a, b);
	char name[32];

	snprintf(name, sizeof(name), "touch-%d", _i);
	repair_case(m, 2000, name);
	mesh_free(a);
	mesh_free(b);
	mesh_free(m);
}
END_TEST

/*
 * Soup sizes: a deterministic sample of 1 to 20k triangles; bigger soups
 * are in `make bench`.  Exact arithmetic under AddressSanitizer is several
 * times slower, so the 20k soup (about 40 s plain) runs in the plain pass
 * of `make check` only.
 */
#ifdef __SANITIZE_ADDRESS__
static const int soup_sizes[] = {1, 10, 100, 1000, 5000};
#else
static const int soup_sizes[] = {1, 10, 100, 1000, 5000, 20000};
#endif

/*
 * Proves that random triangle soups (2 mm triangles, about 1000 in a
 * 20 mm cube, the box grown with their number) repair into printable
 * files.
 */
START_TEST(random_soups)
{
	const double box = 20 * cbrt(soup_sizes[_i] / 1000.0);
	struct mesh *m = fx_soup(1000u + (unsigned)_i, soup_sizes[_i], box, 2);
	char name[32];

	snprintf(name, sizeof(name), "soup-%d", soup_sizes[_i]);
	repair_case(m, NAN, name);
	mesh_free(m);
}
END_TEST

static void setup(void)
{
	tu_scratch_init();
}

static void teardown(void)
{
	tu_scratch_cleanup();
}

Suite *corpus_suite(void)
{
	Suite *s = suite_create("corpus");
	TCase *closed = tcase_create("nearly-closed"), *open = tcase_create("open");
	TCase *parts = tcase_create("parts"), *soup = tcase_create("soup");
	TCase *all[4] = {closed, open, parts, soup};

	for (int i = 0; i < 4; i++) {
		tcase_add_checked_fixture(all[i], setup, teardown);
		/* Exact arithmetic under ASan/UBSan is slow. */
		tcase_set_timeout(all[i], 300);
	}
	tcase_add_test(closed, cubes_missing_facets);
	tcase_add_loop_test(closed, jittered_solids, 0, 4);
	tcase_add_loop_test(closed, seamed_spheres, 0, 3);
	tcase_add_test(closed, small_holes_filled);
	suite_add_tcase(s, closed);
	tcase_add_test(open, open_surfaces_thickened);
	tcase_add_loop_test(open, klein_bottles, 0, 4);
	suite_add_tcase(s, open);
	tcase_add_test(parts, nested_shells);
	tcase_add_loop_test(parts, touching_cubes, 0, 3);
	suite_add_tcase(s, parts);
	tcase_add_loop_test(soup, random_soups, 0, (int)(sizeof(soup_sizes) / sizeof(soup_sizes[0])));
	suite_add_tcase(s, soup);
	return s;
}
