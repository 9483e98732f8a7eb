/*
 * check_infill_solid.c - skins and infill, part of the infill suite
 * (check_infill.c, the same "infill" case): shells as thick as asked,
 * small regions and full density solid, a narrow strip as one bead, the
 * gyroid's chords within tolerance, and bad settings refused.
 */
#include <check.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "clip.h"
#include "fixtures.h"
#include "infill.h"
#include "infilltest.h"
#include "mesh.h"
#include "patterns.h"
#include "perimeters.h"
#include "section.h"
#include "suites.h"
#include "testutil.h"
#include "toolpath.h"

/* A square column of layers of the given heights, 10 mm wide, walls 1 mm. */
static struct slice_stack *column(const double *heights, size_t n, struct clip_expolys *inner)
{
	struct slice_stack *st = calloc(1, sizeof(*st));
	const int64_t sq[] = {0, 0, 10 * NM, 0, 10 * NM, 10 * NM, 0, 10 * NM};
	struct clip_paths p = {0};
	double z = 0;

	ck_assert_ptr_nonnull(st);
	st->layers = calloc(n, sizeof(*st->layers));
	ck_assert_ptr_nonnull(st->layers);
	st->n = n;
	ck_assert_int_eq(clip_paths_add(&p, sq, 4, NULL), 0);
	for (size_t i = 0; i < n; i++) {
		z += heights[i];
		st->layers[i].z = z;
		st->layers[i].height = heights[i];
		st->layers[i].slice_z = z - heights[i] / 2;
		ck_assert_int_eq(clip_boolean_ex(CLIP_UNION, &p, NULL, CLIP_NONZERO,
						 &st->layers[i].regions, NULL),
				 0);
		ck_assert_int_eq(clip_offset_ex(&p, -1 * NM, CLIP_JOIN_MITER, 2, 0, &inner[i], NULL),
				 0);
	}
	clip_paths_free(&p);
	return st;
}

/* Layers (bottom, top) whose infill has the bottom / top skin role. */
static void skin_layers(const struct infill_settings *is, const double *heights, size_t n,
			size_t *nbottom, size_t *ntop)
{
	struct clip_expolys inner[40];

	memset(inner, 0, sizeof(inner));
	struct slice_stack *st;
	struct layer_stack *ls = layer_stack_new(n, NULL);
	struct st_error err = {0};

	ck_assert(n <= 40 && ls);
	st = column(heights, n, inner);
	ck_assert_msg(infill_generate(is, st, inner, ls, &err) == 0, "infill: %s", err.msg);
	*nbottom = *ntop = 0;
	for (size_t i = 0; i < n; i++) {
		*nbottom += tu_count_role(&ls->layers[i], PATH_BOTTOM_SKIN) > 0;
		*ntop += tu_count_role(&ls->layers[i], PATH_TOP_SKIN) > 0;
		/* A layer is one class: all solid or all sparse here. */
		ck_assert(tu_count_role(&ls->layers[i], PATH_SPARSE_INFILL) == 0 ||
			  tu_count_role(&ls->layers[i], PATH_SPARSE_INFILL) == ls->layers[i].n);
		clip_expolys_free(&inner[i]);
	}
	layer_stack_free(ls);
	slice_stack_free(st);
}

START_TEST(shells_by_thickness)
{
	struct infill_settings is;
	double hs[30];
	size_t nb, nt;

	/* 12 layers of 0.1 mm, then 10 of 0.3 mm. */
	for (size_t i = 0; i < 22; i++)
		hs[i] = i < 12 ? 0.1 : 0.3;
	infill_settings_init(&is, 0.4);
	/* Reference 0.2 mm: 3 layers = 0.6 mm = 6 thin layers at the bottom, 2 thick on top. */
	is.layer_height = 0.2;
	skin_layers(&is, hs, 22, &nb, &nt);
	ck_assert_uint_eq(nb, 6);
	ck_assert_uint_eq(nt, 2);
	/* Default reference: the most common height, 0.1 mm: 0.3 mm shells. */
	is.layer_height = 0;
	skin_layers(&is, hs, 22, &nb, &nt);
	ck_assert_uint_eq(nb, 3);
	ck_assert_uint_eq(nt, 1);
	/* A minimum thickness wins over the count. */
	is.top_solid_min_thickness = 0.9;
	is.bottom_solid_min_thickness = 0.55;
	skin_layers(&is, hs, 22, &nb, &nt);
	ck_assert_uint_eq(nb, 6);
	ck_assert_uint_eq(nt, 3);
	/* No shells asked: no skins, sparse up to the top. */
	is.top_solid_min_thickness = is.bottom_solid_min_thickness = 0;
	is.top_solid_layers = is.bottom_solid_layers = 0;
	skin_layers(&is, hs, 22, &nb, &nt);
	ck_assert_uint_eq(nb, 1); /* layer 0 always rests on the bed */
	ck_assert_uint_eq(nt, 0);
}
END_TEST

START_TEST(small_and_full_density_are_solid)
{
	struct infill_settings is;
	double hs[10];
	struct clip_expolys inner[10];

	memset(inner, 0, sizeof(inner));
	struct st_error err = {0};

	for (size_t i = 0; i < 10; i++)
		hs[i] = 0.2;
	for (int pass = 0; pass < 2; pass++) {
		struct slice_stack *st = column(hs, 10, inner);
		struct layer_stack *ls = layer_stack_new(10, NULL);
		infill_settings_init(&is, 0.4);
		if (pass == 0)
			is.fill_density = 100; /* then: an 8 x 8 mm island < 70 mm^2 */
		is.solid_infill_below_area = pass == 0 ? 0 : 70;
		ck_assert_int_eq(infill_generate(&is, st, inner, ls, &err), 0);
		const struct layer_paths *l = &ls->layers[5];
		ck_assert_uint_eq(tu_count_role(l, PATH_SPARSE_INFILL), 0);
		ck_assert_uint_gt(tu_count_role(l, PATH_SOLID_INFILL), 0);
		double A = region_area(&inner[5]);
		ck_assert(covered(l, SOLID_ROLES, 0, CLIP_END_ROUND, &inner[5]) / A >= 0.99);
		for (size_t i = 0; i < 10; i++)
			clip_expolys_free(&inner[i]);
		layer_stack_free(ls);
		slice_stack_free(st);
	}
}
END_TEST

/*
 * A strip 0.33 mm wide given to infill (the walls take such a strip up
 * inside a 2 mm wall, perimeters.h; a region split by the infill classes
 * can still leave one), narrower than a solid line's spacing: one
 * centre-line bead fills it, where lines across it left dashes with voids
 * between.
 */
START_TEST(narrow_strip_gets_one_bead)
{
	struct mesh *m = fx_box(0, 0, 0, 20, 0.33, 10);
	struct infill_settings is;
	struct st_error err = {0};
	struct run r;
	const double h = 0.2;

	infill_settings_init(&is, 0.4);
	ck_assert_msg(slice_mesh(m, h, h, NULL, &r.st, &err) == 0, "slice_mesh: %s", err.msg);
	r.inner = calloc(r.st->n, sizeof(*r.inner));
	ck_assert_ptr_nonnull(r.inner);
	for (size_t i = 0; i < r.st->n; i++)
		ck_assert_int_eq(clip_boolean_ex(CLIP_UNION, &r.st->layers[i].regions.paths, NULL,
						 CLIP_NONZERO, &r.inner[i], &err),
				 0);
	r.ls = layer_stack_new(r.st->n, &err);
	ck_assert_ptr_nonnull(r.ls);
	ck_assert_msg(infill_generate(&is, r.st, r.inner, r.ls, &err) == 0, "infill: %s", err.msg);
	for (size_t i = 5; i < 45; i++) {
		const struct layer_paths *l = &r.ls->layers[i];
		double A = region_area(&r.inner[i]);
		size_t lines = 0, beads = 0;
		ck_assert_msg(A > 0.3 * 18 * NM * NM && A < 0.4 * 19 * NM * NM,
			      "layer %zu: %g mm2 inside the walls", i, A / NM / NM);
		for (size_t k = 0; k < l->n; k++) {
			lines += l->paths[k].role == PATH_SOLID_INFILL;
			beads += l->paths[k].role == PATH_GAP_FILL;
		}
		ck_assert_msg(lines == 0 && beads >= 1, "layer %zu: %zu solid lines, %zu beads", i,
			      lines, beads);
		double cov = covered(l, SOLID_ROLES, 0, CLIP_END_ROUND, &r.inner[i]) / A;
		ck_assert_msg(cov > 0.99, "layer %zu: %.4f of the strip covered", i, cov);
	}
	run_free(&r);
	mesh_free(m);
}
END_TEST

/* Distance (nm) from bed point (X, Y) at height Z (nm) to the gyroid
 * section at scale k, to first order: |f| / |grad f| in the plane; a
 * negative value where the gradient nearly vanishes (branches meet). */
static double gyroid_distance(double k, double X, double Y, double Z)
{
	double x = k * X, y = k * Y, z = k * Z;
	double f = sin(x) * cos(y) + sin(y) * cos(z) + sin(z) * cos(x);
	double fx = cos(x) * cos(y) - sin(z) * sin(x), fy = -sin(x) * sin(y) + cos(y) * cos(z);
	double g = hypot(fx, fy);
	return g < 0.3 ? -1 : fabs(f) / g / k;
}

/* (X, Y) moved onto the gyroid section at height Z (nm, scale k) by two
 * Newton steps along the gradient in the plane. */
static void gyroid_project(double k, double *X, double *Y, double Z)
{
	for (int it = 0; it < 2; it++) {
		double x = k * *X, y = k * *Y, z = k * Z;
		double f = sin(x) * cos(y) + sin(y) * cos(z) + sin(z) * cos(x);
		double fx = cos(x) * cos(y) - sin(z) * sin(x), fy = -sin(x) * sin(y) + cos(y) * cos(z);
		double g2 = fx * fx + fy * fy;
		*X -= f * fx / g2 / k;
		*Y -= f * fy / g2 / k;
	}
}

/*
 * The gyroid's chords stay within PAT_GYROID_TOLERANCE_NM of the curve,
 * and use most of it: sampled finer than sparse infill needs (10 um), the
 * gyroid was written in 1.7 times PrusaSlicer's moves.  They are as long
 * as the curve (measured along it, 16 points a chord projected onto it):
 * their ends moved across it (simplify_balance), where chords with their
 * ends on the curve are shorter, and at 75 um the sparse infill printed
 * that much less line (docs/benchmarks.md, the region check's voids).
 */
START_TEST(gyroid_chords_within_tolerance)
{
	struct st_error err = {0};
	const double k = 0.2 / (0.45e6 * PAT_GYROID_LENGTH); /* 20 %, 0.45 mm lines */
	struct pat_box box = {0, 0, 20000000, 20000000};
	double worst = 0, length = 0, curve = 0;
	size_t chords = 0;
	for (int layer = 0; layer < 12; layer++) {
		double z = 0.2e6 * (layer * 7 + 1);
		struct clip_paths lines = {0};
		ck_assert_int_eq(pat_gyroid(k, z, &box, &lines, &err), 0);
		for (size_t p = 0; p < lines.n; p++) {
			const int64_t *xy = lines.xy + 2 * lines.start[p];
			size_t n = lines.start[p + 1] - lines.start[p];
			double px = NAN, py = NAN;
			for (size_t i = 0; i + 1 < n; i++, chords++) {
				double dx = (double)(xy[2 * i + 2] - xy[2 * i]);
				double dy = (double)(xy[2 * i + 3] - xy[2 * i + 1]);
				length += hypot(dx, dy);
				for (int j = 0; j <= 16; j++) {
					double X = xy[2 * i] + dx * j / 16.0, Y = xy[2 * i + 1] + dy * j / 16.0;
					if (j % 2 == 0 && j > 0 && j < 16) /* the chord's eighths */
						worst = fmax(worst, gyroid_distance(k, X, Y, z));
					gyroid_project(k, &X, &Y, z);
					if (j && !isnan(px))
						curve += hypot(X - px, Y - py);
					px = X;
					py = Y;
				}
			}
		}
		clip_paths_free(&lines);
	}
	/* first order, and the 48 samples a period: a few per cent over */
	ck_assert_msg(worst <= 1.05 * PAT_GYROID_TOLERANCE_NM, "a chord %.0f nm off the curve",
		      worst);
	ck_assert_msg(worst > 0.5 * PAT_GYROID_TOLERANCE_NM, "chords at most %.0f nm off: finer "
		      "than the tolerance asks", worst);
	/* 0.95 mm at 75 um, 0.66 mm at 50 um; 10 um gave half that, twice
	 * the moves */
	ck_assert_msg(length / (double)chords > 0.8e6, "mean chord %.3f mm",
		      length / (double)chords / 1e6);
	/* 1.0026 across the curve; 0.9925 with their ends on it */
	ck_assert_msg(fabs(length / curve - 1) < 0.004, "chords %.4f times the curve's length",
		      length / curve);
}
END_TEST

START_TEST(bad_settings_refused)
{
	struct infill_settings is;
	struct st_error err = {0};
	enum infill_pattern p = INFILL_GRID;
	double hs[4] = {0.2, 0.2, 0.2, 0.2};
	struct clip_expolys inner[4];

	memset(inner, 0, sizeof(inner));

	infill_settings_init(&is, 0.4);
	ck_assert_int_eq(infill_settings_check(&is, &err), 0);
	ck_assert(fabs(is.infill_extrusion_width - 0.45) < 1e-15);
	is.fill_density = 101;
	ck_assert_int_eq(infill_settings_check(&is, &err), ST_ERR_RANGE);
	ck_assert_ptr_nonnull(strstr(err.msg, "fill_density 101"));
	ck_assert_ptr_nonnull(strstr(err.msg, "0 to 100"));
	is.fill_density = -5;
	ck_assert_int_eq(infill_settings_check(&is, &err), ST_ERR_RANGE);
	ck_assert_ptr_nonnull(strstr(err.msg, "fill_density -5"));
	is.fill_density = NAN;
	ck_assert_int_eq(infill_settings_check(&is, &err), ST_ERR_RANGE);
	infill_settings_init(&is, 0.4);
	is.top_solid_layers = -1;
	ck_assert_int_eq(infill_settings_check(&is, &err), ST_ERR_RANGE);
	ck_assert_ptr_nonnull(strstr(err.msg, "top_solid_layers -1"));
	infill_settings_init(&is, 0.4);
	is.bottom_solid_min_thickness = -0.1;
	ck_assert_int_eq(infill_settings_check(&is, &err), ST_ERR_RANGE);
	infill_settings_init(&is, 0.4);
	is.infill_extrusion_width = 0;
	ck_assert_int_eq(infill_settings_check(&is, &err), ST_ERR_RANGE);
	ck_assert_ptr_nonnull(strstr(err.msg, "infill_extrusion_width"));
	infill_settings_init(&is, 0.4);
	is.fill_pattern = INFILL_PATTERNS;
	ck_assert_int_eq(infill_settings_check(&is, &err), ST_ERR_ARG);
	/* Names: PrusaSlicer's, three printed, the others refused as unsupported. */
	ck_assert_int_eq(infill_pattern_parse("gyroid", &p, &err), 0);
	ck_assert_int_eq(p, INFILL_GYROID);
	ck_assert_int_eq(infill_pattern_parse("rectilinear", &p, &err), 0);
	ck_assert_int_eq(p, INFILL_RECTILINEAR);
	ck_assert_str_eq(infill_pattern_name(INFILL_GRID), "grid");
	ck_assert_int_eq(infill_pattern_parse("stars", &p, &err), 0);
	ck_assert_int_eq(p, INFILL_STARS);
	ck_assert_int_eq(infill_pattern_parse("honeycomb", &p, &err), 0);
	ck_assert_int_eq(p, INFILL_HONEYCOMB);
	ck_assert_int_eq(infill_pattern_parse("line", &p, &err), 0);
	ck_assert_int_eq(p, INFILL_LINE);
	ck_assert_int_eq(infill_pattern_parse("concentric", &p, &err), 0);
	ck_assert_int_eq(p, INFILL_CONCENTRIC);
	ck_assert_int_eq(infill_pattern_parse("3dhoneycomb", &p, &err), ST_ERR_UNSUPPORTED);
	ck_assert_ptr_nonnull(strstr(err.msg, "\"3dhoneycomb\" is not supported"));
	ck_assert_ptr_nonnull(strstr(err.msg, "stars, cubic, line, concentric or honeycomb"));
	p = INFILL_RECTILINEAR;
	ck_assert_int_eq(infill_pattern_parse("spaghetti", &p, &err), ST_ERR_ARG);
	ck_assert_ptr_nonnull(strstr(err.msg, "\"spaghetti\" is unknown"));
	ck_assert_int_eq(p, INFILL_RECTILINEAR); /* untouched on error */
	/* infill_generate refuses too, and adds nothing. */
	struct slice_stack *st = column(hs, 4, inner);
	struct layer_stack *ls = layer_stack_new(4, NULL);
	infill_settings_init(&is, 0.4);
	is.fill_density = 150;
	ck_assert_int_eq(infill_generate(&is, st, inner, ls, &err), ST_ERR_RANGE);
	for (size_t i = 0; i < 4; i++)
		ck_assert_uint_eq(ls->layers[i].n, 0);
	infill_settings_init(&is, 0.4);
	st->layers[2].height = 0.5;
	ck_assert_int_eq(infill_generate(&is, st, inner, ls, &err), ST_ERR_RANGE);
	ck_assert_ptr_nonnull(strstr(err.msg, "layer 2"));
	layer_stack_free(ls);
	ls = layer_stack_new(3, NULL);
	st->layers[2].height = 0.2;
	ck_assert_int_eq(infill_generate(&is, st, inner, ls, &err), ST_ERR_ARG);
	for (size_t i = 0; i < 4; i++)
		clip_expolys_free(&inner[i]);
	layer_stack_free(ls);
	slice_stack_free(st);
}
END_TEST

/* The tests of the "infill" case on solid layers and settings, in their place. */
void infill_solid_tests(TCase *tc)
{
	tcase_add_test(tc, shells_by_thickness);
	tcase_add_test(tc, small_and_full_density_are_solid);
	tcase_add_test(tc, narrow_strip_gets_one_bead);
	tcase_add_test(tc, bad_settings_refused);
	tcase_add_test(tc, gyroid_chords_within_tolerance);
}
