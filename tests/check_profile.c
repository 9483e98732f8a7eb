/*
 * check_profile.c - printer profiles: the shipped printers/NAME.ini files,
 * the loader's defaults, every class of bad input (with the file, line and
 * key in the message), NAME resolution, listing, round trips through
 * profile_write and the `stratum printers` command end to end.
 */
#include <check.h>
#include <errno.h>
#include <jansson.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <sys/stat.h>
#include <unistd.h>

#include "ini.h"
#include "printer_profile.h"
#include "profile.h"
#include "profile_int.h"
#include "settings.h"
#include "suites.h"
#include "testutil.h"

static char out[1 << 16];

/* Load text as "test.ini"; the test fails with the loader's message on error. */
static struct profile *load_ok(const char *text)
{
	struct profile *p = NULL;
	struct st_error err = {0};
	int rc = profile_load_buffer(text, strlen(text), "test.ini", &p, &err);

	ck_assert_msg(rc == 0, "load failed (%d): %s", rc, err.msg);
	ck_assert_ptr_nonnull(p);
	return p;
}

/*
 * Load text and expect class code; the message must contain every string of
 * the NULL-terminated list that follows.
 */
static void load_bad(const char *text, int code, ...)
{
	struct profile *p = (struct profile *)&p; /* must be reset to NULL */
	struct st_error err = {0};
	const char *needle;
	va_list ap;
	int rc = profile_load_buffer(text, strlen(text), "test.ini", &p, &err);

	ck_assert_msg(rc == code, "wanted class %d, got %d (%s) for:\n%s", code, rc, err.msg, text);
	ck_assert_int_eq(err.code, code);
	ck_assert_ptr_null(p);
	ck_assert_msg(!strncmp(err.msg, "test.ini: ", 10), "message lacks the file: %s", err.msg);
	va_start(ap, code);
	while ((needle = va_arg(ap, const char *)))
		ck_assert_msg(strstr(err.msg, needle), "'%s' not in message: %s", needle, err.msg);
	va_end(ap);
}

static struct profile *load_shipped(const char *id)
{
	char path[256];
	struct profile *p = NULL;
	struct st_error err = {0};

	snprintf(path, sizeof(path), "printers/%s.ini", id);
	ck_assert_msg(profile_load_file(path, &p, &err) == 0, "%s", err.msg);
	ck_assert_str_eq(p->id, id);
	return p;
}

static void assert_close(double got, double want)
{
	ck_assert_msg(fabs(got - want) < 1e-9, "got %.17g, wanted %.17g", got, want);
}

/* Make a scratch directory for STRATUM_PRINTERS_DIR and return its path. */
static const char *scratch_dir(const char *name)
{
	static char dir[512];

	snprintf(dir, sizeof(dir), "%s", tu_path(name));
	ck_assert_msg(mkdir(dir, 0755) == 0 || errno == EEXIST, "mkdir %s", dir);
	return dir;
}

static void write_in(const char *dir, const char *file, const char *text)
{
	char path[700];

	snprintf(path, sizeof(path), "%s/%s", dir, file);
	tu_write_str(path, text);
}

/* ---- the shipped profiles ------------------------------------------------ */

/* The file line that set key (0: not set), as the loader's messages name it. */
static int key_line(const struct profile *p, const char *key)
{
	const struct profile_kv *kv = prof_find_kv(p->keys, key);

	return kv ? kv->line : 0;
}

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

/* ---- raw access, writing, JSON ------------------------------------------ */

START_TEST(test_raw_keys)
{
	struct profile *p = load_ok("printer_notes = PRINTER_VENDOR_X\\nsecond line\n"
				    "max_print_speed = 150\n"
				    "bad_number = 1e3x\n"
				    "nozzle_diameter = 0.4\n");
	ck_assert_str_eq(profile_get(p, "printer_notes"), "PRINTER_VENDOR_X\nsecond line");
	ck_assert_str_eq(profile_get(p, "nozzle_diameter"), "0.4");
	ck_assert_ptr_null(profile_get(p, "absent"));
	ck_assert_int_eq(key_line(p, "max_print_speed"), 2);
	/* every key of the file kept in file order */
	ck_assert_uint_eq(p->keys->count, 4);
	ck_assert_str_eq(p->keys->kv[1].key, "max_print_speed");
	ck_assert_str_eq(p->keys->kv[1].value, "150");
	ck_assert_int_eq(p->keys->kv[1].line, 2);
	ck_assert_ptr_nonnull(prof_find_def("bed_shape"));
	ck_assert_ptr_null(prof_find_def("printer_notes"));
	profile_free(p);
	profile_free(NULL);
	profile_list_free(NULL, 0);
}
END_TEST

START_TEST(test_write_round_trip)
{
	static const char *const ids[] = {"flashforge-creator-pro", "prusa-i3-mk3s",
					  "creality-ender-3", "generic-marlin"};

	for (size_t k = 0; k < sizeof(ids) / sizeof(ids[0]); k++) {
		struct profile *a = load_shipped(ids[k]), *b = NULL;
		struct st_error err = {0};
		const char *path = tu_path("round.ini");
		FILE *f = fopen(path, "w");

		ck_assert_ptr_nonnull(f);
		ck_assert_int_eq(profile_write(a, f), 0);
		ck_assert_int_eq(fclose(f), 0);
		ck_assert_msg(profile_load_file(path, &b, &err) == 0, "%s: %s", ids[k], err.msg);
		ck_assert_str_eq(a->name, b->name);
		ck_assert_int_eq(a->protocol, b->protocol);
		ck_assert_int_eq(a->gcode_flavor, b->gcode_flavor);
		ck_assert_int_eq(a->extruder_count, b->extruder_count);
		ck_assert_uint_eq(a->bed_points, b->bed_points);
		ck_assert(
		    memcmp(a->bed_shape, b->bed_shape, a->bed_points * sizeof(*a->bed_shape)) == 0);
		ck_assert(memcmp(a->nozzle_diameter, b->nozzle_diameter,
				 sizeof(a->nozzle_diameter)) == 0);
		ck_assert(memcmp(a->steps_per_mm_e, b->steps_per_mm_e, sizeof(a->steps_per_mm_e)) ==
			  0);
		ck_assert(memcmp(a->machine_max_feedrate, b->machine_max_feedrate,
				 sizeof(a->machine_max_feedrate)) == 0);
		ck_assert(a->first_layer_height == b->first_layer_height);
		ck_assert(a->fill_density == b->fill_density);
		ck_assert_uint_eq(a->usb_id_count, b->usb_id_count);
		ck_assert_str_eq(a->start_gcode, b->start_gcode);
		ck_assert_str_eq(a->end_gcode, b->end_gcode);
		profile_free(a);
		profile_free(b);
	}
}
END_TEST

/* The ironing and spiral vase keys: their defaults, and a percentage that
 * is not fill_density's written back as itself (file and JSON). */
START_TEST(test_print_mode_keys)
{
	struct profile *p = load_ok(""), *b = NULL;
	struct st_error err = {0};
	const char *path = tu_path("modes.ini");
	FILE *f;
	json_t *o;

	ck_assert(!p->spiral_vase && !p->ironing);
	ck_assert_str_eq(p->ironing_type, "top");
	assert_close(p->ironing_flowrate, 15);
	assert_close(p->ironing_spacing, 0.1);
	assert_close(p->ironing_speed, 15);
	profile_free(p);
	p = load_ok("spiral_vase = 1\nironing = 1\nironing_type = solid\n"
		    "ironing_flowrate = 10%\nironing_spacing = 0.2\nironing_speed = 25\n");
	ck_assert(p->spiral_vase && p->ironing);
	ck_assert_str_eq(p->ironing_type, "solid");
	assert_close(p->ironing_flowrate, 10);
	f = fopen(path, "w");
	ck_assert_ptr_nonnull(f);
	ck_assert_int_eq(profile_write(p, f), 0);
	ck_assert_int_eq(fclose(f), 0);
	ck_assert_msg(profile_load_file(path, &b, &err) == 0, "%s", err.msg);
	assert_close(b->ironing_flowrate, 10);
	assert_close(b->fill_density, 20);
	assert_close(b->ironing_spacing, 0.2);
	assert_close(b->ironing_speed, 25);
	o = profile_to_json(p);
	assert_close(json_real_value(json_object_get(json_object_get(o, "settings"),
						     "ironing_flowrate")),
		     10);
	json_decref(o);
	load_bad("ironing_type = everything\n", ST_ERR_PARSE, "ironing_type", "topmost", NULL);
	load_bad("ironing_flowrate = 150%\n", ST_ERR_RANGE, "ironing_flowrate", NULL);
	profile_free(p);
	profile_free(b);
}
END_TEST

START_TEST(test_json)
{
	struct profile *p = load_shipped("flashforge-creator-pro");
	json_t *o = profile_to_json(p), *s;

	ck_assert_ptr_nonnull(o);
	ck_assert_str_eq(json_string_value(json_object_get(o, "id")), "flashforge-creator-pro");
	s = json_object_get(o, "settings");
	ck_assert_int_eq(json_integer_value(json_object_get(s, "extruder_count")), 2);
	ck_assert_str_eq(json_string_value(json_array_get(json_object_get(s, "usb_ids"), 0)),
			 "23c1:d314");
	ck_assert_str_eq(json_string_value(json_object_get(s, "protocol")), "sailfish");
	ck_assert_uint_eq(json_array_size(json_object_get(s, "bed_shape")), 4);
	ck_assert(json_is_object(json_object_get(o, "other")));
	json_decref(o);
	profile_free(p);
}
END_TEST

/* ---- finding and listing ------------------------------------------------- */

START_TEST(test_find_by_name)
{
	const char *dir = scratch_dir("printers-find");
	struct profile *p = NULL;
	struct st_error err = {0};
	struct profile_dirs dirs;
	char want[700];

	write_in(dir, "my-printer.ini", "name = Mine\nnozzle_diameter = 0.6\n");
	write_in(dir, "broken.ini", "nozzle_diameter = big\n");
	ck_assert_int_eq(setenv("STRATUM_PRINTERS_DIR", dir, 1), 0);
	profile_search_dirs(&dirs);
	ck_assert_uint_ge(dirs.count, 2);
	ck_assert_str_eq(dirs.path[0], dir);
	ck_assert_str_eq(dirs.path[dirs.count - 1], STRATUM_DATADIR);

	ck_assert_msg(profile_find("my-printer", &p, &err) == 0, "%s", err.msg);
	ck_assert_str_eq(p->id, "my-printer");
	ck_assert_str_eq(p->name, "Mine");
	snprintf(want, sizeof(want), "%s/my-printer.ini", dir);
	ck_assert_str_eq(p->path, want);
	profile_free(p);

	/* a file path, relative or absolute */
	ck_assert_msg(profile_find("printers/generic-marlin.ini", &p, &err) == 0, "%s", err.msg);
	ck_assert_str_eq(p->id, "generic-marlin");
	profile_free(p);
	ck_assert_msg(profile_find(want, &p, &err) == 0, "%s", err.msg);
	profile_free(p);

	/* the shipped profiles are still found behind the first directory */
	ck_assert_msg(profile_find("creality-ender-3", &p, &err) == 0, "%s", err.msg);
	profile_free(p);

	ck_assert_int_eq(profile_find("broken", &p, &err), ST_ERR_PARSE);
	ck_assert_ptr_nonnull(strstr(err.msg, "broken.ini: line 1: nozzle_diameter"));
	ck_assert_int_eq(profile_find("nosuch", &p, &err), ST_ERR_ARG);
	ck_assert_ptr_null(p);
	ck_assert_ptr_nonnull(strstr(err.msg, "no printer profile named 'nosuch'"));
	ck_assert_ptr_nonnull(strstr(err.msg, dir));
	ck_assert_int_eq(profile_find("", &p, &err), ST_ERR_ARG);
	ck_assert_int_eq(profile_find("bad name", &p, &err), ST_ERR_ARG);
	ck_assert_int_eq(profile_find("nosuch.ini", &p, &err), ST_ERR_IO);
	unsetenv("STRATUM_PRINTERS_DIR");
}
END_TEST

START_TEST(test_list)
{
	const char *dir = scratch_dir("printers-list");
	struct profile_entry *list = NULL;
	struct st_error err = {0};
	size_t n = 0, mine = 0;
	char shadow[700];

	write_in(dir, "zeta.ini", "");
	write_in(dir, "alpha.ini", "");
	write_in(dir, "generic-marlin.ini", "name = shadowing\n");
	write_in(dir, ".hidden.ini", "");
	write_in(dir, "notes.txt", "");
	ck_assert_int_eq(setenv("STRATUM_PRINTERS_DIR", dir, 1), 0);
	ck_assert_int_eq(profile_list(&list, &n, &err), 0);
	snprintf(shadow, sizeof(shadow), "%s/generic-marlin.ini", dir);
	for (size_t i = 0; i < n; i++) {
		if (i)
			ck_assert_msg(strcmp(list[i - 1].id, list[i].id) < 0, "not sorted/unique");
		ck_assert_msg(list[i].id[0] != '.', "hidden file listed");
		if (!strcmp(list[i].id, "alpha") || !strcmp(list[i].id, "zeta"))
			mine++;
		if (!strcmp(list[i].id, "generic-marlin"))
			ck_assert_str_eq(list[i].path, shadow);
	}
	ck_assert_uint_eq(mine, 2);
	profile_list_free(list, n);
	unsetenv("STRATUM_PRINTERS_DIR");
}
END_TEST

/* ---- `stratum printers` end to end ---------------------------------------- */

/* Point the binary at the source tree's printers/ folder. */
static void use_source_printers(void)
{
	char cwd[512], dir[600];

	ck_assert_ptr_nonnull(getcwd(cwd, sizeof(cwd)));
	snprintf(dir, sizeof(dir), "%s/printers", cwd);
	ck_assert_int_eq(setenv("STRATUM_PRINTERS_DIR", dir, 1), 0);
}

START_TEST(test_cli_list_json)
{
	static const char *const ids[] = {"creality-ender-3", "flashforge-creator-pro",
					  "generic-marlin", "prusa-i3-mk3s"};
	json_error_t jerr;
	json_t *arr, *item;
	size_t i, found = 0;
	int status;

	use_source_printers();
	status = tu_run(out, sizeof(out), "printers --json");
	ck_assert_msg(status == 0, "exit %d: %s", status, out);
	arr = json_loads(out, 0, &jerr);
	ck_assert_msg(json_is_array(arr), "not a JSON array (%s): %s", jerr.text, out);
	json_array_foreach(arr, i, item)
	{
		const char *id = json_string_value(json_object_get(item, "id"));

		ck_assert_ptr_nonnull(id);
		for (size_t k = 0; k < sizeof(ids) / sizeof(ids[0]); k++)
			if (!strcmp(id, ids[k]))
				found++;
		if (!strcmp(id, "flashforge-creator-pro")) {
			ck_assert_int_eq(json_integer_value(json_object_get(item, "extruders")), 2);
			ck_assert_str_eq(json_string_value(json_object_get(item, "protocol")),
					 "sailfish");
			ck_assert(fabs(json_real_value(
					   json_object_get(json_object_get(item, "bed"), "width")) -
				       227) < 1e-9);
		}
	}
	ck_assert_uint_eq(found, 4);
	json_decref(arr);
}
END_TEST

START_TEST(test_cli_table)
{
	int status;

	use_source_printers();
	status = tu_run(out, sizeof(out), "printers");
	ck_assert_msg(status == 0, "exit %d: %s", status, out);
	ck_assert_ptr_nonnull(strstr(out, "NAME"));
	ck_assert_ptr_nonnull(strstr(out, "flashforge-creator-pro"));
	ck_assert_ptr_nonnull(strstr(out, "227 x 148"));
	ck_assert_ptr_nonnull(strstr(out, "prusa-i3-mk3s"));
	ck_assert_ptr_nonnull(strstr(out, "creality-ender-3"));
	ck_assert_ptr_nonnull(strstr(out, "generic-marlin"));
	status = tu_run(out, sizeof(out), "printers --help");
	ck_assert_int_eq(status, 0);
	ck_assert_ptr_nonnull(strstr(out, "usage: stratum printers"));
	status = tu_run(out, sizeof(out), "printers --bogus");
	ck_assert_int_eq(status, 2);
}
END_TEST

START_TEST(test_cli_show)
{
	const char *bad = tu_path("cli-bad.ini");
	int status;

	use_source_printers();
	status = tu_run(out, sizeof(out), "printers --show flashforge-creator-pro");
	ck_assert_msg(status == 0, "exit %d: %s", status, out);
	ck_assert_ptr_nonnull(strstr(out, "steps_per_mm_x = 94.117647"));
	ck_assert_ptr_nonnull(strstr(out, "extruder_count = 2"));

	status = tu_run(out, sizeof(out), "printers --show nosuch");
	ck_assert_msg(status != 0, "exit 0 for an unknown printer: %s", out);
	ck_assert_ptr_nonnull(strstr(out, "no printer profile named 'nosuch'"));

	tu_write_str(bad, "name = x\nusb_ids = 2c99:2\n");
	status = tu_run(out, sizeof(out), "printers --show '%s'", bad);
	ck_assert_int_eq(status, 65);
	ck_assert_ptr_nonnull(strstr(out, "cli-bad.ini: line 2: usb_ids"));
}
END_TEST

START_TEST(test_cli_bad_profile_in_dir)
{
	const char *dir = scratch_dir("printers-cli");
	int status;

	write_in(dir, "good.ini", "name = Good one\n");
	write_in(dir, "bad.ini", "nozzle_diameter = 0.4mm\n");
	ck_assert_int_eq(setenv("STRATUM_PRINTERS_DIR", dir, 1), 0);
	status = tu_run(out, sizeof(out), "printers");
	ck_assert_msg(status == 0, "exit %d: %s", status, out);
	ck_assert_ptr_nonnull(strstr(out, "Good one"));
	ck_assert_ptr_nonnull(strstr(out, "skipping bad"));
	ck_assert_ptr_nonnull(strstr(out, "bad.ini: line 1: nozzle_diameter"));
}
END_TEST


/* Issue 16: one settings truth.  A profile the slicer would refuse
 * (min_print_speed = 0 was accepted here and refused by the G-code writer
 * after repair and slicing, exit 1) fails when it is loaded: exit 2 from
 * `stratum slice` in milliseconds, no G-code written. */
START_TEST(test_unsliceable_profile_fails_at_load)
{
	static const char text[] = "nozzle_diameter = 0.4\nmin_print_speed = 0\n";
	const char *ini = tu_path("mps0.ini"), *gc = tu_path("mps0.gcode");
	struct st_error err = {0};
	struct profile *p = NULL;
	struct timespec t0, t1;
	double ms;
	int status;

	ck_assert_int_eq(profile_load_buffer(text, sizeof(text) - 1, "mps0.ini", &p, &err),
			 ST_ERR_RANGE);
	ck_assert_ptr_null(p);
	ck_assert_ptr_nonnull(strstr(err.msg, "line 2: min_print_speed"));
	tu_write_str(ini, text);
	clock_gettime(CLOCK_MONOTONIC, &t0);
	status = tu_run(out, sizeof(out), "slice docs/examples/bracket.stl -o '%s' --printer '%s'",
			gc, ini);
	clock_gettime(CLOCK_MONOTONIC, &t1);
	ms = (double)(t1.tv_sec - t0.tv_sec) * 1e3 + (double)(t1.tv_nsec - t0.tv_nsec) / 1e6;
	ck_assert_msg(status == 2, "exit %d: %s", status, out);
	ck_assert_ptr_nonnull(strstr(out, "min_print_speed"));
	ck_assert_ptr_null(strstr(out, "repaired"));
	ck_assert(!tu_file_exists(gc));
	/* Repairing and slicing the bracket takes seconds; refusing it, a
	 * process start and a file read (well under a second even under ASan). */
	ck_assert_msg(ms < 1000, "refused after %.0f ms", ms);
	/* one rule for every command that loads it: printers --show, repair,
	 * x3g and send refuse it with the same 2 */
	ck_assert_int_eq(tu_run(out, sizeof(out), "printers --show '%s'", ini), 2);
	ck_assert_ptr_nonnull(strstr(out, "line 2: min_print_speed"));
	ck_assert_int_eq(tu_run(out, sizeof(out), "repair docs/examples/bracket.stl -o '%s' "
				"--printer '%s'", tu_path("mps0.stl"), ini), 2);
	ck_assert_int_eq(tu_run(out, sizeof(out), "x3g tests/data/prusaslicer-mk3s-cube.gcode -o '%s' "
				"--printer '%s'", tu_path("mps0.x3g"), ini), 2);
	ck_assert_int_eq(tu_run(out, sizeof(out), "send tests/data/prusaslicer-mk3s-cube.gcode --port "
				"/nonexistent --printer '%s'", ini), 2);
	/* A derived value is checked too: 1000% of perimeter_speed 200 is
	 * beyond the declared external_perimeter_speed range. */
	load_bad("perimeter_speed = 200\nexternal_perimeter_speed = 1000%\n", ST_ERR_RANGE,
		 "cannot be sliced", "external_perimeter_speed", NULL);
}
END_TEST

/* Every key the loader binds is declared, in declaration order, and every
 * declared key a profile may set is bound; every default loads. */
START_TEST(test_bindings_match_declaration)
{
	size_t n = settings_count(), bound = 0;
	const char *prev = NULL;

	for (size_t i = 0; i < n; i++) {
		const struct setting *s = settings_at(i);

		ck_assert_msg(prof_find_def(s->name), "%s", s->name);
		bound++;
		prev = s->name;
	}
	ck_assert_ptr_nonnull(prev);
	ck_assert_uint_gt(bound, 80);
	ck_assert_ptr_null(prof_find_def("no_such_key"));
}
END_TEST

/* docs/printers.md's key tables are `stratum printers --keys`, byte for byte. */
START_TEST(test_doc_matches_declaration)
{
	static char doc[1 << 17], keys[1 << 16];
	const char *a = tu_read_between("docs/printers.md", doc, sizeof(doc),
					"<!-- keys:begin -->\n", "<!-- keys:end -->");

	ck_assert_int_eq(tu_run(keys, sizeof(keys), "printers --keys"), 0);
	ck_assert_msg(!strcmp(a, keys),
		      "docs/printers.md's key tables differ from `stratum printers --keys`; "
		      "regenerate them from slicer/settings.c");
}
END_TEST

Suite *profile_suite(void)
{
	Suite *s = suite_create("profile");
	TCase *shipped = tcase_create("shipped");
	TCase *load = tcase_create("load");
	TCase *errors = tcase_create("errors");
	TCase *access = tcase_create("access");
	TCase *find = tcase_create("find");
	TCase *cli = tcase_create("cli");

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

	tcase_add_test(access, test_raw_keys);
	tcase_add_test(access, test_write_round_trip);
	tcase_add_test(access, test_print_mode_keys);
	tcase_add_test(access, test_json);
	suite_add_tcase(s, access);

	tcase_add_test(find, test_find_by_name);
	tcase_add_test(find, test_list);
	suite_add_tcase(s, find);

	tcase_add_test(cli, test_cli_list_json);
	tcase_add_test(cli, test_cli_table);
	tcase_add_test(cli, test_cli_show);
	tcase_add_test(cli, test_cli_bad_profile_in_dir);
	tcase_add_test(cli, test_unsliceable_profile_fails_at_load);
	tcase_add_test(cli, test_doc_matches_declaration);
	tcase_add_test(access, test_bindings_match_declaration);
	tcase_set_timeout(cli, 60);
	suite_add_tcase(s, cli);
	profile_find_tcases(s);
	profile_shipped_tcases(s);
	return s;
}
