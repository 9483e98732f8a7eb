/*
 * check_travel.c - travel between paths, part of the slicer suite: routes
 * around holes inside the part (slicer/travel.h), and in the written
 * G-code travels that stay inside the part, retractions only between
 * islands, the same bytes for any thread count.
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clip.h"
#include "fixtures.h"
#include "gcode.h"
#include "gcode_writer.h"
#include "mesh.h"
#include "slicer.h"
#include "suites.h"
#include "toolpath.h"
#include "travel.h"

#define NM SLICE_UNITS_PER_MM

/* A square (x0, y0)-(x0 + side, y0 + side) in mm as a closed clip path,
 * counter-clockwise, or clockwise when cw. */
static void add_square_nm(struct clip_paths *ps, double x0, double y0, double side, bool cw)
{
	int64_t a = llround(x0 * NM), b = llround(y0 * NM), c = llround((x0 + side) * NM),
		d = llround((y0 + side) * NM);
	const int64_t ccw[8] = {a, b, c, b, c, d, a, d}, rev[8] = {a, b, a, d, c, d, c, b};

	ck_assert_int_eq(clip_paths_add(ps, cw ? rev : ccw, 4, NULL), 0);
}

/* The 30 mm square plate with a 14 mm square hole in the middle, 2 mm tall
 * (the hole from 8 to 22 mm). */
static struct mesh *ring_plate(void)
{
	struct mesh *plate = fx_box(0, 0, 0, 30, 30, 2), *hole = fx_box(8, 8, 0, 22, 22, 2), *m;

	ck_assert(plate && hole);
	for (size_t i = 0; i < hole->ntris; i++) /* inside out: a hole in the plate */
		fx_flip(hole, i);
	m = fx_concat(plate, hole);
	ck_assert_ptr_nonnull(m);
	mesh_free(plate);
	mesh_free(hole);
	return m;
}

/* Two 10 mm squares 10 mm apart, 2 mm tall. */
static struct mesh *two_islands(void)
{
	struct mesh *a = fx_box(0, 0, 0, 10, 10, 2), *b = fx_box(20, 0, 0, 30, 10, 2), *m;

	ck_assert(a && b);
	m = fx_concat(a, b);
	ck_assert_ptr_nonnull(m);
	mesh_free(a);
	mesh_free(b);
	return m;
}

/* Slice m with the defaults (no skirt) and write the G-code to memory;
 * *off gets the placement (mm). */
static char *slice_mem(const struct mesh *m, bool avoid, int threads, double off[2])
{
	struct slicer_config c;
	struct slicer_summary sum;
	struct layer_stack *st = NULL;
	struct st_error err = {0};
	struct gcodew_settings gs;
	char *buf = NULL;
	size_t len = 0;
	FILE *fp;
	int rc;

	slicer_config_init(&c, 0.4);
	c.skirt.skirts = 0;
	c.threads = threads;
	c.gcodew.avoid_crossing_perimeters = avoid;
	rc = slicer_toolpaths(m, &c, &st, &sum, &err);
	ck_assert_msg(rc == 0, "slicer_toolpaths: %s", err.msg);
	gs = c.gcodew;
	gs.layer_height = c.layer_height;
	gs.first_layer_height = c.first_layer_height;
	fp = open_memstream(&buf, &len);
	ck_assert_ptr_nonnull(fp);
	rc = gcodew_write_stream(st, &gs, fp, NULL, &err);
	ck_assert_int_eq(fclose(fp), 0);
	ck_assert_msg(rc == 0, "gcodew_write_stream: %s", err.msg);
	layer_stack_free(st);
	off[0] = sum.offset[0];
	off[1] = sum.offset[1];
	return buf;
}

/* What a replay of the G-code found. */
struct travels {
	struct clip_paths segs; /* every travel segment of the layers, nm */
	int retracts;		/* E moving back */
	int between;		/* travels from one side of x = split to the other */
};

/*
 * Parse text with gcode_parse: every G1 with X/Y and no E after the first
 * layer change is a travel segment; a G1 lowering E is a retraction.
 * Travels (runs of travel segments between extrusions) whose ends lie on
 * either side of x = split (mm) are counted in between.
 */
static void read_travels(const char *text, double split, struct travels *t)
{
	double x = 0, y = 0, e = 0, sx = 0;
	bool layers = false, in_travel = false, known = false; /* known: x, y were set */
	const char *p = text;

	memset(t, 0, sizeof(*t));
	while (*p) {
		const char *end = strchr(p, '\n');
		size_t n = end ? (size_t)(end - p) : strlen(p);
		struct gcode_line l;
		struct st_error err = {0};
		double nx = x, ny = y, ne = e, v;
		long layer;

		ck_assert_msg(gcode_parse(p, n, 0, &l, &err) == 0, "%.*s: %s", (int)n, p, err.msg);
		p += n + (end ? 1 : 0);
		if (gcode_layer_comment(&l, &layer, &v) == GCODE_LAYER_START)
			layers = true;
		if (l.letter == 'G' && l.number == 92 && gcode_word_value(&l, 'E', &v))
			e = v;
		if (l.letter != 'G' || l.number != 1)
			continue;
		bool xy = gcode_word_value(&l, 'X', &nx) | gcode_word_value(&l, 'Y', &ny);
		bool has_e = gcode_word_value(&l, 'E', &ne);
		if (has_e && ne < e - 1e-9)
			t->retracts++;
		if (layers && xy && !has_e && known) {
			const int64_t seg[4] = {llround(x * NM), llround(y * NM), llround(nx * NM),
						llround(ny * NM)};
			if (!in_travel)
				sx = x;
			in_travel = true;
			if (seg[0] != seg[2] || seg[1] != seg[3])
				ck_assert_int_eq(clip_paths_add(&t->segs, seg, 2, NULL), 0);
		} else if (has_e && ne > e && xy) {
			if (in_travel && (sx < split) != (x < split))
				t->between++;
			in_travel = false;
		}
		x = nx;
		y = ny;
		known |= xy;
		if (has_e)
			e = ne;
	}
}

/* Length (mm) of the travel segments outside the region. */
static double outside_length(const struct clip_paths *segs, const struct clip_paths *region)
{
	struct clip_paths out = {0};
	double len = 0;

	ck_assert_int_eq(clip_lines(CLIP_DIFFERENCE, segs, region, CLIP_NONZERO, &out, NULL), 0);
	for (size_t i = 0; i < out.n; i++) {
		const int64_t *xy = clip_path_xy(&out, i);
		for (size_t k = 0; k + 1 < clip_path_len(&out, i); k++)
			len += hypot((double)(xy[2 * k + 2] - xy[2 * k]),
				     (double)(xy[2 * k + 3] - xy[2 * k + 1])) / NM;
	}
	clip_paths_free(&out);
	return len;
}

START_TEST(travel_routes_around_a_hole)
{
	struct clip_paths ring = {0};
	struct clip_expolys ex = {0};
	struct travel_route r = {0};
	struct travel_map *m;
	struct st_error err = {0};

	add_square_nm(&ring, 0, 0, 30, false);
	add_square_nm(&ring, 8, 8, 14, true);
	ck_assert_int_eq(clip_boolean_ex(CLIP_UNION, &ring, NULL, CLIP_NONZERO, &ex, &err), 0);
	m = travel_map_new(&ex, llround(0.6 * NM), &err);
	ck_assert_msg(m != NULL, "%s", err.msg);

	/* Across the hole: routed round it, inside, no wall touched. */
	ck_assert_int_eq(travel_plan(m, llround(4 * NM), llround(15 * NM), llround(26 * NM),
				     llround(15.5 * NM), &r, &err),
			 0);
	ck_assert(r.inside);
	ck_assert_uint_ge(r.n, 3);
	int64_t px = llround(4 * NM), py = llround(15 * NM);
	for (size_t k = 0; k < r.n; k++) {
		ck_assert(travel_segment_inside(m, px, py, r.xy[2 * k], r.xy[2 * k + 1]));
		px = r.xy[2 * k];
		py = r.xy[2 * k + 1];
	}
	ck_assert_int_eq(px, llround(26 * NM));
	/* Round the near side of the hole: about 22 + 2 x 7 mm, well under 30 */
	ck_assert_double_gt(r.length / NM, 22.0);
	ck_assert_double_lt(r.length / NM, 40.0);

	/* From the outer wall's centre line (outside the boundary) too. */
	ck_assert_int_eq(travel_plan(m, llround(0.225 * NM), llround(15 * NM),
				     llround(29.775 * NM), llround(14 * NM), &r, &err),
			 0);
	ck_assert(r.inside);

	/* Straight when the segment stays inside. */
	ck_assert_int_eq(travel_plan(m, llround(2 * NM), llround(2 * NM), llround(28 * NM),
				     llround(4 * NM), &r, &err),
			 0);
	ck_assert(r.inside);
	ck_assert_uint_eq(r.n, 1);

	/* From outside the part (a skirt): straight, crossing. */
	ck_assert_int_eq(travel_plan(m, llround(-3 * NM), llround(15 * NM), llround(4 * NM),
				     llround(15 * NM), &r, &err),
			 0);
	ck_assert(!r.inside);
	ck_assert_uint_eq(r.n, 1);

	/* avoid_crossing_perimeters_max_detour: the route round the hole
	 * detours some 8 mm beyond the 22 mm straight travel, so a limit of
	 * 5 mm or 10% sends it straight across; 0 (any) and 100% route it. */
	static const struct {
		double v;
		bool pct, routed;
	} lim[] = {{5, false, false}, {10, true, false}, {0, false, true}, {100, true, true},
		   {20, false, true}};
	for (size_t i = 0; i < sizeof(lim) / sizeof(lim[0]); i++) {
		travel_map_set_detour(m, lim[i].v, lim[i].pct);
		ck_assert_int_eq(travel_plan(m, llround(4 * NM), llround(15 * NM), llround(26 * NM),
					     llround(15.5 * NM), &r, &err),
				 0);
		ck_assert_msg(r.inside == lim[i].routed && (r.n > 1) == lim[i].routed,
			      "detour %g%s: inside %d, %zu points", lim[i].v, lim[i].pct ? "%" : " mm",
			      r.inside, r.n);
	}

	travel_route_free(&r);
	travel_map_free(m);
	clip_expolys_free(&ex);
	clip_paths_free(&ring);
}
END_TEST

START_TEST(gcode_travels_stay_inside_the_ring)
{
	struct mesh *m = ring_plate();
	struct clip_paths region = {0};
	struct travels on, off;
	double o[2];
	char *text;

	text = slice_mem(m, true, 1, o);
	read_travels(text, -1e9, &on);
	free(text);
	add_square_nm(&region, o[0], o[1], 30, false);
	add_square_nm(&region, o[0] + 8, o[1] + 8, 14, true);
	ck_assert_uint_gt(on.segs.n, 100);
	ck_assert_double_lt(outside_length(&on.segs, &region), 1e-3);

	/* Without the routing some travels cross the hole (the test can fail). */
	text = slice_mem(m, false, 1, o);
	read_travels(text, -1e9, &off);
	free(text);
	ck_assert_double_gt(outside_length(&off.segs, &region), 1.0);
	ck_assert_int_lt(on.retracts, off.retracts);

	clip_paths_free(&on.segs);
	clip_paths_free(&off.segs);
	clip_paths_free(&region);
	mesh_free(m);
}
END_TEST

START_TEST(retract_only_between_islands)
{
	struct mesh *m = two_islands();
	struct travels on, off;
	double o[2];
	char *text;

	text = slice_mem(m, true, 1, o);
	read_travels(text, o[0] + 15, &on);
	free(text);
	text = slice_mem(m, false, 1, o);
	read_travels(text, o[0] + 15, &off);
	free(text);
	/* One retraction per island change (and the final one), none inside. */
	ck_assert_int_gt(on.between, 0);
	ck_assert_int_le(on.retracts, on.between + 1);
	ck_assert_int_lt(on.retracts, off.retracts);
	clip_paths_free(&on.segs);
	clip_paths_free(&off.segs);
	mesh_free(m);
}
END_TEST

START_TEST(gcode_same_for_any_thread_count)
{
	struct mesh *m = ring_plate();
	double o[2];
	char *one = slice_mem(m, true, 1, o), *two = slice_mem(m, true, 2, o),
	     *four = slice_mem(m, true, 4, o);

	ck_assert_str_eq(one, two);
	ck_assert_str_eq(one, four);
	free(one);
	free(two);
	free(four);
	mesh_free(m);
}
END_TEST

void slicer_travel_tcases(Suite *s)
{
	TCase *tc = tcase_create("travel");

	tcase_set_timeout(tc, 60);
	tcase_add_test(tc, travel_routes_around_a_hole);
	tcase_add_test(tc, gcode_travels_stay_inside_the_ring);
	tcase_add_test(tc, retract_only_between_islands);
	tcase_add_test(tc, gcode_same_for_any_thread_count);
	suite_add_tcase(s, tc);
}
