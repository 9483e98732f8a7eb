/*
 * check_heal.c - the healing before the exact repair (repair/heal.h,
 * docs/repair.md "Healing"), through repair_mesh: nearly closed models
 * (unwelded corners, a seam between two halves, a small hole) must come
 * back as the solid they were meant to be, and open surfaces must still
 * be thickened as sheets.
 *
 * Each input is a closed generated model (tests/fixtures.c) with a defect
 * put in, so the intended solid is known: the output must be printable
 * (written as binary STL and read back, mesh_analyze's verdict), one part,
 * and enclose the closed model's volume within 1 %.
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

#define EPS 0.4		/* mm, the default epsilon */
#define VOLUME_TOL 0.01 /* relative: "within 1 % of the intended solid" */

struct healed {
	struct mesh *out;
	struct repair_report rep;
	int rc;
};

static struct healed run(const struct mesh *in, bool keep_holes)
{
	struct repair_options opt;
	struct st_error err = {0};
	struct healed h;

	repair_options_init(&opt);
	opt.epsilon = EPS;
	opt.keep_holes = keep_holes;
	memset(&h, 0, sizeof(h));
	h.rc = repair_mesh(in, &opt, &h.out, NULL, &h.rep, &err);
	ck_assert_msg(h.rc == 0, "repair_mesh returned %d: %s", h.rc, err.msg);
	return h;
}

static struct mesh_report analyze(const struct mesh *m)
{
	struct mesh_report r;
	struct st_error err = {0};

	ck_assert_msg(mesh_analyze(m, 2, &r, &err) == 0, "mesh_analyze: %s", err.msg);
	return r;
}

/*
 * The output, as the binary STL a printer gets, is one printable part
 * whose volume is want's within VOLUME_TOL.  Returns that volume.
 */
static double assert_solid(const struct healed *h, const struct mesh *want, const char *name)
{
	struct mesh *back;
	struct mesh_report r, w = analyze(want);

	ck_assert_msg(w.printable && w.volume > 0, "%s: the intended solid is not one", name);
	ck_assert_msg(h->rep.printable, "%s: not printable: %s", name, h->rep.why);
	back = tu_round_trip(h->out, name, MESHIO_STL_BINARY);
	r = analyze(back);
	mesh_free(back);
	ck_assert_msg(r.printable, "%s: written file not printable (%zu boundary edges, %llu "
				   "intersecting pairs, %zu parts)",
		      name, r.boundary_edges, (unsigned long long)r.self_intersections,
		      r.components);
	ck_assert_uint_eq(h->rep.components, 1);
	ck_assert_msg(fabs(r.volume - w.volume) <= VOLUME_TOL * w.volume,
		      "%s: volume %.6g mm^3, intended %.6g mm^3", name, r.volume, w.volume);
	return r.volume;
}

static void healed_free(struct healed *h)
{
	mesh_free(h->out);
	h->out = NULL;
}

/* Jitter amplitudes of the brief: from below the weld tolerance to 1e-3 mm. */
static const double jitter[] = {1e-6, 1e-5, 1e-4, 1e-3};

/*
 * Proves that a 10 mm cube whose 36 triangle corners were exported
 * unwelded and jittered comes back as the solid cube, not as a thin skin:
 * 28 of the 36 corners are merged into the 8 that remain, by welding when
 * the jitter is below the weld tolerance (8 float32 ulps at 10 mm, 7.6e-6
 * mm), by welding and stitching together above it; no sheet is left.
 */
START_TEST(jittered_cube_solid)
{
	struct mesh *cube = fx_box(0, 0, 0, 10, 10, 10);
	struct mesh *in = fx_jitter(cube, jitter[_i], 7);
	struct healed h = run(in, false);
	char name[64];

	snprintf(name, sizeof(name), "jittered-cube-%g.stl", jitter[_i]);
	assert_solid(&h, cube, name);
	ck_assert_uint_eq(h.rep.welded_vertices + h.rep.stitched_vertices, 28);
	if (2 * sqrt(3.0) * jitter[_i] < h.rep.weld_tolerance)
		ck_assert_uint_eq(h.rep.welded_vertices, 28);
	else /* pairs that happen to lie closer are welded first */
		ck_assert_uint_gt(h.rep.stitched_vertices, 0);
	ck_assert_uint_eq(h.rep.sheet_triangles, 0);
	ck_assert(!h.rep.second_pass);
	ck_assert_uint_eq(h.rep.holes_filled, 0);
	healed_free(&h);
	mesh_free(in);
	mesh_free(cube);
}
END_TEST

/* The same for a UV sphere (radius 10 mm, 12 x 16): every corner rejoined. */
START_TEST(jittered_sphere_solid)
{
	struct mesh *sphere = fx_sphere(0, 0, 0, 10, 12, 16);
	struct mesh *in = fx_jitter(sphere, jitter[_i], 11);
	struct healed h = run(in, false);
	char name[64];

	snprintf(name, sizeof(name), "jittered-sphere-%g.stl", jitter[_i]);
	assert_solid(&h, sphere, name);
	ck_assert_uint_eq(h.rep.welded_vertices + h.rep.stitched_vertices,
			  3 * sphere->ntris - sphere->nverts);
	ck_assert_uint_eq(h.rep.sheet_triangles, 0);
	healed_free(&h);
	mesh_free(in);
	mesh_free(sphere);
}
END_TEST

static const double seam[] = {0.001, 0.01, 0.1};

/*
 * Proves that a sphere exported as two halves with a seam between them
 * (0.001 to 0.1 mm, all below gamma = 1.5 epsilon) is stitched into one
 * closed sphere: the 24 equator vertices of the lower half snap onto the
 * upper half's, one gap between two loops is reported with its width, and
 * the volume is the closed sphere's within 1 %.
 */
START_TEST(sphere_halves_stitched)
{
	struct mesh *sphere = fx_sphere(0, 0, 0, 10, 16, 24);
	struct mesh *in = fx_split_gap(sphere, 0, seam[_i]);
	struct healed h = run(in, false);
	char name[64];

	snprintf(name, sizeof(name), "sphere-halves-%g.stl", seam[_i]);
	assert_solid(&h, sphere, name);
	ck_assert_uint_eq(h.rep.stitched_vertices, 24);
	ck_assert_uint_eq(h.rep.stitched_gaps, 1);
	ck_assert_double_eq_tol(h.rep.stitch_max_gap, seam[_i], 1e-9);
	ck_assert_uint_eq(h.rep.holes_filled, 0);
	ck_assert_uint_eq(h.rep.sheet_triangles, 0);
	healed_free(&h);
	mesh_free(in);
	mesh_free(sphere);
}
END_TEST

/*
 * Proves that small holes are filled, each with the patch of its own
 * corners (no new vertex): a sphere missing one triangle, a 64-sided
 * cylinder missing one side quad (two triangles), a cube missing one of
 * its 12 triangles.  Each comes back closed with the intended volume and
 * the report names one hole of the missing area.
 */
/* The closed models of small_hole_filled. */
static struct mesh *holed_model(int i)
{
	switch (i) {
	case 0:
		return fx_sphere(0, 0, 0, 10, 12, 16);
	case 1:
		return fx_cylinder(0, 0, 10, 20, 64);
	default:
		return fx_box(0, 0, 0, 10, 10, 10);
	}
}

START_TEST(small_hole_filled)
{
	static const char *const names[] = {"sphere-hole.stl", "cylinder-hole.stl",
					    "cube-hole.stl"};
	/* sphere: one band triangle; cylinder: caps are fans of 62 triangles
	 * each, then two per side quad; cube: one of 12 */
	static const size_t drop[] = {40, 2 * 62 + 10, 5}, ndrop[] = {1, 2, 1};
	struct mesh *closed = holed_model(_i), *in = holed_model(_i);
	const char *name = names[_i];
	const size_t patch = ndrop[_i];
	double missing = 0;
	for (size_t k = 0; k < ndrop[_i]; k++) {
		const uint32_t *c = in->tris[drop[_i]];
		const double *a = in->verts[c[0]], *b = in->verts[c[1]], *d = in->verts[c[2]];
		const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
		const double v[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
		const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
				     u[0] * v[1] - u[1] * v[0]};
		missing += 0.5 * sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
		fx_drop(in, drop[_i]);
	}
	struct healed h = run(in, false);
	assert_solid(&h, closed, name);
	ck_assert_uint_eq(h.rep.holes_filled, 1);
	ck_assert_uint_eq(h.rep.fill_triangles, patch);
	ck_assert_double_eq_tol(h.rep.hole_area[0], missing, 1e-9 * missing);
	ck_assert_double_eq_tol(h.rep.fill_area, missing, 1e-9 * missing);
	ck_assert_uint_eq(h.rep.holes_kept, 0);
	ck_assert_uint_eq(h.rep.sheet_triangles, 0);
	ck_assert(!h.rep.second_pass);
	healed_free(&h);
	mesh_free(in);
	mesh_free(closed);
}
END_TEST

/*
 * Proves that open surfaces are not mistaken for holes: a flag (a single
 * open 20 x 10 mm rectangle of 8 triangles) and an open corner (three
 * faces of a cube meeting at a vertex) keep their boundary -- their patch
 * would be as large as themselves -- and stay sheets for the thickening.
 */
START_TEST(open_surface_stays_sheet)
{
	struct repair_options opt;
	struct repair_report rep;
	struct st_error err = {0};
	struct mesh *in, *out = NULL;
	int rc;

	if (_i == 0) {
		const double o[3] = {0, 0, 0}, u[3] = {20, 0, 0}, v[3] = {0, 10, 0};
		in = fx_grid(o, u, v, 2, 2);
	} else {
		/* faces z = 0, y = 0, x = 0 of fx_box: drop z1, y1, x1 */
		in = fx_cube_without(10, 0xccc);
		ck_assert_uint_eq(in->ntris, 6);
	}
	repair_options_init(&opt);
	opt.epsilon = EPS;
	rc = repair_mesh(in, &opt, &out, NULL, &rep, &err);
	/* The decision is reported before the thickening runs. */
	ck_assert_uint_eq(rep.holes_filled, 0);
	ck_assert_uint_eq(rep.holes_kept, 1);
	ck_assert_msg(rep.kept_patch_fraction > 0.25, "patch fraction %g",
		      rep.kept_patch_fraction);
	ck_assert_uint_eq(rep.stitched_vertices, 0);
	/* The slab: printable, thickened, nothing closed. */
	ck_assert_msg(rc == 0, "repair_mesh returned %d: %s", rc, err.msg);
	ck_assert_msg(rep.printable, "not printable: %s", rep.why);
	ck_assert_uint_eq(rep.sheet_triangles, in->ntris);
	ck_assert(rep.second_pass);
	ck_assert_uint_gt(rep.thickened_triangles, 0);
	mesh_free(out);
	mesh_free(in);
}
END_TEST

/*
 * Proves that --keep-holes gives the seed's pipeline: the sphere halves
 * are not stitched and the missing triangle not filled; their boundary is
 * thickened as a sheet instead.
 */
START_TEST(keep_holes_turns_off_stitch_and_fill)
{
	struct mesh *sphere = fx_sphere(0, 0, 0, 10, 8, 12);
	struct mesh *in = fx_split_gap(sphere, 0, 0.01);
	struct repair_options opt;
	struct repair_report rep;
	struct st_error err = {0};
	struct mesh *out = NULL;

	repair_options_init(&opt);
	opt.keep_holes = true;
	repair_mesh(in, &opt, &out, NULL, &rep, &err);
	ck_assert_uint_eq(rep.stitched_vertices, 0);
	ck_assert_uint_eq(rep.holes_filled, 0);
	ck_assert_double_eq(rep.stitch_tolerance, 0);
	ck_assert_uint_eq(rep.sheet_triangles, in->ntris);
	mesh_free(out);
	mesh_free(in);
	mesh_free(sphere);
}
END_TEST

/* Proves the documented defaults: both tolerances automatic, holes healed. */
START_TEST(heal_defaults)
{
	struct repair_options opt;
	struct mesh *cube = fx_box(0, 0, 0, 10, 10, 10);
	struct healed h;

	memset(&opt, 0xff, sizeof(opt));
	repair_options_init(&opt);
	ck_assert_double_lt(opt.weld, 0);
	ck_assert_double_lt(opt.stitch, 0);
	ck_assert(!opt.keep_holes);
	h = run(cube, false);
	/* 8 float32 ulps at 10 mm (2^-20 mm each), gamma 1.5 epsilon */
	ck_assert_double_eq(h.rep.weld_tolerance, 8 * 0x1p-20);
	ck_assert_double_eq(h.rep.stitch_tolerance, 1.5 * EPS);
	ck_assert_uint_eq(h.rep.welded_vertices, 0);
	healed_free(&h);
	mesh_free(cube);
}
END_TEST

/* Proves that a tolerance that is not a number is refused, not used. */
START_TEST(bad_tolerance_rejected)
{
	struct repair_options opt;
	struct repair_report rep;
	struct st_error err = {0};
	struct mesh *cube = fx_box(0, 0, 0, 10, 10, 10), *out = NULL;

	repair_options_init(&opt);
	if (_i == 0)
		opt.weld = NAN;
	else
		opt.stitch = INFINITY;
	ck_assert_int_eq(repair_mesh(cube, &opt, &out, NULL, &rep, &err), ST_ERR_ARG);
	ck_assert_ptr_null(out);
	ck_assert_msg(strstr(err.msg, "finite") != NULL, "message: %s", err.msg);
	mesh_free(cube);
}
END_TEST

/*
 * Proves that a patch is checked exactly against its own shell: an open
 * box (patch 1/5, small enough to fill) with a spike of the same shell
 * (a tetrahedron hanging from the bottom corner) standing up through the
 * opening.  The flat patch would cross the spike, so the hole is left open
 * and counted as crossing; the repair thickens the box instead.
 */
START_TEST(crossing_patch_not_used)
{
	static const double spike[4][3] = {{0, 0, 0}, {3, 3, 1}, {4, 2, 1}, {3, 3, 14}};
	static const int faces[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
	struct mesh *box = fx_cube_without(10, 0xc); /* no top face (z = 10) */
	struct mesh_builder *b = mesh_builder_new(box->ntris + 4);
	struct repair_options opt;
	struct repair_report rep;
	struct st_error err = {0};
	struct mesh *in, *out = NULL;
	uint32_t v[4];

	ck_assert_ptr_nonnull(b);
	ck_assert_int_eq(mesh_builder_append(b, box, &err), 0);
	for (int i = 0; i < 4; i++)
		ck_assert_int_eq(mesh_builder_vertex(b, spike[i], &v[i], &err), 0);
	for (int f = 0; f < 4; f++)
		ck_assert_int_eq(mesh_builder_triangle(b, v[faces[f][0]], v[faces[f][1]],
						       v[faces[f][2]], &err), 0);
	in = mesh_builder_finish(b);
	ck_assert_ptr_nonnull(in);
	repair_options_init(&opt);
	opt.epsilon = EPS;
	ck_assert_int_eq(repair_mesh(in, &opt, &out, NULL, &rep, &err), 0);
	ck_assert_uint_eq(rep.holes_filled, 0);
	ck_assert_uint_eq(rep.holes_kept, 1);
	ck_assert_uint_eq(rep.holes_crossing, 1);
	ck_assert_msg(rep.printable, "not printable: %s", rep.why);
	ck_assert_uint_gt(rep.sheet_triangles, 0);
	mesh_free(out);
	mesh_free(in);
	mesh_free(box);
}
END_TEST

/*
 * Proves that a curved hole gets a curved patch: a sphere (r 10) without
 * its cap above z = 9 (rim at z = 9.24) is filled, and the refined and
 * faired patch rises above the rim towards the pole (a flat patch would
 * end at the rim), the volume within 1 % of the closed sphere.
 */
START_TEST(curved_hole_faired)
{
	struct mesh *closed = fx_sphere(0, 0, 0, 10, 32, 64);
	struct mesh *in = fx_sphere(0, 0, 0, 10, 32, 64);
	struct healed h;
	double lo[3], hi[3], rim = 0;

	for (size_t t = in->ntris; t-- > 0;) {
		const uint32_t *c = in->tris[t];
		if (in->verts[c[0]][2] > 9 && in->verts[c[1]][2] > 9 && in->verts[c[2]][2] > 9)
			fx_drop(in, t);
	}
	for (size_t t = 0; t < in->ntris; t++)
		for (int k = 0; k < 3; k++)
			rim = fmax(rim, in->verts[in->tris[t][k]][2]);
	h = run(in, false);
	ck_assert_uint_eq(h.rep.holes_filled, 1);
	ck_assert_uint_gt(h.rep.fill_triangles, 64 - 2); /* refined: more than the rim's fan */
	mesh_bbox(h.out, lo, hi);
	ck_assert_msg(hi[2] > rim + 0.2, "patch top z %g, rim %g: not faired", hi[2], rim);
	ck_assert_msg(hi[2] < 10 + 1e-9, "patch top z %g above the sphere", hi[2]);
	assert_solid(&h, closed, "capless.stl");
	healed_free(&h);
	mesh_free(in);
	mesh_free(closed);
}
END_TEST

Suite *heal_suite(void)
{
	Suite *s = suite_create("heal");
	TCase *solid = tcase_create("solid"), *open = tcase_create("open");
	TCase *args = tcase_create("args");

	tcase_set_timeout(solid, 120); /* exact passes under ASan */
	tcase_set_timeout(open, 120);
	tcase_add_loop_test(solid, jittered_cube_solid, 0, 4);
	tcase_add_loop_test(solid, jittered_sphere_solid, 0, 4);
	tcase_add_loop_test(solid, sphere_halves_stitched, 0, 3);
	tcase_add_loop_test(solid, small_hole_filled, 0, 3);
	tcase_add_test(solid, curved_hole_faired);
	suite_add_tcase(s, solid);
	tcase_add_loop_test(open, open_surface_stays_sheet, 0, 2);
	tcase_add_test(open, keep_holes_turns_off_stitch_and_fill);
	tcase_add_test(open, crossing_patch_not_used);
	suite_add_tcase(s, open);
	tcase_add_test(args, heal_defaults);
	tcase_add_loop_test(args, bad_tolerance_rejected, 0, 2);
	suite_add_tcase(s, args);
	return s;
}
