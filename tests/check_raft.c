/*
 * check_raft.c - the raft (slicer/support.h, raft_layers) through the whole
 * slicing job, with expectations that follow from PrusaSlicer's rules:
 * raft_layers layers under the part (the first first_layer_height thick,
 * the others 0.75 nozzle), the part lifted by the raft's height plus
 * raft_contact_distance and otherwise unchanged, raft lines reaching
 * raft_expansion (and raft_first_layer_expansion on layer 0) beyond the
 * part's first layer at the spacings the keys give, the skirt and brim
 * around the raft, and no change at all with raft_layers = 0.
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fixtures.h"
#include "mesh.h"
#include "perimeters.h"
#include "slicer.h"
#include "suites.h"
#include "testutil.h"
#include "toolpath.h"

#define NM SLICE_UNITS_PER_MM
#define TOL 5e-3 /* mm: arc tolerance, rounding to the nm grid, slack */

/* ---- helpers ---- */

/* Defaults for a 0.4 mm nozzle, no skirt (so the part's layers compare). */
static void config(struct slicer_config *c, int raft_layers)
{
	slicer_config_init(c, 0.4);
	c->skirt.skirts = 0;
	c->threads = 1;
	c->raft.layers = raft_layers;
}

static struct layer_stack *toolpaths_ok(const struct mesh *m, const struct slicer_config *c,
					struct slicer_summary *sum)
{
	struct layer_stack *st = NULL;
	struct st_error err = {0};

	ck_assert_msg(slicer_toolpaths(m, c, &st, sum, &err) == 0, "slicer_toolpaths: %s", err.msg);
	ck_assert_ptr_nonnull(st);
	return st;
}

/* Bounding box (mm) of the beads (centre line +- w/2 across X and Y) of
 * layer l's paths of role a or b; false when there is none. */
static bool bead_box(const struct layer_paths *l, enum path_role a, enum path_role b, double box[4])
{
	bool any = false;

	box[0] = box[1] = INFINITY;
	box[2] = box[3] = -INFINITY;
	for (size_t i = 0; i < l->n; i++) {
		const struct toolpath *p = &l->paths[i];

		if (p->role != a && p->role != b)
			continue;
		for (size_t k = 0; k < p->n; k++) {
			double x = p->pts[k].x / NM, y = p->pts[k].y / NM,
			       r = p->pts[k].width / NM / 2;
			box[0] = fmin(box[0], x - r);
			box[1] = fmin(box[1], y - r);
			box[2] = fmax(box[2], x + r);
			box[3] = fmax(box[3], y + r);
			any = true;
		}
	}
	return any;
}

/* Whether every path of layer l has role a or b. */
static bool only_roles(const struct layer_paths *l, enum path_role a, enum path_role b)
{
	for (size_t i = 0; i < l->n; i++)
		if (l->paths[i].role != a && l->paths[i].role != b)
			return false;
	return l->n > 0;
}

/* Sorted distinct positions (nm) across the straight raft lines of layer l:
 * y of lines along X (axis 0), x of lines along Y (axis 1), segments over
 * 2 mm long; the links joining them along the raft's edge run across.
 * Returns the count. */
static size_t line_positions(const struct layer_paths *l, int axis, int64_t *pos, size_t cap)
{
	size_t n = 0;

	for (size_t i = 0; i < l->n; i++) {
		const struct toolpath *p = &l->paths[i];

		if (p->role != PATH_SUPPORT && p->role != PATH_SUPPORT_INTERFACE)
			continue;
		for (size_t j = 0; j + 1 < p->n; j++) {
			const struct path_point *a = &p->pts[j], *b = &p->pts[j + 1];
			int64_t v = axis == 0 ? a->y : a->x, along = axis == 0 ? b->x - a->x : b->y - a->y;
			size_t k = 0;

			if ((axis == 0 ? b->y : b->x) != v || llabs(along) <= 2 * NM)
				continue;
			while (k < n && pos[k] < v)
				k++;
			if (k < n && pos[k] == v)
				continue;
			ck_assert_uint_lt(n, cap);
			memmove(pos + k + 1, pos + k, (n - k) * sizeof(*pos));
			pos[k] = v;
			n++;
		}
	}
	return n;
}

/* slicer_run into a scratch file; the G-code text (caller frees). */
static char *gcode_ok(const struct mesh *m, const struct slicer_config *c)
{
	char path[4096];
	struct st_error err = {0};
	size_t len;

	snprintf(path, sizeof(path), "%s", tu_path("raft.gcode"));
	ck_assert_msg(slicer_run(m, c, path, NULL, &err) == 0, "slicer_run: %s", err.msg);
	return tu_slurp(path, &len);
}

/* ---- tests ---- */

START_TEST(raft_lifts_the_part_onto_three_layers)
{
	struct mesh *m = fx_box(0, 0, 0, 20, 10, 5);
	struct slicer_config c;
	struct slicer_summary s0, s3;
	struct layer_stack *plain, *raft;
	const double z[3] = {0.2, 0.5, 0.8}, h[3] = {0.2, 0.3, 0.3};

	config(&c, 0);
	plain = toolpaths_ok(m, &c, &s0);
	config(&c, 3);
	raft = toolpaths_ok(m, &c, &s3);

	/* Three more layers, below the part. */
	ck_assert_uint_eq(raft->nlayers, plain->nlayers + 3);
	ck_assert_uint_eq(s3.layers, s0.layers + 3);
	ck_assert_uint_eq(s3.raft_layers, 3);
	ck_assert_uint_eq(s0.raft_layers, 0);
	/* PrusaSlicer's split of 3: one base layer (the first, first_layer_height
	 * thick), two interface layers 0.75 x 0.4 mm thick. */
	for (int i = 0; i < 3; i++) {
		ck_assert_double_eq_tol(raft->layers[i].z, z[i], 1e-9);
		ck_assert_double_eq_tol(raft->layers[i].height, h[i], 1e-9);
	}
	ck_assert(only_roles(&raft->layers[0], PATH_SUPPORT, PATH_SUPPORT));
	ck_assert(only_roles(&raft->layers[1], PATH_SUPPORT_INTERFACE, PATH_SUPPORT_INTERFACE));
	ck_assert(only_roles(&raft->layers[2], PATH_SUPPORT_INTERFACE, PATH_SUPPORT_INTERFACE));

	/* The part's first layer starts raft height + contact distance up. */
	ck_assert_double_eq_tol(raft->layers[3].z - raft->layers[3].height, 0.8 + 0.1, 1e-9);
	ck_assert_double_eq_tol(raft->layers[3].height, c.layer_height, 1e-9);
	ck_assert_double_eq_tol(s3.min[2], 0.9, 1e-9);
	ck_assert_double_eq_tol(s3.max[2], s0.max[2] + 0.9, 1e-9);

	/* Otherwise the same part (first layer = layer height here): every
	 * layer's paths as without the raft, 0.9 mm higher. */
	for (size_t i = 0; i < plain->nlayers; i++) {
		const struct layer_paths *a = &plain->layers[i], *b = &raft->layers[i + 3];

		ck_assert_double_eq_tol(b->z, a->z + 0.9, 1e-9);
		ck_assert_uint_eq(a->n, b->n);
		for (size_t k = 0; k < a->n; k++) {
			ck_assert_msg(a->paths[k].role == b->paths[k].role,
				      "layer %zu path %zu: %d %d", i, k, a->paths[k].role,
				      b->paths[k].role);
			ck_assert_uint_eq(a->paths[k].n, b->paths[k].n);
			ck_assert(!memcmp(a->paths[k].pts, b->paths[k].pts,
					  a->paths[k].n * sizeof(*a->paths[k].pts)));
		}
	}
	layer_stack_free(plain);
	layer_stack_free(raft);

	/* A wider gap lifts the part further. */
	config(&c, 3);
	c.raft.contact_distance = 0.25;
	raft = toolpaths_ok(m, &c, &s3);
	ck_assert_double_eq_tol(raft->layers[3].z - raft->layers[3].height, 0.8 + 0.25, 1e-9);
	layer_stack_free(raft);
	mesh_free(m);
}
END_TEST

START_TEST(raft_reaches_past_the_footprint)
{
	struct mesh *m = fx_box(0, 0, 0, 20, 10, 5);
	struct slicer_config c;
	struct slicer_summary s;
	struct layer_stack *st;
	double box[4], fp[4];
	/* The line pitch of layer 0 (the widest across its lines) bounds how
	 * far short of the edge the last line may stop. */
	double pitch0;

	config(&c, 3);
	c.raft.expansion = 2.5;
	st = toolpaths_ok(m, &c, &s);
	fp[0] = s.min[0], fp[1] = s.min[1], fp[2] = s.max[0], fp[3] = s.max[1];
	pitch0 = perim_spacing(c.perim.extrusion_width, 0.2) / 0.9;

	/* Layer 0, lines along X: their ends reach expansion + first-layer
	 * expansion beyond the footprint in X, the lines across within a pitch. */
	ck_assert(bead_box(&st->layers[0], PATH_SUPPORT, PATH_SUPPORT, box));
	ck_assert_double_eq_tol(box[0], fp[0] - 2.5 - 3.0, TOL);
	ck_assert_double_eq_tol(box[2], fp[2] + 2.5 + 3.0, TOL);
	ck_assert_double_le(box[3], fp[3] + 5.5 + TOL);
	ck_assert_double_ge(box[3], fp[3] + 5.5 - pitch0 - TOL);
	ck_assert_double_ge(box[1], fp[1] - 5.5 - TOL);
	ck_assert_double_le(box[1], fp[1] - 5.5 + pitch0 + TOL);

	/* Layer 1, lines along Y, under the contact layer: raft_expansion and
	 * PrusaSlicer's 0.5 mm beyond in Y. */
	ck_assert(bead_box(&st->layers[1], PATH_SUPPORT_INTERFACE, PATH_SUPPORT_INTERFACE, box));
	ck_assert_double_eq_tol(box[1], fp[1] - 3.0, TOL);
	ck_assert_double_eq_tol(box[3], fp[3] + 3.0, TOL);
	ck_assert_double_le(box[2], fp[2] + 3.0 + TOL);
	ck_assert_double_ge(box[2], fp[2] + 3.0 - 0.5);

	/* Layer 2 (the contact layer), lines along X: raft_expansion in X. */
	ck_assert(bead_box(&st->layers[2], PATH_SUPPORT_INTERFACE, PATH_SUPPORT_INTERFACE, box));
	ck_assert_double_eq_tol(box[0], fp[0] - 2.5, TOL);
	ck_assert_double_eq_tol(box[2], fp[2] + 2.5, TOL);
	layer_stack_free(st);

	/* Without a first-layer expansion layer 0 still grows the 0.5 mm; a
	 * one-layer raft is the contact layer, raft_expansion wide. */
	config(&c, 2);
	c.raft.first_layer_expansion = 0;
	st = toolpaths_ok(m, &c, &s);
	ck_assert(bead_box(&st->layers[0], PATH_SUPPORT, PATH_SUPPORT, box));
	ck_assert_double_eq_tol(box[2], fp[2] + 1.5 + 0.5, TOL);
	layer_stack_free(st);
	config(&c, 1);
	st = toolpaths_ok(m, &c, &s);
	ck_assert(only_roles(&st->layers[0], PATH_SUPPORT_INTERFACE, PATH_SUPPORT_INTERFACE));
	ck_assert(bead_box(&st->layers[0], PATH_SUPPORT_INTERFACE, PATH_SUPPORT_INTERFACE, box));
	ck_assert_double_eq_tol(box[2], fp[2] + 1.5, TOL);
	ck_assert_double_eq_tol(st->layers[1].z - st->layers[1].height, 0.2 + 0.1, 1e-9);
	layer_stack_free(st);
	mesh_free(m);
}
END_TEST

START_TEST(raft_line_spacing)
{
	struct mesh *m = fx_box(0, 0, 0, 20, 10, 5);
	struct slicer_config c;
	struct layer_stack *st;
	int64_t pos[512];
	size_t n;
	double w;

	/* Four layers: two base (layer 0 and a body layer), two interface. */
	config(&c, 4);
	c.raft.first_layer_density = 50;
	st = toolpaths_ok(m, &c, NULL);
	w = c.perim.extrusion_width;
	ck_assert(only_roles(&st->layers[1], PATH_SUPPORT, PATH_SUPPORT));
	ck_assert(only_roles(&st->layers[2], PATH_SUPPORT_INTERFACE, PATH_SUPPORT_INTERFACE));

	/* Layer 0 at raft_first_layer_density of the flow spacing. */
	n = line_positions(&st->layers[0], 0, pos, 512);
	ck_assert_uint_gt(n, 5);
	for (size_t k = 1; k < n; k++)
		ck_assert_double_eq_tol((pos[k] - pos[k - 1]) / NM, perim_spacing(w, 0.2) / 0.5,
					1e-5);
	/* Layer 1, a body layer: support_material_spacing (2.5 mm) between beads. */
	n = line_positions(&st->layers[1], 1, pos, 512);
	ck_assert_uint_gt(n, 5);
	for (size_t k = 1; k < n; k++)
		ck_assert_double_eq_tol((pos[k] - pos[k - 1]) / NM, 2.5 + perim_spacing(w, 0.3),
					1e-5);
	/* Layers 2 and 3, interface: dense, one flow spacing, the lines joined
	 * along the raft's edge into fewer runs, as PrusaSlicer links them. */
	for (int l = 2; l < 4; l++) {
		n = line_positions(&st->layers[l], l & 1, pos, 512);
		ck_assert_uint_gt(n, 20);
		ck_assert_uint_lt(st->layers[l].n, n / 2);
		for (size_t k = 1; k < n; k++)
			ck_assert_double_eq_tol((pos[k] - pos[k - 1]) / NM, perim_spacing(w, 0.3),
						1e-5);
	}
	layer_stack_free(st);
	mesh_free(m);
}
END_TEST

START_TEST(raft_under_support_and_skirt_around_it)
{
	struct mesh *m = fx_overhang();
	struct slicer_config c;
	struct slicer_summary s;
	struct layer_stack *st;
	double raft0[4], brim[4], skirt[4], sup[4];

	config(&c, 2);
	c.support.enabled = true;
	c.support.threshold = 60;
	c.skirt.skirts = 1;
	c.skirt.brim_width = 2;
	st = toolpaths_ok(m, &c, &s);
	ck_assert(s.support);

	/* The support's first layer stands on the raft: the raft's layer 0
	 * reaches 4.5 mm past the support's beads, not just the block's. */
	ck_assert(bead_box(&st->layers[2], PATH_SUPPORT, PATH_SUPPORT_INTERFACE, sup));
	ck_assert_double_gt(sup[2], s.min[0] + 15);
	ck_assert(bead_box(&st->layers[0], PATH_SUPPORT, PATH_SUPPORT_INTERFACE, raft0));
	ck_assert_double_ge(raft0[2], sup[2] + 4.5 - TOL);

	/* The brim touches the raft's first layer, the skirt is 6 mm beyond the
	 * brim, both on the first layer only. */
	ck_assert(bead_box(&st->layers[0], PATH_BRIM, PATH_BRIM, brim));
	ck_assert_double_le(brim[2], raft0[2] + 2 + 0.5);
	ck_assert_double_ge(brim[2], raft0[2] + 2 - 0.5);
	ck_assert(bead_box(&st->layers[0], PATH_SKIRT, PATH_SKIRT, skirt));
	ck_assert_double_ge(skirt[2], brim[2] + 6);
	for (size_t l = 1; l < st->nlayers; l++) {
		ck_assert(!bead_box(&st->layers[l], PATH_SKIRT, PATH_BRIM, skirt));
	}
	layer_stack_free(st);
	mesh_free(m);
}
END_TEST

START_TEST(raft_off_changes_nothing)
{
	struct mesh *m = fx_box(0, 0, 0, 20, 10, 5);
	struct slicer_config c;
	char *dflt, *other, *raft;

	config(&c, 0);
	dflt = gcode_ok(m, &c);
	/* With raft_layers = 0 the other raft keys do nothing. */
	c.raft.contact_distance = 0.5;
	c.raft.expansion = 7;
	c.raft.first_layer_density = 40;
	c.raft.first_layer_expansion = 9;
	c.gcodew.first_layer_speed_over_raft = 5;
	other = gcode_ok(m, &c);
	ck_assert_str_eq(dflt, other);
	ck_assert_ptr_null(strstr(dflt, "raft"));

	/* With a raft the header lists the values used. */
	config(&c, 3);
	c.raft.expansion = 2;
	c.gcodew.first_layer_speed_over_raft = 12;
	raft = gcode_ok(m, &c);
	ck_assert_ptr_nonnull(strstr(raft, "; raft_layers = 3\n"));
	ck_assert_ptr_nonnull(strstr(raft, "; raft_contact_distance = 0.1\n"));
	ck_assert_ptr_nonnull(strstr(raft, "; raft_expansion = 2\n"));
	ck_assert_ptr_nonnull(strstr(raft, "; raft_first_layer_density = 90%\n"));
	ck_assert_ptr_nonnull(strstr(raft, "; raft_first_layer_expansion = 3\n"));
	ck_assert_ptr_nonnull(strstr(raft, "; first_layer_speed_over_raft = 12\n"));
	ck_assert_ptr_nonnull(strstr(raft, "; total layers count = "));
	/* The part's first layer, on the raft, at first_layer_speed_over_raft. */
	const char *l4 = strstr(raft, ";Z:1.1\n"), *l5 = l4 ? strstr(l4, ";Z:1.3\n") : NULL;
	ck_assert_ptr_nonnull(l5);
	const char *f = strstr(l4, " F720\n");
	ck_assert(f && f < l5);
	free(dflt);
	free(other);
	free(raft);
	mesh_free(m);
}
END_TEST

START_TEST(raft_settings_refused)
{
	struct mesh *m = fx_box(0, 0, 0, 20, 10, 5);
	struct slicer_config c;
	struct layer_stack *st = NULL;
	struct st_error err = {0};

	config(&c, -1);
	ck_assert_int_eq(slicer_config_check(&c, &err), ST_ERR_RANGE);
	ck_assert_ptr_nonnull(strstr(err.msg, "raft_layers"));
	config(&c, 101);
	ck_assert_int_eq(slicer_config_check(&c, &err), ST_ERR_RANGE);
	config(&c, 3);
	c.raft.first_layer_density = 5;
	ck_assert_int_eq(slicer_config_check(&c, &err), ST_ERR_RANGE);
	ck_assert_ptr_nonnull(strstr(err.msg, "raft_first_layer_density"));
	config(&c, 3);
	c.raft.expansion = -1;
	ck_assert_int_eq(slicer_config_check(&c, &err), ST_ERR_RANGE);
	ck_assert_ptr_nonnull(strstr(err.msg, "raft_expansion"));

	/* The lifted part must fit the build height: 5 mm fits 5.5 mm, not
	 * on a 0.9 mm raft. */
	config(&c, 0);
	c.bed.max_height = 5.5;
	ck_assert_int_eq(slicer_toolpaths(m, &c, &st, NULL, &err), 0);
	layer_stack_free(st);
	config(&c, 3);
	c.bed.max_height = 5.5;
	ck_assert_int_eq(slicer_toolpaths(m, &c, &st, NULL, &err), ST_ERR_RANGE);
	ck_assert_ptr_null(st);
	ck_assert_ptr_nonnull(strstr(err.msg, "raft"));
	mesh_free(m);
}
END_TEST

Suite *raft_suite(void)
{
	Suite *s = suite_create("raft");
	TCase *tc = tcase_create("core");

	tcase_set_timeout(tc, 60);
	tcase_add_test(tc, raft_lifts_the_part_onto_three_layers);
	tcase_add_test(tc, raft_reaches_past_the_footprint);
	tcase_add_test(tc, raft_line_spacing);
	tcase_add_test(tc, raft_under_support_and_skirt_around_it);
	tcase_add_test(tc, raft_off_changes_nothing);
	tcase_add_test(tc, raft_settings_refused);
	suite_add_tcase(s, tc);
	return s;
}
