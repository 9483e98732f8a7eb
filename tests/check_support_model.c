/*
 * check_support_model.c - support standing on the model, its gaps and
 * interfaces, bridges left alone, the pattern's angle and spacing, and
 * the shelf end to end: `stratum slice` checked by the region verifier
 * (region.h, region_support_check).
 */
#include <check.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fixtures.h"
#include "mesh.h"
#include "meshio.h"
#include "perimeters.h"
#include "region.h"
#include "section.h"
#include "suites.h"
#include "support.h"
#include "testutil.h"
#include "toolpath.h"

#define NM SLICE_UNITS_PER_MM
#define TOL 5000.0 /* nm: arc tolerance, rounding to the nm grid, slack */
#define STEP_TOP 2.0 /* mm, the shelf's lower step */

/* The shelf (fixtures.h): its step's top is at z 2, the plate overhangs
 * the step at x 4-12 and the bed at x 12-20 from z 9. */
static struct mesh *shelf(void)
{
	return fx_shelf();
}

/* A bridge: pillars at x 0-4 and 14-18, a deck at z 9-10 over x 0-18. */
static struct mesh *bridge(void)
{
	struct mesh *a = fx_box(0, 0, 0, 4, 10, 10), *b = fx_box(14, 0, 0, 18, 10, 10);
	struct mesh *deck = fx_box(0, 0, 9, 18, 10, 10);
	struct mesh *ab = fx_concat(a, b), *m = fx_concat(ab, deck);

	mesh_free(a);
	mesh_free(b);
	mesh_free(deck);
	mesh_free(ab);
	return m;
}

static struct slice_stack *slice_ok(const struct mesh *m)
{
	struct st_error err = {0};
	struct slice_stack *st = NULL;

	ck_assert_msg(slice_mesh(m, 0.2, 0.2, NULL, &st, &err) == 0, "slice_mesh: %s", err.msg);
	return st;
}

static struct layer_stack *support_ok(const struct support_settings *s,
				      const struct slice_stack *st)
{
	struct layer_stack *ls = layer_stack_new(st->n, NULL);
	struct st_error err = {0};

	ck_assert_ptr_nonnull(ls);
	for (size_t i = 0; i < st->n; i++) {
		ls->layers[i].z = st->layers[i].z;
		ls->layers[i].height = st->layers[i].height;
	}
	ck_assert_msg(support_generate(s, st, ls, &err) == 0, "support_generate: %s", err.msg);
	return ls;
}

static struct support_settings on(void)
{
	struct support_settings s;

	support_settings_init(&s, 0.4);
	s.support_material = true;
	return s;
}

/* Paths of layer l with a point at x < 12 mm (over the step), by role. */
static void over_step(const struct layer_paths *l, size_t *body, size_t *face)
{
	*body = *face = 0;
	for (size_t i = 0; i < l->n; i++)
		for (size_t k = 0; k < l->paths[i].n; k++)
			if (l->paths[i].pts[k].x < 12 * NM) {
				*(l->paths[i].role == PATH_SUPPORT_INTERFACE ? face : body) += 1;
				break;
			}
}

/* The lowest layer with support over the step, or the layer count. */
static size_t lowest_over_step(const struct layer_stack *ls)
{
	for (size_t j = 0; j < ls->nlayers; j++) {
		size_t b, f;
		over_step(&ls->layers[j], &b, &f);
		if (b + f)
			return j;
	}
	return ls->nlayers;
}

/* No support bead on any layer comes nearer the model on that layer than
 * the xy spacing (less the tolerance): nothing is printed inside the part. */
static void assert_clear_of_model(const struct support_settings *s, const struct slice_stack *st,
				  const struct layer_stack *ls)
{
	struct st_error err = {0};
	struct clip_paths beads = {0}, near = {0}, x = {0};

	for (size_t j = 0; j < st->n; j++) {
		double a = 0;
		ck_assert_int_eq(support_beads(&ls->layers[j], 2000, &beads, &err), 0);
		ck_assert_int_eq(clip_offset(&st->layers[j].regions.paths,
					     s->support_material_xy_spacing * NM - TOL, CLIP_JOIN_ROUND,
					     2.0, 2000, &near, &err),
				 0);
		ck_assert_int_eq(clip_boolean(CLIP_INTERSECTION, &beads, &near, CLIP_NONZERO, &x, &err),
				 0);
		ck_assert_int_eq(clip_paths_area(&x, &a, &err), 0);
		ck_assert_msg(a < 1e-3 * NM * NM, "layer %zu: %.4f mm^2 of support in the part", j,
			      a / NM / NM);
	}
	clip_paths_free(&beads);
	clip_paths_free(&near);
	clip_paths_free(&x);
}

START_TEST(shelf_support_stands_on_the_step)
{
	struct mesh *m = shelf();
	struct slice_stack *st = slice_ok(m);

	for (int style = 0; style < SUPPORT_STYLES; style++) {
		struct support_settings s = on();
		s.support_material_style = style;
		struct layer_stack *ls = support_ok(&s, st);
		size_t low = lowest_over_step(ls), b, f;
		/* The bottom gap (0 = the top's 0.2 mm): one empty layer over the
		 * step's top at z 2.0, support from layer 11 (z 2.2-2.4) up to 43. */
		ck_assert_uint_eq(low, 11);
		ck_assert(fabs(st->layers[low].z - st->layers[low].height - STEP_TOP -
			       s.support_material_contact_distance) < 1e-6);
		for (size_t j = low; j < 44; j++) {
			over_step(&ls->layers[j], &b, &f);
			ck_assert_msg(b + f > 0, "layer %zu: nothing over the step", j);
			/* three bottom interface layers (-1 = as many as on top) */
			if (j < low + 3)
				ck_assert_msg(f > 0 && b == 0, "layer %zu: %zu body %zu interface", j, b, f);
			else if (j < 41)
				ck_assert_msg(b > 0 && f == 0, "layer %zu: %zu body %zu interface", j, b, f);
		}
		ck_assert_uint_eq(ls->layers[44].n, 0);
		assert_clear_of_model(&s, st, ls);
		layer_stack_free(ls);
	}
	slice_stack_free(st);
	mesh_free(m);
}
END_TEST

/* The lowest layer of s's support over the step, which keeps clear of the model. */
static size_t lowest_with(const struct support_settings *s, const struct slice_stack *st)
{
	struct layer_stack *ls = support_ok(s, st);
	size_t low = lowest_over_step(ls);

	assert_clear_of_model(s, st, ls);
	layer_stack_free(ls);
	return low;
}

START_TEST(shelf_bottom_gap_and_interfaces)
{
	struct mesh *m = shelf();
	struct slice_stack *st = slice_ok(m);
	struct support_settings s = on();
	struct layer_stack *ls;
	size_t b, f;

	/* A 0.4 mm bottom gap: two empty layers over the step. */
	s.support_material_bottom_contact_distance = 0.4;
	ck_assert_uint_eq(lowest_with(&s, st), 12);
	/* A top gap of 0 (soluble) leaves no bottom gap either. */
	s = on();
	s.support_material_contact_distance = 0;
	ck_assert_uint_eq(lowest_with(&s, st), 10);
	/* No bottom interface layers: body down to the foot. */
	s = on();
	s.support_material_bottom_interface_layers = 0;
	ls = support_ok(&s, st);
	over_step(&ls->layers[11], &b, &f);
	ck_assert(b > 0 && f == 0);
	layer_stack_free(ls);
	slice_stack_free(st);
	mesh_free(m);
}
END_TEST

START_TEST(shelf_buildplate_only_drops_the_step)
{
	struct mesh *m = shelf();
	struct slice_stack *st = slice_ok(m);
	struct support_settings s = on();

	s.support_material_buildplate_only = true;
	struct layer_stack *ls = support_ok(&s, st);
	double w = s.extrusion_width * NM, clear = s.support_material_xy_spacing * NM;
	size_t n = 0;
	ck_assert_uint_eq(lowest_over_step(ls), ls->nlayers);
	for (size_t j = 0; j < ls->nlayers; j++)
		for (size_t i = 0; i < ls->layers[j].n; i++, n++)
			for (size_t k = 0; k < ls->layers[j].paths[i].n; k++)
				ck_assert(ls->layers[j].paths[i].pts[k].x >= 12 * NM + clear + w / 2 - TOL);
	ck_assert_uint_gt(n, 40); /* the plate is held from the bed at x 12-20 */
	layer_stack_free(ls);
	slice_stack_free(st);
	mesh_free(m);
}
END_TEST

/* Support paths over every layer of the bridge model. */
static size_t bridge_support(bool dont)
{
	struct mesh *m = bridge();
	struct slice_stack *st = slice_ok(m);
	struct support_settings s = on();
	size_t n = 0;

	s.dont_support_bridges = dont;
	struct layer_stack *ls = support_ok(&s, st);
	for (size_t j = 0; j < ls->nlayers; j++) {
		n += ls->layers[j].n;
		for (size_t i = 0; i < ls->layers[j].n; i++)
			for (size_t k = 0; k < ls->layers[j].paths[i].n; k++) {
				int64_t x = ls->layers[j].paths[i].pts[k].x;
				ck_assert(x > 4 * NM && x < 14 * NM); /* under the span only */
			}
	}
	layer_stack_free(ls);
	slice_stack_free(st);
	mesh_free(m);
	return n;
}

START_TEST(bridge_left_unsupported)
{
	ck_assert_uint_eq(bridge_support(true), 0);
	ck_assert_uint_gt(bridge_support(false), 40);
	/* A cantilever is no bridge: the shelf keeps its support with the
	 * default dont_support_bridges = 1 (the tests above). */
	struct support_settings s = on();
	ck_assert(s.dont_support_bridges);
}
END_TEST

START_TEST(pattern_angle_and_interface_spacing)
{
	struct mesh *m = shelf();
	struct slice_stack *st = slice_ok(m);
	struct support_settings s = on();

	s.support_material_angle = 30;
	s.support_material_interface_spacing = 1.0;
	struct layer_stack *ls = support_ok(&s, st);
	size_t turned = 0, faces = 0;
	/* Every segment a millimetre long or more is a line at 30 degrees, or a
	 * link between two body lines along the shelf's straight sides. */
	for (size_t j = 0; j < ls->nlayers; j++)
		for (size_t i = 0; i < ls->layers[j].n; i++) {
			const struct toolpath *p = &ls->layers[j].paths[i];
			for (size_t k = 0; k + 1 < p->n && !p->closed; k++) {
				double dx = (double)(p->pts[k + 1].x - p->pts[k].x);
				double dy = (double)(p->pts[k + 1].y - p->pts[k].y);
				double a = fmod(atan2(dy, dx) * 180.0 / M_PI + 360.0, 90.0);
				if (hypot(dx, dy) < 1.0 * NM)
					continue;
				ck_assert_msg(fabs(a - 30.0) < 0.1 || fmin(a, 90.0 - a) < 0.1,
					      "layer %zu: a line at %.2f degrees", j, a);
				turned += fabs(a - 30.0) < 0.1;
			}
		}
	ck_assert_uint_gt(turned, 100);
	/* Interface lines 1 mm apart edge to edge: a pitch of 1 mm plus the
	 * flow spacing, on the plate's top interface layer (43, odd: lines at
	 * 30 + 90 degrees, so 30 degrees across them), each a segment over a
	 * millimetre long (the links between them along the edge are not). */
	const struct layer_paths *l = &ls->layers[43];
	double pitch = (1.0 + perim_spacing(s.extrusion_width, 0.2)) * NM;
	const struct path_point *first = NULL;
	for (size_t i = 0; i < l->n; i++)
		for (size_t k = 0; l->paths[i].role == PATH_SUPPORT_INTERFACE && k + 1 < l->paths[i].n;
		     k++) {
			const struct path_point *p = &l->paths[i].pts[k], *q = p + 1;
			double along = (q->x - p->x) * cos(2 * M_PI / 3) + (q->y - p->y) * sin(2 * M_PI / 3);
			double side = (q->x - p->x) * cos(M_PI / 6) + (q->y - p->y) * sin(M_PI / 6);
			if (fabs(along) < 1.0 * NM || fabs(side) > 0.01 * NM)
				continue;
			if (!first)
				first = p;
			double across = fabs((p->x - first->x) * cos(M_PI / 6) +
					     (p->y - first->y) * sin(M_PI / 6));
			faces++;
			ck_assert_msg(fabs(fmod(across + pitch / 2, pitch) - pitch / 2) < 0.01 * NM,
				      "interface lines %.4f mm apart, pitch %.4f", across / NM,
				      pitch / NM);
		}
	ck_assert_uint_gt(faces, 3);
	layer_stack_free(ls);
	slice_stack_free(st);
	mesh_free(m);
}
END_TEST

/* Slice the shelf with stratum (support on, threshold 45, extra: --set
 * options) and run the support check on the G-code. */
static void shelf_end_to_end(const char *extra, struct region_support_report *r)
{
	struct mesh *m = shelf();
	struct st_error err = {0};
	struct region_print *p = NULL;
	char out[4096], stl[512], gc[512];

	snprintf(stl, sizeof(stl), "%s", tu_path("shelf.stl"));
	snprintf(gc, sizeof(gc), "%s", tu_path("shelf.gcode"));
	ck_assert_msg(meshio_write_stl(stl, m, MESHIO_STL_BINARY, &err) == 0, "%s", err.msg);
	int status = tu_run(out, sizeof(out),
			    "slice '%s' -o '%s' --printer prusa-i3-mk3s --set support_material=1 "
			    "--set support_material_threshold=45 %s",
			    stl, gc, extra);
	ck_assert_msg(status == 0, "stratum slice: %d\n%s", status, out);
	ck_assert_msg(!strstr(out, "not supported"), "%s: %s", extra, out);
	ck_assert_msg(region_read(gc, NULL, &p, &err) == 0, "%s", err.msg);
	/* within reach: the xy spacing (0.225 mm) and a bead, rounded up */
	ck_assert_msg(region_support_check(gc, m, p, NULL, 45, 0.2, 1.0, r, &err) == 0, "%s",
		      err.msg);
	region_print_free(p);
	mesh_free(m);
}

START_TEST(shelf_verified_end_to_end)
{
	struct region_support_report r;

	tu_scratch_init();
	shelf_end_to_end("", &r);
	ck_assert_uint_gt(r.beads, 300);
	ck_assert_uint_eq(r.stray, 0);
	ck_assert_msg(r.inside_mm2 < 0.01, "%.4f mm^2 of support inside the part", r.inside_mm2);
	ck_assert_msg(r.overhang_mm2 > 150, "overhang %.1f mm^2", r.overhang_mm2);
	ck_assert_msg(r.unsupported_mm2 < 0.01, "%.3f mm^2 unsupported at z %.2f",
		      r.unsupported_mm2, r.worst_z);
	/* On the bed only, the plate over the step (x 4-12) is left bare, and
	 * the verifier says so. */
	shelf_end_to_end("--set support_material_buildplate_only=1", &r);
	ck_assert_msg(r.inside_mm2 < 0.01, "%.4f mm^2 inside", r.inside_mm2);
	ck_assert_msg(r.unsupported_mm2 > 60, "%.3f mm^2 unsupported", r.unsupported_mm2);
	tu_scratch_cleanup();
}
END_TEST

/*
 * support_material_pattern, _style and _with_sheath are honoured (before,
 * named in the "not supported" warning): each choice still supports every
 * overhang of the shelf and prints nothing inside it.  organic (PrusaSlicer
 * 2.6's trees) is refused, naming what is allowed.
 */
START_TEST(shelf_patterns_and_styles_verified)
{
	static const char *const extra[] = {
	    "--set support_material_pattern=rectilinear-grid",
	    "--set support_material_pattern=honeycomb --set support_material_style=snug",
	    "--set support_material_with_sheath=0 --set support_material_style=grid",
	};
	struct region_support_report r;
	char out[4096];

	tu_scratch_init();
	for (size_t i = 0; i < sizeof(extra) / sizeof(extra[0]); i++) {
		shelf_end_to_end(extra[i], &r);
		ck_assert_uint_gt(r.beads, 300);
		ck_assert_msg(r.inside_mm2 < 0.01, "%s: %.4f mm^2 inside", extra[i], r.inside_mm2);
		ck_assert_msg(r.unsupported_mm2 < 0.01, "%s: %.3f mm^2 unsupported", extra[i],
			      r.unsupported_mm2);
	}
	int status = tu_run(out, sizeof(out),
			    "slice '%s' -o '%s' --printer prusa-i3-mk3s --set support_material=1 "
			    "--set support_material_style=organic",
			    tu_path("shelf.stl"), tu_path("organic.gcode"));
	ck_assert_int_ne(status, 0);
	ck_assert_msg(strstr(out, "organic") && strstr(out, "use grid or snug"), "%s", out);
	tu_scratch_cleanup();
}
END_TEST

Suite *supportmodel_suite(void)
{
	Suite *s = suite_create("supportmodel");
	TCase *tc = tcase_create("core");

	tcase_set_timeout(tc, 60);
	tcase_add_test(tc, shelf_support_stands_on_the_step);
	tcase_add_test(tc, shelf_bottom_gap_and_interfaces);
	tcase_add_test(tc, shelf_buildplate_only_drops_the_step);
	tcase_add_test(tc, bridge_left_unsupported);
	tcase_add_test(tc, pattern_angle_and_interface_spacing);
	tcase_add_test(tc, shelf_verified_end_to_end);
	tcase_add_test(tc, shelf_patterns_and_styles_verified);
	suite_add_tcase(s, tc);
	return s;
}
