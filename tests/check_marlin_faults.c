/*
 * check_marlin_faults.c - the Marlin driver against the simulated Marlin,
 * part of the marlin suite (check_marlin.c): a board that hangs, kept or
 * lost replies, bare or late answers, long busy spells, the emergency halt
 * and the safe stop, lost newlines, errors that shrink the window, and a
 * printer that never answers.
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gcode.h"
#include "marlin.h"
#include "marlintest.h"
#include "printer.h"
#include "sim/marlin_sim.h"
#include "st_clock.h"
#include "suites.h"
#include "testutil.h"
#include "xport.h"

/* A board that hangs (no byte in or out, like kill -STOP) while lines are
 * in flight: the probes must not keep the dead-link clock young; the job
 * ends as a link failure within dead_ms (+ a probe), naming the last line. */
START_TEST(frozen_detected)
{
	struct sim_marlin_options so;
	fast_sim(&so);
	so.freeze_at_line = 900;
	fault_ends_job(&so, 900, "stopped answering", "last line acknowledged", 5.0 + 1.5);
}
END_TEST

/* The same hang during a heat wait of a firmware that reports while it
 * waits: dead_ms applies, not the 10 minutes allowed a silent G28/M109. */
START_TEST(frozen_in_heat_wait_detected)
{
	struct rig r;
	struct sim_marlin_options so;
	struct printer_options mo;
	struct st_error err = {0};
	struct marlin_status st;
	fast_sim(&so);
	so.speedup = 40; /* a first wait of a few seconds with W: reports */
	so.freeze_at_line = 4; /* the second M109 (M155 is N2) */
	fast_driver(&mo);
	rig_start(&r, &so, &mo);
	double t0 = st_mono_s();
	ck_assert_int_eq(stream_text(&r, "M109 S100\nM109 S200\nG1 X1\n", &err),
			 PRINTER_END_LINK_LOST);
	marlin_status(r.m, &st);
	ck_assert_int_eq(st.fail, MARLIN_FAIL_LINK);
	ck_assert_msg(strstr(err.msg, "stopped answering"), "%s", err.msg);
	ck_assert_double_lt(st_mono_s() - t0, 15.0);
	rig_stop(&r);
}
END_TEST

/* A firmware that keeps the bytes behind a bad line and answers each
 * (Error, Resend, ok per stale copy): late Resends un-ack lines it has
 * run, and the host must take them back when it says it has them, not
 * rewrite them for ever.  Every line runs once, in order. */
START_TEST(stream_keep_rx_no_livelock)
{
	static const double rate[] = {0.005, 0.01};
	for (size_t i = 0; i < 2; i++) {
		struct sim_marlin_options so;
		struct printer_options mo;
		fast_sim(&so);
		fast_driver(&mo);
		so.keep_rx_on_error = true;
		so.corrupt_p = rate[i];
		so.seed = 5 + i;
		struct marlin_status st = stream_and_check(&so, &mo, FAULTY / (1 + 4 * (long)i));
		ck_assert_uint_gt(st.line_errors, FAULTY / 50);
	}
}
END_TEST

/* oks lost on the way back: each leaves the host counting
 * lines in flight that the firmware has run; the probe's answer ("Resend:
 * last + 1") must settle them, or the window stays shut and the host
 * rewrites the same lines for ever. */
START_TEST(stream_lost_oks_no_livelock)
{
	struct sim_marlin_options so;
	struct printer_options mo;
	fast_sim(&so);
	fast_driver(&mo);
	so.reply_loss_p = 0.01;
	so.corrupt_p = 0.005;
	so.seed = 13;
	struct marlin_status st = stream_and_check(&so, &mo, 2000);
	ck_assert_uint_gt(st.resend_requests, 10);
}
END_TEST

/* M115 answered with a bare "ok": online, capabilities unknown. */
START_TEST(m115_bare_ok)
{
	struct sim_marlin_options so;
	struct printer_options mo;
	fast_sim(&so);
	fast_driver(&mo);
	so.no_firmware_name = true;
	struct marlin_status st = stream_and_check(&so, &mo, 2000);
	ck_assert_uint_eq(st.stray_oks, 0);
}
END_TEST

/* ADVANCED_OK with moves slow enough to fill the planner: the head command
 * blocks, the firmware reads no input meanwhile, and the window must still
 * fit the 128-byte ring: not one byte lost. */
START_TEST(advanced_ok_no_overflow)
{
	struct rig r;
	struct sim_marlin_options so;
	struct printer_options mo;
	struct st_error err = {0};
	fast_sim(&so);
	/* slow enough that the planner is full for most of the job (about
	 * 2,000 of the 3,000 moves wait for a slot, as at 100) */
	so.speedup = 300;
	so.advanced_ok = true;
	fast_driver(&mo);
	FILE *f = gen_file(3000);
	rig_start(&r, &so, &mo);
	ck_assert_msg(rig_stream(&r, GEN_PATH, &err) == PRINTER_END_DONE, "%s", err.msg);
	sim_marlin_stop(r.sim);
	ck_assert_uint_eq(sim_marlin_dropped_bytes(r.sim), 0);
	ck_assert_int_eq(check_log(&r, f), 3003);
	rig_stop(&r);
	fclose(f);
}
END_TEST

/* Minutes of "busy" (a long G29, a filament change) are not a dead link:
 * the keep-alives hold the job (here 8 s against a 5 s dead_ms). */
START_TEST(long_busy_survives)
{
	struct sim_marlin_options so;
	struct printer_options mo;
	fast_sim(&so);
	fast_driver(&mo);
	mo.probe_ms = 3000; /* longer than the 2 s between keep-alives */
	so.busy_at_line = 300;
	so.busy_s = 8;
	struct marlin_status st = stream_and_check(&so, &mo, 1000);
	ck_assert_uint_ge(st.busy, 3);
	ck_assert_uint_eq(st.resends, 0);
}
END_TEST

/* M112 through the emergency parser halts the board: the firmware's
 * "Error:Printer halted. kill() called!" stops the job, nothing is resent. */
START_TEST(halt_stops_without_resend)
{
	struct rig r;
	struct sim_marlin_options so;
	struct printer_options mo;
	struct marlin_status st;
	struct st_error err = {0};
	fast_sim(&so);
	so.speedup = 20; /* the G4 keeps the queue busy for 0.5 s */
	fast_driver(&mo);
	rig_start(&r, &so, &mo);
	ck_assert(marlin_caps(r.m)->emergency_parser);
	ck_assert_int_eq(marlin_submit(r.m, "G4 S10", 1, -1, NAN, &err), 1);
	for (int i = 0; i < 20; i++)
		ck_assert_int_eq(marlin_submit(r.m, "G1 X5 F3000", (uint64_t)i + 2, -1, NAN, &err), 1);
	ck_assert_int_eq(marlin_step(r.m, 50, &err), 0);
	ck_assert_int_eq(marlin_emergency(r.m, "M112", &err), 0);
	int rc = 0;
	for (int i = 0; i < 40 && rc == 0; i++)
		rc = marlin_step(r.m, 50, &err);
	ck_assert_int_eq(rc, ST_ERR_IO);
	marlin_status(r.m, &st);
	ck_assert_int_eq(st.fail, MARLIN_FAIL_FIRMWARE);
	ck_assert_msg(strstr(err.msg, "Printer halted"), "%s", err.msg);
	ck_assert_uint_eq(st.resends, 0);
	ck_assert(sim_marlin_halted(r.sim));
	rig_stop(&r);
}
END_TEST

/* Cancel, then the safe stop: heaters and motors off reach the firmware. */
START_TEST(cancel_safe_stop)
{
	struct rig r;
	struct sim_marlin_options so;
	struct printer_options mo;
	struct marlin_status st;
	struct st_error err = {0};
	char line[256];
	fast_sim(&so);
	so.speedup = 50;
	fast_driver(&mo);
	rig_start(&r, &so, &mo);
	ck_assert_int_eq(marlin_submit(r.m, "M104 S200", 1, -1, NAN, &err), 1);
	for (int i = 0; i < 200; i++)
		ck_assert_int_eq(marlin_submit(r.m, "G1 X50 F3000", 2, -1, NAN, &err), 1);
	ck_assert_int_eq(marlin_step(r.m, 50, &err), 0);
	marlin_request_cancel(r.m);
	ck_assert_int_eq(marlin_step(r.m, 10, &err), ST_ERR_IO);
	marlin_status(r.m, &st);
	ck_assert_int_eq(st.fail, MARLIN_FAIL_CANCELLED);
	ck_assert_msg(marlin_safe_stop(r.m, 5000, &err) == 0, "%s", err.msg);
	sim_marlin_stop(r.sim);
	fflush(r.log);
	rewind(r.log);
	bool m84 = false, m104 = false, m140 = false;
	long moves = 0;
	while (fgets(line, sizeof(line), r.log)) {
		m84 = m84 || strstr(line, "M84");
		m104 = m104 || strstr(line, "M104 S0");
		m140 = m140 || strstr(line, "M140 S0");
		moves += strstr(line, "G1 X50") != NULL;
	}
	ck_assert(m84 && m104 && m140);
	ck_assert_int_lt(moves, 200); /* the rest of the job was not sent */
	rig_stop(&r);
}
END_TEST

/* The job's last line arrives with its number spoilt into the one before
 * (noise on a digit of N): Marlin drops it silently as a duplicate, no
 * error, no ok.  Nothing follows to draw a Resend, and the M105 probe's
 * "ok T:" acknowledged it, so the job ended one line short (marlin suite,
 * corrupt, once in a two-lane run).  The probe now vouches only for the
 * lines before its last; the last one is asked for by the older probe. */
START_TEST(last_line_dropped_as_duplicate)
{
	struct sim_marlin_options so;
	struct printer_options mo;
	fast_sim(&so);
	fast_driver(&mo);
	so.spoil_number_at = 55; /* N55: the last of the 53 job lines after M110, M115 */
	struct marlin_status st = stream_and_check(&so, &mo, 50);
	ck_assert_uint_ge(st.resend_requests, 1); /* the firmware was asked where it is */
}
END_TEST

/*
 * The board stalls (freeze_s) just before the job's last two lines run,
 * and the host's probes pile up in its ring.  After the stall Marlin
 * reads its ring before it runs the next command, so the older probe's
 * copy draws "Resend: last + 1" before any ok, with both lines still in
 * its queue (BUFSIZE 32 holds them and the probes).  A Resend says which
 * lines the firmware has, not which ran: counting them as run made the
 * oks that followed count for later lines, and the job ended before the
 * board ran its last line, here a 2 s one (long_busy and corrupt, once
 * each in loaded two-lane runs).
 */
START_TEST(stall_before_last_lines)
{
	struct rig r;
	struct sim_marlin_options so;
	struct printer_options mo;
	struct marlin_status st;
	struct st_error err = {0};
	const char *path = tu_path("marlin-stall.gcode");
	FILE *f = fopen(path, "w");
	ck_assert_ptr_nonnull(f);
	fputs("G21\nG90\nM83\n", f);
	for (int i = 0; i < 20; i++)
		fprintf(f, "G1 X%d\n", i % 2 ? 0 : 5);
	fclose(f);
	const long last = 25; /* M110 and M115 first: the job is N3-N25 */
	fast_sim(&so);
	so.bufsize = 32;
	so.freeze_at_line = last - 1;
	so.freeze_s = 4;
	so.busy_at_line = last;
	so.busy_s = 2;
	fast_driver(&mo);
	mo.probe_ms = 800;
	rig_start(&r, &so, &mo);
	ck_assert_int_eq(rig_stream(&r, path, &err), PRINTER_END_DONE);
	long answered = sim_marlin_answered_line(r.sim);
	marlin_status(r.m, &st);
	rig_stop(&r);
	ck_assert_uint_ge(st.resend_requests, 1); /* the stall drew the older probe */
	ck_assert_msg(answered == last, "done with N%ld the last line answered, not N%ld",
		      answered, last);
}
END_TEST

/*
 * long_busy with its last line held for 1 s (a freeze), so that a job
 * declared done early shows.  The M105 probes written before the first
 * "busy" report were given up as overdue 3 s later, though the firmware
 * said it was busy; their answers came after the busy line, and, taken
 * for lines' oks, ended the job a line early per probe (long_busy,
 * "stopped after 1001" of 1003, in CI, when the simulator was too slow
 * to run the last lines before the test stopped it).
 */
START_TEST(long_busy_late_answers)
{
	struct sim_marlin_options so;
	struct printer_options mo;
	struct rig_result res;
	fast_sim(&so);
	fast_driver(&mo);
	mo.probe_ms = 3000;
	so.busy_at_line = 300;
	so.busy_s = 8;
	so.freeze_at_line = 1005; /* the last: M110 and M115 come first */
	so.freeze_s = 1;
	struct marlin_status st = stream_and_check_r(&so, &mo, 1000, &res);
	ck_assert_uint_ge(st.busy, 3);
	ck_assert_msg(res.answered == 1005, "done with N%ld the last line answered, not N1005",
		      res.answered);
}
END_TEST

/*
 * The last line's '*' arrives as a newline (one bit flipped): the line
 * errs for its missing checksum, and its checksum digits, a byte time
 * behind, run as an unknown command that Marlin answers "ok".  That ok is
 * no line's: counted for the line asked for again, it ended the job
 * before the line was written again (lost_oks, "stopped after 2002" of
 * 2003).
 */
START_TEST(fragment_ok_counts_for_no_line)
{
	struct sim_marlin_options so;
	struct printer_options mo;
	struct rig_result res;
	fast_sim(&so);
	fast_driver(&mo);
	so.star_to_newline_at = 55; /* the last of the 53 job lines after M110, M115 */
	struct marlin_status st = stream_and_check_r(&so, &mo, 50, &res);
	ck_assert_uint_ge(st.unknown_commands, 1);
	ck_assert_int_eq(res.unnumbered, 1);
}
END_TEST

/* Two lines lose their newline (the one after connect, M155, and one in
 * the job): each waits in the firmware until the M105 probe's "\n" ends
 * it.  The probe must come within a few round trips, not after probe_ms:
 * before, the first ok after the first probe (3 s) was taken as a
 * round-trip sample, and with no sample from the handshake the first
 * wait was the whole probe_ms, so at 4 % of bytes hit the job ran at 6
 * lines/s (docs/reliability.md). */
START_TEST(lost_newlines_probed_at_once)
{
	struct sim_marlin_options so;
	struct printer_options mo;
	struct rig_result res;
	fast_sim(&so);
	fast_driver(&mo);
	mo.probe_ms = 3000; /* the default */
	so.lose_newline_at[0] = 2;
	so.lose_newline_at[1] = 30;
	stream_and_check_r(&so, &mo, 50, &res);
	ck_assert_msg(res.seconds < 1.5, "%.2f s: the probe waited for probe_ms", res.seconds);
}
END_TEST

/* At 2 % corruption and 2 % drops with ADVANCED_OK, each error rewinds
 * the window and every line after the spoilt one is written again
 * (go-back-N): at full window about 12 writes a line.  The window halves
 * with each rewind and grows with each ack. */
START_TEST(window_shrinks_under_errors)
{
	struct sim_marlin_options so;
	struct printer_options mo;
	fast_sim(&so);
	fast_driver(&mo);
	so.advanced_ok = true;
	so.corrupt_p = so.drop_p = 0.02;
	so.seed = 11;
	undetectable_per_mille = 80;
	struct marlin_status st = stream_and_check(&so, &mo, 120);
	undetectable_per_mille = 5;
	ck_assert_msg(st.resends < 8 * 123, "%llu lines written again for 123",
		      (unsigned long long)st.resends);
}
END_TEST

/* Count the log lines that hold text. */
static long log_count(struct rig *r, const char *text)
{
	char line[256];
	long k = 0;
	fflush(r->log);
	rewind(r->log);
	while (fgets(line, sizeof(line), r->log))
		k += strstr(line, text) != NULL;
	return k;
}

/* Cancel while M190 waits, M109 queued behind it: every unnumbered line
 * (probes, M108) waits in the RX ring with the job's lines and must be
 * counted there.  Before they were, the ring overflowed: a stop line was
 * spoilt and the M108 for the M109 was lost, so the heater wait ran on. */
START_TEST(stop_in_heat_wait_no_overflow)
{
	static const char *const start[] = {"M140 S60", "M104 S200", "G28", "M190 S60",
					    "M109 S200"};
	struct rig r;
	struct sim_marlin_options so;
	struct printer_options mo;
	struct st_error err = {0};
	fast_sim(&so);
	so.speedup = 5; /* heating takes seconds */
	so.advanced_ok = true;
	fast_driver(&mo);
	rig_start(&r, &so, &mo);
	for (size_t i = 0; i < sizeof(start) / sizeof(start[0]); i++)
		ck_assert_int_eq(marlin_submit(r.m, start[i], i + 1, -1, NAN, &err), 1);
	for (int i = 0; i < 40; i++)
		ck_assert_int_eq(marlin_submit(r.m, "G1 X50 Y60 F3000", (uint64_t)i + 6, -1, NAN, &err), 1);
	double end = st_mono_s() + 3;
	while (st_mono_s() < end)
		ck_assert_msg(marlin_step(r.m, 50, &err) == 0, "%s", err.msg);
	marlin_request_cancel(r.m);
	ck_assert_int_eq(marlin_step(r.m, 10, &err), ST_ERR_IO);
	ck_assert_msg(marlin_safe_stop(r.m, 5000, &err) == 0, "%s", err.msg);
	sim_marlin_stop(r.sim);
	ck_assert_uint_eq(sim_marlin_dropped_bytes(r.sim), 0);
	ck_assert_int_eq(log_count(&r, "M109"), 1);
	ck_assert_int_eq(log_count(&r, "M108"), 2); /* one for each wait */
	ck_assert_int_eq(log_count(&r, "M84"), 1);
	rig_stop(&r);
}
END_TEST

/* A printer that never answers: connect gives up with a clear error. */
START_TEST(connect_no_answer)
{
	struct sim_marlin_options so;
	struct sim_marlin *sim;
	struct xport *x;
	struct marlin *m;
	struct marlin_options mo;
	struct st_error err = {0};
	fast_sim(&so);
	ck_assert_int_eq(sim_marlin_new(&so, &sim, &err), 0); /* not running: silent */
	ck_assert_int_eq(xport_open(sim_marlin_slave_path(sim), NULL, &x, &err), 0);
	marlin_options_init(&mo);
	mo.retry_ms = 300;
	mo.connect_timeout_ms = 700;
	ck_assert_int_eq(marlin_new(x, &mo, &m, &err), 0);
	ck_assert_int_eq(marlin_connect(m, &err), ST_ERR_IO);
	ck_assert_msg(strstr(err.msg, "no answer"), "%s", err.msg);
	marlin_free(m);
	xport_close(x);
	sim_marlin_free(sim);
}
END_TEST

void marlin_faults_tcases(Suite *s)
{
	marlin_add_case(s, "halt", halt_stops_without_resend, 60);
	marlin_add_case(s, "cancel", cancel_safe_stop, 60);
	marlin_add_case(s, "stop_in_heat_wait", stop_in_heat_wait_no_overflow, 60);
	marlin_add_case(s, "last_line_dropped", last_line_dropped_as_duplicate, 60);
	marlin_add_case(s, "lost_newlines", lost_newlines_probed_at_once, 60);
	marlin_add_case(s, "window_shrinks", window_shrinks_under_errors, 120);
	marlin_add_case(s, "connect_no_answer", connect_no_answer, 60);
	marlin_add_case(s, "frozen", frozen_detected, 20);
	marlin_add_case(s, "frozen_heat_wait", frozen_in_heat_wait_detected, 40);
	marlin_add_case(s, "keep_rx", stream_keep_rx_no_livelock, 120);
	marlin_add_case(s, "m115_bare_ok", m115_bare_ok, 60);
	marlin_add_case(s, "lost_oks", stream_lost_oks_no_livelock, 60);
	marlin_add_case(s, "advanced_ok_no_overflow", advanced_ok_no_overflow, 120);
	marlin_add_case(s, "long_busy", long_busy_survives, 60);
	marlin_add_case(s, "stall_before_last_lines", stall_before_last_lines, 60);
	marlin_add_case(s, "long_busy_late_answers", long_busy_late_answers, 60);
	marlin_add_case(s, "fragment_ok", fragment_ok_counts_for_no_line, 60);
}
