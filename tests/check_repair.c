/*
 * check_repair.c - seed 000's repair end to end (repair/repair.h).
 *
 * Every input is generated in code (tests/fixtures.c) so what the answer
 * must be follows from how the input is built.  Every test judges the
 * result the way a printer would get it: each part (a manifold-connected
 * shell with its cavities)
 * of the output is written as a binary STL (ASCII with 17 digits for
 * REPAIR_FLOAT64), read back, and the project's exact checker
 * (mesh_analyze) must call the file printable (Definition 3.11 holds per
 * component; seed 000 §4.2.1 saves each component to its own file).  On
 * top of that each test checks the geometric claim that makes the repair
 * "as exact as possible": what was already solid is not moved, unions have
 * the exact volume, sheets and wires become solids of thickness epsilon.
 * This file has the solid inputs; sheets, wires, soups and bad arguments
 * are in check_repair_sheet.c, the shared checks in repairtest.c.
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

/* Nothing geometric happened: no cuts, no deletions, no sheets, no wires. */
static void assert_untouched_report(const struct repair_report *rep)
{
	ck_assert_uint_eq(rep->intersecting_pairs, 0);
	ck_assert_uint_eq(rep->triangles_split, 0);
	ck_assert_uint_eq(rep->interior_deleted, 0);
	ck_assert_uint_eq(rep->enclosed_deleted, 0);
	ck_assert_uint_eq(rep->sheet_triangles, 0);
	ck_assert_uint_eq(rep->wires, 0);
	ck_assert(!rep->second_pass);
	ck_assert_double_eq(rep->solid_deviation, 0.0);
	ck_assert_uint_eq(rep->components, 1);
}

/* ---- 1. printable inputs come back unchanged ---- */

/* Solid inputs whose coordinates are all floats (what binary STL holds). */
static struct mesh *float_solid(int i)
{
	struct mesh *m, *f;

	switch (i) {
	case 0:
		return fx_box(0, 0, 0, 10, 10, 10);
	case 1: /* float-representable but not integers */
		return fx_box(-1.5, 0.25, 3, 7.75, 9.5, 12.125);
	case 2:
		m = fx_sphere(0, 0, 0, 10, 8, 12);
		break;
	default:
		m = fx_torus(10, 3, 24, 12);
		break;
	}
	f = fx_to_float(m);
	mesh_free(m);
	return f;
}

/*
 * Proves that a mesh that is already printable (box, sphere, torus) is
 * returned with exactly the same triangles, same orientation, same
 * coordinates, both in memory and in the written binary STL: Hausdorff
 * distance 0, and the report shows nothing was cut, deleted or thickened.
 */
START_TEST(solid_float_input_unchanged)
{
	struct mesh *in = float_solid(_i);
	struct fixed f = repair_eps(in, EPS);
	struct mesh *back;

	assert_same_triangles(f.out, in, "output");
	judge(&f, REPAIR_FLOAT32, "unchanged");
	back = tu_round_trip(f.out, "unchanged-file.stl", MESHIO_STL_BINARY);
	assert_same_triangles(back, in, "written file");
	assert_untouched_report(&f.rep);
	ck_assert_double_eq(f.rep.rounding_deviation, 0.0);
	mesh_free(back);
	fixed_free(&f);
	mesh_free(in);
}
END_TEST

/*
 * Proves the same for double coordinates when the output precision is
 * float64 (ASCII STL with 17 digits): not even rounding moves a vertex.
 */
START_TEST(solid_double_input_unchanged_float64)
{
	struct mesh *in = _i == 0 ? fx_sphere(0, 0, 0, 10, 8, 12) : fx_torus(10, 3, 24, 12);
	struct repair_options opt;
	struct fixed f;

	repair_options_init(&opt);
	opt.precision = REPAIR_FLOAT64;
	f = repair_with(in, &opt);
	assert_same_triangles(f.out, in, "output");
	judge(&f, REPAIR_FLOAT64, "unchanged64");
	assert_untouched_report(&f.rep);
	ck_assert_double_eq(f.rep.rounding_deviation, 0.0);
	fixed_free(&f);
	mesh_free(in);
}
END_TEST

/*
 * Proves that with float32 output a printable double-coordinate mesh is
 * only rounded: every vertex goes to its nearest float (the smallest move
 * there is; rounding a sphere or torus this coarse creates no
 * intersection, so no further rounds are needed), and the reported
 * rounding deviation is that move, well under a micrometre.
 */
START_TEST(solid_double_input_rounded_to_nearest_float)
{
	struct mesh *in = _i == 0 ? fx_sphere(0, 0, 0, 10, 8, 12) : fx_torus(10, 3, 24, 12);
	struct mesh *want = fx_to_float(in);
	struct fixed f = repair_eps(in, EPS);

	assert_same_triangles(f.out, want, "output vs input rounded to float");
	judge(&f, REPAIR_FLOAT32, "rounded");
	assert_untouched_report(&f.rep);
	ck_assert_msg(f.rep.rounding_deviation > 0 && f.rep.rounding_deviation < 1e-6,
		      "rounding_deviation %g", f.rep.rounding_deviation);
	fixed_free(&f);
	mesh_free(want);
	mesh_free(in);
}
END_TEST

/* ---- 2. overlapping cubes: the exact union ---- */

/* p is within tol of the closed box lo..hi. */
static int in_box(const double p[3], const double lo[3], const double hi[3], double tol)
{
	for (int k = 0; k < 3; k++)
		if (p[k] < lo[k] - tol || p[k] > hi[k] + tol)
			return 0;
	return 1;
}

/*
 * p lies on the boundary of the union of the closed boxes: it is in the
 * union, and a step of 1e-3 along one of the 26 lattice directions leaves
 * every box.  For axis-aligned boxes the lattice directions find the
 * outside wherever it touches p.
 */
static int on_union_boundary(const double p[3], const double (*lo)[3], const double (*hi)[3],
			     int n)
{
	int inside = 0;

	for (int b = 0; b < n; b++)
		inside |= in_box(p, lo[b], hi[b], 1e-9);
	if (!inside)
		return 0;
	for (int d = 0; d < 27; d++) {
		const double q[3] = {p[0] + 1e-3 * (d % 3 - 1), p[1] + 1e-3 * (d / 3 % 3 - 1),
				     p[2] + 1e-3 * (d / 9 - 1)};
		int out = 1;
		if (d == 13)
			continue;
		for (int b = 0; b < n; b++)
			if (in_box(q, lo[b], hi[b], 0))
				out = 0;
		if (out)
			return 1;
	}
	return 0;
}

/*
 * Proves the exact union of [0,2]^3 and [1,3]^3: one component of volume
 * 8 + 8 - 1 = 15 exactly, made only of triangles that lie in a face plane
 * of the input (x, y or z in {0,1,2,3} at all three corners) and on the
 * union's boundary (the parts of each cube's faces inside the other cube
 * are gone).
 */
START_TEST(overlapping_cubes_union)
{
	struct mesh *a = fx_box(0, 0, 0, 2, 2, 2), *b = fx_box(1, 1, 1, 3, 3, 3);
	struct mesh *in = fx_concat(a, b);
	const double lo[2][3] = {{0, 0, 0}, {1, 1, 1}}, hi[2][3] = {{2, 2, 2}, {3, 3, 3}};
	struct fixed f = repair_eps(in, EPS);
	struct mesh_report r = judge(&f, REPAIR_FLOAT32, "union");

	ck_assert_uint_gt(f.rep.intersecting_pairs, 0);
	ck_assert_uint_gt(f.rep.triangles_split, 0);
	ck_assert_uint_eq(f.rep.components, 1);
	ck_assert_uint_eq(f.rep.sheet_triangles, 0);
	ck_assert(!f.rep.second_pass);
	ck_assert_double_eq(f.rep.solid_deviation, 0.0);
	ck_assert_uint_eq(r.components, 1);
	ck_assert_msg(fabs(r.volume - 15.0) <= 15.0 * 1e-9, "union volume %.17g, expected 15",
		      r.volume);
	for (size_t t = 0; t < f.out->ntris; t++) {
		const double *p[3] = {f.out->verts[f.out->tris[t][0]], f.out->verts[f.out->tris[t][1]],
				      f.out->verts[f.out->tris[t][2]]};
		double g[3];
		int planar = 0;

		for (int k = 0; k < 3; k++) {
			double c = p[0][k];
			g[k] = (p[0][k] + p[1][k] + p[2][k]) / 3;
			if (p[1][k] == c && p[2][k] == c && (c == 0 || c == 1 || c == 2 || c == 3))
				planar = 1;
		}
		ck_assert_msg(planar, "triangle %zu (%g,%g,%g)(%g,%g,%g)(%g,%g,%g) is in no face plane",
			      t, p[0][0], p[0][1], p[0][2], p[1][0], p[1][1], p[1][2], p[2][0],
			      p[2][1], p[2][2]);
		for (int k = 0; k < 3; k++)
			ck_assert_msg(on_union_boundary(p[k], lo, hi, 2),
				      "vertex (%g,%g,%g) of triangle %zu is not on the union's surface",
				      p[k][0], p[k][1], p[k][2], t);
		ck_assert_msg(on_union_boundary(g, lo, hi, 2),
			      "triangle %zu (centroid %g,%g,%g) is not on the union's surface", t,
			      g[0], g[1], g[2]);
	}
	fixed_free(&f);
	mesh_free(in);
	mesh_free(a);
	mesh_free(b);
}
END_TEST

/*
 * Proves the result does not depend on the thread count: one thread and
 * all cores give the same triangles.
 */
START_TEST(threads_do_not_change_result)
{
	struct mesh *a = fx_box(0, 0, 0, 2, 2, 2), *b = fx_box(1, 1, 1, 3, 3, 3);
	struct mesh *in = fx_concat(a, b);
	struct repair_options opt;
	struct fixed f1, f0;

	repair_options_init(&opt);
	opt.threads = 1;
	f1 = repair_with(in, &opt);
	opt.threads = 0;
	f0 = repair_with(in, &opt);
	assert_same_triangles(f0.out, f1.out, "threads 0 vs 1");
	ck_assert_uint_eq(f0.rep.intersecting_pairs, f1.rep.intersecting_pairs);
	fixed_free(&f1);
	fixed_free(&f0);
	mesh_free(in);
	mesh_free(a);
	mesh_free(b);
}
END_TEST

/* ---- 3. a shell inside another is deleted ---- */

/*
 * Proves that a closed component enclosed by another (box [3,7]^3 inside
 * [0,10]^3, both outward) is deleted and the outer box is returned exactly.
 */
START_TEST(nested_shell_deleted)
{
	struct mesh *outer = fx_box(0, 0, 0, 10, 10, 10), *inner = fx_box(3, 3, 3, 7, 7, 7);
	struct mesh *in = fx_concat(outer, inner);
	struct fixed f = repair_eps(in, EPS);
	struct mesh_report r = judge(&f, REPAIR_FLOAT32, "nested");

	assert_same_triangles(f.out, outer, "output vs outer box");
	ck_assert_uint_eq(f.rep.enclosed_deleted, 12);
	ck_assert_uint_eq(f.rep.intersecting_pairs, 0);
	ck_assert_uint_eq(f.rep.sheet_triangles, 0);
	ck_assert_uint_eq(f.rep.components, 1);
	ck_assert_double_eq_tol(r.volume, 1000.0, 1e-9);
	fixed_free(&f);
	mesh_free(in);
	mesh_free(outer);
	mesh_free(inner);
}
END_TEST

/* m with every triangle reversed (a closed shell facing inwards). */
static struct mesh *reversed(const struct mesh *m)
{
	struct mesh *r = fx_concat(m, m);

	r->ntris = m->ntris; /* the copy welded onto the same vertices: keep one */
	for (size_t t = 0; t < r->ntris; t++)
		fx_flip(r, t);
	return r;
}

/*
 * Proves that an enclosed shell the input faces inwards is a designed
 * cavity and is kept (docs/repair.md, "Cavities"): the output is the
 * input, triangle for triangle and orientation for orientation, one part
 * with one cavity, volume 1000 - 64; nothing is counted as enclosed.
 */
START_TEST(nested_inward_shell_is_a_cavity)
{
	struct mesh *outer = fx_box(0, 0, 0, 10, 10, 10), *box = fx_box(3, 3, 3, 7, 7, 7);
	struct mesh *inner = reversed(box), *in = fx_concat(outer, inner);
	struct fixed f = repair_eps(in, EPS);
	struct mesh_report r = judge(&f, REPAIR_FLOAT32, "cavity");

	assert_same_triangles(f.out, in, "output vs input");
	ck_assert_uint_eq(f.rep.enclosed_deleted, 0);
	ck_assert_uint_eq(f.rep.cavities, 1);
	ck_assert_uint_eq(f.rep.components, 1);
	ck_assert_uint_eq(r.cavities, 1);
	ck_assert_double_eq_tol(r.volume, 1000.0 - 64.0, 1e-9);
	fixed_free(&f);
	mesh_free(in);
	mesh_free(outer);
	mesh_free(box);
	mesh_free(inner);
}
END_TEST

/*
 * Proves that a part inside a cavity is in empty space and is kept as a
 * part of its own (a ball in a hollow box): outer box, inward cavity
 * [2,8]^3, outward cube [4,6]^3 in it: two parts, one cavity, volume
 * 1000 - 216 + 8.
 */
START_TEST(part_inside_a_cavity_kept)
{
	struct mesh *outer = fx_box(0, 0, 0, 10, 10, 10), *box = fx_box(2, 2, 2, 8, 8, 8);
	struct mesh *cavity = reversed(box), *core = fx_box(4, 4, 4, 6, 6, 6);
	struct mesh *shell = fx_concat(outer, cavity), *in = fx_concat(shell, core);
	struct fixed f = repair_eps(in, EPS);
	struct mesh_report r = judge(&f, REPAIR_FLOAT32, "ballinbox");

	assert_same_triangles(f.out, in, "output vs input");
	ck_assert_uint_eq(f.rep.components, 2);
	ck_assert_uint_eq(f.rep.cavities, 1);
	ck_assert_double_eq_tol(r.volume, 1000.0 - 216.0 + 8.0, 1e-9);
	fixed_free(&f);
	mesh_free(in);
	mesh_free(shell);
	mesh_free(outer);
	mesh_free(box);
	mesh_free(cavity);
	mesh_free(core);
}
END_TEST

/*
 * Proves that touching cubes come out as one printable file: two 10 mm
 * cubes sharing a face (i = 0: fused into one solid), an edge (i = 1) or
 * a vertex (i = 2) (two parts); 2000 mm^3 either way, the file printable
 * as a whole and part by part.
 */
START_TEST(touching_cubes_printable)
{
	const int i = _i;
	const double off[3][3] = {{10, 0, 0}, {10, 10, 0}, {10, 10, 10}};
	struct mesh *a = fx_box(0, 0, 0, 10, 10, 10);
	struct mesh *b = fx_box(off[i][0], off[i][1], off[i][2], off[i][0] + 10, off[i][1] + 10,
				off[i][2] + 10);
	struct mesh *in = fx_concat(a, b);
	struct fixed f = repair_eps(in, EPS);
	struct mesh_report r = judge(&f, REPAIR_FLOAT32, "touching");

	ck_assert_uint_eq(f.rep.components, i == 0 ? 1 : 2);
	ck_assert_double_eq_tol(r.volume, 2000.0, 1e-9);
	fixed_free(&f);
	mesh_free(in);
	mesh_free(a);
	mesh_free(b);
}
END_TEST

/*
 * Proves that a part smaller than epsilon in every direction is dropped
 * and counted: a 0.1 mm cube beside a 10 mm cube, epsilon 0.4, leaves
 * the 10 mm cube alone (its 12 triangles unchanged); a plate 0.1 mm thin
 * but 10 mm wide is kept.
 */
START_TEST(tiny_part_dropped)
{
	struct mesh *big = fx_box(0, 0, 0, 10, 10, 10), *tiny = fx_box(20, 0, 0, 20.1, 0.1, 0.1);
	struct mesh *plate = fx_box(0, 20, 0, 10, 30, 0.1);
	struct mesh *in = fx_concat(big, tiny), *both = fx_concat(big, plate);
	struct fixed f = repair_eps(in, EPS), g;

	judge(&f, REPAIR_FLOAT32, "tiny");
	assert_same_triangles(f.out, big, "output vs the big cube");
	ck_assert_uint_eq(f.rep.parts_dropped, 1);
	ck_assert_uint_eq(f.rep.dropped_triangles, 12);
	ck_assert_uint_eq(f.rep.components, 1);
	g = repair_eps(both, EPS);
	judge(&g, REPAIR_FLOAT32, "plate");
	ck_assert_uint_eq(g.rep.parts_dropped, 0);
	ck_assert_uint_eq(g.rep.components, 2);
	fixed_free(&f);
	fixed_free(&g);
	mesh_free(in);
	mesh_free(both);
	mesh_free(big);
	mesh_free(tiny);
	mesh_free(plate);
}
END_TEST

/*
 * Proves that a wire entirely inside the solid ((2,2,2)-(8,8,8) with a
 * middle corner (5,5,5)) is discarded and the cube comes back exactly.
 */
START_TEST(inner_wire_discarded)
{
	const double a[3] = {2, 2, 2}, b[3] = {8, 8, 8}, c[3] = {5, 5, 5};
	struct mesh *cube = fx_box(0, 0, 0, 10, 10, 10), *wire = fx_triangle(a, b, c);
	struct mesh *in = fx_concat(cube, wire);
	struct fixed f = repair_eps(in, EPS);
	struct mesh_report r = judge(&f, REPAIR_FLOAT32, "innerwire");

	ck_assert_uint_eq(f.rep.degenerate_removed, 1);
	ck_assert_uint_eq(f.rep.wires_discarded, 1);
	assert_same_triangles(f.out, cube, "output vs cube");
	ck_assert_double_eq_tol(r.volume, 1000.0, 1e-9);
	ck_assert_uint_eq(f.rep.components, 1);
	fixed_free(&f);
	mesh_free(in);
	mesh_free(cube);
	mesh_free(wire);
}
END_TEST

/* ---- 9. split into manifold-connected parts ---- */

/* Mean x of m's vertices. */
static double mean_x(const struct mesh *m)
{
	double sum = 0;

	for (size_t v = 0; v < m->nverts; v++)
		sum += m->verts[v][0];
	return m->nverts ? sum / m->nverts : 0;
}

/*
 * Proves that two cubes sharing only an edge ([0,1]^3 and [1,2]x[1,2]x[0,1])
 * are not manifold-connected (Def. 3.10): the output is the input
 * unchanged, split into two components of 12 triangles, each one cube.
 */
START_TEST(edge_touching_cubes_two_components)
{
	struct mesh *a = fx_box(0, 0, 0, 1, 1, 1), *b = fx_box(1, 1, 0, 2, 2, 1);
	struct mesh *in = fx_concat(a, b);
	struct fixed f = repair_eps(in, EPS);
	struct mesh *p0, *p1;

	judge(&f, REPAIR_FLOAT32, "edgecubes");
	ck_assert_uint_eq(f.rep.components, 2);
	ck_assert_uint_eq(f.rep.intersecting_pairs, 0);
	ck_assert_uint_eq(f.rep.sheet_triangles, 0);
	assert_same_triangles(f.out, in, "output vs input");
	p0 = part_mesh(f.out, f.comp, 0);
	p1 = part_mesh(f.out, f.comp, 1);
	ck_assert_uint_eq(p0->ntris, 12);
	ck_assert_uint_eq(p1->ntris, 12);
	/* Each component is one of the cubes; a's vertices average x = 0.5, b's 1.5. */
	if (mean_x(p0) < 1) {
		assert_same_triangles(p0, a, "component 0");
		assert_same_triangles(p1, b, "component 1");
	} else {
		assert_same_triangles(p0, b, "component 0");
		assert_same_triangles(p1, a, "component 1");
	}
	mesh_free(p0);
	mesh_free(p1);
	fixed_free(&f);
	mesh_free(in);
	mesh_free(a);
	mesh_free(b);
}
END_TEST

Suite *repair_suite(void)
{
	Suite *s = suite_create("repair");
	TCase *solid = tcase_create("solid");

	/* Exact arithmetic under ASan/UBSan is slow; these are small inputs. */
	tcase_set_timeout(solid, 60);
	tcase_add_loop_test(solid, solid_float_input_unchanged, 0, 4);
	tcase_add_loop_test(solid, solid_double_input_unchanged_float64, 0, 2);
	tcase_add_loop_test(solid, solid_double_input_rounded_to_nearest_float, 0, 2);
	tcase_add_test(solid, overlapping_cubes_union);
	tcase_add_test(solid, threads_do_not_change_result);
	tcase_add_test(solid, nested_shell_deleted);
	tcase_add_test(solid, nested_inward_shell_is_a_cavity);
	tcase_add_test(solid, part_inside_a_cavity_kept);
	tcase_add_loop_test(solid, touching_cubes_printable, 0, 3);
	tcase_add_test(solid, tiny_part_dropped);
	tcase_add_test(solid, inner_wire_discarded);
	tcase_add_test(solid, edge_touching_cubes_two_components);
	suite_add_tcase(s, solid);
	repair_sheet_tcases(s);
	return s;
}
