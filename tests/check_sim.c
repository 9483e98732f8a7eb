/*
 * check_sim.c - the simulated Marlin (serial/sim/marlin_sim.c) driven over
 * its pty from the test: boot banner, ok and execution log, checksum and
 * line-number errors with Resend, duplicates, M110, M105, M115, ADVANCED_OK,
 * M109 heating, pacing.  RX overflow, M112, unplug and reset faults, and
 * hosts that are not ours (printcore) are in check_sim_faults.c.
 */
#include <check.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include "gcode.h"
#include "s3g.h"
#include "sim/marlin_sim.h"
#include "sim/sailfish_sim.h"
#include "simtest.h"
#include "st_clock.h"
#include "suites.h"
#include "testutil.h"
#include "xport.h"

START_TEST(boot_banner)
{
	struct sim_marlin_options o;
	struct client c;
	fast_opts(&o);
	memset(&c, 0, sizeof(c));
	struct st_error err = {0};
	ck_assert_int_eq(sim_marlin_new(&o, &c.sim, &err), 0);
	c.fd = open(sim_marlin_slave_path(c.sim), O_RDWR | O_NOCTTY | O_NONBLOCK);
	ck_assert_int_ge(c.fd, 0);
	ck_assert_int_eq(sim_marlin_start_thread(c.sim, &err), 0);
	cl_next_is(&c, "start");
	cl_expect(&c, "echo:Marlin 2.1", NULL, 0, 1.0);
	cl_expect(&c, "echo: Free Memory:", NULL, 0, 1.0);
	sim_marlin_stop(c.sim);
	sim_marlin_free(c.sim);
	close(c.fd);
}
END_TEST

START_TEST(ok_and_log)
{
	struct sim_marlin_options o;
	struct client c;
	fast_opts(&o);
	cl_start(&c, &o);
	cl_send_n(&c, 1, "G28");
	cl_send_n(&c, 2, "G1 X10 Y5 F6000");
	cl_send(&c, "N3 M400*");
	cl_send(&c, "36 ; comments are stripped first\n");
	cl_next_is(&c, "ok");
	cl_next_is(&c, "ok");
	cl_next_is(&c, "ok");
	sim_marlin_stop(c.sim);
	ck_assert_str_eq(cl_log(&c), "1 G28\n2 G1 X10 Y5 F6000\n3 M400\n");
	cl_stop(&c);
}
END_TEST

START_TEST(bad_checksum)
{
	struct sim_marlin_options o;
	struct client c;
	char line[64];
	fast_opts(&o);
	cl_start(&c, &o);
	cl_send_n(&c, 1, "G21");
	cl_next_is(&c, "ok");
	snprintf(line, sizeof(line), "N2 G21*%u\n", (unsigned)(gcode_checksum("N2 G21", 6) ^ 1));
	cl_send(&c, line);
	cl_next_is(&c, "Error:checksum mismatch, Last Line: 1");
	cl_next_is(&c, "Resend: 2");
	cl_next_is(&c, "ok");
	cl_send_n(&c, 2, "G21");
	cl_next_is(&c, "ok");
	cl_stop(&c);
}
END_TEST

/* Marlin 2.1's flush_and_request_resend ends with a plain "ok", also with
 * ADVANCED_OK: that ok answers the resend request, not a command. */
START_TEST(line_error_plain_ok)
{
	struct sim_marlin_options o;
	struct client c;
	char bad[64];
	fast_opts(&o);
	o.advanced_ok = true;
	cl_start(&c, &o);
	cl_send_n(&c, 1, "G21");
	cl_expect(&c, "ok N1 ", NULL, 0, 2.0);
	snprintf(bad, sizeof(bad), "N2 G21*%u\n", (unsigned)(gcode_checksum("N2 G21", 6) ^ 1));
	cl_send(&c, bad);
	cl_next_is(&c, "Error:checksum mismatch, Last Line: 1");
	cl_next_is(&c, "Resend: 2");
	cl_next_is(&c, "ok");
	cl_send_n(&c, 2, "G21");
	cl_expect(&c, "ok N2 ", NULL, 0, 2.0);
	sim_marlin_stop(c.sim);
	ck_assert_str_eq(cl_log(&c), "1 G21\n2 G21\n");
	cl_stop(&c);
}
END_TEST

START_TEST(wrong_line_number)
{
	struct sim_marlin_options o;
	struct client c;
	fast_opts(&o);
	cl_start(&c, &o);
	cl_send_n(&c, 1, "G21");
	cl_next_is(&c, "ok");
	cl_send_n(&c, 3, "G21");
	cl_next_is(&c, "Error:Line Number is not Last Line Number+1, Last Line: 1");
	cl_next_is(&c, "Resend: 2");
	cl_next_is(&c, "ok");
	cl_send(&c, "N2 G21\n");
	cl_next_is(&c, "Error:No Checksum with line number, Last Line: 1");
	cl_next_is(&c, "Resend: 2");
	cl_next_is(&c, "ok");
	cl_stop(&c);
}
END_TEST

START_TEST(duplicate_ignored)
{
	struct sim_marlin_options o;
	struct client c;
	fast_opts(&o);
	o.advanced_ok = true;
	cl_start(&c, &o);
	cl_send_n(&c, 1, "G21");
	cl_expect(&c, "ok N1 ", NULL, 0, 2.0);
	cl_send_n(&c, 2, "G21");
	cl_expect(&c, "ok N2 ", NULL, 0, 2.0);
	cl_send_n(&c, 2, "G21");
	cl_send_n(&c, 1, "G21");
	cl_send_n(&c, 3, "G21");
	cl_expect(&c, "ok N3 ", NULL, 0, 2.0); /* the very next line: no reply to dups */
	sim_marlin_stop(c.sim);
	ck_assert_str_eq(cl_log(&c), "1 G21\n2 G21\n3 G21\n");
	cl_stop(&c);
}
END_TEST

START_TEST(m110_renumbers)
{
	struct sim_marlin_options o;
	struct client c;
	char line[128];
	fast_opts(&o);
	cl_start(&c, &o);
	cl_send_n(&c, 1, "G21");
	cl_next_is(&c, "ok");
	cl_send_n(&c, 7, "M110 N100");
	cl_next_is(&c, "ok");
	cl_send_n(&c, 101, "G21");
	cl_next_is(&c, "ok");
	cl_send(&c, "M110 N5\n");
	cl_next_is(&c, "ok");
	cl_send_n(&c, 6, "G21");
	ck_assert_int_ge(cl_line(&c, line, sizeof(line), 2.0), 0);
	ck_assert_str_eq(line, "ok");
	cl_stop(&c);
}
END_TEST

/* printcore starts a job with "N-1 M110*15": Marlin's parser skips a signed
 * line number, so the reply is a plain "ok" and the next line is N0. */
START_TEST(m110_negative_line_number)
{
	struct sim_marlin_options o;
	struct client c;
	char line[64];
	fast_opts(&o);
	cl_start(&c, &o);
	snprintf(line, sizeof(line), "N-1 M110*%u\n", (unsigned)gcode_checksum("N-1 M110", 8));
	cl_send(&c, line);
	cl_next_is(&c, "ok");
	cl_send_n(&c, 0, "G21");
	cl_next_is(&c, "ok");
	sim_marlin_stop(c.sim);
	ck_assert_str_eq(cl_log(&c), "-1 M110\n0 G21\n");
	cl_stop(&c);
}
END_TEST

START_TEST(m105_format)
{
	struct sim_marlin_options o;
	struct client c;
	fast_opts(&o);
	cl_start(&c, &o);
	cl_send(&c, "M105\n");
	cl_next_is(&c, "ok T:25.00 /0.00 B:25.00 /0.00 @:0 B@:0");
	cl_send_n(&c, 1, "M105");
	cl_next_is(&c, "ok T:25.00 /0.00 B:25.00 /0.00 @:0 B@:0");
	cl_send(&c, "M9999\n");
	cl_next_is(&c, "echo:Unknown command: \"M9999\"");
	cl_next_is(&c, "ok");
	cl_stop(&c);
}
END_TEST

/* G2/G3 run as Marlin's ARC_SUPPORT does, in 1 mm chords on the circle:
 * they end on the target, take the arc's length of machine time (not the
 * chord's), and an arc without its centre is refused with Marlin's words. */
START_TEST(arcs_in_chords)
{
	struct sim_marlin_options o;
	struct client c;
	double t0, t1;
	fast_opts(&o);
	cl_start(&c, &o);
	cl_send(&c, "G1 X10 Y0 F600\nM400\n");
	cl_next_is(&c, "ok");
	cl_next_is(&c, "ok");
	t0 = sim_marlin_machine_s(c.sim);
	/* a quarter round the origin: 15.7 mm at 10 mm/s in 15 chords (a
	 * straight line would be 14.1 mm) */
	cl_send(&c, "G3 X0 Y10 I-10 J0 E1\nM400\nM114\n");
	cl_next_is(&c, "ok");
	cl_next_is(&c, "ok");
	cl_next_is(&c, "X:0.00 Y:10.00 Z:0.00 E:1.00 Count X:0 Y:0 Z:0");
	cl_next_is(&c, "ok");
	t1 = sim_marlin_machine_s(c.sim) - t0;
	ck_assert_msg(t1 > 15 * (1.047 / 10 + 10 / 1000.0) - 0.01 && t1 < 1.8, "%.3f s", t1);
	cl_send(&c, "G2 X5 Y5\n");
	cl_next_is(&c, "Error:G2/G3 bad parameters");
	cl_next_is(&c, "ok");
	cl_stop(&c);
}
END_TEST

START_TEST(m115_caps)
{
	struct sim_marlin_options o;
	struct client c;
	char line[512];
	fast_opts(&o);
	cl_start(&c, &o);
	cl_send(&c, "M115\n");
	cl_next_is(&c, "FIRMWARE_NAME:Marlin 2.1.2 (Stratum simulator) "
		       "SOURCE_CODE_URL:github.com/MarlinFirmware/Marlin PROTOCOL_VERSION:1.0 "
		       "MACHINE_TYPE:Stratum Simulated Printer EXTRUDER_COUNT:1 "
		       "UUID:cede2a2f-41a2-4748-9b12-c55c62f367ff");
	int seen = 0;
	for (;;) {
		ck_assert_int_ge(cl_line(&c, line, sizeof(line), 2.0), 0);
		if (!strcmp(line, "ok"))
			break;
		ck_assert_msg(!strncmp(line, "Cap:", 4), "unexpected line '%s'", line);
		if (!strcmp(line, "Cap:EMERGENCY_PARSER:1") || !strcmp(line, "Cap:AUTOREPORT_TEMP:1") ||
		    !strcmp(line, "Cap:HOST_ACTION_COMMANDS:1") || !strcmp(line, "Cap:ADVANCED_OK:0"))
			seen++;
	}
	ck_assert_int_eq(seen, 4);
	cl_stop(&c);
}
END_TEST

START_TEST(advanced_ok)
{
	struct sim_marlin_options o;
	struct client c;
	fast_opts(&o);
	o.advanced_ok = true;
	cl_start(&c, &o);
	cl_send_n(&c, 1, "G21");
	cl_next_is(&c, "ok N1 P16 B3");
	cl_send(&c, "G90\n");
	cl_next_is(&c, "ok P16 B3");
	cl_send_n(&c, 2, "G1 X100 F600");
	cl_next_is(&c, "ok N2 P15 B3");
	cl_stop(&c);
}
END_TEST

START_TEST(m109_waits)
{
	struct sim_marlin_options o;
	struct client c;
	char line[512];
	fast_opts(&o);
	cl_start(&c, &o);
	double t0 = st_mono_s();
	cl_send_n(&c, 1, "M109 S200");
	int reports = 0;
	for (;;) {
		ck_assert_int_ge(cl_line(&c, line, sizeof(line), 3.0), 0);
		if (!strcmp(line, "ok"))
			break;
		if (!strncmp(line, " T:", 3)) {
			size_t n = strlen(line);
			ck_assert_msg(n > 4 && !strcmp(line + n - 4, " W:?"), "report '%s'", line);
			reports++;
		}
	}
	double dt = st_mono_s() - t0;
	/* 25 -> 199 degC at 2 degC/s, 100 times faster: about 0.87 s. */
	ck_assert_msg(dt > 0.7 && dt < 2.5, "M109 took %.2f s", dt);
	ck_assert_int_gt(reports, 20);
	cl_send(&c, "M105\n");
	cl_expect(&c, "ok T:", line, sizeof(line), 2.0);
	ck_assert_msg(strstr(line, "/200.00 B:") != NULL, "'%s'", line);
	cl_stop(&c);
}
END_TEST
START_TEST(busy_keepalive)
{
	struct sim_marlin_options o;
	struct client c;
	char line[512];
	fast_opts(&o);
	cl_start(&c, &o);
	cl_send_n(&c, 1, "G4 S250"); /* 2.5 s of wall time at speedup 100 */
	ck_assert_int_ge(cl_line(&c, line, sizeof(line), 3.0), 0);
	ck_assert_str_eq(line, "echo:busy: processing");
	cl_next_is(&c, "ok");
	cl_stop(&c);
}
END_TEST
/* An idle link banks no capacity: a ping-pong host that pauses between
 * lines still pays one byte time per byte, line and "ok" alike. */
START_TEST(pacing_after_idle)
{
	struct sim_marlin_options o;
	struct client c;
	char cmd[64], framed[96];
	size_t bytes = 0;
	fast_opts(&o);
	o.baud = 115200; /* 11 520 bytes/s */
	o.speedup = 1e6;
	cl_start(&c, &o);
	double t0 = st_mono_s();
	for (long n = 1; n <= 60; n++) {
		snprintf(cmd, sizeof(cmd), "G1 X%.3f Y100.000 E0.01660", 100 + n * 0.5);
		ck_assert_int_gt(gcode_format_numbered(framed, sizeof(framed), n, cmd), 0);
		bytes += strlen(framed) + 1 + 3; /* the line, its newline, "ok\n" */
		cl_send_n(&c, n, cmd);
		cl_next_is(&c, "ok");
		usleep(5000); /* idle: a token bucket would refill here */
	}
	double wire = (double)bytes / 11520.0, dt = st_mono_s() - t0 - 60 * 0.005;
	ck_assert_msg(dt > 0.97 * wire, "%zu bytes took %.3f s on the link, less than the %.3f s "
		      "115200 baud needs", bytes, dt, wire);
	cl_stop(&c);
}
END_TEST

START_TEST(pacing)
{
	struct sim_marlin_options o;
	struct client c;
	fast_opts(&o);
	o.baud = 9600; /* 960 bytes/s */
	cl_start(&c, &o);
	double t0 = st_mono_s();
	cl_send(&c, "M115\n"); /* about 1 KiB of reply */
	cl_expect(&c, "ok", NULL, 0, 5.0);
	double dt = st_mono_s() - t0;
	ck_assert_msg(dt > 0.8, "1 KiB at 9600 baud took only %.2f s", dt);
	cl_stop(&c);
}
END_TEST

Suite *sim_suite(void)
{
	Suite *s = suite_create("sim");
	TCase *proto = tcase_create("protocol");

	tcase_set_timeout(proto, 20);
	tcase_add_test(proto, boot_banner);
	tcase_add_test(proto, ok_and_log);
	tcase_add_test(proto, bad_checksum);
	tcase_add_test(proto, line_error_plain_ok);
	tcase_add_test(proto, wrong_line_number);
	tcase_add_test(proto, duplicate_ignored);
	tcase_add_test(proto, m110_renumbers);
	tcase_add_test(proto, m110_negative_line_number);
	tcase_add_test(proto, m105_format);
	tcase_add_test(proto, arcs_in_chords);
	tcase_add_test(proto, m115_caps);
	tcase_add_test(proto, advanced_ok);
	tcase_add_test(proto, m109_waits);
	tcase_add_test(proto, pacing);
	tcase_add_test(proto, pacing_after_idle);
	tcase_add_test(proto, busy_keepalive);
	suite_add_tcase(s, proto);
	sim_faults_tcases(s);
	return s;
}
