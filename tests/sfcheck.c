/*
 * sfcheck.c - Sailfish simulator log checks shared by suites (sfcheck.h).
 */
#include <check.h>
#include <stdlib.h>
#include <string.h>

#include "sfcheck.h"
#include "testutil.h"

static char sfc_out[1 << 16];

json_t *sfc_reference(const char *gcode, const char *x3g, const char *dec, size_t min)
{
	json_error_t je;
	int rc = tu_run(sfc_out, sizeof(sfc_out), "x3g %s -o %s --printer " SFC_PRINTER, gcode,
			x3g);
	ck_assert_msg(rc == 0, "x3g: exit %d: %s", rc, sfc_out);
	rc = tu_run(sfc_out, sizeof(sfc_out), "x3g --decode %s --json >%s", x3g, dec);
	ck_assert_msg(rc == 0, "x3g --decode: exit %d: %s", rc, sfc_out);
	json_t *o = json_load_file(dec, 0, &je);
	ck_assert_msg(o != NULL, "%s: %s", dec, je.text);
	json_t *cmds = json_incref(json_object_get(o, "commands"));
	json_decref(o);
	ck_assert(json_is_array(cmds));
	ck_assert_uint_ge(json_array_size(cmds), min);
	return cmds;
}

/* A field of a decoded command as an integer. */
static long field(json_t *cmd, const char *name)
{
	json_t *v = json_object_get(json_object_get(cmd, "fields"), name);
	ck_assert_msg(json_is_number(v), "no field %s", name);
	return (long)json_number_value(v);
}

void sfc_check_log(FILE *f, json_t *cmds, bool fields)
{
	char line[512];

	for (size_t i = 0; i < json_array_size(cmds); i++) {
		unsigned long long seq;
		unsigned code;
		json_t *c = json_array_get(cmds, i);

		ck_assert_msg(fgets(line, sizeof(line), f), "only %zu of %zu commands executed", i,
			      json_array_size(cmds));
		ck_assert_msg(sscanf(line, "%llu %u", &seq, &code) == 2, "log line: %s", line);
		ck_assert_uint_eq(seq, i + 1);
		ck_assert_msg(code == json_integer_value(json_object_get(c, "code")),
			      "command %zu: code %u executed, %lld expected", i + 1, code,
			      (long long)json_integer_value(json_object_get(c, "code")));
		const char *p = strstr(line, " X=");
		if (fields && p) {
			long x, y, z, a, b;
			ck_assert_int_eq(sscanf(p, " X=%ld Y=%ld Z=%ld A=%ld B=%ld", &x, &y, &z, &a,
						&b), 5);
			ck_assert_msg(x == field(c, "x") && y == field(c, "y") && z == field(c, "z") &&
					      a == field(c, "a") && b == field(c, "b"),
				      "command %zu: %s", i + 1, line);
		}
		if (fields && code == 155) {
			p = strstr(line, " rate=");
			ck_assert_ptr_nonnull(p);
			ck_assert_int_eq(atol(p + 6), field(c, "dda_rate"));
		}
		if (fields && code == 136 && (p = strstr(line, " value=")))
			ck_assert_int_eq(atol(p + 7), field(c, "value"));
	}
}
