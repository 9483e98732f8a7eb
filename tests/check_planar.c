/*
 * check_planar.c - planar simplification (repair/simplify_planar.h,
 * docs/repair.md "Planar simplification"): subdivided flat faces come
 * back with the fewest triangles their topology allows, curved sides do
 * not merge beyond the angle limit, bumps above the flatness stay, a
 * cluster whose new triangles would cross another surface is left as it
 * was, and `stratum repair --simplify-planar` writes what `stratum check`
 * calls printable with the volume unchanged.
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fixtures.h"
#include "deviation.h"
#include "mesh.h"
#include "meshio.h"
#include "repair.h"
#include "simplify_planar.h"
#include "suites.h"
#include "testutil.h"

/* What a run gives, and the analysis of its result. */
struct simplified {
	struct mesh *out;
	struct planar_report rep;
	struct mesh_report check;
};

static struct simplified simplify(const struct mesh *in, double angle, double flatness)
{
	struct planar_options opt;
	struct st_error err = {0};
	struct simplified s;
	uint32_t *origin = NULL;
	int rc;

	planar_options_init(&opt);
	opt.angle = angle;
	opt.flatness = flatness;
	rc = planar_simplify(in, &opt, &s.out, &origin, &s.rep, &err);
	ck_assert_msg(rc == 0, "planar_simplify: %d %s", rc, err.msg);
	for (size_t i = 0; i < s.out->ntris; i++)
		ck_assert_uint_lt(origin[i], in->ntris);
	free(origin);
	rc = mesh_analyze(s.out, 0, &s.check, &err);
	ck_assert_msg(rc == 0, "mesh_analyze: %s", err.msg);
	return s;
}

/* Whether m has a vertex at exactly p. */
static bool has_vertex(const struct mesh *m, const double p[3])
{
	for (size_t v = 0; v < m->nverts; v++)
		if (!memcmp(m->verts[v], p, sizeof(double[3])))
			return true;
	return false;
}

/* A closed cube of side s at the origin, each face cut into n x n squares. */
static struct mesh *subdivided_cube(double s, int n)
{
	const double o0[3] = {0, 0, 0}, x[3] = {s, 0, 0}, y[3] = {0, s, 0}, z[3] = {0, 0, s};
	const double top[3] = {0, 0, s}, back[3] = {0, s, 0}, right[3] = {s, 0, 0};
	/* origin, u, v with u x v pointing outwards */
	const double *faces[6][3] = {{o0, y, x}, {top, x, y},  {o0, x, z},
				     {back, z, x}, {o0, z, y}, {right, y, z}};
	struct mesh *m = NULL;

	for (int f = 0; f < 6; f++) {
		struct mesh *g = fx_grid(faces[f][0], faces[f][1], faces[f][2], n, n);
		struct mesh *both = m ? fx_concat(m, g) : g;
		if (m) {
			mesh_free(m);
			mesh_free(g);
		}
		m = both;
	}
	return m;
}

START_TEST(subdivided_cube_to_12)
{
	struct mesh *cube = subdivided_cube(8, 4);
	struct simplified s;

	ck_assert_uint_eq(cube->ntris, 6 * 32);
	s = simplify(cube, PLANAR_ANGLE_DEFAULT, PLANAR_FLATNESS_DEFAULT);
	ck_assert_uint_eq(s.out->ntris, 12);
	ck_assert_uint_eq(s.out->nverts, 8);
	ck_assert_uint_eq(s.rep.triangles_before, 192);
	ck_assert_uint_eq(s.rep.triangles_after, 12);
	ck_assert_uint_eq(s.rep.retriangulated, 6);
	ck_assert(s.rep.max_deviation == 0);
	ck_assert(s.check.printable);
	ck_assert_double_eq_tol(s.check.volume, 512, 1e-9);
	/* Flatness 0 still merges faces that are exactly flat. */
	mesh_free(s.out);
	s = simplify(cube, 0, 0);
	ck_assert_uint_eq(s.out->ntris, 12);
	mesh_free(s.out);
	mesh_free(cube);
}
END_TEST

/*
 * A 24 x 24 x 3 plate with an 8 x 8 square hole, made as the union of
 * four overlapping boxes and repaired exactly: the repair cuts the faces
 * where the boxes overlap, the simplification brings back the minimum.
 * The solid has V = 16 corners (8 outside, 8 around the hole) and genus 1,
 * so chi = V - E + F = 0 with E = 3F/2: F = 2 (V - chi) = 32.
 */
static struct mesh *frame_boxes(void)
{
	struct mesh *a = fx_box(0, 0, 0, 24, 8, 3), *b = fx_box(0, 16, 0, 24, 24, 3);
	struct mesh *c = fx_box(0, 4, 0, 8, 20, 3), *d = fx_box(16, 4, 0, 24, 20, 3);
	struct mesh *ab = fx_concat(a, b), *cd = fx_concat(c, d), *all = fx_concat(ab, cd);

	mesh_free(a);
	mesh_free(b);
	mesh_free(c);
	mesh_free(d);
	mesh_free(ab);
	mesh_free(cd);
	return all;
}

START_TEST(plate_with_hole_to_minimum)
{
	const int corners = 16, genus = 1, chi = 2 - 2 * genus;
	const size_t minimum = (size_t)(2 * (corners - chi));
	struct mesh *boxes = frame_boxes(), *repaired = NULL;
	struct repair_options opt;
	struct repair_report rr;
	struct st_error err = {0};
	struct simplified s;

	repair_options_init(&opt);
	ck_assert_int_eq(repair_mesh(boxes, &opt, &repaired, NULL, &rr, &err), 0);
	ck_assert(rr.printable);
	ck_assert_uint_gt(repaired->ntris, minimum); /* the cuts left more */
	s = simplify(repaired, PLANAR_ANGLE_DEFAULT, PLANAR_FLATNESS_DEFAULT);
	ck_assert_uint_eq(minimum, 32);
	ck_assert_uint_eq(s.out->ntris, minimum);
	ck_assert_uint_eq(s.out->nverts, (size_t)corners);
	ck_assert_int_eq(s.check.genus, genus);
	ck_assert(s.check.printable);
	ck_assert_double_eq_tol(s.check.volume, 24 * 24 * 3 - 8 * 8 * 3, 1e-9);
	ck_assert_double_eq_tol(s.rep.volume_before, s.rep.volume_after, 1e-9);
	mesh_free(s.out);
	mesh_free(repaired);
	mesh_free(boxes);
}
END_TEST

/*
 * tests/fixtures.h's plate with a square and a round (64-gon) hole,
 * generated with its faces in strips: V = 8 outer corners + 8 around the
 * square hole + 2 x 64 around the round one = 144, genus 2, so
 * chi = -2 and F = 2 (V - chi) = 292.
 */
START_TEST(plate_two_holes_to_minimum)
{
	const int corners = 8 + 8 + 2 * 64, genus = 2, chi = 2 - 2 * genus;
	struct mesh *plate = fx_plate_holes();
	struct simplified s;

	ck_assert_uint_gt(plate->ntris, (size_t)(2 * (corners - chi)));
	s = simplify(plate, PLANAR_ANGLE_DEFAULT, PLANAR_FLATNESS_DEFAULT);
	ck_assert_uint_eq(s.out->ntris, (size_t)(2 * (corners - chi)));
	ck_assert_uint_eq(s.out->nverts, (size_t)corners);
	ck_assert_int_eq(s.check.genus, genus);
	ck_assert(s.check.printable);
	ck_assert_double_eq_tol(s.rep.volume_after, s.rep.volume_before, 1e-9);
	mesh_free(s.out);
	mesh_free(plate);
}
END_TEST

/*
 * A cylinder of radius 10 whose side is n strips, each cut into rows:
 * row vertices lie on the strips' vertical edges, caps are fans around
 * their centres.
 */
static struct mesh *cylinder_rows(int n, int rows)
{
	struct mesh_builder *b = mesh_builder_new((size_t)(2 * n * rows + 2 * n));
	struct st_error err;
	uint32_t v[257][9], centre[2];

	for (int j = 0; j < n; j++)
		for (int i = 0; i <= rows; i++) {
			const double p[3] = {10 * cos(2 * M_PI * j / n), 10 * sin(2 * M_PI * j / n),
					     20.0 * i / rows};
			ck_assert_int_eq(mesh_builder_vertex(b, p, &v[j][i], &err), 0);
		}
	for (int k = 0; k < 2; k++) {
		const double p[3] = {0, 0, k ? 20 : 0};
		ck_assert_int_eq(mesh_builder_vertex(b, p, &centre[k], &err), 0);
	}
	for (int j = 0; j < n; j++) {
		const int jn = (j + 1) % n;
		for (int i = 0; i < rows; i++) {
			mesh_builder_triangle(b, v[j][i], v[jn][i], v[jn][i + 1], &err);
			mesh_builder_triangle(b, v[j][i], v[jn][i + 1], v[j][i + 1], &err);
		}
		mesh_builder_triangle(b, centre[0], v[jn][0], v[j][0], &err);
		mesh_builder_triangle(b, centre[1], v[j][rows], v[jn][rows], &err);
	}
	return mesh_builder_finish(b);
}

/* Side triangles whose corners span more than one of the n strips. */
static int spanning(const struct mesh *m, int n)
{
	int count = 0;

	for (size_t t = 0; t < m->ntris; t++) {
		const double z0 = m->verts[m->tris[t][0]][2];
		int lo = n, hi = -1;
		bool side = false; /* caps are flat */
		for (int k = 0; k < 3; k++) {
			const double *p = m->verts[m->tris[t][k]];
			const double a = atan2(p[1], p[0]);
			const int j = (int)lround((a < 0 ? a + 2 * M_PI : a) * n / (2 * M_PI)) % n;
			side = side || p[2] != z0;
			lo = j < lo ? j : lo;
			hi = j > hi ? j : hi;
		}
		count += side && hi - lo > 1 && !(lo == 0 && hi == n - 1);
	}
	return count;
}

START_TEST(cylinder_side_keeps_angle_limit)
{
	const int n = 32; /* 11.25 degrees between neighbouring strips */
	struct mesh *cyl = cylinder_rows(n, 4);
	struct simplified s;

	/* Within the angle limit each strip is one face: its row vertices
	 * go, its edges stay; the caps lose their centres. */
	s = simplify(cyl, 10, PLANAR_FLATNESS_MAX);
	ck_assert_uint_eq(s.rep.clusters, (size_t)n + 2);
	ck_assert_int_eq(spanning(s.out, n), 0);
	ck_assert_uint_eq(s.out->ntris, 2 * n + 2 * (n - 2));
	ck_assert(s.check.printable);
	mesh_free(s.out);
	/* Past 11.25 degrees neighbouring strips merge (the flatness of 1 mm
	 * allows it): fewer clusters, and the surface moves off the edges
	 * between merged strips. */
	s = simplify(cyl, 12, PLANAR_FLATNESS_MAX);
	ck_assert_uint_lt(s.rep.clusters, (size_t)n + 2);
	ck_assert(s.rep.max_deviation > 0);
	ck_assert(s.check.printable);
	ck_assert(s.rep.max_deviation <= PLANAR_FLATNESS_MAX);
	mesh_free(s.out);
	mesh_free(cyl);
}
END_TEST

/*
 * A 20 x 20 x 10 box whose top is an 8 x 8 grid with one vertex raised
 * above the flatness (stays) and one below it (goes).
 */
START_TEST(bumps_above_flatness_stay)
{
	const double high[3] = {10, 10, 10.05}, low[3] = {5, 5, 10.004};
	struct mesh *m = subdivided_cube(20, 8), *box;
	struct simplified s;
	bool raised[2] = {false, false};

	/* subdivided_cube is a cube of 20; make it 10 high, then bump. */
	for (size_t v = 0; v < m->nverts; v++)
		m->verts[v][2] /= 2;
	for (size_t v = 0; v < m->nverts; v++) {
		double *p = m->verts[v];
		if (p[2] == 10 && p[0] == high[0] && p[1] == high[1]) {
			p[2] = high[2];
			raised[0] = true;
		} else if (p[2] == 10 && p[0] == low[0] && p[1] == low[1]) {
			p[2] = low[2];
			raised[1] = true;
		}
	}
	ck_assert(raised[0] && raised[1]);
	box = fx_to_float(m);
	s = simplify(box, PLANAR_ANGLE_DEFAULT, PLANAR_FLATNESS_DEFAULT);
	ck_assert(s.check.printable);
	ck_assert(has_vertex(s.out, box->verts[0])); /* a corner */
	{
		const double hf[3] = {10, 10, (float)high[2]}, lf[3] = {5, 5, (float)low[2]};
		ck_assert_msg(has_vertex(s.out, hf), "the 0.05 mm bump was flattened");
		ck_assert_msg(!has_vertex(s.out, lf), "the 0.004 mm bump stayed");
	}
	ck_assert_uint_lt(s.out->ntris, box->ntris / 2);
	ck_assert(s.rep.max_deviation > 0.003 && s.rep.max_deviation <= PLANAR_FLATNESS_DEFAULT);
	ck_assert(fabs(s.rep.volume_after - s.rep.volume_before) <=
		  PLANAR_FLATNESS_DEFAULT * s.rep.area);
	mesh_free(s.out);
	mesh_free(box);
	mesh_free(m);
}
END_TEST

/*
 * The same box, 16 x 16 squares a face, with every vertex on the rim of
 * its top moved up or down by up to 0.0045 mm (pseudo-random, fixed):
 * the top merges into one face, and the largest deviation reported
 * bounds the distance `stratum compare` measures between the surfaces
 * before and after.  Here the widest gap is where an old edge crosses a
 * new one, not at a removed vertex (measured 0.0055 mm against 0.0042 at
 * the vertices).
 */
START_TEST(reported_deviation_bounds_the_surface_distance)
{
	struct mesh *m = subdivided_cube(20, 16), *box;
	struct deviation_report d;
	struct st_error err = {0};
	struct simplified s;
	uint32_t seed = 12345;

	for (size_t v = 0; v < m->nverts; v++) {
		double *p = m->verts[v];
		p[2] /= 2;
		if (p[2] == 10 && (p[0] == 0 || p[0] == 20 || p[1] == 0 || p[1] == 20)) {
			seed = seed * 1103515245u + 12345u;
			p[2] += 0.0045 * ((double)(seed >> 8 & 0xffff) / 32767.5 - 1);
		}
	}
	box = fx_to_float(m);
	s = simplify(box, PLANAR_ANGLE_DEFAULT, PLANAR_FLATNESS_DEFAULT);
	ck_assert(s.check.printable);
	ck_assert_uint_lt(s.out->ntris, box->ntris / 2);
	ck_assert_int_eq(deviation_measure(s.out, box, 400000, &d, &err), 0);
	ck_assert_msg(d.max <= s.rep.max_deviation + 1e-6, "measured %.6f mm, reported %.6f mm",
		      d.max, s.rep.max_deviation);
	ck_assert(s.rep.max_deviation <= PLANAR_FLATNESS_DEFAULT);
	deviation_report_free(&d);
	mesh_free(s.out);
	mesh_free(box);
	mesh_free(m);
}
END_TEST

/*
 * An open 10 x 10 patch whose centre is raised 0.008 mm (within the
 * flatness) over a small tetrahedron that crosses the patch's base plane:
 * the flat re-triangulation would cut through it, so the patch stays.
 */
static struct mesh *tent(bool with_tetra)
{
	struct mesh_builder *b = mesh_builder_new(8);
	const double p[9][3] = {{0, 0, 0},	   {10, 0, 0},		{10, 10, 0},
				{0, 10, 0},	   {5, 5, 0.008},	{4.8, 4.8, -0.002},
				{5.2, 4.8, -0.002}, {5, 5.2, -0.002}, {5, 4.9, 0.002}};
	const uint32_t t[8][3] = {{0, 1, 4}, {1, 2, 4}, {2, 3, 4}, {3, 0, 4},
				  {5, 7, 6}, {5, 6, 8}, {6, 7, 8}, {7, 5, 8}};
	struct st_error err;
	uint32_t v[9];

	for (int i = 0; i < 9; i++)
		mesh_builder_vertex(b, p[i], &v[i], &err);
	for (int i = 0; i < (with_tetra ? 8 : 4); i++)
		mesh_builder_triangle(b, v[t[i][0]], v[t[i][1]], v[t[i][2]], &err);
	return mesh_builder_finish(b);
}

START_TEST(crossing_cluster_left_as_it_was)
{
	struct mesh *alone = tent(false), *crossed = tent(true);
	struct simplified s;

	/* Open boundary: corners stay, the raised centre goes. */
	s = simplify(alone, PLANAR_ANGLE_DEFAULT, PLANAR_FLATNESS_DEFAULT);
	ck_assert_uint_eq(s.out->ntris, 2);
	ck_assert_double_eq_tol(s.rep.max_deviation, 0.008, 1e-12);
	mesh_free(s.out);
	s = simplify(crossed, PLANAR_ANGLE_DEFAULT, PLANAR_FLATNESS_DEFAULT);
	ck_assert_uint_eq(s.rep.refused_crossing, 1);
	ck_assert_uint_eq(s.out->ntris, 8);
	ck_assert_uint_eq(s.check.self_intersections, 0);
	mesh_free(s.out);
	mesh_free(alone);
	mesh_free(crossed);
}
END_TEST

/*
 * A 10 mm cube, faces cut 2 x 2, the top's centre raised 0.008 mm over
 * the tetrahedron of tent(), lifted to the top: the top is left as it
 * was, so each side keeps the midpoint of its top edge (dropping it would
 * leave a T-junction there) and needs 3 triangles instead of 2.
 */
START_TEST(refused_neighbour_keeps_seam)
{
	struct mesh *cube = subdivided_cube(10, 2), *tetra = tent(true), *both;
	struct simplified s;

	for (size_t v = 0; v < cube->nverts; v++)
		if (cube->verts[v][0] == 5 && cube->verts[v][1] == 5 && cube->verts[v][2] == 10)
			cube->verts[v][2] = 10.008;
	for (size_t v = 0; v < tetra->nverts; v++)
		tetra->verts[v][2] += 10;
	/* the tetrahedron alone: tent(true) without its patch */
	for (int i = 0; i < 4; i++)
		fx_drop(tetra, 0);
	both = fx_concat(cube, tetra);
	s = simplify(both, PLANAR_ANGLE_DEFAULT, PLANAR_FLATNESS_DEFAULT);
	ck_assert_uint_eq(s.rep.refused_crossing, 1);
	ck_assert_uint_eq(s.rep.refused_topology, 0);
	ck_assert_uint_eq(s.rep.retriangulated, 5);
	ck_assert_uint_eq(s.out->ntris, 8 + 4 * 3 + 2 + 4);
	ck_assert_uint_eq(s.check.boundary_edges, 0);
	ck_assert_uint_eq(s.check.self_intersections, 0);
	mesh_free(s.out);
	/* Without the tetrahedron the cube comes back with 12 triangles. */
	s = simplify(cube, PLANAR_ANGLE_DEFAULT, PLANAR_FLATNESS_DEFAULT);
	ck_assert_uint_eq(s.out->ntris, 12);
	mesh_free(s.out);
	mesh_free(both);
	mesh_free(tetra);
	mesh_free(cube);
}
END_TEST

/* The command: repair of the four boxes, simplified, passes `stratum check`. */
START_TEST(cli_simplified_is_printable)
{
	struct mesh *boxes = frame_boxes();
	const char *in = tu_path("frame-boxes.stl"), *out = tu_path("frame-simple.stl");
	struct st_error err = {0};
	char buf[8192];
	int rc;

	ck_assert_int_eq(meshio_write_stl(in, boxes, MESHIO_STL_BINARY, &err), 0);
	rc = tu_run(buf, sizeof(buf), "repair %s -o %s --simplify-planar --json", in, out);
	ck_assert_msg(rc == 0, "%s", buf);
	ck_assert_msg(strstr(buf, "\"triangles_after\": 32"), "%s", buf);
	rc = tu_run(buf, sizeof(buf), "check %s", out);
	ck_assert_msg(rc == 0 && strstr(buf, "printable: yes"), "%s", buf);
	/* --split: each part keeps its own triangles (a subdivided cube
	 * beside the frame comes back as 12 in a file of its own). */
	{
		struct mesh *cube = subdivided_cube(8, 4), *both;
		const char *parts = tu_path("parts.stl");
		for (size_t v = 0; v < cube->nverts; v++)
			cube->verts[v][0] += 40;
		both = fx_concat(boxes, cube);
		ck_assert_int_eq(meshio_write_stl(in, both, MESHIO_STL_BINARY, &err), 0);
		rc = tu_run(buf, sizeof(buf), "repair %s -o %s --simplify-planar --split", in, parts);
		ck_assert_msg(rc == 0, "%s", buf);
		rc = tu_run(buf, sizeof(buf), "check %s", tu_path("parts-1.stl"));
		ck_assert_msg(rc == 0 && strstr(buf, "binary STL, 32 triangles"), "%s", buf);
		rc = tu_run(buf, sizeof(buf), "check %s", tu_path("parts-2.stl"));
		ck_assert_msg(rc == 0 && strstr(buf, "binary STL, 12 triangles"), "%s", buf);
		mesh_free(both);
		mesh_free(cube);
	}
	/* --angle and --flatness belong to --simplify-planar. */
	rc = tu_run(buf, sizeof(buf), "repair %s -o %s --flatness 0.1", in, out);
	ck_assert_msg(rc == 2 && strstr(buf, "--simplify-planar"), "%s", buf);
	rc = tu_run(buf, sizeof(buf), "repair %s -o %s --simplify-planar --angle 50", in, out);
	ck_assert_msg(rc == 2, "%s", buf);
	mesh_free(boxes);
}
END_TEST

Suite *planar_suite(void)
{
	Suite *s = suite_create("planar");
	TCase *shapes = tcase_create("shapes"), *cli = tcase_create("cli");

	tcase_set_timeout(shapes, 60); /* exact checks under ASan */
	tcase_set_timeout(cli, 60);
	tcase_add_test(shapes, subdivided_cube_to_12);
	tcase_add_test(shapes, plate_with_hole_to_minimum);
	tcase_add_test(shapes, plate_two_holes_to_minimum);
	tcase_add_test(shapes, cylinder_side_keeps_angle_limit);
	tcase_add_test(shapes, bumps_above_flatness_stay);
	tcase_add_test(shapes, reported_deviation_bounds_the_surface_distance);
	tcase_add_test(shapes, crossing_cluster_left_as_it_was);
	tcase_add_test(shapes, refused_neighbour_keeps_seam);
	suite_add_tcase(s, shapes);
	tcase_add_test(cli, cli_simplified_is_printable);
	suite_add_tcase(s, cli);
	return s;
}
