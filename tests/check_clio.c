/*
 * check_clio.c - the binary's answers through host/clio.h: `print --json`
 * prints its object on early failures too.  Part of the cli suite.
 */
#include <check.h>
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "suites.h"
#include "testutil.h"

static char out[1 << 16];

/* The last line of text that parses as a JSON object (NULL when none). */
static json_t *json_answer(char *text)
{
	char *line = NULL, *save = NULL;

	for (char *t = strtok_r(text, "\n", &save); t; t = strtok_r(NULL, "\n", &save))
		if (t[0] == '{')
			line = t;
	return line ? json_loads(line, 0, NULL) : NULL;
}

/* `print ARGS --json` with stderr dropped: the object, its exit status checked. */
static json_t *print_json_fails(const char *args, int want)
{
	json_t *o;
	int rc = tu_run(out, sizeof(out), "print %s --json 2>/dev/null", args);

	ck_assert_msg(rc == want, "print %s: exit %d, wanted %d: %s", args, rc, want, out);
	o = json_answer(out);
	ck_assert_msg(o != NULL, "print %s --json printed no object: '%s'", args, out);
	ck_assert(json_is_false(json_object_get(o, "ok")));
	ck_assert_int_eq(json_integer_value(json_object_get(o, "exit")), want);
	ck_assert_msg(json_string_length(json_object_get(o, "error")) > 0, "no error text");
	return o;
}

START_TEST(print_json_on_early_failures)
{
	json_t *o;

	setenv("STRATUM_STATE_DIR", tu_path("rio-state"), 1);
	o = print_json_fails("/nonexistent/model.stl --printer generic-marlin", 65);
	ck_assert_msg(strstr(json_string_value(json_object_get(o, "error")), "/nonexistent/model.stl"),
		      "error: %s", json_string_value(json_object_get(o, "error")));
	json_decref(o);
	o = print_json_fails("docs/examples/bracket.stl --printer no-such-printer", 2);
	ck_assert_ptr_nonnull(strstr(json_string_value(json_object_get(o, "error")), "no-such-printer"));
	json_decref(o);
	json_decref(print_json_fails("docs/examples/bracket.stl", 2));		/* no printer */
	json_decref(print_json_fails("docs/examples/bracket.stl --printer generic-marlin "
				     "--dry-run", 2));			/* no -o */
	json_decref(print_json_fails("--bogus", 2));				/* parser */
}
END_TEST

void cli_stdio_tcases(Suite *s)
{
	TCase *tc = tcase_create("stdio");

	tcase_set_timeout(tc, 120);
	tcase_add_test(tc, print_json_on_early_failures);
	suite_add_tcase(s, tc);
}
