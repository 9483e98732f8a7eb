/*
 * check_support.c - skirt, brim and support material on meshes built in
 * code, with expectations that follow from the geometry: a skirt loop at
 * skirt_distance + w/2 from a cube, brim loops one flow spacing apart
 * touching the part, support under a cantilever on exactly the layers
 * below its interface gap, and a slope supported or not by its angle.
 */
#include <check.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fixtures.h"
#include "mesh.h"
#include "perimeters.h"
#include "section.h"
#include "skirt.h"
#include "suites.h"
#include "testutil.h"
#include "support.h"
#include "toolpath.h"

#define NM SLICE_UNITS_PER_MM
#define TOL 5000.0 /* nm: arc tolerance, rounding to the nm grid, slack */

/* ---- setup ---- */

static struct slice_stack *slice_ok(const struct mesh *m)
{
	struct st_error err = {0};
	struct slice_stack *st = NULL;

	ck_assert_msg(slice_mesh(m, 0.2, 0.2, NULL, &st, &err) == 0, "slice_mesh: %s", err.msg);
	return st;
}

/* An empty output stack matching st layer for layer. */
static struct layer_stack *stack_for(const struct slice_stack *st)
{
	struct layer_stack *ls = layer_stack_new(st->n, NULL);

	ck_assert_ptr_nonnull(ls);
	for (size_t i = 0; i < st->n; i++) {
		ls->layers[i].z = st->layers[i].z;
		ls->layers[i].height = st->layers[i].height;
	}
	return ls;
}

/* Slice m, run the skirt with s (and support paths sup), free m. */
static struct layer_stack *skirt_ok(const struct skirt_settings *s, struct slice_stack *st,
				    const struct layer_stack *sup)
{
	struct layer_stack *ls = stack_for(st);
	struct st_error err = {0};

	ck_assert_msg(skirt_generate(s, st, sup, ls, &err) == 0, "skirt_generate: %s", err.msg);
	return ls;
}

static struct layer_stack *support_ok(const struct support_settings *s,
				      const struct slice_stack *st)
{
	struct layer_stack *ls = stack_for(st);
	struct st_error err = {0};

	ck_assert_msg(support_generate(s, st, ls, &err) == 0, "support_generate: %s", err.msg);
	return ls;
}

/* A 20 mm cube on the bed, sliced; *m receives the mesh. */
static struct slice_stack *cube(struct mesh **m)
{
	*m = fx_box(0, 0, 0, 20, 20, 20);
	return slice_ok(*m);
}

/* Free what a test made; any of them may be NULL. */
static void release(struct layer_stack *ls, struct slice_stack *st, struct mesh *m)
{
	layer_stack_free(ls);
	slice_stack_free(st);
	if (m)
		mesh_free(m);
}

/* ---- measures ---- */

/* Signed distance (nm) from (x, y) to the box [x0,x1] x [y0,y1] (mm):
 * > 0 outside, < 0 inside. */
static double box_dist(double x, double y, double x0, double y0, double x1, double y1)
{
	double dx = fmax(fmax(x0 * NM - x, x - x1 * NM), 0.0);
	double dy = fmax(fmax(y0 * NM - y, y - y1 * NM), 0.0);

	if (dx > 0.0 || dy > 0.0)
		return hypot(dx, dy);
	return -fmin(fmin(x - x0 * NM, x1 * NM - x), fmin(y - y0 * NM, y1 * NM - y));
}

static size_t count_support(const struct layer_paths *l)
{
	return tu_count_role(l, PATH_SUPPORT) + tu_count_role(l, PATH_SUPPORT_INTERFACE);
}

/* Smallest and largest distance from the points of path p to a box. */
static void path_box_range(const struct toolpath *p, const double box[4], double *lo, double *hi)
{
	*lo = INFINITY;
	*hi = -INFINITY;
	for (size_t k = 0; k < p->n; k++) {
		double d = box_dist(p->pts[k].x, p->pts[k].y, box[0], box[1], box[2], box[3]);
		*lo = fmin(*lo, d);
		*hi = fmax(*hi, d);
	}
}

/* Every point of p lies want nm (within TOL) from the box; what names p. */
static void assert_at(const struct toolpath *p, const double box[4], double want,
		      const char *what, size_t k)
{
	double lo, hi;

	path_box_range(p, box, &lo, &hi);
	ck_assert_msg(fabs(lo - want) < TOL && fabs(hi - want) < TOL,
		      "%s %zu at %.4f..%.4f mm, want %.4f", what, k, lo / NM, hi / NM, want / NM);
}

/* No paths on layers first .. top of ls. */
static void assert_empty_from(const struct layer_stack *ls, size_t first)
{
	for (size_t l = first; l < ls->nlayers; l++)
		ck_assert_msg(ls->layers[l].n == 0, "layer %zu has %zu paths", l, ls->layers[l].n);
}

/* Filament (mm) one closed path of width w mm on a layer h mm high uses. */
static double filament_mm(const struct toolpath *p, double w, double h)
{
	double len = 0.0;

	for (size_t i = 0; i < p->n; i++) {
		size_t j = (i + 1) % p->n;
		len += hypot((double)(p->pts[j].x - p->pts[i].x), (double)(p->pts[j].y - p->pts[i].y));
	}
	return len / NM * perim_bead_area(w, h) / (M_PI * 1.75 * 1.75 / 4.0);
}

/* ---- meshes ---- */

/* A 10 x 10 x 6 mm stem with a 20 x 10 x 1 mm plate on top: the plate
 * overhangs the stem by 10 mm in x from z = 5 to 6. */
static struct mesh *cantilever(void)
{
	struct mesh *stem = fx_box(0, 0, 0, 10, 10, 6), *plate = fx_box(0, 0, 5, 20, 10, 6);
	struct mesh *m = fx_concat(stem, plate);

	mesh_free(stem);
	mesh_free(plate);
	return m;
}

static uint32_t vtx(struct mesh_builder *b, double x, double y, double z)
{
	const double p[3] = {x, y, z};
	uint32_t i;

	ck_assert_int_eq(mesh_builder_vertex(b, p, &i, NULL), 0);
	return i;
}

/*
 * A 10 mm deep (y) block, 5 mm high, whose right face leans out at angle
 * deg from horizontal: its section in x runs from 0 to 10 at the bed and
 * to 10 + 5 / tan(deg) at the top.
 */
static struct mesh *slope_block(double deg)
{
	const double px[4] = {0, 10, 10 + 5 / tan(deg * M_PI / 180), 0}, pz[4] = {0, 0, 5, 5};
	struct mesh_builder *b = mesh_builder_new(12);
	uint32_t f[4], k[4];

	ck_assert_ptr_nonnull(b);
	for (int i = 0; i < 4; i++) {
		f[i] = vtx(b, px[i], 0, pz[i]);
		k[i] = vtx(b, px[i], 10, pz[i]);
	}
	/* Front (y = 0) and back faces, then the four sides; outward. */
	ck_assert_int_eq(mesh_builder_triangle(b, f[0], f[1], f[2], NULL), 0);
	ck_assert_int_eq(mesh_builder_triangle(b, f[0], f[2], f[3], NULL), 0);
	ck_assert_int_eq(mesh_builder_triangle(b, k[0], k[2], k[1], NULL), 0);
	ck_assert_int_eq(mesh_builder_triangle(b, k[0], k[3], k[2], NULL), 0);
	for (int i = 0; i < 4; i++) {
		int j = (i + 1) % 4;
		ck_assert_int_eq(mesh_builder_triangle(b, f[i], k[i], k[j], NULL), 0);
		ck_assert_int_eq(mesh_builder_triangle(b, f[i], k[j], f[j], NULL), 0);
	}
	return mesh_builder_finish(b);
}

/* ---- skirt and brim ---- */

static const double cube_box[4] = {0, 0, 20, 20};

START_TEST(skirt_one_loop_around_cube)
{
	struct mesh *m;
	struct slice_stack *st = cube(&m);
	struct skirt_settings s;

	skirt_settings_init(&s, 0.4);
	struct layer_stack *ls = skirt_ok(&s, st, NULL);
	double want = (6.0 + s.extrusion_width / 2) * NM;

	ck_assert_uint_eq(ls->layers[0].n, 1);
	const struct toolpath *p = &ls->layers[0].paths[0];
	ck_assert_int_eq(p->role, PATH_SKIRT);
	ck_assert(p->closed);
	ck_assert_uint_ge(p->n, 8); /* round corners */
	assert_at(p, cube_box, want, "skirt", 0);
	for (size_t i = 0; i < p->n; i++)
		ck_assert_int_eq(p->pts[i].width, llround(s.extrusion_width * NM));
	assert_empty_from(ls, 1);
	layer_stack_free(ls);

	/* Three loops one flow spacing apart, the outermost printed first;
	 * skirt_height 2 repeats them on layer 1. */
	s.skirts = 3;
	s.skirt_height = 2;
	ls = skirt_ok(&s, st, NULL);
	double sp = perim_spacing(s.extrusion_width, 0.2) * NM;
	for (size_t l = 0; l < 2; l++) {
		ck_assert_uint_eq(tu_count_role(&ls->layers[l], PATH_SKIRT), 3);
		for (size_t k = 0; k < 3; k++) {
			assert_at(&ls->layers[l].paths[k], cube_box, want + (2 - (double)k) * sp,
				  "skirt loop", k);
		}
	}
	assert_empty_from(ls, 2);
	release(ls, st, m);
}
END_TEST

START_TEST(skirt_min_length_adds_loops)
{
	struct mesh *m;
	struct slice_stack *st = cube(&m);
	struct skirt_settings s;
	double used = 0, last = 0;

	skirt_settings_init(&s, 0.4);
	s.min_skirt_length = 20.0; /* one loop (~136 mm) uses about 4.6 mm */
	struct layer_stack *ls = skirt_ok(&s, st, NULL);
	const struct layer_paths *l = &ls->layers[0];
	for (size_t i = 0; i < l->n; i++) {
		last = filament_mm(&l->paths[i], s.extrusion_width, 0.2);
		used += last;
	}
	ck_assert_uint_gt(l->n, 1);
	ck_assert_msg(used >= 20.0 && used - last < 20.0, "%zu loops use %.3f mm", l->n, used);
	release(ls, st, m);
}
END_TEST

START_TEST(brim_attached_to_part)
{
	struct mesh *m;
	struct slice_stack *st = cube(&m);
	struct skirt_settings s;
	double lo, hi;

	skirt_settings_init(&s, 0.4);
	s.skirts = 0;
	s.brim_width = 5.0;
	struct layer_stack *ls = skirt_ok(&s, st, NULL);
	double w = s.extrusion_width * NM, sp = perim_spacing(s.extrusion_width, 0.2) * NM;
	size_t want = (size_t)ceil(5.0 * NM / sp);
	const struct layer_paths *l = &ls->layers[0];

	ck_assert_uint_eq(want, 13);
	ck_assert_uint_eq(tu_count_role(l, PATH_BRIM), want);
	ck_assert_uint_eq(l->n, want);
	/* Outermost first; the last loop's inner edge touches the part. */
	for (size_t k = 0; k < want; k++) {
		ck_assert(l->paths[k].closed);
		assert_at(&l->paths[k], cube_box, w / 2 + (double)(want - 1 - k) * sp, "brim loop",
			  k);
	}
	path_box_range(&l->paths[want - 1], cube_box, &lo, &hi);
	ck_assert_msg(fabs(lo - w / 2) < TOL, "inner edge %.4f mm from the part", (lo - w / 2) / NM);
	assert_empty_from(ls, 1);
	layer_stack_free(ls);

	/* With a skirt too: skirt first, skirt_distance beyond the brim's outer
	 * edge; a brim separation moves every brim loop out. */
	s.skirts = 1;
	s.brim_separation = 1.0;
	ls = skirt_ok(&s, st, NULL);
	l = &ls->layers[0];
	ck_assert_uint_eq(l->n, want + 1);
	ck_assert_int_eq(l->paths[0].role, PATH_SKIRT);
	path_box_range(&l->paths[0], cube_box, &lo, &hi);
	double edge = 1.0 * NM + w + (double)(want - 1) * sp;
	ck_assert_msg(fabs(lo - (edge + 6.0 * NM + w / 2)) < TOL, "skirt at %.4f mm", lo / NM);
	path_box_range(&l->paths[want], cube_box, &lo, &hi);
	ck_assert_msg(fabs(lo - (1.0 * NM + w / 2)) < TOL, "first brim loop at %.4f mm", lo / NM);
	release(ls, st, m);
}
END_TEST

START_TEST(skirt_settings_refused)
{
	struct mesh *m;
	struct slice_stack *st = cube(&m);
	struct layer_stack *ls = stack_for(st), *short_ls = layer_stack_new(3, NULL);
	struct skirt_settings s, bad;
	struct st_error err = {0};

	skirt_settings_init(&s, 0.4);
	ck_assert_int_eq(skirt_settings_check(&s, &err), 0);
	bad = s;
	bad.skirts = -1;
	ck_assert_int_eq(skirt_generate(&bad, st, NULL, ls, &err), ST_ERR_RANGE);
	ck_assert_ptr_nonnull(strstr(err.msg, "skirts"));
	bad = s;
	bad.brim_width = -2;
	ck_assert_int_eq(skirt_settings_check(&bad, &err), ST_ERR_RANGE);
	ck_assert_ptr_nonnull(strstr(err.msg, "brim_width"));
	bad = s;
	bad.skirt_distance = NAN;
	ck_assert_int_eq(skirt_settings_check(&bad, &err), ST_ERR_RANGE);
	bad = s;
	bad.extrusion_width = 0;
	ck_assert_int_eq(skirt_settings_check(&bad, &err), ST_ERR_RANGE);
	ck_assert_ptr_nonnull(strstr(err.msg, "width"));
	bad = s;
	bad.skirt_height = 0;
	ck_assert_int_eq(skirt_settings_check(&bad, &err), ST_ERR_RANGE);
	ck_assert_int_eq(skirt_generate(&s, st, NULL, short_ls, &err), ST_ERR_ARG);
	ck_assert_int_eq(skirt_generate(NULL, st, NULL, ls, &err), ST_ERR_ARG);
	for (size_t i = 0; i < ls->nlayers; i++)
		ck_assert_uint_eq(ls->layers[i].n, 0);
	layer_stack_free(ls);
	layer_stack_free(short_ls);
	slice_stack_free(st);
	mesh_free(m);
}
END_TEST

/* ---- support ---- */

/*
 * The interface lines of layer l: segments over 1 mm long along X (axis 0)
 * or Y (axis 1); every segment of an interface path is one of them or a
 * link across, shorter than three lines' spacing, and the lines are sp apart
 * (across consecutive ones).  Returns how many lines; paths with more
 * than one line are counted in links.
 */
static size_t interface_lines(const struct layer_paths *l, int axis, double sp)
{
	int64_t pos[256];
	size_t n = 0, linked = 0;

	for (size_t i = 0; i < l->n; i++) {
		const struct toolpath *p = &l->paths[i];
		size_t lines = 0;
		if (p->role != PATH_SUPPORT_INTERFACE)
			continue;
		for (size_t k = 0; k + 1 < p->n; k++) {
			const struct path_point *a = &p->pts[k], *b = &p->pts[k + 1];
			int64_t along = axis ? b->y - a->y : b->x - a->x;
			int64_t across = axis ? b->x - a->x : b->y - a->y;
			if (across == 0 && llabs(along) > 1 * NM) {
				ck_assert_uint_lt(n, 256);
				pos[n++] = axis ? a->x : a->y;
				lines++;
			} else {
				ck_assert_msg(hypot((double)along, (double)across) < 3 * sp + 1.0,
					      "a link of %.3f mm", hypot((double)along, (double)across) / NM);
			}
		}
		linked += lines > 1;
	}
	for (size_t i = 1; i < n; i++) /* insertion sort: a few dozen lines */
		for (size_t k = i; k > 0 && pos[k - 1] > pos[k]; k--) {
			int64_t t = pos[k];
			pos[k] = pos[k - 1];
			pos[k - 1] = t;
		}
	for (size_t i = 1; i < n; i++)
		ck_assert_msg(fabs((double)(pos[i] - pos[i - 1]) - sp) <= 1.0,
			      "interface lines %.4f mm apart", (pos[i] - pos[i - 1]) / NM);
	ck_assert_uint_gt(linked, 0);
	return n;
}

/*
 * Support under the cantilever in one style: the plate's first layer is
 * 25 (z 5.0-5.2), the 0.2 mm gap is layer 24, so support runs on layers
 * 0-23 with interface on 21-23, and every bead keeps the xy spacing from
 * the stem.
 */
static void check_cantilever(enum support_style style)
{
	struct mesh *m = cantilever();
	struct slice_stack *st = slice_ok(m);
	struct support_settings s;

	support_settings_init(&s, 0.4);
	s.support_material = true;
	s.support_material_style = style;
	struct layer_stack *ls = support_ok(&s, st);
	double w = s.extrusion_width * NM, clear = s.support_material_xy_spacing * NM;
	bool loop = false;

	ck_assert_uint_eq(st->n, 30);
	ck_assert(fabs(st->layers[25].z - 5.2) < 1e-9);
	for (size_t j = 0; j < ls->nlayers; j++) {
		const struct layer_paths *l = &ls->layers[j];
		size_t body = tu_count_role(l, PATH_SUPPORT), face = tu_count_role(l, PATH_SUPPORT_INTERFACE);
		if (j >= 24) {
			ck_assert_msg(l->n == 0, "layer %zu has %zu paths", j, l->n);
			continue;
		}
		ck_assert_msg(l->n == body + face, "layer %zu has other roles", j);
		if (j >= 21)
			ck_assert_msg(face > 0 && body == 0, "layer %zu: %zu body %zu interface", j,
				      body, face);
		else
			ck_assert_msg(body > 0 && face == 0, "layer %zu: %zu body %zu interface", j,
				      body, face);
		for (size_t i = 0; i < l->n; i++) {
			const struct toolpath *p = &l->paths[i];
			for (size_t k = 0; k < p->n; k++) {
				double x = (double)p->pts[k].x, y = (double)p->pts[k].y;
				/* Under the overhang, beads clear of the stem. */
				ck_assert(box_dist(x, y, 10, 0, 20, 10) <= -w / 2 + TOL);
				ck_assert_msg(box_dist(x, y, 0, 0, 10, 10) >= clear + w / 2 - TOL,
					      "layer %zu: bead at (%.3f, %.3f) too near the stem", j,
					      x / NM, y / NM);
				ck_assert_int_eq(p->pts[k].width, llround(w));
			}
			loop = loop || p->closed;
		}
	}
	ck_assert(loop == s.support_material_with_sheath); /* the sheath, on by default */
	/* Body lines along X (PrusaSlicer's at 0 degrees), on every layer,
	 * support_material_spacing apart edge to edge, joined along the
	 * boundary into one zigzag (before, separate lines in X and Y). */
	const struct layer_paths *b = &ls->layers[10];
	double pitch = (s.support_material_spacing + perim_spacing(s.extrusion_width, 0.2)) * NM;
	int64_t prev = INT64_MIN;
	size_t xlines = 0, open = 0;
	for (size_t i = 0; i < b->n; i++) {
		const struct toolpath *p = &b->paths[i];
		if (p->closed)
			continue;
		open++;
		for (size_t k = 0; k + 1 < p->n; k++) {
			const struct path_point *q = &p->pts[k], *r = &p->pts[k + 1];
			ck_assert_msg(q->y == r->y || fabs((double)(r->y - q->y)) <= pitch + 1.0,
				      "layer 10: a segment across %.3f mm", (r->y - q->y) / NM);
			if (q->y != r->y || llabs(r->x - q->x) < 1 * NM)
				continue;
			if (xlines++)
				ck_assert_msg(fabs(fabs((double)(q->y - prev)) - pitch) <= 1.0,
					      "body lines %.4f mm apart", (q->y - prev) / NM);
			prev = q->y;
		}
	}
	ck_assert_uint_eq(xlines, 3); /* y = 1, 2, 3 pitches: 2.9, 5.8, 8.7 mm */
	ck_assert_uint_eq(open, 1);
	/* Interface lines are one flow spacing apart, alternating direction,
	 * joined along their boundary by links shorter than the lines. */
	double sp = perim_spacing(s.extrusion_width, 0.2) * NM;
	ck_assert_uint_gt(interface_lines(&ls->layers[23], 1, sp), 5); /* odd: along Y */
	ck_assert_uint_gt(interface_lines(&ls->layers[22], 0, sp), 5);
	/* one zigzag a layer (before, a run per line), as PrusaSlicer prints it */
	ck_assert_uint_eq(tu_count_role(&ls->layers[22], PATH_SUPPORT_INTERFACE), 1);
	ck_assert_uint_eq(tu_count_role(&ls->layers[23], PATH_SUPPORT_INTERFACE), 1);
	release(ls, st, m);
}

/*
 * The body's patterns under the cantilever: rectilinear-grid turns its
 * lines 90 degrees every other layer (layer 10 along X, 11 along Y);
 * honeycomb's run at 60 degrees; without the sheath no loop.
 */
START_TEST(support_body_patterns)
{
	struct mesh *m = cantilever();
	struct slice_stack *st = slice_ok(m);
	struct support_settings s;

	support_settings_init(&s, 0.4);
	s.support_material = true;
	s.support_material_with_sheath = false;
	for (int pat = SUPPORT_RECTILINEAR_GRID; pat <= SUPPORT_HONEYCOMB; pat++) {
		s.support_material_pattern = (enum support_pattern)pat;
		struct layer_stack *ls = support_ok(&s, st);
		for (size_t j = 10; j <= 11; j++) {
			size_t along[3] = {0, 0, 0}; /* X, Y, slanted: segments over 0.5 mm */
			for (size_t i = 0; i < ls->layers[j].n; i++) {
				const struct toolpath *p = &ls->layers[j].paths[i];
				ck_assert(!p->closed);
				for (size_t k = 0; k + 1 < p->n; k++) {
					int64_t dx = p->pts[k + 1].x - p->pts[k].x,
						dy = p->pts[k + 1].y - p->pts[k].y;
					if (hypot((double)dx, (double)dy) > 0.5 * NM)
						along[dy == 0 ? 0 : dx == 0 ? 1 : 2]++;
				}
			}
			if (pat == SUPPORT_HONEYCOMB)
				ck_assert_uint_gt(along[2], 4);
			else /* the lines, and the links between them across */
				ck_assert_msg(along[2] == 0 && along[j & 1] >= 3 &&
						  along[j & 1] > along[1 - (j & 1)],
					      "layer %zu: %zu along X, %zu along Y", j, along[0],
					      along[1]);
		}
		layer_stack_free(ls);
	}
	slice_stack_free(st);
	mesh_free(m);
}
END_TEST

START_TEST(support_under_cantilever_grid)
{
	check_cantilever(SUPPORT_GRID);
}
END_TEST

START_TEST(support_under_cantilever_snug)
{
	check_cantilever(SUPPORT_SNUG);
}
END_TEST

START_TEST(support_off_and_skirt_around_it)
{
	struct mesh *m = cantilever();
	struct slice_stack *st = slice_ok(m);
	struct support_settings s;
	struct skirt_settings k;
	double lo, hi;

	support_settings_init(&s, 0.4);
	struct layer_stack *none = support_ok(&s, st); /* off by default */
	for (size_t j = 0; j < none->nlayers; j++)
		ck_assert_uint_eq(none->layers[j].n, 0);

	/* The skirt goes around the support's first layer: x up to the plate's
	 * edge (20 mm) plus skirt_distance + w/2, not just around the stem. */
	s.support_material = true;
	struct layer_stack *sup = support_ok(&s, st);
	skirt_settings_init(&k, 0.4);
	double want = (6.0 + k.extrusion_width / 2) * NM;
	const double plate[4] = {0, 0, 20, 10}, stem[4] = {0, 0, 10, 10};
	struct layer_stack *bare = skirt_ok(&k, st, none), *around = skirt_ok(&k, st, sup);
	ck_assert_uint_eq(bare->layers[0].n, 1);
	ck_assert_uint_eq(around->layers[0].n, 1);
	assert_at(&bare->layers[0].paths[0], stem, want, "skirt around the stem", 0);
	/* The support beads reach the plate's edge x = 20 but not its corners. */
	const struct toolpath *p = &around->layers[0].paths[0];
	double xmax = -INFINITY;
	path_box_range(p, plate, &lo, &hi);
	ck_assert_msg(hi < want + TOL && lo > 0, "%.4f..%.4f", lo / NM, hi / NM);
	for (size_t i = 0; i < p->n; i++)
		xmax = fmax(xmax, (double)p->pts[i].x);
	ck_assert_msg(fabs(xmax - (20 * NM + want)) < TOL, "skirt reaches x = %.4f", xmax / NM);
	layer_stack_free(none);
	layer_stack_free(sup);
	layer_stack_free(bare);
	layer_stack_free(around);
	slice_stack_free(st);
	mesh_free(m);
}
END_TEST

/* Support paths over all layers of a slope of deg at the given threshold;
 * every point lies under the slope (x beyond the 10 mm base). */
static size_t slope_support(double deg, double threshold)
{
	struct mesh *m = slope_block(deg);
	struct slice_stack *st = slice_ok(m);
	struct support_settings s;
	size_t c = 0;

	support_settings_init(&s, 0.4);
	s.support_material = true;
	s.support_material_threshold = threshold;
	struct layer_stack *ls = support_ok(&s, st);
	for (size_t j = 0; j < ls->nlayers; j++) {
		const struct layer_paths *l = &ls->layers[j];
		c += count_support(l);
		for (size_t i = 0; i < l->n; i++)
			for (size_t k = 0; k < l->paths[i].n; k++)
				ck_assert(l->paths[i].pts[k].x > 10 * NM);
	}
	layer_stack_free(ls);
	slice_stack_free(st);
	mesh_free(m);
	return c;
}

START_TEST(support_by_overhang_angle)
{
	/* Threshold 45: a 30 deg slope (0.35 mm out per 0.2 mm layer) needs
	 * support, a 60 deg one (0.12 mm) does not. */
	size_t flat = slope_support(30, 45), steep = slope_support(60, 45);
	ck_assert_uint_gt(flat, 10);
	ck_assert_uint_eq(steep, 0);
	/* The threshold is what decides: at 25 deg the 30 deg slope prints
	 * unsupported; automatic (w/2 = 0.225 mm) splits them like 45. */
	ck_assert_uint_eq(slope_support(30, 25), 0);
	ck_assert_uint_gt(slope_support(30, 0), 10);
	ck_assert_uint_eq(slope_support(60, 0), 0);
}
END_TEST

START_TEST(support_only_from_the_bed)
{
	/* A stem at x 0-4, a step on the bed at x 4-12 up to z 2, a plate at
	 * z 9-10 over x 0-20: with support_material_buildplate_only the plate
	 * is held from the bed at x 12-20 only; over the step the support
	 * would stand on the part (check_support_model.c has it there). */
	struct mesh *stem = fx_box(0, 0, 0, 4, 10, 10), *step = fx_box(3, 0, 0, 12, 10, 2);
	struct mesh *plate = fx_box(0, 0, 9, 20, 10, 10);
	struct mesh *a = fx_concat(stem, step), *m = fx_concat(a, plate);
	struct slice_stack *st = slice_ok(m);
	struct support_settings s;
	size_t layers = 0;

	support_settings_init(&s, 0.4);
	s.support_material = true;
	s.support_material_buildplate_only = true;
	double w = s.extrusion_width * NM, clear = s.support_material_xy_spacing * NM;
	for (int style = 0; style < SUPPORT_STYLES; style++) {
		s.support_material_style = style;
		struct layer_stack *ls = support_ok(&s, st);
		layers = 0;
		for (size_t j = 0; j < ls->nlayers; j++) {
			const struct layer_paths *l = &ls->layers[j];
			layers += l->n > 0;
			for (size_t i = 0; i < l->n; i++)
				for (size_t k = 0; k < l->paths[i].n; k++) {
					const struct path_point *q = &l->paths[i].pts[k];
					ck_assert_msg(q->x >= 12 * NM + clear + w / 2 - TOL,
						      "layer %zu: bead at x %.3f over the step", j,
						      q->x / NM);
				}
		}
		/* Layer 45 (z 9.0-9.2) is the plate's first: support on 0-43. */
		ck_assert_uint_eq(layers, 44);
		ck_assert_uint_eq(count_support(&ls->layers[43]), ls->layers[43].n);
		ck_assert_uint_eq(ls->layers[44].n, 0);
		layer_stack_free(ls);
	}
	slice_stack_free(st);
	mesh_free(stem);
	mesh_free(step);
	mesh_free(plate);
	mesh_free(a);
	mesh_free(m);
}
END_TEST

START_TEST(support_under_sphere)
{
	/* A sphere of radius 10 on the bed overhangs below its equator only:
	 * support stays under the lower half, outside the sphere by the xy
	 * spacing on every layer, and reaches up to just under the 45 degree
	 * latitude at threshold 45 (above it each layer steps in less than
	 * it steps out below). */
	struct mesh *m = fx_sphere(0, 0, 10, 10, 48, 96);
	struct slice_stack *st = slice_ok(m);
	struct support_settings s;
	size_t top = 0;

	support_settings_init(&s, 0.4);
	s.support_material = true;
	s.support_material_threshold = 45;
	struct layer_stack *ls = support_ok(&s, st);
	double w = s.extrusion_width * NM, clear = s.support_material_xy_spacing * NM;
	for (size_t j = 0; j < ls->nlayers; j++) {
		const struct layer_paths *l = &ls->layers[j];
		const struct clip_paths *sec = &st->layers[j].regions.paths;
		double r = 0.0; /* the section's outermost vertex */
		for (size_t k = 0; k < clip_paths_points(sec); k++)
			r = fmax(r, hypot((double)sec->xy[2 * k], (double)sec->xy[2 * k + 1]));
		if (l->n)
			top = j;
		for (size_t i = 0; i < l->n; i++)
			for (size_t k = 0; k < l->paths[i].n; k++) {
				const struct path_point *q = &l->paths[i].pts[k];
				ck_assert_msg(hypot((double)q->x, (double)q->y) >= r + clear + w / 2 -
										  TOL,
					      "layer %zu: bead %.3f mm from the axis, sphere %.3f", j,
					      hypot((double)q->x, (double)q->y) / NM, r / NM);
			}
	}
	/* 45 degrees down from the equator lies at z = 10 - 7.07 = 2.93. */
	ck_assert_msg(st->layers[top].z > 2.0 && st->layers[top].z < 3.0, "support up to z %.2f",
		      st->layers[top].z);
	ck_assert_uint_gt(ls->layers[0].n, 4);
	release(ls, st, m);
}
END_TEST

START_TEST(support_settings_refused)
{
	struct mesh *m = cantilever();
	struct slice_stack *st = slice_ok(m);
	struct layer_stack *ls = stack_for(st), *short_ls = layer_stack_new(2, NULL);
	struct support_settings s, bad;
	struct st_error err = {0};

	support_settings_init(&s, 0.4);
	s.support_material = true;
	ck_assert_int_eq(support_settings_check(&s, &err), 0);
	const double thresholds[] = {-1, 90.5, NAN};
	for (size_t i = 0; i < 3; i++) {
		bad = s;
		bad.support_material_threshold = thresholds[i];
		ck_assert_int_eq(support_generate(&bad, st, ls, &err), ST_ERR_RANGE);
		ck_assert_ptr_nonnull(strstr(err.msg, "support_material_threshold"));
	}
	bad = s;
	bad.support_material_spacing = 0;
	ck_assert_int_eq(support_settings_check(&bad, &err), ST_ERR_RANGE);
	ck_assert_ptr_nonnull(strstr(err.msg, "support_material_spacing"));
	bad = s;
	bad.support_material_interface_layers = -1;
	ck_assert_int_eq(support_settings_check(&bad, &err), ST_ERR_RANGE);
	bad = s;
	bad.support_material_contact_distance = -0.1;
	ck_assert_int_eq(support_settings_check(&bad, &err), ST_ERR_RANGE);
	bad = s;
	bad.support_material_xy_spacing = -1;
	ck_assert_int_eq(support_settings_check(&bad, &err), ST_ERR_RANGE);
	bad = s;
	bad.support_material_style = SUPPORT_STYLES;
	ck_assert_int_eq(support_settings_check(&bad, &err), ST_ERR_ARG);
	ck_assert_ptr_nonnull(strstr(err.msg, "style"));
	bad = s;
	bad.extrusion_width = 0.1; /* narrower than the flow model allows at 0.2 mm */
	ck_assert_int_eq(support_generate(&bad, st, ls, &err), ST_ERR_RANGE);
	ck_assert_int_eq(support_generate(&s, st, short_ls, &err), ST_ERR_ARG);
	for (size_t i = 0; i < ls->nlayers; i++)
		ck_assert_uint_eq(ls->layers[i].n, 0);
	/* Interface layers 0 and contact distance 0: body right under the plate. */
	s.support_material_interface_layers = 0;
	s.support_material_contact_distance = 0;
	layer_stack_free(ls);
	ls = support_ok(&s, st);
	ck_assert_uint_gt(tu_count_role(&ls->layers[24], PATH_SUPPORT), 0);
	ck_assert_uint_eq(count_support(&ls->layers[25]), 0);
	for (size_t j = 0; j < ls->nlayers; j++)
		ck_assert_uint_eq(tu_count_role(&ls->layers[j], PATH_SUPPORT_INTERFACE), 0);
	layer_stack_free(ls);
	layer_stack_free(short_ls);
	slice_stack_free(st);
	mesh_free(m);
}
END_TEST

Suite *support_suite(void)
{
	Suite *s = suite_create("support");
	TCase *tc = tcase_create("core");

	tcase_set_timeout(tc, 60);
	tcase_add_test(tc, skirt_one_loop_around_cube);
	tcase_add_test(tc, skirt_min_length_adds_loops);
	tcase_add_test(tc, brim_attached_to_part);
	tcase_add_test(tc, skirt_settings_refused);
	tcase_add_test(tc, support_under_cantilever_grid);
	tcase_add_test(tc, support_under_cantilever_snug);
	tcase_add_test(tc, support_body_patterns);
	tcase_add_test(tc, support_off_and_skirt_around_it);
	tcase_add_test(tc, support_by_overhang_angle);
	tcase_add_test(tc, support_only_from_the_bed);
	tcase_add_test(tc, support_under_sphere);
	tcase_add_test(tc, support_settings_refused);
	suite_add_tcase(s, tc);
	return s;
}
