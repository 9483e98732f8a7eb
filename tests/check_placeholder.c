/*
 * check_placeholder.c - PrusaSlicer's placeholder language
 * (slicer/placeholder.h): each construct, PrusaSlicer's types, the bundled
 * MK3S filament G-code, and errors that name the line and column.
 */
#include <check.h>
#include <stdlib.h>
#include <string.h>

#include "placeholder.h"
#include "suites.h"

static struct ph_vars *vars(void)
{
	struct ph_vars *v = ph_vars_new(NULL);
	struct st_error e = {0};
	double t[2] = {215, 220};

	ck_assert_ptr_nonnull(v);
	ck_assert_int_eq(ph_vars_set_numbers(v, "temperature", PH_INT, t, 2, true, &e), 0);
	ck_assert_int_eq(ph_vars_set_number(v, "layer_height", PH_REAL, 0.2, &e), 0);
	ck_assert_int_eq(ph_vars_set_number(v, "layer_num", PH_INT, 3, &e), 0);
	ck_assert_int_eq(ph_vars_set_number(v, "initial_tool", PH_INT, 0, &e), 0);
	ck_assert_int_eq(ph_vars_set_number(v, "spiral", PH_BOOL, 0, &e), 0);
	ck_assert_int_eq(ph_vars_set_config(v, "printer_notes",
					    "Keep\nPRINTER_VENDOR_PRUSA3D\nPRINTER_MODEL_MK3\n", &e),
			 0);
	ck_assert_int_eq(ph_vars_set_config(v, "nozzle_diameter", "0.4", &e), 0);
	ck_assert_int_eq(ph_vars_set_config(v, "wipe", "1", &e), 0);
	ck_assert_int_eq(ph_vars_set_config(v, "filament_settings_id", "\"Prusament PLA\"", &e), 0);
	ck_assert_int_eq(ph_vars_set_config(v, "max_print_height", "210", &e), 0);
	ck_assert_int_eq(ph_vars_set_config(v, "fill_density", "15%", &e), 0);
	return v;
}

/* text expands to want. */
static void expands(const struct ph_vars *v, const char *text, const char *want)
{
	struct st_error e = {0};
	char *out = NULL;
	int rc = ph_expand(text, "start_gcode", v, 0, &out, &e);

	ck_assert_msg(rc == 0, "%s: %s", text, e.msg);
	ck_assert_msg(!strcmp(out, want), "%s: got '%s', want '%s'", text, out, want);
	free(out);
}

/* text is refused with code, the message holding msg. */
static void refused(const struct ph_vars *v, const char *text, int code, const char *msg)
{
	struct st_error e = {0};
	char *out = (char *)1;
	int rc = ph_expand(text, "start_gcode", v, 0, &out, &e);

	ck_assert_msg(rc == code, "%s: rc %d, want %d (%s)", text, rc, code, e.msg);
	ck_assert_ptr_null(out);
	ck_assert_msg(strstr(e.msg, msg), "%s: message '%s' lacks '%s'", text, e.msg, msg);
}

START_TEST(legacy_and_braces)
{
	struct ph_vars *v = vars();

	expands(v, "M104 S[temperature] [temperature_1] {temperature[1]} {temperature}",
		"M104 S215 220 220 215");
	expands(v, "[temperature[initial_tool]] {temperature[initial_tool]}", "215 215");
	expands(v, "; [not a key] [ x", "; [not a key] [ x");
	expands(v, "[wipe] {spiral} [spiral] {fill_density}", "1 false 0 15");
	expands(v, "{filament_settings_id[initial_tool]}", "Prusament PLA");
	ph_vars_free(v);
}
END_TEST

START_TEST(arithmetic_and_types)
{
	struct ph_vars *v = vars();

	/* int / int stays whole, as in PrusaSlicer; a real prints as %g. */
	expands(v, "{7/2} {7.0/2} {7%3} {2*3+4*5} {(1+2)*3} {2-3-4} {-(2)} {layer_height*2}",
		"3 3.5 1 26 9 -5 -2 0.4");
	expands(v, "{max_print_height/4} {max_print_height/4.0}", "52 52.5");
	expands(v, "{\"a\" + 1 + layer_height}", "a10.2");
	expands(v, "{min(layer_num, 2.5)} {max(2,3)} {int(3.7)} {round(3.5)}", "2.5 3 3 4");
	expands(v, "{digits(layer_height,1,2)} {zdigits(3,3)}", "0.20 003");
	ph_vars_free(v);
}
END_TEST

START_TEST(conditions)
{
	struct ph_vars *v = vars();

	expands(v, "{1 < 2} {2 <= 2} {3 > 4} {3 >= 4} {1 == 1.0} {1 != 2} {1 <> 1}",
		"true true false false true true false");
	expands(v, "{\"abc\" == \"abc\"} {\"x\" < \"y\"} {true and not false} {false || true}",
		"true true true true");
	expands(v, "{layer_num > 2 ? \"big\" : \"small\"} {!(1 < 2) or 2 >= 2}", "big true");
	expands(v, "{printer_notes =~ /.*PRINTER_MODEL_MK3.*/} {printer_notes !~ /.*MK2.*/}",
		"true true");
	expands(v, "{if layer_num == 2}two{elsif layer_num == 3}three{else}other{endif}", "three");
	expands(v, "{if layer_num == 9}x{else}else{endif}", "else");
	expands(v, "{if true}a{if false}b{else}c{endif}d{endif}", "acd");
	/* A config's 0/1 may stand for a bool, as PrusaSlicer writes bools. */
	expands(v, "{if wipe[0]}W{endif}{if not wipe}N{else}n{endif}", "Wn");
	/* A branch not taken is read for syntax only. */
	expands(v, "{if false}{undefined_var}{1/0}{endif}ok", "ok");
	/* The bundled MK3S filament's start G-code (PrusaResearch.ini 1.5). */
	expands(v, "M900 K{if printer_notes=~/.*PRINTER_MODEL_MINI.*/ and nozzle_diameter[0]==0.6}"
		   "0.12{elsif printer_notes=~/.*PRINTER_MODEL_MK3.*/ and "
		   "nozzle_diameter[0]==0.4}0.05{else}0{endif}",
		"M900 K0.05");
	ph_vars_free(v);
}
END_TEST

START_TEST(errors_name_line_and_column)
{
	struct ph_vars *v = vars();
	bool b;
	struct st_error e = {0};

	refused(v, "G28\nG1 Z{foo}", ST_ERR_PARSE, "start_gcode: line 2, column 6: unknown placeholder {foo}");
	refused(v, "G1 Z[bogus]", ST_ERR_PARSE, "line 1, column 5: unknown placeholder [bogus]");
	refused(v, "line1\nline2 {if true}x", ST_ERR_PARSE, "line 2, column 7: {if} has no {endif}");
	refused(v, "{endif}", ST_ERR_PARSE, "{endif} without {if}");
	refused(v, "{if true}{else}{else}{endif}", ST_ERR_PARSE, "column 16: {else} after {else}");
	refused(v, "M104 {temperature", ST_ERR_PARSE, "expected '}' before the end");
	refused(v, "{if 1}x{endif}", ST_ERR_RANGE, "need a condition");
	refused(v, "{1/0}", ST_ERR_RANGE, "column 3: division by zero");
	refused(v, "{temperature[2]}", ST_ERR_UNSUPPORTED, "index 2 is out of range");
	refused(v, "[temperature_5]", ST_ERR_UNSUPPORTED, "use [temperature_0]");
	refused(v, "{1 and true}", ST_ERR_RANGE, "'and' needs conditions");
	refused(v, "{layer_num =~ /3/}", ST_ERR_RANGE, "must be a string");
	refused(v, "{\"abc}", ST_ERR_PARSE, "no closing '\"'");
	ck_assert_int_eq(ph_eval_bool("nozzle_diameter[0]==0.4 and printer_notes=~/.*MK3.*/", "c", v,
				      &b, &e),
			 0);
	ck_assert(b);
	ck_assert_int_eq(ph_eval_bool("1 + 1", "c", v, &b, &e), ST_ERR_RANGE);
	ph_vars_free(v);
}
END_TEST

Suite *placeholder_suite(void)
{
	Suite *s = suite_create("placeholder");
	TCase *t = tcase_create("expand");

	tcase_add_test(t, legacy_and_braces);
	tcase_add_test(t, arithmetic_and_types);
	tcase_add_test(t, conditions);
	tcase_add_test(t, errors_name_line_and_column);
	suite_add_tcase(s, t);
	return s;
}
