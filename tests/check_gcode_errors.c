/*
 * check_gcode_errors.c - serial/gcode.c, part of the gcode suite
 * (check_gcode.c): every refused input with its column and reason, line
 * lengths, the classifier and blocking flags, slicer layer comments and
 * numbered-line round trips.
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "gcode.h"
#include "gcodetest.h"
#include "suites.h"

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


void gcode_errors_tcases(Suite *s)
{
	TCase *errors = tcase_create("errors");
	TCase *meaning = tcase_create("meaning");

	tcase_add_test(errors, test_rejects);
	tcase_add_test(errors, test_lengths);
	tcase_add_test(errors, test_firmware_refusals);
	suite_add_tcase(s, errors);

	tcase_add_test(meaning, test_classify);
	tcase_add_test(meaning, test_layers);
	tcase_add_test(meaning, test_format_numbered);
	suite_add_tcase(s, meaning);
}
