/*
 * check_refine.c - seed 003's vertex translation against a finer mesh
 * (repair/refine.h) and `stratum refine`.
 *
 * A 16-sided cylinder of radius r against a 256-sided one: a side facet's
 * chordal error is the sagitta r (1 - cos(pi / 16)) = 0.19 mm; reaching
 * 0.02 mm takes chords of at most 2 acos(1 - 0.02 / r) = 0.13 rad, so 64
 * sides (2 halvings, 0.012 mm; 32 sides leave 0.048 mm).  Uniform
 * subdivision halves every edge, the caps' and the height's too:
 * 60 * 4^2 = 960 triangles.  The refinement only needs the sides cut around, so it must
 * come out smaller; its new rim vertices must stay on the rim (the crease
 * where cap and side meet), or the rim is cut short and the error stalls.
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fixtures.h"
#include "meshio.h"
#include "refine.h"
#include "suites.h"
#include "testutil.h"

#define R 10.0	       /* mm, the cylinders' radius */
#define H 20.0	       /* mm, their height */
#define TOL 0.02       /* mm (0.01 takes 3 times as long) */
#define SAMPLES 2000   /* per measurement: each facet still gets its grid */

static struct refine_options options(void)
{
	struct refine_options o;

	refine_options_init(&o);
	o.tolerance = TOL;
	o.samples = SAMPLES;
	return o;
}

START_TEST(cylinder_reaches_tolerance_with_fewer_triangles_than_uniform)
{
	struct mesh *coarse = fx_cylinder(0, 0, R, H, 16), *fine = fx_cylinder(0, 0, R, H, 256);
	struct mesh *out = NULL, *uout = NULL;
	struct refine_options o = options();
	struct refine_report r, u;
	struct mesh_report check;
	struct st_error err;

	ck_assert_int_eq(refine_mesh(coarse, fine, &o, &out, &r, &err), 0);
	ck_assert_msg(r.reached && r.error_after <= TOL, "largest %g mm, %zu facets over",
		      r.error_after, r.facets_over);
	ck_assert(fabs(r.error_before - R * (1 - cos(M_PI / 16))) < 1e-3);
	ck_assert_uint_gt(r.on_creases, 0); /* the rim's new vertices */
	ck_assert_uint_eq(r.triangles_after, out->ntris);
	o.uniform = true;
	ck_assert_int_eq(refine_mesh(coarse, fine, &o, &uout, &u, &err), 0);
	ck_assert(u.reached);
	ck_assert_uint_eq(u.triangles_after, 60 * 16);
	ck_assert_msg(r.triangles_after < u.triangles_after, "refined %zu, uniform %zu",
		      r.triangles_after, u.triangles_after);
	ck_assert_int_eq(mesh_analyze(out, 0, &check, &err), 0);
	ck_assert(check.printable && check.boundary_edges == 0 && !check.self_intersections);
	refine_report_free(&r);
	refine_report_free(&u);
	mesh_free(out);
	mesh_free(uout);
	mesh_free(coarse);
	mesh_free(fine);
}
END_TEST

/*
 * A torus of 12 x 6 quads (R 30, r 10 mm; a facet up to 2.5 mm off)
 * against one of 48 x 24: a surface curved both ways, where a vertex must
 * move far beside thin triangles.  Splitting the edge that carries a
 * facet's error leaves long slivers across the tube, whose new vertices
 * flip their neighbours when moved, are refused, and the error stalls
 * (issue 21: a torus of 12 x 6 stopped at 0.92 mm with 539 moves
 * refused); it must reach the tolerance, printable.
 */
START_TEST(coarse_torus_reaches_tolerance)
{
	struct mesh *coarse = fx_torus(30, 10, 12, 6), *fine = fx_torus(30, 10, 48, 24);
	struct mesh *out = NULL;
	struct refine_options o = options();
	struct refine_report r;
	struct mesh_report check;
	struct st_error err;

	o.tolerance = 0.1;
	ck_assert_int_eq(refine_mesh(coarse, fine, &o, &out, &r, &err), 0);
	ck_assert_msg(r.reached, "largest %g mm, %zu facets over, %zu refused after %zu rounds",
		      r.error_after, r.facets_over, r.refused, r.rounds);
	ck_assert_int_eq(mesh_analyze(out, 0, &check, &err), 0);
	ck_assert(check.printable && check.boundary_edges == 0 && !check.self_intersections);
	refine_report_free(&r);
	mesh_free(out);
	mesh_free(coarse);
	mesh_free(fine);
}
END_TEST

/* A coarse cylinder 0.2 mm too wide: its corners lie off the reference,
 * which new vertices cannot mend; --move-vertices moves them too. */
START_TEST(corners_off_the_reference_need_move_vertices)
{
	struct mesh *coarse = fx_cylinder(0, 0, R + 0.2, H, 16), *fine = fx_cylinder(0, 0, R, H, 256);
	struct mesh *out = NULL;
	struct refine_options o = options();
	struct refine_report r;
	struct st_error err;

	o.tolerance = 0.05;
	ck_assert_int_eq(refine_mesh(coarse, fine, &o, &out, &r, &err), 0);
	ck_assert(!r.reached && r.rounds == 0);
	ck_assert(fabs(r.vertex_error - 0.2) < 1e-3);
	refine_report_free(&r);
	mesh_free(out);
	o.move_vertices = true;
	ck_assert_int_eq(refine_mesh(coarse, fine, &o, &out, &r, &err), 0);
	ck_assert_msg(r.reached, "largest %g mm", r.error_after);
	ck_assert_uint_eq(r.vertices_moved, 32);
	ck_assert(r.vertex_error < 1e-5);
	refine_report_free(&r);
	mesh_free(out);
	mesh_free(coarse);
	mesh_free(fine);
}
END_TEST

/* A plate from x0 to 10 mm, 10 mm wide and 0.2 mm thick, its top an
 * upside-down pyramid dipping to z = -0.5 mm under the middle, with or
 * without its bottom (a surface, not a solid: the dip pierces the bottom). */
static struct mesh *dipped_plate(double x0, bool bottom)
{
	const double p[9][3] = {{x0, 0, 0},   {10, 0, 0},   {10, 10, 0},   {x0, 10, 0},
				{x0, 0, 0.2}, {10, 0, 0.2}, {10, 10, 0.2}, {x0, 10, 0.2},
				{5, 5, -0.5}};
	const uint32_t t[14][3] = {{0, 2, 1}, {0, 3, 2}, {0, 1, 5}, {0, 5, 4}, {1, 2, 6},
				   {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7},
				   {4, 5, 8}, {5, 6, 8}, {6, 7, 8}, {7, 4, 8}};
	struct mesh_builder *b = mesh_builder_new(14);
	uint32_t v[9];
	struct st_error err;

	for (int i = 0; i < 9; i++)
		ck_assert_int_eq(mesh_builder_vertex(b, p[i], &v[i], &err), 0);
	for (int i = bottom ? 0 : 2; i < 14; i++)
		ck_assert_int_eq(mesh_builder_triangle(b, v[t[i][0]], v[t[i][1]], v[t[i][2]], &err),
				 0);
	return mesh_builder_finish(b);
}

/* The plate of dipped_plate refined against it, at most max_triangles. */
static void refine_plate(double x0, bool bottom, size_t max_triangles, struct mesh **out,
			 struct refine_report *r)
{
	struct mesh *plate = fx_box(x0, 0, 0, 10, 10, 0.2), *dipped = dipped_plate(x0, bottom);
	struct refine_options o = options();
	struct mesh_report check;
	struct st_error err;

	o.tolerance = 0.05;
	o.max_triangles = max_triangles;
	ck_assert_int_eq(refine_mesh(plate, dipped, &o, out, r, &err), 0);
	ck_assert(r->vertex_error < 1e-6); /* 0.2 as float32 */
	ck_assert(!r->reached);
	ck_assert_int_eq(mesh_analyze(*out, 0, &check, &err), 0);
	ck_assert(check.printable && !check.self_intersections);
	for (size_t v = 0; v < (*out)->nverts; v++) /* nothing went under the bottom */
		ck_assert((*out)->verts[v][2] >= 0 && (*out)->verts[v][2] <= (float)0.2);
	mesh_free(plate);
	mesh_free(dipped);
}

/* Against the dipped top without a bottom, the top's first new vertex, on
 * its diagonal, goes straight down onto the dip, through the plate's
 * bottom: its triangles would cross the bottom's (exact test), so the move
 * is refused and the plate stays whole and printable, short of the
 * tolerance.  (The rounds stop when every facet over the tolerance has a
 * corner short of its place.) */
START_TEST(moves_that_would_cross_are_refused)
{
	struct mesh *out = NULL;
	struct refine_report r;

	refine_plate(0, false, 1000, &out, &r);
	ck_assert_uint_gt(r.refused, 0);
	refine_report_free(&r);
	mesh_free(out);
}
END_TEST

/* With its bottom, the reference under the top's middle is the bottom,
 * facing away: the new vertices there stay on their edges, which is no
 * refused move.  The plate starts at x = 0.1 mm, so their edges' midpoints
 * are off the float32 grid and a vertex is put back to its midpoint rounded
 * as stored (a build whose compiler dropped that rounding counted such
 * vertices as refused).  Bounded at 100 triangles: unbounded, the rounds
 * go on shrinking the facets beside the dip for a minute. */
START_TEST(vertices_left_on_their_edges_are_not_refused)
{
	struct mesh *out = NULL;
	struct refine_report r;

	refine_plate(0.1, true, 100, &out, &r);
	ck_assert_uint_gt(r.vertices_added, 0);
	ck_assert_uint_eq(r.refused, 0);
	refine_report_free(&r);
	mesh_free(out);
}
END_TEST

/*
 * A box 10 x 10 x 2 mm whose top folds up into a ridge along y: ridge_h
 * high on a base ridge_w either side of x = 5, so its two long facets
 * stand at 79 degrees to the box's top, within ridge_h of it.
 */
#define RIDGE_H 0.15
#define RIDGE_W 0.03

static struct mesh *ridged_box(void)
{
	const double x[7][2] = {{0, 0}, {10, 0}, {10, 2}, {5 + RIDGE_W, 2}, {5, 2 + RIDGE_H},
				{5 - RIDGE_W, 2}, {0, 2}}; /* A..G: the front's (x, z) */
	/* A B C D E F G at y = 0 are 0..6, at y = 10 are 7..13 */
	const uint32_t t[24][3] = {
	    {0, 1, 2},	 {0, 2, 3},    {0, 3, 5},    {3, 4, 5},	  {0, 5, 6},	 /* front */
	    {7, 9, 8},	 {7, 10, 9},   {7, 12, 10},  {10, 12, 11}, {7, 13, 12},	 /* back */
	    {6, 5, 12},	 {6, 12, 13},  {5, 4, 11},   {5, 11, 12},  {4, 3, 10},	 /* top */
	    {4, 10, 11}, {3, 2, 9},    {3, 9, 10},   {0, 8, 1},	  {0, 7, 8},	 /* bottom */
	    {1, 8, 9},	 {1, 9, 2},    {0, 6, 13},   {0, 13, 7}};		 /* sides */
	struct mesh_builder *b = mesh_builder_new(24);
	uint32_t v[14];
	struct st_error err;

	for (int i = 0; i < 14; i++) {
		const double p[3] = {x[i % 7][0], i < 7 ? 0 : 10, x[i % 7][1]};
		ck_assert_int_eq(mesh_builder_vertex(b, p, &v[i], &err), 0);
	}
	for (int i = 0; i < 24; i++)
		ck_assert_int_eq(mesh_builder_triangle(b, v[t[i][0]], v[t[i][1]], v[t[i][2]], &err),
				 0);
	return mesh_builder_finish(b);
}

/* `compare --reference`'s count of facets over tol, from its --json. */
static long facets_over(char *out, size_t cap, const char *a, const char *fine, double tol)
{
	ck_assert_int_eq(tu_run(out, cap, "compare '%s' --reference '%s' --tolerance %g --samples %d "
					  "--json", a, fine, tol, SAMPLES), 0);
	char *over = strstr(out, "\"facets_over\": ");
	ck_assert_msg(over, "%s", out);
	return strtol(over + strlen("\"facets_over\": "), NULL, 10);
}

/*
 * What refine reaches, compare --reference passes at the same tolerance
 * (issue 21): both measure with chordal_measure.  The ridged box against
 * the plain box at 0.2 mm: every point of the ridge lies within 0.15 mm of
 * the box's top, but a line along a ridge facet's normal grazes the top
 * and meets it up to 0.15 / cos(79 deg) = 0.77 mm away, within the facet's
 * 10 mm edge.  Refine counted the nearest point there and said reached;
 * compare counted the crossing and found the ridge's facets over.  And the
 * cylinder, refined to the tolerance, passes compare too.
 */
START_TEST(what_refine_reaches_compare_passes)
{
	static char out[1 << 16];
	char ridged[256], box[256], coarse[256], fine[256], result[256];
	struct mesh *r = ridged_box(), *bx = fx_box(0, 0, 0, 10, 10, 2);
	struct mesh *c = fx_cylinder(0, 0, R, H, 16), *f = fx_cylinder(0, 0, R, H, 256);
	struct mesh_report check;
	struct st_error err;

	ck_assert_int_eq(mesh_analyze(r, 0, &check, &err), 0);
	ck_assert(check.printable && !check.self_intersections);
	snprintf(ridged, sizeof(ridged), "%s", tu_path("ridged.stl"));
	snprintf(box, sizeof(box), "%s", tu_path("box.stl"));
	snprintf(coarse, sizeof(coarse), "%s", tu_path("cyl16.stl"));
	snprintf(fine, sizeof(fine), "%s", tu_path("cyl256.stl"));
	snprintf(result, sizeof(result), "%s", tu_path("refined.stl"));
	ck_assert_int_eq(meshio_write_stl(ridged, r, MESHIO_STL_BINARY, &err), 0);
	ck_assert_int_eq(meshio_write_stl(box, bx, MESHIO_STL_BINARY, &err), 0);
	ck_assert_int_eq(meshio_write_stl(coarse, c, MESHIO_STL_BINARY, &err), 0);
	ck_assert_int_eq(meshio_write_stl(fine, f, MESHIO_STL_BINARY, &err), 0);
	mesh_free(r);
	mesh_free(bx);
	mesh_free(c);
	mesh_free(f);

	ck_assert_int_eq(tu_run(out, sizeof(out), "refine '%s' --reference '%s' --tolerance 0.2 "
						  "-o '%s' --samples %d --json",
				ridged, box, result, SAMPLES), 0);
	ck_assert_msg(strstr(out, "\"reached\": true"), "%s", out);
	ck_assert_int_eq(facets_over(out, sizeof(out), result, box, 0.2), 0);

	ck_assert_int_eq(tu_run(out, sizeof(out), "refine '%s' --reference '%s' --tolerance %g "
						  "-o '%s' --samples %d --json",
				coarse, fine, TOL, result, SAMPLES), 0);
	ck_assert_msg(strstr(out, "\"reached\": true"), "%s", out);
	ck_assert_int_eq(facets_over(out, sizeof(out), result, fine, TOL), 0);
}
END_TEST

/* The command: the file, the report, and the exit statuses. */
START_TEST(cli_writes_reports_and_refuses)
{
	static char out[1 << 16];
	char coarse[256], fine[256], result[256], missing[256], open_box[256], wide[256];
	struct mesh *c = fx_cylinder(0, 0, R, H, 16), *f = fx_cylinder(0, 0, R, H, 256);
	struct mesh *w = fx_cylinder(0, 0, R + 0.2, H, 16), *open = fx_cube_without(10, 1);
	struct st_error err;

	snprintf(coarse, sizeof(coarse), "%s", tu_path("cyl16.stl"));
	snprintf(fine, sizeof(fine), "%s", tu_path("cyl256.stl"));
	snprintf(wide, sizeof(wide), "%s", tu_path("wide16.stl"));
	snprintf(open_box, sizeof(open_box), "%s", tu_path("open.stl"));
	snprintf(result, sizeof(result), "%s", tu_path("refined.stl"));
	snprintf(missing, sizeof(missing), "%s", tu_path("no-such-model.stl"));
	ck_assert_int_eq(meshio_write_stl(coarse, c, MESHIO_STL_BINARY, &err), 0);
	ck_assert_int_eq(meshio_write_stl(fine, f, MESHIO_STL_BINARY, &err), 0);
	ck_assert_int_eq(meshio_write_stl(wide, w, MESHIO_STL_BINARY, &err), 0);
	ck_assert_int_eq(meshio_write_stl(open_box, open, MESHIO_STL_BINARY, &err), 0);
	mesh_free(c);
	mesh_free(f);
	mesh_free(w);
	mesh_free(open);

	ck_assert_int_eq(tu_run(out, sizeof(out),
				"refine '%s' --reference '%s' --tolerance %g -o '%s' --samples %d "
				"--json",
				coarse, fine, TOL, result, SAMPLES), 0);
	ck_assert_msg(strstr(out, "\"reached\": true"), "%s", out);
	ck_assert_int_eq(tu_run(out, sizeof(out), "check '%s'", result), 0);
	ck_assert_msg(strstr(out, "printable: yes"), "%s", out);
	/* within the tolerance by the symmetric surface distance, a measure
	 * the refinement did not steer by */
	ck_assert_int_eq(tu_run(out, sizeof(out), "compare '%s' '%s' --samples 20000 --json",
				result, fine), 0);
	char *max = strstr(out, "\"max\": ");
	ck_assert_msg(max && strtod(max + 7, NULL) <= TOL, "%s", out);

	/* 2 usage: no reference, no output, a tolerance not above 0 */
	remove(result);
	ck_assert_int_eq(tu_run(out, sizeof(out), "refine '%s' -o '%s'", coarse, result), 2);
	ck_assert_msg(strstr(out, "--reference"), "%s", out);
	ck_assert_int_eq(tu_run(out, sizeof(out), "refine '%s' --reference '%s'", coarse, fine), 2);
	ck_assert_int_eq(tu_run(out, sizeof(out), "refine '%s' --reference '%s' -o '%s' "
						  "--tolerance 0", coarse, fine, result), 2);
	ck_assert_int_eq(tu_run(out, sizeof(out), "refine '%s' --reference '%s' -o '%s' "
						  "--tolerance -0.1", coarse, fine, result), 2);
	/* 65: a file that cannot be read, a coarse mesh that is not printable */
	ck_assert_int_eq(tu_run(out, sizeof(out), "refine '%s' --reference '%s' -o '%s'", coarse,
				missing, result), 65);
	ck_assert_msg(strstr(out, missing), "%s", out);
	ck_assert_int_eq(tu_run(out, sizeof(out), "refine '%s' --reference '%s' -o '%s'",
				open_box, fine, result), 65);
	ck_assert_msg(strstr(out, "not printable"), "%s", out);
	/* 1: not reached (corners off the reference), and nothing written */
	ck_assert_int_eq(tu_run(out, sizeof(out), "refine '%s' --reference '%s' -o '%s' "
						  "--tolerance 0.05 --samples %d", wide, fine,
				result, SAMPLES), 1);
	ck_assert_msg(strstr(out, "--move-vertices"), "%s", out);
	ck_assert(!tu_file_exists(result));
}
END_TEST

Suite *refine_suite(void)
{
	Suite *s = suite_create("refine");
	TCase *tc = tcase_create("refine");

	tcase_set_timeout(tc, 120); /* ASan makes the queries several times slower */
	tcase_add_test(tc, cylinder_reaches_tolerance_with_fewer_triangles_than_uniform);
	tcase_add_test(tc, coarse_torus_reaches_tolerance);
	tcase_add_test(tc, corners_off_the_reference_need_move_vertices);
	tcase_add_test(tc, moves_that_would_cross_are_refused);
	tcase_add_test(tc, vertices_left_on_their_edges_are_not_refused);
	tcase_add_test(tc, what_refine_reaches_compare_passes);
	tcase_add_test(tc, cli_writes_reports_and_refuses);
	suite_add_tcase(s, tc);
	return s;
}
