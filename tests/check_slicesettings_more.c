/*
 * check_slicesettings_more.c - more print settings honoured end to end, part
 * of the slicecli suite (check_slicesettings.c, the same "settings" case):
 * elephant foot compensation, wall order and fill angle, infill and support
 * widths, the fan ramp, small perimeters, infill overlap and bridge flow,
 * profile keys that reach the slicer, retraction before a wipe, and silent
 * mode.
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fixtures.h"
#include "meshio.h"
#include "profile_slicer.h"
#include "sliceclitest.h"
#include "suites.h"
#include "testutil.h"

/* The text after the n-th ;LAYER_CHANGE line's start (n >= 1), or NULL. */
static char *layer_start(char *text, int n)
{
	char *l = text;

	for (int k = 0; k < n && l; k++)
		l = strstr(l + 1, "\n;LAYER_CHANGE");
	return l;
}

START_TEST(elefant_foot_compensation_honoured)
{
	char model[4096];
	double x1, x2;
	char *g, *second;

	model_file(fx_box(0, 0, 0, 20, 20, 2), "efcube.stl", model, sizeof(model));
	g = slice(model, "--set elefant_foot_compensation=0.3");
	second = layer_start(g, 2);
	ck_assert_ptr_nonnull(second);
	ck_assert_int_gt(role_layers(second, "External perimeter", &x2), 0);
	*second = '\0';
	ck_assert_int_eq(role_layers(g, "External perimeter", &x1), 1);
	/* The part spans x 90..110; its outer wall's centre line lies half a
	 * bead inside, on the first layer 0.3 mm further in. */
	ck_assert_msg(fabs(x1 - x2 - 0.3) < 1e-3, "first layer x %g, above %g", x1, x2);
	free(g);
	ck_assert_msg(!strstr(slice_out, "elefant_foot_compensation="), "%s", slice_out);

	/* A wall too thin to shrink keeps its first layer. */
	model_file(fx_box(0, 0, 0, 20, 0.5, 2), "efwall.stl", model, sizeof(model));
	g = slice(model, "--set elefant_foot_compensation=0.3");
	second = layer_start(g, 2);
	ck_assert_ptr_nonnull(second);
	*second = '\0';
	long printed = 0;
	for (const char *l = layer_start(g, 1); l && (l = strstr(l + 1, "\nG1 ")) != NULL;) {
		size_t n = strcspn(l + 1, "\n");
		const char *e = memchr(l + 1, 'E', n);
		printed += e && strtod(e + 1, NULL) > 0 && (memchr(l + 1, 'X', n) || memchr(l + 1, 'Y', n));
	}
	ck_assert_msg(printed > 0, "the first layer prints");
	free(g);
}
END_TEST

/* Extrusion moves of role whose direction is (not) axis-aligned. */
static void axis_moves(const char *text, const char *role, long *aligned, long *other)
{
	double x = 0, y = 0;
	bool in_role = false;
	char mark[128];

	snprintf(mark, sizeof(mark), ";TYPE:%s\n", role);
	*aligned = *other = 0;
	for (const char *l = text; *l; l = strchr(l, '\n') ? strchr(l, '\n') + 1 : l + strlen(l)) {
		size_t n = strcspn(l, "\n");
		const char *xw = memchr(l, 'X', n), *yw = memchr(l, 'Y', n), *ew = memchr(l, 'E', n);
		double nx = xw ? strtod(xw + 1, NULL) : x, ny = yw ? strtod(yw + 1, NULL) : y;

		if (!strncmp(l, ";TYPE:", 6))
			in_role = !strncmp(l, mark, strlen(mark));
		if (strncmp(l, "G1 ", 3))
			continue;
		if (in_role && ew && strtod(ew + 1, NULL) > 0 && (xw || yw)) {
			if (fabs(nx - x) < 1e-3 || fabs(ny - y) < 1e-3)
				++*aligned;
			else
				++*other;
		}
		x = nx;
		y = ny;
	}
}

START_TEST(wall_order_and_fill_angle_honoured)
{
	char model[4096];
	long aligned, other;
	char *g, *l2;

	model_file(fx_box(0, 0, 0, 20, 20, 3), "wallcube.stl", model, sizeof(model));
	g = slice(model, "--set external_perimeters_first=1 --set fill_angle=0");
	l2 = layer_start(g, 5);
	ck_assert_ptr_nonnull(l2);
	ck_assert_msg(strstr(l2, ";TYPE:External perimeter") < strstr(l2, ";TYPE:Perimeter"),
		      "outer wall first");
	axis_moves(g, "Internal infill", &aligned, &other);
	ck_assert_msg(aligned > 0 && other == 0, "fill_angle 0: %ld along the axes, %ld not",
		      aligned, other);
	free(g);
	ck_assert_msg(!strstr(slice_out, "fill_angle=") &&
			  !strstr(slice_out, "external_perimeters_first="),
		      "%s", slice_out);
	g = slice(model, "");
	l2 = layer_start(g, 5);
	ck_assert_ptr_nonnull(l2);
	ck_assert_msg(strstr(l2, ";TYPE:Perimeter") < strstr(l2, ";TYPE:External perimeter"),
		      "inner walls first by default");
	axis_moves(g, "Internal infill", &aligned, &other);
	ck_assert_msg(other > aligned, "fill_angle 45: %ld along the axes, %ld not", aligned, other);
	free(g);
}
END_TEST

/* Per-role infill widths: mm, or a percentage of layer_height (0.2). */
START_TEST(infill_widths_honoured)
{
	char model[4096];
	char *g;

	model_file(fx_box(0, 0, 0, 20, 20, 3), "widthcube.stl", model, sizeof(model));
	g = slice(model, "--set infill_extrusion_width=0.6 --set solid_infill_extrusion_width=0.5 "
			 "--set top_infill_extrusion_width=200%");
	assert_header(g, "extrusion width (Internal infill) = 0.6 mm");
	assert_header(g, "extrusion width (Bottom solid infill) = 0.5 mm");
	assert_header(g, "extrusion width (Top solid infill) = 0.4 mm");
	assert_header(g, "extrusion width (Perimeter) = 0.45 mm");
	free(g);
	ck_assert_msg(!strstr(slice_out, "infill_extrusion_width="), "%s", slice_out);
}
END_TEST

/* E per mm of XY of the extrusions whose ;TYPE: starts with "Support
 * material" (support and its interface, the raft's lines), relative E. */
static double support_e_per_mm(const char *text)
{
	double x = 0, y = 0, e = 0, len = 0;
	bool in_support = false;

	for (const char *l = text; *l; l = strchr(l, '\n') ? strchr(l, '\n') + 1 : l + strlen(l)) {
		size_t n = strcspn(l, "\n");
		const char *xw = memchr(l, 'X', n), *yw = memchr(l, 'Y', n), *ew = memchr(l, 'E', n);
		const char *semi = memchr(l, ';', n);
		double nx = x, ny = y;

		if (!strncmp(l, ";TYPE:", 6))
			in_support = !strncmp(l + 6, "Support material", 16);
		if (strncmp(l, "G1 ", 3) && strncmp(l, "G0 ", 3))
			continue;
		if (xw && (!semi || xw < semi))
			nx = strtod(xw + 1, NULL);
		if (yw && (!semi || yw < semi))
			ny = strtod(yw + 1, NULL);
		if (in_support && ew && (!semi || ew < semi) && strtod(ew + 1, NULL) > 0 &&
		    (nx != x || ny != y)) {
			e += strtod(ew + 1, NULL);
			len += hypot(nx - x, ny - y);
		}
		x = nx;
		y = ny;
	}
	ck_assert_msg(len > 0, "no support or raft extrusion");
	return e / len;
}

/* support_material_extrusion_width sets the beads of support and of the
 * raft (PrusaSlicer prints the raft with support's width): more E per mm
 * at 0.7 mm than at the automatic 0.4 (the nozzle's, PrusaSlicer's Flow
 * with extrusion_width 0), in the ratio of the beads' cross-sections
 * (PrusaSlicer's flow: (w - h) h + pi h^2 / 4). */
START_TEST(support_width_honoured)
{
	char model[4096];
	/* the model is a bridge: supported only with dont_support_bridges = 0 */
	const char *with[2] = {STEADY "--set support_material=1 --set support_material_threshold=60 "
				      "--set dont_support_bridges=0 ",
			       STEADY "--set raft_layers=2 "};
	const double h = 0.2;
	double want = ((0.7 - h) * h + M_PI * h * h / 4) / ((0.4 - h) * h + M_PI * h * h / 4);

	model_file(wide_bridge(), "supportwidth.stl", model, sizeof(model));
	for (int i = 0; i < 2; i++) {
		char args[512];
		char *g = slice(model, with[i]);
		double base = support_e_per_mm(g);

		free(g);
		snprintf(args, sizeof(args), "%s--set support_material_extrusion_width=0.7", with[i]);
		g = slice(model, args);
		ck_assert_msg(!strstr(slice_out, "support_material_extrusion_width="), "%s",
			      slice_out);
		double wide = support_e_per_mm(g);

		if (i == 0) {
			assert_header(g, "extrusion width (Support material) = 0.7 mm");
			/* support alone: every bead 0.2 mm high but the first layer's */
			ck_assert_msg(fabs(wide / base - want) < 0.05 * want,
				      "support E/mm %g at 0.7 mm, %g at 0.4 (ratio %g, wanted %g)",
				      wide, base, wide / base, want);
		} else {
			/* the raft's upper layers are 0.3 mm high: a smaller ratio, still
			 * well above 1 */
			ck_assert_msg(wide / base > 1.2, "raft E/mm %g at 0.7 mm, %g at 0.4", wide,
				      base);
		}
		free(g);
	}
}
END_TEST

/* full_fan_speed_layer ramps the fan up as PrusaSlicer 2.5 does: from
 * disable_fan_first_layers (1: fan from layer 2) to full on layer 5. */
START_TEST(fan_ramp_honoured)
{
	static const char *const want[] = {"M106 S64\n", "M106 S128\n", "M106 S191\n", "M106 S255\n"};
	char model[4096];
	char *g;

	model_file(fx_box(0, 0, 0, 20, 20, 3), "rampcube.stl", model, sizeof(model));
	g = slice(model, "--set disable_fan_first_layers=1 --set full_fan_speed_layer=5 "
			 "--set fan_below_layer_time=1000 --set slowdown_below_layer_time=0 "
			 "--set min_fan_speed=100");
	for (int k = 0; k < 4; k++) {
		char *at = strstr(layer_start(g, k + 2), want[k]);
		ck_assert_msg(at && at < layer_start(g, k + 3), "layer %d: no %s", k + 2, want[k]);
	}
	ck_assert_int_eq(count_before_layer(g, "M106", 2), 0);
	assert_header(g, "full_fan_speed_layer = 5");
	free(g);
	ck_assert_msg(!strstr(slice_out, "full_fan_speed_layer="), "%s", slice_out);
}
END_TEST

/* Closed walls at most 2 pi 6.5 mm long print at small_perimeter_speed (a
 * percentage of perimeter_speed), as in PrusaSlicer; longer ones do not. */
START_TEST(small_perimeter_speed_honoured)
{
	char model[4096];
	char *g;

	model_file(fx_box(0, 0, 0, 8, 8, 2), "smallbox.stl", model, sizeof(model));
	g = slice(model, STEADY "--set perimeter_speed=40 --set small_perimeter_speed=50%");
	assert_feed(g, "External perimeter", false, 20 * 60);
	assert_feed(g, "Perimeter", false, 20 * 60);
	assert_header(g, "small_perimeter_speed = 20");
	free(g);
	model_file(fx_box(0, 0, 0, 16, 16, 2), "bigbox.stl", model, sizeof(model));
	g = slice(model, STEADY "--set perimeter_speed=40 --set small_perimeter_speed=50%");
	assert_feed(g, "Perimeter", false, 40 * 60);
	free(g);
}
END_TEST

/* The smallest X the extrusions of role reach, over the whole print. */
static double role_min_x(const char *text, const char *role)
{
	double x;

	role_layers(text, role, &x);
	return x;
}

/* infill_overlap (mm, or % of extrusion_width 0.45) moves the infill's
 * ends into the innermost wall; bridge_flow_ratio thins the bridge thread. */
START_TEST(infill_overlap_and_bridge_flow_honoured)
{
	char model[4096];
	double x0, x1, x2;
	char *g;
	const char *bw;

	model_file(fx_box(0, 0, 0, 20, 20, 3), "ovcube.stl", model, sizeof(model));
	g = slice(model, "--set infill_overlap=0");
	x0 = role_min_x(g, "Internal infill");
	free(g);
	g = slice(model, "--set infill_overlap=0.3");
	x1 = role_min_x(g, "Internal infill");
	free(g);
	g = slice(model, "--set infill_overlap=50%");
	x2 = role_min_x(g, "Internal infill");
	free(g);
	ck_assert_msg(fabs(x0 - x1 - 0.3) < 0.01 && fabs(x0 - x2 - 0.225) < 0.01,
		      "infill reaches x %g, %g, %g", x0, x1, x2);
	ck_assert_msg(!strstr(slice_out, "infill_overlap="), "%s", slice_out);

	model_file(wide_bridge(), "flowbridge.stl", model, sizeof(model));
	g = slice(model, "--set bridge_flow_ratio=1");
	bw = strstr(g, "; extrusion width (Bridge infill) = ");
	ck_assert_ptr_nonnull(bw);
	double w1 = strtod(bw + 36, NULL);
	free(g);
	g = slice(model, "--set bridge_flow_ratio=0.5");
	bw = strstr(g, "; extrusion width (Bridge infill) = ");
	ck_assert_ptr_nonnull(bw);
	/* Half the thread's cross-section; the header gives the bead width of
	 * the same flow, (w - h) h + pi h^2 / 4 with h = 0.2. */
	double w2 = strtod(bw + 36, NULL), h = 0.2;
	double a1 = (w1 - h) * h + M_PI * h * h / 4, a2 = (w2 - h) * h + M_PI * h * h / 4;
	ck_assert_msg(fabs(a2 / a1 - 0.5) < 0.02, "bridge width %g, was %g", w2, w1);
	free(g);
	ck_assert_msg(!strstr(slice_out, "bridge_flow_ratio="), "%s", slice_out);
}
END_TEST

/* The slicer's settings of profile text (asserted to load); free the
 * profile returned. */
static struct profile *config_of(const char *text, struct slicer_config *c)
{
	struct st_error err = {0};
	struct profile *p = NULL;

	ck_assert_msg(!profile_load_buffer(text, strlen(text), "bound.ini", &p, &err), "%s",
		      err.msg);
	ck_assert_msg(!profile_slicer_config(p, c, &err), "%s", err.msg);
	return p;
}

/*
 * Keys copied into the slicer's fields as the profile holds them
 * (host/profile_bind.c) land in the field each is bound to, of each kind:
 * a whole number into an int and into a double, a per-extruder value,
 * a renamed bool, a choice, a first-of-list string, the bed's height.
 */
START_TEST(profile_keys_reach_slicer_fields)
{
	static const char text[] = "temperature = 213\n"
				   "fan_below_layer_time = 37\n"
				   "support_material_threshold = 33\n"
				   "external_perimeters_first = 1\n"
				   "ironing_type = topmost\n"
				   "start_filament_gcode = \"M117 a\";\"M117 b\"\n"
				   "max_print_height = 123.5\n"
				   "raft_first_layer_density = 70%\n"
				   "layer_height = 0.15\n"
				   "gcode_resolution = 0.02\n"
				   "remaining_times = 1\n"
				   "retract_layer_change = 1\n"
				   "retract_lift_below = 209\n"
				   "retract_lift_above = 0.6\n"
				   "retract_before_wipe = 70%\n"
				   "bridge_acceleration = 1234\n";
	struct slicer_config c;
	struct profile *p = config_of(text, &c);

	ck_assert_int_eq(c.gcodew.temperature, 213);
	ck_assert_double_eq(c.gcodew.fan_below_layer_time, 37);
	ck_assert_int_eq(c.support.threshold, 33);
	ck_assert(c.perim.outer_first);
	ck_assert_str_eq(c.gcodew.ironing_type, "topmost");
	ck_assert_str_eq(c.gcodew.start_filament_gcode, "M117 a");
	ck_assert_double_eq(c.bed.max_height, 123.5);
	ck_assert_double_eq(c.raft.first_layer_density, 70);
	ck_assert_double_eq(c.layer_height, 0.15);
	ck_assert_double_eq(c.gcodew.gcode_resolution, 0.02);
	ck_assert(c.gcodew.remaining_times);
	ck_assert(c.gcodew.retract_layer_change);
	ck_assert_double_eq(c.gcodew.retract_lift_below, 209);
	ck_assert_double_eq(c.gcodew.retract_lift_above, 0.6);
	ck_assert_double_eq(c.gcodew.retract_before_wipe, 70);
	ck_assert_double_eq(c.gcodew.bridge_acceleration, 1234);
	ck_assert_int_eq(c.gcodew.accel_form, GCODEW_ACCEL_M204_S);
	ck_assert(c.gcodew.remaining_times_silent); /* silent_mode's default, marlin2 */
	profile_free(p);
}
END_TEST

/* retract_before_wipe is per extruder in PrusaSlicer: a list loads, its
 * first value used (the MMU bundles write 0%,0%,0%,0%). */
START_TEST(retract_before_wipe_list)
{
	struct slicer_config c;
	struct profile *p =
	    config_of("nozzle_diameter = 0.4,0.4\nretract_before_wipe = 30%,0%\n", &c);

	ck_assert_double_eq(c.gcodew.retract_before_wipe, 30);
	profile_free(p);
}
END_TEST

/* wall_transition_length is a length or a percentage of the nozzle, 100 %
 * by default as PrusaSlicer's; wall_transition_angle in degrees. */
START_TEST(wall_transition_keys)
{
	struct slicer_config c;
	struct profile *p = config_of("nozzle_diameter = 0.6\n", &c);

	ck_assert_double_eq_tol(c.perim.transition_length, 0.6, 1e-12);
	ck_assert_double_eq(c.perim.transition_angle, 10);
	profile_free(p);
	p = config_of("nozzle_diameter = 0.4\nwall_transition_length = 50%\n"
		      "wall_transition_angle = 20\n",
		      &c);
	ck_assert_double_eq_tol(c.perim.transition_length, 0.2, 1e-12);
	ck_assert_double_eq(c.perim.transition_angle, 20);
	profile_free(p);
	p = config_of("wall_transition_length = 0\n", &c);
	ck_assert_double_eq(c.perim.transition_length, 0);
	profile_free(p);
}
END_TEST

/* M73 Q S for silent_mode with a marlin flavour only, as PrusaSlicer. */
START_TEST(silent_mode_needs_marlin)
{
	static const char *const texts[] = {"gcode_flavor = marlin\nsilent_mode = 1\n",
					    "gcode_flavor = marlin2\nsilent_mode = 0\n",
					    "gcode_flavor = klipper\nsilent_mode = 1\n"};
	static const bool silent[] = {true, false, false};

	for (size_t i = 0; i < sizeof(texts) / sizeof(texts[0]); i++) {
		struct slicer_config c;
		struct profile *p = config_of(texts[i], &c);

		ck_assert_msg(c.gcodew.remaining_times_silent == silent[i], "%s", texts[i]);
		profile_free(p);
	}
}
END_TEST

/* The tests of the "settings" case after the seam's, in their place. */
void slicecli_settings_more_tests(TCase *tc)
{
	tcase_add_test(tc, elefant_foot_compensation_honoured);
	tcase_add_test(tc, wall_order_and_fill_angle_honoured);
	tcase_add_test(tc, infill_widths_honoured);
	tcase_add_test(tc, support_width_honoured);
	tcase_add_test(tc, fan_ramp_honoured);
	tcase_add_test(tc, small_perimeter_speed_honoured);
	tcase_add_test(tc, infill_overlap_and_bridge_flow_honoured);
	tcase_add_test(tc, profile_keys_reach_slicer_fields);
	tcase_add_test(tc, silent_mode_needs_marlin);
	tcase_add_test(tc, retract_before_wipe_list);
	tcase_add_test(tc, wall_transition_keys);
}
