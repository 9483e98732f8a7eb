/*
 * check_profile_find.c - where --printer NAME is found (host/profile.h,
 * profile_find): the user's profiles in $XDG_CONFIG_HOME/stratum/printers,
 * and PrusaSlicer's vendor bundles by preset name or slug (issue 18 item 6).
 * Part of the profile suite.
 */
#include <check.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "profile.h"
#include "suites.h"
#include "testutil.h"

/* A bundle with one printer preset in a scratch vendor dir ($STRATUM_VENDOR_DIR). */
static void tiny_vendor_dir(void)
{
	char dir[512];

	snprintf(dir, sizeof(dir), "%s", tu_path("vendors"));
	mkdir(dir, 0755);
	tu_write_str(tu_path("vendors/Tiny.ini"),
		     "[vendor]\nname = Tiny\n\n[printer:*common*]\nbed_shape = 0x0,180x0,180x180,0x180\n"
		     "\n[printer:Tiny Printer Mk2 & Co+]\ninherits = *common*\nprinter_model = TINY2\n"
		     "default_print_profile = 0.2mm\ndefault_filament_profile = PLA\n\n"
		     "[print:0.2mm]\nlayer_height = 0.2\n\n[filament:PLA]\ntemperature = 205\n"
		     "compatible_printers = \"Tiny Printer Mk2 & Co+\"\n\n"
		     "[printer:Tiny Three]\ninherits = *common*\nprinter_model = TINY3\n"
		     "default_print_profile = 0.3mm\n\n[print:0.3mm Other]\nlayer_height = 0.25\n"
		     "compatible_printers_condition = printer_model=~/.*OTHER.*/\n\n"
		     "[print:0.3mm Tiny3]\nlayer_height = 0.3\n"
		     "compatible_printers_condition = printer_model==\"TINY3\" and "
		     "nozzle_diameter[0]==0.4\n\n[filament:PETG listed]\ntemperature = 240\n"
		     "compatible_printers = \"Tiny Three\";\"Tiny Four\"\n");
	setenv("STRATUM_VENDOR_DIR", dir, 1);
}

START_TEST(vendor_preset_by_name_and_slug)
{
	const char *names[] = {"Tiny Printer Mk2 & Co+", "tiny-printer-mk2-co"};
	struct st_error err = {0};
	struct profile *p = NULL;

	tiny_vendor_dir();
	for (size_t i = 0; i < 2; i++) {
		ck_assert_msg(profile_find(names[i], &p, &err) == 0, "%s: %s", names[i], err.msg);
		ck_assert_str_eq(p->printer_model, "TINY2");
		ck_assert_str_eq(profile_printer_name(p), "Tiny Printer Mk2 & Co+");
		ck_assert(p->bed_max_x == 180 && p->temperature[0] == 205);
		profile_free(p);
		p = NULL;
	}
	/* Abstract presets are not printers; an unknown name says where it looked. */
	ck_assert_int_eq(profile_find("common", &p, &err), ST_ERR_ARG);
	ck_assert_msg(strstr(err.msg, "PrusaSlicer's bundles"), "%s", err.msg);
	ck_assert_int_eq(profile_find("No Such Printer", &p, &err), ST_ERR_ARG);
	ck_assert_msg(strstr(err.msg, "nor a printer preset of PrusaSlicer's bundles"), "%s",
		      err.msg);
}
END_TEST

/* A default preset the bundle lacks (or none named): the first compatible
 * one, a name starting with the default's first (PrusaSlicer's choice). */
START_TEST(vendor_missing_default_preset)
{
	struct st_error err = {0};
	struct profile *p = NULL;

	tiny_vendor_dir();
	ck_assert_msg(profile_find("Tiny Three", &p, &err) == 0, "%s", err.msg);
	ck_assert(p->layer_height == 0.3);     /* [print:0.3mm Tiny3]: its condition holds */
	ck_assert_int_eq(p->temperature[0], 240); /* PLA lists another printer, PETG this one */
	ck_assert_str_eq(profile_get(p, "print_settings_id"), "0.3mm Tiny3");
	profile_free(p);
}
END_TEST

/* $XDG_CONFIG_HOME/stratum/printers comes before the shipped profiles. */
START_TEST(user_profiles_dir)
{
	char dir[512];
	struct st_error err = {0};
	struct profile *p = NULL;

	unsetenv("STRATUM_PRINTERS_DIR");
	snprintf(dir, sizeof(dir), "%s", tu_path("xdg"));
	mkdir(dir, 0755);
	mkdir(tu_path("xdg/stratum"), 0755);
	mkdir(tu_path("xdg/stratum/printers"), 0755);
	tu_write_str(tu_path("xdg/stratum/printers/generic-marlin.ini"),
		     "name = My own\nprinter_model = MINE\n");
	tu_write_str(tu_path("xdg/stratum/printers/only-mine.ini"), "name = Only mine\n");
	setenv("XDG_CONFIG_HOME", dir, 1);
	ck_assert_msg(profile_find("only-mine", &p, &err) == 0, "%s", err.msg);
	ck_assert_str_eq(p->name, "Only mine");
	profile_free(p);
	ck_assert_msg(profile_find("generic-marlin", &p, &err) == 0, "%s", err.msg);
	ck_assert_str_eq(p->printer_model, "MINE");
	profile_free(p);
}
END_TEST

void profile_find_tcases(Suite *s)
{
	TCase *tc = tcase_create("find vendor");

	tcase_add_test(tc, vendor_preset_by_name_and_slug);
	tcase_add_test(tc, vendor_missing_default_preset);
	tcase_add_test(tc, user_profiles_dir);
	suite_add_tcase(s, tc);
}
