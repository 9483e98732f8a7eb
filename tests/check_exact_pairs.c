/*
 * check_exact_pairs.c - the CGAL bridge, part of the exact suite
 * (check_exact.c): the self-intersection count on hand-placed triangle
 * pairs and fans whose expected counts are derived in the comments (seed 000
 * Definition 3.6), cut points exact at any scale, and bad arguments.
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

void exact_pairs_tcases(Suite *s)
{
	TCase *pairs = tcase_create("pairs"), *args = tcase_create("arguments");

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
}
