/*
 * gcodetest.c - the helpers of gcodetest.h.
 */
#include <check.h>
#include <stdarg.h>
#include <string.h>

#include "gcodetest.h"

void parse_ok(const char *s, struct gcode_line *l)
{
	struct st_error err = {0};
	int rc = gcode_parse(s, strlen(s), 0, l, &err);

	ck_assert_msg(rc == 0, "parse of \"%s\" failed (%d): %s", s, rc, err.msg);
}

void parse_bad_n(const char *buf, size_t len, ...)
{
	struct gcode_line l, before;
	struct st_error err = {0};
	const char *needle;
	va_list ap;
	int rc;

	memset(&l, 0x5a, sizeof(l));
	before = l;
	rc = gcode_parse(buf, len, 0, &l, &err);
	ck_assert_msg(rc == ST_ERR_PARSE, "\"%.*s\": wanted ST_ERR_PARSE, got %d", (int)len, buf,
		      rc);
	ck_assert_int_eq(err.code, ST_ERR_PARSE);
	ck_assert_msg(memcmp(&l, &before, sizeof(l)) == 0, "\"%.*s\": output changed on error",
		      (int)len, buf);
	va_start(ap, len);
	while ((needle = va_arg(ap, const char *)))
		ck_assert_msg(strstr(err.msg, needle), "\"%.*s\": '%s' not in message: %s",
			      (int)len, buf, needle, err.msg);
	va_end(ap);
}

void want_word(const struct gcode_line *l, size_t i, char letter, double v)
{
	ck_assert_uint_lt(i, l->nwords);
	ck_assert_int_eq(l->words[i].letter, letter);
	ck_assert_msg(l->words[i].has_value, "word %c has no value", letter);
	ck_assert_msg(l->words[i].value == v, "word %c: %.17g != %.17g", letter, l->words[i].value,
		      v);
}
