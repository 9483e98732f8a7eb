/*
 * check_repair_sheet.c - seed 000's repair end to end, part of the repair
 * suite (check_repair.c, whose comment says how each result is judged):
 * sheets and wires thickened, random soups and Klein bottles printable, and
 * bad arguments refused.
 */
#include <check.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fixtures.h"
#include "mesh.h"
#include "meshio.h"
#include "repair.h"
#include "repairtest.h"
#include "suites.h"
#include "testutil.h"

/* ---- 4.-6. sheets are thickened ---- */

/* The bounding box of m lies within lo..hi (per axis) with slack tol. */
static void assert_bbox_within(const struct mesh *m, const double lo[3], const double hi[3],
			       double tol)
{
	double mn[3], mx[3];

	mesh_bbox(m, mn, mx);
	for (int k = 0; k < 3; k++)
		ck_assert_msg(mn[k] >= lo[k] - tol && mx[k] <= hi[k] + tol,
			      "axis %d: bbox [%.9g, %.9g] not within [%.9g, %.9g]", k, mn[k], mx[k],
			      lo[k], hi[k]);
}

/*
 * Proves that with --keep-holes an open cube (one triangle missing; by
 * default the hole is filled, tests/check_heal.c) is entirely M_sheet (all
 * 11 triangles double-sided) and becomes a closed thin-walled box: the
 * second pass runs and finds no sheet, the result stays within epsilon of
 * the cube, and its volume is that of a wall of thickness epsilon over the
 * cube's surface (A = 600 mm^2, loose bounds 0.3..1.5 * A * epsilon).
 */
START_TEST(open_cube_thickened)
{
	struct mesh *in = fx_box(0, 0, 0, 10, 10, 10);
	struct repair_options opt;
	const double lo[3] = {-EPS, -EPS, -EPS}, hi[3] = {10 + EPS, 10 + EPS, 10 + EPS};
	struct fixed f;
	struct mesh_report r;

	fx_drop(in, 5);
	repair_options_init(&opt);
	opt.epsilon = EPS;
	opt.keep_holes = true; /* the seed's pipeline: no hole filling */
	f = repair_with(in, &opt);
	r = judge(&f, REPAIR_FLOAT32, "opencube");
	ck_assert_uint_eq(f.rep.sheet_triangles, 11);
	ck_assert(f.rep.second_pass);
	ck_assert_uint_eq(f.rep.second_sheet_triangles, 0);
	ck_assert_uint_gt(f.rep.thickened_triangles, 0);
	assert_near_input(&f, in);
	ck_assert_msg(f.rep.sheet_deviation <= EPS / 2 + 1e-3, "reported sheet_deviation %g",
		      f.rep.sheet_deviation);
	ck_assert_uint_eq(f.rep.components, 1);
	assert_bbox_within(f.out, lo, hi, 1e-6);
	ck_assert_msg(r.volume >= 0.3 * 600 * EPS && r.volume <= 1.5 * 600 * EPS,
		      "thin-walled box volume %g, expected %g..%g", r.volume, 0.3 * 600 * EPS,
		      1.5 * 600 * EPS);
	fixed_free(&f);
	mesh_free(in);
}
END_TEST

/*
 * The output is a slab of thickness epsilon over the square [x0,x1]^2 in
 * z = 0: z extent epsilon (0.9..1.1 epsilon), it covers the square and
 * grows at most epsilon/2 past each edge, volume about area * epsilon.
 */
static void assert_slab(const struct fixed *f, const struct mesh_report *r, double x0, double x1)
{
	double mn[3], mx[3], side = x1 - x0;

	mesh_bbox(f->out, mn, mx);
	ck_assert_msg(mx[2] - mn[2] >= 0.9 * EPS && mx[2] - mn[2] <= 1.1 * EPS + 1e-3,
		      "slab z extent %.9g (z %.9g..%.9g), expected epsilon = %g", mx[2] - mn[2],
		      mn[2], mx[2], EPS);
	ck_assert_msg(mn[2] <= 0 && mx[2] >= 0, "slab z %.9g..%.9g does not contain the sheet",
		      mn[2], mx[2]);
	for (int k = 0; k < 2; k++) {
		ck_assert_msg(mn[k] <= x0 && mx[k] >= x1,
			      "axis %d: slab %.9g..%.9g does not cover the sheet %g..%g", k, mn[k],
			      mx[k], x0, x1);
		ck_assert_msg(mx[k] - mn[k] <= side + EPS + 1e-3, "axis %d: slab extent %.9g > %g",
			      k, mx[k] - mn[k], side + EPS);
	}
	ck_assert_msg(r->volume >= 0.9 * side * side * EPS &&
			      r->volume <= 1.1 * (side + EPS) * (side + EPS) * EPS,
		      "slab volume %g, expected about %g", r->volume, side * side * EPS);
	ck_assert_msg(f->rep.sheet_deviation <= EPS / 2 + 1e-3, "reported sheet_deviation %g",
		      f->rep.sheet_deviation);
	ck_assert(f->rep.second_pass);
	ck_assert_uint_eq(f->rep.second_sheet_triangles, 0);
	ck_assert_uint_eq(f->rep.components, 1);
}

/*
 * Proves that an open 30 x 30 mm square sheet in z = 0 (as two triangles,
 * and as an 8 x 8 grid of 128) becomes one slab of total thickness
 * epsilon around it.
 */
START_TEST(open_square_becomes_slab)
{
	const int n = _i == 0 ? 1 : 8;
	const double o[3] = {0, 0, 0}, u[3] = {30, 0, 0}, v[3] = {0, 30, 0};
	struct mesh *in = fx_grid(o, u, v, n, n);
	struct fixed f = repair_eps(in, EPS);
	struct mesh_report r = judge(&f, REPAIR_FLOAT32, "square");

	ck_assert_uint_eq(f.rep.sheet_triangles, (size_t)2 * n * n);
	ck_assert_uint_eq(f.rep.sheet_components, 1);
	ck_assert_double_eq_tol(f.rep.sheet_area, 900.0, 1e-9);
	ck_assert(f.rep.second_pass);
	ck_assert_uint_eq(f.rep.second_sheet_triangles, 0);
	assert_near_input(&f, in);
	assert_slab(&f, &r, 0, 30);
	fixed_free(&f);
	mesh_free(in);
}
END_TEST

/*
 * Proves that a box of zero height, fx_box(0,0,0,10,10,0) (8 irregular
 * side triangles, the top an equivalent copy of the bottom: one open
 * square, see check_mesh.c flat_cube), becomes a 10 x 10 slab of
 * thickness epsilon.
 */
START_TEST(flat_cube_becomes_slab)
{
	struct mesh *in = fx_box(0, 0, 0, 10, 10, 0);
	struct fixed f = repair_eps(in, EPS);
	struct mesh_report r = judge(&f, REPAIR_FLOAT32, "flat");

	ck_assert_uint_eq(in->ntris, 12);
	ck_assert_uint_eq(f.rep.irregular_removed, 8);
	ck_assert_uint_eq(f.rep.duplicates_removed, 2);
	ck_assert_uint_eq(f.rep.sheet_triangles, 2);
	ck_assert(f.rep.second_pass);
	ck_assert_uint_eq(f.rep.second_sheet_triangles, 0);
	assert_near_input(&f, in);
	assert_slab(&f, &r, 0, 10);
	fixed_free(&f);
	mesh_free(in);
}
END_TEST

/*
 * Proves that a fin (a 10 x 5 mm sheet standing on the top face of the
 * cube [0,10]^3 at x = 5, as 2 triangles and as a 4 x 4 grid) is
 * thickened and fused to the cube: one component, top at z = 15 (plus at
 * most epsilon/2), volume 1000 plus about 50 * epsilon, and the cube's
 * bottom face, which nothing touches, is still there exactly.
 */
START_TEST(fin_fused_to_cube)
{
	const int n = _i == 0 ? 1 : 4;
	const double o[3] = {5, 0, 10}, u[3] = {0, 10, 0}, v[3] = {0, 0, 5};
	const double lo[3] = {0, -EPS / 2, 0}, hi[3] = {10, 10 + EPS / 2, 15 + EPS / 2};
	const double c000[3] = {0, 0, 0}, c100[3] = {10, 0, 0}, c010[3] = {0, 10, 0},
		     c110[3] = {10, 10, 0};
	struct mesh *cube = fx_box(0, 0, 0, 10, 10, 10), *fin = fx_grid(o, u, v, n, n);
	struct mesh *in = fx_concat(cube, fin);
	struct fixed f = repair_eps(in, EPS);
	struct mesh_report r = judge(&f, REPAIR_FLOAT32, "fin");
	double mn[3], mx[3];

	ck_assert_uint_eq(f.rep.components, 1);
	ck_assert_uint_eq(r.components, 1);
	ck_assert_uint_ge(f.rep.sheet_triangles, (size_t)2 * n * n);
	ck_assert(f.rep.second_pass);
	ck_assert_uint_eq(f.rep.second_sheet_triangles, 0);
	mesh_bbox(f.out, mn, mx);
	ck_assert_msg(mx[2] >= 15 && mx[2] <= 15 + EPS / 2 + 1e-3, "top z %.9g, expected 15",
		      mx[2]);
	ck_assert_double_eq(mn[2], 0.0);
	assert_bbox_within(f.out, lo, hi, 1e-3);
	assert_near_input(&f, in);
	ck_assert_msg(r.volume >= 1000 && r.volume <= 1000 + 50 * EPS * 1.5,
		      "cube + fin volume %.9g, expected 1000 + about %g", r.volume, 50 * EPS);
	/* Bottom face, quad v0 v2 v3 v1 of fx_box. */
	ck_assert(has_triangle(f.out, c000, c010, c110));
	ck_assert(has_triangle(f.out, c000, c110, c100));
	fixed_free(&f);
	mesh_free(in);
	mesh_free(cube);
	mesh_free(fin);
}
END_TEST

/* ---- 8. wires ---- */

/*
 * Proves that a degenerate triangle (collinear corners (5,5,10),
 * (5,5,15), (5,5,12.5)) standing on the cube's top face is kept as one
 * wire of length 5, thickened and fused: one component reaching z = 15
 * (within epsilon), and a thin rod adds little volume.
 */
START_TEST(dangling_wire_thickened)
{
	const double a[3] = {5, 5, 10}, b[3] = {5, 5, 15}, c[3] = {5, 5, 12.5};
	const double lo[3] = {0, 0, 0}, hi[3] = {10, 10, 15 + EPS};
	struct mesh *cube = fx_box(0, 0, 0, 10, 10, 10), *wire = fx_triangle(a, b, c);
	struct mesh *in = fx_concat(cube, wire);
	struct fixed f = repair_eps(in, EPS);
	struct mesh_report r = judge(&f, REPAIR_FLOAT32, "wire");
	double mn[3], mx[3];

	ck_assert_uint_eq(f.rep.degenerate_removed, 1);
	ck_assert_uint_eq(f.rep.wires, 1);
	ck_assert_double_eq_tol(f.rep.wire_length, 5.0, 1e-9);
	ck_assert_uint_eq(f.rep.wires_discarded, 0);
	ck_assert(f.rep.second_pass);
	ck_assert_uint_eq(f.rep.second_sheet_triangles, 0);
	ck_assert_uint_eq(f.rep.components, 1);
	mesh_bbox(f.out, mn, mx);
	ck_assert_msg(fabs(mx[2] - 15) <= EPS, "top z %.9g, expected 15 +- %g", mx[2], EPS);
	assert_near_input(&f, in);
	assert_bbox_within(f.out, lo, hi, 1e-6);
	ck_assert_msg(r.volume > 1000 && r.volume <= 1000 + 2 * (5 + EPS) * EPS * EPS,
		      "cube + rod volume %.9g", r.volume);
	fixed_free(&f);
	mesh_free(in);
	mesh_free(cube);
	mesh_free(wire);
}
END_TEST

/* ---- 10.-11. arbitrary soups ---- */

/*
 * Proves the claim of seed 000 §4, any soup in, printable out, on 20
 * random triangles in a 10 mm box (intersecting, open, isolated).  Each
 * component must be printable and the result stays within epsilon of the
 * input's box.  Seed 10 is a soup where plain float32 rounding made new
 * crossings faster than re-cutting removed them; snap rounding places its
 * vertices without any.  (Seeds 14, 18, 20, 30, 36 were such too; they
 * pass as well but cost the suite too much time.)  Its moves stay within two float
 * steps of the exact places (a few micrometres at 10 mm), per rounding
 * round.  The second pass must leave M_sheet empty (a sheet left is an
 * internal error, no third pass): seeds 1 and 10 left 1 and 6 sheet
 * triangles while the hull growing could leave one side of a face in
 * the middle of a sheet unwalked.
 */
static const unsigned random_seeds[] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13};

START_TEST(random_triangles_printable)
{
	struct mesh *in = fx_random_triangles(random_seeds[_i], 20, 10.0);
	struct fixed f = repair_eps(in, EPS);
	double mn[3], mx[3], lo[3], hi[3];
	char name[32];

	snprintf(name, sizeof(name), "random%u", random_seeds[_i]);
	judge(&f, REPAIR_FLOAT32, name);
	ck_assert(f.rep.second_pass);
	ck_assert_uint_eq(f.rep.second_sheet_triangles, 0);
	mesh_bbox(in, mn, mx);
	for (int k = 0; k < 3; k++) {
		lo[k] = mn[k] - EPS;
		hi[k] = mx[k] + EPS;
	}
	assert_bbox_within(f.out, lo, hi, 1e-6);
	assert_near_input(&f, in);
	/* Two float steps at 10 mm (< 1.9e-6 mm per coordinate) a round. */
	ck_assert_msg(f.rep.rounding_deviation < 3.3e-6 * (f.rep.rounding_rounds + 1),
		      "rounding_deviation %g after %d rounds", f.rep.rounding_deviation,
		      f.rep.rounding_rounds);
	fixed_free(&f);
	mesh_free(in);
}
END_TEST

/* Klein bottle resolutions: the 40 x 20 of the plan and others around it. */
static const int klein_grid[][2] = {{40, 20}, {24, 12}, {32, 16}, {48, 24}};

/*
 * Proves that a closed, unorientable, self-intersecting surface (the
 * figure-8 Klein bottle immersion, about 22 mm across, at several grid
 * resolutions) is resolved into printable solids: the intersections are
 * found and cut, and the result stays within the input's box (plus epsilon
 * for any sheet) and within epsilon/2 of the input surface.
 */
START_TEST(klein_bottle_printable)
{
	struct mesh *in = fx_klein_bottle(3, 2.5, klein_grid[_i][0], klein_grid[_i][1]);
	struct fixed f = repair_eps(in, EPS);
	double mn[3], mx[3], lo[3], hi[3];
	struct mesh_report r;

	r = judge(&f, REPAIR_FLOAT32, "klein");
	ck_assert_uint_gt(f.rep.intersecting_pairs, 0);
	ck_assert_uint_gt(f.rep.triangles_split, 0);
	ck_assert_uint_eq(f.rep.second_sheet_triangles, 0);
	ck_assert(r.volume > 0);
	mesh_bbox(in, mn, mx);
	for (int k = 0; k < 3; k++) {
		lo[k] = mn[k] - EPS;
		hi[k] = mx[k] + EPS;
	}
	assert_bbox_within(f.out, lo, hi, 1e-6);
	assert_near_input(&f, in);
	fixed_free(&f);
	mesh_free(in);
}
END_TEST

/* ---- 12. bad input ---- */

/*
 * Proves that a non-positive or NaN epsilon is refused with ST_ERR_ARG, a
 * message, and both output pointers set to NULL (docs/architecture.md convention 3).
 */
START_TEST(bad_epsilon_rejected)
{
	const double bad[] = {0.0, -0.4, NAN};
	struct mesh *in = fx_box(0, 0, 0, 10, 10, 10);
	struct mesh sentinel;
	uint32_t dummy = 0;
	struct repair_options opt;
	struct repair_report rep;
	struct st_error err;
	struct mesh *out = &sentinel;
	uint32_t *comp = &dummy;
	int rc;

	repair_options_init(&opt);
	opt.epsilon = bad[_i];
	memset(&err, 0, sizeof(err));
	rc = repair_mesh(in, &opt, &out, &comp, &rep, &err);
	ck_assert_msg(rc == ST_ERR_ARG, "epsilon %g: returned %d, expected ST_ERR_ARG", bad[_i],
		      rc);
	ck_assert_int_eq(err.code, ST_ERR_ARG);
	ck_assert_msg(err.msg[0] != '\0', "no error message");
	ck_assert_ptr_null(out);
	ck_assert_ptr_null(comp);
	mesh_free(in);
}
END_TEST

/* Proves that the defaults are the documented ones (epsilon 0.4 mm, float32). */
START_TEST(default_options)
{
	struct repair_options opt;

	memset(&opt, 0xff, sizeof(opt));
	repair_options_init(&opt);
	ck_assert_double_eq(opt.epsilon, 0.4);
	ck_assert_int_eq(opt.precision, REPAIR_FLOAT32);
	ck_assert_int_eq(opt.threads, 0);
	ck_assert(opt.progress == NULL);
}
END_TEST

/*
 * Proves that an empty mesh is not an error but not printable either:
 * repair_mesh returns 0, rep.printable false and rep.why says why.
 */
START_TEST(empty_mesh_not_printable)
{
	struct mesh_builder *b = mesh_builder_new(0);
	struct mesh *in = mesh_builder_finish(b);
	struct repair_options opt;
	struct repair_report rep;
	struct st_error err = {0};
	struct mesh *out = NULL;
	uint32_t *comp = NULL;
	int rc;

	repair_options_init(&opt);
	rc = repair_mesh(in, &opt, &out, &comp, &rep, &err);
	ck_assert_msg(rc == 0, "returned %d: %s", rc, err.msg);
	ck_assert(!rep.printable);
	ck_assert_msg(rep.why[0] != '\0', "rep.why is empty");
	ck_assert_uint_eq(rep.input_triangles, 0);
	if (out)
		ck_assert_uint_eq(out->ntris, 0);
	mesh_free(out);
	free(comp);
	mesh_free(in);
}
END_TEST


void repair_sheet_tcases(Suite *s)
{
	TCase *sheet = tcase_create("sheet");
	TCase *soup = tcase_create("soup"), *args = tcase_create("args");

	/* Exact arithmetic under ASan/UBSan is slow; these are small inputs. */
	tcase_set_timeout(sheet, 60);
	tcase_set_timeout(soup, 300); /* random soups re-cut several rounds; slow under ASan */
	tcase_add_test(sheet, open_cube_thickened);
	tcase_add_loop_test(sheet, open_square_becomes_slab, 0, 2);
	tcase_add_test(sheet, flat_cube_becomes_slab);
	tcase_add_loop_test(sheet, fin_fused_to_cube, 0, 2);
	tcase_add_test(sheet, dangling_wire_thickened);
	suite_add_tcase(s, sheet);
	tcase_add_loop_test(soup, random_triangles_printable, 0,
			    (int)(sizeof(random_seeds) / sizeof(random_seeds[0])));
	tcase_add_loop_test(soup, klein_bottle_printable, 0,
			    (int)(sizeof(klein_grid) / sizeof(klein_grid[0])));
	suite_add_tcase(s, soup);
	tcase_add_loop_test(args, bad_epsilon_rejected, 0, 3);
	tcase_add_test(args, default_options);
	tcase_add_test(args, empty_mesh_not_printable);
	suite_add_tcase(s, args);
}
