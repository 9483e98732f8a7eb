/*
 * check_gcode.c - serial/gcode.c: words and numbers, comments, checksums,
 * tool changes, string-argument commands and the texts the firmware accepts.
 * The refusals and the classifier are in check_gcode_errors.c, the reader
 * and the robustness tests in check_gcode_io.c (helpers: gcodetest.h).
 */
#include <check.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gcode.h"
#include "gcodetest.h"
#include "suites.h"

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

Suite *gcode_suite(void)
{
	Suite *s = suite_create("gcode");
	TCase *parse = tcase_create("parse");

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
	gcode_errors_tcases(s);
	gcode_io_tcases(s);
	return s;
}
