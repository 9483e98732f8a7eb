/*
 * check_slicesettings.c - the print settings users set, honoured end to end
 * (issue 18 item 4; part of the slicecli suite): `stratum slice` with
 * --set, its G-code read back for the feed rate of every extrusion by
 * role and layer, the fan commands, and the header's values (more settings:
 * check_slicesettings_more.c; the shared readers: sliceclitest.c).
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

START_TEST(role_speeds_honoured)
{
	char model[4096];
	char *g;

	model_file(wide_bridge(), "bridge.stl", model, sizeof(model));
	g = slice(model, STEADY "--set perimeter_speed=40 --set external_perimeter_speed=25 "
			  "--set infill_speed=70 --set solid_infill_speed=33 "
			  "--set top_solid_infill_speed=19 --set bridge_speed=17 "
			  "--set support_material_speed=37 --set first_layer_speed=23 "
			  "--set travel_speed_z=7");
	assert_feed(g, "External perimeter", false, 25 * 60);
	assert_feed(g, "Solid infill", false, 33 * 60);
	assert_feed(g, "Perimeter", false, 40 * 60);
	assert_feed(g, "Internal infill", false, 70 * 60);
	assert_feed(g, "Top solid infill", false, 19 * 60);
	assert_feed(g, "Bridge infill", false, 17 * 60);
	/* An absolute first-layer speed replaces every role's there. */
	assert_feed(g, "External perimeter", true, 23 * 60);
	assert_feed(g, "Skirt/Brim", true, 23 * 60);
	assert_feed(g, "Bottom solid infill", true, 23 * 60);
	ck_assert_msg(strstr(g, "Z10.2 F420\n"), "Z moves at travel_speed_z");
	assert_header(g, "external_perimeter_speed = 25");
	assert_header(g, "solid_infill_speed = 33");
	assert_header(g, "top_solid_infill_speed = 19");
	assert_header(g, "bridge_speed = 17");
	assert_header(g, "travel_speed_z = 7");
	free(g);
}
END_TEST

/* A 2 mm strip with three walls asked: no room for the third, so the
 * middle is gap fill (tests/check_slicer.c), at gap_fill_speed. */
START_TEST(gap_fill_speed_honoured)
{
	char model[4096];
	char *g;

	model_file(fx_box(0, 0, 0, 20, 2, 1), "strip.stl", model, sizeof(model));
	g = slice(model, STEADY "--set perimeters=3 --set gap_fill_speed=13");
	assert_feed(g, "Gap fill", false, 13 * 60);
	assert_header(g, "gap_fill_speed = 13");
	free(g);
}
END_TEST

/* Support under the bridge's deck at support_material_speed, its interface
 * at support_material_interface_speed (a percentage of it, as in PrusaSlicer). */
START_TEST(support_speeds_honoured)
{
	char model[4096];
	char *g;

	model_file(wide_bridge(), "bridge.stl", model, sizeof(model));
	/* the model is a bridge: supported only with dont_support_bridges = 0 */
	g = slice(model, STEADY "--set support_material=1 --set dont_support_bridges=0 "
			  "--set support_material_speed=37 "
			  "--set support_material_interface_speed=50% "
			  "--set support_material_interface_layers=2");
	assert_feed(g, "Support material", false, 37 * 60);
	assert_feed(g, "Support material interface", false, 18.5 * 60);
	free(g);
}
END_TEST

/* The header lists the slicer's own settings as printed: a per-job
 * override, a pattern Stratum does not print as the rectilinear it prints,
 * a spiral vase's one wall and no infill. */
START_TEST(header_lists_slicing_settings)
{
	char model[4096];
	char *g;

	model_file(fx_box(0, 0, 0, 20, 20, 4), "hdrbox.stl", model, sizeof(model));
	g = slice(model, "--perimeters 4 --fill-density 25% --set fill_pattern=lightning "
			 "--brim-width 3 --support-material --set seam_position=rear "
			 "--set skirts=2 --set elefant_foot_compensation=0.2");
	assert_header(g, "perimeters = 4");
	assert_header(g, "fill_density = 25%");
	assert_header(g, "fill_pattern = rectilinear");
	assert_header(g, "brim_width = 3");
	assert_header(g, "support_material = 1");
	assert_header(g, "seam_position = rear");
	assert_header(g, "skirts = 2");
	assert_header(g, "elefant_foot_compensation = 0.2");
	free(g);
	g = slice(model, "--set spiral_vase=1 --perimeters 3 --fill-density 40%");
	assert_header(g, "perimeters = 1");
	assert_header(g, "top_solid_layers = 0");
	assert_header(g, "fill_density = 0%");
	free(g);
}
END_TEST

/* Percentages, PrusaSlicer's way: each of its own base key, and the
 * first layer's of each role's own speed. */
START_TEST(speed_percentages_resolved)
{
	char model[4096];
	char *g;

	model_file(wide_bridge(), "bridge.stl", model, sizeof(model));
	g = slice(model, STEADY "--set perimeter_speed=40 --set external_perimeter_speed=50% "
			  "--set infill_speed=70 --set solid_infill_speed=60% "
			  "--set top_solid_infill_speed=50% --set support_material_speed=37 "
			  "--set first_layer_speed=50%");
	assert_feed(g, "External perimeter", false, 20 * 60);
	assert_feed(g, "Top solid infill", false, 21 * 60); /* 50% of 60% of 70 */
	assert_feed(g, "External perimeter", true, 10 * 60);
	assert_feed(g, "Perimeter", true, 20 * 60);
	/* Skirt and brim print at support_material_speed, as in PrusaSlicer. */
	assert_feed(g, "Skirt/Brim", true, 18.5 * 60);
	/* The header lists what was printed with, the percentage resolved. */
	assert_header(g, "external_perimeter_speed = 20");
	assert_header(g, "solid_infill_speed = 42");
	assert_header(g, "top_solid_infill_speed = 21");
	assert_header(g, "first_layer_speed = 50%");
	free(g);
	/* Honoured keys are not named in the warning of unsupported ones. */
	ck_assert_msg(!strstr(slice_out, "external_perimeter_speed="), "%s", slice_out);
}
END_TEST

/* Every layer here takes longer than fan_below_layer_time, so the fan is
 * off unless fan_always_on keeps it at min_fan_speed; never on the
 * disable_fan_first_layers first layers. */
#define LONG_LAYERS "--set fan_below_layer_time=1 --set slowdown_below_layer_time=0 "

START_TEST(fan_always_on_honoured)
{
	char model[4096];
	char *g;

	model_file(fx_box(0, 0, 0, 20, 20, 3), "fancube.stl", model, sizeof(model));
	g = slice(model, LONG_LAYERS "--set min_fan_speed=40 --set disable_fan_first_layers=2 "
				     "--set fan_always_on=1");
	ck_assert_int_eq(count_before_layer(g, "M106", 2), 0);
	ck_assert_int_eq(count_before_layer(g, "M106 S102\n", 0), 1); /* 40% of 255 */
	ck_assert_int_eq(count_before_layer(g, "M106", 0), 1);
	assert_header(g, "fan_always_on = 1");
	free(g);
	ck_assert_msg(!strstr(slice_out, "fan_always_on="), "%s", slice_out);

	g = slice(model, LONG_LAYERS "--set min_fan_speed=40 --set fan_always_on=0");
	ck_assert_int_eq(count_before_layer(g, "M106", 0), 0);
	free(g);
}
END_TEST

/* The Creator Pro's part fan is M126/M127, as PrusaSlicer writes it for
 * sailfish and makerware (their M106 is the extruder's heatsink fan). */
START_TEST(sailfish_fan_is_m126)
{
	char model[4096], gc[4096];
	char *g;
	size_t len;
	int status;

	model_file(fx_box(0, 0, 0, 20, 20, 3), "ffcube.stl", model, sizeof(model));
	snprintf(gc, sizeof(gc), "%s", tu_path("ff.gcode"));
	status = tu_run(slice_out, sizeof(slice_out),
			"slice '%s' -o '%s' --printer flashforge-creator-pro " LONG_LAYERS
			"--set fan_always_on=1 --set disable_fan_first_layers=1",
			model, gc);
	ck_assert_msg(status == 0, "exit %d: %s", status, slice_out);
	g = tu_slurp(gc, &len);
	ck_assert_int_eq(count_before_layer(g, "M126", 1), 0);
	ck_assert_int_ge(count_before_layer(g, "M126", 0), 1);
	ck_assert_int_eq(count_before_layer(g, "M106", 0), 0);
	ck_assert_int_eq(count_before_layer(g, "M107", 0), 0);
	free(g);
}
END_TEST

START_TEST(skirt_settings_honoured)
{
	char model[4096];
	double x;
	char *g;

	/* generic-marlin's bed is 200 x 200: the part spans x 90..110. */
	model_file(fx_box(0, 0, 0, 20, 20, 3), "skirtcube.stl", model, sizeof(model));
	g = slice(model, "--set skirts=1 --set skirt_distance=10 --set skirt_height=3");
	ck_assert_int_eq(role_layers(g, "Skirt/Brim", &x), 3);
	/* A centre line 10 mm + half a bead outside the part: x 79.5..80. */
	ck_assert_msg(x > 90 - 10.5 && x < 90 - 10, "skirt reaches x = %g", x);
	free(g);
	ck_assert_msg(!strstr(slice_out, "skirt_distance=") && !strstr(slice_out, "skirt_height="),
		      "%s", slice_out);
	g = slice(model, "--set skirts=2 --set skirt_height=0");
	ck_assert_int_eq(role_layers(g, "Skirt/Brim", &x), 0);
	free(g);
	/* min_skirt_length adds loops until the skirt uses that much filament. */
	g = slice(model, "--set skirts=1");
	long one = role_feeds(g, "Skirt/Brim", true).moves;
	free(g);
	g = slice(model, "--set skirts=1 --set min_skirt_length=20");
	ck_assert_int_gt(role_feeds(g, "Skirt/Brim", true).moves, 3 * one);
	free(g);
	ck_assert_msg(!strstr(slice_out, "min_skirt_length="), "%s", slice_out);
}
END_TEST

/* A small island's infill is solid below solid_infill_below_area. */
START_TEST(solid_infill_below_area_honoured)
{
	char model[4096];
	double x;
	char *g;

	model_file(fx_box(0, 0, 0, 8, 8, 4), "small.stl", model, sizeof(model));
	g = slice(model, "--set solid_infill_below_area=70");
	ck_assert_int_eq(role_layers(g, "Internal infill", &x), 0);
	free(g);
	g = slice(model, "--set solid_infill_below_area=0");
	ck_assert_int_gt(role_layers(g, "Internal infill", &x), 0);
	free(g);
	ck_assert_msg(!strstr(slice_out, "solid_infill_below_area="), "%s", slice_out);
}
END_TEST

/* External perimeter loops in text, and how many start at their rearmost
 * point (largest Y of the loop, within 1 um). */
static int rear_seams(const char *text, int *loops)
{
	double y = 0, start_y = 0, max_y = -INFINITY;
	bool in_loop = false;
	int rear = 0;

	*loops = 0;
	for (const char *l = text; *l; l = strchr(l, '\n') ? strchr(l, '\n') + 1 : l + strlen(l)) {
		size_t n = strcspn(l, "\n");
		const char *yw = memchr(l, 'Y', n);

		if (!strncmp(l, ";TYPE:", 6)) {
			if (in_loop)
				rear += start_y >= max_y - 1e-3;
			in_loop = !strncmp(l, ";TYPE:External perimeter\n", 25);
			*loops += in_loop;
			start_y = y;
			max_y = y;
		}
		if (strncmp(l, "G1 ", 3))
			continue;
		if (yw)
			y = strtod(yw + 1, NULL);
		if (in_loop && memchr(l, 'E', n))
			max_y = fmax(max_y, y);
	}
	return rear + (in_loop && start_y >= max_y - 1e-3);
}

START_TEST(seam_position_honoured)
{
	char model[4096];
	int loops, rear;
	char *g;

	model_file(fx_sphere(0, 0, 8, 8, 16, 40), "ball.stl", model, sizeof(model));
	g = slice(model, "--set seam_position=rear");
	rear = rear_seams(g, &loops);
	ck_assert_int_gt(loops, 20);
	ck_assert_msg(rear == loops, "rear: %d of %d loops start at the back", rear, loops);
	free(g);
	g = slice(model, "--set seam_position=random");
	rear = rear_seams(g, &loops);
	ck_assert_msg(rear < loops / 2, "random: %d of %d loops start at the back", rear, loops);
	free(g);
	ck_assert_msg(!strstr(slice_out, "seam_position="), "%s", slice_out);
}
END_TEST

void slicecli_settings_tcases(Suite *s)
{
	TCase *tc = tcase_create("settings");

	tcase_set_timeout(tc, 120);
	tcase_add_test(tc, role_speeds_honoured);
	tcase_add_test(tc, speed_percentages_resolved);
	tcase_add_test(tc, gap_fill_speed_honoured);
	tcase_add_test(tc, support_speeds_honoured);
	tcase_add_test(tc, header_lists_slicing_settings);
	tcase_add_test(tc, fan_always_on_honoured);
	tcase_add_test(tc, sailfish_fan_is_m126);
	tcase_add_test(tc, skirt_settings_honoured);
	tcase_add_test(tc, solid_infill_below_area_honoured);
	tcase_add_test(tc, seam_position_honoured);
	slicecli_settings_more_tests(tc);
	suite_add_tcase(s, tc);
}
