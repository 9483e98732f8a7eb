/*
 * check_slicewidths.c - PrusaSlicer's per-role extrusion widths and
 * volumetric speed limits honoured end to end (issue 18 item 4; part of the slicecli suite): `stratum slice`
 * of a 20 mm box centred at (100, 100) with --set, its G-code read back for
 * the filament per mm of each role's moves (the bead's width through the
 * flow model) and where the walls run (the outer wall's centre line half
 * its width inside the surface, the inner one the two spacings' mean
 * further in, docs/slicing.md).
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "fixtures.h"
#include "meshio.h"
#include "suites.h"
#include "testutil.h"

static char out[1 << 16];

/* generic-marlin's filament, mm */
#define FILAMENT_D 1.75
/* The box's left face once centred at (100, 100), mm */
#define BOX_X0 90.0

/* m as a binary STL scratch file (m is freed), its path into buf. */
static void model_file(struct mesh *m, char *buf, size_t cap)
{
	struct st_error err = {0};
	int rc;

	snprintf(buf, cap, "%s", tu_path("widthmodel.stl"));
	rc = meshio_write_stl(buf, m, MESHIO_STL_BINARY, &err);
	mesh_free(m);
	ck_assert_msg(rc == 0, "%s", err.msg);
}

/* m (freed) sliced with printer (the --printer or --load arguments) and
 * args; the G-code (free it). */
static char *slice_for(struct mesh *m, const char *printer, const char *args)
{
	char model[4096], gc[4096];
	size_t len;
	int status;

	model_file(m, model, sizeof(model));
	snprintf(gc, sizeof(gc), "%s", tu_path("widths.gcode"));
	status = tu_run(out, sizeof(out), "slice '%s' -o '%s' %s --center 100,100 %s", model, gc,
			printer, args);
	ck_assert_msg(status == 0, "exit %d: %s", status, out);
	return tu_slurp(gc, &len);
}

/* A 20 x 20 x 3 mm box sliced for generic-marlin with args. */
static char *slice_box(const char *args)
{
	return slice_for(fx_box(0, 0, 0, 20, 20, 3), "--printer generic-marlin", args);
}

/* Filament per mm of a bead w wide and h high (PrusaSlicer's flow model). */
static double e_per_mm(double w, double h)
{
	return ((w - h) * h + M_PI * h * h / 4) / (M_PI * FILAMENT_D * FILAMENT_D / 4);
}

/* Centre distance of beads w wide, h high. */
static double spacing(double w, double h)
{
	return w - h * (1 - M_PI / 4);
}

/* Where a move of the G-code is: its ;TYPE: (NULL before the first, in the
 * start G-code), its layer (1 = the first), its feed (mm/min). */
struct move_at {
	const char *role; /* points into the text, ends at the line's end */
	size_t role_len;
	int layer;
	double feed;
};

/* Call fn for every G0/G1 move of text that changes X or Y (relative E). */
static void walk_moves(const char *text,
		       void (*fn)(void *ctx, const struct move_at *at, double x0, double y0,
				  double x1, double y1, double e),
		       void *ctx)
{
	struct move_at at = {NULL, 0, 0, 0};
	double x = 0, y = 0;

	for (const char *l = text; *l; l = strchr(l, '\n') ? strchr(l, '\n') + 1 : l + strlen(l)) {
		size_t n = strcspn(l, "\n");
		const char *semi = memchr(l, ';', n);
		size_t code = semi ? (size_t)(semi - l) : n;
		const char *xw = memchr(l, 'X', code), *yw = memchr(l, 'Y', code);
		const char *ew = memchr(l, 'E', code), *fw = memchr(l, 'F', code);
		double nx = xw ? strtod(xw + 1, NULL) : x, ny = yw ? strtod(yw + 1, NULL) : y;

		if (!strncmp(l, ";LAYER_CHANGE", 13))
			at.layer++;
		if (!strncmp(l, ";TYPE:", 6)) {
			at.role = l + 6;
			at.role_len = n - 6;
		}
		if (strncmp(l, "G1 ", 3) && strncmp(l, "G0 ", 3))
			continue;
		if (fw)
			at.feed = strtod(fw + 1, NULL);
		if (nx != x || ny != y)
			fn(ctx, &at, x, y, nx, ny, ew ? strtod(ew + 1, NULL) : 0);
		x = nx;
		y = ny;
	}
}

/* The extruding XY moves of one ;TYPE: on one layer (0: on every one). */
struct role_moves {
	const char *role;
	int layer;
	double e, len; /* filament and path length, mm */
	double min_x;  /* smallest X the moves reach */
};

static void add_role_move(void *ctx, const struct move_at *at, double x0, double y0, double x1,
			  double y1, double e)
{
	struct role_moves *r = ctx;

	if (!at->role || at->role_len != strlen(r->role) ||
	    strncmp(at->role, r->role, at->role_len) || (r->layer && at->layer != r->layer) ||
	    e <= 0)
		return;
	r->e += e;
	r->len += hypot(x1 - x0, y1 - y0);
	r->min_x = fmin(r->min_x, fmin(x0, x1));
}

static struct role_moves moves_of(const char *text, const char *role, int layer)
{
	struct role_moves r = {role, layer, 0, 0, INFINITY};

	walk_moves(text, add_role_move, &r);
	ck_assert_msg(r.len > 0, "no %s extrusion on layer %d", role, layer);
	return r;
}

/* role's beads on layer are w wide at height h, within tol (a share). */
static void assert_width(const char *g, const char *role, int layer, double w, double h,
			 double tol)
{
	struct role_moves r = moves_of(g, role, layer);
	double want = e_per_mm(w, h), got = r.e / r.len;

	ck_assert_msg(fabs(got - want) < tol * want,
		      "%s on layer %d: %.5f mm of filament per mm, a %.3f mm bead wants %.5f", role,
		      layer, got, w, want);
}

/* role's moves on layer reach at most x_in mm inside the box's left face. */
static void assert_depth(const char *g, const char *role, int layer, double x_in)
{
	struct role_moves r = moves_of(g, role, layer);

	ck_assert_msg(fabs(r.min_x - (BOX_X0 + x_in)) < 0.002,
		      "%s on layer %d runs %.4f mm inside the surface, wanted %.4f", role, layer,
		      r.min_x - BOX_X0, x_in);
}

/* The key is honoured: not named in the warning. */
static void assert_not_warned(const char *key)
{
	char item[96];

	snprintf(item, sizeof(item), " %s=", key);
	ck_assert_msg(!strstr(out, item), "%s", out);
}

/* On layer (height h) the outer wall's beads are wo wide, their centre line
 * wo/2 inside the face, and the inner wall's wi wide, the mean of both
 * spacings further in. */
static void assert_walls(const char *g, int layer, double wo, double wi, double h)
{
	assert_width(g, "External perimeter", layer, wo, h, 0.005);
	assert_width(g, "Perimeter", layer, wi, h, 0.005);
	assert_depth(g, "External perimeter", layer, wo / 2);
	assert_depth(g, "Perimeter", layer, wo / 2 + (spacing(wo, h) + spacing(wi, h)) / 2);
}

/*
 * external_perimeter_extrusion_width sets the outer wall (0.6 mm), the
 * inner wall keeping the automatic 0.45 mm; perimeter_extrusion_width as a
 * percentage of layer_height (300% of 0.2: 0.6 mm) sets the inner walls,
 * the outer wall keeping extrusion_width (0.5), not the inner walls' width,
 * as PrusaSlicer's Flow does.
 */
START_TEST(wall_widths_honoured)
{
	static const struct {
		const char *args, *key;
		double wo, wi;
	} cases[] = {
	    {"--set external_perimeter_extrusion_width=0.6", "external_perimeter_extrusion_width",
	     0.6, 0.45},
	    {"--set extrusion_width=0.5 --set perimeter_extrusion_width=300%",
	     "perimeter_extrusion_width", 0.5, 0.6},
	};

	for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
		char *g = slice_box(cases[i].args);

		assert_not_warned(cases[i].key);
		assert_walls(g, 2, cases[i].wo, cases[i].wi, 0.2);
		free(g);
	}
}
END_TEST

/* first_layer_extrusion_width, a percentage of first_layer_height (240%
 * of 0.25: 0.6 mm, where 240% of layer_height would be 0.48), sets every
 * bead of the first layer, skirt included; the second layer keeps the
 * walls' 0.45 mm. */
START_TEST(first_layer_width_honoured)
{
	const double h1 = 0.25;
	char *g = slice_box("--set first_layer_height=0.25 --set first_layer_extrusion_width=240%");

	assert_not_warned("first_layer_extrusion_width");
	assert_walls(g, 1, 0.6, 0.6, h1);
	assert_width(g, "Skirt/Brim", 1, 0.6, h1, 0.005);
	/* solid lines are spaced so a whole number spans the island */
	assert_width(g, "Bottom solid infill", 1, 0.6, h1, 0.03);
	assert_walls(g, 2, 0.45, 0.45, 0.2);
	free(g);
}
END_TEST

/* With extrusion_width 0 (generic-marlin) every role's width is PrusaSlicer
 * 2.5's automatic one: the top skin the nozzle's 0.4 mm, the walls and the
 * other infill 1.125 x that; with extrusion_width set, that for all. */
START_TEST(automatic_widths_are_prusaslicers)
{
	char *g = slice_box("");

	assert_width(g, "Top solid infill", 15, 0.4, 0.2, 0.03);
	assert_walls(g, 2, 0.45, 0.45, 0.2);
	free(g);
	g = slice_box("--set extrusion_width=0.5");
	assert_width(g, "Top solid infill", 15, 0.5, 0.2, 0.03);
	free(g);
}
END_TEST

/* The most filament volume per second of an extrusion, mm^3/s; those of
 * the start G-code (its prime line is the profile's) left out. */
static void peak_move(void *ctx, const struct move_at *at, double x0, double y0, double x1,
		      double y1, double e)
{
	double *peak = ctx;

	if (at->role && e > 0)
		*peak = fmax(*peak, e / hypot(x1 - x0, y1 - y0) * M_PI * FILAMENT_D * FILAMENT_D /
					4 * at->feed / 60);
}

static double peak_volume_rate(const char *text)
{
	double peak = 0;

	walk_moves(text, peak_move, &peak);
	return peak;
}

/* filament_max_volumetric_speed and max_volumetric_speed cap every
 * extrusion's speed so its bead's cross-section times its speed stays
 * within the lower limit, and the cap binds (80 mm/s infill of 0.45 x 0.2
 * mm beads would be 6.5 mm^3/s). */
START_TEST(volumetric_speed_capped)
{
	static const char *const args[] = {
	    "--set cooling=0 --set filament_max_volumetric_speed=2",
	    "--set cooling=0 --set max_volumetric_speed=2 --set filament_max_volumetric_speed=3",
	};

	for (size_t i = 0; i < sizeof(args) / sizeof(args[0]); i++) {
		char *g = slice_box(args[i]);
		double peak = peak_volume_rate(g);

		assert_not_warned("filament_max_volumetric_speed");
		assert_not_warned("max_volumetric_speed");
		/* E is the flow model's to the printed digits (and the
		 * simplifier's stretch of at most a few per cent) */
		ck_assert_msg(peak <= 2.0 * 1.03 && peak >= 2.0 * 0.97,
			      "%s: peak %.3f mm^3/s, wanted 2", args[i], peak);
		free(g);
	}
}
END_TEST

/* thick_bridges = 0: the bridge's beads are the solid infill's (0.45 x
 * 0.2 mm here), their cross-section times bridge_flow_ratio; 1: round
 * threads of the nozzle's diameter (PrusaSlicer's two bridge flows). */
START_TEST(thick_bridges_honoured)
{
	const double fil = M_PI * FILAMENT_D * FILAMENT_D / 4;
	static const struct {
		const char *args;
		double ratio;
	} flat[] = {{"--set thick_bridges=0", 1.0},
		    {"--set thick_bridges=0 --set bridge_flow_ratio=0.8", 0.8}};
	char *g = slice_for(fx_bridge(), "--printer generic-marlin", "--set thick_bridges=1");
	struct role_moves r = moves_of(g, "Bridge infill", 0);
	double want = M_PI * 0.4 * 0.4 / 4 / fil;

	ck_assert_msg(fabs(r.e / r.len - want) < 0.01 * want, "thick: %.5f, wanted %.5f",
		      r.e / r.len, want);
	free(g);
	for (size_t i = 0; i < sizeof(flat) / sizeof(flat[0]); i++) {
		g = slice_for(fx_bridge(), "--printer generic-marlin", flat[i].args);
		assert_not_warned("thick_bridges");
		r = moves_of(g, "Bridge infill", 0);
		want = flat[i].ratio * e_per_mm(0.45, 0.2);
		ck_assert_msg(fabs(r.e / r.len - want) < 0.01 * want, "%s: %.5f, wanted %.5f",
			      flat[i].args, r.e / r.len, want);
		free(g);
	}
}
END_TEST

/* The feeds (mm/min) of every move of one ;TYPE: lie in [lo, hi], and the
 * X of their ends in [x0, x1]. */
struct role_span {
	const char *role;
	double lo, hi, x0, x1;
	size_t moves;
};

static void span_move(void *ctx, const struct move_at *at, double x0, double y0, double x1,
		      double y1, double e)
{
	struct role_span *r = ctx;

	(void)y0;
	(void)y1;
	if (!at->role || at->role_len != strlen(r->role) ||
	    strncmp(at->role, r->role, at->role_len) || e <= 0)
		return;
	r->lo = fmin(r->lo, at->feed);
	r->hi = fmax(r->hi, at->feed);
	r->x0 = fmin(r->x0, fmin(x0, x1));
	r->x1 = fmax(r->x1, fmax(x0, x1));
	r->moves++;
}

/* overhangs = 1: the walls' pieces over fx_bridge's 10 mm gap (x 5 to 15,
 * placed 95 to 105) print as Overhang perimeter, at bridge_speed with
 * bridge flow (a round thread of the nozzle's diameter); they start and
 * end within half a sample of where the pillars grown by half the nozzle
 * end (95.2 and 104.8); 0 (the default) prints no such piece. */
#define OVERHANG_HALF_STEP 0.05 /* mm, overhang.h's sample step / 2 */
START_TEST(overhangs_honoured)
{
	const double fil = M_PI * FILAMENT_D * FILAMENT_D / 4;
	char *g = slice_for(fx_bridge(), "--printer generic-marlin",
			    "--set cooling=0 --set overhangs=1 --set bridge_speed=17");
	struct role_span sp = {"Overhang perimeter", INFINITY, -INFINITY, INFINITY, -INFINITY, 0};
	struct role_moves r = moves_of(g, "Overhang perimeter", 0);
	double want = M_PI * 0.4 * 0.4 / 4 / fil;

	assert_not_warned("overhangs");
	walk_moves(g, span_move, &sp);
	ck_assert_msg(sp.moves > 0 && sp.lo == 17 * 60 && sp.hi == 17 * 60, "F%g to F%g", sp.lo,
		      sp.hi);
	ck_assert_msg(fabs(r.e / r.len - want) < 0.01 * want, "E/mm %.5f, wanted %.5f",
		      r.e / r.len, want);
	ck_assert_msg(fabs(sp.x0 - 95.2) <= OVERHANG_HALF_STEP &&
			      fabs(sp.x1 - 104.8) <= OVERHANG_HALF_STEP,
		      "overhang from X%g to X%g", sp.x0, sp.x1);
	free(g);
	g = slice_for(fx_bridge(), "--printer generic-marlin", "");
	ck_assert_msg(!strstr(g, ";TYPE:Overhang perimeter"), "overhangs off by default");
	free(g);
}
END_TEST

/* Where the extrusions of one ;TYPE: on one layer lie across their own
 * direction (mm, by the first move's), in printing order. */
struct across {
	const char *role;
	int layer;
	double dx, dy; /* the first move's direction, 0 until one is seen */
	size_t n;
	double v[4096];
};

static void across_move(void *ctx, const struct move_at *at, double x0, double y0, double x1,
			double y1, double e)
{
	struct across *a = ctx;
	double len = hypot(x1 - x0, y1 - y0);

	if (!at->role || at->role_len != strlen(a->role) ||
	    strncmp(at->role, a->role, at->role_len) || at->layer != a->layer || e <= 0 ||
	    len < 0.5 || a->n == sizeof(a->v) / sizeof(a->v[0]))
		return;
	if (a->dx == 0 && a->dy == 0) {
		a->dx = (x1 - x0) / len;
		a->dy = (y1 - y0) / len;
	}
	a->v[a->n++] = -a->dy * (x0 + x1) / 2 + a->dx * (y0 + y1) / 2;
}

/* Whether the lines are printed in one sweep (each no further back than a
 * tenth of a mm from the one before), and how many there are. */
static bool one_sweep(const char *g, int layer, size_t *n)
{
	static struct across a;
	bool up = true, down = true;

	memset(&a, 0, sizeof(a));
	a.role = "Top solid infill";
	a.layer = layer;
	walk_moves(g, across_move, &a);
	for (size_t k = 1; k < a.n; k++) {
		up = up && a.v[k] > a.v[k - 1] - 0.1;
		down = down && a.v[k] < a.v[k - 1] + 0.1;
	}
	*n = a.n;
	return up || down;
}

/* top_fill_pattern = monotonic: the top skin of an L-shaped plate is
 * printed in one sweep across it; rectilinear (nearest line first) is not
 * here, its arms printed one after the other. */
START_TEST(monotonic_top_skin)
{
	struct mesh *a = fx_box(0, 0, 0, 20, 6, 3), *b = fx_box(0, 0, 0, 6, 20, 3);
	struct mesh *l = fx_concat(a, b), *l2 = fx_concat(a, b);
	char *g = slice_for(l, "--printer generic-marlin", "--set top_fill_pattern=monotonic");
	size_t n;

	mesh_free(a);
	mesh_free(b);
	assert_not_warned("top_fill_pattern");
	ck_assert_msg(one_sweep(g, 15, &n) && n > 20, "monotonic: %zu lines", n);
	free(g);
	g = slice_for(l2, "--printer generic-marlin", "");
	ck_assert_msg(!one_sweep(g, 15, &n) && n > 20, "rectilinear: %zu lines in one sweep", n);
	free(g);
	g = slice_box("--set top_fill_pattern=concentric");
	ck_assert_msg(strstr(out, " top_fill_pattern=concentric (rectilinear used)"), "%s", out);
	free(g);
}
END_TEST

/* first_layer_extrusion_width sets support's beads on the bed and the
 * raft's first layer too (PrusaSlicer's first-layer support flow); the
 * layers above keep support's own (the nozzle's 0.4 mm here). */
START_TEST(first_layer_width_of_support_and_raft)
{
	static const char *const args[] = {
	    /* a bridge: supported only with dont_support_bridges = 0 */
	    "--set cooling=0 --set support_material=1 --set support_material_threshold=60 "
	    "--set dont_support_bridges=0 --set first_layer_extrusion_width=0.6",
	    "--set cooling=0 --set raft_layers=2 --set first_layer_extrusion_width=0.6"};

	for (size_t i = 0; i < sizeof(args) / sizeof(args[0]); i++) {
		char *g = slice_for(fx_bridge(), "--printer generic-marlin", args[i]);

		assert_width(g, "Support material", 1, 0.6, 0.2, 0.005);
		if (!i)
			assert_width(g, "Support material", 2, 0.4, 0.2, 0.005);
		free(g);
	}
}
END_TEST

/* The travels within Internal infill runs, and its extrusions. */
struct infill_runs {
	size_t travels, moves;
};

static void count_infill(void *ctx, const struct move_at *at, double x0, double y0, double x1,
			 double y1, double e)
{
	struct infill_runs *r = ctx;

	(void)x0, (void)y0, (void)x1, (void)y1;
	if (!at->role || at->role_len != 15 || strncmp(at->role, "Internal infill", 15))
		return;
	if (e > 0)
		r->moves++;
	else
		r->travels++;
}

/* infill_anchor_max joins the sparse lines' ends along the boundary (the
 * MK3S preset's 12 mm, anchors of 2.5 mm): a box's rectilinear infill is a
 * few paths a layer instead of one per line; 0 (the default) joins none,
 * and every pattern that joins slices. */
START_TEST(infill_anchors_join_lines)
{
	static const char *const patterns[] = {"grid", "gyroid", "honeycomb", "cubic"};
	struct infill_runs plain = {0}, joined = {0};
	char *g = slice_box("--set fill_pattern=rectilinear");
	char args[256];

	walk_moves(g, count_infill, &plain);
	free(g);
	g = slice_box("--set fill_pattern=rectilinear --set infill_anchor_max=12 "
		      "--set infill_anchor=2.5");
	assert_not_warned("infill_anchor_max");
	assert_not_warned("infill_anchor");
	walk_moves(g, count_infill, &joined);
	free(g);
	ck_assert_msg(plain.travels > 3 * joined.travels && joined.moves > plain.moves,
		      "travels %zu joined against %zu, moves %zu against %zu", joined.travels,
		      plain.travels, joined.moves, plain.moves);
	for (size_t i = 0; i < sizeof(patterns) / sizeof(patterns[0]); i++) {
		snprintf(args, sizeof(args), "--set fill_pattern=%s --set infill_anchor_max=50",
			 patterns[i]);
		free(slice_box(args));
	}
}
END_TEST

/* The per-role keys at the width they fall back to print the same file as
 * without them (the walls' offsets are computed so, to the last bit). */
START_TEST(role_widths_at_their_fallback_change_nothing)
{
	char *plain = slice_box("--set extrusion_width=0.5");
	char *same = slice_box("--set extrusion_width=0.5 --set perimeter_extrusion_width=0.5 "
			       "--set external_perimeter_extrusion_width=0.5 "
			       "--set first_layer_extrusion_width=0");

	ck_assert_msg(!strcmp(plain, same), "the G-code changed");
	free(plain);
	free(same);
}
END_TEST

/* The bundled MK3S and Ender-3 presets (PrusaSlicer 2.5's vendor bundles,
 * where installed) slice with every key honoured: no warning. */
START_TEST(bundled_presets_warn_only_unprinted_keys)
{
	static const struct {
		const char *bundle, *preset, *warning; /* NULL: no warning */
	} cases[] = {
	    {"PrusaResearch.ini", "Original Prusa i3 MK3S & MK3S+", NULL},
	    {"Creality.ini", "Creality Ender-3 (0.4 mm nozzle)", NULL},
	};
	const char *dir = "/usr/share/PrusaSlicer/profiles";

	for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
		char printer[1024], path[512];

		snprintf(path, sizeof(path), "%s/%s", dir, cases[i].bundle);
		if (access(path, R_OK)) {
			fprintf(stderr, "slicecli: %s not installed, its presets not sliced\n", path);
			continue;
		}
		snprintf(printer, sizeof(printer), "--load '%s' --printer-preset '%s'", path,
			 cases[i].preset);
		free(slice_for(fx_box(0, 0, 0, 20, 20, 3), printer, ""));
		if (cases[i].warning)
			ck_assert_msg(strstr(out, cases[i].warning), "%s: %s", cases[i].preset, out);
		else
			ck_assert_msg(!strstr(out, "not supported"), "%s: %s", cases[i].preset, out);
	}
}
END_TEST

void slicecli_widths_tcases(Suite *s)
{
	TCase *tc = tcase_create("widths");

	tcase_set_timeout(tc, 120);
	tcase_add_test(tc, wall_widths_honoured);
	tcase_add_test(tc, first_layer_width_honoured);
	tcase_add_test(tc, automatic_widths_are_prusaslicers);
	tcase_add_test(tc, volumetric_speed_capped);
	tcase_add_test(tc, thick_bridges_honoured);
	tcase_add_test(tc, overhangs_honoured);
	tcase_add_test(tc, monotonic_top_skin);
	tcase_add_test(tc, first_layer_width_of_support_and_raft);
	tcase_add_test(tc, infill_anchors_join_lines);
	tcase_add_test(tc, bundled_presets_warn_only_unprinted_keys);
	tcase_add_test(tc, role_widths_at_their_fallback_change_nothing);
	suite_add_tcase(s, tc);
}
