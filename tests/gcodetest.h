/*
 * gcodetest.h - what the gcode suite's files share (check_gcode.c,
 * check_gcode_errors.c, check_gcode_io.c): parse a line and check it parsed,
 * or that it was refused with the words expected in the message.
 */
#ifndef STRATUM_TESTS_GCODETEST_H
#define STRATUM_TESTS_GCODETEST_H

#include <stddef.h>
#include <string.h>

#include "gcode.h"

/* Parse s (NUL-terminated) and fail the test with the message on error. */
void parse_ok(const char *s, struct gcode_line *l);

/*
 * Parse (buf, len), expect ST_ERR_PARSE and a message containing every
 * string of the NULL-terminated list; the output struct must be unchanged.
 */
void parse_bad_n(const char *buf, size_t len, ...);

#define parse_bad(s, ...) parse_bad_n((s), strlen(s), __VA_ARGS__, (const char *)NULL)

/* Word i must be letter with value v (exactly). */
void want_word(const struct gcode_line *l, size_t i, char letter, double v);

#endif
