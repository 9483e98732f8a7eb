/*
 * check_exact.c - the CGAL bridge: exact predicates on inputs where plain
 * double arithmetic decides wrongly, and the self-intersection count on
 * generated meshes whose expected counts are derived in the comments (seed
 * 000 Definition 3.6); hand-placed pairs and bad arguments are in
 * check_exact_pairs.c.
 */
#include <check.h>
#include <float.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "exact.h"
#include "exacttest.h"
#include "fixtures.h"
#include "mesh.h"
#include "suites.h"

/* Count over a whole mesh; the call must succeed. */
static uint64_t count_mesh(const struct mesh *m, const uint8_t *skip, int threads)
{
	struct st_error err = {0};
	uint64_t n = 12345;

	ck_assert_msg(exact_count_self_intersections(CVERTS(m->verts), m->nverts, CTRIS(m->tris),
						     m->ntris, skip, threads, &n, &err) == 0,
		      "exact_count_self_intersections: %s", err.msg);
	return n;
}

/* ---- predicates ---- */

START_TEST(collinear_exact)
{
	/*
	 * p is 1/3 rounded down: 3p = 1 - 2^-54 exactly, which rounds to 1.0,
	 * so the cross product of (1,3,0) and (p,1,0) evaluated in doubles is
	 * 1*1 - fl(3p) = 0: naive arithmetic calls these collinear.  They are
	 * not; the z component is exactly 2^-54.
	 */
	const double p = 0x1.5555555555555p-2;
	const double o[3] = {0, 0, 0}, b[3] = {1, 3, 0}, c[3] = {p, 1, 0};
	/* Points t*(1,1,1): exactly collinear although 0.1 + 0.2 != 0.3. */
	const double d[3] = {0.1, 0.1, 0.1}, e[3] = {0.2, 0.2, 0.2}, f[3] = {0.3, 0.3, 0.3};
	const double g[3] = {0.1 * 7, 0.1 * 7, 0.1 * 7};
	/* One ulp off the line in one coordinate. */
	const double h[3] = {0.3, 0.3, 0x1.3333333333334p-2};

	ck_assert(!exact_collinear(o, b, c));
	ck_assert(exact_collinear(d, e, f));
	ck_assert(exact_collinear(d, f, g));
	ck_assert(!exact_collinear(d, e, h));
	ck_assert(exact_collinear(d, d, e)); /* coincident points */
	ck_assert(exact_collinear(d, d, d));
}
END_TEST

START_TEST(orient3d_exact)
{
	/*
	 * Plane through the z axis and (1,3,0), i.e. y = 3x.  det[b-a, c-a,
	 * d-a] for d = (p,1,0) expands to 1 - 3p = 2^-54 > 0 (naive: 0).
	 */
	const double p = 0x1.5555555555555p-2;
	const double a[3] = {0, 0, 0}, b[3] = {0, 0, 1}, c[3] = {1, 3, 0};
	const double d[3] = {p, 1, 0};
	const double on[3] = {1, 3, 5}, off[3] = {1, 0x1.8000000000001p+1, 5};
	/* 0.3 is not 3 * 0.1 in doubles: (0.1, 0.3) is just off y = 3x. */
	const double near[3] = {0.1, 0.3, 7};
	/* A plane far from the origin: z = 1e15 + x with unit steps. */
	const double big_a[3] = {0, 0, 1e15}, big_b[3] = {1, 0, 1e15 + 1};
	const double big_c[3] = {0, 1, 1e15}, big_on[3] = {3, 5, 1e15 + 3};
	const double big_up[3] = {3, 5, 1e15 + 3.125};

	ck_assert_int_eq(exact_orient3d(a, b, c, d), 1);
	ck_assert_int_eq(exact_orient3d(a, c, b, d), -1);
	ck_assert_int_eq(exact_orient3d(a, b, c, on), 0);
	ck_assert_int_eq(exact_orient3d(a, b, c, off), 1); /* y - 3x = 1 ulp */
	/* fl(0.1) * 3 = 0.3000000000000000166 > fl(0.3): below y = 3x, the
	 * side opposite to (p,1,0). */
	ck_assert_int_eq(exact_orient3d(a, b, c, near), -1);
	ck_assert_int_eq(exact_orient3d(big_a, big_b, big_c, big_on), 0);
	ck_assert_int_eq(exact_orient3d(big_a, big_b, big_c, big_up), 1);
}
END_TEST

START_TEST(predicates_non_finite)
{
	const double a[3] = {0, 0, 0}, b[3] = {1, 0, 0}, c[3] = {0, 1, 0};
	const double n[3] = {NAN, 0, 0}, i[3] = {0, INFINITY, 0};

	/* The degenerate answer, never a crash. */
	ck_assert(exact_collinear(a, b, n));
	ck_assert(exact_collinear(i, b, c));
	ck_assert_int_eq(exact_orient3d(a, b, c, n), 0);
	ck_assert_int_eq(exact_orient3d(i, a, b, c), 0);
}
END_TEST

/* ---- self-intersections of generated meshes ---- */

START_TEST(closed_meshes_are_clean)
{
	struct mesh *box = fx_box(0, 0, 0, 10, 10, 10);
	struct mesh *torus = fx_torus(10, 3, 60, 30);
	struct mesh *sphere = fx_sphere(1, 2, 3, 5, 24, 48);

	ck_assert_uint_eq(count_mesh(box, NULL, 1), 0);
	ck_assert_uint_eq(count_mesh(torus, NULL, 1), 0);
	ck_assert_uint_eq(count_mesh(torus, NULL, 2), 0);
	ck_assert_uint_eq(count_mesh(sphere, NULL, 1), 0);
	ck_assert_uint_eq(count_mesh(sphere, NULL, 0), 0);
	mesh_free(box);
	mesh_free(torus);
	mesh_free(sphere);
}
END_TEST

START_TEST(disjoint_cubes)
{
	struct mesh *a = fx_box(0, 0, 0, 1, 1, 1), *b = fx_box(3, 0, 0, 4, 1, 1);
	struct mesh *m = fx_concat(a, b);

	ck_assert_uint_eq(count_mesh(m, NULL, 1), 0);
	mesh_free(a);
	mesh_free(b);
	mesh_free(m);
}
END_TEST

/*
 * A = [0,10]^3 and B = [5,15]^3.  Only A's three upper faces (x, y or z =
 * 10) meet B's three lower faces (= 5), and only for different axes: six
 * face pairs, each meeting in a segment of length 5 (e.g. x = 10, y = 5,
 * z in [5,10]).  Every face of fx_box is split along the diagonal where its
 * two free coordinates are equal, for both boxes, so any permutation of the
 * axes maps the whole configuration onto itself and the six face pairs look
 * alike.  Take A's x = 10 face against B's y = 5 face, on the line x = 10,
 * y = 5: A's triangles cover z in [0,5] (z <= y) and [5,10] (z >= y); B's
 * cover z in [5,10] (z <= x) and [10,15] (z >= x).  Meeting: [5,10]x[5,10]
 * (a segment), [5,10]x[10,15] (the point z = 10), [0,5]x[5,10] (the point
 * z = 5); [0,5]x[10,15] is empty.  3 pairs per face pair, 18 in all.
 */
START_TEST(overlapping_cubes)
{
	struct mesh *a = fx_box(0, 0, 0, 10, 10, 10), *b = fx_box(5, 5, 5, 15, 15, 15);
	struct mesh *m = fx_concat(a, b);

	ck_assert_uint_eq(m->ntris, 24);
	ck_assert_uint_eq(count_mesh(m, NULL, 1), 18);
	ck_assert_uint_eq(count_mesh(m, NULL, 2), 18);
	mesh_free(a);
	mesh_free(b);
	mesh_free(m);
}
END_TEST

/*
 * Skip mask: fx_box emits the faces z0, z1, y0, y1, x0, x1 as triangle pairs
 * 0-1 ... 10-11, and fx_concat keeps the order (A = 0..11, B = 12..23).
 * Skipping A's x = 10 face (10, 11) removes its two face pairs with B's
 * y = 5 and z = 5 faces, 6 pairs: 12 remain.  Skipping all of B leaves 0.
 */
START_TEST(skip_mask_honoured)
{
	struct mesh *a = fx_box(0, 0, 0, 10, 10, 10), *b = fx_box(5, 5, 5, 15, 15, 15);
	struct mesh *m = fx_concat(a, b);
	uint8_t skip[24] = {0};

	skip[10] = skip[11] = 1;
	ck_assert_uint_eq(count_mesh(m, skip, 1), 12);
	ck_assert_uint_eq(count_mesh(m, skip, 2), 12);
	for (int i = 0; i < 24; i++)
		skip[i] = i >= 12;
	ck_assert_uint_eq(count_mesh(m, skip, 1), 0);
	mesh_free(a);
	mesh_free(b);
	mesh_free(m);
}
END_TEST

/*
 * Cubes welded along the edge x = y = 1.  The triangles on that edge share
 * it (two coplanar pairs in x = 1 and y = 1 lie on opposite sides of it);
 * the others touch B only at a shared corner.  Common faces only: 0.
 */
START_TEST(cubes_sharing_an_edge)
{
	struct mesh *a = fx_box(0, 0, 0, 1, 1, 1), *b = fx_box(1, 1, 0, 2, 2, 1);
	struct mesh *m = fx_concat(a, b);

	ck_assert_uint_eq(m->nverts, 14);
	ck_assert_uint_eq(count_mesh(m, NULL, 1), 0);
	mesh_free(a);
	mesh_free(b);
	mesh_free(m);
}
END_TEST

/*
 * A = [0,1]^3, B = [1,2] x [.25,.75]^2: B's x = 1 face lies inside A's, no
 * vertex shared.  A's x = 1 triangles cover z <= y and z >= y; B's x = 1
 * triangles z >= y and z <= y (same diagonal y = z): all 4 coplanar pairs
 * meet.  Each of B's four side faces has one triangle holding its whole
 * edge on x = 1 (it meets both A triangles: 4 x 2 = 8) and one touching
 * x = 1 at a single corner: (1,.25,.25) lies on A's diagonal and touches
 * both A triangles (y = .25 and z = .25 faces: 2 x 2), (1,.75,.25) and
 * (1,.25,.75) only one each (2 x 1).  4 + 8 + 4 + 2 = 18.
 */
START_TEST(cubes_face_contact)
{
	struct mesh *a = fx_box(0, 0, 0, 1, 1, 1), *b = fx_box(1, 0.25, 0.25, 2, 0.75, 0.75);
	struct mesh *m = fx_concat(a, b);

	ck_assert_uint_eq(m->nverts, 16);
	ck_assert_uint_eq(count_mesh(m, NULL, 1), 18);
	ck_assert_uint_eq(count_mesh(m, NULL, 2), 18);
	mesh_free(a);
	mesh_free(b);
	mesh_free(m);
}
END_TEST

START_TEST(duplicates_not_counted)
{
	struct mesh *m = fx_box(0, 0, 0, 1, 1, 1);

	fx_duplicate(m, 0, 0);
	fx_duplicate(m, 5, 1);
	/* Each copy shares all three vertices with its original; with its
	 * neighbours it shares what the original shares. */
	ck_assert_uint_eq(count_mesh(m, NULL, 1), 0);
	mesh_free(m);
}
END_TEST

START_TEST(threads_agree)
{
	struct mesh *a = fx_sphere(0, 0, 0, 1, 64, 128);
	struct mesh *b = fx_sphere(0.3, 0.2, 0.1, 1, 64, 128);
	struct mesh *m = fx_concat(a, b);
	uint64_t n1 = count_mesh(m, NULL, 1);

	/* 32k triangles: enough for the parallel path to split the work. */
	ck_assert_uint_gt(n1, 100);
	ck_assert_uint_eq(count_mesh(m, NULL, 2), n1);
	ck_assert_uint_eq(count_mesh(m, NULL, 0), n1);
	ck_assert_uint_eq(count_mesh(m, NULL, 64), n1);
	mesh_free(a);
	mesh_free(b);
	mesh_free(m);
}
END_TEST

/*
 * counts[0]: pairs of sphere with one triangle in the plane z of half
 * width 2w, small enough for the grid; counts[1]: the same triangle 100
 * times larger, which makes the grid decline (CGAL's box intersection).
 * Each on one core and on two, which must agree.
 */
static void count_cut_twice(const struct mesh *sphere, double z, double w, uint64_t counts[2])
{
	for (int i = 0; i < 2; i++) {
		const double s = i ? 100 * w : w;
		const double a[3] = {-2 * s, -s, z}, b[3] = {2 * s, -s, z}, c[3] = {0, 2 * s, z};
		struct mesh *cut = fx_triangle(a, b, c);
		struct mesh *m = fx_concat(sphere, cut);

		counts[i] = count_mesh(m, NULL, 1);
		ck_assert_uint_eq(count_mesh(m, NULL, 2), counts[i]);
		mesh_free(cut);
		mesh_free(m);
	}
}

/*
 * A sphere cut by one triangle in a plane: with a triangle of 40 mm the
 * candidate pairs come from the grid (gridpairs.hpp); one of 4 m would
 * put it in millions of grid cells, so the grid declines and CGAL's box
 * intersection finds them.  Both cross the same sphere triangles.
 */
START_TEST(grid_and_boxes_agree)
{
	struct mesh *sphere = fx_sphere(0, 0, 0, 5, 32, 64);
	uint64_t counts[2];

	count_cut_twice(sphere, 0.123, 10, counts);
	/* The 64 quads (128 triangles) of the band the plane goes through. */
	ck_assert_uint_eq(counts[0], 128);
	ck_assert_uint_eq(counts[1], counts[0]);
	mesh_free(sphere);
}
END_TEST

/*
 * Triangles the count leaves out (a degenerate one, one the caller skips)
 * come before the sphere and the cut, so every later triangle's box sits
 * at another place than its triangle's index: the pairs found must still
 * be those of the right triangles, from the grid (cut of 20 mm) and from
 * CGAL's box intersection (2 m) alike.
 */
START_TEST(left_out_triangles_shift_nothing)
{
	struct mesh *sphere = fx_sphere(0, 0, 0, 5, 32, 64);
	const double d[3] = {1, 1, 1}, e[3] = {2, 2, 2}, f[3] = {3, 3, 3};
	struct mesh *flat = fx_triangle(d, e, f);

	for (int i = 0; i < 2; i++) {
		const double s = i ? 1000 : 10;
		const double a[3] = {-2 * s, -s, 0.123}, b[3] = {2 * s, -s, 0.123};
		const double c[3] = {0, 2 * s, 0.123};
		struct mesh *cut = fx_triangle(a, b, c);
		struct mesh *lead = fx_concat(flat, cut); /* 1: a copy of cut, skipped */
		struct mesh *body = fx_concat(lead, sphere);
		struct mesh *m = fx_concat(body, cut);
		uint8_t *skip = calloc(m->ntris, 1);

		ck_assert_ptr_nonnull(skip);
		skip[1] = 1;
		/* The 128 triangles of the band the plane goes through. */
		for (int threads = 1; threads <= 2; threads++)
			ck_assert_uint_eq(count_mesh(m, skip, threads), 128);
		free(skip);
		mesh_free(m);
		mesh_free(body);
		mesh_free(lead);
		mesh_free(cut);
	}
	mesh_free(flat);
	mesh_free(sphere);
}
END_TEST

/*
 * The poles of a UV sphere put hundreds of slivers in a few grid cells,
 * which the grid sweeps along x instead of comparing all against all
 * (gridpairs.hpp).  A plane just below the north pole, between the first
 * and second rings, crosses the 256 quads (512 triangles) of that band:
 * the same count from the grid as from CGAL's box intersection (the cut
 * 100 times larger makes the grid decline).
 */
START_TEST(crowded_pole_swept)
{
	struct mesh *sphere = fx_sphere(0, 0, 0, 5, 64, 256);
	const double z = 5 * cos(M_PI * 1.5 / 64);
	uint64_t counts[2];

	count_cut_twice(sphere, z, 1, counts);
	ck_assert_uint_eq(counts[0], 512);
	ck_assert_uint_eq(counts[1], counts[0]);
	mesh_free(sphere);
}
END_TEST

/*
 * 200 flat triangles stacked 0.001 apart all fall in one grid cell, so
 * comparing all their pairs there is too much for the grid: it declines
 * after sorting the boxes, and CGAL's box intersection must still see
 * every box where it was.  One upright triangle crosses each of them.
 */
START_TEST(crowded_cell_falls_back)
{
	enum { LAYERS = 200 };
	double (*v)[3] = calloc(3 * (LAYERS + 1), sizeof(*v));
	uint32_t (*t)[3] = calloc(LAYERS + 1, sizeof(*t));
	struct st_error err = {0};
	uint64_t n = 12345;

	ck_assert_ptr_nonnull(v);
	ck_assert_ptr_nonnull(t);
	for (int i = 0; i <= LAYERS; i++)
		for (int k = 0; k < 3; k++)
			t[i][k] = (uint32_t)(3 * i + k);
	for (int i = 0; i < LAYERS; i++) {
		const double z = 0.001 * i;
		const double c[3][3] = {{0, 0, z}, {1, 0, z}, {0, 1, z}};
		memcpy(v[3 * i], c, sizeof(c));
	}
	/* Upright in x = 0.25 from z = -1 to 2, through every layer. */
	const double up[3][3] = {{0.25, 0.1, -1}, {0.25, 0.2, -1}, {0.25, 0.15, 2}};
	memcpy(v[3 * LAYERS], up, sizeof(up));
	for (int threads = 1; threads <= 2; threads++) {
		ck_assert_int_eq(exact_count_self_intersections(CVERTS(v), 3 * (LAYERS + 1),
								 CTRIS(t), LAYERS + 1, NULL,
								 threads, &n, &err),
				 0);
		ck_assert_uint_eq(n, LAYERS);
	}
	free(v);
	free(t);
}
END_TEST

/*
 * Scaling by a power of two is exact, so no predicate changes: the count of
 * two overlapping spheres must not change when they are moved beyond float
 * range (the boxes are clamped there and still go through the tree).
 */
START_TEST(huge_coordinates)
{
	struct mesh *a = fx_sphere(0, 0, 0, 1, 16, 32);
	struct mesh *b = fx_sphere(0.3, 0.2, 0.1, 1, 16, 32);
	struct mesh *m = fx_concat(a, b);
	uint64_t n = count_mesh(m, NULL, 1);

	ck_assert_uint_gt(n, 10);
	for (size_t i = 0; i < m->nverts; i++)
		for (int k = 0; k < 3; k++)
			m->verts[i][k] = ldexp(m->verts[i][k], 130);
	ck_assert_uint_eq(count_mesh(m, NULL, 1), n);
	mesh_free(a);
	mesh_free(b);
	mesh_free(m);
}
END_TEST

/*
 * Snap rounding of a tetrahedron plus an unused vertex: on the float grid
 * already, nothing moves and the result holds the used vertices in order of
 * first use; one corner off the grid goes to its nearest float.
 */
START_TEST(snap_round_on_grid_and_off)
{
	double v[5][3] = {{9, 9, 9}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
	const uint32_t t[4][3] = {{4, 2, 3}, {1, 3, 2}, {1, 2, 4}, {1, 4, 3}};
	const uint32_t origin[4] = {7, 8, 9, 10};
	const uint32_t want_tris[4][3] = {{0, 1, 2}, {3, 2, 1}, {3, 1, 0}, {3, 0, 2}};
	const uint32_t order[4] = {4, 2, 3, 1};

	for (int off = 0; off < 2; off++) {
		struct st_error err = {0};
		struct exact_mesh *m = NULL, *r = NULL;
		struct exact_snap_stats st;

		v[4][2] = off ? 0.1 : 1;
		ck_assert_int_eq(exact_mesh_new(CVERTS(v), 5, t, 4, origin, &m, &err), 0);
		ck_assert_int_eq(exact_mesh_snap_round(m, 24, 1e-3, 1, &r, &st, &err), 0);
		ck_assert_uint_eq(exact_mesh_nverts(r), 4);
		ck_assert_uint_eq(exact_mesh_ntris(r), 4);
		ck_assert_uint_eq(st.rounded, (size_t)off);
		ck_assert_uint_eq(st.other_corner + st.collapsed + st.unplaced, 0);
		ck_assert(off ? st.max_move > 0 && st.max_move < 1e-8 : st.max_move == 0);
		for (size_t i = 0; i < 4; i++) {
			ck_assert_uint_eq(exact_mesh_origin(r)[i], origin[i]);
			for (int k = 0; k < 3; k++) {
				ck_assert_uint_eq(exact_mesh_tris(r)[i][k], want_tris[i][k]);
				ck_assert(exact_mesh_verts(r)[i][k] ==
					  (double)(float)v[order[i]][k]);
			}
		}
		exact_mesh_free(r);
		exact_mesh_free(m);
	}
}
END_TEST

Suite *exact_suite(void)
{
	Suite *s = suite_create("exact");
	TCase *pred = tcase_create("predicates"), *mesh = tcase_create("meshes");

	tcase_add_test(pred, collinear_exact);
	tcase_add_test(pred, orient3d_exact);
	tcase_add_test(pred, predicates_non_finite);
	suite_add_tcase(s, pred);
	tcase_add_test(mesh, closed_meshes_are_clean);
	tcase_add_test(mesh, disjoint_cubes);
	tcase_add_test(mesh, overlapping_cubes);
	tcase_add_test(mesh, skip_mask_honoured);
	tcase_add_test(mesh, cubes_sharing_an_edge);
	tcase_add_test(mesh, cubes_face_contact);
	tcase_add_test(mesh, duplicates_not_counted);
	tcase_add_test(mesh, threads_agree);
	tcase_add_test(mesh, grid_and_boxes_agree);
	tcase_add_test(mesh, crowded_cell_falls_back);
	tcase_add_test(mesh, crowded_pole_swept);
	tcase_add_test(mesh, left_out_triangles_shift_nothing);
	tcase_add_test(mesh, huge_coordinates);
	tcase_add_test(mesh, snap_round_on_grid_and_off);
	tcase_set_timeout(mesh, 30);
	suite_add_tcase(s, mesh);
	exact_pairs_tcases(s);
	exact_patches_tcases(s);
	return s;
}
