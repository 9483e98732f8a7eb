/*
 * check_preview.c - the layer preview (host/preview.h, host/pvdraw.h,
 * `stratum preview`) and the move walker under it (serial/gcwalk.h): hand
 * G-code whose moves are known, our slicer's box drawn as SVG (xmllint,
 * paths per feature, the model outline where the box is) and PNG (decoded
 * with cairo: size, bead colour where beads are, background elsewhere),
 * PrusaSlicer-style files, and the refusals.
 */
#include <cairo.h>
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fixtures.h"
#include "gcwalk.h"
#include "meshio.h"
#include "preview.h"
#include "pvdraw.h"
#include "slicer.h"
#include "suites.h"
#include "testutil.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define FIL 1.75 /* mm */

static char out[16384];

/* Filament mm for a bead of width w, height h, length len (perimeters.h flow model). */
static double e_for(double w, double h, double len)
{
	double area = (w - h) * h + M_PI * h * h / 4;
	return area * len / (M_PI * FIL * FIL / 4);
}

static struct gcwalk *walker(const char *name, const char *text, FILE **fp)
{
	struct gcwalk *w = NULL;
	struct st_error err = {0};
	const char *path = tu_path(name);

	tu_write_str(path, text);
	*fp = fopen(path, "rb");
	ck_assert_ptr_nonnull(*fp);
	ck_assert_msg(gcwalk_new(*fp, name, &w, &err) == 0, "%s", err.msg);
	return w;
}

static void next_ok(struct gcwalk *w, struct gcwalk_move *m)
{
	struct st_error err = {0};
	int rc = gcwalk_next(w, m, &err);
	ck_assert_msg(rc == 1, "gcwalk_next: %d %s", rc, err.msg);
}

START_TEST(walker_tracks_modes)
{
	FILE *fp;
	struct gcwalk_move m;
	struct gcwalk *w = walker("walk.gcode",
				  "G90\nM83\nG1 X10 Y0 Z0.3 E1\n"	  /* abs XYZ, rel E */
				  "G91\nG1 X5 E0.5\n"			  /* all relative */
				  "G90\nM82\nG92 E10\nG1 X20 E11 F600\n" /* abs E after G92 */
				  ";TYPE:Perimeter\n;LAYER_CHANGE\n;Z:0.6\n;HEIGHT:0.3\n"
				  "G1 Z0.6\nG28\nG1 X1 Y1\n"
				  "; filament_diameter = 2.85\n",
				  &fp);

	next_ok(w, &m);
	ck_assert(m.to[0] == 10 && m.to[2] == 0.3 && m.de == 1 && m.from[0] == 0);
	ck_assert_str_eq(m.type, "");
	ck_assert_int_eq(m.layer, -1);
	next_ok(w, &m);
	ck_assert(m.from[0] == 10 && m.to[0] == 15 && m.to[2] == 0.3 && m.de == 0.5);
	next_ok(w, &m);
	ck_assert(m.to[0] == 20 && fabs(m.de - 1) < 1e-12 && m.feed == 600);
	next_ok(w, &m);
	ck_assert(m.to[2] == 0.6 && m.de == 0 && m.layer == 0);
	ck_assert(fabs(m.layer_z - 0.6) < 1e-12 && fabs(m.layer_height - 0.3) < 1e-12);
	ck_assert_str_eq(m.type, "Perimeter");
	next_ok(w, &m);
	/* G28 puts X, Y, Z at 0. */
	ck_assert(m.from[0] == 0 && m.from[2] == 0 && m.to[0] == 1 && m.to[1] == 1);
	struct st_error err = {0};
	ck_assert_int_eq(gcwalk_next(w, &m, &err), 0);
	ck_assert(gcwalk_filament_diameter(w) == 2.85);
	ck_assert_int_eq(gcwalk_layer_marks(w), 1);
	gcwalk_free(w);
	fclose(fp);
}
END_TEST

/* Arcs as Marlin cuts them (motion/G2_G3.cpp): chords of about 1 mm on
 * the circle, E and Z spread over them, the last on the target, all with
 * the arc's line: counter-clockwise with I J, clockwise with R, a whole
 * circle (issue 18). */
START_TEST(walker_arcs)
{
	static const struct {
		const char *line;
		double to[2], centre[2], r, de, lo[2], hi[2];
		int chords;
	} arcs[] = {
	    /* a quarter from (10,0) to (0,10) round the origin: 15.7 mm */
	    {"G3 X0 Y10 I-10 J0 E2", {0, 10}, {0, 0}, 10, 2, {0, 0}, {10, 10}, 15},
	    /* back, clockwise, the short way (R > 0) */
	    {"G2 X10 Y0 R10 E1", {10, 0}, {0, 0}, 10, 1, {0, 0}, {10, 10}, 15},
	    /* the long way (R < 0): three quarters through the other side */
	    {"G2 X0 Y10 R-10", {0, 10}, {0, 0}, 10, 0, {-10, -10}, {10, 10}, 47},
	    /* a whole circle: no X Y, I J only */
	    {"G3 I0 J-5 E3", {0, 10}, {0, 5}, 5, 3, {-5, 0}, {5, 10}, 31},
	};
	char text[512];
	size_t n = (size_t)snprintf(text, sizeof(text), "M83\nG1 X10 Y0 Z0.2\n");
	for (size_t i = 0; i < sizeof(arcs) / sizeof(arcs[0]); i++)
		n += (size_t)snprintf(text + n, sizeof(text) - n, "%s\n", arcs[i].line);
	snprintf(text + n, sizeof(text) - n, "G1 X1 Y1\n");
	FILE *fp;
	struct gcwalk_move m;
	struct gcwalk *w = walker("arcs.gcode", text, &fp);

	next_ok(w, &m);
	for (size_t i = 0; i < sizeof(arcs) / sizeof(arcs[0]); i++) {
		double de = 0, at[2] = {m.to[0], m.to[1]};
		double lo[2] = {at[0], at[1]}, hi[2] = {at[0], at[1]};
		int chords = 0;

		do {
			next_ok(w, &m);
			ck_assert_msg(m.line == i + 3, "%s: move of line %llu", arcs[i].line,
				      (unsigned long long)m.line);
			ck_assert(m.from[0] == at[0] && m.from[1] == at[1] && m.to[2] == 0.2);
			ck_assert_msg(fabs(hypot(m.to[0] - arcs[i].centre[0],
						 m.to[1] - arcs[i].centre[1]) - arcs[i].r) < 1e-9,
				      "%s: chord %d ends at %g %g, off the circle", arcs[i].line, chords,
				      m.to[0], m.to[1]);
			de += m.de;
			for (int a = 0; a < 2; a++) {
				lo[a] = fmin(lo[a], m.to[a]);
				hi[a] = fmax(hi[a], m.to[a]);
				at[a] = m.to[a];
			}
			chords++;
		} while (chords < arcs[i].chords);
		ck_assert_msg(m.to[0] == arcs[i].to[0] && m.to[1] == arcs[i].to[1],
			      "%s: ends at %g %g", arcs[i].line, m.to[0], m.to[1]);
		ck_assert_msg(fabs(de - arcs[i].de) < 1e-12, "%s: E %g", arcs[i].line, de);
		for (int a = 0; a < 2; a++)
			ck_assert_msg(fabs(lo[a] - arcs[i].lo[a]) < 0.05 &&
					  fabs(hi[a] - arcs[i].hi[a]) < 0.05,
				      "%s: spans %g..%g on axis %d", arcs[i].line, lo[a], hi[a], a);
	}
	/* then the next line, and no more chords */
	next_ok(w, &m);
	ck_assert(m.line == 7 && m.g == 1 && m.to[0] == 1 && m.to[1] == 1);
	gcwalk_free(w);
	fclose(fp);
}
END_TEST

START_TEST(walker_refusals)
{
	static const struct {
		const char *text;
		int code;
		const char *says;
	} cases[] = {
	    {"G20\n", ST_ERR_UNSUPPORTED, "line 1: G20"},
	    {"G1 X1 Y1\nG2 X5 Y5 E1\n", ST_ERR_PARSE, "line 2: G2 needs its centre"},
	    {"G3 X0 Y0 R5\n", ST_ERR_PARSE, "line 1: G3 needs its centre"},
	    {"G2 I1 P101\n", ST_ERR_PARSE, "line 1: P101: the full circles of G2 go from 0 to 100"},
	    {"G1 X2000000\n", ST_ERR_RANGE, "beyond"},
	    {"G2 I999999999999999\n", ST_ERR_RANGE, "line 1: the arc reaches beyond"},
	    {"G1 X1..2\n", ST_ERR_PARSE, "line 1"},
	};
	for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
		FILE *fp;
		struct gcwalk_move m;
		struct st_error err = {0};
		struct gcwalk *w = walker("bad.gcode", cases[i].text, &fp);
		int rc;
		while ((rc = gcwalk_next(w, &m, &err)) == 1)
			;
		ck_assert_int_eq(rc, cases[i].code);
		ck_assert_msg(strstr(err.msg, cases[i].says), "%s", err.msg);
		gcwalk_free(w);
		fclose(fp);
	}
}
END_TEST

/* A 20 x 10 x 5 mm box sliced with the library defaults (centre 100,100). */
static const char *slice_box(struct mesh **m)
{
	struct slicer_config c;
	struct st_error err = {0};
	const char *path = tu_path("box.gcode");

	*m = fx_box(0, 0, 0, 20, 10, 5);
	slicer_config_init(&c, 0.4);
	c.threads = 1;
	ck_assert_msg(slicer_run(*m, &c, path, NULL, &err) == 0, "%s", err.msg);
	return path;
}

static struct preview *load(const char *path, long layer, double z)
{
	struct preview_opts o;
	struct preview *pv = NULL;
	struct st_error err = {0};

	preview_opts_init(&o);
	o.layer = layer;
	o.z = z;
	ck_assert_msg(preview_load(path, &o, &pv, &err) == 0, "%s", err.msg);
	return pv;
}

static const struct preview_path *first_of(const struct preview *pv, enum preview_feature f)
{
	for (size_t i = 0; i < pv->n; i++)
		if (pv->paths[i].feature == f)
			return &pv->paths[i];
	ck_abort_msg("no %s path", preview_feature_name(f));
	return NULL;
}

static void path_box(const struct preview_path *p, double lo[2], double hi[2])
{
	lo[0] = lo[1] = INFINITY;
	hi[0] = hi[1] = -INFINITY;
	for (size_t k = 0; k < p->n; k++)
		for (int a = 0; a < 2; a++) {
			lo[a] = fmin(lo[a], p->xy[2 * k + a]);
			hi[a] = fmax(hi[a], p->xy[2 * k + a]);
		}
}

START_TEST(box_layers_and_outline)
{
	struct mesh *m;
	const char *path = slice_box(&m);
	struct st_error err = {0};
	struct preview *pv = load(path, 1, 0);
	double lo[2], hi[2], plo[2], phi[2];

	ck_assert_uint_eq(pv->layers, 25);
	ck_assert(pv->by_comments);
	ck_assert_uint_eq(pv->count[PREVIEW_SKIRT], 1);
	ck_assert_uint_eq(pv->count[PREVIEW_OUTER_PERIMETER], 1);
	ck_assert_uint_eq(pv->count[PREVIEW_INNER_PERIMETER], 1);
	ck_assert_uint_gt(pv->count[PREVIEW_SKIN], 0);
	ck_assert_uint_eq(pv->count[PREVIEW_INFILL], 0);
	preview_free(pv);

	/* Layer 10 (Z 2 mm) is between the skins: sparse infill, no skirt. */
	pv = load(path, 0, 1.95);
	ck_assert_uint_eq(pv->layer, 10);
	ck_assert(fabs(pv->z - 2.0) < 1e-9 && fabs(pv->height - 0.2) < 1e-9);
	ck_assert_uint_eq(pv->count[PREVIEW_SKIRT], 0);
	ck_assert_uint_eq(pv->count[PREVIEW_OUTER_PERIMETER], 1);
	ck_assert_uint_eq(pv->count[PREVIEW_INNER_PERIMETER], 1);
	ck_assert_uint_gt(pv->count[PREVIEW_INFILL], 0);
	ck_assert_uint_eq(pv->count[PREVIEW_SKIN], 0);

	/* The section sits where the slicer put the box: 90..110 x 95..105. */
	ck_assert_msg(preview_add_model(pv, m, NULL, &err) == 0, "%s", err.msg);
	ck_assert_uint_eq(pv->noutline, 1);
	path_box(&pv->outline[0], lo, hi);
	ck_assert_msg(fabs(lo[0] - 90) < 1e-6 && fabs(hi[0] - 110) < 1e-6 &&
			      fabs(lo[1] - 95) < 1e-6 && fabs(hi[1] - 105) < 1e-6,
		      "outline %g..%g x %g..%g", lo[0], hi[0], lo[1], hi[1]);
	/* The outer wall's centre line runs half its real width inside it. */
	const struct preview_path *outer = first_of(pv, PREVIEW_OUTER_PERIMETER);
	ck_assert(outer->closed);
	ck_assert_msg(outer->width > 0.3 && outer->width < 0.6, "width %g", outer->width);
	path_box(outer, plo, phi);
	for (int a = 0; a < 2; a++) {
		ck_assert_msg(fabs(plo[a] - outer->width / 2 - lo[a]) < 0.01, "axis %d: %g vs %g", a,
			      plo[a] - outer->width / 2, lo[a]);
		ck_assert_msg(fabs(phi[a] + outer->width / 2 - hi[a]) < 0.01, "axis %d: %g vs %g", a,
			      phi[a] + outer->width / 2, hi[a]);
	}
	preview_free(pv);
	mesh_free(m);
}
END_TEST

/* Number of "<path" inside <g id="ID"> ... </g> of the SVG text s. */
static int svg_paths(const char *s, const char *id)
{
	char open[64];
	int n = 0;

	snprintf(open, sizeof(open), "<g id=\"%s\"", id);
	const char *g = strstr(s, open);
	if (!g)
		return 0;
	const char *end = strstr(g, "</g>");
	ck_assert_ptr_nonnull(end);
	for (const char *p = strstr(g, "<path"); p && p < end; p = strstr(p + 1, "<path"))
		n++;
	return n;
}

static char *slurp(const char *path)
{
	FILE *f = fopen(path, "rb");
	ck_assert_ptr_nonnull(f);
	fseek(f, 0, SEEK_END);
	long n = ftell(f);
	rewind(f);
	char *buf = malloc((size_t)n + 1);
	ck_assert_ptr_nonnull(buf);
	ck_assert_uint_eq(fread(buf, 1, (size_t)n, f), (size_t)n);
	buf[n] = 0;
	fclose(f);
	return buf;
}

START_TEST(box_svg)
{
	struct mesh *m;
	const char *gcode = slice_box(&m);
	char model[512], svg[512], cmd[1200];
	struct st_error err = {0};

	snprintf(model, sizeof(model), "%s", tu_path("box.stl"));
	snprintf(svg, sizeof(svg), "%s", tu_path("box.svg"));
	ck_assert_msg(meshio_write_stl(model, m, MESHIO_STL_BINARY, &err) == 0, "%s", err.msg);
	ck_assert_int_eq(tu_run(out, sizeof(out), "preview %s --layer 10 -o %s --model %s", gcode,
				svg, model),
			 0);
	ck_assert_msg(strstr(out, "layer 10 of 25") && strstr(out, "written:"), "%s", out);
	snprintf(cmd, sizeof(cmd), "xmllint --noout '%s' 2>&1", svg);
	ck_assert_msg(system(cmd) == 0, "xmllint rejects %s", svg);

	struct preview *pv = load(gcode, 10, 0);
	char *s = slurp(svg);
	int total = 0;
	for (int f = 0; f < PREVIEW_FEATURES; f++) {
		int n = svg_paths(s, preview_feature_id(f));
		ck_assert_msg(n == (int)pv->count[f], "%s: %d paths, want %zu",
			      preview_feature_id(f), n, pv->count[f]);
		total += n;
	}
	ck_assert_int_eq(svg_paths(s, "outer-perimeter"), 1);
	ck_assert_int_eq(svg_paths(s, "inner-perimeter"), 1);
	ck_assert_int_eq(svg_paths(s, "model-outline"), 1);
	/* Nothing else is a path: legend and scale bar are rects, lines, text. */
	int all = 0;
	for (const char *p = strstr(s, "<path"); p; p = strstr(p + 1, "<path"))
		all++;
	ck_assert_int_eq(all, total + 1);
	ck_assert_ptr_nonnull(strstr(s, "outer perimeter (1)"));
	ck_assert_ptr_nonnull(strstr(s, " mm</text>"));
	free(s);
	preview_free(pv);
	mesh_free(m);
}
END_TEST

/* Pixel (x, y) of an RGB24 surface as 0xRRGGBB. */
static unsigned pixel(cairo_surface_t *img, int x, int y)
{
	const unsigned char *row = cairo_image_surface_get_data(img) +
				   (size_t)y * (size_t)cairo_image_surface_get_stride(img);
	uint32_t v;
	memcpy(&v, row + 4 * x, 4);
	return v & 0xffffff;
}

START_TEST(box_png)
{
	struct mesh *m;
	const char *gcode = slice_box(&m);
	const char *png = tu_path("box.png");
	struct pvdraw_opts o = {.width_px = 600, .title = "box"};
	struct st_error err = {0};
	struct preview *pv = load(gcode, 10, 0);
	int w, h;
	double px, py;

	ck_assert_msg(pvdraw_write(pv, &o, png, &err) == 0, "%s", err.msg);
	ck_assert_int_eq(pvdraw_size(pv, &o, &w, &h, &err), 0);
	cairo_surface_t *img = cairo_image_surface_create_from_png(png);
	ck_assert_int_eq(cairo_surface_status(img), CAIRO_STATUS_SUCCESS);
	ck_assert_int_eq(cairo_image_surface_get_width(img), 600);
	ck_assert_int_eq(cairo_image_surface_get_height(img), h);
	ck_assert_int_eq(w, 600);

	/* On the outer wall's centre line: its colour, orange. */
	const struct preview_path *outer = first_of(pv, PREVIEW_OUTER_PERIMETER);
	double mx = (outer->xy[0] + outer->xy[2]) / 2, my = (outer->xy[1] + outer->xy[3]) / 2;
	ck_assert_int_eq(pvdraw_to_px(pv, &o, mx, my, &px, &py, &err), 0);
	unsigned c = pixel(img, (int)px, (int)py);
	ck_assert_msg(c == 0xff6f20, "outer wall pixel %06x at %g,%g", c, px, py);
	/* 2 mm outside the box, inside the frame: background. */
	ck_assert_int_eq(pvdraw_to_px(pv, &o, 88, 100, &px, &py, &err), 0);
	c = pixel(img, (int)px, (int)py);
	ck_assert_msg(c == 0xffffff, "background pixel %06x at %g,%g", c, px, py);
	/* A wider picture scales the layer, not the legend. */
	o.width_px = 1200;
	int w2, h2;
	ck_assert_int_eq(pvdraw_size(pv, &o, &w2, &h2, &err), 0);
	ck_assert_int_eq(w2, 1200);
	ck_assert_int_gt(h2, h);
	cairo_surface_destroy(img);
	preview_free(pv);
	mesh_free(m);
}
END_TEST

/*
 * PrusaSlicer's way of writing: absolute E with G92 E0 resets, retractions,
 * ;LAYER_CHANGE ;Z: ;HEIGHT:, "Skirt/Brim", "Support material interface",
 * a start G-code prime line before the first layer, the filament diameter
 * at the end.
 */
START_TEST(prusa_style_file)
{
	const char *path = tu_path("prusa.gcode");
	char buf[4096];
	double e1 = e_for(0.5, 0.3, 10), e2 = e_for(0.45, 0.2, 10);

	snprintf(buf, sizeof(buf),
		 "M82\nG92 E0\nG1 Z0.3\nG1 X0 Y-5 E5 ; prime line, start G-code\n"
		 ";LAYER_CHANGE\n;Z:0.3\n;HEIGHT:0.3\nG1 E-0.8 F2100\nG92 E0\nG1 X0 Y0\n"
		 "G1 E0.8\n;TYPE:Skirt/Brim\nG1 X10 Y0 E%.5f\nG92 E0\n"
		 ";TYPE:External perimeter\nG1 X0 Y10\nG1 X10 Y10 E%.5f\nG1 X10 Y20 E%.5f\n"
		 ";LAYER_CHANGE\n;Z:0.5\n;HEIGHT:0.2\nG1 Z0.5\nG92 E0\n"
		 ";TYPE:Support material interface\nG1 X0 Y20 E%.5f\n"
		 "; filament_diameter = 1.75\n",
		 0.8 + e1, e1, 2 * e1, e2);
	tu_write_str(path, buf);
	struct preview *pv = load(path, 1, 0);
	ck_assert_uint_eq(pv->layers, 2);
	ck_assert_uint_eq(pv->count[PREVIEW_SKIRT], 1);
	ck_assert_uint_eq(pv->count[PREVIEW_OUTER_PERIMETER], 1);
	ck_assert_uint_eq(pv->count[PREVIEW_SUPPORT], 0);
	const struct preview_path *p = first_of(pv, PREVIEW_OUTER_PERIMETER);
	ck_assert_uint_eq(p->n, 3);
	ck_assert_msg(fabs(p->width - 0.5) < 1e-3, "width %g", p->width);
	ck_assert_msg(fabs(first_of(pv, PREVIEW_SKIRT)->width - 0.5) < 1e-3, "skirt width");
	/* The prime line before the first layer comment is not framed. */
	ck_assert_msg(pv->min[1] > -2, "frame reaches y %g", pv->min[1]);
	preview_free(pv);
	pv = load(path, 0, 0.45);
	ck_assert_uint_eq(pv->layer, 2);
	ck_assert_uint_eq(pv->count[PREVIEW_SUPPORT], 1);
	ck_assert_msg(fabs(first_of(pv, PREVIEW_SUPPORT)->width - 0.45) < 1e-3, "support width");
	preview_free(pv);
}
END_TEST

/* PrusaSlicer 2.5's own MK3S output (M862.3, M115 U3.11.0, M73 Q S, G80)
 * previews (issue 18). */
START_TEST(prusaslicer_output)
{
	const char *svg = tu_path("mk3s.svg");

	ck_assert_msg(tu_run(out, sizeof(out),
			     "preview tests/data/prusaslicer-mk3s-cube.gcode --layer 2 -o %s", svg) ==
			  0,
		      "%s", out);
	ck_assert(tu_file_exists(svg));
}
END_TEST

/* The extruding arcs of PrusaSlicer's arc fitting (FLSun, TriLAB) are drawn
 * as the curve they are: a half circle from (0,0) to (20,0) bulging to
 * y = -10, framed to its apex (issue 18). */
START_TEST(arcs_previewed)
{
	const char *path = tu_path("arc.gcode");
	char buf[1024];
	double lo[2], hi[2];

	snprintf(buf, sizeof(buf),
		 "; filament_diameter = 1.75\nM83\n;LAYER_CHANGE\n;Z:0.2\n;HEIGHT:0.2\n"
		 "G1 Z0.2\nG1 X0 Y0\n;TYPE:External perimeter\nG3 X20 Y0 I10 J0 E%.5f\n",
		 e_for(0.45, 0.2, 10 * M_PI));
	tu_write_str(path, buf);
	struct preview *pv = load(path, 1, 0);
	const struct preview_path *p = first_of(pv, PREVIEW_OUTER_PERIMETER);
	ck_assert_msg(p->n == 32, "%zu points", p->n); /* 31 chords of 31.4 mm */
	path_box(p, lo, hi);
	ck_assert_msg(fabs(lo[0]) < 1e-9 && fabs(hi[0] - 20) < 1e-9, "x %g..%g", lo[0], hi[0]);
	ck_assert_msg(fabs(lo[1] + 10) < 0.02 && fabs(hi[1]) < 1e-9, "y %g..%g", lo[1], hi[1]);
	ck_assert_msg(fabs(p->width - 0.45) < 1e-3, "width %g", p->width);
	preview_free(pv);
	ck_assert_msg(tu_run(out, sizeof(out), "preview %s --layer 1 -o %s", path,
			     tu_path("arc.png")) == 0,
		      "%s", out);
}
END_TEST

/* No layer comments at all: layers are the extrusion heights; a Z hop stays in its layer. */
START_TEST(layers_by_z)
{
	const char *path = tu_path("noc.gcode");
	char buf[2048];
	double e = e_for(0.4, 0.2, 10);

	snprintf(buf, sizeof(buf),
		 "; filament_diameter = 1.75\nM83\nG1 Z0.2\nG1 X10 Y0 E%.5f\n"
		 "G1 Z0.6\nG1 X20 Y5\nG1 Z0.2\nG1 X20 Y15 E%.5f\n" /* hop, travel, bead */
		 "G1 Z0.4\nG1 X0 Y0\nG1 X10 Y0 E%.5f\n",
		 e, e, e);
	tu_write_str(path, buf);
	struct preview *pv = load(path, 1, 0);
	ck_assert(!pv->by_comments);
	ck_assert_uint_eq(pv->layers, 2);
	ck_assert_uint_eq(pv->count[PREVIEW_OTHER], 2);
	ck_assert_uint_eq(pv->count[PREVIEW_TRAVEL], 1);
	ck_assert_msg(fabs(pv->paths[0].width - 0.4) < 1e-3, "width %g", pv->paths[0].width);
	preview_free(pv);
	pv = load(path, 2, 0);
	ck_assert(fabs(pv->z - 0.4) < 1e-9);
	ck_assert_uint_eq(pv->count[PREVIEW_OTHER], 1);
	preview_free(pv);
}
END_TEST

START_TEST(cli_refusals)
{
	struct mesh *m;
	const char *gcode = slice_box(&m);
	char svg[512], bad[512];

	snprintf(svg, sizeof(svg), "%s", tu_path("keep.svg"));
	snprintf(bad, sizeof(bad), "%s", tu_path("bad.gcode"));
	tu_write_str(svg, "keep");
	tu_write_str(bad, "; filament_diameter = 1.75\nG1 X1 Y1 E1\nG1 X1..2 Y3\n");

	ck_assert_int_eq(tu_run(out, sizeof(out), "preview %s --layer 26 -o %s", gcode, svg), 2);
	ck_assert_msg(strstr(out, "no layer 26: the file has layers 1 to 25 (Z 0.2 to 5 mm)"),
		      "%s", out);
	ck_assert_int_eq(tu_run(out, sizeof(out), "preview %s --z 7 -o %s", gcode, svg), 2);
	ck_assert_msg(strstr(out, "no layer at Z 7 mm"), "%s", out);
	ck_assert_int_eq(tu_run(out, sizeof(out), "preview %s --layer 0 -o %s", gcode, svg), 2);
	ck_assert_int_eq(tu_run(out, sizeof(out), "preview %s --layer 1 --z 1 -o %s", gcode, svg),
			 2);
	ck_assert_int_eq(tu_run(out, sizeof(out), "preview %s --layer 1", gcode), 2);
	ck_assert_int_eq(tu_run(out, sizeof(out), "preview %s --layer 1 -o x.jpg", gcode), 2);
	ck_assert_msg(strstr(out, "must end in .svg or .png"), "%s", out);
	ck_assert_int_eq(tu_run(out, sizeof(out), "preview %s --layer 1 -o %s --width 50", gcode,
				svg),
			 2);
	ck_assert_msg(strstr(out, "--width wants a whole number of pixels from 200 to 8192"), "%s",
		      out);
	ck_assert_int_eq(tu_run(out, sizeof(out), "preview %s --layer 1 -o %s", bad, svg), 65);
	ck_assert_msg(strstr(out, "line 3"), "%s", out);
	ck_assert_int_eq(tu_run(out, sizeof(out), "preview %s.missing --layer 1 -o %s", bad, svg),
			 65);
	ck_assert_int_eq(
	    tu_run(out, sizeof(out), "preview %s --layer 1 -o %s --model %s", gcode, svg, bad), 65);
	/* Every refusal left the old picture alone. */
	char *s = slurp(svg);
	ck_assert_str_eq(s, "keep");
	free(s);
	/* A directory that does not exist: the job fails (1), nothing half-written. */
	ck_assert_int_eq(tu_run(out, sizeof(out), "preview %s --layer 1 -o /nonexistent/x.png",
				gcode),
			 1);
	ck_assert_msg(strstr(out, "/nonexistent/x.png: cannot create a temporary file"), "%s",
		      out);
	mesh_free(m);
}
END_TEST

Suite *preview_suite(void)
{
	Suite *s = suite_create("preview");
	TCase *tc = tcase_create("preview");

	tcase_set_timeout(tc, 60);
	tcase_add_test(tc, walker_tracks_modes);
	tcase_add_test(tc, walker_refusals);
	tcase_add_test(tc, walker_arcs);
	tcase_add_test(tc, box_layers_and_outline);
	tcase_add_test(tc, box_svg);
	tcase_add_test(tc, box_png);
	tcase_add_test(tc, prusa_style_file);
	tcase_add_test(tc, prusaslicer_output);
	tcase_add_test(tc, layers_by_z);
	tcase_add_test(tc, arcs_previewed);
	tcase_add_test(tc, cli_refusals);
	suite_add_tcase(s, tc);
	return s;
}
