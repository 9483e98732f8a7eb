/*
 * check_profile_cli.c - printer profiles, part of the profile suite
 * (check_profile.c): raw keys, round trips through profile_write, JSON,
 * NAME resolution and listing, and the `stratum printers` command end to
 * end, with the settings declaration and its doc.
 */
#include <check.h>
#include <errno.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "ini.h"
#include "printer_profile.h"
#include "profile.h"
#include "profile_int.h"
#include "profiletest.h"
#include "settings.h"
#include "suites.h"
#include "testutil.h"

static char out[1 << 16];

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

/* Every declared key is found by its name as itself (names are unique, so
 * the sorted lookup finds what a scan in declaration order would). */
START_TEST(test_every_key_found_as_itself)
{
	for (size_t i = 0; i < settings_count(); i++) {
		const struct setting *s = settings_at(i);
		ck_assert_msg(settings_find(s->name) == s, "%s", s->name);
	}
	ck_assert_ptr_null(settings_find("no_such_key"));
	ck_assert_ptr_null(settings_find(""));
	ck_assert_ptr_null(settings_find(NULL));
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

void profile_cli_tcases(Suite *s)
{
	TCase *access = tcase_create("access");
	TCase *find = tcase_create("find");
	TCase *cli = tcase_create("cli");

	tcase_add_test(access, test_raw_keys);
	tcase_add_test(access, test_write_round_trip);
	tcase_add_test(access, test_print_mode_keys);
	tcase_add_test(access, test_json);
	tcase_add_test(access, test_bindings_match_declaration);
	tcase_add_test(access, test_every_key_found_as_itself);
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
	tcase_set_timeout(cli, 60);
	suite_add_tcase(s, cli);
}
