/*
 * check_marlin.c - the Marlin driver (serial/marlin.c) against the
 * simulated Marlin over a pty, in-process, files streamed through the
 * printer interface (serial/printer.h, the one path send, print and the
 * node use) with the simulator's faults set here: generated files streamed clean
 * and through every fault the simulator injects, with the execution log
 * compared line by line with the file; M109 waits, reset and unplug.
 * Hangs, lost replies, busy firmware and stops are in check_marlin_faults.c,
 * reply parsing in check_marlin_parse.c, the rig in marlintest.c.
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "gcode.h"
#include "marlin.h"
#include "marlintest.h"
#include "printer.h"
#include "sim/marlin_sim.h"
#include "st_clock.h"
#include "suites.h"
#include "testutil.h"
#include "xport.h"

static void big_ring(struct sim_marlin_options *so, struct printer_options *mo)
{
	fast_sim(so);
	fast_driver(mo);
	so->rx_buffer = 1024;
	mo->rx_buffer = 1024;
}

START_TEST(stream_clean)
{
	struct sim_marlin_options so;
	struct printer_options mo;
	big_ring(&so, &mo);
	struct marlin_status st = stream_and_check(&so, &mo, BIG);
	ck_assert_uint_eq(st.resends, 0);
	ck_assert_uint_eq(st.line_errors, 0);
	ck_assert_int_eq(st.layer, (BIG - 1) / 1000);
}
END_TEST

/*
 * A stall on a clean link (the board, or the loaded computer running the
 * host, held still for longer than probe_ms, as a loaded machine does to
 * the clean run): the probe fires while the firmware's ring still holds a
 * full window of lines.  A stall shorter than two probes must cost
 * nothing: no resend, no overflow (fragments run), no cascade.
 */
START_TEST(stream_clean_stall)
{
	struct sim_marlin_options so;
	struct printer_options mo;
	struct rig_result res;
	big_ring(&so, &mo);
	so.freeze_at_line = 3000;
	so.freeze_s = 0.8;
	struct marlin_status st = stream_and_check_r(&so, &mo, SMALL, &res);
	ck_assert_uint_eq(st.resends, 0);
	ck_assert_uint_eq(st.line_errors, 0);
	ck_assert_uint_eq(res.dropped, 0);
	ck_assert_int_eq(res.unnumbered, 0);
}
END_TEST

START_TEST(stream_corrupt)
{
	struct sim_marlin_options so;
	struct printer_options mo;
	fast_sim(&so);
	fast_driver(&mo);
	so.corrupt_p = 0.01;
	so.seed = 7;
	struct marlin_status st = stream_and_check(&so, &mo, FAULTY);
	ck_assert_uint_gt(st.line_errors, FAULTY / 20);
	ck_assert_uint_gt(st.resends, FAULTY / 20);
}
END_TEST

START_TEST(stream_drop)
{
	struct sim_marlin_options so;
	struct printer_options mo;
	fast_sim(&so);
	fast_driver(&mo);
	so.drop_p = 0.005;
	so.seed = 11;
	struct marlin_status st = stream_and_check(&so, &mo, FAULTY);
	ck_assert_uint_gt(st.resends, FAULTY / 100);
}
END_TEST

START_TEST(stream_advanced_ok_faults)
{
	struct sim_marlin_options so;
	struct printer_options mo;
	fast_sim(&so);
	fast_driver(&mo);
	so.advanced_ok = true;
	so.corrupt_p = 0.005;
	so.drop_p = 0.002;
	so.seed = 3;
	struct marlin_status st = stream_and_check(&so, &mo, FAULTY);
	ck_assert_uint_gt(st.resends, FAULTY / 100);
}
END_TEST

/* A small ring: the window must never overflow it (no line errors). */
START_TEST(stream_rx32)
{
	struct sim_marlin_options so;
	struct printer_options mo;
	fast_sim(&so);
	fast_driver(&mo);
	so.rx_buffer = mo.rx_buffer = 32;
	struct marlin_status st = stream_and_check(&so, &mo, 3000) /* one line at a time: slow */;
	ck_assert_uint_eq(st.line_errors, 0);
}
END_TEST

START_TEST(stream_rx32_advanced_ok)
{
	struct sim_marlin_options so;
	struct printer_options mo;
	fast_sim(&so);
	fast_driver(&mo);
	so.rx_buffer = mo.rx_buffer = 32;
	so.advanced_ok = true;
	struct marlin_status st = stream_and_check(&so, &mo, SMALL);
	ck_assert_uint_eq(st.line_errors, 0);
}
END_TEST

START_TEST(stream_rx128)
{
	struct sim_marlin_options so;
	struct printer_options mo;
	fast_sim(&so);
	fast_driver(&mo);
	struct marlin_status st = stream_and_check(&so, &mo, SMALL);
	ck_assert_uint_eq(st.line_errors, 0);
}
END_TEST

/* Motion is the limit, so the command queue stays full: the bytes beyond
 * the queue must still fit the ring. */
START_TEST(stream_queue_full)
{
	struct sim_marlin_options so;
	struct printer_options mo;
	fast_sim(&so);
	so.speedup = 2000;
	fast_driver(&mo);
	struct marlin_status st = stream_and_check(&so, &mo, 1000);
	ck_assert_uint_eq(st.line_errors, 0);
	ck_assert_uint_eq(st.resends, 0);
}
END_TEST

/* M109 waits minutes of simulated time, several real seconds, with only
 * temperature and busy lines meanwhile: no time-out, no resend, although
 * the probe time-out is far shorter than the wait. */
START_TEST(m109_no_timeout)
{
	struct rig r;
	struct sim_marlin_options so;
	struct printer_options mo;
	struct marlin_status st;
	struct st_error err = {0};
	fast_sim(&so);
	so.speedup = 40; /* 25 -> 200 degC at 2 degC/s: 87 s simulated, ~2.2 s real */
	fast_driver(&mo);
	mo.probe_ms = 300;
	mo.dead_ms = 1000;
	rig_start(&r, &so, &mo);
	double t0 = st_mono_s();
	enum printer_end end = stream_text(&r, "M104 S200\nM109 S200\nG1 X10 F3000\nM400\n", &err);
	ck_assert_msg(end == PRINTER_END_DONE, "%s", err.msg);
	ck_assert_double_gt(st_mono_s() - t0, 1.5);
	marlin_status(r.m, &st);
	ck_assert_uint_eq(st.resends, 0);
	ck_assert_uint_eq(st.acked, 4);
	ck_assert(st.tool[0].present);
	ck_assert_double_ge(st.tool[0].actual, 190.0); /* last report before the end */
	ck_assert_double_eq(st.tool[0].target, 200.0);
	rig_stop(&r);
}
END_TEST
/* A board reset mid-stream ("start" again) ends the job with a clear
 * error naming the last line acknowledged. */
START_TEST(reset_detected)
{
	struct sim_marlin_options so;
	fast_sim(&so);
	so.reset_at_line = 500;
	fault_ends_job(&so, 500, "restarted", "last line acknowledged", 4.0);
}
END_TEST

/* The cable pulled mid-stream: the port hangs up, the job ends. */
START_TEST(unplug_detected)
{
	struct sim_marlin_options so;
	fast_sim(&so);
	so.unplug_at_line = 700;
	fault_ends_job(&so, 700, "closed", "last line acknowledged", 4.0);
}
END_TEST

Suite *marlin_suite(void)
{
	Suite *s = suite_create("marlin");
	marlin_add_case(s, "clean", stream_clean, 120);
	marlin_add_case(s, "clean_stall", stream_clean_stall, 60);
	marlin_add_case(s, "corrupt", stream_corrupt, 120);
	marlin_add_case(s, "drop", stream_drop, 120);
	marlin_add_case(s, "advanced_ok_faults", stream_advanced_ok_faults, 120);
	marlin_add_case(s, "rx32", stream_rx32, 120);
	marlin_add_case(s, "rx32_advanced_ok", stream_rx32_advanced_ok, 120);
	marlin_add_case(s, "rx128", stream_rx128, 120);
	marlin_add_case(s, "queue_full", stream_queue_full, 120);
	marlin_add_case(s, "m109", m109_no_timeout, 60);
	marlin_add_case(s, "reset", reset_detected, 60);
	marlin_add_case(s, "unplug", unplug_detected, 60);
	marlin_faults_tcases(s);
	marlin_parse_tcases(s);
	return s;
}
