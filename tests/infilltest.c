/*
 * infilltest.c - the helpers of infilltest.h.
 */
#include <check.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "clip.h"
#include "infill.h"
#include "infilltest.h"
#include "mesh.h"
#include "patterns.h"
#include "perimeters.h"
#include "section.h"
#include "testutil.h"
#include "toolpath.h"

void run_infill(const struct mesh *m, double h, const struct infill_settings *is,
		struct run *r)
{
	struct st_error err = {0};
	struct perim_settings ps;
	struct layer_paths walls;

	r->st = NULL;
	ck_assert_msg(slice_mesh(m, h, h, NULL, &r->st, &err) == 0, "slice_mesh: %s", err.msg);
	perim_settings_init(&ps, 0.4);
	r->inner = calloc(r->st->n, sizeof(*r->inner));
	ck_assert_ptr_nonnull(r->inner);
	for (size_t i = 0; i < r->st->n; i++) {
		memset(&walls, 0, sizeof(walls));
		ck_assert_msg(perim_generate(&ps, &r->st->layers[i].regions, h, NULL, &walls,
					     &r->inner[i], NULL, &err) == 0,
			      "perim_generate: %s", err.msg);
		for (size_t k = 0; k < walls.n; k++)
			free(walls.paths[k].pts);
		free(walls.paths);
	}
	r->ls = layer_stack_new(r->st->n, &err);
	ck_assert_ptr_nonnull(r->ls);
	ck_assert_msg(infill_generate(is, r->st, r->inner, r->ls, &err) == 0, "infill: %s",
		      err.msg);
}

void run_free(struct run *r)
{
	for (size_t i = 0; i < r->st->n; i++)
		clip_expolys_free(&r->inner[i]);
	free(r->inner);
	layer_stack_free(r->ls);
	slice_stack_free(r->st);
}

/*
 * Flow-equivalent area (nm^2) of the paths of role on layer l: length x
 * the bead spacing of their width at height h (perim_spacing), i.e. the
 * deposited volume over h.
 */
double flow_area(const struct layer_paths *l, enum path_role role, double h)
{
	double a = 0;

	for (size_t i = 0; i < l->n; i++)
		if (l->paths[i].role == role)
			a += tu_path_length(&l->paths[i]) *
			     perim_spacing(l->paths[i].pts[0].width / NM, h) * NM;
	return a;
}

/* Sum of width x length (nm^2) of the paths of role on layer l. */
double bead_area(const struct layer_paths *l, enum path_role role)
{
	double a = 0;

	for (size_t i = 0; i < l->n; i++)
		if (l->paths[i].role == role)
			a += tu_path_length(&l->paths[i]) * (double)l->paths[i].pts[0].width;
	return a;
}

double region_area(const struct clip_expolys *ex)
{
	double a = 0;

	ck_assert_int_eq(clip_paths_area(&ex->paths, &a, NULL), 0);
	return a;
}

/*
 * Into all, the beads of the paths of the roles in mask on layer l, each
 * its width (or the given width when > 0) wide with ends as end.
 */
void beads_of(const struct layer_paths *l, unsigned mask, double width,
	      enum clip_end end, struct clip_paths *all)
{
	struct clip_paths line = {0}, bead = {0};

	for (size_t i = 0; i < l->n; i++) {
		const struct toolpath *p = &l->paths[i];
		if (!(mask & 1u << p->role))
			continue;
		int64_t *xy = malloc(2 * p->n * sizeof(*xy));
		ck_assert_ptr_nonnull(xy);
		for (size_t k = 0; k < p->n; k++) {
			xy[2 * k] = p->pts[k].x;
			xy[2 * k + 1] = p->pts[k].y;
		}
		clip_paths_clear(&line);
		ck_assert_int_eq(clip_paths_add(&line, xy, p->n, NULL), 0);
		free(xy);
		double w = width > 0 ? width : (double)p->pts[0].width;
		ck_assert_int_eq(clip_offset_open(&line, w / 2, CLIP_JOIN_ROUND, end, 2, ARC, &bead,
						  NULL),
				 0);
		ck_assert_int_eq(clip_paths_append(all, &bead, NULL), 0);
	}
	clip_paths_free(&line);
	clip_paths_free(&bead);
}

/* Area (nm^2) of the region ps covered by the beads of beads_of(l, ...). */
double covered_paths(const struct layer_paths *l, unsigned mask, double width,
		     enum clip_end end, const struct clip_paths *ps)
{
	struct clip_paths all = {0}, in = {0};
	double a = 0;

	beads_of(l, mask, width, end, &all);
	ck_assert_int_eq(clip_boolean(CLIP_INTERSECTION, &all, ps, CLIP_NONZERO, &in, NULL), 0);
	ck_assert_int_eq(clip_paths_area(&in, &a, NULL), 0);
	clip_paths_free(&all);
	clip_paths_free(&in);
	return a;
}

/* Area (nm^2) of region covered by the beads of beads_of(l, ...). */
double covered(const struct layer_paths *l, unsigned mask, double width,
	       enum clip_end end, const struct clip_expolys *region)
{
	return covered_paths(l, mask, width, end, &region->paths);
}

/* Is (x, y) inside or on the polygon set ps? */
bool inside(const struct clip_paths *ps, int64_t x, int64_t y)
{
	int parity = 0, where;

	for (size_t i = 0; i < ps->n; i++) {
		ck_assert_int_eq(clip_point_in_polygon(x, y, clip_path_xy(ps, i),
						       clip_path_len(ps, i), &where, NULL),
				 0);
		if (where < 0)
			return true;
		parity ^= where;
	}
	return parity != 0;
}

/* Every point of every path of layer l lies in region grown by d nm. */
void assert_inside(const struct layer_paths *l, const struct clip_expolys *region, double d)
{
	struct clip_paths g = {0};

	ck_assert_int_eq(clip_offset(&region->paths, d, CLIP_JOIN_ROUND, 0, ARC, &g, NULL), 0);
	for (size_t i = 0; i < l->n; i++)
		for (size_t k = 0; k < l->paths[i].n; k++)
			ck_assert_msg(inside(&g, l->paths[i].pts[k].x, l->paths[i].pts[k].y),
				      "path %zu point %zu (%g, %g) mm outside the region", i, k,
				      l->paths[i].pts[k].x / NM, l->paths[i].pts[k].y / NM);
	clip_paths_free(&g);
}

