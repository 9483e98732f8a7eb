/*
 * check_thicken.c - the sheet thickening (repair/thicken.c) is closed by
 * construction, and the repair's second pass leaves no sheet on any open
 * surface.
 *
 * thicken_sheets is judged combinatorially: every directed edge of the
 * slab must be matched by the same edge the other way round as often (a
 * closed, consistently oriented surface), whatever the sheet: open, folded,
 * crossing itself, non-orientable, non-manifold.  The end-to-end tests run
 * the whole repair on every cube with one or two facets missing and on
 * open and non-orientable surfaces: the second pass must find no sheet.
 */
#include <check.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "fixtures.h"
#include "mesh.h"
#include "repair.h"
#include "suites.h"
#include "thicken.h"

#define EPS 0.4 /* mm */

struct dir_edge {
	uint32_t from, to;
};

static int compare_dir_edge(const void *a, const void *b)
{
	const struct dir_edge *x = a, *y = b;

	if (x->from != y->from)
		return x->from < y->from ? -1 : 1;
	return x->to < y->to ? -1 : x->to > y->to;
}

/* How often from -> to occurs in the sorted array e of n edges. */
static size_t count_edge(const struct dir_edge *e, size_t n, uint32_t from, uint32_t to)
{
	size_t lo = 0, hi = n, c = 0;

	while (lo < hi) {
		const size_t mid = lo + (hi - lo) / 2;
		if (e[mid].from < from || (e[mid].from == from && e[mid].to < to))
			lo = mid + 1;
		else
			hi = mid;
	}
	while (lo + c < n && e[lo + c].from == from && e[lo + c].to == to)
		c++;
	return c;
}

/* Which walls may skip the sheet's own edge (thicken_sheets' free_edges). */
enum free_walls { NO_FREE, SOME_FREE, ALL_FREE };

/*
 * Thicken every triangle of m and assert the slab is closed and oriented:
 * each directed edge as often as its reverse, no triangle repeating a
 * vertex, every copy within half of the sheet.  With SOME_FREE, edges are
 * marked free by a fixed pseudo-random pattern, so vertices where free and
 * held walls meet are covered.  Returns the slab's size.
 */
static size_t assert_closed_slab(const struct mesh *m, const char *name, enum free_walls walls)
{
	uint32_t *list = malloc((m->ntris + 1) * sizeof(*list));
	uint8_t *free_edges = malloc(m->ntris + 1);
	struct thick_out slab;
	struct st_error err = {0};
	struct dir_edge *e;
	size_t ne;
	int rc;

	ck_assert_ptr_nonnull(list);
	ck_assert_ptr_nonnull(free_edges);
	for (size_t t = 0; t < m->ntris; t++) {
		list[t] = (uint32_t)t;
		free_edges[t] = walls == ALL_FREE ? 7 : (uint8_t)((t * 2654435761u) >> 13 & 7);
	}
	rc = thicken_sheets((const double(*)[3])m->verts, (const uint32_t(*)[3])m->tris, list,
			    walls == NO_FREE ? NULL : free_edges, m->ntris, EPS / 2, 0, &slab,
			    &err);
	ck_assert_msg(rc == 0, "%s: thicken_sheets returned %d: %s", name, rc, err.msg);
	ne = 3 * slab.ntris;
	e = malloc((ne + 1) * sizeof(*e));
	ck_assert_ptr_nonnull(e);
	for (size_t t = 0; t < slab.ntris; t++) {
		const uint32_t *v = slab.tris[t];
		ck_assert_msg(v[0] != v[1] && v[1] != v[2] && v[0] != v[2],
			      "%s: slab triangle %zu repeats a vertex", name, t);
		for (int k = 0; k < 3; k++) {
			e[3 * t + (size_t)k].from = v[k];
			e[3 * t + (size_t)k].to = v[(k + 1) % 3];
		}
	}
	qsort(e, ne, sizeof(*e), compare_dir_edge);
	for (size_t i = 0; i < ne; i++) {
		const size_t fwd = count_edge(e, ne, e[i].from, e[i].to);
		const size_t back = count_edge(e, ne, e[i].to, e[i].from);
		ck_assert_msg(fwd == back, "%s: slab edge %u->%u occurs %zu times, back %zu", name,
			      e[i].from, e[i].to, fwd, back);
	}
	ck_assert_msg(slab.deviation <= EPS / 2 * (1 + 1e-9), "%s: copy %g from the sheet", name,
		      slab.deviation);
	const size_t n = slab.ntris;
	free(e);
	free(list);
	free(free_edges);
	free(slab.verts);
	free(slab.tris);
	free(slab.sheet_ref);
	return n;
}

/*
 * Proves that the slab of every cube with one or two facets missing (78
 * sheets with sharp 90-degree creases, which the old bevels left open) is
 * closed, also where walls along edges that touch nothing skip the sheet's
 * edge (fewer triangles) and where such walls meet held ones.
 */
START_TEST(open_cubes_slab_closed)
{
	for (int i = 0; i < 12; i++)
		for (int j = i; j < 12; j++) {
			struct mesh *m = fx_cube_without(10, (1u << i) | (1u << j));
			char name[32];
			snprintf(name, sizeof(name), "cube-%d-%d", i, j);
			const size_t held = assert_closed_slab(m, name, NO_FREE);
			ck_assert_uint_gt(held, 0);
			ck_assert_uint_le(assert_closed_slab(m, name, SOME_FREE), held);
			ck_assert_uint_lt(assert_closed_slab(m, name, ALL_FREE), held);
			mesh_free(m);
		}
}
END_TEST

/*
 * Proves closure on sheets that are hard for an offset: a non-orientable
 * Klein bottle, a torus and a sphere taken as sheets (every fan a closed
 * disk), a cone-like fan (a sphere's pole), a grid folded back on itself,
 * and random triangles (non-manifold, crossing, anything).
 */
START_TEST(hard_sheets_slab_closed)
{
	const double o[3] = {0, 0, 0}, u[3] = {10, 0, 0}, v[3] = {0, 10, 0};
	struct mesh *m[6];

	m[0] = fx_klein_bottle(3, 2.5, 24, 12);
	m[1] = fx_torus(10, 3, 16, 8);
	m[2] = fx_sphere(0, 0, 0, 5, 6, 8);
	m[3] = fx_grid(o, u, v, 6, 6);
	/* Fold the grid: the upper half is bent back over the lower one. */
	for (size_t i = 0; i < m[3]->nverts; i++)
		if (m[3]->verts[i][1] > 5) {
			const double y = m[3]->verts[i][1] - 5;
			m[3]->verts[i][1] = 5 - y * cos(2.9);
			m[3]->verts[i][2] = y * sin(2.9);
		}
	m[4] = fx_random_triangles(7, 60, 10);
	m[5] = fx_klein_bottle(3, 0.05, 16, 8);
	for (int i = 0; i < 6; i++) {
		char name[32];
		snprintf(name, sizeof(name), "sheet-%d", i);
		for (int w = NO_FREE; w <= ALL_FREE; w++)
			ck_assert_uint_gt(assert_closed_slab(m[i], name, (enum free_walls)w), 0);
		mesh_free(m[i]);
	}
}
END_TEST

/* The repair of m must succeed with a closed result and no second sheet. */
static void assert_repaired(const struct mesh *m, const char *name)
{
	struct repair_options opt;
	struct repair_report rep;
	struct st_error err = {0};
	struct mesh *out = NULL;
	int rc;

	repair_options_init(&opt);
	opt.epsilon = EPS;
	opt.keep_holes = true; /* the seed's pipeline: every hole thickened */
	rc = repair_mesh(m, &opt, &out, NULL, &rep, &err);
	ck_assert_msg(rc == 0, "%s: repair_mesh returned %d: %s", name, rc, err.msg);
	ck_assert_msg(rep.second_sheet_triangles == 0, "%s: %zu sheet triangles left", name,
		      rep.second_sheet_triangles);
	ck_assert_msg(rep.printable, "%s: not printable: %s", name, rep.why);
	mesh_free(out);
}

/*
 * Proves that every cube with one facet or two facets missing repairs to a
 * printable result without an internal error (before, 4 of 12 and 36 of
 * 66 ended in exit 70 "the second pass left N sheet triangles").
 */
START_TEST(open_cubes_repaired)
{
	for (int i = 0; i < 12; i++)
		for (int j = i; j < 12; j++) {
			struct mesh *m = fx_cube_without(10, (1u << i) | (1u << j));
			char name[32];
			snprintf(name, sizeof(name), "cube-%d-%d", i, j);
			assert_repaired(m, name);
			mesh_free(m);
		}
}
END_TEST

/* Proves the same for an open corner: three faces of a cube (6 facets). */
START_TEST(open_corner_repaired)
{
	struct mesh *m = fx_cube_without(10, 0xccc);

	assert_repaired(m, "corner");
	mesh_free(m);
}
END_TEST

/*
 * Proves that two triangles crossing through each other are thickened
 * whole, not as the pieces the first pass cut them into, and with plain
 * walls along edges that touch nothing: 2 x (2 faces + 3 walls of 2) = 16
 * triangles (the pieces gave 14 per piece), and the result is printable.
 */
START_TEST(crossing_sheets_thickened_whole)
{
	const double a[3] = {0, 0, 0}, b[3] = {10, 0, 0}, c[3] = {0, 10, 0};
	const double d[3] = {2, 2, -5}, e[3] = {2, 2, 5}, f[3] = {8, -3, 0.5};
	struct mesh *t1 = fx_triangle(a, b, c), *t2 = fx_triangle(d, e, f);
	struct mesh *m = fx_concat(t1, t2);
	struct repair_options opt;
	struct repair_report rep;
	struct st_error err = {0};
	struct mesh *out = NULL;

	repair_options_init(&opt);
	opt.epsilon = EPS;
	ck_assert_int_eq(repair_mesh(m, &opt, &out, NULL, &rep, &err), 0);
	ck_assert(rep.printable);
	ck_assert_uint_gt(rep.intersecting_pairs, 0);
	ck_assert_uint_gt(rep.sheet_triangles, 2);
	ck_assert_uint_eq(rep.thickened_triangles, 16);
	mesh_free(out);
	mesh_free(m);
	mesh_free(t1);
	mesh_free(t2);
}
END_TEST

Suite *thicken_suite(void)
{
	Suite *s = suite_create("thicken");
	TCase *slab = tcase_create("slab"), *repair = tcase_create("repair");

	tcase_add_test(slab, open_cubes_slab_closed);
	tcase_add_test(slab, hard_sheets_slab_closed);
	suite_add_tcase(s, slab);
	/* 79 small exact repairs; slow under ASan. */
	tcase_set_timeout(repair, 240);
	tcase_add_test(repair, open_cubes_repaired);
	tcase_add_test(repair, open_corner_repaired);
	tcase_add_test(repair, crossing_sheets_thickened_whole);
	suite_add_tcase(s, repair);
	return s;
}
