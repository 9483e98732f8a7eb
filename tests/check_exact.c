/*
 * check_exact.c - the CGAL bridge: exact predicates on inputs where plain
 * double arithmetic decides wrongly, and the self-intersection count on
 * generated meshes and hand-placed triangle pairs whose expected counts are
 * derived in the comments (seed 000 Definition 3.6).
 */
#include <check.h>
#include <float.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "exact.h"
#include "fixtures.h"
#include "mesh.h"
#include "suites.h"

/*
 * ISO C before C23 does not convert double (*)[3] to const double (*)[3]
 * implicitly, so callers with writable tables cast.
 */
#define CVERTS(v) ((const double(*)[3])(v))
#define CTRIS(t) ((const uint32_t(*)[3])(t))

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

/* Count for two triangles (indices t into v), on one thread and on two. */
static uint64_t count_two(double (*v)[3], size_t nv, const uint32_t (*t)[3])
{
	struct st_error err = {0};
	uint64_t n1 = 12345, n2 = 12345;

	ck_assert_int_eq(exact_count_self_intersections(CVERTS(v), nv, t, 2, NULL, 1, &n1, &err),
			 0);
	ck_assert_int_eq(exact_count_self_intersections(CVERTS(v), nv, t, 2, NULL, 2, &n2, &err),
			 0);
	ck_assert_uint_eq(n1, n2);
	return n1;
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

/* ---- hand-placed pairs ---- */

START_TEST(shared_edge_pairs)
{
	/* Edge (0,1) shared; corner 2 of the first, corner 3 of the second. */
	double v[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.5, 0.5, 0}};
	const uint32_t t[2][3] = {{0, 1, 2}, {1, 0, 3}};

	/* Folded onto each other in z = 0. */
	ck_assert_uint_eq(count_two(v, 4, t), 1);
	/* Coplanar, opposite sides of the edge. */
	v[3][1] = -1;
	ck_assert_uint_eq(count_two(v, 4, t), 0);
	/* Out of the plane. */
	v[3][1] = 0.5;
	v[3][2] = 1e-300;
	ck_assert_uint_eq(count_two(v, 4, t), 0);
	/* Same side, a sliver hugging the edge line. */
	v[3][0] = 2;
	v[3][1] = 1e-300;
	v[3][2] = 0;
	ck_assert_uint_eq(count_two(v, 4, t), 1);
}
END_TEST

START_TEST(shared_vertex_pairs)
{
	/* Corner 0 shared: (v,a,b) = 0,1,2 and (v,c,d) = 0,3,4. */
	double v[5][3] = {{0, 0, 0}, {2, 0, -1}, {2, 0, 1}, {2, -1, 0}, {2, 1, 0}};
	const uint32_t t[2][3] = {{0, 1, 2}, {0, 3, 4}};

	/* Planes y = 0 and z = 0 crossing along [0,2] on the x axis. */
	ck_assert_uint_eq(count_two(v, 5, t), 1);
	/* Second one above z = 0 except at v: touch at v only. */
	v[3][2] = v[4][2] = 1;
	v[1][2] = -1;
	v[2][2] = -1e-300;
	v[2][1] = 1;
	ck_assert_uint_eq(count_two(v, 5, t), 0);
}
END_TEST

START_TEST(shared_vertex_coplanar)
{
	/* Both in z = 0 with corner (0,0,0) shared. */
	double v[5][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}};
	const uint32_t t[2][3] = {{0, 1, 2}, {0, 3, 4}};

	/* Opposite quadrants. */
	ck_assert_uint_eq(count_two(v, 5, t), 0);
	/* Edges along the same ray (second in the first's corner). */
	v[3][0] = 2;
	ck_assert_uint_eq(count_two(v, 5, t), 1);
	/* Adjacent quadrants, touching along nothing but v... */
	v[3][0] = -1;
	v[4][0] = 0;
	v[4][1] = 1;
	v[2][0] = 1;
	v[2][1] = 1;
	ck_assert_uint_eq(count_two(v, 5, t), 0);
	/* ...d just past the first's edge vb: a sliver of overlap... */
	v[4][0] = 1;
	v[4][1] = 1 - 0x1p-30;
	ck_assert_uint_eq(count_two(v, 5, t), 1);
	/* ...or just short of it: v only. */
	v[4][1] = 1 + 0x1p-30;
	ck_assert_uint_eq(count_two(v, 5, t), 0);
}
END_TEST

START_TEST(shared_vertex_corner)
{
	/*
	 * Second triangle (v,c,d) in z = 0; the first stands up from v with its
	 * edge va lying in z = 0 and pointing into the second's corner.
	 */
	double v[5][3] = {{0, 0, 0}, {0.5, 0.5, 0}, {0, 0, 1}, {2, 0, 0}, {0, 2, 0}};
	const uint32_t t[2][3] = {{0, 1, 2}, {0, 3, 4}};

	ck_assert_uint_eq(count_two(v, 5, t), 1); /* a inside */
	v[1][0] = v[1][1] = 3;
	ck_assert_uint_eq(count_two(v, 5, t), 1); /* a beyond cd */
	v[1][0] = 1;
	v[1][1] = 0;
	ck_assert_uint_eq(count_two(v, 5, t), 1); /* va along vc */
	v[1][0] = -1;
	v[1][1] = 1;
	ck_assert_uint_eq(count_two(v, 5, t), 0); /* outside the corner */
	v[1][0] = 1;
	v[1][1] = -1e-300;
	ck_assert_uint_eq(count_two(v, 5, t), 0); /* just outside */
}
END_TEST

/*
 * A fan of n triangles around an apex above the unit circle, ring vertex i
 * at angle i * step (radians); closed joins the last to the first.  Every
 * triangle turns counterclockwise, so only going around more than once
 * makes them cross: what the vertex stars must notice (stars.hpp).
 */
static uint64_t count_fan(int n, double step, bool closed, int threads)
{
	double v[16][3] = {{0, 0, 1}};
	uint32_t t[16][3];
	const int ntris = closed ? n : n - 1;
	struct st_error err = {0};
	uint64_t count = 12345;

	ck_assert_int_lt(n, 16);
	for (int i = 0; i < n; i++) {
		v[1 + i][0] = cos(i * step);
		v[1 + i][1] = sin(i * step);
		v[1 + i][2] = 0;
	}
	for (int i = 0; i < ntris; i++) {
		t[i][0] = 0;
		t[i][1] = (uint32_t)(1 + i);
		t[i][2] = (uint32_t)(1 + (i + 1) % n);
	}
	ck_assert_int_eq(exact_count_self_intersections(CVERTS(v), (size_t)n + 1, CTRIS(t),
							 (size_t)ntris, NULL, threads, &count, &err),
			 0);
	/* The same count from stars the caller built, as the topology
	 * report passes them: the pairs sharing the apex are decided there. */
	uint32_t off[18] = {0}, star[48], fill[17];
	uint8_t skip[16] = {0};
	uint64_t given = 12345;
	for (int i = 0; i < ntris; i++)
		for (int k = 0; k < 3; k++)
			off[t[i][k] + 1]++;
	for (int x = 0; x <= n; x++) {
		off[x + 1] += off[x];
		fill[x] = off[x];
	}
	for (int i = 0; i < ntris; i++)
		for (int k = 0; k < 3; k++)
			star[fill[t[i][k]]++] = (uint32_t)i;
	ck_assert_int_eq(exact_count_self_intersections_stars(CVERTS(v), (size_t)n + 1, CTRIS(t),
							       (size_t)ntris, skip, off, star,
							       threads, &given, &err),
			 0);
	ck_assert_uint_eq(given, count);
	return count;
}

START_TEST(fans_winding_more_than_once)
{
	for (int threads = 1; threads <= 2; threads++) {
		/* Once around (a cone): nothing. */
		ck_assert_uint_eq(count_fan(7, 2 * M_PI / 7, true, threads), 0);
		ck_assert_uint_eq(count_fan(6, 2 * M_PI / 7, false, threads), 0);
		/* Twice around, a {7/2} star: each chord crosses two others. */
		ck_assert_uint_eq(count_fan(7, 4 * M_PI / 7, true, threads), 7);
		/* One and a half turns, open: 108 degree steps, three crossings. */
		ck_assert_uint_eq(count_fan(6, 108 * M_PI / 180, false, threads), 3);
	}
}
END_TEST

START_TEST(vertex_on_interior)
{
	/* No shared index; the second touches the first's inside with a corner. */
	double v[6][3] = {{0, 0, 0.1},	   {2, 0, 0.1},	  {0, 2, 0.1},
			  {0.5, 0.5, 0.1}, {0.5, 0.5, 1}, {1, 0.5, 1}};
	const uint32_t t[2][3] = {{0, 1, 2}, {3, 4, 5}};

	ck_assert_uint_eq(count_two(v, 6, t), 1);
	/* One ulp above the plane: apart. */
	v[3][2] = nextafter(0.1, 1);
	ck_assert_uint_eq(count_two(v, 6, t), 0);
	/* Beyond float range the boxes are clamped; the test stays exact. */
	for (int i = 0; i < 3; i++)
		v[i][2] = 1e39;
	v[3][2] = 2e39;
	v[4][2] = v[5][2] = 3e39;
	ck_assert_uint_eq(count_two(v, 6, t), 0);
	v[3][2] = 1e39;
	ck_assert_uint_eq(count_two(v, 6, t), 1);
	v[3][2] = nextafter(1e39, INFINITY);
	ck_assert_uint_eq(count_two(v, 6, t), 0);
}
END_TEST

START_TEST(degenerate_triangles_ignored)
{
	/* A flat (collinear) triangle through a good one, and an irregular
	 * one: neither is looked at, and nothing aborts. */
	double v[7][3] = {{0, 0, 0},	 {2, 0, 0},	{0, 2, 0}, {0.5, 0.5, -1},
			  {0.5, 0.5, 0}, {0.5, 0.5, 1}, {1, 1, 1}};
	const uint32_t t[3][3] = {{0, 1, 2}, {3, 4, 5}, {6, 6, 4}};
	struct st_error err = {0};
	uint64_t n = 1;

	ck_assert_int_eq(exact_count_self_intersections(CVERTS(v), 7, t, 3, NULL, 1, &n, &err), 0);
	ck_assert_uint_eq(n, 0);
	ck_assert(exact_collinear(v[3], v[4], v[5]));
}
END_TEST

/* ---- argument checks ---- */

START_TEST(bad_arguments)
{
	double v[3][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
	uint32_t t[1][3] = {{0, 1, 3}};
	struct st_error err = {0};
	uint64_t n = 7;

	ck_assert_int_eq(
	    exact_count_self_intersections(CVERTS(v), 3, CTRIS(t), 1, NULL, 1, &n, &err),
	    ST_ERR_ARG);
	ck_assert_int_eq(err.code, ST_ERR_ARG);
	ck_assert_uint_eq(n, 0);
	ck_assert_ptr_nonnull(strstr(err.msg, "triangle 0"));
	t[0][2] = 2;
	ck_assert_int_eq(exact_count_self_intersections(NULL, 3, CTRIS(t), 1, NULL, 1, &n, &err),
			 ST_ERR_ARG);
	ck_assert_int_eq(exact_count_self_intersections(CVERTS(v), 3, NULL, 1, NULL, 1, &n, &err),
			 ST_ERR_ARG);
	ck_assert_int_eq(
	    exact_count_self_intersections(CVERTS(v), 3, CTRIS(t), 1, NULL, 1, NULL, &err),
	    ST_ERR_ARG);
	ck_assert_int_eq(
	    exact_count_self_intersections(CVERTS(v), 3, CTRIS(t), 1, NULL, -1, &n, &err),
	    ST_ERR_ARG);
	v[1][0] = NAN;
	ck_assert_int_eq(
	    exact_count_self_intersections(CVERTS(v), 3, CTRIS(t), 1, NULL, 1, &n, &err),
	    ST_ERR_ARG);
	/* A skipped triangle is not looked at, NaN or not. */
	ck_assert_int_eq(exact_count_self_intersections(CVERTS(v), 3, CTRIS(t), 1,
							(const uint8_t *)"\1", 1, &n, &err),
			 0);
	/* Nothing to count: fine with no arrays at all, and err untouched. */
	err.code = 0;
	n = 7;
	ck_assert_int_eq(exact_count_self_intersections(NULL, 0, NULL, 0, NULL, 2, &n, NULL), 0);
	ck_assert_uint_eq(n, 0);
	ck_assert_int_eq(err.code, 0);
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

/*
 * The points where one triangle's edges cross another's plane are exact
 * at any scale: the integer construction of double corners
 * (repair/exact/cutpair.hpp) factors out the smallest exponent, which is
 * far below 1 for tiny models and above 1 for huge ones.  Triangle w
 * stands in the plane y = s and crosses u (in z = s / 2) along the
 * segment from (1, 1, 1/2) s to (23/7, 1, 1/2) s; 23/7 is no double.
 */
START_TEST(cut_points_exact_at_any_scale)
{
	const double scale[] = {0x1p-70, 1.0 / 3.0, 1, 0x1p+60};
	const double s = scale[_i];
	const double v[6][3] = {{0, 0, s / 2}, {8 * s, 0, s / 2}, {0, 8 * s, s / 2},
				{s, s, -s},    {5 * s, s, -s},	  {s, s, 2.5 * s}};
	const uint32_t t[2][3] = {{0, 1, 2}, {3, 4, 5}};
	const uint32_t origin[2] = {0, 1};
	const double want[2][3] = {{s, s, s / 2}, {23.0 / 7.0 * s, s, s / 2}};
	struct st_error err = {0};
	struct exact_mesh *m = NULL;
	struct exact_refine_stats st;

	ck_assert_int_eq(exact_mesh_new(CVERTS(v), 6, t, 2, origin, &m, &err), 0);
	ck_assert_int_eq(exact_mesh_refine(m, 1, &st, &err), 0);
	ck_assert_uint_eq(st.intersecting_pairs, 1);
	ck_assert_uint_eq(st.triangles_split, 2);
	for (int w = 0; w < 2; w++) {
		bool found = false;
		for (size_t i = 0; i < exact_mesh_nverts(m); i++) {
			const double *p = exact_mesh_verts(m)[i];
			bool near = true;
			for (int k = 0; k < 3; k++)
				near = near && fabs(p[k] - want[w][k]) <= 2 * DBL_EPSILON * fabs(want[w][k]);
			found = found || near;
		}
		ck_assert_msg(found, "scale %g: cut point %d missing", s, w);
	}
	/* The first point is a double, and must be found as one exactly. */
	bool exact_double = false;
	for (size_t i = 0; i < exact_mesh_nverts(m); i++)
		exact_double = exact_double || (memcmp(exact_mesh_verts(m)[i], want[0],
						       sizeof(want[0])) == 0);
	ck_assert(exact_double);
	/* And the mesh is now free of crossings. */
	uint64_t n = 1;
	ck_assert_int_eq(exact_count_self_intersections(exact_mesh_verts(m), exact_mesh_nverts(m),
							exact_mesh_tris(m), exact_mesh_ntris(m),
							NULL, 1, &n, &err),
			 0);
	ck_assert_uint_eq(n, 0);
	exact_mesh_free(m);
}
END_TEST

Suite *exact_suite(void)
{
	Suite *s = suite_create("exact");
	TCase *pred = tcase_create("predicates"), *mesh = tcase_create("meshes");
	TCase *pairs = tcase_create("pairs"), *args = tcase_create("arguments");

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
	tcase_add_test(pairs, shared_edge_pairs);
	tcase_add_test(pairs, shared_vertex_pairs);
	tcase_add_test(pairs, shared_vertex_coplanar);
	tcase_add_test(pairs, shared_vertex_corner);
	tcase_add_test(pairs, vertex_on_interior);
	tcase_add_loop_test(pairs, cut_points_exact_at_any_scale, 0, 4);
	tcase_add_test(pairs, fans_winding_more_than_once);
	tcase_add_test(pairs, degenerate_triangles_ignored);
	suite_add_tcase(s, pairs);
	tcase_add_test(args, bad_arguments);
	suite_add_tcase(s, args);
	exact_patches_tcases(s);
	return s;
}
