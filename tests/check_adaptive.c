/*
 * check_adaptive.c - adaptive layer heights (slicer/adaptive.h, `stratum
 * slice --adaptive`): the plan against a cusp computed here from the
 * facets, on a sphere (thin layers at the poles, thick at the equator) and
 * a box (vertical walls: the largest layers); the smoothing's bound between
 * neighbours; the G-code's Z, flow and M73 following the heights; uniform
 * heights through the adaptive path printing as uniform slicing does; the
 * refusals; the command's summary and plot.
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "adaptive.h"
#include "fixtures.h"
#include "mesh.h"
#include "meshio.h"
#include "slicer.h"
#include "suites.h"
#include "testutil.h"

#define EPS 1e-9

static struct adaptive_settings settings(double first, double min, double max, double cusp)
{
	return (struct adaptive_settings){
	    .first_height = first, .min_height = min, .max_height = max, .max_cusp = cusp};
}

static struct layer_span *plan_ok(const struct mesh *m, const struct adaptive_settings *s,
				  size_t *n)
{
	struct layer_span *plan = NULL;
	struct st_error err = {0};

	ck_assert_msg(adaptive_plan(m, s, &plan, n, &err) == 0, "adaptive_plan: %s", err.msg);
	ck_assert_uint_gt(*n, 1);
	return plan;
}

/* The largest h |n_z| over the sloped facets whose Z span overlaps layer i
 * (mesh Z from its lowest point), computed apart from adaptive.c. */
static double layer_cusp(const struct mesh *m, const struct layer_span *l)
{
	double lo3[3], hi3[3], worst = 0.0;

	mesh_bbox(m, lo3, hi3);
	for (size_t t = 0; t < m->ntris; t++) {
		const double *a = m->verts[m->tris[t][0]], *b = m->verts[m->tris[t][1]],
			     *c = m->verts[m->tris[t][2]];
		double nx = (b[1] - a[1]) * (c[2] - a[2]) - (b[2] - a[2]) * (c[1] - a[1]);
		double ny = (b[2] - a[2]) * (c[0] - a[0]) - (b[0] - a[0]) * (c[2] - a[2]);
		double nz = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
		double lo = fmin(a[2], fmin(b[2], c[2])) - lo3[2];
		double hi = fmax(a[2], fmax(b[2], c[2])) - lo3[2];

		if (hi > lo && lo < l->z && hi > l->z - l->height)
			worst =
			    fmax(worst, l->height * fabs(nz) / sqrt(nx * nx + ny * ny + nz * nz));
	}
	return worst;
}

START_TEST(adaptive_sphere_thin_at_poles_thick_at_equator)
{
	struct mesh *m = fx_sphere(0, 0, 10, 10, 48, 48);
	struct adaptive_settings s = settings(0.1, 0.05, 0.3, 0.05);
	size_t n, thin = 0, thick = 0;
	struct layer_span *p = plan_ok(m, &s, &n);

	ck_assert_double_eq_tol(p[0].height, 0.1, EPS);
	ck_assert_double_eq_tol(p[0].z, 0.1, EPS);
	ck_assert_double_le(fabs(p[n - 1].z - 20.0), s.min_height); /* up to the top */
	for (size_t i = 1; i < n; i++) {
		double mid = p[i].z - p[i].height / 2;

		ck_assert_double_eq_tol(p[i].z - p[i].height, p[i - 1].z, 1e-6); /* no gaps */
		ck_assert_double_ge(p[i].height, s.min_height - EPS);
		ck_assert_double_le(p[i].height, s.max_height + EPS);
		/* the pole's facets have |n_z| < 1: the bound is reachable everywhere */
		ck_assert_msg(layer_cusp(m, &p[i]) <= s.max_cusp + EPS,
			      "layer %zu (Z %g, %g mm) leaves a cusp of %g mm", i, p[i].z,
			      p[i].height, layer_cusp(m, &p[i]));
		if (mid < 0.5 || mid > 19.5) {
			ck_assert_double_le(p[i].height, 0.06);
			thin++;
		}
		if (fabs(mid - 10.0) < 0.8) {
			ck_assert_double_eq_tol(p[i].height, s.max_height, EPS);
			thick++;
		}
		/* smoothed: neighbours within ADAPTIVE_SMOOTHING, the last
		 * layer (cut at the top) and the rounding to whole steps aside */
		if (i >= 2 && i + 1 < n)
			ck_assert_msg(p[i].height <= p[i - 1].height * (1 + ADAPTIVE_SMOOTHING) +
							 2 * ADAPTIVE_STEP_MM &&
					  p[i - 1].height <=
					      p[i].height * (1 + ADAPTIVE_SMOOTHING) +
						  2 * ADAPTIVE_STEP_MM,
				      "layers %zu and %zu: %g then %g mm", i - 1, i,
				      p[i - 1].height, p[i].height);
	}
	ck_assert_uint_ge(thin, 10);
	ck_assert_uint_ge(thick, 4);
	free(p);
	mesh_free(m);
}
END_TEST

START_TEST(adaptive_box_gets_the_largest_layers)
{
	struct mesh *m = fx_box(0, 0, 5, 20, 20, 15); /* lifted: Z counts from its bottom */
	struct adaptive_settings s = settings(0.2, 0.07, 0.3, 0.1);
	size_t n;
	struct layer_span *p = plan_ok(m, &s, &n);

	ck_assert_uint_eq(n, 34); /* 0.2, 32 x 0.3, the last 0.2 up to 10 */
	for (size_t i = 1; i + 1 < n; i++)
		ck_assert_double_eq_tol(p[i].height, 0.3, EPS);
	ck_assert_double_eq_tol(p[n - 1].z, 10.0, 1e-6);
	ck_assert_double_eq_tol(p[n - 1].height, 0.2, 1e-6);
	free(p);
	mesh_free(m);
}
END_TEST

/* adaptive_measure: a box has no sloped facet; uniform 0.2 mm layers on a
 * sphere leave 0.2 |n_z| of its flattest facets (the polar caps). */
START_TEST(adaptive_measure_of_known_shapes)
{
	struct mesh *box = fx_box(0, 0, 0, 10, 10, 10), *ball = fx_sphere(0, 0, 0, 10, 48, 48);
	struct layer_span *plan = NULL;
	struct adaptive_cusp c;
	struct st_error err = {0};
	double per[100];
	size_t n;

	ck_assert_int_eq(slice_plan_uniform(20.0, 0.2, 0.2, &plan, &n, &err), 0);
	ck_assert_uint_eq(n, 100);
	ck_assert_int_eq(adaptive_measure(box, plan, 50, per, &c, &err), 0);
	ck_assert_double_eq(c.max, 0.0);
	ck_assert_double_eq(c.mean, 0.0);
	ck_assert_int_eq(adaptive_measure(ball, plan, n, per, &c, &err), 0);
	/* the cap's facets lean cos(90/48 degrees)... their normal's Z is the
	 * cosine of the band's mid-latitude complement */
	ck_assert_double_le(c.max, 0.2);
	ck_assert_double_ge(c.max, 0.2 * cos(M_PI / 48));
	ck_assert(c.worst_layer == 0 || c.worst_layer == n - 1);
	ck_assert_double_eq_tol(per[c.worst_layer], c.max, EPS);
	ck_assert_double_lt(per[n / 2], 0.02); /* at the equator the wall is nearly vertical */
	ck_assert_double_gt(c.mean, 0.0);
	ck_assert_double_lt(c.mean, c.max);
	free(plan);
	mesh_free(box);
	mesh_free(ball);
}
END_TEST

static void config(struct slicer_config *c)
{
	slicer_config_init(c, 0.4);
	c->threads = 1;
	c->gcodew.remaining_times = true;
	c->gcodew.use_relative_e_distances = true; /* each G1's E is its own */
}

static char *gcode_ok(const struct mesh *m, const struct slicer_config *c,
		      struct slicer_summary *sum)
{
	char path[4096];
	struct st_error err = {0};
	size_t len;

	snprintf(path, sizeof(path), "%s", tu_path("adaptive.gcode"));
	ck_assert_msg(slicer_run(m, c, path, sum, &err) == 0, "slicer_run: %s", err.msg);
	return tu_slurp(path, &len);
}

/* Adaptive heights all equal to layer_height take the uniform plan's
 * place and every stage prints them the same; other adaptive keys do
 * nothing while it is off. */
START_TEST(adaptive_uniform_heights_print_as_uniform)
{
	struct mesh *m = fx_sphere(100, 100, 10, 10, 24, 24);
	struct slicer_config c;
	char *uniform, *same, *off;

	config(&c);
	uniform = gcode_ok(m, &c, NULL);
	c.adaptive.max_cusp = 0.01;
	c.adaptive.min_height = 0.1;
	off = gcode_ok(m, &c, NULL);
	ck_assert_str_eq(off, uniform);
	c.adaptive.enabled = true;
	c.adaptive.min_height = c.adaptive.max_height = 0.2;
	same = gcode_ok(m, &c, NULL);
	ck_assert_str_eq(same, uniform);
	free(uniform);
	free(same);
	free(off);
	mesh_free(m);
}
END_TEST

/* E per mm of outer wall over the flow model's cross-section, per layer height. */
struct flow_seen {
	double h[512], e[512], len[512];
	size_t n;
};

static void outer_wall_flow(const char *g, struct flow_seen *f)
{
	double h = 0, x = NAN, y = NAN;
	bool outer = false;

	f->n = 0;
	for (const char *line = g; line && *line;
	     line = strchr(line, '\n') ? strchr(line, '\n') + 1 : NULL) {
		double nx = x, ny = y, e = 0;
		const char *v;

		if (!strncmp(line, ";HEIGHT:", 8)) {
			h = atof(line + 8);
			ck_assert_uint_lt(f->n, 512);
			f->h[f->n] = h;
			f->e[f->n] = f->len[f->n] = 0;
			f->n++;
		} else if (!strncmp(line, ";TYPE:", 6)) {
			outer = !strncmp(line + 6, "External perimeter", 18);
		} else if (!strncmp(line, "G1 ", 3)) {
			const char *end = strchr(line, '\n');
			for (v = line; v < end && (v = strpbrk(v, "XYE ;")) && v < end && *v != ';';
			     v++) {
				if (*v == 'X')
					nx = atof(v + 1);
				else if (*v == 'Y')
					ny = atof(v + 1);
				else if (*v == 'E')
					e = atof(v + 1);
			}
			if (outer && e > 0 && f->n && isfinite(x))
				f->e[f->n - 1] += e, f->len[f->n - 1] += hypot(nx - x, ny - y);
			x = nx;
			y = ny;
		}
	}
}

START_TEST(adaptive_gcode_follows_the_heights)
{
	struct mesh *m = fx_sphere(100, 100, 10, 10, 48, 48);
	struct slicer_config c;
	struct slicer_summary s;
	struct flow_seen f;
	double w = 0.45, per_area = NAN, last_p = -1; /* the walls' 1.125 x nozzle */
	size_t thin = 0, thick = 0;
	char *g;
	const char *z;

	config(&c);
	c.adaptive.enabled = true;
	c.adaptive.max_cusp = 0.05;
	c.adaptive.min_height = 0.05;
	g = gcode_ok(m, &c, &s);
	ck_assert(s.adaptive);
	ck_assert_double_le(s.cusp_max, 0.05 + EPS);
	ck_assert_double_eq_tol(s.height_max, 0.3, EPS);
	ck_assert_double_le(s.height_min, 0.06);
	/* Z: each layer's top is the last one's plus its height */
	outer_wall_flow(g, &f);
	ck_assert_uint_eq(f.n, s.layers);
	z = g;
	double top = 0;
	for (size_t i = 0; i < f.n; i++) {
		z = strstr(z, "\n;Z:");
		ck_assert_ptr_nonnull(z);
		z += 4;
		top += f.h[i];
		ck_assert_double_eq_tol(atof(z), top, 1e-3);
	}
	/* flow: E per mm over the cross-section (w - h) h + pi h^2 / 4 is one
	 * constant on every layer, thin or thick */
	for (size_t i = 1; i < f.n; i++) {
		double area = (w - f.h[i]) * f.h[i] + M_PI * f.h[i] * f.h[i] / 4;

		if (!(f.len[i] > 10))
			continue;
		if (isnan(per_area))
			per_area = f.e[i] / f.len[i] / area;
		ck_assert_msg(
		    fabs(f.e[i] / f.len[i] / area - per_area) < 0.02 * per_area,
		    "layer %zu (%g mm): %g mm of wall, E/mm %g, over the area %g (%g before)", i,
		    f.h[i], f.len[i], f.e[i] / f.len[i], f.e[i] / f.len[i] / area, per_area);
		thin += f.h[i] < 0.1;
		thick += f.h[i] > 0.25;
	}
	ck_assert_uint_gt(thin, 5);
	ck_assert_uint_gt(thick, 5);
	/* M73: from 0 to 100, never back */
	for (const char *p = strstr(g, "\nM73 P"); p; p = strstr(p + 1, "\nM73 P")) {
		double pct = atof(p + 6);
		ck_assert_double_ge(pct, last_p);
		last_p = pct;
	}
	ck_assert_double_eq(last_p, 100);
	free(g);
	mesh_free(m);
}
END_TEST

START_TEST(adaptive_settings_refused)
{
	struct slicer_config c;
	struct st_error err = {0};

	config(&c);
	c.adaptive.enabled = true;
	ck_assert_int_eq(slicer_config_check(&c, &err), 0);
	c.adaptive.allowed = false; /* variable_layer_height = 0 */
	ck_assert_int_eq(slicer_config_check(&c, &err), ST_ERR_RANGE);
	ck_assert_ptr_nonnull(strstr(err.msg, "variable_layer_height"));
	config(&c);
	c.adaptive.enabled = true;
	c.adaptive.min_height = 0.31; /* above 75 % of the nozzle */
	ck_assert_int_eq(slicer_config_check(&c, &err), ST_ERR_RANGE);
	ck_assert_ptr_nonnull(strstr(err.msg, "min_layer_height"));
	config(&c);
	c.adaptive.enabled = true;
	c.adaptive.max_cusp = 0;
	ck_assert_int_eq(slicer_config_check(&c, &err), ST_ERR_RANGE);
	ck_assert_ptr_nonnull(strstr(err.msg, "adaptive_max_cusp"));
	c.adaptive.enabled = false; /* off: not looked at */
	ck_assert_int_eq(slicer_config_check(&c, &err), 0);

	/* the plan itself: bad settings and meshes */
	const double a[3] = {0, 0, 0}, b[3] = {1, 0, 0}, far[3] = {0, 1, INFINITY};
	struct mesh *bad = fx_triangle(a, b, far), *box = fx_box(0, 0, 0, 1, 1, 1);
	struct adaptive_settings s = settings(0.2, 0.07, 0.3, 0.1);
	struct layer_span *plan = (struct layer_span *)&s; /* set to NULL on failure */
	size_t n = 1;

	ck_assert_int_eq(adaptive_plan(bad, &s, &plan, &n, &err), ST_ERR_ARG);
	ck_assert_ptr_null(plan);
	ck_assert_uint_eq(n, 0);
	s.min_height = 0.4; /* above the maximum */
	ck_assert_int_eq(adaptive_plan(box, &s, &plan, &n, &err), ST_ERR_RANGE);
	ck_assert_ptr_nonnull(strstr(err.msg, "min_layer_height"));
	s = settings(0.2, 0.07, 0.3, 0);
	ck_assert_int_eq(adaptive_plan(box, &s, &plan, &n, &err), ST_ERR_RANGE);
	mesh_free(bad);
	mesh_free(box);
}
END_TEST

START_TEST(adaptive_command_summary_and_plot)
{
	struct mesh *m = fx_sphere(0, 0, 0, 8, 24, 24);
	char out[16384], stl[4096], gc[4096], png[4096];
	unsigned char magic[8];
	FILE *f;
	int rc;

	snprintf(stl, sizeof(stl), "%s", tu_path("ball.stl"));
	snprintf(gc, sizeof(gc), "%s", tu_path("ball.gcode"));
	snprintf(png, sizeof(png), "%s", tu_path("ball.png"));
	mesh_free(tu_round_trip(m, "ball.stl", MESHIO_STL_BINARY));
	rc = tu_run(out, sizeof(out),
		    "slice %s -o %s --printer generic-marlin --max-cusp 0.08 --png %s --threads 1",
		    stl, gc, png);
	ck_assert_msg(rc == 0, "%s", out);
	ck_assert_ptr_nonnull(strstr(out, "then adaptive"));
	ck_assert_ptr_nonnull(strstr(out, "(bound 0.08 mm)"));
	ck_assert_ptr_nonnull(strstr(out, "layers of 0.0"));
	f = fopen(png, "rb");
	ck_assert_ptr_nonnull(f);
	ck_assert_uint_eq(fread(magic, 1, 8, f), 8);
	fclose(f);
	ck_assert_int_eq(memcmp(magic, "\x89PNG\r\n\x1a\n", 8), 0);
	/* the JSON summary: the bound, the cusp and every layer of the part */
	rc = tu_run(out, sizeof(out),
		    "slice %s -o %s --printer generic-marlin --adaptive --json --threads 1 "
		    "2>/dev/null",
		    stl, gc);
	ck_assert_msg(rc == 0, "%s", out);
	ck_assert_ptr_nonnull(strstr(out, "\"adaptive\": true"));
	ck_assert_ptr_nonnull(strstr(out, "\"max_cusp\": 0.1"));
	ck_assert_ptr_nonnull(strstr(out, "\"cusp_max\": "));
	ck_assert_ptr_nonnull(strstr(out, "\"layer_profile\": ["));
	/* a printer that does not allow it: refused as a bad setting, nothing written */
	remove(gc);
	rc = tu_run(out, sizeof(out),
		    "slice %s -o %s --printer generic-marlin --adaptive --set "
		    "variable_layer_height=0",
		    stl, gc);
	ck_assert_int_eq(rc, ST_EXIT_USAGE);
	ck_assert_ptr_nonnull(strstr(out, "variable_layer_height = 0"));
	ck_assert(!tu_file_exists(gc));
	mesh_free(m);
}
END_TEST

Suite *adaptive_suite(void)
{
	Suite *s = suite_create("adaptive");
	TCase *tc = tcase_create("core");

	tcase_set_timeout(tc, 60);
	tcase_add_test(tc, adaptive_sphere_thin_at_poles_thick_at_equator);
	tcase_add_test(tc, adaptive_box_gets_the_largest_layers);
	tcase_add_test(tc, adaptive_measure_of_known_shapes);
	tcase_add_test(tc, adaptive_uniform_heights_print_as_uniform);
	tcase_add_test(tc, adaptive_gcode_follows_the_heights);
	tcase_add_test(tc, adaptive_settings_refused);
	tcase_add_test(tc, adaptive_command_summary_and_plot);
	suite_add_tcase(s, tc);
	adaptive_3mf_tcases(s);
	return s;
}
