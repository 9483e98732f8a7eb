/*
 * check_slicer.c - slicing, the Clipper bridge, walls, thin walls and gap
 * fill on meshes built in code, with expectations that follow from the
 * geometry: a wall's centre line w/2 inside the surface, a wall of exactly
 * the nozzle diameter printed as one bead along its centre.
 */
#include <check.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "clip.h"
#include "fixtures.h"
#include "mesh.h"
#include "perimeters.h"
#include "section.h"
#include "slicer.h"
#include "suites.h"
#include "testutil.h"
#include "toolpath.h"

#define NM SLICE_UNITS_PER_MM
#define UM 1000.0 /* nm */

/* ---- meshes ---- */

static uint32_t vtx(struct mesh_builder *b, double x, double y, double z)
{
	const double p[3] = {x, y, z};
	uint32_t i;

	ck_assert_int_eq(mesh_builder_vertex(b, p, &i, NULL), 0);
	return i;
}

static void tri(struct mesh_builder *b, uint32_t a, uint32_t c, uint32_t d, bool flip)
{
	ck_assert_int_eq(flip ? mesh_builder_triangle(b, a, d, c, NULL)
			      : mesh_builder_triangle(b, a, c, d, NULL),
			 0);
}

/* Quad a-b-c-d, counter-clockwise seen from outside. */
static void quad(struct mesh_builder *b, uint32_t a, uint32_t c, uint32_t d, uint32_t e, bool flip)
{
	tri(b, a, c, d, flip);
	tri(b, a, d, e, flip);
}

/*
 * Prism over the convex polygon (x[i], y[i]) (counter-clockwise) from z0 to
 * z1; flip turns it inside out (a hole when added to an enclosing solid).
 */
static void add_prism(struct mesh_builder *b, const double *x, const double *y, int n, double z0,
		      double z1, bool flip)
{
	uint32_t *lo = malloc(n * sizeof(*lo)), *hi = malloc(n * sizeof(*hi));

	ck_assert(lo && hi);
	for (int i = 0; i < n; i++) {
		lo[i] = vtx(b, x[i], y[i], z0);
		hi[i] = vtx(b, x[i], y[i], z1);
	}
	for (int i = 1; i + 1 < n; i++) {
		tri(b, lo[0], lo[i + 1], lo[i], flip);
		tri(b, hi[0], hi[i], hi[i + 1], flip);
	}
	for (int i = 0; i < n; i++)
		quad(b, lo[i], lo[(i + 1) % n], hi[(i + 1) % n], hi[i], flip);
	free(lo);
	free(hi);
}

/* Regular n-gon of radius r around (cx, cy), vertices on the circle. */
static void ngon(double cx, double cy, double r, int n, double *x, double *y)
{
	for (int i = 0; i < n; i++) {
		x[i] = cx + r * cos(2 * M_PI * i / n);
		y[i] = cy + r * sin(2 * M_PI * i / n);
	}
}

static struct mesh *cylinder(double r, int n, double height)
{
	struct mesh_builder *b = mesh_builder_new(0);
	double *x = malloc(n * sizeof(*x)), *y = malloc(n * sizeof(*y));

	ck_assert(b && x && y);
	ngon(0, 0, r, n, x, y);
	add_prism(b, x, y, n, 0, height, false);
	free(x);
	free(y);
	return mesh_builder_finish(b);
}

/* ---- geometry helpers ---- */

static double seg_dist(double px, double py, double ax, double ay, double bx, double by)
{
	double dx = bx - ax, dy = by - ay, l2 = dx * dx + dy * dy;
	double t = l2 > 0 ? ((px - ax) * dx + (py - ay) * dy) / l2 : 0;

	t = fmin(1, fmax(0, t));
	return hypot(ax + t * dx - px, ay + t * dy - py);
}

/* Distance (nm) from (px, py) to the nearest edge of any closed path of ps. */
static double dist_to_paths(const struct clip_paths *ps, double px, double py)
{
	double best = INFINITY;

	for (size_t i = 0; i < ps->n; i++) {
		const int64_t *xy = clip_path_xy(ps, i);
		size_t n = clip_path_len(ps, i);
		for (size_t k = 0; k < n; k++) {
			size_t j = (k + 1) % n;
			best = fmin(best, seg_dist(px, py, xy[2 * k], xy[2 * k + 1], xy[2 * j],
						   xy[2 * j + 1]));
		}
	}
	return best;
}

static const struct toolpath *first_role(const struct layer_paths *l, enum path_role role)
{
	for (size_t i = 0; i < l->n; i++)
		if (l->paths[i].role == role)
			return &l->paths[i];
	return NULL;
}

/* Signed area (nm^2) of a closed toolpath, > 0 counter-clockwise. */
static double path_area(const struct toolpath *p)
{
	double a = 0;

	for (size_t i = 0; i < p->n; i++) {
		size_t j = (i + 1) % p->n;
		a += (double)p->pts[i].x * p->pts[j].y - (double)p->pts[j].x * p->pts[i].y;
	}
	return a / 2;
}

static void free_paths(struct layer_paths *l)
{
	for (size_t i = 0; i < l->n; i++)
		free(l->paths[i].pts);
	free(l->paths);
	memset(l, 0, sizeof(*l));
}

static struct slice_stack *slice_ok(const struct mesh *m, double first, double h)
{
	struct st_error err = {0};
	struct slice_stack *st = NULL;

	ck_assert_msg(slice_mesh(m, first, h, NULL, &st, &err) == 0, "slice_mesh: %s", err.msg);
	ck_assert_ptr_nonnull(st);
	return st;
}

/* Walls of one layer with settings s; infill into *inner (caller frees). */
static void walls_ok(const struct perim_settings *s, const struct slice_layer *sl,
		     struct layer_paths *out, struct clip_expolys *inner)
{
	struct st_error err = {0};

	memset(out, 0, sizeof(*out));
	ck_assert_msg(perim_generate(s, &sl->regions, sl->height, NULL, out, inner, NULL, &err) == 0,
		      "perim_generate: %s", err.msg);
}

/* ---- tests ---- */

START_TEST(clip_bridge_basics)
{
	const int64_t a[] = {0, 0, 10, 0, 10, 10, 0, 10}, b[] = {5, 5, 15, 5, 15, 15, 5, 15};
	struct clip_paths A = {0}, B = {0}, out = {0};
	struct clip_expolys ex = {0};
	struct st_error err = {0};
	double area;
	int where;

	ck_assert_int_eq(clip_paths_add(&A, a, 4, &err), 0);
	ck_assert_int_eq(clip_paths_add(&B, b, 4, &err), 0);
	const double expect[CLIP_OPS] = {175, 75, 25, 150};
	for (int op = 0; op < CLIP_OPS; op++) {
		ck_assert_int_eq(clip_boolean(op, &A, &B, CLIP_NONZERO, &out, &err), 0);
		ck_assert_int_eq(clip_paths_area(&out, &area, &err), 0);
		ck_assert_msg(fabs(area - expect[op]) < 1e-9, "op %d area %g", op, area);
	}
	ck_assert_int_eq(clip_boolean(CLIP_OPS, &A, &B, CLIP_NONZERO, &out, &err), ST_ERR_ARG);
	ck_assert_ptr_nonnull(strstr(err.msg, "operation"));
	ck_assert_int_eq(clip_boolean(CLIP_UNION, &A, &B, (enum clip_fill)9, &out, &err),
			 ST_ERR_ARG);
	/* A square with a square hole: one expolygon, outer CCW, hole CW. */
	const int64_t big[] = {0, 0, 100, 0, 100, 100, 0, 100}, hole[] = {40, 40, 60, 40, 60, 60, 40, 60};
	clip_paths_clear(&A);
	clip_paths_add(&A, big, 4, &err);
	clip_paths_add(&A, hole, 4, &err);
	ck_assert_int_eq(clip_boolean_ex(CLIP_UNION, &A, NULL, CLIP_EVEN_ODD, &ex, &err), 0);
	ck_assert_uint_eq(ex.n, 1);
	ck_assert_uint_eq(ex.first[1] - ex.first[0], 2);
	clip_area(clip_path_xy(&ex.paths, 0), clip_path_len(&ex.paths, 0), &area, &err);
	ck_assert(area == 10000);
	clip_area(clip_path_xy(&ex.paths, 1), clip_path_len(&ex.paths, 1), &area, &err);
	ck_assert(area == -400);
	ck_assert_int_eq(clip_point_in_polygon(50, 50, big, 4, &where, &err), 0);
	ck_assert_int_eq(where, 1);
	ck_assert_int_eq(clip_point_in_polygon(100, 50, big, 4, &where, &err), 0);
	ck_assert_int_eq(where, -1);
	ck_assert_int_eq(clip_point_in_polygon(150, 50, big, 4, &where, &err), 0);
	ck_assert_int_eq(where, 0);
	/* Round offset of a point-like square approaches a disk. */
	const int64_t sq[] = {0, 0, 1000, 0, 1000, 1000, 0, 1000};
	clip_paths_clear(&A);
	clip_paths_add(&A, sq, 4, &err);
	ck_assert_int_eq(clip_offset(&A, 1e6, CLIP_JOIN_ROUND, 0, 100, &out, &err), 0);
	clip_paths_area(&out, &area, &err);
	ck_assert_msg(fabs(area - (M_PI * 1e12 + 4e9 + 1e6)) < 1e-3 * M_PI * 1e12, "area %g", area);
	ck_assert_int_eq(clip_offset(&A, 10, CLIP_JOIN_MITER, 1.0, 0, &out, &err), ST_ERR_ARG);
	/* An open line grown by 5 each side with butt ends: 105 x 10. */
	const int64_t line[] = {-5, 5, 100, 5};
	clip_paths_clear(&A);
	clip_paths_add(&A, line, 2, &err);
	ck_assert_int_eq(clip_offset_open(&A, 5, CLIP_JOIN_MITER, CLIP_END_BUTT, 2, 0, &out, &err), 0);
	clip_paths_area(&out, &area, &err);
	ck_assert(fabs(area - 1050) < 1e-9);
	/* Clip that line by the square: 10 units remain inside. */
	clip_paths_clear(&B);
	clip_paths_add(&B, a, 4, &err);
	ck_assert_int_eq(clip_lines(CLIP_INTERSECTION, &A, &B, CLIP_NONZERO, &out, &err), 0);
	ck_assert_uint_eq(out.n, 1);
	ck_assert_int_eq(llabs(clip_path_xy(&out, 0)[0] - clip_path_xy(&out, 0)[2]), 10);
	clip_paths_free(&A);
	clip_paths_free(&B);
	clip_paths_free(&out);
	clip_expolys_free(&ex);
}
END_TEST

START_TEST(cube_layers_and_outer_wall)
{
	struct mesh *m = fx_box(0, 0, 0, 20, 20, 20);
	struct slice_stack *st = slice_ok(m, 0.3, 0.2);
	struct perim_settings s;
	struct layer_paths out;
	struct clip_expolys inner = {0};

	/* Planes at 0.15, then 0.4, 0.6, ... while below 20: 99 layers, top 19.9. */
	ck_assert_uint_eq(st->n, 99);
	ck_assert(st->layers[0].z == 0.3 && st->layers[0].height == 0.3);
	ck_assert(fabs(st->layers[0].slice_z - 0.15) < 1e-12);
	ck_assert(fabs(st->layers[1].z - 0.5) < 1e-12 && st->layers[1].height == 0.2);
	ck_assert(fabs(st->layers[98].z - 19.9) < 1e-9);
	for (size_t i = 0; i < st->n; i++) {
		ck_assert_uint_eq(st->layers[i].regions.n, 1);
		ck_assert_uint_eq(st->layers[i].open_dropped, 0);
	}
	slice_stack_free(st);
	st = slice_ok(m, 0.2, 0.2);
	ck_assert_uint_eq(st->n, 100);
	ck_assert(fabs(st->layers[99].z - 20.0) < 1e-9);

	perim_settings_init(&s, 0.4);
	ck_assert(fabs(s.extrusion_width - 0.45) < 1e-15);
	const struct slice_layer *sl = &st->layers[10];
	walls_ok(&s, sl, &out, &inner);
	double w = 0.45 * NM, sp = perim_spacing(0.45, 0.2) * NM;
	ck_assert_uint_eq(tu_count_role(&out, PATH_OUTER_PERIMETER), 1);
	ck_assert_uint_eq(tu_count_role(&out, PATH_INNER_PERIMETER), 1);
	ck_assert_uint_eq(tu_count_role(&out, PATH_THIN_WALL), 0);
	ck_assert_uint_eq(tu_count_role(&out, PATH_GAP_FILL), 0);
	/* Inner to outer by default. */
	ck_assert_int_eq(out.paths[0].role, PATH_INNER_PERIMETER);
	ck_assert_int_eq(out.paths[1].role, PATH_OUTER_PERIMETER);
	double worst_outer = 0, worst_inner = 0;
	for (size_t i = 0; i < out.n; i++) {
		const struct toolpath *p = &out.paths[i];
		double want = p->role == PATH_OUTER_PERIMETER ? w / 2 : w / 2 + sp;
		ck_assert(p->closed);
		for (size_t k = 0; k < p->n; k++) {
			double d = dist_to_paths(&sl->regions.paths, p->pts[k].x, p->pts[k].y);
			double e = fabs(d - want);
			if (p->role == PATH_OUTER_PERIMETER)
				worst_outer = fmax(worst_outer, e);
			else
				worst_inner = fmax(worst_inner, e);
			ck_assert_int_eq(p->pts[k].width, llround(w));
		}
	}
	ck_assert_msg(worst_outer <= 1 * UM, "outer wall off by %g nm", worst_outer);
	ck_assert_msg(worst_inner <= 1 * UM, "inner wall off by %g nm", worst_inner);
	/* Outer loop is the 20 mm square shrunk by w/2: area (20 - w)^2. */
	const struct toolpath *o = first_role(&out, PATH_OUTER_PERIMETER);
	ck_assert_uint_eq(o->n, 4);
	double side = 20 * NM - w;
	ck_assert(fabs(path_area(o) - side * side) < 4 * side);
	/* Infill: inside w/2 + 1.5 spacing from the surface. */
	ck_assert_uint_eq(inner.n, 1);
	double ia, iside = 20 * NM - 2 * (w / 2 + 1.5 * sp);
	clip_paths_area(&inner.paths, &ia, NULL);
	ck_assert_msg(fabs(ia - iside * iside) < 8 * iside, "infill area %g", ia);
	free_paths(&out);
	/* outer_first reverses the order. */
	s.outer_first = true;
	walls_ok(&s, sl, &out, &inner);
	ck_assert_int_eq(out.paths[0].role, PATH_OUTER_PERIMETER);
	ck_assert_int_eq(out.paths[1].role, PATH_INNER_PERIMETER);
	free_paths(&out);
	clip_expolys_free(&inner);
	slice_stack_free(st);
	mesh_free(m);
}
END_TEST

START_TEST(cylinder_outer_wall_within_chord)
{
	const int n = 128;
	const double r = 10;
	struct mesh *m = cylinder(r, n, 5);
	struct slice_stack *st = slice_ok(m, 0.2, 0.2);
	struct perim_settings s;
	struct layer_paths out;
	struct clip_expolys inner = {0};
	double w = 0.45 * NM, sag = r * (1 - cos(M_PI / n)) * NM;

	perim_settings_init(&s, 0.4);
	walls_ok(&s, &st->layers[3], &out, &inner);
	const struct toolpath *o = first_role(&out, PATH_OUTER_PERIMETER);
	ck_assert_ptr_nonnull(o);
	ck_assert_uint_eq(tu_count_role(&out, PATH_OUTER_PERIMETER), 1);
	ck_assert(path_area(o) > 0); /* counter-clockwise */
	double worst_poly = 0, worst_circle = 0;
	for (size_t k = 0; k < o->n; k++) {
		double x = o->pts[k].x, y = o->pts[k].y;
		double d = dist_to_paths(&st->layers[3].regions.paths, x, y);
		worst_poly = fmax(worst_poly, fabs(d - w / 2));
		/* Distance to the true circle minus w/2: within the chord sagitta. */
		double dc = r * NM - hypot(x, y) - w / 2;
		worst_circle = fmax(worst_circle, fabs(dc));
	}
	ck_assert_msg(worst_poly <= 1 * UM, "outer wall off the sliced outline by %g nm",
		      worst_poly);
	ck_assert_msg(worst_circle <= sag + 1 * UM, "outer wall off the circle by %g nm (chord %g)",
		      worst_circle, sag);
	/* Aligned seams: the same point on consecutive layers. */
	struct perim_seams *sm = perim_seams_new(1);
	struct layer_paths l1 = {0}, l2 = {0};
	struct st_error err = {0};
	ck_assert_int_eq(perim_generate(&s, &st->layers[4].regions, 0.2, sm, &l1, &inner, NULL, &err), 0);
	ck_assert_int_eq(perim_generate(&s, &st->layers[5].regions, 0.2, sm, &l2, &inner, NULL, &err), 0);
	const struct toolpath *o1 = first_role(&l1, PATH_OUTER_PERIMETER),
			      *o2 = first_role(&l2, PATH_OUTER_PERIMETER);
	ck_assert(hypot((double)(o1->pts[0].x - o2->pts[0].x),
			(double)(o1->pts[0].y - o2->pts[0].y)) < 0.5 * NM);
	free_paths(&l1);
	free_paths(&l2);
	perim_seams_free(sm);
	free_paths(&out);
	clip_expolys_free(&inner);
	slice_stack_free(st);
	mesh_free(m);
}
END_TEST

START_TEST(two_mm_wall_filled_by_walls)
{
	struct mesh *m = fx_box(0, 0, 0, 20, 2, 1);
	struct slice_stack *st = slice_ok(m, 0.2, 0.2);
	struct perim_settings s;
	struct layer_paths out;
	struct clip_expolys inner = {0};
	double w = 0.45, sp = perim_spacing(0.45, 0.2);

	perim_settings_init(&s, 0.4);
	walls_ok(&s, &st->layers[2], &out, &inner);
	ck_assert_uint_eq(tu_count_role(&out, PATH_OUTER_PERIMETER), 1);
	ck_assert_uint_eq(tu_count_role(&out, PATH_INNER_PERIMETER), 1);
	ck_assert_uint_eq(tu_count_role(&out, PATH_THIN_WALL), 0);
	ck_assert_uint_eq(tu_count_role(&out, PATH_GAP_FILL), 0);
	/* The middle strip, 2 - 2 (w/2 + 1.5 s) wide, narrower than a line
	 * spacing: the inner loop's beads take it up, w + iw/2 wide (0.614 mm,
	 * PrusaSlicer's Arachne beads), and nothing is left for infill. */
	double iw = 2 - 2 * (w / 2 + 1.5 * sp), il = 20 - 2 * (w / 2 + 1.5 * sp), widest = 0;
	ck_assert_uint_eq(inner.n, 0);
	const struct toolpath *ip = first_role(&out, PATH_INNER_PERIMETER);
	for (size_t k = 0; k < ip->n; k++)
		widest = fmax(widest, (double)ip->pts[k].width);
	ck_assert_msg(fabs(widest - (w + iw / 2) * NM) < 2 * UM, "inner loop %g mm wide",
		      widest / NM);
	free_paths(&out);
	/* Three walls asked: no room for the third, the strip is gap-filled. */
	s.perimeters = 3;
	walls_ok(&s, &st->layers[2], &out, &inner);
	ck_assert_uint_eq(tu_count_role(&out, PATH_OUTER_PERIMETER), 1);
	ck_assert_uint_eq(tu_count_role(&out, PATH_INNER_PERIMETER), 1);
	ck_assert_uint_eq(tu_count_role(&out, PATH_THIN_WALL), 0);
	ck_assert_uint_eq(tu_count_role(&out, PATH_GAP_FILL), 1);
	ck_assert_uint_eq(inner.n, 0);
	/* The strip runs between the walls' spacing edges: its bead is w - sp
	 * wider, so that its flow fills iw (a bead w wide holds w - (w - sp)). */
	const struct toolpath *g = first_role(&out, PATH_GAP_FILL);
	for (size_t k = 0; k < g->n; k++) {
		ck_assert_msg(fabs(g->pts[k].width - (iw + w - sp) * NM) < 2 * UM, "gap width %lld",
			      (long long)g->pts[k].width);
		ck_assert(fabs(g->pts[k].y - 1 * NM) < 1 * UM);
	}
	double gl = tu_path_length(g) / NM;
	ck_assert_msg(fabs(gl - (il - iw)) < 0.05, "gap fill length %g, want %g", gl, il - iw);
	free_paths(&out);
	clip_expolys_free(&inner);
	slice_stack_free(st);
	mesh_free(m);
}
END_TEST

START_TEST(wall_of_nozzle_width_gets_one_thin_wall)
{
	struct mesh *m = fx_box(0, 0, 0, 20, 0.4, 1);
	struct slice_stack *st = slice_ok(m, 0.2, 0.2);
	struct perim_settings s;
	struct layer_paths out;
	struct clip_expolys inner = {0};

	perim_settings_init(&s, 0.4);
	ck_assert(fabs(s.extrusion_width - 0.45) < 1e-15);
	walls_ok(&s, &st->layers[1], &out, &inner);
	ck_assert_uint_eq(out.n, 1);
	ck_assert_uint_eq(tu_count_role(&out, PATH_THIN_WALL), 1);
	ck_assert_uint_eq(inner.n, 0);
	const struct toolpath *t = &out.paths[0];
	ck_assert(!t->closed);
	for (size_t k = 0; k < t->n; k++) {
		ck_assert_msg(llabs(t->pts[k].width - 400000) <= 1000, "width %lld",
			      (long long)t->pts[k].width);
		ck_assert_msg(fabs(t->pts[k].y - 0.2 * NM) <= 1 * UM, "off centre: y %lld",
			      (long long)t->pts[k].y);
	}
	/* Bead ends are round: the centre line stops w/2 short of each end. */
	double len = tu_path_length(t) / NM;
	ck_assert_msg(fabs(len - (20 - 0.4)) < 0.01, "thin wall length %g", len);
	free_paths(&out);
	/* Without thin walls the wall would be lost entirely. */
	s.thin_walls = false;
	walls_ok(&s, &st->layers[1], &out, &inner);
	ck_assert_uint_eq(out.n, 0);
	free_paths(&out);
	clip_expolys_free(&inner);
	slice_stack_free(st);
	mesh_free(m);
}
END_TEST

START_TEST(pillar_of_nozzle_width_gets_a_bead)
{
	/* An eps x eps square pillar, and a 0.3 mm one (narrower than eps). */
	struct mesh *m = fx_box(0, 0, 0, 0.4, 0.4, 1), *thin = fx_box(0, 0, 0, 0.3, 0.3, 1);
	struct slice_stack *st = slice_ok(m, 0.2, 0.2), *st_thin = slice_ok(thin, 0.2, 0.2);
	struct perim_settings s;
	struct layer_paths out;
	struct clip_expolys inner = {0};

	perim_settings_init(&s, 0.4);
	for (size_t i = 0; i < st->n; i++) {
		walls_ok(&s, &st->layers[i], &out, &inner);
		ck_assert_uint_eq(out.n, 1);
		ck_assert_uint_eq(tu_count_role(&out, PATH_THIN_WALL), 1);
		const struct toolpath *t = &out.paths[0];
		double h = st->layers[i].height, w = t->pts[0].width / NM;
		double len = tu_path_length(t) / NM;
		/* Centred, inside the pillar, and its flow fills the pillar's area. */
		for (size_t k = 0; k < t->n; k++) {
			ck_assert(t->pts[k].x > 0 && t->pts[k].x < 0.4 * NM);
			ck_assert(t->pts[k].y > 0 && t->pts[k].y < 0.4 * NM);
		}
		ck_assert_double_eq_tol((t->pts[0].x + t->pts[1].x) / 2.0 / NM, 0.2, 1e-3);
		ck_assert_double_eq_tol((t->pts[0].y + t->pts[1].y) / 2.0 / NM, 0.2, 1e-3);
		ck_assert_double_eq_tol(perim_bead_area(w, h) * len, 0.16 * h, 0.01 * 0.16 * h);
		free_paths(&out);
	}
	/* Narrower than eps: a bead of min_bead_width whose flow fills it. */
	walls_ok(&s, &st_thin->layers[1], &out, &inner);
	ck_assert_uint_eq(tu_count_role(&out, PATH_THIN_WALL), 1);
	ck_assert_int_eq(out.paths[0].pts[0].width, llround(s.min_bead_width * NM));
	ck_assert_double_eq_tol(perim_bead_area(s.min_bead_width, 0.2) *
					tu_path_length(&out.paths[0]) / NM,
				0.09 * 0.2, 0.01 * 0.09 * 0.2);
	free_paths(&out);
	clip_expolys_free(&inner);
	slice_stack_free(st);
	slice_stack_free(st_thin);
	mesh_free(m);
	mesh_free(thin);
}
END_TEST

START_TEST(plate_holes_stay_holes)
{
	struct mesh_builder *b = mesh_builder_new(0);
	const double px[] = {0, 40, 40, 0}, py[] = {0, 0, 40, 40};
	const double hx[] = {8, 16, 16, 8}, hy[] = {16, 16, 24, 24};
	double cx[64], cy[64];
	struct perim_settings s;
	struct layer_paths out;
	struct clip_expolys inner = {0};
	struct clip_paths holes = {0};
	struct st_error err = {0};

	ck_assert_ptr_nonnull(b);
	add_prism(b, px, py, 4, 0, 3, false);
	add_prism(b, hx, hy, 4, 0, 3, true);
	ngon(28, 20, 4, 64, cx, cy);
	add_prism(b, cx, cy, 64, 0, 3, true);
	struct mesh *m = mesh_builder_finish(b);
	struct slice_stack *st = slice_ok(m, 0.2, 0.2);
	const struct slice_layer *sl = &st->layers[5];

	ck_assert_uint_eq(sl->regions.n, 1);
	ck_assert_uint_eq(sl->regions.first[1] - sl->regions.first[0], 3);
	for (size_t i = 1; i < 3; i++)
		clip_paths_add(&holes, clip_path_xy(&sl->regions.paths, i),
			       clip_path_len(&sl->regions.paths, i), &err);
	perim_settings_init(&s, 0.4);
	walls_ok(&s, sl, &out, &inner);
	double w = 0.45 * NM;
	size_t hole_loops = 0;
	for (size_t i = 0; i < out.n; i++) {
		const struct toolpath *p = &out.paths[i];
		if (p->role != PATH_OUTER_PERIMETER || path_area(p) > 0)
			continue;
		/* A hole's wall: clockwise, w/2 outside one hole boundary. */
		hole_loops++;
		for (size_t k = 0; k < p->n; k++) {
			double d = dist_to_paths(&holes, p->pts[k].x, p->pts[k].y);
			/* Round joins: chords within the arc tolerance of the arc. */
			ck_assert_msg(fabs(d - w / 2) <= s.arc_tolerance * NM + 1,
				      "hole wall off by %g nm", d - w / 2);
		}
	}
	ck_assert_uint_eq(hole_loops, 2);
	ck_assert_uint_eq(tu_count_role(&out, PATH_OUTER_PERIMETER), 3);
	ck_assert_uint_eq(tu_count_role(&out, PATH_INNER_PERIMETER), 3);
	ck_assert_uint_eq(tu_count_role(&out, PATH_THIN_WALL), 0);
	/* The infill region keeps both holes. */
	ck_assert_uint_eq(inner.n, 1);
	ck_assert_uint_eq(inner.first[1] - inner.first[0], 3);
	free_paths(&out);
	clip_paths_free(&holes);
	clip_expolys_free(&inner);
	slice_stack_free(st);
	mesh_free(m);
}
END_TEST

/* Does loop i of ps contain the point (x, y) as a vertex? */
static bool has_vertex(const struct clip_paths *ps, size_t i, double x, double y)
{
	const int64_t *xy = clip_path_xy(ps, i);

	for (size_t k = 0; k < clip_path_len(ps, i); k++)
		if (xy[2 * k] == llround(x * NM) && xy[2 * k + 1] == llround(y * NM))
			return true;
	return false;
}

START_TEST(vertices_on_the_plane)
{
	/* A double pyramid: base square z=0, middle ring exactly on z=0.625, apex. */
	struct mesh_builder *b = mesh_builder_new(0);
	const double bx[] = {-2, 2, 2, -2}, by[] = {-2, -2, 2, 2};
	const double mx[] = {-5, 5, 5, -5}, my[] = {-5, -5, 5, 5};
	uint32_t B[4], M[4], top;
	struct clip_paths loops = {0};
	struct st_error err = {0};
	size_t dropped = 99;
	double area;

	for (int i = 0; i < 4; i++) {
		B[i] = vtx(b, bx[i], by[i], 0);
		M[i] = vtx(b, mx[i], my[i], 0.625);
	}
	top = vtx(b, 0, 0, 2);
	quad(b, B[0], B[3], B[2], B[1], false);
	for (int i = 0; i < 4; i++) {
		quad(b, B[i], B[(i + 1) % 4], M[(i + 1) % 4], M[i], false);
		tri(b, M[i], M[(i + 1) % 4], top, false);
	}
	struct mesh *m = mesh_builder_finish(b);
	ck_assert_int_eq(slice_plane(m, 0.625, 0.0, &loops, &dropped, &err), 0);
	ck_assert_uint_eq(dropped, 0);
	ck_assert_uint_eq(loops.n, 1);
	ck_assert_uint_eq(clip_path_len(&loops, 0), 4); /* each ring vertex once */
	for (int i = 0; i < 4; i++)
		ck_assert(has_vertex(&loops, 0, mx[i], my[i]));
	clip_area(clip_path_xy(&loops, 0), 4, &area, &err);
	ck_assert(area == 100 * NM * NM);
	/* Planes through the apex only and through the base give nothing. */
	ck_assert_int_eq(slice_plane(m, 2.0, 0.0, &loops, &dropped, &err), 0);
	ck_assert_uint_eq(loops.n + dropped, 0);
	ck_assert_int_eq(slice_plane(m, 0.0, 0.0, &loops, &dropped, &err), 0);
	ck_assert_uint_eq(loops.n + dropped, 0);
	mesh_free(m);

	/* A step: a horizontal annulus lies exactly in the plane z=0.625. */
	b = mesh_builder_new(0);
	const double ox[] = {0, 20, 20, 0}, oy[] = {0, 0, 20, 20};
	const double ix[] = {5, 15, 15, 5}, iy[] = {5, 5, 15, 15};
	uint32_t L0[4], L1[4], U0[4], U1[4];
	for (int i = 0; i < 4; i++) {
		L0[i] = vtx(b, ox[i], oy[i], 0);
		L1[i] = vtx(b, ox[i], oy[i], 0.625);
		U0[i] = vtx(b, ix[i], iy[i], 0.625);
		U1[i] = vtx(b, ix[i], iy[i], 2);
	}
	quad(b, L0[0], L0[3], L0[2], L0[1], false);
	quad(b, U1[0], U1[1], U1[2], U1[3], false);
	for (int i = 0; i < 4; i++) {
		int j = (i + 1) % 4;
		quad(b, L0[i], L0[j], L1[j], L1[i], false);
		quad(b, L1[i], L1[j], U0[j], U0[i], false);
		quad(b, U0[i], U0[j], U1[j], U1[i], false);
	}
	m = mesh_builder_finish(b);
	ck_assert_int_eq(slice_plane(m, 0.625, 0.0, &loops, &dropped, &err), 0);
	ck_assert_uint_eq(dropped, 0);
	ck_assert_uint_eq(loops.n, 1);
	ck_assert_uint_eq(clip_path_len(&loops, 0), 4);
	for (int i = 0; i < 4; i++)
		ck_assert(has_vertex(&loops, 0, ox[i], oy[i]));
	/* Layers of 0.5 then 0.25: layer 1 is cut at exactly 0.625. */
	struct slice_settings ss;
	struct slice_stack *st = NULL;
	slice_settings_init(&ss);
	ss.nozzle_diameter = 0.6;
	ck_assert_int_eq(slice_mesh(m, 0.5, 0.25, &ss, &st, &err), 0);
	ck_assert(st->layers[1].slice_z == 0.625);
	ck_assert_uint_eq(st->layers[1].regions.n, 1);
	clip_paths_area(&st->layers[1].regions.paths, &area, &err);
	ck_assert(area == 400 * NM * NM);
	clip_paths_area(&st->layers[2].regions.paths, &area, &err);
	ck_assert(area == 100 * NM * NM);
	slice_stack_free(st);
	clip_paths_free(&loops);
	mesh_free(m);
}
END_TEST

START_TEST(open_contour_gap_closed)
{
	/* A cube missing one side triangle: the cut has one open chain whose
	 * ends are the two ends of the missing segment. */
	struct mesh *m = fx_box(0, 0, 0, 10, 10, 10);
	struct clip_paths loops = {0};
	struct st_error err = {0};
	size_t dropped = 0;

	fx_drop(m, 4); /* first triangle of the y = 0 side */
	ck_assert_int_eq(slice_plane(m, 2.0, 0.0, &loops, &dropped, &err), 0);
	ck_assert_uint_eq(loops.n, 0);
	ck_assert_uint_eq(dropped, 1);
	ck_assert_int_eq(slice_plane(m, 2.0, 20.0, &loops, &dropped, &err), 0);
	ck_assert_uint_eq(loops.n, 1);
	ck_assert_uint_eq(dropped, 0);
	clip_paths_free(&loops);
	mesh_free(m);
}
END_TEST

START_TEST(bad_settings_refused)
{
	struct mesh *m = fx_box(0, 0, 0, 10, 10, 10);
	struct slice_stack *st = (struct slice_stack *)&st;
	struct perim_settings s;
	struct st_error err = {0};

	ck_assert_int_eq(slice_mesh(m, 0.2, 0.5, NULL, &st, &err), ST_ERR_RANGE);
	ck_assert_ptr_null(st);
	ck_assert_msg(strstr(err.msg, "layer height 0.5 mm") && strstr(err.msg, "nozzle"), "%s",
		      err.msg);
	ck_assert_int_eq(slice_mesh(m, 0.0, 0.2, NULL, &st, &err), ST_ERR_RANGE);
	ck_assert_ptr_nonnull(strstr(err.msg, "first layer height"));
	perim_settings_init(&s, 0.4);
	ck_assert_int_eq(perim_settings_check(&s, 0.2, &err), 0);
	ck_assert_int_eq(perim_settings_check(&s, 0.45, &err), ST_ERR_RANGE);
	ck_assert_msg(strstr(err.msg, "layer height 0.45 mm is larger than the nozzle"), "%s",
		      err.msg);
	s.perimeters = -1;
	ck_assert_int_eq(perim_settings_check(&s, 0.2, &err), ST_ERR_RANGE);
	ck_assert_msg(strstr(err.msg, "perimeter count -1 is negative"), "%s", err.msg);
	perim_settings_init(&s, 0.4);
	s.extrusion_width = 0;
	ck_assert_int_eq(perim_settings_check(&s, 0.2, &err), ST_ERR_RANGE);
	ck_assert_msg(strstr(err.msg, "extrusion width 0 mm must be greater than 0"), "%s",
		      err.msg);
	s.extrusion_width = -0.4;
	ck_assert_int_eq(perim_settings_check(&s, 0.2, &err), ST_ERR_RANGE);
	perim_settings_init(&s, 0.4);
	s.seam = PERIM_SEAMS;
	ck_assert_int_eq(perim_settings_check(&s, 0.2, &err), ST_ERR_ARG);
	/* perim_generate refuses them too, adding nothing. */
	struct clip_expolys none = {0}, inner = {0};
	struct layer_paths out = {0};
	s.seam = PERIM_SEAM_ALIGNED;
	s.perimeters = -3;
	ck_assert_int_eq(perim_generate(&s, &none, 0.2, NULL, &out, &inner, NULL, &err), ST_ERR_RANGE);
	ck_assert_uint_eq(out.n, 0);
	mesh_free(m);
}
END_TEST

START_TEST(seam_hides_in_concave_corner)
{
	/* An L-shaped island: one concave corner, at (10, 10). */
	const int64_t L[] = {0, 0, 20, 0, 20, 10, 10, 10, 10, 20, 0, 20};
	struct clip_paths p = {0};
	struct clip_expolys region = {0}, inner = {0};
	struct perim_settings s;
	struct layer_paths out = {0};
	struct st_error err = {0};
	int64_t xy[12];

	for (int i = 0; i < 12; i++)
		xy[i] = L[i] * (int64_t)NM;
	clip_paths_add(&p, xy, 6, &err);
	ck_assert_int_eq(clip_boolean_ex(CLIP_UNION, &p, NULL, CLIP_NONZERO, &region, &err), 0);
	perim_settings_init(&s, 0.4);
	for (int mode = 0; mode < PERIM_SEAMS; mode++) {
		s.seam = mode;
		ck_assert_int_eq(perim_generate(&s, &region, 0.2, NULL, &out, &inner, NULL, &err), 0);
		const struct toolpath *o = first_role(&out, PATH_OUTER_PERIMETER);
		/* The outer wall's concave corner is an arc of radius w/2 around (10, 10). */
		double d = hypot(o->pts[0].x - 10 * NM, o->pts[0].y - 10 * NM);
		ck_assert_msg(fabs(d - 0.225 * NM) < 2 * UM, "mode %d: seam %g mm from the corner",
			      mode, d / NM);
		free_paths(&out);
	}
	clip_paths_free(&p);
	clip_expolys_free(&region);
	clip_expolys_free(&inner);
}
END_TEST

START_TEST(flow_model)
{
	/* (w - h) h + pi (h/2)^2 = s h */
	double w = 0.45, h = 0.2;
	ck_assert(fabs(perim_bead_area(w, h) - perim_spacing(w, h) * h) < 1e-15);
	ck_assert(fabs(perim_spacing(w, h) - (0.45 - 0.2 * (1 - M_PI / 4))) < 1e-15);
}
END_TEST

Suite *slicer_suite(void)
{
	Suite *s = suite_create("slicer");
	TCase *tc = tcase_create("geometry");

	tcase_set_timeout(tc, 60);
	tcase_add_test(tc, clip_bridge_basics);
	tcase_add_test(tc, cube_layers_and_outer_wall);
	tcase_add_test(tc, cylinder_outer_wall_within_chord);
	tcase_add_test(tc, two_mm_wall_filled_by_walls);
	tcase_add_test(tc, wall_of_nozzle_width_gets_one_thin_wall);
	tcase_add_test(tc, pillar_of_nozzle_width_gets_a_bead);
	tcase_add_test(tc, plate_holes_stay_holes);
	tcase_add_test(tc, vertices_on_the_plane);
	tcase_add_test(tc, open_contour_gap_closed);
	tcase_add_test(tc, bad_settings_refused);
	tcase_add_test(tc, seam_hides_in_concave_corner);
	tcase_add_test(tc, flow_model);
	suite_add_tcase(s, tc);
	slicer_modes_tcases(s);
	slicer_travel_tcases(s);
	slicer_clip_tcases(s);
	return s;
}
