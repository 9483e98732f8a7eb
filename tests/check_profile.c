/*
 * check_profile.c - printer profiles: the shipped printers/NAME.ini files,
 * the loader's defaults, every class of bad input (with the file, line and
 * key in the message).  NAME resolution, listing, round trips through
 * profile_write and the `stratum printers` command end to end are in
 * check_profile_cli.c, the shared loaders in profiletest.c.
 */
#include <check.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "ini.h"
#include "printer_profile.h"
#include "profile.h"
#include "profile_int.h"
#include "profiletest.h"
#include "settings.h"
#include "suites.h"
#include "testutil.h"

/* ---- the shipped profiles ------------------------------------------------ */

START_TEST(test_creator_pro)
{
	struct profile *p = load_shipped("flashforge-creator-pro");

	ck_assert_int_eq(p->protocol, PROFILE_PROTOCOL_SAILFISH);
	ck_assert_int_eq(p->gcode_flavor, PROFILE_FLAVOR_SAILFISH);
	ck_assert_int_eq(p->extruder_count, 2);
	assert_close(p->nozzle_diameter[0], 0.4);
	assert_close(p->nozzle_diameter[1], 0.4);
	assert_close(p->filament_diameter[1], 1.75);
	assert_close(p->bed_max_x - p->bed_min_x, 227);
	assert_close(p->bed_max_y - p->bed_min_y, 148);
	assert_close(p->max_print_height, 150);
	ck_assert_int_eq(p->baudrate, 115200);
	ck_assert_uint_eq(p->usb_id_count, 1);
	ck_assert_uint_eq(p->usb_ids[0].vid, 0x23c1);
	ck_assert_uint_eq(p->usb_ids[0].pid, 0xd314);
	ck_assert(p->bed_temperature > 0); /* heated bed */
	/* GPX r1d, the machine behind its "fcp" alias */
	assert_close(p->steps_per_mm[0], 94.117647);
	assert_close(p->steps_per_mm[1], 94.117647);
	assert_close(p->steps_per_mm[2], 400);
	assert_close(p->steps_per_mm_e[0], 96.275201870333662);
	assert_close(p->steps_per_mm_e[1], 96.275201870333662);
	ck_assert_int_eq(p->home_direction[0], PROFILE_HOME_MAX);
	ck_assert_int_eq(p->home_direction[1], PROFILE_HOME_MAX);
	ck_assert_int_eq(p->home_direction[2], PROFILE_HOME_MIN);
	assert_close(p->home_feedrate[2], 1100);
	assert_close(p->x3g_toolhead_offset[0], 33);
	assert_close(p->machine_max_feedrate[PROFILE_AXIS_X] * 60, 18000);
	assert_close(p->machine_max_feedrate[PROFILE_AXIS_Z] * 60, 1170);
	ck_assert(fabs(p->machine_max_feedrate[PROFILE_AXIS_E] * 60 - 1600) < 1e-9);
	ck_assert(p->use_relative_e_distances);
	ck_assert_ptr_nonnull(strstr(p->start_gcode, "\nM132 X Y Z A B"));
	ck_assert_ptr_null(strstr(p->start_gcode, "\\n"));
	ck_assert_str_eq(p->name, "FlashForge Creator Pro");
	profile_free(p);
}
END_TEST

START_TEST(test_mk3s)
{
	struct profile *p = load_shipped("prusa-i3-mk3s");

	ck_assert_int_eq(p->protocol, PROFILE_PROTOCOL_MARLIN);
	ck_assert_int_eq(p->gcode_flavor, PROFILE_FLAVOR_MARLIN);
	ck_assert_int_eq(p->extruder_count, 1);
	assert_close(p->nozzle_diameter[0], 0.4);
	assert_close(p->filament_diameter[0], 1.75);
	assert_close(p->bed_min_x, 0);
	assert_close(p->bed_max_x, 250);
	assert_close(p->bed_max_y, 210);
	assert_close(p->max_print_height, 210);
	ck_assert_int_eq(p->baudrate, 115200);
	ck_assert_uint_eq(p->usb_id_count, 1);
	ck_assert_uint_eq(p->usb_ids[0].vid, 0x2c99);
	ck_assert_uint_eq(p->usb_ids[0].pid, 0x0002);
	ck_assert_int_eq(p->rx_buffer_size, 128);
	ck_assert_str_eq(p->printer_model, "MK3S");
	/* normal,stealth lists: the first value is used */
	assert_close(p->machine_max_feedrate[PROFILE_AXIS_X], 200);
	assert_close(p->machine_max_acceleration[PROFILE_AXIS_X], 1000);
	assert_close(p->retract_length[0], 0.8);
	assert_close(p->fill_density, 15);
	ck_assert_str_eq(p->fill_pattern, "gyroid");
	ck_assert_ptr_nonnull(strstr(p->start_gcode, "M862.3 P \"MK3S\""));
	ck_assert_ptr_nonnull(strstr(p->start_gcode, "\nG80 "));
	profile_free(p);
}
END_TEST

START_TEST(test_ender3)
{
	struct profile *p = load_shipped("creality-ender-3");

	ck_assert_int_eq(p->protocol, PROFILE_PROTOCOL_MARLIN);
	assert_close(p->bed_max_x - p->bed_min_x, 235);
	assert_close(p->bed_max_y - p->bed_min_y, 235);
	assert_close(p->max_print_height, 250);
	assert_close(p->nozzle_diameter[0], 0.4);
	ck_assert_int_eq(p->baudrate, 115200);
	ck_assert_uint_eq(p->usb_id_count, 1);
	ck_assert_uint_eq(p->usb_ids[0].vid, 0x1a86);
	ck_assert_uint_eq(p->usb_ids[0].pid, 0x7523);
	assert_close(p->retract_length[0], 5);
	profile_free(p);
}
END_TEST

START_TEST(test_generic_marlin)
{
	struct profile *p = load_shipped("generic-marlin");

	ck_assert_int_eq(p->protocol, PROFILE_PROTOCOL_MARLIN);
	ck_assert_int_eq(p->gcode_flavor, PROFILE_FLAVOR_MARLIN2);
	ck_assert_int_eq(p->extruder_count, 1);
	assert_close(p->bed_max_x, 200);
	assert_close(p->bed_max_y, 200);
	assert_close(p->max_print_height, 200);
	ck_assert_uint_eq(p->usb_id_count, 0);
	ck_assert(p->dtr_reset);
	ck_assert_int_eq(p->rx_buffer_size, 128);
	ck_assert_str_eq(p->printer_model, "");
	profile_free(p);
}
END_TEST

/* ---- defaults and syntax ------------------------------------------------- */

START_TEST(test_defaults)
{
	struct profile *p = load_ok("");

	ck_assert_str_eq(p->id, "test");
	ck_assert_str_eq(p->name, "test");
	ck_assert_int_eq(p->protocol, PROFILE_PROTOCOL_MARLIN);
	ck_assert_int_eq(p->gcode_flavor, PROFILE_FLAVOR_MARLIN2);
	ck_assert_int_eq(p->extruder_count, 1);
	assert_close(p->nozzle_diameter[0], 0.4);
	assert_close(p->filament_diameter[0], 1.75);
	ck_assert_uint_eq(p->bed_points, 4);
	assert_close(p->bed_max_x, 200);
	assert_close(p->max_print_height, 200);
	assert_close(p->layer_height, 0.2);
	assert_close(p->max_layer_height[0], 0.3); /* 0 means 75% of the nozzle */
	ck_assert_int_eq(p->baudrate, 115200);
	ck_assert_int_eq(p->rx_buffer_size, 128);
	ck_assert_int_eq(p->temperature[0], 200);
	ck_assert_int_eq(p->first_layer_temperature[0], 200);
	/* a pattern the slicer prints (issue 17: "stars" could not be sliced) */
	ck_assert_str_eq(p->fill_pattern, "rectilinear");
	ck_assert_ptr_nonnull(strstr(p->start_gcode, "G28"));
	assert_close(p->steps_per_mm[0], 0); /* unknown on Marlin: the firmware knows */
	ck_assert_ptr_null(profile_get(p, "nozzle_diameter"));
	ck_assert_int_eq(key_line(p, "nozzle_diameter"), 0);
	profile_free(p);
}
END_TEST

START_TEST(test_sailfish_defaults)
{
	struct profile *p = load_ok("protocol = sailfish\n");

	ck_assert_int_eq(p->gcode_flavor, PROFILE_FLAVOR_SAILFISH);
	assert_close(p->steps_per_mm[2], 400);
	assert_close(p->steps_per_mm_e[0], 96.275201870333662);
	ck_assert_int_eq(p->home_direction[0], PROFILE_HOME_MAX);
	ck_assert_str_eq(p->start_gcode, "");
	profile_free(p);

	p = load_ok("gcode_flavor = makerware\n");
	ck_assert_int_eq(p->protocol, PROFILE_PROTOCOL_SAILFISH);
	ck_assert_int_eq(p->gcode_flavor, PROFILE_FLAVOR_MAKERWARE);
	profile_free(p);
}
END_TEST

START_TEST(test_syntax_accepted)
{
	struct profile *p = load_ok("\xEF\xBB\xBF# generated by PrusaSlicer\r\n"
				    "; another comment\n"
				    "   \n"
				    "\tnozzle_diameter\t=\t0.6 \r\n"
				    "layer_height=.3\n"
				    "first_layer_height = +0.35\n"
				    "printer_notes = \n"
				    "end_gcode = M104 S0 ; nozzle off # not a comment\n"
				    "printer_model = MK3S");

	assert_close(p->nozzle_diameter[0], 0.6);
	assert_close(p->layer_height, 0.3);
	assert_close(p->first_layer_height, 0.35);
	ck_assert_str_eq(profile_get(p, "printer_notes"), "");
	ck_assert_str_eq(p->end_gcode, "M104 S0 ; nozzle off # not a comment");
	ck_assert_str_eq(p->printer_model, "MK3S"); /* last line without a newline */
	ck_assert_int_eq(key_line(p, "nozzle_diameter"), 4);
	profile_free(p);
}
END_TEST

START_TEST(test_escapes)
{
	struct profile *p =
	    load_ok("start_gcode = G28\\nG1 Z5 ; lift\\n\\nM117 \\\"hi\\\" C:\\\\dir "
		    "\\t \\q end\\\n");

	ck_assert_str_eq(p->start_gcode, "G28\nG1 Z5 ; lift\n\nM117 \"hi\" C:\\dir \\t \\q end\\");
	ck_assert_str_eq(profile_get(p, "start_gcode"), p->start_gcode);
	profile_free(p);
}
END_TEST

START_TEST(test_lists)
{
	struct profile *p = load_ok("nozzle_diameter = 0.4, 0.6\n"
				    "temperature = 215\n"
				    "extruder_offset = 0x0,-33.5x0.25\n"
				    "retract_length = 1,2\n"
				    "bed_temperature = 60,70\n"
				    "cooling = 1,0\n"
				    "fill_density = 0.25\n"
				    "first_layer_speed = 50%\n"
				    "layer_height = 0.2\n"
				    "first_layer_height = 150%\n"
				    "extrusion_width = 225%\n");

	ck_assert_int_eq(p->extruder_count, 2);
	assert_close(p->nozzle_diameter[1], 0.6);
	ck_assert_int_eq(p->temperature[0], 215);
	ck_assert_int_eq(p->temperature[1], 215);	      /* one value for every extruder */
	ck_assert_int_eq(p->first_layer_temperature[1], 215); /* follows temperature */
	assert_close(p->extruder_offset[1].x, -33.5);
	assert_close(p->extruder_offset[1].y, 0.25);
	assert_close(p->retract_length[1], 2);
	ck_assert_int_eq(p->bed_temperature, 60);
	ck_assert_int_eq(p->first_layer_bed_temperature, 60);
	ck_assert(p->cooling);
	assert_close(p->fill_density, 25); /* a bare number is a fraction */
	assert_close(p->first_layer_speed.value, 50);
	ck_assert(p->first_layer_speed.is_percent);
	assert_close(p->first_layer_height, 0.3);
	assert_close(p->extrusion_width, 0.45);
	profile_free(p);
}
END_TEST

/* ---- errors ---------------------------------------------------------------- */

START_TEST(test_bad_number)
{
	load_bad("# a comment\nnozzle_diameter = 0.4mm\n", ST_ERR_PARSE, "line 2",
		 "nozzle_diameter", "'0.4mm' is not a number", NULL);
	load_bad("layer_height = 1e\n", ST_ERR_PARSE, "line 1", "layer_height", "'1e'", NULL);
	load_bad("layer_height = 1e+\n", ST_ERR_PARSE, "'1e+'", NULL);
	load_bad("layer_height = 0,2\n", ST_ERR_PARSE, "'0,2' is not a number", NULL);
	/* a '#' comment after a number and a blank, as BIBO's bundle writes it
	 * (PrusaSlicer reads the number); run into the number it is no comment */
	{
		struct profile *p = load_ok("retract_speed = 20\nderetract_speed = 0 # Setting "
					    "this value to 0 uses the retract speed\n"
					    "layer_height = 0.25\t# thin\n");
		assert_close(p->deretract_speed[0], 0);
		assert_close(p->layer_height, 0.25);
		profile_free(p);
	}
	load_bad("layer_height = 0.2#x\n", ST_ERR_PARSE, "'0.2#x' is not a number", NULL);
	load_bad("layer_height = # 0.2\n", ST_ERR_PARSE, "is not a number", NULL);
	load_bad("layer_height = nan\n", ST_ERR_PARSE, "'nan'", NULL);
	load_bad("layer_height = 0x10\n", ST_ERR_PARSE, NULL);
	load_bad("layer_height = .\n", ST_ERR_PARSE, NULL);
	load_bad("layer_height = -\n", ST_ERR_PARSE, NULL);
	load_bad("layer_height =\n", ST_ERR_PARSE, "no value", NULL);
	load_bad("perimeters = 2.5\n", ST_ERR_PARSE, "perimeters", "not a whole number", NULL);
	load_bad("dtr_reset = yes\n", ST_ERR_PARSE, "dtr_reset", "expected 0 or 1", NULL);
	load_bad("temperature = 200,,210\n", ST_ERR_PARSE, "empty value", NULL);
	load_bad("nozzle_diameter = 0.4,0.4\ntemperature = 200,abc\n", ST_ERR_PARSE, "line 2",
		 "value 2 of 2", "'abc'", NULL);
}
END_TEST

START_TEST(test_out_of_range)
{
	load_bad("\nnozzle_diameter = 5\n", ST_ERR_RANGE, "line 2", "nozzle_diameter",
		 "between 0.05 and 3 mm", NULL);
	load_bad("nozzle_diameter = 0.01\n", ST_ERR_RANGE, "nozzle_diameter", NULL);
	load_bad("filament_diameter = 4\n", ST_ERR_RANGE, "filament_diameter", NULL);
	load_bad("temperature = 451\n", ST_ERR_RANGE, "temperature", NULL);
	load_bad("bed_temperature = 151\n", ST_ERR_RANGE, "bed_temperature", NULL);
	load_bad("max_print_height = 0\n", ST_ERR_RANGE, "more than 0", NULL);
	load_bad("layer_height = 0\n", ST_ERR_RANGE, "layer_height", NULL);
	load_bad("fill_density = 150%\n", ST_ERR_RANGE, "fill_density", NULL);
	load_bad("first_layer_height = 0%\n", ST_ERR_RANGE, NULL);
	load_bad("baudrate = 115201\n", ST_ERR_RANGE, "baudrate", "not a standard baud rate", NULL);
	load_bad("baudrate = fast\n", ST_ERR_PARSE, "baudrate", NULL);
	load_bad("rx_buffer_size = 8\n", ST_ERR_RANGE, "rx_buffer_size", NULL);
	load_bad("machine_max_feedrate_x = 200,100,50\n", ST_ERR_RANGE, "1 or 2", NULL);
	load_bad("extruder_count = 9\n", ST_ERR_RANGE, "extruder_count", NULL);
}
END_TEST

/* `bufsize` declares the firmware's BUFSIZE, so the Marlin window counts
 * command slots without ADVANCED_OK (issue 17 defect 8); 0 = unknown. */
START_TEST(test_bufsize_reaches_the_driver)
{
	struct profile *p = load_ok("bufsize = 4\n");
	struct printer_options o;
	const struct printer_ops *ops;
	struct st_error err = {0};

	ck_assert_int_eq(p->bufsize, 4);
	ck_assert_int_eq(printer_profile_options(p, "sim", 0, &o, &ops, &err), 0);
	ck_assert_uint_eq(o.bufsize, 4);
	profile_free(p);
	p = load_ok("nozzle_diameter = 0.4\n");
	ck_assert_int_eq(printer_profile_options(p, "sim", 0, &o, &ops, &err), 0);
	ck_assert_uint_eq(o.bufsize, 0);
	profile_free(p);
	load_bad("bufsize = 257\n", ST_ERR_RANGE, "bufsize", "between 0 and 256", NULL);
}
END_TEST

START_TEST(test_cross_checks)
{
	load_bad("nozzle_diameter = 0.4\nlayer_height = 0.5\n", ST_ERR_RANGE, "line 2",
		 "layer_height", "larger than the nozzle", NULL);
	/* the default layer height (0.2) against a small nozzle: blamed on the nozzle's line */
	load_bad("nozzle_diameter = 0.15\n", ST_ERR_RANGE, "line 1", "(default)", NULL);
	load_bad("layer_height = 0.2\nfirst_layer_height = 300%\n", ST_ERR_RANGE,
		 "first_layer_height", NULL);
	load_bad("min_layer_height = 0.3\nmax_layer_height = 0.2\n", ST_ERR_RANGE,
		 "min_layer_height", NULL);
	load_bad("protocol = marlin\ngcode_flavor = sailfish\n", ST_ERR_RANGE, "gcode_flavor",
		 "protocol", NULL);
	load_bad("protocol = sailfish\ngcode_flavor = marlin2\n", ST_ERR_RANGE, "gcode_flavor",
		 NULL);
	load_bad("protocol = sailfish\nextruder_count = 3\n", ST_ERR_RANGE, "at most 2", NULL);
	load_bad("protocol = sailfish\nsteps_per_mm_z = 0\n", ST_ERR_RANGE, "steps_per_mm_z", NULL);
}
END_TEST

START_TEST(test_extruder_counts)
{
	load_bad("extruder_count = 2\nnozzle_diameter = 0.4,0.4,0.4\n", ST_ERR_RANGE, "line 2",
		 "nozzle_diameter", "3 values", "2 extruders", "extruder_count on line 1", NULL);
	load_bad("nozzle_diameter = 0.4,0.4\ntemperature = 200,210,220\n", ST_ERR_RANGE,
		 "temperature", "nozzle_diameter on line 1", NULL);
	load_bad("temperature = 200,210\n", ST_ERR_RANGE, "1 extruder", "the default", NULL);
}
END_TEST

START_TEST(test_duplicate_key)
{
	load_bad("nozzle_diameter = 0.4\nlayer_height = 0.2\n\n#\nnozzle_diameter = 0.4\n",
		 ST_ERR_PARSE, "line 5", "duplicate key 'nozzle_diameter'", "first set on line 1",
		 NULL);
	/* unknown keys may repeat neither */
	load_bad("foo = 1\nfoo = 2\n", ST_ERR_PARSE, "duplicate key 'foo'", NULL);
}
END_TEST

START_TEST(test_bad_enums)
{
	load_bad("protocol = klipper\n", ST_ERR_PARSE, "line 1", "protocol",
		 "expected marlin or sailfish", "'klipper'", NULL);
	load_bad("gcode_flavor = prusa\n", ST_ERR_PARSE, "gcode_flavor", "marlin2", NULL);
	load_bad("fill_pattern = spiral\n", ST_ERR_PARSE, "fill_pattern", "gyroid", NULL);
	load_bad("home_direction_x = up\n", ST_ERR_PARSE, "min or max", NULL);
}
END_TEST

START_TEST(test_bad_usb_ids)
{
	struct profile *p;

	load_bad("usb_ids = 2c99:2\n", ST_ERR_PARSE, "line 1", "usb_ids", "'2c99:2'", "VVVV:PPPP",
		 NULL);
	load_bad("usb_ids = zz99:0002\n", ST_ERR_PARSE, "usb_ids", NULL);
	load_bad("usb_ids = 2c99-0002\n", ST_ERR_PARSE, "usb_ids", NULL);
	load_bad("usb_ids = 2c99:0002,\n", ST_ERR_PARSE, "empty value", NULL);
	p = load_ok("usb_ids = 2C99:0002, 1a86:7523\n");
	ck_assert_uint_eq(p->usb_id_count, 2);
	ck_assert_uint_eq(p->usb_ids[0].vid, 0x2c99);
	ck_assert_uint_eq(p->usb_ids[1].pid, 0x7523);
	profile_free(p);
}
END_TEST

START_TEST(test_bad_bed_shape)
{
	struct profile *p;

	load_bad("bed_shape = 0x0,200x0\n", ST_ERR_PARSE, "line 1", "bed_shape", "at least 3",
		 NULL);
	load_bad("bed_shape = 0x0,200,200x200\n", ST_ERR_PARSE, "bed_shape", "'200'", "not a point",
		 NULL);
	load_bad("bed_shape = 0x0,200xA,200x200\n", ST_ERR_PARSE, "bed_shape", NULL);
	load_bad("bed_shape = 0x0,100x100,200x200\n", ST_ERR_RANGE, "no area", NULL);
	load_bad("bed_shape = 0x0,20000x0,0x200\n", ST_ERR_RANGE, "bed_shape", NULL);
	p = load_ok("bed_shape = -115x-77,115x-77,115x78,-115x78\n");
	assert_close(p->bed_min_x, -115);
	assert_close(p->bed_max_y, 78);
	profile_free(p);
	/* A round bed as PrusaSlicer writes it (TriLAB, FLSun bundles). */
	p = load_ok("bed_shape = 90x0,5.51091e-15x90,-90x1.10218e-14,-1.65327e-14x-90\n");
	assert_close(p->bed_min_x, -90);
	assert_close(p->bed_max_y, 90);
	profile_free(p);
}
END_TEST

START_TEST(test_bad_lines)
{
	load_bad("nozzle_diameter = 0.4\n\njust some words\n", ST_ERR_PARSE, "line 3",
		 "expected 'key = value'", "just some words", NULL);
	load_bad("[printer:Foo]\nnozzle_diameter = 0.4\n", ST_ERR_PARSE, "line 1", "sections",
		 NULL);
	load_bad("nozzle diameter = 0.4\n", ST_ERR_PARSE, "not a valid key", NULL);
	load_bad(" = 0.4\n", ST_ERR_PARSE, "not a valid key", NULL);
}
END_TEST

START_TEST(test_nul_byte)
{
	struct profile *p = NULL;
	struct st_error err = {0};
	const char text[] = "name = a\nnozzle_diameter = 0.4\0\n";

	ck_assert_int_eq(profile_load_buffer(text, sizeof(text) - 1, "nul.ini", &p, &err),
			 ST_ERR_PARSE);
	ck_assert_ptr_null(p);
	ck_assert_ptr_nonnull(strstr(err.msg, "line 2"));
	ck_assert_ptr_nonnull(strstr(err.msg, "NUL"));
}
END_TEST

START_TEST(test_overlong_line)
{
	size_t body = INI_LINE_MAX + 1;
	char *text = malloc(body + 64);
	struct profile *p = NULL;
	struct st_error err = {0};
	size_t n;

	ck_assert_ptr_nonnull(text);
	/* exactly INI_LINE_MAX bytes is fine */
	n = (size_t)sprintf(text, "name = x\nstart_gcode = ");
	memset(text + n, 'G', INI_LINE_MAX - strlen("start_gcode = "));
	n += INI_LINE_MAX - strlen("start_gcode = ");
	text[n++] = '\n';
	ck_assert_msg(profile_load_buffer(text, n, "long.ini", &p, &err) == 0, "%s", err.msg);
	ck_assert_uint_eq(strlen(p->start_gcode), INI_LINE_MAX - strlen("start_gcode = "));
	profile_free(p);
	/* one byte more is rejected, never cut */
	text[n - 1] = 'G';
	text[n++] = '\n';
	ck_assert_int_eq(profile_load_buffer(text, n, "long.ini", &p, &err), ST_ERR_PARSE);
	ck_assert_ptr_null(p);
	ck_assert_ptr_nonnull(strstr(err.msg, "long.ini: line 2 is longer than 65536 bytes"));
	/* the same from a file */
	tu_write(tu_path("long.ini"), text, n);
	ck_assert_int_eq(profile_load_file(tu_path("long.ini"), &p, &err), ST_ERR_PARSE);
	ck_assert_ptr_nonnull(strstr(err.msg, "line 2 is longer"));
	free(text);
}
END_TEST

START_TEST(test_missing_file)
{
	struct profile *p = (struct profile *)&p;
	struct st_error err = {0};

	ck_assert_int_eq(profile_load_file("/nonexistent/dir/none.ini", &p, &err), ST_ERR_IO);
	ck_assert_ptr_null(p);
	ck_assert_ptr_nonnull(strstr(err.msg, "/nonexistent/dir/none.ini: cannot open"));
	ck_assert_int_eq(profile_load_file("printers", &p, &err), ST_ERR_IO);
	ck_assert_ptr_nonnull(strstr(err.msg, "is a directory"));
}
END_TEST

Suite *profile_suite(void)
{
	Suite *s = suite_create("profile");
	TCase *shipped = tcase_create("shipped");
	TCase *load = tcase_create("load");
	TCase *errors = tcase_create("errors");

	tcase_add_test(shipped, test_creator_pro);
	tcase_add_test(shipped, test_mk3s);
	tcase_add_test(shipped, test_ender3);
	tcase_add_test(shipped, test_generic_marlin);
	suite_add_tcase(s, shipped);

	tcase_add_test(load, test_defaults);
	tcase_add_test(load, test_sailfish_defaults);
	tcase_add_test(load, test_syntax_accepted);
	tcase_add_test(load, test_escapes);
	tcase_add_test(load, test_lists);
	suite_add_tcase(s, load);

	tcase_add_test(errors, test_bad_number);
	tcase_add_test(errors, test_out_of_range);
	tcase_add_test(errors, test_bufsize_reaches_the_driver);
	tcase_add_test(errors, test_cross_checks);
	tcase_add_test(errors, test_extruder_counts);
	tcase_add_test(errors, test_duplicate_key);
	tcase_add_test(errors, test_bad_enums);
	tcase_add_test(errors, test_bad_usb_ids);
	tcase_add_test(errors, test_bad_bed_shape);
	tcase_add_test(errors, test_bad_lines);
	tcase_add_test(errors, test_nul_byte);
	tcase_add_test(errors, test_overlong_line);
	tcase_add_test(errors, test_missing_file);
	suite_add_tcase(s, errors);
	profile_cli_tcases(s);
	profile_find_tcases(s);
	profile_shipped_tcases(s);
	return s;
}
