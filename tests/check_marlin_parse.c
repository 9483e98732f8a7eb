/*
 * check_marlin_parse.c - serial/marlin.c's reply parser, part of the marlin
 * suite (check_marlin.c): ok, resend and error lines, temperature reports,
 * M115's capabilities.
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "marlin.h"
#include "suites.h"

/* ---- reply parsing ---- */

static enum marlin_reply_kind parse(const char *s, struct marlin_reply *r,
				    struct marlin_status *st, struct marlin_caps *caps)
{
	return marlin_parse_reply(s, strlen(s), r, st, caps);
}

START_TEST(parse_ok)
{
	struct marlin_reply r;
	ck_assert_int_eq(parse("ok", &r, NULL, NULL), MARLIN_REPLY_OK);
	ck_assert(!r.has_n && !r.has_b);
	ck_assert_int_eq(parse("ok\r", &r, NULL, NULL), MARLIN_REPLY_OK);
	ck_assert_int_eq(parse("ok N123 P15 B3", &r, NULL, NULL), MARLIN_REPLY_OK);
	ck_assert(r.has_n && r.has_p && r.has_b);
	ck_assert_int_eq(r.n, 123);
	ck_assert_int_eq(r.p, 15);
	ck_assert_int_eq(r.b, 3);
	ck_assert_int_eq(parse("ok P16 B4", &r, NULL, NULL), MARLIN_REPLY_OK);
	ck_assert(!r.has_n && r.has_b && r.b == 4);
	ck_assert_int_eq(parse("okay", &r, NULL, NULL), MARLIN_REPLY_OTHER);
}
END_TEST

START_TEST(parse_resend_and_errors)
{
	struct marlin_reply r;
	ck_assert_int_eq(parse("Resend: 42", &r, NULL, NULL), MARLIN_REPLY_RESEND);
	ck_assert_int_eq(r.resend, 42);
	ck_assert_int_eq(parse("Resend:7", &r, NULL, NULL), MARLIN_REPLY_RESEND);
	ck_assert_int_eq(r.resend, 7);
	ck_assert_int_eq(parse("rs N9", &r, NULL, NULL), MARLIN_REPLY_RESEND);
	ck_assert_int_eq(r.resend, 9);
	ck_assert_int_eq(parse("Resend: x", &r, NULL, NULL), MARLIN_REPLY_OTHER);
	ck_assert_int_eq(parse("Error:checksum mismatch, Last Line: 41", &r, NULL, NULL),
			 MARLIN_REPLY_LINE_ERROR);
	ck_assert_int_eq(parse("Error:Line Number is not Last Line Number+1, Last Line: 4", &r,
			       NULL, NULL),
			 MARLIN_REPLY_LINE_ERROR);
	ck_assert_int_eq(parse("Error:No Checksum with line number, Last Line: 4", &r, NULL, NULL),
			 MARLIN_REPLY_LINE_ERROR);
	ck_assert_int_eq(parse("Error:Printer halted. kill() called!", &r, NULL, NULL),
			 MARLIN_REPLY_FATAL);
	ck_assert_int_eq(parse("Error:Thermal Runaway, system stopped! Heater_ID: 0", &r, NULL,
			       NULL),
			 MARLIN_REPLY_FATAL);
	ck_assert_int_eq(parse("Error:MINTEMP triggered, system stopped! Heater_ID: bed", &r,
			       NULL, NULL),
			 MARLIN_REPLY_FATAL);
	ck_assert_int_eq(parse("Error: MAXTEMP triggered", &r, NULL, NULL), MARLIN_REPLY_FATAL);
	ck_assert_int_eq(parse("Error:Something else", &r, NULL, NULL), MARLIN_REPLY_ERROR);
	ck_assert_int_eq(parse("echo:busy: processing", &r, NULL, NULL), MARLIN_REPLY_BUSY);
	ck_assert_int_eq(parse("echo:busy: paused for user", &r, NULL, NULL), MARLIN_REPLY_BUSY);
	ck_assert_int_eq(parse("echo:Unknown command: \"M9999\"", &r, NULL, NULL),
			 MARLIN_REPLY_UNKNOWN_CMD);
	ck_assert_int_eq(parse("start", &r, NULL, NULL), MARLIN_REPLY_START);
	ck_assert_int_eq(parse("//action:pause", &r, NULL, NULL), MARLIN_REPLY_ACTION);
	ck_assert_str_eq(r.action, "pause");
	ck_assert_int_eq(parse("//action:prompt_begin Filament", &r, NULL, NULL),
			 MARLIN_REPLY_ACTION);
	ck_assert_str_eq(r.action, "prompt_begin");
}
END_TEST

START_TEST(parse_temperatures)
{
	struct marlin_reply r;
	struct marlin_status st;
	memset(&st, 0, sizeof(st));
	ck_assert_int_eq(parse("ok T:210.50 /215.00 B:60.00 /60.00 @:127 B@:0", &r, &st, NULL),
			 MARLIN_REPLY_OK);
	ck_assert(r.has_temps && !r.has_b);
	ck_assert_double_eq_tol(st.tool[0].actual, 210.5, 1e-9);
	ck_assert_double_eq_tol(st.tool[0].target, 215.0, 1e-9);
	ck_assert_double_eq_tol(st.bed.actual, 60.0, 1e-9);
	ck_assert(!st.heating_wait);
	ck_assert_int_eq(parse(" T:180.3 /200.0 B:25.0 /0.0 @:0 B@:0 W:?", &r, &st, NULL),
			 MARLIN_REPLY_TEMP);
	ck_assert(st.heating_wait);
	ck_assert_double_eq_tol(st.tool[0].actual, 180.3, 1e-9);
	ck_assert_int_eq(parse("T:200 /200 B:60 /60 T0:200 /200 T1:150.5 /160 C:35.5 /40 @:0 "
			       "W:3",
			       &r, &st, NULL),
			 MARLIN_REPLY_TEMP);
	ck_assert(st.tool[1].present && st.chamber.present);
	ck_assert_double_eq_tol(st.tool[1].actual, 150.5, 1e-9);
	ck_assert_double_eq_tol(st.tool[1].target, 160.0, 1e-9);
	ck_assert_double_eq_tol(st.chamber.target, 40.0, 1e-9);
	ck_assert(st.heating_wait);
	ck_assert_int_eq(parse("X:0.00 Y:0.00 Z:0.00 E:0.00 Count X:0", &r, &st, NULL),
			 MARLIN_REPLY_OTHER);
}
END_TEST

START_TEST(parse_m115)
{
	struct marlin_reply r;
	struct marlin_caps caps;
	memset(&caps, 0, sizeof(caps));
	ck_assert_int_eq(parse("FIRMWARE_NAME:Marlin 2.1.2.1 (Github) SOURCE_CODE_URL:github.com/"
			       "MarlinFirmware/Marlin PROTOCOL_VERSION:1.0 MACHINE_TYPE:Ender-3 V2 "
			       "EXTRUDER_COUNT:1 UUID:cede2a2f-41a2-4748-9b12-c55c62f367ff",
			       &r, NULL, &caps),
			 MARLIN_REPLY_FIRMWARE);
	ck_assert(caps.m115);
	ck_assert_str_eq(caps.firmware_name, "Marlin 2.1.2.1 (Github)");
	ck_assert_str_eq(caps.machine_type, "Ender-3 V2");
	ck_assert_int_eq(caps.extruder_count, 1);
	ck_assert_int_eq(parse("Cap:EMERGENCY_PARSER:1", &r, NULL, &caps), MARLIN_REPLY_CAP);
	ck_assert_int_eq(parse("Cap:AUTOREPORT_TEMP:1", &r, NULL, &caps), MARLIN_REPLY_CAP);
	ck_assert_int_eq(parse("Cap:HOST_ACTION_COMMANDS:0", &r, NULL, &caps), MARLIN_REPLY_CAP);
	ck_assert_int_eq(parse("Cap:ADVANCED_OK:1", &r, NULL, &caps), MARLIN_REPLY_CAP);
	ck_assert(caps.emergency_parser && caps.autoreport_temp && caps.advanced_ok);
	ck_assert(!caps.host_action_commands);
}
END_TEST

/*
 * The reply is (line, len) with no NUL after it (issue 17, found by
 * fuzzing): the parser once ran strstr past len.  The line sits in a heap
 * block of exactly len bytes, so ASan (make check's sanitizer pass) sees any read
 * beyond; a count past len is not the line's.
 */
START_TEST(parse_m115_not_terminated)
{
	static const char *const lines[] = {
		"FIRMWARE_NAME:Marlin",
		"FIRMWARE_NAME:Marlin EXTRUDER_COUNT:",
		"FIRMWARE_NAME:Marlin EXTRUDER_COUNT:2",
	};
	for (size_t i = 0; i < sizeof(lines) / sizeof(lines[0]); i++) {
		size_t len = strlen(lines[i]);
		char *buf = malloc(len);
		struct marlin_reply r;
		struct marlin_caps caps;

		ck_assert(buf);
		memcpy(buf, lines[i], len);
		memset(&caps, 0, sizeof(caps));
		ck_assert_int_eq(marlin_parse_reply(buf, len, &r, NULL, &caps),
				 MARLIN_REPLY_FIRMWARE);
		ck_assert_int_eq(caps.extruder_count, i == 2 ? 2 : 0);
		free(buf);
	}
	/* "EXTRUDER_COUNT:5" after len is outside the line. */
	{
		const char text[] = "FIRMWARE_NAME:Marlin EXTRUDER_COUNT:5";
		struct marlin_reply r;
		struct marlin_caps caps;

		memset(&caps, 0, sizeof(caps));
		ck_assert_int_eq(marlin_parse_reply(text, strlen("FIRMWARE_NAME:Marlin"), &r, NULL,
						    &caps),
				 MARLIN_REPLY_FIRMWARE);
		ck_assert_int_eq(caps.extruder_count, 0);
		ck_assert_str_eq(caps.firmware_name, "Marlin");
	}
}
END_TEST

void marlin_parse_tcases(Suite *s)
{
	TCase *tc = tcase_create("parse");
	tcase_add_test(tc, parse_ok);
	tcase_add_test(tc, parse_resend_and_errors);
	tcase_add_test(tc, parse_temperatures);
	tcase_add_test(tc, parse_m115);
	tcase_add_test(tc, parse_m115_not_terminated);
	suite_add_tcase(s, tc);
}
