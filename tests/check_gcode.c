/*
 * check_gcode.c - serial/gcode.c: words and numbers, comments, checksums,
 * string-argument commands, the texts the firmware accepts (PrusaSlicer's
 * real output among them), every refused input (with its column), the
 * classifier and blocking flags, slicer layer comments, numbered-line
 * round trips, the streaming reader, and a randomized robustness test.
 */
#include <check.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gcode.h"
#include "suites.h"

/* Parse s (NUL-terminated) and fail the test with the message on error. */
static void parse_ok(const char *s, struct gcode_line *l)
{
	struct st_error err = {0};
	int rc = gcode_parse(s, strlen(s), 0, l, &err);

	ck_assert_msg(rc == 0, "parse of \"%s\" failed (%d): %s", s, rc, err.msg);
}

/*
 * Parse (buf, len), expect ST_ERR_PARSE and a message containing every
 * string of the NULL-terminated list; the output struct must be unchanged.
 */
static void parse_bad_n(const char *buf, size_t len, ...)
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

#define parse_bad(s, ...) parse_bad_n((s), strlen(s), __VA_ARGS__, (const char *)NULL)

/* Word i must be letter with value v (exactly). */
static void want_word(const struct gcode_line *l, size_t i, char letter, double v)
{
	ck_assert_uint_lt(i, l->nwords);
	ck_assert_int_eq(l->words[i].letter, letter);
	ck_assert_msg(l->words[i].has_value, "word %c has no value", letter);
	ck_assert_msg(l->words[i].value == v, "word %c: %.17g != %.17g", letter, l->words[i].value,
		      v);
}

START_TEST(test_words)
{
	static const struct {
		const char *in, *text;
	} cases[] = {
	    {"G1 X10 Y-2.5 E0.123 F1800", "G1 X10 Y-2.5 E0.123 F1800"},
	    {"G1X10Y-2.5E0.123F1800", "G1 X10 Y-2.5 E0.123 F1800"},
	    {"  \tG1\tX10   Y-2.5 E0.123\tF1800  \r\n", "G1 X10 Y-2.5 E0.123 F1800"},
	    {"g1 x10 y-2.5 e0.123 f1800\n", "G1 X10 Y-2.5 E0.123 F1800"},
	    {"G01 X 10 Y -2.5 E0.123 F1800\r", "G1 X10 Y-2.5 E0.123 F1800"},
	};
	struct gcode_line l;

	for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
		parse_ok(cases[i].in, &l);
		ck_assert_int_eq(l.letter, 'G');
		ck_assert_int_eq(l.number, 1);
		ck_assert_int_eq(l.subcode, -1);
		ck_assert_int_eq(l.kind, GCODE_KIND_MOTION);
		ck_assert_uint_eq(l.nwords, 4);
		want_word(&l, 0, 'X', 10);
		want_word(&l, 1, 'Y', -2.5);
		want_word(&l, 2, 'E', 0.123);
		want_word(&l, 3, 'F', 1800);
		ck_assert_str_eq(l.text, cases[i].text);
		ck_assert_uint_eq(l.text_len, strlen(cases[i].text));
		ck_assert(!l.has_comment && !l.has_paren && !l.has_checksum && !l.has_line_number);
		ck_assert(!l.has_string);
		ck_assert_uint_eq(l.string_off, l.text_len);
	}
}
END_TEST

START_TEST(test_word_details)
{
	struct gcode_line l;
	double v = -1;

	parse_ok("G28 X Y", &l);
	ck_assert_int_eq(l.kind, GCODE_KIND_HOME);
	ck_assert_uint_eq(l.nwords, 2);
	ck_assert(!l.words[0].has_value && l.words[0].letter == 'X');
	ck_assert(!l.words[1].has_value && l.words[1].letter == 'Y');
	ck_assert_uint_eq(l.words[1].column, 7);
	ck_assert_str_eq(l.text, "G28 X Y");
	ck_assert_ptr_nonnull(gcode_find_word(&l, 'x'));
	ck_assert_ptr_null(gcode_find_word(&l, 'Z'));
	ck_assert(!gcode_word_value(&l, 'X', &v));
	ck_assert(v == -1);

	parse_ok("G28XY", &l);
	ck_assert_str_eq(l.text, "G28 X Y");

	/* A bare F on a move keeps the feed rate, as in Marlin. */
	parse_ok("G1 Z15.0 F ;move the platform down 15mm", &l);
	ck_assert_uint_eq(l.nwords, 2);
	ck_assert(!l.words[1].has_value && l.words[1].letter == 'F');
	ck_assert(!gcode_word_value(&l, 'F', &v));
	ck_assert_str_eq(l.text, "G1 Z15.0 F");

	/* Marlin and grbl read X1E3 as two words; the number reader alone refuses 1e3. */
	parse_ok("G1 X1E3", &l);
	want_word(&l, 0, 'X', 1);
	want_word(&l, 1, 'E', 3);

	/* Numbers keep the text as written. */
	parse_ok("G1 X+5 Y.5 Z-.5 E5. F010", &l);
	want_word(&l, 0, 'X', 5);
	want_word(&l, 1, 'Y', 0.5);
	want_word(&l, 2, 'Z', -0.5);
	want_word(&l, 3, 'E', 5);
	want_word(&l, 4, 'F', 10);
	ck_assert_str_eq(l.text, "G1 X+5 Y.5 Z-.5 E5. F010");
	ck_assert(gcode_word_value(&l, 'z', &v) && v == -0.5);

	parse_ok("G29.1 P2", &l);
	ck_assert_int_eq(l.number, 29);
	ck_assert_int_eq(l.subcode, 1);
	ck_assert_str_eq(l.text, "G29.1 P2");
	ck_assert_int_eq(l.kind, GCODE_KIND_PROBE);

	parse_ok("M104 T1 S215", &l);
	ck_assert_int_eq(l.kind, GCODE_KIND_TEMP_SET);
	want_word(&l, 0, 'T', 1);
	want_word(&l, 1, 'S', 215);

	/* A second G word is a parameter, as in Marlin. */
	parse_ok("G90 G21", &l);
	ck_assert_int_eq(l.number, 90);
	want_word(&l, 0, 'G', 21);
}
END_TEST

START_TEST(test_comments)
{
	struct gcode_line l;

	parse_ok("G1 X1 ; move up  ", &l);
	ck_assert(l.has_comment);
	ck_assert_str_eq(l.comment, " move up");
	ck_assert_uint_eq(l.comment_len, 8);
	ck_assert_str_eq(l.text, "G1 X1");

	parse_ok("G1 (first) X1( second ; inner )Y2 ; tail (not a paren) ;x", &l);
	ck_assert_str_eq(l.text, "G1 X1 Y2");
	ck_assert_uint_eq(l.nwords, 2);
	ck_assert(l.has_paren);
	ck_assert_str_eq(l.paren, "first second ; inner");
	ck_assert_str_eq(l.comment, " tail (not a paren) ;x");

	parse_ok("(header) G1 X1", &l);
	ck_assert_str_eq(l.text, "G1 X1");

	parse_ok(";only a comment", &l);
	ck_assert_int_eq(l.letter, 0);
	ck_assert_int_eq(l.number, -1);
	ck_assert_int_eq(l.kind, GCODE_KIND_HOST_ONLY);
	ck_assert_str_eq(l.comment, "only a comment");
	ck_assert_uint_eq(l.text_len, 0);

	parse_ok("", &l);
	ck_assert_int_eq(l.kind, GCODE_KIND_HOST_ONLY);
	ck_assert(!l.has_comment);
	parse_ok(" \t \r\n", &l);
	ck_assert_int_eq(l.kind, GCODE_KIND_HOST_ONLY);
	parse_ok("(just a paren)", &l);
	ck_assert_int_eq(l.kind, GCODE_KIND_HOST_ONLY);
	ck_assert_str_eq(l.paren, "just a paren");
	parse_ok(";", &l);
	ck_assert(l.has_comment);
	ck_assert_uint_eq(l.comment_len, 0);

	/* Comments may carry UTF-8 (object names); commands may not. */
	parse_ok("; printing object W\xc3\xbcrfel.stl", &l);
	ck_assert_str_eq(l.comment, " printing object W\xc3\xbcrfel.stl");

	/* Long comments are kept in part and flagged; the line is fine. */
	{
		static char big[3000];

		memset(big, 'c', sizeof(big) - 1);
		big[0] = ';';
		big[sizeof(big) - 1] = '\0';
		parse_ok(big, &l);
		ck_assert(l.comment_truncated);
		ck_assert_uint_eq(l.comment_len, GCODE_COMMENT_MAX);
		ck_assert_uint_eq(strlen(l.comment), GCODE_COMMENT_MAX);
	}

	parse_bad("G1 X1 (open", "column 7", "unterminated '(' comment");
}
END_TEST

START_TEST(test_checksums)
{
	struct gcode_line l;
	struct st_error err = {0};
	char line[128];
	uint8_t cs = gcode_checksum("N123 G1 X1", 10);

	/* The value every Marlin host uses to reset the line counter. */
	ck_assert_uint_eq(gcode_checksum("N0 M110 N0", 10), 125);
	ck_assert_uint_eq(gcode_checksum("", 0), 0);

	snprintf(line, sizeof(line), "N123 G1 X1*%u\n", cs);
	parse_ok(line, &l);
	ck_assert(l.has_line_number && l.line_number == 123);
	ck_assert(l.has_checksum && l.checksum_ok);
	ck_assert_uint_eq(l.checksum, cs);
	ck_assert_uint_eq(l.checksum_computed, cs);
	ck_assert_str_eq(l.text, "G1 X1");
	ck_assert_uint_eq(l.nwords, 1);

	/* Leading blanks are not covered, a comment after the checksum is fine. */
	snprintf(line, sizeof(line), "  N123 G1 X1*%u ; done", cs);
	parse_ok(line, &l);
	ck_assert(l.checksum_ok);
	ck_assert_str_eq(l.comment, " done");

	/* Wrong checksum: refused, or kept and flagged on request. */
	snprintf(line, sizeof(line), "N123 G1 X1*%u", (unsigned)(cs ^ 1));
	{
		char want[64];

		snprintf(want, sizeof(want), "checksum %u does not match %u", (unsigned)(cs ^ 1),
			 (unsigned)cs);
		parse_bad(line, want);
	}
	ck_assert_int_eq(gcode_parse(line, strlen(line), GCODE_PARSE_KEEP_BAD_CHECKSUM, &l, &err),
			 0);
	ck_assert(l.has_checksum && !l.checksum_ok);
	ck_assert_uint_eq(l.checksum_computed, cs);

	/* M110: the first N is the line number, the second a parameter. */
	parse_ok("N0 M110 N0*125", &l);
	ck_assert(l.has_line_number && l.line_number == 0 && l.checksum_ok);
	ck_assert_int_eq(l.kind, GCODE_KIND_LINE_NUMBER);
	want_word(&l, 0, 'N', 0);
	parse_ok("M110 N100", &l);
	ck_assert(!l.has_line_number);
	want_word(&l, 0, 'N', 100);

	parse_ok("N2147483647 G4", &l);
	ck_assert_int_eq(l.line_number, 2147483647L);

	parse_bad("G1 X1*", "column 6", "checksum from 0 to 255");
	parse_bad("G1 X1*256", "checksum from 0 to 255");
	parse_bad("G1 X1*1234", "checksum from 0 to 255");
	parse_bad("G1 X1*12 Y2", "column 10", "text after the checksum");
	parse_bad("G1 X1*12Y", "checksum from 0 to 255");
	parse_bad("N G1", "column 1", "N without a number");
	parse_bad("N-5 G1", "N without a number");
	parse_bad("N2147483648 G1", "'N2147483648'", "out of range");
	parse_bad("N99999999999999 G1", "out of range");
	parse_bad("N12x G1", "column 4", "'x' is not a command");
}
END_TEST

START_TEST(test_tools)
{
	struct gcode_line l;

	parse_ok("T0", &l);
	ck_assert_int_eq(l.letter, 'T');
	ck_assert_int_eq(l.number, 0);
	ck_assert_int_eq(l.kind, GCODE_KIND_TOOL_CHANGE);
	parse_ok("t1 ; second extruder", &l);
	ck_assert_int_eq(l.number, 1);
	ck_assert_str_eq(l.text, "T1");
	parse_ok("M6 T2", &l);
	ck_assert_int_eq(l.kind, GCODE_KIND_TOOL_CHANGE);
	want_word(&l, 0, 'T', 2);
	parse_bad("T1.5", "'T1.5' is not a command");

	/* Prusa MMU filament commands (PrusaSlicer's MK2S MMU and MK3 MMU2
	 * start G-code): Prusa's firmware and Marlin's PRUSA_MMU2 read them. */
	parse_ok("T? ; let the user pick", &l);
	ck_assert_int_eq(l.letter, 'T');
	ck_assert_int_eq(l.number, -1);
	ck_assert_int_eq(l.kind, GCODE_KIND_TOOL_CHANGE);
	ck_assert_str_eq(l.text, "T?");
	ck_assert_str_eq(l.text + l.string_off, "?");
	parse_ok("Tx", &l);
	ck_assert_str_eq(l.text, "Tx");
	parse_ok("Tc", &l);
	ck_assert_str_eq(l.text + l.string_off, "c");
	/* Anything else without a number is, to Marlin, an unknown command
	 * (its MMU reads x, not X): a text command, passed on as written. */
	static const char *const unknown[] = {"TX", "T?x", "T#"};
	for (size_t i = 0; i < sizeof(unknown) / sizeof(unknown[0]); i++) {
		parse_ok(unknown[i], &l);
		ck_assert_int_eq(l.letter, GCODE_LETTER_TEXT);
		ck_assert_str_eq(l.text, unknown[i]);
	}
}
END_TEST

/* Lines that are not G, M or T commands but start with a name: Klipper's
 * extended commands and macros, a toolchanger's bare T, text.  Marlin's
 * parser marks them '?' and answers "Unknown command" (Marlin
 * gcode/parser.cpp), Klipper runs them: kept as written, with their line
 * number and checksum, no words (issue 18). */
START_TEST(test_text_commands)
{
	static const struct {
		const char *line, *text;
	} cases[] = {
	    {"print_start EXTRUDER=215 BED=60 CHAMBER=0", "print_start EXTRUDER=215 BED=60 CHAMBER=0"},
	    {"START_PRINT ; the macro", "START_PRINT"},
	    {"  BED_MESH_CALIBRATE\t", "BED_MESH_CALIBRATE"},
	    {"SET_PRESSURE_ADVANCE ADVANCE=0.05 SMOOTH_TIME=0.04", "SET_PRESSURE_ADVANCE ADVANCE=0.05 SMOOTH_TIME=0.04"},
	    {"Start printing (the end)", "Start printing (the end)"},
	    {"T", "T"},
	    {"T ; active tool", "T"},
	    {"T-1 ; Make sure nothing is parked on the carriage", "T-1"},
	    {"G-1", "G-1"},
	    {"TURN_OFF_HEATERS", "TURN_OFF_HEATERS"},
	    {"M", "M"},
	    {"G X10", "G X10"},
	    {"_CLIENT_LINEAR_MOVE X=10", "_CLIENT_LINEAR_MOVE X=10"},
	    {"RESPOND MSG=\"Wärmen…\"", "RESPOND MSG=\"Wärmen…\""},
	};
	struct gcode_line l;
	char line[128];
	int n;

	for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
		parse_ok(cases[i].line, &l);
		ck_assert_msg(l.letter == GCODE_LETTER_TEXT, "%s: letter %d", cases[i].line, l.letter);
		ck_assert_int_eq(l.kind, GCODE_KIND_TEXT_COMMAND);
		ck_assert_str_eq(l.text, cases[i].text);
		ck_assert_uint_eq(l.nwords, 0);
		ck_assert(l.has_string);
		ck_assert_uint_eq(l.string_off, 0);
		ck_assert(gcode_is_blocking(l.kind));
	}
	/* numbered as the sender writes it, then read back as Marlin reads it */
	n = gcode_format_numbered(line, sizeof(line), 12, "START_PRINT EXTRUDER=215");
	ck_assert_int_gt(n, 0);
	parse_ok(line, &l);
	ck_assert(l.has_line_number && l.line_number == 12);
	ck_assert(l.has_checksum && l.checksum_ok);
	ck_assert_str_eq(l.text, "START_PRINT EXTRUDER=215");
	ck_assert_int_eq(l.kind, GCODE_KIND_TEXT_COMMAND);
	parse_bad("N12 START_PRINT*1", "checksum 1 does not match");
	/* '*' would cut the text at the firmware; a word alone could move */
	parse_bad("SET_MSG A*B", "'*' inside the text of SET_MSG");
	parse_bad("X10 Y10", "'X10' is not a command", "G, M or T");
	parse_bad("N5 Z0.2", "column 4", "'Z0.2' is not a command");
	parse_bad("#macro", "'#macro' is not a command");
	parse_bad("\xc3\xa9t\xc3\xa9", "non-ASCII byte");
}
END_TEST

START_TEST(test_string_args)
{
	struct gcode_line l;
	char line[128];

	parse_ok("M117 Hello World ; comment", &l);
	ck_assert(l.has_string);
	ck_assert_str_eq(l.text, "M117 Hello World");
	ck_assert_str_eq(l.text + l.string_off, "Hello World");
	ck_assert_str_eq(l.comment, " comment");
	ck_assert_int_eq(l.kind, GCODE_KIND_MESSAGE);
	ck_assert_uint_eq(l.nwords, 0);

	/* Inner spacing, parentheses and letters are text; ';' is not. */
	parse_ok("m117   Layer  2 (50%) X1.2.3 a+b  ", &l);
	ck_assert_str_eq(l.text + l.string_off, "Layer  2 (50%) X1.2.3 a+b");
	ck_assert_str_eq(l.text, "M117 Layer  2 (50%) X1.2.3 a+b");
	ck_assert(!l.has_paren && !l.has_checksum);

	parse_ok("M117", &l);
	ck_assert(l.has_string);
	ck_assert_str_eq(l.text, "M117");
	ck_assert_str_eq(l.text + l.string_off, "");

	parse_ok("M118 E1 hello host", &l);
	ck_assert_str_eq(l.text + l.string_off, "E1 hello host");
	parse_ok("M23 /models/part one.gco", &l);
	ck_assert_int_eq(l.kind, GCODE_KIND_OTHER);
	ck_assert_str_eq(l.text + l.string_off, "/models/part one.gco");

	/* A trailing *<digits> is the checksum. */
	snprintf(line, sizeof(line), "N7 M117 a+b*%u",
		 gcode_checksum("N7 M117 a+b", strlen("N7 M117 a+b")));
	parse_ok(line, &l);
	ck_assert(l.has_checksum && l.checksum_ok);
	ck_assert_str_eq(l.text + l.string_off, "a+b");
	ck_assert_int_eq(l.line_number, 7);
	/* Any other '*' is refused: Marlin's parser cuts the command at the
	 * first '*' and Prusa's firmware checksums up to it. */
	snprintf(line, sizeof(line), "N7 M117 a*b*%u",
		 gcode_checksum("N7 M117 a*b", strlen("N7 M117 a*b")));
	parse_bad(line, "column 10", "'*' inside the text of M117", "remove it");
	parse_bad("M117 a*b", "column 7", "'*' inside the text of M117");
	parse_bad("M23 part*.gco", "'*' inside the text of M23");

	/* M73 progress has ordinary words. */
	parse_ok("M73 P42 R10", &l);
	ck_assert_int_eq(l.kind, GCODE_KIND_MESSAGE);
	ck_assert(!l.has_string);
	want_word(&l, 0, 'P', 42);

	/* Host commands (OctoPrint '@'). */
	parse_ok("@pause now ; why", &l);
	ck_assert_int_eq(l.letter, '@');
	ck_assert_int_eq(l.kind, GCODE_KIND_HOST_ONLY);
	ck_assert_str_eq(l.text, "@pause now");
	ck_assert_str_eq(l.text + l.string_off, "pause now");
	parse_bad("@", "'@' without a host command name");

	/* UTF-8 in a message is the firmware's to show (Marlin's LCDs do). */
	parse_ok("M117 caf\xc3\xa9", &l);
	ck_assert_str_eq(l.text + l.string_off, "caf\xc3\xa9");
}
END_TEST

START_TEST(test_number_reader)
{
	static const struct {
		const char *in;
		double v;
	} good[] = {
	    {"0", 0},
	    {"+5", 5},
	    {".5", 0.5},
	    {"-.5", -0.5},
	    {"5.", 5},
	    {"007", 7},
	    {"0.1", 0.1},
	    {"123.456", 123.456},
	    {"-2.5", -2.5},
	    {"1.000000000000000000", 1},
	    {"0.0000000000000000000001", 1e-22},
	    {"999999999999999", 999999999999999.0},
	    {"3.14159265358979", 3.14159265358979},
	    {"0.30000000000000", 0.3},
	};
	static const char *const bad[] = {
	    "1e3",
	    "1E3",
	    "1.2.3",
	    "--1",
	    "+-1",
	    "nan",
	    "NaN",
	    "inf",
	    "-inf",
	    "0x10",
	    "",
	    ".",
	    "-",
	    "+",
	    " 1",
	    "1 ",
	    "1,5",
	    "1_000",
	    "1234567890123456",		 /* 16 significant digits */
	    "0000000000000000000000001", /* 25 characters */
	    "0.00000000000000000000001", /* 23 decimals in 25 characters */
	};
	struct st_error err = {0};
	double v;

	for (size_t i = 0; i < sizeof(good) / sizeof(good[0]); i++) {
		v = 42;
		ck_assert_msg(gcode_read_number(good[i].in, strlen(good[i].in), &v, &err) == 0,
			      "'%s' refused: %s", good[i].in, err.msg);
		ck_assert_msg(v == good[i].v, "'%s' read as %.17g", good[i].in, v);
	}
	v = 1;
	ck_assert_int_eq(gcode_read_number("-0", 2, &v, &err), 0);
	ck_assert(v == 0 && signbit(v));
	/* Not NUL-terminated: only len bytes are read. */
	ck_assert_int_eq(gcode_read_number("12345", 2, &v, &err), 0);
	ck_assert(v == 12);

	for (size_t i = 0; i < sizeof(bad) / sizeof(bad[0]); i++) {
		v = 42;
		err.msg[0] = '\0';
		ck_assert_msg(gcode_read_number(bad[i], strlen(bad[i]), &v, &err) == ST_ERR_PARSE,
			      "'%s' accepted as %.17g", bad[i], v);
		ck_assert_msg(v == 42, "'%s' changed the output", bad[i]);
		ck_assert_msg(strstr(err.msg, "is not a number"), "message: %s", err.msg);
	}
	ck_assert_int_eq(gcode_read_number(NULL, 0, &v, &err), ST_ERR_ARG);
}
END_TEST

START_TEST(test_rejects)
{
	parse_bad("G1 X1.2.3", "column 4: 'X1.2.3' is not a number");
	parse_bad("G1 X--1", "column 4: 'X--1' is not a number");
	parse_bad("G1 X1,5", "column 4: 'X1,5' is not a number");
	parse_bad("G1 X.", "'X.' is not a number");
	parse_bad("G1 X-", "'X-' is not a number");
	parse_bad("G1 X1234567890123456", "is not a number", "15 significant digits");
	parse_bad("G1 X1 X2", "column 7", "'X' appears twice", "column 4");
	parse_bad("G1 X", "column 4", "'X' without a value", "G1");
	parse_bad("G4 P", "'P' without a value");
	parse_bad("G1 E", "'E' without a value");
	parse_bad("G4 F", "'F' without a value");
	parse_bad("X10 Y10", "column 1", "'X10' is not a command", "G, M or T");
	parse_bad("N5 X10", "column 4", "'X10' is not a command");
	parse_bad("10 G1", "'10' is not a command");
	parse_bad("G123456", "over 5 digits");
	parse_bad("G1-5", "'G1-5' is not a command");
	parse_bad("G1.x", "bad subcode");
	parse_bad("G1 X1 #", "column 7", "unexpected character '#'");
	parse_bad("G1 X1 \"a\"", "unexpected character '\"'");
	parse_bad("G1 10", "column 4", "'10' has no word letter");
	parse_bad("G1 X\xff", "column 5: non-ASCII byte 0xff");
	parse_bad("\xef\xbb\xbfG1", "column 1: non-ASCII byte 0xef");
	parse_bad("G1\x01", "column 3: control byte 0x01");
	parse_bad("G1 X1\nG1 X2", "column 6: control byte 0x0a");
	parse_bad("G1 X1\r\r\n", "column 6: control byte 0x0d");
	parse_bad("G1 X1 ;bell\x07", "column 12: control byte 0x07");
	parse_bad_n("G1 X1\0Y2", 8, "column 6: control byte 0x00", (const char *)NULL);

	{
		struct gcode_line l;
		struct st_error err = {0};

		ck_assert_int_eq(gcode_parse(NULL, 3, 0, &l, &err), ST_ERR_ARG);
		ck_assert_int_eq(gcode_parse("G1", 2, 0, NULL, &err), ST_ERR_ARG);
		ck_assert_int_eq(gcode_parse(NULL, 0, 0, &l, &err), 0);
		ck_assert_int_eq(l.kind, GCODE_KIND_HOST_ONLY);
		/* err may be NULL */
		ck_assert_int_eq(gcode_parse("G1 X", 4, 0, &l, NULL), ST_ERR_PARSE);
	}
}
END_TEST

START_TEST(test_lengths)
{
	static char line[GCODE_RAW_MAX + 64];
	struct gcode_line l;
	size_t n;

	/* Exactly GCODE_LINE_MAX characters of command: accepted. */
	n = (size_t)snprintf(line, sizeof(line), "M117 ");
	memset(line + n, 'a', GCODE_LINE_MAX - n);
	line[GCODE_LINE_MAX] = '\0';
	parse_ok(line, &l);
	ck_assert_uint_eq(l.text_len, GCODE_LINE_MAX);

	/* One more: refused, not cut. */
	line[GCODE_LINE_MAX] = 'a';
	line[GCODE_LINE_MAX + 1] = '\0';
	parse_bad(line, "command longer than 256 characters");

	/* Many short words grow the cleaned text too. */
	n = 0;
	n += (size_t)snprintf(line + n, sizeof(line) - n, "G1");
	for (char c = 'A'; c <= 'Z'; c++)
		n += (size_t)snprintf(line + n, sizeof(line) - n, " %c1.0000000", c);
	parse_bad(line, "command longer than 256");

	/* Blanks and comments do not count against the command... */
	memset(line, ' ', 1000);
	strcpy(line + 1000, "G1 X1 (");
	memset(line + 1007, 'p', 2000);
	strcpy(line + 3007, ") ;tail");
	parse_ok(line, &l);
	ck_assert_str_eq(l.text, "G1 X1");
	ck_assert(l.paren_truncated);

	/* ...but the raw line is bounded too. */
	memset(line, ';', GCODE_RAW_MAX + 1);
	parse_bad_n(line, GCODE_RAW_MAX + 1, "line longer than 65536 bytes", (const char *)NULL);
	parse_ok("", &l);
	{
		struct st_error err = {0};

		/* A line ending does not count. */
		line[GCODE_RAW_MAX] = '\n';
		ck_assert_int_eq(gcode_parse(line, GCODE_RAW_MAX + 1, 0, &l, &err), 0);
	}
}
END_TEST

START_TEST(test_classify)
{
	static const struct {
		const char *in;
		enum gcode_kind kind;
		bool blocking;
	} cases[] = {
	    {"G0 X1", GCODE_KIND_MOTION, false},
	    {"G1 X1 E1", GCODE_KIND_MOTION, false},
	    {"G2 X1 Y1 I1 J0", GCODE_KIND_MOTION, false},
	    {"G3 X1 Y1 R5", GCODE_KIND_MOTION, false},
	    {"G5 I0 J3 P0 Q-3 X10 Y10", GCODE_KIND_MOTION, false},
	    {"G4 S2", GCODE_KIND_DWELL, true},
	    {"G28", GCODE_KIND_HOME, true},
	    {"G29", GCODE_KIND_PROBE, true},
	    {"G30", GCODE_KIND_PROBE, true},
	    {"G80", GCODE_KIND_PROBE, true},
	    {"M48 P10", GCODE_KIND_PROBE, true},
	    {"G92 E0", GCODE_KIND_SET_POSITION, false},
	    {"G20", GCODE_KIND_MODE, false},
	    {"G21", GCODE_KIND_MODE, false},
	    {"G90", GCODE_KIND_MODE, false},
	    {"G91", GCODE_KIND_MODE, false},
	    {"M82", GCODE_KIND_MODE, false},
	    {"M83", GCODE_KIND_MODE, false},
	    {"M104 S200", GCODE_KIND_TEMP_SET, false},
	    {"M140 S60", GCODE_KIND_TEMP_SET, false},
	    {"M141 S40", GCODE_KIND_TEMP_SET, false},
	    {"M109 S200", GCODE_KIND_TEMP_WAIT, true},
	    {"M190 S60", GCODE_KIND_TEMP_WAIT, true},
	    {"M191 S40", GCODE_KIND_TEMP_WAIT, true},
	    {"M116", GCODE_KIND_TEMP_WAIT, true},
	    {"M106 S255", GCODE_KIND_FAN, false},
	    {"M107", GCODE_KIND_FAN, false},
	    {"T1", GCODE_KIND_TOOL_CHANGE, false},
	    {"M6 T1", GCODE_KIND_TOOL_CHANGE, false},
	    {"M400", GCODE_KIND_FINISH_MOVES, true},
	    {"M0", GCODE_KIND_USER_WAIT, true},
	    {"M1 S10", GCODE_KIND_USER_WAIT, true},
	    {"M600", GCODE_KIND_USER_WAIT, true},
	    {"M112", GCODE_KIND_EMERGENCY, false},
	    {"M108", GCODE_KIND_EMERGENCY, false},
	    {"M410", GCODE_KIND_EMERGENCY, false},
	    {"M876 S1", GCODE_KIND_EMERGENCY, false},
	    {"M524", GCODE_KIND_EMERGENCY, false},
	    {"M110 N0", GCODE_KIND_LINE_NUMBER, false},
	    {"M105", GCODE_KIND_REPORT, false},
	    {"M114", GCODE_KIND_REPORT, false},
	    {"M115", GCODE_KIND_REPORT, false},
	    {"M119", GCODE_KIND_REPORT, false},
	    {"M155 S2", GCODE_KIND_REPORT, false},
	    {"M117 hi", GCODE_KIND_MESSAGE, false},
	    {"M118 hi", GCODE_KIND_MESSAGE, false},
	    {"M73 P5", GCODE_KIND_MESSAGE, false},
	    {"", GCODE_KIND_HOST_ONLY, false},
	    {"; just words", GCODE_KIND_HOST_ONLY, false},
	    {"@cancel", GCODE_KIND_HOST_ONLY, false},
	    {"M84", GCODE_KIND_OTHER, false},
	    {"G10", GCODE_KIND_OTHER, false},
	    {"M220 S100", GCODE_KIND_OTHER, false},
	    {"M1040", GCODE_KIND_OTHER, false},
	};
	struct gcode_line l;

	for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
		parse_ok(cases[i].in, &l);
		ck_assert_msg(l.kind == cases[i].kind, "'%s': kind %s, wanted %s", cases[i].in,
			      gcode_kind_name(l.kind), gcode_kind_name(cases[i].kind));
		ck_assert_msg(gcode_is_blocking(l.kind) == cases[i].blocking,
			      "'%s': blocking flag wrong", cases[i].in);
	}
	ck_assert_str_eq(gcode_kind_name(GCODE_KIND_TEMP_WAIT), "temp_wait");
	ck_assert_str_eq(gcode_kind_name(GCODE_KIND_OTHER), "other");
	ck_assert_str_eq(gcode_kind_name(GCODE_KIND_COUNT_), "unknown");
	for (int k = 0; k < GCODE_KIND_COUNT_; k++)
		ck_assert_str_ne(gcode_kind_name((enum gcode_kind)k), "unknown");
}
END_TEST

START_TEST(test_layers)
{
	static const struct {
		const char *in;
		enum gcode_layer_mark mark;
		long layer;
		double z; /* NAN: no height */
	} cases[] = {
	    /* Cura (CuraEngine GCodeExport::writeLayerComment) */
	    {";LAYER:0", GCODE_LAYER_START, 0, NAN},
	    {";LAYER:17\r\n", GCODE_LAYER_START, 17, NAN},
	    {";LAYER:-2", GCODE_LAYER_START, -2, NAN},
	    {";LAYER_COUNT:120", GCODE_LAYER_NONE, 0, 0},
	    {";LAYER:x", GCODE_LAYER_NONE, 0, 0},
	    /* PrusaSlicer / SuperSlicer / OrcaSlicer */
	    {";LAYER_CHANGE", GCODE_LAYER_START, -1, NAN},
	    {";Z:0.2", GCODE_LAYER_Z, -1, 0.2},
	    {";Z:12.35", GCODE_LAYER_Z, -1, 12.35},
	    {";HEIGHT:0.2", GCODE_LAYER_NONE, 0, 0},
	    {";Z:", GCODE_LAYER_NONE, 0, 0},
	    /* Simplify3D */
	    {"; layer 1, Z = 0.200", GCODE_LAYER_START, 1, 0.2},
	    {"; layer 12, Z = 2.45", GCODE_LAYER_START, 12, 2.45},
	    {"; layer end", GCODE_LAYER_NONE, 0, 0},
	    {"; layer 3", GCODE_LAYER_NONE, 0, 0},
	    /* not comment-only, or not a layer comment */
	    {"G1 Z0.2 ;LAYER:1", GCODE_LAYER_NONE, 0, 0},
	    {";TYPE:WALL-OUTER", GCODE_LAYER_NONE, 0, 0},
	    {"", GCODE_LAYER_NONE, 0, 0},
	};
	struct gcode_line l;

	for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
		long layer = 999;
		double z = 999;
		enum gcode_layer_mark m;

		parse_ok(cases[i].in, &l);
		m = gcode_layer_comment(&l, &layer, &z);
		ck_assert_msg(m == cases[i].mark, "'%s': mark %d, wanted %d", cases[i].in, m,
			      cases[i].mark);
		if (m == GCODE_LAYER_NONE) {
			ck_assert(layer == 999 && z == 999);
			continue;
		}
		ck_assert_msg(layer == cases[i].layer, "'%s': layer %ld", cases[i].in, layer);
		if (isnan(cases[i].z))
			ck_assert_msg(isnan(z), "'%s': z %g", cases[i].in, z);
		else
			ck_assert_msg(z == cases[i].z, "'%s': z %.17g", cases[i].in, z);
	}
	parse_ok(";LAYER:3", &l);
	ck_assert_int_eq(gcode_layer_comment(&l, NULL, NULL), GCODE_LAYER_START);
}
END_TEST

START_TEST(test_format_numbered)
{
	static const char *const cmds[] = {
	    "G1 X10 Y-2.5 E0.123 F1800",
	    "M110 N0",
	    "T1",
	    "M117 Hello World",
	    "M117 Bed: 60\xc2\xb0" "C",
	    "M0 Click to continue",
	    "M115 U3.11.0",
	    "M862.3 P \"MK3S\"",
	    "T?",
	    "G28 X Y",
	    "M104 S215",
	    "G29.1 P2",
	};
	static const long nums[] = {0, 1, 9, 10, 99, 123, 4096, 2147483647L};
	char out[GCODE_LINE_MAX + 32];
	struct gcode_line l;
	int n;

	n = gcode_format_numbered(out, sizeof(out), 0, "M110 N0");
	ck_assert_int_eq(n, 14);
	ck_assert_str_eq(out, "N0 M110 N0*125");

	for (size_t i = 0; i < sizeof(cmds) / sizeof(cmds[0]); i++) {
		for (size_t j = 0; j < sizeof(nums) / sizeof(nums[0]); j++) {
			n = gcode_format_numbered(out, sizeof(out), nums[j], cmds[i]);
			ck_assert_int_gt(n, 0);
			ck_assert_uint_eq((size_t)n, strlen(out));
			parse_ok(out, &l);
			ck_assert(l.has_line_number && l.line_number == nums[j]);
			ck_assert(l.has_checksum && l.checksum_ok);
			ck_assert_str_eq(l.text, cmds[i]);
			/* and again from the cleaned text */
			ck_assert_int_gt(
			    gcode_format_numbered(out, sizeof(out), nums[j] + 0, l.text), 0);
		}
	}

	/* Exactly enough room, then one byte short. */
	n = gcode_format_numbered(out, sizeof(out), 5, "G28");
	ck_assert_int_eq(gcode_format_numbered(out, (size_t)n + 1, 5, "G28"), n);
	ck_assert_int_eq(gcode_format_numbered(out, (size_t)n, 5, "G28"), ST_ERR_RANGE);
	ck_assert_str_eq(out, "");

	ck_assert_int_eq(gcode_format_numbered(out, sizeof(out), -1, "G28"), ST_ERR_ARG);
	ck_assert_int_eq(gcode_format_numbered(out, sizeof(out), 2147483648L, "G28"), ST_ERR_ARG);
	ck_assert_int_eq(gcode_format_numbered(out, sizeof(out), 1, ""), ST_ERR_ARG);
	ck_assert_int_eq(gcode_format_numbered(out, sizeof(out), 1, "G1 ;x"), ST_ERR_ARG);
	ck_assert_int_eq(gcode_format_numbered(out, sizeof(out), 1, "G1\n"), ST_ERR_ARG);
	ck_assert_int_gt(gcode_format_numbered(out, sizeof(out), 1, "M117 \xc3\xa9"), 0);
	ck_assert_int_eq(gcode_format_numbered(out, sizeof(out), 1, "M117 a*b"), ST_ERR_ARG);
	ck_assert_int_eq(gcode_format_numbered(out, sizeof(out), 1, "M117 a\x08"), ST_ERR_ARG);
	ck_assert_int_eq(gcode_format_numbered(out, sizeof(out), 1, NULL), ST_ERR_ARG);
	ck_assert_int_eq(gcode_format_numbered(NULL, 10, 1, "G28"), ST_ERR_ARG);
}
END_TEST

/* Parse in, check the cleaned text, the text part (NULL: none) and the
 * number of words, and that a resend (new line number, checksum) reads the
 * same. */
static void want_text(const char *in, const char *text, const char *string, size_t nwords)
{
	struct gcode_line l, again;
	struct st_error err = {0};
	char out[GCODE_LINE_MAX + 32];
	int n;

	parse_ok(in, &l);
	ck_assert_msg(!strcmp(l.text, text), "'%s': text '%s', wanted '%s'", in, l.text, text);
	ck_assert_msg(l.has_string == (string != NULL), "'%s': has_string %d", in, l.has_string);
	if (string)
		ck_assert_msg(!strcmp(l.text + l.string_off, string), "'%s': string '%s', wanted '%s'",
			      in, l.text + l.string_off, string);
	ck_assert_msg(l.nwords == nwords, "'%s': %zu words, wanted %zu", in, l.nwords, nwords);
	n = gcode_format_numbered(out, sizeof(out), 4711, l.text);
	ck_assert_msg(n > 0, "'%s': cannot number '%s'", in, l.text);
	ck_assert_msg(gcode_parse(out, (size_t)n, 0, &again, &err) == 0, "'%s': %s", out, err.msg);
	ck_assert_str_eq(again.text, l.text);
	ck_assert_uint_eq(again.string_off, l.string_off);
	ck_assert_uint_eq(again.nwords, l.nwords);
	ck_assert_int_eq(again.kind, l.kind);
}

/* What Marlin (and Prusa's firmware) accept is accepted and passed on as
 * written: version strings, texts after M0/M1, quotes, UTF-8, unknown
 * commands and letters (issue 18). */
START_TEST(test_firmware_texts)
{
	struct gcode_line l;
	char line[128];

	/* PrusaSlicer's bundled start G-code, 29 of 31 printers */
	want_text("M115 U3.11.0 ; tell printer latest fw version", "M115 U3.11.0", "U3.11.0", 0);
	parse_ok("M115 U3.11.0", &l);
	ck_assert_int_eq(l.kind, GCODE_KIND_REPORT);
	want_text("M115U3.2.3", "M115 U3.2.3", "U3.2.3", 0);
	want_text("M115", "M115", NULL, 0);
	want_text("M862.3 P \"MK3S\" ; printer model check", "M862.3 P \"MK3S\"", "P \"MK3S\"", 0);
	want_text("M862.1 P0.4 ; nozzle diameter check", "M862.1 P0.4", "P0.4", 0);
	/* M0/M1 with a message, Marlin's string_arg from the first bare letter */
	want_text("M0 Click to continue", "M0 Click to continue", "Click to continue", 0);
	parse_ok("M1 Change filament", &l);
	ck_assert_int_eq(l.kind, GCODE_KIND_USER_WAIT);
	ck_assert_str_eq(l.text + l.string_off, "Change filament");
	want_text("M0 S30 Remove the print", "M0 S30 Remove the print", "Remove the print", 1);
	want_text("M0 Push S to stop", "M0 Push S to stop", "Push S to stop", 0);
	want_text("M0 PRESS OK", "M0 PRESS OK", "PRESS OK", 0);
	want_text("M0 S5 S6", "M0 S5 S6", "S6", 1);
	want_text("M0 X10abc", "M0 X10abc", "X10abc", 0);
	/* UTF-8 and quotes in messages */
	want_text("M117 Bed: 60\xc2\xb0" "C", "M117 Bed: 60\xc2\xb0" "C", "Bed: 60\xc2\xb0" "C", 0);
	want_text("M0 W\xc3\xa4rmen", "M0 W\xc3\xa4rmen", "W\xc3\xa4rmen", 0);
	want_text("M117 \"quoted\" text", "M117 \"quoted\" text", "\"quoted\" text", 0);
	want_text("M118 E1 \"Hello\"", "M118 E1 \"Hello\"", "E1 \"Hello\"", 0);
	/* '( )' inside a text is text, before it a comment; an open '(' is text */
	want_text("M0 Click (here) to go", "M0 Click (here) to go", "Click (here) to go", 0);
	want_text("M0 (first) Click", "M0 Click", "Click", 0);
	want_text("M0 Wait (forever", "M0 Wait (forever", "Wait (forever", 0);
	want_text("M0 (forever", "M0 (forever", "(forever", 0);
	/* tabs inside a text are kept, around words they are blanks */
	want_text("M0\tClick\tnow", "M0 Click\tnow", "Click\tnow", 0);
	want_text("G1\tX10\tY10 F3000", "G1 X10 Y10 F3000", NULL, 3);
	/* commands and letters the firmware does not know: "Unknown command", ok */
	want_text("M999 Q1 W ; unknown", "M999 Q1 W", NULL, 2);
	want_text("G28 X0 Y0 Q", "G28 X0 Y0 Q", NULL, 3);
	want_text("M300 S440 P200 beep", "M300 S440 P200 beep", "beep", 2);
	/* PrusaSlicer's own words */
	want_text("M73 Q0 S37", "M73 Q0 S37", NULL, 2);
	want_text("M204 P1250 R1250 T1250", "M204 P1250 R1250 T1250", NULL, 3);
	want_text("M900 K0.05 ; Filament gcode LA 1.5", "M900 K0.05", NULL, 1);
	want_text("G28 W ; home all without mesh bed level", "G28 W", NULL, 1);
	want_text("G80 ; mesh bed leveling", "G80", NULL, 0);
	want_text("G29", "G29", NULL, 0);
	/* SD card file names */
	want_text("M23 my part.gco", "M23 my part.gco", "my part.gco", 0);
	want_text("M32 P !/models/part.gco#", "M32 P !/models/part.gco#", "P !/models/part.gco#", 0);
	/* a checksum after a text */
	snprintf(line, sizeof(line), "N3 M115 U3.11.0*%u",
		 gcode_checksum("N3 M115 U3.11.0", strlen("N3 M115 U3.11.0")));
	parse_ok(line, &l);
	ck_assert(l.has_checksum && l.checksum_ok);
	ck_assert_str_eq(l.text, "M115 U3.11.0");
	parse_bad("N3 M115 U3.11.0*1", "checksum 1 does not match");
}
END_TEST

/* What cannot be sent safely is refused, with the column and the reason. */
START_TEST(test_firmware_refusals)
{
	static char line[GCODE_LINE_MAX + 64];
	size_t n;

	/* numbers that heat, move or set how the machine moves: never a prefix */
	parse_bad("M104 S2.1.0", "column 6: 'S2.1.0' is not a number");
	parse_bad("M140 S60\xc2\xb0", "column 9: non-ASCII byte 0xc2");
	parse_bad("M104 S200 S210", "'S' appears twice");
	parse_bad("M900 K0.0.5", "'K0.0.5' is not a number");
	parse_bad("M851 Z-1.2.3", "'Z-1.2.3' is not a number");
	parse_bad("M221 S95%", "column 6: 'S95%' is not a number");
	parse_bad("G1 X1 Move", "without a value", "G1");
	parse_bad("G28 X\"a\"", "unexpected character '\"'");
	parse_bad("T0 F1.2.3", "'F1.2.3' is not a number");
	/* '*' in a text: Marlin cuts the command at the first '*' */
	parse_bad("M0 Press * to go", "column 10", "'*' inside the text of M0");
	parse_bad("M115 U3*", "column 8: '*' must be followed by a checksum");
	parse_bad("M115 U3.1.0* x", "'*' inside the text of M115");
	parse_bad("M862.3 P \"MK*\"", "'*' inside the text of M862.3");
	/* control bytes break the line protocol, texts and comments included */
	parse_bad("M117 a\x08" "b", "column 7: control byte 0x08");
	parse_bad_n("M117 a\0b", 8, "column 7: control byte 0x00", (const char *)NULL);
	parse_bad("M0 Click\x1b[0m", "control byte 0x1b");
	parse_bad("M117 ok\x7f", "control byte 0x7f");
	/* a line that starts with no command is not sent (with Marlin's motion
	 * modes "X10" would move) */
	parse_bad("X10 Y10", "'X10' is not a command");
	parse_bad("e5", "'e5' is not a command");
	/* a text longer than the cleaned command holds is refused, not cut */
	n = (size_t)snprintf(line, sizeof(line), "M0 ");
	memset(line + n, 'a', GCODE_LINE_MAX);
	line[n + GCODE_LINE_MAX] = '\0';
	parse_bad(line, "command longer than 256 characters");
}
END_TEST

/* Every command line of FILE, in order, as gcode_reader reads it. */
static size_t read_all(const char *path, struct gcode_line *lines, size_t cap, size_t *total)
{
	FILE *fp = fopen(path, "rb");
	struct gcode_reader *r;
	struct st_error err = {0};
	struct gcode_line l;
	size_t n = 0;
	int rc;

	ck_assert_msg(fp != NULL, "%s: not found (run from the source tree)", path);
	ck_assert_int_eq(gcode_reader_new(fp, path, &r, &err), 0);
	while ((rc = gcode_reader_next(r, 0, &l, &err)) == 1)
		if (l.text_len > 0 && n < cap)
			lines[n++] = l;
	ck_assert_msg(rc == 0, "%s", err.msg);
	*total = (size_t)gcode_reader_line(r);
	gcode_reader_free(r);
	fclose(fp);
	return n;
}

/* PrusaSlicer 2.5's G-code for the MK3S (a 20 mm cube, first three layers
 * and the end): every line reads, and each command is the line as written,
 * comment and trailing blanks removed, since PrusaSlicer writes the words
 * single-spaced. */
START_TEST(test_prusaslicer_file)
{
	static struct gcode_line lines[2048];
	static const char path[] = "tests/data/prusaslicer-mk3s-cube.gcode";
	static char raw[GCODE_RAW_MAX + 2];
	size_t total, n = read_all(path, lines, 2048, &total), k = 0;
	bool m115 = false, m862 = false, g80 = false;
	FILE *fp = fopen(path, "rb");

	ck_assert_uint_eq(total, 1058);
	while (fgets(raw, sizeof(raw), fp)) {
		char *semi = strchr(raw, ';');
		size_t len = semi ? (size_t)(semi - raw) : strlen(raw);

		while (len > 0 && strchr(" \t\r\n", raw[len - 1]))
			len--;
		if (len == 0)
			continue;
		raw[len] = '\0';
		ck_assert_uint_lt(k, n);
		ck_assert_msg(!strcmp(lines[k].text, raw), "command %zu: '%s', the file says '%s'", k,
			      lines[k].text, raw);
		m115 |= !strcmp(raw, "M115 U3.11.0");
		m862 |= !strcmp(raw, "M862.3 P \"MK3S\"");
		g80 |= !strcmp(raw, "G80");
		k++;
	}
	fclose(fp);
	ck_assert_uint_eq(k, n);
	ck_assert(m115 && m862 && g80);
}
END_TEST

/* tests/data/firmware-texts.gcode (what the send suite streams): every line
 * reads, the last one has no line ending. */
START_TEST(test_firmware_texts_file)
{
	static struct gcode_line lines[64];
	size_t total, n = read_all("tests/data/firmware-texts.gcode", lines, 64, &total);

	ck_assert_uint_eq(total, 26);
	ck_assert_uint_eq(n, 23);
	ck_assert_str_eq(lines[0].text, "M115 U3.11.0");
	ck_assert_str_eq(lines[6].text, "M117 Bed: 60\xc2\xb0" "C");
	ck_assert_str_eq(lines[9].text, "M0 Click to continue");
	ck_assert_str_eq(lines[10].text, "M1 Change filament");
	ck_assert_str_eq(lines[n - 1].text, "M117 Done");
}
END_TEST

/* A temporary file holding len bytes, rewound. */
static FILE *temp_with(const char *data, size_t len)
{
	FILE *fp = tmpfile();

	ck_assert_ptr_nonnull(fp);
	ck_assert_uint_eq(fwrite(data, 1, len, fp), len);
	rewind(fp);
	return fp;
}

START_TEST(test_reader)
{
	static const char data[] = "G28\r\nG1 X1\n;comment\rM104 S200\n\n  \r\nG1 Y2";
	static const struct {
		uint64_t line;
		const char *text;
		enum gcode_kind kind;
	} want[] = {
	    {1, "G28", GCODE_KIND_HOME},     {2, "G1 X1", GCODE_KIND_MOTION},
	    {3, "", GCODE_KIND_HOST_ONLY},   {4, "M104 S200", GCODE_KIND_TEMP_SET},
	    {5, "", GCODE_KIND_HOST_ONLY},   {6, "", GCODE_KIND_HOST_ONLY},
	    {7, "G1 Y2", GCODE_KIND_MOTION},
	};
	FILE *fp = temp_with(data, sizeof(data) - 1);
	struct gcode_reader *r = NULL;
	struct st_error err = {0};
	struct gcode_line l;

	ck_assert_int_eq(gcode_reader_new(fp, "part.gcode", &r, &err), 0);
	ck_assert_uint_eq(gcode_reader_line(r), 0);
	for (size_t i = 0; i < sizeof(want) / sizeof(want[0]); i++) {
		int rc = gcode_reader_next(r, 0, &l, &err);

		ck_assert_msg(rc == 1, "line %zu: %d %s", i + 1, rc, err.msg);
		ck_assert_uint_eq(gcode_reader_line(r), want[i].line);
		ck_assert_str_eq(l.text, want[i].text);
		ck_assert_int_eq(l.kind, want[i].kind);
	}
	ck_assert_int_eq(gcode_reader_next(r, 0, &l, &err), 0);
	ck_assert_int_eq(gcode_reader_next(r, 0, &l, &err), 0);
	ck_assert_uint_eq(gcode_reader_bytes(r), sizeof(data) - 1);
	gcode_reader_free(r);
	fclose(fp);

	/* Empty input, trailing newline, NULL arguments. */
	fp = temp_with("", 0);
	ck_assert_int_eq(gcode_reader_new(fp, NULL, &r, &err), 0);
	ck_assert_int_eq(gcode_reader_next(r, 0, &l, &err), 0);
	ck_assert_uint_eq(gcode_reader_line(r), 0);
	gcode_reader_free(r);
	fclose(fp);
	fp = temp_with("G28\n", 4);
	ck_assert_int_eq(gcode_reader_new(fp, NULL, &r, &err), 0);
	ck_assert_int_eq(gcode_reader_next(r, 0, &l, &err), 1);
	ck_assert_int_eq(gcode_reader_next(r, 0, &l, &err), 0);
	ck_assert_uint_eq(gcode_reader_line(r), 1);
	gcode_reader_free(r);
	fclose(fp);
	gcode_reader_free(NULL);
	r = (struct gcode_reader *)&err;
	ck_assert_int_eq(gcode_reader_new(NULL, "x", &r, &err), ST_ERR_ARG);
	ck_assert_ptr_null(r);
	ck_assert_int_eq(gcode_reader_next(NULL, 0, &l, &err), ST_ERR_ARG);
}
END_TEST

START_TEST(test_reader_errors)
{
	/* line 2: command too long; line 4: raw line too long; line 5: bad
	 * number; the reader goes on after each. */
	size_t cap = 2 * GCODE_RAW_MAX, n = 0;
	char *data = malloc(cap);
	FILE *fp;
	struct gcode_reader *r = NULL;
	struct st_error err = {0};
	struct gcode_line l;

	ck_assert_ptr_nonnull(data);
	n += (size_t)snprintf(data + n, cap - n, "G28\nM117 ");
	memset(data + n, 'm', 300);
	n += 300;
	n += (size_t)snprintf(data + n, cap - n, "\r\nG1 X1\n;");
	memset(data + n, 'c', GCODE_RAW_MAX + 10);
	n += GCODE_RAW_MAX + 10;
	n += (size_t)snprintf(data + n, cap - n, "\nG1 X1.2.3\nM400");
	fp = temp_with(data, n);
	free(data);

	ck_assert_int_eq(gcode_reader_new(fp, "big.gcode", &r, &err), 0);
	ck_assert_int_eq(gcode_reader_next(r, 0, &l, &err), 1);
	ck_assert_str_eq(l.text, "G28");

	ck_assert_int_eq(gcode_reader_next(r, 0, &l, &err), ST_ERR_PARSE);
	ck_assert_msg(strstr(err.msg, "big.gcode: line 2: command longer than 256"), "%s", err.msg);
	ck_assert_str_eq(l.text, "G28"); /* untouched */

	ck_assert_int_eq(gcode_reader_next(r, 0, &l, &err), 1);
	ck_assert_str_eq(l.text, "G1 X1");
	ck_assert_uint_eq(gcode_reader_line(r), 3);

	ck_assert_int_eq(gcode_reader_next(r, 0, &l, &err), ST_ERR_PARSE);
	ck_assert_msg(strstr(err.msg, "big.gcode: line 4: line longer than 65536 bytes"), "%s",
		      err.msg);

	ck_assert_int_eq(gcode_reader_next(r, 0, &l, &err), ST_ERR_PARSE);
	ck_assert_msg(strstr(err.msg, "big.gcode: line 5: column 4: 'X1.2.3' is not a number"),
		      "%s", err.msg);

	ck_assert_int_eq(gcode_reader_next(r, 0, &l, &err), 1);
	ck_assert_int_eq(l.kind, GCODE_KIND_FINISH_MOVES);
	ck_assert_uint_eq(gcode_reader_line(r), 6);
	ck_assert_int_eq(gcode_reader_next(r, 0, &l, &err), 0);
	ck_assert_uint_eq(gcode_reader_bytes(r), n);
	gcode_reader_free(r);
	fclose(fp);
}
END_TEST

/* xorshift64: a fixed, portable pseudo-random sequence. */
static uint64_t rnd(uint64_t *s)
{
	*s ^= *s << 13;
	*s ^= *s >> 7;
	*s ^= *s << 17;
	return *s;
}

START_TEST(test_random)
{
	static const char alphabet[] = "GMTNXYZEFSPgmx0123456789.-+ \t;()*@\r\n";
	static const char *const tokens[] = {
	    "G1",   "G28", "M104", "M117",  "T0", "N5 ",  "@",	  " ", " ",  "\t",  "X1.5",
	    "Y-2",  "E.5", "Z",	   "F1800", "S",  "(p)",  "(",	  ")", ";c", "*12", "*",
	    "\r\n", "1e3", "-",	   ".",	    "a",  "\xff", "M110", "N", "0",
	    /* the paths of commands that end in a text */
	    "M0",   "M115", "U3.11.0", "Click", "\"q\"", "\xc2\xb0", "T?", "M862.3",
	};
	uint64_t seed = 0x5eed5eed12345678ULL;
	char buf[320], out[GCODE_LINE_MAX + 32];
	int accepted = 0;

	for (int iter = 0; iter < 10000; iter++) {
		size_t len = (size_t)(rnd(&seed) % sizeof(buf));
		int mode = (int)(rnd(&seed) % 4); /* 0 raw bytes, 1 characters, 2-3 tokens */
		struct gcode_line l, again;
		struct st_error err = {0};
		int rc;

		if (mode >= 2) {
			size_t ntok = (size_t)(rnd(&seed) % 12);

			len = 0;
			for (size_t t = 0; t < ntok; t++) {
				const char *tok =
				    tokens[rnd(&seed) % (sizeof(tokens) / sizeof(tokens[0]))];
				size_t tl = strlen(tok);

				if (len + tl > sizeof(buf))
					break;
				memcpy(buf + len, tok, tl);
				len += tl;
			}
		} else {
			for (size_t i = 0; i < len; i++)
				buf[i] = mode == 0 ? (char)(rnd(&seed) & 0xff)
						   : alphabet[rnd(&seed) % (sizeof(alphabet) - 1)];
		}
		/* Exact-size heap copy so ASan sees any read past the end. */
		{
			char *copy = malloc(len ? len : 1);

			ck_assert_ptr_nonnull(copy);
			memcpy(copy, buf, len);
			memset(&l, 0, sizeof(l));
			rc = gcode_parse(copy, len, 0, &l, &err);
			free(copy);
		}
		if (rc != 0) {
			ck_assert_int_eq(rc, ST_ERR_PARSE);
			ck_assert_msg(err.msg[0] != '\0', "empty message");
			continue;
		}
		accepted++;
		ck_assert_uint_le(l.text_len, GCODE_LINE_MAX);
		ck_assert_uint_eq(strlen(l.text), l.text_len);
		ck_assert_uint_le(l.nwords, GCODE_WORDS_MAX);
		ck_assert_uint_le(l.string_off, l.text_len);
		ck_assert(l.kind >= 0 && l.kind < GCODE_KIND_COUNT_);
		/* What was accepted survives a resend with a new number. */
		if (l.text_len > 0 && l.letter != '@') {
			int n = gcode_format_numbered(out, sizeof(out), iter, l.text);

			ck_assert_msg(n > 0, "cannot format '%s'", l.text);
			rc = gcode_parse(out, (size_t)n, 0, &again, &err);
			ck_assert_msg(rc == 0, "'%s' from '%s': %s", out, l.text, err.msg);
			ck_assert_str_eq(again.text, l.text);
			ck_assert_int_eq(again.kind, l.kind);
			ck_assert_uint_eq(again.nwords, l.nwords);
			ck_assert_uint_eq(again.string_off, l.string_off);
		}
	}
	/* The generator must exercise the accepting paths too. */
	ck_assert_int_gt(accepted, 1000);
}
END_TEST

/* Random well-formed lines: the values come back exactly. */
START_TEST(test_random_values)
{
	uint64_t seed = 0x0123456789abcdefULL;

	for (int iter = 0; iter < 2000; iter++) {
		char line[128];
		long ip = (long)(rnd(&seed) % 100000);
		long fp = (long)(rnd(&seed) % 100000);
		bool neg = rnd(&seed) & 1;
		double want, got;
		struct gcode_line l;

		snprintf(line, sizeof(line), "G1 X%s%ld.%05ld", neg ? "-" : "", ip, fp);
		want = strtod(line + 4, NULL); /* C locale in the tests */
		parse_ok(line, &l);
		ck_assert(gcode_word_value(&l, 'X', &got));
		ck_assert_msg(got == want, "%s read as %.17g, strtod %.17g", line, got, want);
	}
}
END_TEST

Suite *gcode_suite(void)
{
	Suite *s = suite_create("gcode");
	TCase *parse = tcase_create("parse");
	TCase *errors = tcase_create("errors");
	TCase *meaning = tcase_create("meaning");
	TCase *io = tcase_create("io");
	TCase *fuzz = tcase_create("fuzz");

	tcase_add_test(parse, test_words);
	tcase_add_test(parse, test_word_details);
	tcase_add_test(parse, test_comments);
	tcase_add_test(parse, test_checksums);
	tcase_add_test(parse, test_tools);
	tcase_add_test(parse, test_string_args);
	tcase_add_test(parse, test_text_commands);
	tcase_add_test(parse, test_number_reader);
	tcase_add_test(parse, test_firmware_texts);
	suite_add_tcase(s, parse);

	tcase_add_test(errors, test_rejects);
	tcase_add_test(errors, test_lengths);
	tcase_add_test(errors, test_firmware_refusals);
	suite_add_tcase(s, errors);

	tcase_add_test(meaning, test_classify);
	tcase_add_test(meaning, test_layers);
	tcase_add_test(meaning, test_format_numbered);
	suite_add_tcase(s, meaning);

	tcase_add_test(io, test_reader);
	tcase_add_test(io, test_reader_errors);
	tcase_add_test(io, test_prusaslicer_file);
	tcase_add_test(io, test_firmware_texts_file);
	suite_add_tcase(s, io);

	tcase_add_test(fuzz, test_random);
	tcase_add_test(fuzz, test_random_values);
	tcase_set_timeout(fuzz, 60);
	suite_add_tcase(s, fuzz);
	return s;
}
