/*
 * check_shells.c - the vertical shells of sloped surfaces (part of the
 * infill suite): the shells are counted through every layer's whole region
 * (infill.h), so no sparse infill lies within top_solid_layers of air above
 * it or bottom_solid_layers of air below it, however steep the slope:
 * PrusaSlicer's ensure_vertical_shell_thickness = 1, which the profile
 * loader therefore takes as honoured.
 */
#include <check.h>
#include <stdlib.h>
#include <string.h>

#include "clip.h"
#include "fixtures.h"
#include "infill.h"
#include "perimeters.h"
#include "section.h"
#include "suites.h"
#include "toolpath.h"

/* Sparse points of a sphere's infill (shells of n layers above and below)
 * that lie outside a layer within `within` of theirs. */
static size_t points_without_shell(int n, size_t within)
{
	const double h = 0.2;
	struct st_error err = {0};
	struct mesh *m = fx_sphere(0, 0, 10, 10, 48, 96);
	struct slice_stack *st = NULL;
	struct infill_settings is;
	struct perim_settings ps;
	struct clip_expolys *inner;
	struct clip_locator **loc;
	struct layer_stack *ls;
	size_t bad = 0;

	ck_assert_msg(slice_mesh(m, h, h, NULL, &st, &err) == 0, "slice_mesh: %s", err.msg);
	mesh_free(m);
	perim_settings_init(&ps, 0.4);
	infill_settings_init(&is, 0.4);
	is.top_solid_layers = is.bottom_solid_layers = n;
	is.solid_infill_below_area = 0; /* only the shells make solid infill */
	inner = calloc(st->n, sizeof(*inner));
	loc = calloc(st->n, sizeof(*loc));
	ls = layer_stack_new(st->n, &err);
	ck_assert(inner && loc && ls);
	for (size_t i = 0; i < st->n; i++) {
		struct layer_paths walls = {0};

		ck_assert_msg(perim_generate(&ps, &st->layers[i].regions, h, NULL, &walls, &inner[i], NULL,
					     &err) == 0,
			      "walls: %s", err.msg);
		layer_paths_clear(&walls);
		loc[i] = clip_locator_new(&st->layers[i].regions.paths, &err);
		ck_assert_ptr_nonnull(loc[i]);
	}
	ck_assert_msg(infill_generate(&is, st, inner, ls, &err) == 0, "infill: %s", err.msg);
	for (size_t i = 0; i < st->n; i++) {
		const struct layer_paths *l = &ls->layers[i];
		size_t lo = i >= within ? i - within : 0;
		size_t hi = i + within < st->n ? i + within : st->n - 1;

		for (size_t p = 0; p < l->n; p++) {
			if (l->paths[p].role != PATH_SPARSE_INFILL)
				continue;
			for (size_t k = 0; k < l->paths[p].n; k++)
				for (size_t j = lo; j <= hi; j++)
					if (!clip_locator_inside(loc[j], l->paths[p].pts[k].x,
								 l->paths[p].pts[k].y)) {
						bad++;
						break;
					}
		}
	}
	for (size_t i = 0; i < st->n; i++) {
		clip_locator_free(loc[i]);
		clip_expolys_free(&inner[i]);
	}
	free(loc);
	free(inner);
	layer_stack_free(ls);
	slice_stack_free(st);
	return bad;
}

/* Three layers of shell over and under a sphere's slopes: every sparse
 * point has part above and below it for three layers; with one layer of
 * shell the same check finds points with air within three (so it can fail). */
START_TEST(slopes_keep_vertical_shells)
{
	size_t bad3 = points_without_shell(3, 3), bad1 = points_without_shell(1, 3);

	ck_assert_msg(bad3 == 0, "%zu sparse points within 3 layers of air", bad3);
	ck_assert_msg(bad1 > 0, "one layer of shell kept three");
}
END_TEST

void infill_shell_tcases(Suite *s)
{
	TCase *tc = tcase_create("shells");

	tcase_set_timeout(tc, 60);
	tcase_add_test(tc, slopes_keep_vertical_shells);
	suite_add_tcase(s, tc);
}
