/*
 * check_simplify.c - gcode_resolution (part of the gcodewriter suite):
 * slicer/simplify.h's deviation bound on random and circle-like
 * polylines, simplify_balance's area, and the writer's use of it: filament
 * preserved, closed loops closed, widths never merged, routed travels
 * simplified inside the part, 0 = off byte for byte the output from before
 * the key existed (tests/data/gcodew-dense-r0.gcode), and a sliced model
 * written in fewer lines.
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clip.h"
#include "fixtures.h"
#include "gcode_writer.h"
#include "meshio.h"
#include "simplify.h"
#include "suites.h"
#include "testutil.h"
#include "travel.h"

#define NM 1000000.0 /* nm per mm */
#define GOLDEN "tests/data/gcodew-dense-r0.gcode"
#define RES 0.0125 /* mm, the default gcode_resolution */

/* ---------------------------------------------------------------------------
 * The bound, checked apart from simplify.c's own arithmetic
 */

/* Distance (nm) from p to the segment a-b, in long double. */
static long double seg_dist(const int64_t *p, const int64_t *a, const int64_t *b)
{
	long double dx = (long double)(b[0] - a[0]), dy = (long double)(b[1] - a[1]);
	long double qx = (long double)(p[0] - a[0]), qy = (long double)(p[1] - a[1]);
	long double l2 = dx * dx + dy * dy, t = l2 > 0 ? (qx * dx + qy * dy) / l2 : 0;

	t = t < 0 ? 0 : t > 1 ? 1 : t;
	return hypotl(qx - t * dx, qy - t * dy);
}

/* Mark xy[0 .. 2n) within tol nm; every dropped point within tol of the
 * segment between its kept neighbours.  Returns the points kept. */
static size_t mark_and_check(const int64_t *xy, size_t n, double tol)
{
	struct simplify_work wk = {0};
	bool *keep = calloc(n, sizeof(*keep));
	size_t kept = 0, prev = 0;

	ck_assert_ptr_nonnull(keep);
	ck_assert_int_eq(simplify_mark(&wk, xy, n, tol, keep, NULL), 0);
	ck_assert(keep[0] && keep[n - 1]);
	for (size_t k = 1; k < n; k++) {
		if (!keep[k])
			continue;
		for (size_t d = prev + 1; d < k; d++) {
			long double dev = seg_dist(xy + 2 * d, xy + 2 * prev, xy + 2 * k);
			ck_assert_msg(dev <= tol, "point %zu is %.3Lf nm from the simplified line "
				      "(tolerance %.0f nm)", d, dev, tol);
		}
		prev = k;
	}
	for (size_t k = 0; k < n; k++)
		kept += keep[k];
	free(keep);
	simplify_work_free(&wk);
	return kept;
}

/* A fixed generator, the same sequence everywhere. */
static uint64_t rnd_next(uint64_t *st)
{
	*st = *st * 6364136223846793005ull + 1442695040888963407ull;
	return *st >> 33;
}

/* Random walks: steps up to 0.5 mm in any direction, turns of any angle
 * (hairpins included), some points repeated; tolerances from 2 nm to
 * 0.2 mm. */
START_TEST(bound_on_random_polylines)
{
	static const double tols[] = {2, 1000, RES * NM, 0.2 * NM};
	uint64_t st = 12345;
	size_t n = 400, dropped = 0;
	int64_t *xy = malloc(2 * n * sizeof(*xy));

	ck_assert_ptr_nonnull(xy);
	for (int round = 0; round < 50; round++) {
		xy[0] = 100000000;
		xy[1] = 100000000;
		for (size_t k = 1; k < n; k++) {
			int64_t step = (int64_t)(rnd_next(&st) % 500000), r = (int64_t)(rnd_next(&st) % 8);
			xy[2 * k] = xy[2 * k - 2] + (r == 0 ? 0 : (int64_t)(rnd_next(&st) % (2 * step + 1)) - step);
			xy[2 * k + 1] = xy[2 * k - 1] + (r == 0 ? 0 : (int64_t)(rnd_next(&st) % (2 * step + 1)) - step);
		}
		for (size_t t = 0; t < sizeof(tols) / sizeof(tols[0]); t++)
			dropped += n - mark_and_check(xy, n, tols[t]);
	}
	ck_assert_uint_gt(dropped, 0);
	free(xy);
}
END_TEST

/* Circles and arcs of 0.2 to 100 mm radius, 8 to 4000 points, closed as
 * polylines (first point repeated), with and without 1 um of noise: within
 * the bound, and about the chords a circle needs at that tolerance. */
START_TEST(bound_on_circles)
{
	static const double radii[] = {0.2, 1, 6.5, 10, 37, 100};
	static const size_t counts[] = {8, 64, 360, 4000};
	uint64_t st = 99;

	for (size_t ri = 0; ri < sizeof(radii) / sizeof(radii[0]); ri++)
		for (size_t ci = 0; ci < sizeof(counts) / sizeof(counts[0]); ci++)
			for (int noise = 0; noise < 2; noise++) {
				size_t n = counts[ci] + 1, kept;
				double r = radii[ri] * NM;
				int64_t *xy = malloc(2 * n * sizeof(*xy));
				ck_assert_ptr_nonnull(xy);
				for (size_t k = 0; k < n; k++) {
					double a = 2 * M_PI * (double)(k % counts[ci]) / (double)counts[ci];
					int64_t jx = noise ? (int64_t)(rnd_next(&st) % 2001) - 1000 : 0;
					int64_t jy = noise ? (int64_t)(rnd_next(&st) % 2001) - 1000 : 0;
					xy[2 * k] = llround(150 * NM + r * cos(a)) + (k % counts[ci] ? jx : 0);
					xy[2 * k + 1] = llround(150 * NM + r * sin(a)) + (k % counts[ci] ? jy : 0);
				}
				kept = mark_and_check(xy, n, RES * NM);
				/* A chord of sagitta RES spans 2 acos(1 - RES / r). */
				double need = 2 * M_PI / (2 * acos(1 - RES * NM / r));
				if (counts[ci] > 2 * need)
					ck_assert_msg(kept <= 2 * need + 3,
						      "r %g mm, %zu points: %zu kept, %g chords suffice",
						      radii[ri], counts[ci], kept, need);
				free(xy);
			}
}
END_TEST

/* A round wall's chords moved out (simplify_balance) keep the circle's
 * area, where the kept points alone lose 1.5e-3 of it, and stay within
 * the bound of every point of the circle. */
START_TEST(balance_keeps_area)
{
	size_t n = 257, m = 0;
	int64_t xy[2 * 257], out[2 * 257];
	bool keep[257];
	struct simplify_work wk = {0};
	double a0 = 0, a1 = 0, a2 = 0;

	for (size_t k = 0; k < n; k++) {
		double a = 2 * M_PI * (double)(k % 256) / 256;
		xy[2 * k] = llround(9.775 * NM * cos(a));
		xy[2 * k + 1] = llround(9.775 * NM * sin(a));
	}
	ck_assert_int_eq(simplify_mark(&wk, xy, n, RES * NM, keep, NULL), 0);
	ck_assert(simplify_balance(xy, n, keep, RES * NM, out));
	for (size_t k = 0; k < n; k++)
		m += keep[k];
	ck_assert_uint_lt(m, 80);
	/* The seam, first and last, stays where it was. */
	ck_assert(out[0] == xy[0] && out[1] == xy[1]);
	ck_assert(out[2 * m - 2] == xy[2 * n - 2] && out[2 * m - 1] == xy[2 * n - 1]);
	for (size_t k = 0; k + 1 < n; k++)
		a0 += (double)xy[2 * k] * (double)xy[2 * k + 3] - (double)xy[2 * k + 2] * (double)xy[2 * k + 1];
	for (size_t j = 0, k = 0; j + 1 < m; j++) {
		size_t next = k + 1, a = k;
		while (!keep[next])
			next++;
		a1 += (double)out[2 * j] * (double)out[2 * j + 3] - (double)out[2 * j + 2] * (double)out[2 * j + 1];
		a2 += (double)xy[2 * a] * (double)xy[2 * next + 1] - (double)xy[2 * next] * (double)xy[2 * a + 1];
		for (size_t i = a; i <= next; i++)
			ck_assert_msg(seg_dist(xy + 2 * i, out + 2 * j, out + 2 * j + 2) <= RES * NM,
				      "point %zu off its moved chord", i);
		k = next;
	}
	ck_assert_msg(fabs(a1 / a0 - 1) < 1e-4, "moved chords: area %.6g of the circle's", a1 / a0);
	ck_assert_msg(a2 / a0 < 1 - 1e-3, "kept points: area %.6g of the circle's", a2 / a0);
	simplify_work_free(&wk);
}
END_TEST

/* A closed loop balanced as one (simplify_balance_loop): its seam moves
 * out with the other kept points, where simplify_balance leaves it on the
 * circle, a dent two thirds of a chord's sagitta deep; and every point of
 * the circle stays within the bound of its moved chord. */
START_TEST(balance_loop_moves_seam)
{
	size_t n = 257, m = 0;
	int64_t xy[2 * 257], out[2 * 257];
	bool keep[257];
	struct simplify_work wk = {0};
	double rmin = INFINITY, rmax = 0;

	for (size_t k = 0; k < n; k++) {
		double a = 2 * M_PI * (double)(k % 256) / 256;
		xy[2 * k] = llround(9.775 * NM * cos(a));
		xy[2 * k + 1] = llround(9.775 * NM * sin(a));
	}
	ck_assert_int_eq(simplify_mark(&wk, xy, n, RES * NM, keep, NULL), 0);
	ck_assert(simplify_balance_loop(xy, n, keep, RES * NM, out));
	for (size_t k = 0; k < n; k++)
		m += keep[k];
	ck_assert(out[0] == out[2 * m - 2] && out[1] == out[2 * m - 1]);
	for (size_t j = 0; j < m; j++) {
		double r = hypot((double)out[2 * j], (double)out[2 * j + 1]);
		rmin = fmin(rmin, r);
		rmax = fmax(rmax, r);
	}
	/* the kept points all move out alike: a few nm apart, not microns */
	ck_assert_msg(rmax - rmin < 100, "kept points %.0f to %.0f nm from the centre", rmin,
		      rmax);
	ck_assert_msg(rmin > 9.775 * NM + 1000, "the seam at %.0f nm", rmin);
	for (size_t j = 0, k = 0; j + 1 < m; j++) {
		size_t next = k + 1;
		while (!keep[next])
			next++;
		for (size_t i = k; i <= next; i++)
			ck_assert_msg(seg_dist(xy + 2 * i, out + 2 * j, out + 2 * j + 2) <= RES * NM,
				      "point %zu off its moved chord", i);
		k = next;
	}
	simplify_work_free(&wk);
}
END_TEST

/* At most the slack, nothing is dropped: even collinear points stay. */
START_TEST(tiny_tolerance_keeps_everything)
{
	int64_t xy[20];

	for (int k = 0; k < 10; k++) {
		xy[2 * k] = k * 1000;
		xy[2 * k + 1] = 0;
	}
	ck_assert_uint_eq(mark_and_check(xy, 10, SIMPLIFY_SLACK_NM), 10);
	ck_assert_uint_eq(mark_and_check(xy, 10, 0), 10);
	ck_assert_uint_eq(mark_and_check(xy, 10, SIMPLIFY_SLACK_NM + 1), 2);
}
END_TEST

/* ---------------------------------------------------------------------------
 * A dense stack: what a slicer hands the writer for round walls, a gyroid
 * and a thin wall of varying width.
 */

/* A closed circle of n points, radius r mm around (cx, cy), bead w mm. */
static void add_circle(struct layer_paths *l, enum path_role role, double cx, double cy,
		       double r, size_t n, double w)
{
	struct path_point *p = calloc(n, sizeof(*p));

	ck_assert_ptr_nonnull(p);
	for (size_t k = 0; k < n; k++) {
		double a = 2 * M_PI * (double)k / (double)n;
		p[k] = (struct path_point){llround((cx + r * cos(a)) * NM),
					   llround((cy + r * sin(a)) * NM), llround(w * NM)};
	}
	ck_assert_int_eq(layer_add_path(l, role, true, p, n, NULL), 0);
	free(p);
}

/* An open wave y = cy + amp sin(x) from x0 to x1 mm in n points; width
 * w mm, or, when steps is set, w + 0.05 mm * (k / steps % 3) at point k. */
static void add_wave(struct layer_paths *l, enum path_role role, double x0, double x1,
		     double cy, double amp, size_t n, double w, size_t steps)
{
	struct path_point *p = calloc(n, sizeof(*p));

	ck_assert_ptr_nonnull(p);
	for (size_t k = 0; k < n; k++) {
		double x = x0 + (x1 - x0) * (double)k / (double)(n - 1);
		double wk = steps ? w + 0.05 * (double)(k / steps % 3) : w;
		p[k] = (struct path_point){llround(x * NM), llround((cy + amp * sin(x)) * NM),
					   llround(wk * NM)};
	}
	ck_assert_int_eq(layer_add_path(l, role, false, p, n, NULL), 0);
	free(p);
}

/* Two layers of 0.2 mm: round walls, a gyroid-like wave, a straight
 * line of collinear points, a thin wall whose width steps every 7 points. */
struct layer_stack *dense_stack(void)
{
	struct layer_stack *st = layer_stack_new(2, NULL);

	ck_assert_ptr_nonnull(st);
	for (size_t i = 0; i < 2; i++) {
		struct layer_paths *l = &st->layers[i];
		l->z = 0.2 * (double)(i + 1);
		l->height = 0.2;
		add_circle(l, PATH_INNER_PERIMETER, 100, 100, 9.55, 120, 0.45);
		add_circle(l, PATH_OUTER_PERIMETER, 100, 100, 10, 120, 0.45);
		add_wave(l, PATH_SPARSE_INFILL, 92, 108, 100, 3, 161, 0.45, 0);
		add_wave(l, PATH_SOLID_INFILL, 92, 108, 104, 0, 33, 0.45, 0);
		add_wave(l, PATH_THIN_WALL, 93, 107, 96, 0.02, 57, 0.3, 7);
	}
	return st;
}

/* ---------------------------------------------------------------------------
 * 0 = off
 */

/* The writer's output for dense_stack() with s is the file golden, byte
 * for byte. */
void dense_stack_matches(const struct gcodew_settings *s, const char *golden)
{
	struct layer_stack *st = dense_stack();
	size_t glen;
	char *want = tu_slurp(golden, &glen), *text = tu_gcode_mem(st, s, NULL);

	ck_assert_msg(strlen(text) == glen && memcmp(text, want, glen) == 0,
		      "output differs from %s", golden);
	free(text);
	free(want);
	layer_stack_free(st);
}

/* The golden file is the writer's output for dense_stack() at the commit
 * before gcode_resolution existed; with the key at 0 not a byte differs.
 * A change meant to alter the writer's output replaces it with this
 * test's output at 0, in the same commit. */
START_TEST(resolution_zero_is_output_before)
{
	struct gcodew_settings s;

	gcodew_settings_init(&s);
	s.gcode_resolution = 0;
	dense_stack_matches(&s, GOLDEN);
}
END_TEST

/* ---------------------------------------------------------------------------
 * The writer at the default resolution
 */

/* The distance (mm) from (px, py) to the nearest extrusion move of the
 * role on the layer. */
static double dist_to_printed(const struct tu_moves *r, int layer, const char *role, double px,
			      double py)
{
	double best = INFINITY;

	for (size_t k = 0; k < r->n; k++) {
		const struct tu_move *g = &r->m[k];
		int64_t p[2] = {llround(px * NM), llround(py * NM)};
		int64_t a[2] = {llround(g->x0 * NM), llround(g->y0 * NM)};
		int64_t b[2] = {llround(g->x1 * NM), llround(g->y1 * NM)};
		if (g->layer == layer && !strcmp(g->role, role))
			best = fmin(best, (double)seg_dist(p, a, b) / NM);
	}
	return best;
}

/* At the default, the dense stack is written in a fifth fewer moves
 * (the 120-gons' chords have a sagitta of 3.4 um), every point
 * of every path within the tolerance of what is printed for it (plus the
 * 1 um the written coordinates are rounded to), the filament of each role
 * as at 0 within the rounding of E. */
START_TEST(default_resolution_bound_and_filament)
{
	static const char *const roles[] = {"Perimeter", "External perimeter", "Internal infill",
					    "Solid infill", "Thin wall"};
	struct layer_stack *st = dense_stack();
	struct gcodew_settings s;
	char *off, *on;
	struct tu_moves r0, r1;

	gcodew_settings_init(&s);
	ck_assert_double_eq(s.gcode_resolution, RES);
	on = tu_gcode_mem(st, &s, NULL);
	s.gcode_resolution = 0;
	off = tu_gcode_mem(st, &s, NULL);
	r0 = tu_read_moves(off);
	r1 = tu_read_moves(on);
	ck_assert_msg(r1.g1 * 5 < r0.g1 * 4, "%zu G1 lines at %g mm, %zu at 0", r1.g1, RES, r0.g1);
	ck_assert(strstr(on, "\n; gcode_resolution = 0.0125\n"));
	ck_assert(!strstr(off, "gcode_resolution"));
	for (size_t i = 0; i < sizeof(roles) / sizeof(roles[0]); i++) {
		double e0 = tu_moves_e(&r0, roles[i]), e1 = tu_moves_e(&r1, roles[i]);
		ck_assert_msg(e0 > 0 && fabs(e1 - e0) < 1e-4, "%s: %.6f mm of filament, %.6f at 0",
			      roles[i], e1, e0);
	}
	for (size_t li = 0; li < st->nlayers; li++)
		for (size_t pi = 0; pi < st->layers[li].n; pi++) {
			const struct toolpath *p = &st->layers[li].paths[pi];
			const char *role = path_role_name(p->role);
			for (size_t k = 0; k < p->n; k++) {
				double d = dist_to_printed(&r1, (int)li + 1, role, p->pts[k].x / NM,
							   p->pts[k].y / NM);
				ck_assert_msg(d <= RES + 0.001, "layer %zu %s point %zu: %.5f mm off",
					      li + 1, role, k, d);
			}
		}
	free(r0.m);
	free(r1.m);
	free(on);
	free(off);
	layer_stack_free(st);
}
END_TEST

/* The thin wall's width steps every 7 points: every printed segment
 * carries the flow of one of its three widths (a merged segment would
 * carry a mix), and no fewer segments than there are steps. */
START_TEST(widths_never_merged)
{
	struct layer_stack *st = dense_stack();
	struct gcodew_settings s;
	char *text;
	struct tu_moves r;
	double fil = M_PI * 1.75 * 1.75 / 4, h = 0.2;
	size_t thin = 0;

	gcodew_settings_init(&s);
	text = tu_gcode_mem(st, &s, NULL);
	r = tu_read_moves(text);
	for (size_t k = 0; k < r.n; k++) {
		const struct tu_move *g = &r.m[k];
		double len = hypot(g->x1 - g->x0, g->y1 - g->y0), best = INFINITY;
		if (strcmp(g->role, "Thin wall") || g->layer != 1)
			continue;
		thin++;
		for (int step = 0; step < 3; step++) {
			double w = 0.3 + 0.05 * step, flow = ((w - h) * h + M_PI * h * h / 4) / fil;
			best = fmin(best, fabs(g->e / len / flow - 1));
		}
		ck_assert_msg(best < 0.005, "thin wall move %zu: %.5f mm over %.4f mm matches no width",
			      k, g->e, len);
	}
	ck_assert_uint_ge(thin, 56 / 7);
	ck_assert_uint_lt(thin, 56);
	free(r.m);
	free(text);
	layer_stack_free(st);
}
END_TEST

/* A closed loop simplified still ends at its seam, where it started; the
 * seam, balanced with the rest (simplify_balance_loop), stays within the
 * outer wall's half of the tolerance of where it was sliced. */
START_TEST(loops_stay_closed)
{
	struct layer_stack *st = layer_stack_new(1, NULL);
	struct gcodew_settings s;
	char *text;
	struct tu_moves r;

	ck_assert_ptr_nonnull(st);
	st->layers[0].z = st->layers[0].height = 0.2;
	add_circle(&st->layers[0], PATH_OUTER_PERIMETER, 60, 70, 5, 500, 0.45);
	gcodew_settings_init(&s);
	text = tu_gcode_mem(st, &s, NULL);
	r = tu_read_moves(text);
	ck_assert_uint_gt(r.n, 10);
	ck_assert_uint_lt(r.n, 150); /* of 500; an outer wall is held to half the tolerance */
	ck_assert_double_le(hypot(r.m[0].x0 - 65, r.m[0].y0 - 70), s.gcode_resolution / 2);
	ck_assert_double_eq_tol(r.m[r.n - 1].x1, r.m[0].x0, 1e-9);
	ck_assert_double_eq_tol(r.m[r.n - 1].y1, r.m[0].y0, 1e-9);
	free(r.m);
	free(text);
	layer_stack_free(st);
}
END_TEST

/*
 * The outer wall's points go on the written micron grid where they move
 * the face least (snap_face in gcode_writer_simplify.c): a round wall's
 * written points stay within a fraction of a micron of one circle, where
 * rounding each to the nearest grid point scatters them up to 0.7 um in
 * and out, which the region check reads as the face standing out.
 */
START_TEST(outer_wall_rounded_along_the_face)
{
	struct layer_stack *st = layer_stack_new(1, NULL);
	struct gcodew_settings s;
	double r[400], lo = INFINITY, hi = 0;
	size_t n = 0, wide = 0;
	char *text;
	struct tu_moves mv;

	ck_assert_ptr_nonnull(st);
	st->layers[0].z = st->layers[0].height = 0.2;
	add_circle(&st->layers[0], PATH_OUTER_PERIMETER, 125, 105, 9.775, 2048, 0.45);
	gcodew_settings_init(&s);
	text = tu_gcode_mem(st, &s, NULL);
	mv = tu_read_moves(text);
	for (size_t k = 0; k < mv.n && n < 400; k++)
		r[n++] = hypot(mv.m[k].x1 - 125, mv.m[k].y1 - 105);
	ck_assert_uint_gt(n, 40);
	for (size_t k = 0; k < n; k++) {
		lo = fmin(lo, r[k]);
		hi = fmax(hi, r[k]);
	}
	for (size_t k = 0; k < n; k++) /* off the mean radius by more than 0.25 um */
		wide += fabs(r[k] - (lo + hi) / 2) > 0.25e-3;
	/* 0.31 um and none wide; the nearest grid points: 1.0 um and 28 wide */
	ck_assert_msg(hi - lo < 0.4e-3 && wide == 0, "written radii %.6f to %.6f mm, %zu wide", lo,
		      hi, wide);
	free(mv.m);
	free(text);
	layer_stack_free(st);
}
END_TEST

/* A 30 mm square with a round hole of 7 mm radius (200 sides) around
 * (115, 115), as a travel map; two lines either side of the hole. */
static struct layer_stack *hole_stack(void)
{
	struct layer_stack *st = layer_stack_new(1, NULL);
	struct clip_paths ring = {0};
	struct clip_expolys ex = {0};
	int64_t sq[8], hole[400];
	double left[4] = {101, 112, 101, 118}, right[4] = {129, 118, 129, 112}, w[2] = {0.45, 0.45};

	ck_assert_ptr_nonnull(st);
	st->layers[0].z = st->layers[0].height = 0.2;
	for (int k = 0; k < 4; k++) {
		sq[2 * k] = llround((k == 1 || k == 2 ? 130 : 100) * NM);
		sq[2 * k + 1] = llround((k >= 2 ? 130 : 100) * NM);
	}
	for (int k = 0; k < 200; k++) { /* clockwise: a hole */
		double a = -2 * M_PI * k / 200;
		hole[2 * k] = llround((115 + 7 * cos(a)) * NM);
		hole[2 * k + 1] = llround((115 + 7 * sin(a)) * NM);
	}
	ck_assert_int_eq(clip_paths_add(&ring, sq, 4, NULL), 0);
	ck_assert_int_eq(clip_paths_add(&ring, hole, 200, NULL), 0);
	ck_assert_int_eq(clip_boolean_ex(CLIP_UNION, &ring, NULL, CLIP_NONZERO, &ex, NULL), 0);
	st->layers[0].travel = travel_map_new(&ex, llround(0.6 * NM), NULL);
	ck_assert_ptr_nonnull(st->layers[0].travel);
	for (int k = 0; k < 2; k++) {
		struct path_point p[2];
		const double *xy = k ? right : left;
		for (int i = 0; i < 2; i++)
			p[i] = (struct path_point){llround(xy[2 * i] * NM), llround(xy[2 * i + 1] * NM),
						   llround(w[i] * NM)};
		ck_assert_int_eq(layer_add_path(&st->layers[0], PATH_GAP_FILL, false, p, 2, NULL), 0);
	}
	clip_expolys_free(&ex);
	clip_paths_free(&ring);
	return st;
}

/* XY moves without E after the first extrusion: the travel's segments,
 * each checked inside the map. */
static size_t routed_moves(const char *text, struct travel_map *m)
{
	double x = 0, y = 0;
	bool started = false;
	size_t n = 0;

	for (const char *l = text; *l; l = strchr(l, '\n') ? strchr(l, '\n') + 1 : l + strlen(l)) {
		size_t len = strcspn(l, "\n");
		const char *xw = memchr(l, 'X', len), *yw = memchr(l, 'Y', len);
		double nx = xw ? strtod(xw + 1, NULL) : x, ny = yw ? strtod(yw + 1, NULL) : y;
		bool e = memchr(l, 'E', len) != NULL;

		if (strncmp(l, "G1 ", 3) || !(xw || yw))
			continue;
		if (started && !e) {
			n++;
			ck_assert_msg(travel_segment_inside(m, llround(x * NM), llround(y * NM),
							   llround(nx * NM), llround(ny * NM)),
				      "travel %.3f,%.3f to %.3f,%.3f leaves the part", x, y, nx, ny);
		}
		started = started || e;
		x = nx;
		y = ny;
	}
	return n;
}

/* The travel round the hole follows its sides at 0; at the default it is
 * simplified too, and still inside the part. */
START_TEST(routed_travel_simplified)
{
	struct layer_stack *st = hole_stack();
	struct gcodew_settings s;
	char *on, *off;
	size_t n1, n0;

	gcodew_settings_init(&s);
	on = tu_gcode_mem(st, &s, NULL);
	s.gcode_resolution = 0;
	off = tu_gcode_mem(st, &s, NULL);
	n1 = routed_moves(on, st->layers[0].travel);
	n0 = routed_moves(off, st->layers[0].travel);
	ck_assert_msg(n0 > 20 && n1 * 2 < n0, "%zu travel moves, %zu at 0", n1, n0);
	free(on);
	free(off);
	layer_stack_free(st);
}
END_TEST

/* ---------------------------------------------------------------------------
 * A sliced model
 */

/* stratum slice of a cylinder of 256 sides, 10 mm radius and h mm high for
 * printer with args; the G-code, and what the command said in out. */
char *slice_cylinder_for(double h, const char *printer, const char *args, char *out, size_t cap)
{
	char model[4096], gc[4096];
	struct st_error err = {0};
	struct mesh *m = fx_cylinder(0, 0, 10, h, 256);
	size_t len;
	int rc, status;

	snprintf(model, sizeof(model), "%s", tu_path("cylinder.stl"));
	snprintf(gc, sizeof(gc), "%s", tu_path("cylinder.gcode"));
	rc = meshio_write_stl(model, m, MESHIO_STL_BINARY, &err);
	mesh_free(m);
	ck_assert_msg(rc == 0, "%s", err.msg);
	status = tu_run(out, cap, "slice '%s' -o '%s' --printer %s %s 2>&1", model, gc, printer,
			args);
	ck_assert_msg(status == 0, "exit %d: %s", status, out);
	return tu_slurp(gc, &len);
}

/* stratum slice of a 6 mm cylinder (generic-marlin) with args; the G-code. */
static char *slice_cylinder(const char *args)
{
	static char out[1 << 14];

	return slice_cylinder_for(6, "generic-marlin", args, out, sizeof(out));
}

/* Lines in text. */
static size_t lines(const char *text)
{
	size_t n = 0;

	for (const char *c = text; *c; c++)
		n += *c == '\n';
	return n;
}

/* The value of a "; KEY = V" header line. */
static double header_value(const char *text, const char *key)
{
	const char *at = strstr(text, key);

	ck_assert_msg(at, "no %s", key);
	return strtod(at + strlen(key), NULL);
}

/* The default writes a sliced round part in a third fewer lines or better,
 * with the filament of gcode_resolution = 0 to 0.1 %. */
START_TEST(sliced_model_gets_fewer_lines)
{
	char *on = slice_cylinder(""), *off = slice_cylinder("--set gcode_resolution=0");
	size_t n1 = lines(on), n0 = lines(off);
	double f1 = header_value(on, "; filament used [mm] = ");
	double f0 = header_value(off, "; filament used [mm] = ");

	ck_assert_msg(3 * n1 < 2 * n0, "%zu lines at the default, %zu at 0", n1, n0);
	ck_assert_msg(fabs(f1 - f0) <= 0.001 * f0, "filament %.2f mm, %.2f at 0", f1, f0);
	free(on);
	free(off);
}
END_TEST

void gcodewriter_simplify_tcases(Suite *s)
{
	TCase *tc = tcase_create("simplify");

	tcase_add_test(tc, bound_on_random_polylines);
	tcase_add_test(tc, bound_on_circles);
	tcase_add_test(tc, tiny_tolerance_keeps_everything);
	tcase_add_test(tc, balance_keeps_area);
	tcase_add_test(tc, balance_loop_moves_seam);
	tcase_add_test(tc, resolution_zero_is_output_before);
	tcase_add_test(tc, default_resolution_bound_and_filament);
	tcase_add_test(tc, widths_never_merged);
	tcase_add_test(tc, loops_stay_closed);
	tcase_add_test(tc, outer_wall_rounded_along_the_face);
	tcase_add_test(tc, routed_travel_simplified);
	tcase_add_test(tc, sliced_model_gets_fewer_lines);
	suite_add_tcase(s, tc);
}
