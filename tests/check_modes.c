/*
 * check_modes.c - print modes of the slicing job, part of the slicer
 * suite: spiral vase (slicer/spiral.h) and ironing (slicer/ironing.h) on
 * meshes built in code, checked on the layer stack and on the G-code the
 * writer makes of it.
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clip.h"
#include "fixtures.h"
#include "ironing.h"
#include "mesh.h"
#include "slicer.h"
#include "suites.h"
#include "testutil.h"
#include "toolpath.h"

#define NM SLICE_UNITS_PER_MM

/* A 10 mm tall tube (radius 10, 4 mm hole) beside a 2 mm pillar, 10 mm tall. */
static struct mesh *tube_and_pillar(void)
{
	struct mesh *outer = fx_cylinder(0, 0, 10, 10, 64), *hole = fx_cylinder(0, 0, 4, 10, 32);
	struct mesh *pillar = fx_cylinder(20, 0, 2, 10, 16), *tube, *m;

	ck_assert(outer && hole && pillar);
	for (size_t i = 0; i < hole->ntris; i++)
		fx_flip(hole, i);
	tube = fx_concat(outer, hole);
	m = fx_concat(tube, pillar);
	ck_assert(tube && m);
	mesh_free(outer);
	mesh_free(hole);
	mesh_free(pillar);
	mesh_free(tube);
	return m;
}

/* The job's defaults for a 0.4 mm nozzle, no skirt, one thread. */
static void config(struct slicer_config *c, bool vase)
{
	slicer_config_init(c, 0.4);
	c->skirt.skirts = 0;
	c->threads = 1;
	c->gcodew.spiral_vase = vase;
}

static struct layer_stack *toolpaths(const struct mesh *m, const struct slicer_config *c,
				     struct slicer_summary *sum)
{
	struct layer_stack *st = NULL;
	struct st_error err = {0};

	ck_assert_msg(slicer_toolpaths(m, c, &st, sum, &err) == 0, "slicer_toolpaths: %s",
		      err.msg);
	return st;
}

/* The G-code of c's job on m, in memory (free() it). */
static char *gcode_of(const struct mesh *m, const struct slicer_config *c)
{
	struct layer_stack *st = toolpaths(m, c, NULL);
	struct gcodew_settings gs = c->gcodew;
	struct st_error err = {0};
	char *buf = NULL;
	size_t len = 0;
	FILE *fp = open_memstream(&buf, &len);
	int rc;

	ck_assert_ptr_nonnull(fp);
	gs.layer_height = c->layer_height;
	gs.first_layer_height = c->first_layer_height;
	rc = gcodew_write_stream(st, &gs, fp, NULL, &err);
	ck_assert_int_eq(fclose(fp), 0);
	ck_assert_msg(rc == 0, "gcodew_write_stream: %s", err.msg);
	layer_stack_free(st);
	return buf;
}

/* Infill paths of any kind on layer l. */
static size_t count_infill(const struct layer_paths *l)
{
	return tu_count_role(l, PATH_SOLID_INFILL) + tu_count_role(l, PATH_TOP_SKIN) +
	       tu_count_role(l, PATH_BOTTOM_SKIN) + tu_count_role(l, PATH_SPARSE_INFILL) +
	       tu_count_role(l, PATH_BRIDGE);
}

/*
 * Above the 3 bottom layers every layer is one closed outer wall around
 * the tube's outline (hole and pillar dropped), marked spiral, with no
 * infill and no top skin; the bottom layers keep the hole, the pillar and
 * their bottom skin.  Without spiral_vase the same layers have more.
 */
START_TEST(spiral_vase_one_wall_above_the_bottom)
{
	struct mesh *m = tube_and_pillar();
	struct slicer_config c;
	struct slicer_summary sum;
	struct layer_stack *st;

	config(&c, false);
	st = toolpaths(m, &c, &sum);
	ck_assert_uint_gt(st->layers[10].n, 1);
	ck_assert_uint_gt(tu_count_role(&st->layers[st->nlayers - 1], PATH_TOP_SKIN), 0);
	for (size_t i = 0; i < st->nlayers; i++)
		ck_assert(!st->layers[i].spiral);
	layer_stack_free(st);

	config(&c, true);
	st = toolpaths(m, &c, &sum);
	ck_assert_uint_eq(st->nlayers, 50);
	for (size_t i = 0; i < 3; i++) {
		const struct layer_paths *l = &st->layers[i];
		ck_assert_msg(!l->spiral, "bottom layer %zu is flat", i);
		ck_assert_uint_gt(tu_count_role(l, PATH_BOTTOM_SKIN), 0);
		/* tube outside and hole, pillar: 3 walls (one perimeter each) */
		ck_assert_uint_eq(tu_count_role(l, PATH_OUTER_PERIMETER), 3);
	}
	for (size_t i = 3; i < st->nlayers; i++) {
		const struct layer_paths *l = &st->layers[i];
		const struct toolpath *p = &l->paths[0];
		double cx = sum.offset[0] * NM, cy = sum.offset[1] * NM, rmin = INFINITY, rmax = 0;

		ck_assert_msg(l->spiral && l->n == 1, "layer %zu: spiral %d, %zu paths", i,
			      l->spiral, l->n);
		ck_assert(p->closed && p->role == PATH_OUTER_PERIMETER);
		ck_assert_uint_eq(count_infill(l), 0);
		/* the tube's outline, centre line w/2 inside radius 10 (64-gon chords) */
		for (size_t k = 0; k < p->n; k++) {
			double r = hypot(p->pts[k].x - cx, p->pts[k].y - cy) / NM;
			rmin = fmin(rmin, r);
			rmax = fmax(rmax, r);
		}
		ck_assert_msg(rmax < 10.0 && rmin > 9.0, "layer %zu: radius %g..%g", i, rmin, rmax);
	}
	layer_stack_free(st);
	mesh_free(m);
}
END_TEST

/* What a replay of the spiral part of the G-code found. */
struct spiral_replay {
	int layers;	     /* layers seen */
	int zs_last;	     /* distinct Z values on the last layer */
	bool z_down;	     /* Z went down within or between spiral layers */
	bool e_back;	     /* E went back (a retraction) between spiral layers */
	bool outside;	     /* an extrusion Z outside (z - h, z] of its layer */
};

/* A number after letter c on line s (up to its end), or false. */
static bool word(const char *s, const char *end, char c, double *v)
{
	for (const char *p = s; p < end && *p != ';'; p++)
		if (*p == c) {
			*v = strtod(p + 1, NULL);
			return true;
		}
	return false;
}

/*
 * Replay text (absolute E) from layer first (0-based) to the last layer's
 * last XY move: Z and E of every G1, checked against each layer's ;Z:.
 */
static void replay(const char *text, int first, double h, struct spiral_replay *r)
{
	const char *last_xy = NULL, *p;
	double z = 0, e = 0, lz = 0, prev_z = -1;
	int layer = -1;

	memset(r, 0, sizeof(*r));
	for (p = text; *p; p = strchr(p, '\n') ? strchr(p, '\n') + 1 : p + strlen(p)) {
		const char *end = strchr(p, '\n') ? strchr(p, '\n') : p + strlen(p);
		double v;
		if (!strncmp(p, "G1 ", 3) && (word(p, end, 'X', &v) || word(p, end, 'Y', &v)))
			last_xy = p;
	}
	for (p = text; *p && p <= last_xy; p = strchr(p, '\n') + 1) {
		const char *end = strchr(p, '\n');
		double v, ne = e;
		if (!strncmp(p, ";Z:", 3)) {
			layer++;
			lz = strtod(p + 3, NULL);
			if (layer >= first)
				r->layers++;
			prev_z = -1;
			r->zs_last = 0;
			continue;
		}
		if (!strncmp(p, "G92 ", 4) && word(p, end, 'E', &v)) { /* each layer's reset */
			e = v;
			continue;
		}
		if (strncmp(p, "G1 ", 3))
			continue;
		if (word(p, end, 'Z', &v))
			z = v;
		if (word(p, end, 'E', &v))
			ne = v;
		if (layer >= first) {
			if (ne < e - 1e-9)
				r->e_back = true;
			if (z < prev_z - 1e-9)
				r->z_down = true;
			if (ne > e && (z <= lz - h + 1e-9 || z > lz + 1e-9))
				r->outside = true;
			if (z != prev_z)
				r->zs_last++;
			prev_z = z;
		}
		e = ne;
	}
}

/*
 * The G-code of the spiral layers: Z rises within each loop (many distinct
 * values, never down, every extrusion within its layer's (z - h, z]), and
 * nothing retracts from one spiral layer to the next; the header says
 * spiral_vase = 1.  The flat print of the same mesh has one Z per layer.
 */
START_TEST(spiral_vase_gcode_rises_without_retraction)
{
	struct mesh *m = tube_and_pillar();
	struct slicer_config c;
	struct spiral_replay r;
	char *text;

	config(&c, false);
	text = gcode_of(m, &c);
	replay(text, 4, c.layer_height, &r);
	ck_assert_int_le(r.zs_last, 2);
	ck_assert_ptr_null(strstr(text, "; spiral_vase"));
	free(text);

	config(&c, true);
	text = gcode_of(m, &c);
	/* from layer 4: the one below (3) is a spiral too */
	replay(text, 4, c.layer_height, &r);
	ck_assert_int_eq(r.layers, 46);
	ck_assert_msg(r.zs_last > 20, "%d Z values on the last layer", r.zs_last);
	ck_assert(!r.z_down);
	ck_assert(!r.e_back);
	ck_assert(!r.outside);
	ck_assert_ptr_nonnull(strstr(text, "\n; spiral_vase = 1\n"));
	free(text);
	mesh_free(m);
}
END_TEST

/* E per mm of the first and last extrusion of the layer whose ;Z: is z (relative E). */
static void flow_ends(const char *text, const char *z, double *first, double *last)
{
	const char *p = strstr(text, z);
	double x = 0, y = 0;

	*first = *last = -1;
	ck_assert_ptr_nonnull(p);
	for (const char *q = text; q < p; q = strchr(q, '\n') + 1) /* the position there */
		if (!strncmp(q, "G1 ", 3)) {
			word(q, strchr(q, '\n'), 'X', &x);
			word(q, strchr(q, '\n'), 'Y', &y);
		}
	for (p = strchr(p, '\n') + 1; *p && strncmp(p, ";LAYER_CHANGE", 13); p = strchr(p, '\n') + 1) {
		const char *end = strchr(p, '\n');
		double nx = x, ny = y, e;
		if (strncmp(p, "G1 ", 3))
			continue;
		word(p, end, 'X', &nx);
		word(p, end, 'Y', &ny);
		if (word(p, end, 'E', &e) && e > 0 && hypot(nx - x, ny - y) > 0.1) {
			*last = e / hypot(nx - x, ny - y);
			if (*first < 0)
				*first = *last;
		}
		x = nx;
		y = ny;
	}
}

/*
 * The first spiral layer (3, Z 0.8) starts with almost no flow and ends
 * with the full flow, as the gap under the nozzle grows; the next one (4)
 * has the full flow throughout.
 */
START_TEST(spiral_vase_first_loop_ramps_the_flow)
{
	struct mesh *m = tube_and_pillar();
	struct slicer_config c;
	double a, b, full = (0.45 - 0.2) * 0.2 + M_PI * 0.01; /* mm^2 of a 0.45 x 0.2 bead */
	char *text;

	full /= M_PI * 1.75 * 1.75 / 4;
	config(&c, true);
	c.gcodew.use_relative_e_distances = true;
	text = gcode_of(m, &c);
	flow_ends(text, "\n;Z:0.8\n", &a, &b);
	ck_assert_msg(a > 0 && a < 0.1 * full && fabs(b - full) < 0.01 * full,
		      "first spiral layer: %g to %g mm/mm (full %g)", a, b, full);
	flow_ends(text, "\n;Z:1\n", &a, &b);
	ck_assert_msg(fabs(a - full) < 0.01 * full && fabs(b - full) < 0.01 * full,
		      "second spiral layer: %g to %g mm/mm (full %g)", a, b, full);
	free(text);
	mesh_free(m);
}
END_TEST

/*
 * With wipe, the final retraction after the last loop wipes back along
 * that loop from where it ended: its first move is one chord (under 1 mm
 * of a 64-gon of radius 10) from the end, not a jump across the vase.
 */
START_TEST(spiral_vase_wipes_back_along_the_loop)
{
	struct mesh *m = tube_and_pillar();
	struct slicer_config c;
	const char *p, *wipe = NULL, *last = NULL;
	double x = 0, y = 0, wx = 0, wy = 0, e;
	char *text;

	config(&c, true);
	c.gcodew.wipe = true;
	c.gcodew.use_relative_e_distances = true;
	text = gcode_of(m, &c);
	for (p = text; *p; p = strchr(p, '\n') + 1) {
		const char *end = strchr(p, '\n');
		if (strncmp(p, "G1 ", 3) || !word(p, end, 'E', &e))
			continue;
		if (e > 0 && word(p, end, 'X', &x)) {
			word(p, end, 'Y', &y);
			last = p;
		} else if (e < 0 && last && word(p, end, 'X', &wx)) {
			word(p, end, 'Y', &wy);
			wipe = p;
		}
	}
	ck_assert(last && wipe && wipe > last);
	/* wipe is the last wiping move: find the first one after last */
	for (p = strchr(last, '\n') + 1; p < wipe; p = strchr(p, '\n') + 1)
		if (!strncmp(p, "G1 ", 3) && word(p, strchr(p, '\n'), 'X', &wx)) {
			word(p, strchr(p, '\n'), 'Y', &wy);
			break;
		}
	ck_assert_msg(hypot(wx - x, wy - y) < 1.0, "the wipe starts %g mm from the loop's end",
		      hypot(wx - x, wy - y));
	free(text);
	mesh_free(m);
}
END_TEST

/* spiral_vase with support material is refused, as PrusaSlicer refuses it. */
START_TEST(spiral_vase_refuses_support)
{
	struct slicer_config c;
	struct st_error err = {0};

	config(&c, true);
	c.support.enabled = true;
	ck_assert_int_eq(slicer_config_check(&c, &err), ST_ERR_RANGE);
	ck_assert_ptr_nonnull(strstr(err.msg, "spiral_vase"));
}
END_TEST

/* A 20 x 20 x 5 mm block with a 10 x 10 x 5 mm block on its middle. */
static struct mesh *step(void)
{
	struct mesh *a = fx_box(0, 0, 0, 20, 20, 5), *b = fx_box(5, 5, 5, 15, 15, 10);
	struct mesh *m = fx_concat(a, b);

	ck_assert(a && b && m);
	mesh_free(a);
	mesh_free(b);
	return m;
}

static void iron_config(struct slicer_config *c, bool on, const char *type)
{
	config(c, false);
	c->gcodew.ironing = on;
	c->gcodew.ironing_type = type;
	c->gcodew.cooling = false; /* speeds as set */
}

/* Ironing lines of layer l: their count, length (mm) and bounding box (mm). */
struct iron_stats {
	size_t n;
	double len, x0, y0, x1, y1;
};

/* Whether a segment of an ironing path of l passes inside the box (mm, 1 um in). */
static bool crosses(const struct layer_paths *l, double x0, double y0, double x1, double y1)
{
	for (size_t i = 0; i < l->n; i++) {
		const struct toolpath *p = &l->paths[i];
		for (size_t k = 0; p->role == PATH_IRONING && k + 1 < p->n; k++)
			for (int s = 1; s < 8; s++) {
				double t = s / 8.0;
				double x = (p->pts[k].x + t * (p->pts[k + 1].x - p->pts[k].x)) / NM;
				double y = (p->pts[k].y + t * (p->pts[k + 1].y - p->pts[k].y)) / NM;
				if (x > x0 + 1e-3 && x < x1 - 1e-3 && y > y0 + 1e-3 && y < y1 - 1e-3)
					return true;
			}
	}
	return false;
}

static struct iron_stats iron_of(const struct layer_paths *l)
{
	struct iron_stats s = {0, 0, INFINITY, INFINITY, -INFINITY, -INFINITY};

	for (size_t i = 0; i < l->n; i++) {
		const struct toolpath *p = &l->paths[i];
		if (p->role != PATH_IRONING)
			continue;
		s.n++;
		ck_assert_int_eq(p->pts[0].width, 100000); /* ironing_spacing */
		for (size_t k = 0; k < p->n; k++) {
			double x = p->pts[k].x / NM, y = p->pts[k].y / NM;
			s.x0 = fmin(s.x0, x);
			s.y0 = fmin(s.y0, y);
			s.x1 = fmax(s.x1, x);
			s.y1 = fmax(s.y1, y);
			if (k)
				s.len += hypot(x - p->pts[k - 1].x / NM, y - p->pts[k - 1].y / NM);
		}
	}
	return s;
}

/*
 * ironing_type top: the last layer's whole top and, on layer 24 (z 5), the
 * ring the upper block leaves uncovered (no line or link across the
 * block), each half a nozzle inside the outline, lines 0.1 mm apart
 * covering it (length x spacing = area); no other layer.  topmost: the last layer only.  Every other path is what
 * the print without ironing has.
 */
START_TEST(ironing_covers_the_top_surfaces)
{
	struct mesh *m = step();
	struct slicer_config c;
	struct slicer_summary sum;
	struct layer_stack *off, *on, *most;

	/* fill_angle 0: ironing at 45 degrees on layer 24, so links near the
	 * block's corners would cut across them */
	iron_config(&c, false, "top");
	c.infill.fill_angle = 0;
	off = toolpaths(m, &c, &sum);
	iron_config(&c, true, "top");
	c.infill.fill_angle = 0;
	on = toolpaths(m, &c, &sum);
	iron_config(&c, true, "topmost");
	c.infill.fill_angle = 0;
	most = toolpaths(m, &c, &sum);
	ck_assert_uint_eq(on->nlayers, 50);
	for (size_t i = 0; i < on->nlayers; i++) {
		const struct layer_paths *a = &off->layers[i], *b = &on->layers[i];
		struct iron_stats s = iron_of(b), t = iron_of(&most->layers[i]);
		size_t k = 0;

		/* the same paths, ironing appended after them; above the first
		 * ironing the infill starts from where it ended, so only the
		 * roles are compared there */
		ck_assert_uint_eq(b->n, a->n + s.n);
		for (; k < a->n; k++) {
			ck_assert_int_eq(a->paths[k].role, b->paths[k].role);
			if (i > 24)
				continue;
			ck_assert_uint_eq(a->paths[k].n, b->paths[k].n);
			ck_assert(!memcmp(a->paths[k].pts, b->paths[k].pts,
					  a->paths[k].n * sizeof(*a->paths[k].pts)));
		}
		ck_assert_uint_eq(tu_count_role(a, PATH_IRONING), 0);
		if (i == 24) { /* the ring around the upper block, 0.2 mm inside */
			double ring = 19.6 * 19.6 - 10 * 10;
			ck_assert_uint_gt(s.n, 0);
			ck_assert_msg(!crosses(b, sum.min[0] + 5, sum.min[1] + 5, sum.max[0] - 5,
					       sum.max[1] - 5),
				      "an ironing line or link crosses the upper block");
			ck_assert_msg(fabs(s.len * 0.1 - ring) < 0.03 * ring, "ring: %g mm", s.len);
			ck_assert(fabs(s.x0 - (sum.min[0] + 0.2)) < 0.11 &&
				  fabs(s.x1 - (sum.max[0] - 0.2)) < 0.11);
			ck_assert_uint_eq(t.n, 0);
		} else if (i == on->nlayers - 1) { /* the upper block's top */
			double top = 9.6 * 9.6;
			ck_assert_msg(fabs(s.len * 0.1 - top) < 0.03 * top, "top: %g mm", s.len);
			ck_assert(fabs(s.x0 - (sum.min[0] + 5.2)) < 0.11 &&
				  fabs(s.y1 - (sum.max[1] - 5.2)) < 0.11);
			ck_assert_uint_eq(t.n, s.n);
		} else {
			ck_assert_msg(s.n == 0 && t.n == 0, "layer %zu ironed", i);
		}
	}
	layer_stack_free(off);
	layer_stack_free(on);
	layer_stack_free(most);
	mesh_free(m);
}
END_TEST

/*
 * ironing_type solid at 100 % infill: every layer is solid throughout and
 * ironed over its whole section (half a nozzle inside), and so at 96 %
 * (sparse above 95 % counts as solid); at 20 % a middle layer of the lower
 * block has only sparse infill and is not ironed.
 */
START_TEST(ironing_solid_irons_solid_layers)
{
	struct mesh *m = step();
	struct slicer_config c;
	struct slicer_summary sum;
	struct layer_stack *st;
	struct iron_stats s;

	iron_config(&c, true, "solid");
	st = toolpaths(m, &c, &sum);
	ck_assert_uint_eq(iron_of(&st->layers[12]).n, 0);
	layer_stack_free(st);
	c.infill.density = 100;
	st = toolpaths(m, &c, &sum);
	s = iron_of(&st->layers[12]);
	ck_assert_msg(fabs(s.len * 0.1 - 19.6 * 19.6) < 0.03 * 19.6 * 19.6, "%g mm", s.len);
	s = iron_of(&st->layers[37]);
	ck_assert_msg(fabs(s.len * 0.1 - 9.6 * 9.6) < 0.03 * 9.6 * 9.6, "%g mm", s.len);
	layer_stack_free(st);
	c.infill.density = 96; /* sparse above 95 % counts as solid, as in PrusaSlicer */
	st = toolpaths(m, &c, &sum);
	ck_assert_uint_gt(tu_count_role(&st->layers[12], PATH_SPARSE_INFILL), 0);
	s = iron_of(&st->layers[12]);
	ck_assert_msg(fabs(s.len * 0.1 - 19.6 * 19.6) < 0.03 * 19.6 * 19.6, "96 %%: %g mm", s.len);
	layer_stack_free(st);
	mesh_free(m);
}
END_TEST

/*
 * The G-code: the ironing of the last layer comes after its top skin, at
 * that layer's Z, at ironing_speed, with PrusaSlicer's flow (layer_height
 * x 15 % x 0.1 mm per mm of line); the header lists the five settings.
 * Without ironing nothing of it is there, and the other four settings
 * change no byte.
 */
START_TEST(ironing_gcode_low_flow_at_the_top_z)
{
	struct mesh *m = fx_box(0, 0, 0, 20, 20, 2);
	struct slicer_config c;
	char *text, *at, *skin;
	double fil = M_PI * 1.75 * 1.75 / 4, x = 0, y = 0, e = 0, len = 0, ext = 0;
	int moves = 0;

	iron_config(&c, false, "top");
	text = gcode_of(m, &c);
	ck_assert_ptr_null(strstr(text, "Ironing"));
	ck_assert_ptr_null(strstr(text, "; ironing"));
	iron_config(&c, false, "solid");
	c.gcodew.ironing_flowrate = 50;
	c.gcodew.ironing_spacing = 0.3;
	c.gcodew.ironing_speed = 99;
	at = gcode_of(m, &c);
	ck_assert_str_eq(text, at);
	free(at);
	free(text);

	iron_config(&c, true, "top");
	c.gcodew.use_relative_e_distances = true;
	text = gcode_of(m, &c);
	ck_assert_ptr_nonnull(strstr(text, "\n; ironing = 1\n; ironing_type = top\n"
					   "; ironing_flowrate = 15%\n; ironing_spacing = 0.1\n"
					   "; ironing_speed = 15\n"));
	at = strstr(text, ";TYPE:Ironing\n");
	skin = strstr(text, ";Z:2\n");
	ck_assert(at && skin && skin < at);
	ck_assert_ptr_nonnull(strstr(skin, ";TYPE:Top solid infill\n"));
	ck_assert(strstr(skin, ";TYPE:Top solid infill\n") < at);
	ck_assert_ptr_null(strstr(at + 1, ";TYPE:Ironing")); /* one layer, one run */
	/* replay the run: position from the last XY before it */
	for (char *p = skin; p < at; p = strchr(p, '\n') + 1) {
		char *end = strchr(p, '\n');
		double v;
		if (!strncmp(p, "G1 ", 3) && word(p, end, 'X', &v))
			x = v;
		if (!strncmp(p, "G1 ", 3) && word(p, end, 'Y', &v))
			y = v;
	}
	for (char *p = strchr(at, '\n') + 1; !strncmp(p, "G1 ", 3); p = strchr(p, '\n') + 1) {
		char *end = strchr(p, '\n');
		double nx = x, ny = y, v;
		ck_assert_msg(!word(p, end, 'Z', &v), "a Z move in the ironing");
		word(p, end, 'X', &nx);
		word(p, end, 'Y', &ny);
		e = 0;
		if (word(p, end, 'E', &e) && e > 0) {
			double d = hypot(nx - x, ny - y);
			len += d;
			ext += e;
			moves++;
			if (word(p, end, 'F', &v))
				ck_assert_double_eq_tol(v, 15 * 60, 1e-9);
		}
		x = nx;
		y = ny;
	}
	ck_assert_int_gt(moves, 100);
	ck_assert_msg(fabs(ext / len - 0.2 * 0.15 * 0.1 / fil) < 1e-3 * 0.2 * 0.15 * 0.1 / fil,
		      "%g mm of filament per mm", ext / len);
	ck_assert_msg(fabs(len * 0.1 - 19.6 * 19.6) < 0.03 * 19.6 * 19.6, "%g mm", len);
	free(text);
	mesh_free(m);
}
END_TEST

/*
 * iron_lines on a staircase (10 steps of 1 mm, each a concave corner) at
 * 45 degrees: the lines are joined into zigzags (far fewer paths than
 * lines), and no line or link leaves the area, although a link between
 * the two line ends beside a concave corner would cut across it.
 */
START_TEST(ironing_links_stay_inside)
{
	int64_t xy[2 * 22];
	struct clip_paths area = {0}, zig = {0};
	struct clip_locator *loc;
	struct st_error err = {0};
	size_t n = 0, pts = 0;

	/* (0,0) (10,0) then down the steps (10,1) (9,1) (9,2) ... (1,10) (0,10), in mm */
	xy[n++] = 0, xy[n++] = 0;
	for (int k = 0; k < 10; k++) {
		xy[n++] = (int64_t)(10 - k) * 1000000, xy[n++] = (int64_t)k * 1000000;
		xy[n++] = (int64_t)(10 - k) * 1000000, xy[n++] = (int64_t)(k + 1) * 1000000;
	}
	xy[n++] = 0, xy[n++] = 10000000;
	ck_assert_int_eq(clip_paths_add(&area, xy, n / 2, &err), 0);
	ck_assert_int_eq(iron_lines(&area, M_PI / 4, 100000, &zig, &err), 0);
	loc = clip_locator_new(&area, &err);
	ck_assert_ptr_nonnull(loc);
	for (size_t i = 0; i < zig.n; i++) {
		const int64_t *p = clip_path_xy(&zig, i);
		size_t m = clip_path_len(&zig, i);
		pts += m;
		for (size_t k = 0; k + 1 < m; k++)
			for (int s = 1; s < 16; s++) {
				double t = s / 16.0;
				int64_t x = llround(p[2 * k] + t * (double)(p[2 * k + 2] - p[2 * k]));
				int64_t y = llround(p[2 * k + 1] + t * (double)(p[2 * k + 3] - p[2 * k + 1]));
				ck_assert_msg(clip_locator_inside(loc, x, y),
					      "path %zu segment %zu leaves the area at %g,%g mm", i, k,
					      x / NM, y / NM);
			}
	}
	/* about 10 * sqrt(2) / 0.1 = 141 lines of 2 points, joined */
	ck_assert_uint_gt(pts, 200);
	ck_assert_msg(zig.n < 40, "%zu paths", zig.n);
	clip_locator_free(loc);
	clip_paths_free(&area);
	clip_paths_free(&zig);
}
END_TEST

void slicer_modes_tcases(Suite *s)
{
	TCase *tc = tcase_create("modes");

	tcase_set_timeout(tc, 120);
	tcase_add_test(tc, spiral_vase_one_wall_above_the_bottom);
	tcase_add_test(tc, spiral_vase_gcode_rises_without_retraction);
	tcase_add_test(tc, spiral_vase_first_loop_ramps_the_flow);
	tcase_add_test(tc, spiral_vase_wipes_back_along_the_loop);
	tcase_add_test(tc, spiral_vase_refuses_support);
	tcase_add_test(tc, ironing_covers_the_top_surfaces);
	tcase_add_test(tc, ironing_solid_irons_solid_layers);
	tcase_add_test(tc, ironing_gcode_low_flow_at_the_top_z);
	tcase_add_test(tc, ironing_links_stay_inside);
	suite_add_tcase(s, tc);
}
