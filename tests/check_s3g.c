/*
 * check_s3g.c - the S3G packet layer and driver (serial/s3g*.c) and the
 * simulated Sailfish printer (serial/sim/sailfish_sim.c): queries, thousands
 * of packets streamed over a pty with nothing lost or doubled (clean, 1 % corruption
 * both ways, a small buffer), reset and unplug detection, and Debian's gpx
 * driving the simulator as a real host.  CRC vectors, framing, resync and
 * command lengths are in check_s3g_packets.c.
 */
#include <check.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "s3g.h"
#include "sim/sailfish_sim.h"
#include "st_clock.h"
#include "suites.h"
#include "testutil.h"
#include "xport.h"

/* A simulator on its thread and our driver on its pty. */
struct rig {
	struct sim_sailfish *sim;
	struct xport *x;
	struct s3g *d;
	FILE *log;
};

/* Simulator options for tests that are not about timing. */
static void fast_sim(struct sim_sailfish_options *o)
{
	sim_sailfish_options_init(o);
	o->speedup = 200;
	o->baud = 1000000;
	o->seed = 7;
}

/* Driver options with short time-outs (still above the firmware's 200 ms). */
static void fast_drv(struct s3g_options *o)
{
	s3g_options_init(o);
	o->timeout_ms = 300;
	o->stats_ms = 100;
	o->quiet_ms = 5;
	o->poll_ms = 1;
}

static void rig_start(struct rig *r, struct sim_sailfish_options *so, const struct s3g_options *d)
{
	struct st_error err = {0};
	struct xport_options xo = {.baudrate = 115200};
	memset(r, 0, sizeof(*r));
	r->log = tmpfile();
	ck_assert_ptr_nonnull(r->log);
	so->log_fp = r->log;
	ck_assert_int_eq(sim_sailfish_new(so, &r->sim, &err), 0);
	ck_assert_msg(xport_open(sim_sailfish_slave_path(r->sim), &xo, &r->x, &err) == 0, "%s",
		      err.msg);
	ck_assert_int_eq(s3g_new(r->x, d, &r->d, &err), 0);
	ck_assert_int_eq(sim_sailfish_start_thread(r->sim, &err), 0);
}

static void rig_stop(struct rig *r)
{
	sim_sailfish_stop(r->sim);
	s3g_free(r->d);
	xport_close(r->x);
	sim_sailfish_free(r->sim);
	fclose(r->log);
}

/* n commands: build start, n-2 tiny x3g moves with X = 10 * i, build end.
 * Payload storage is returned in *store (caller frees). */
static struct s3g_cmd *make_stream(size_t n, uint32_t rate, uint8_t **store)
{
	struct s3g_cmd *c = calloc(n, sizeof(*c));
	uint8_t *b = calloc(n, 32);
	ck_assert(c && b && n >= 2);
	static const uint8_t start[] = {153, 0, 0, 0, 0, 't', 'e', 's', 't', 0};
	memcpy(b, start, sizeof(start));
	c[0] = (struct s3g_cmd){b, sizeof(start)};
	for (size_t i = 1; i + 1 < n; i++) {
		uint8_t *p = b + 32 * i;
		int32_t x = (int32_t)(10 * i);
		float mm = 0.1f;
		uint32_t fb;
		memset(p, 0, 32);
		p[0] = 155;
		for (int k = 0; k < 4; k++)
			p[1 + k] = (uint8_t)((uint32_t)x >> (8 * k));
		for (int k = 0; k < 4; k++)
			p[21 + k] = (uint8_t)(rate >> (8 * k));
		memcpy(&fb, &mm, 4);
		for (int k = 0; k < 4; k++)
			p[26 + k] = (uint8_t)(fb >> (8 * k));
		p[30] = 64 * 50 & 0xFF;
		p[31] = (64 * 50) >> 8;
		c[i] = (struct s3g_cmd){p, 32};
	}
	uint8_t *e = b + 32 * (n - 1);
	e[0] = 154;
	e[1] = 0;
	c[n - 1] = (struct s3g_cmd){e, 2};
	*store = b;
	return c;
}

/* The log must hold exactly the stream, in order, each command once. */
static void check_log(FILE *log, size_t n)
{
	char line[512];
	size_t want = 0, moves = 0;
	fflush(log);
	rewind(log);
	while (fgets(line, sizeof(line), log)) {
		unsigned long long seq;
		unsigned code;
		if (line[0] == '#')
			continue;
		ck_assert_msg(sscanf(line, "%llu %u", &seq, &code) == 2, "bad log line: %s", line);
		ck_assert_msg(seq == want + 1, "log sequence %llu where %zu was due: %s", seq,
			      want + 1, line);
		if (want == 0) {
			ck_assert_uint_eq(code, 153);
		} else if (want + 1 == n) {
			ck_assert_uint_eq(code, 154);
		} else {
			char x[32];
			ck_assert_msg(code == 155, "command %zu is not a move: %s", want + 1, line);
			snprintf(x, sizeof(x), " X=%zu ", 10 * want);
			ck_assert_msg(strstr(line, x), "command %zu: expected%s in: %s", want + 1, x,
				      line);
			moves++;
		}
		want++;
	}
	ck_assert_uint_eq(want, n);
	ck_assert_uint_eq(moves, n - 2);
}

START_TEST(queries)
{
	struct sim_sailfish_options so;
	struct s3g_options d;
	struct rig r;
	struct st_error err = {0};
	fast_sim(&so);
	fast_drv(&d);
	rig_start(&r, &so, &d);

	uint16_t fw = 0;
	ck_assert_int_eq(s3g_get_version(r.d, 40, &fw, &err), 0);
	ck_assert_uint_eq(fw, 707);
	ck_assert_int_eq(s3g_get_version(r.d, 38, &fw, &err), 0);
	ck_assert_uint_eq(fw, 0); /* Sailfish refuses hosts older than RepG 39 */
	uint32_t f = 0;
	ck_assert_int_eq(s3g_get_buffer_free(r.d, &f, &err), 0);
	ck_assert_uint_eq(f, 512);
	bool done = false;
	ck_assert_int_eq(s3g_is_finished(r.d, &done, &err), 0);
	ck_assert(done);
	struct s3g_build_stats b;
	ck_assert_int_eq(s3g_get_build_stats(r.d, &b, &err), 0);
	ck_assert_uint_eq(b.state, S3G_BUILD_NONE);
	uint8_t bits = 0xFF;
	ck_assert_int_eq(s3g_get_board_status(r.d, &bits, &err), 0);
	ck_assert_uint_eq(bits, 0);

	/* queue a temperature, a position and a move; read them back */
	uint8_t resp[32];
	size_t n;
	const uint8_t heat[] = {136, 0, 3, 2, 210, 0}, bed[] = {136, 0, 31, 2, 60, 0};
	const uint8_t setpos[] = {140, 1, 0, 0, 0, 2, 0, 0, 0, 3, 0, 0, 0, 4, 0, 0, 0, 5, 0, 0, 0};
	ck_assert_int_eq(s3g_transact(r.d, heat, sizeof(heat), resp, sizeof(resp), &n, &err), 0);
	ck_assert_uint_eq(resp[0], S3G_RC_OK);
	ck_assert_int_eq(s3g_transact(r.d, bed, sizeof(bed), resp, sizeof(resp), &n, &err), 0);
	ck_assert_int_eq(s3g_transact(r.d, setpos, sizeof(setpos), resp, sizeof(resp), &n, &err),
			 0);
	usleep(20000);
	struct s3g_temps t;
	ck_assert_int_eq(s3g_get_temps(r.d, &t, &err), 0);
	ck_assert_int_eq(t.tool_target, 210);
	ck_assert_int_eq(t.platform_target, 60);
	ck_assert_int_ge(t.tool, 25);
	struct s3g_position p;
	ck_assert_int_eq(s3g_get_position(r.d, &p, &err), 0);
	for (int i = 0; i < 5; i++)
		ck_assert_int_eq(p.steps[i], i + 1);
	/* an unknown query is "unsupported", passed back for the caller to skip */
	const uint8_t unk = 99;
	ck_assert_int_eq(s3g_transact(r.d, &unk, 1, resp, sizeof(resp), &n, &err), 0);
	ck_assert_uint_eq(resp[0], S3G_RC_UNSUPPORTED);
	/* safe cancel: abort, then heaters off */
	ck_assert_int_eq(s3g_cancel(r.d, &err), 0);
	usleep(20000);
	ck_assert_int_eq(s3g_get_temps(r.d, &t, &err), 0);
	ck_assert_int_eq(t.tool_target, 0);
	ck_assert_int_eq(t.platform_target, 0);
	rig_stop(&r);
}
END_TEST

/* Stream n commands and check the log; returns the final status. */
static struct s3g_status stream_and_check(struct sim_sailfish_options *so, size_t n,
					  uint32_t rate)
{
	struct s3g_options d;
	struct rig r;
	struct st_error err = {0};
	struct s3g_status st;
	uint8_t *store;
	fast_drv(&d); /* the default retry budgets: they must carry 1 % noise */
	rig_start(&r, so, &d);
	struct s3g_cmd *c = make_stream(n, rate, &store);
	int rc = s3g_stream(r.d, c, n, NULL, NULL, NULL, &st, &err);
	ck_assert_msg(rc == 0, "stream failed: %s", err.msg);
	ck_assert_uint_eq(st.confirmed, n);
	if (sim_sailfish_undetected(r.sim)) {
		/* a spoilt packet matched its CRC-8 and ran as something else:
		 * a limit of the protocol, which no host can see (about one
		 * 3000-packet run in fifteen at 1 % noise); the log cannot be
		 * compared, the stream still had to end confirmed */
		fprintf(stderr, "s3g: %llu packets spoilt past CRC-8; log not compared\n",
			(unsigned long long)sim_sailfish_undetected(r.sim));
		rig_stop(&r);
		free(c);
		free(store);
		return st;
	}
	ck_assert_msg(sim_sailfish_executed(r.sim) == n,
		      "%llu commands executed for %zu sent (retries %llu, time-outs %llu, "
		      "resolved %llu, unsure %llu)",
		      (unsigned long long)sim_sailfish_executed(r.sim), n,
		      (unsigned long long)st.retries, (unsigned long long)st.timeouts,
		      (unsigned long long)st.resolved, (unsigned long long)st.dup_risk);
	check_log(r.log, n);
	rig_stop(&r);
	free(c);
	free(store);
	return st;
}

START_TEST(stream_clean)
{
	struct sim_sailfish_options so;
	fast_sim(&so);
	struct s3g_status st = stream_and_check(&so, 3000, 200000);
	ck_assert_uint_eq(st.retries, 0);
	ck_assert_uint_eq(st.timeouts, 0);
	ck_assert_uint_eq(st.overflows, 0);
}
END_TEST

START_TEST(stream_corrupt)
{
	struct sim_sailfish_options so;
	fast_sim(&so);
	so.corrupt_p = 0.01;
	/* CRC-8 misses some two-bit errors (the polynomial's period is 127
	 * bits), so at this noise level about one 3000-packet run in fifteen
	 * lets a damaged packet through, as it would on the real firmware:
	 * the simulator counts those and the log is then not compared.  The
	 * noise falls on what the link carries, so the driver's queries move
	 * it and no seed is sure to stay clean. */
	so.seed = 12;
	/* 1 000 packets in the sanitizer pass: the same code, in less time */
	struct s3g_status st = stream_and_check(&so, TU_SANITIZED ? 1000 : 1500, 200000);
	ck_assert_uint_gt(st.retries, 10); /* 1 % of ~50 000 bytes were hit */
	ck_assert_uint_gt(st.errors, 10);
	ck_assert_uint_eq(st.dup_risk, 0);
}
END_TEST

START_TEST(stream_corrupt_replies)
{
	struct sim_sailfish_options so;
	fast_sim(&so);
	so.reply_corrupt_p = 0.01;
	so.seed = 5;
	struct s3g_status st = stream_and_check(&so, 600, 200000);
	/* a damaged reply is settled once the line goes quiet, not after the
	 * full time-out (issue 17 defect 7): every one was heard */
	ck_assert_uint_gt(st.garbled, 2);
	ck_assert_uint_eq(st.timeouts, 0);
	/* every lost reply to a move was settled by asking the firmware */
	ck_assert_uint_gt(st.resolved, 0);
	ck_assert_uint_eq(st.dup_risk, 0);
}
END_TEST

/* After a fault the driver counts again before each packet (free space,
 * build statistics, free space); on a buffer the firmware has emptied the
 * second reading can tell nothing new.  At 2 % of reply bytes spoilt the
 * link stays noisy for the whole stream, and the moves here drain at
 * once: 3.87 queries a move were written with the second reading, 2.78
 * without it (docs/reliability.md, the Sailfish soak at 2 % corruption). */
START_TEST(stream_recount_two_queries_when_empty)
{
	struct sim_sailfish_options so;
	fast_sim(&so);
	so.reply_corrupt_p = 0.02;
	so.seed = 5;
	const size_t n = 400;
	struct s3g_status st = stream_and_check(&so, n, 200000);
	ck_assert_uint_gt(st.garbled, 10); /* the noise kept the re-count on */
	ck_assert_uint_eq(st.dup_risk, 0);
	double per_move = (double)(st.packets - n - st.retries) / (double)n;
	ck_assert_msg(per_move < 3.3, "%.2f queries a move", per_move);
}
END_TEST

/* A move damaged where CRC-8 cannot see reaches the firmware as a query
 * (code 155 read as 27), which it answers with data: once the command was
 * lost while the host counted it confirmed ("2999 commands executed for
 * 3000 sent", issue 17 defect 7).  A success with data to an action is a
 * misread: it is sent again and runs once. */
START_TEST(stream_crc_escape_resent)
{
	struct sim_sailfish_options so;
	fast_sim(&so);
	so.crc_escape_at = 40;
	struct s3g_status st = stream_and_check(&so, 300, 200000);
	ck_assert_uint_eq(st.misread, 1);
	ck_assert_uint_eq(st.dup_risk, 0);
}
END_TEST

/* A query spoilt past CRC-8 runs as another query (here: get version, the
 * shortest reply): the job failed on the short reply ("reply to get build
 * statistics has 5 bytes, expected 8" at 1 % noise, in a two-lane run).
 * A query changes nothing in the printer, so it is asked again. */
START_TEST(stream_query_escape_asked_again)
{
	struct sim_sailfish_options so;
	fast_sim(&so);
	for (long at = 2; at <= 6; at++) {
		so.query_escape_at = at;
		so.query_escape_code = S3G_Q_VERSION;
		stream_and_check(&so, 100, 200000);
	}
}
END_TEST

/*
 * A move damaged past CRC-8 into other action commands (issue 17 soak at
 * 2 % corruption: 144 and 145 ran where 155 was sent) leaves the build's
 * line count off from the commands the host confirmed: by one more when
 * it runs as two commands, one fewer when it runs as none.  Lost replies
 * after it (2 % of reply bytes spoilt) were settled against the old count:
 * moves that had run were resent and moves that had not were taken as run.
 * The driver counts again at the next packet after a fault and absorbs
 * the drift: every other move runs once, in order.  (When the reply to
 * the damaged packet itself is lost, the count cannot tell and it is
 * resent as the protocol says: its own commands ran, not the move.)
 */
static void drift_case(uint8_t code, uint32_t rate, const unsigned *garbage, size_t ngarbage)
{
	struct sim_sailfish_options so;
	struct s3g_options d;
	struct rig r;
	struct st_error err = {0};
	struct s3g_status st;
	uint8_t *store;
	const size_t n = TU_SANITIZED ? 300 : 600;
	char line[512];
	size_t moves = 0, extra = 0;
	unsigned long last_x = 0, missing = 0;
	unsigned long long seq, want = 1;
	unsigned c;

	fast_sim(&so);
	so.reply_corrupt_p = 0.02;
	so.seed = 3;
	so.crc_escape_at = 50;
	so.crc_escape_code = code;
	fast_drv(&d);
	rig_start(&r, &so, &d);
	struct s3g_cmd *cmds = make_stream(n, rate, &store);
	int rc = s3g_stream(r.d, cmds, n, NULL, NULL, NULL, &st, &err);
	ck_assert_msg(rc == 0, "stream failed: %s", err.msg);
	fflush(r.log);
	rewind(r.log);
	while (fgets(line, sizeof(line), r.log)) {
		if (line[0] == '#' || line[0] == '-')
			continue;
		ck_assert_msg(sscanf(line, "%llu %u", &seq, &c) == 2, "bad log line: %s", line);
		ck_assert_msg(seq == want++, "log sequence broken: %s", line);
		if (seq == 1) {
			ck_assert_uint_eq(c, 153);
		} else if (c == 155) {
			unsigned long x = 0;
			const char *px = strstr(line, " X=");
			ck_assert_ptr_nonnull(px);
			x = strtoul(px + 3, NULL, 10);
			/* each move once, in order: the damaged copy may be any
			 * packet, so one move may be missing, none repeated */
			ck_assert_msg(x > last_x, "code %u (%llu resent unsure, %llu drifts): "
				      "move X=%lu ran again after X=%lu: %s", code,
				      (unsigned long long)st.dup_risk,
				      (unsigned long long)st.drifts, x, last_x, line);
			missing += (x - last_x) / 10 - 1;
			last_x = x;
			moves++;
		} else if (c != 154) {
			ck_assert_msg(extra < ngarbage && c == garbage[extra], "unexpected: %s",
				      line);
			extra++;
		}
	}
	ck_assert_uint_eq(extra, ngarbage);
	missing += (10 * (n - 2) - last_x) / 10;
	ck_assert_uint_le(missing, 1);
	ck_assert_uint_ge(moves + 1, n - 2);
	ck_assert_uint_gt(st.garbled, 10); /* the lost replies were there */
	rig_stop(&r);
	free(cmds);
	free(store);
}

START_TEST(stream_drift_absorbed)
{
	/* 144 takes the move's first X byte; the DDA rate's low byte 137
	 * reads as "enable axes": two commands for one packet */
	static const unsigned two[] = {144, 137};
	drift_case(144, 137, two, 2);
	/* an unknown code: every byte of the move is skipped, no command */
	drift_case(205, 200000, NULL, 0);
	/* a build start (its text ends at the first zero byte): the running
	 * build counts from 0 again, which is no reboot (that answers "no
	 * build"); the job ended as "the printer reset" */
	static const unsigned start[] = {153};
	drift_case(153, 200000, start, 1);
}
END_TEST

START_TEST(stream_small_buffer)
{
	struct sim_sailfish_options so;
	fast_sim(&so);
	so.buffer_size = 64; /* two moves at most */
	so.speedup = 20;
	struct s3g_status st = stream_and_check(&so, 400, 200);
	ck_assert_uint_eq(st.overflows, 0); /* the driver waited for room instead */
}
END_TEST

START_TEST(overflow_resend)
{
	struct sim_sailfish_options so;
	struct s3g_options d;
	struct rig r;
	struct st_error err = {0};
	uint8_t *store, resp[32];
	size_t n;
	fast_sim(&so);
	so.buffer_size = 64;
	so.speedup = 20;
	fast_drv(&d);
	rig_start(&r, &so, &d);
	/* 5 ms moves: the 16-block planner and the buffer fill up */
	struct s3g_cmd *c = make_stream(40, 100, &store);
	/* no free-space tracking: the firmware must refuse some with 0x82 */
	for (size_t i = 0; i < 40; i++)
		ck_assert_msg(s3g_transact(r.d, c[i].payload, c[i].len, resp, sizeof(resp), &n,
					   &err) == 0,
			      "%s", err.msg);
	ck_assert_uint_gt(s3g_status_get(r.d)->overflows, 0);
	bool done = false;
	for (int k = 0; k < 400 && !done; k++) {
		ck_assert_int_eq(s3g_is_finished(r.d, &done, &err), 0);
		usleep(10000);
	}
	ck_assert(done);
	check_log(r.log, 40);
	rig_stop(&r);
	free(c);
	free(store);
}
END_TEST

/* Stream n moves with a fault set in so; the stream must fail with ST_ERR_IO
 * and a message holding want and naming the last confirmed command. */
static void fault_stream(struct sim_sailfish_options *so, size_t n, const char *want,
			 struct rig *r)
{
	struct s3g_options d;
	struct st_error err = {0};
	uint8_t *store;
	fast_drv(&d);
	rig_start(r, so, &d);
	struct s3g_cmd *c = make_stream(n, 50000, &store);
	int rc = s3g_stream(r->d, c, n, NULL, NULL, NULL, NULL, &err);
	ck_assert_int_eq(rc, ST_ERR_IO);
	ck_assert_msg(strstr(err.msg, want), "%s", err.msg);
	ck_assert_msg(strstr(err.msg, "was confirmed"), "%s", err.msg);
	free(c);
	free(store);
}

START_TEST(reset_detected)
{
	struct sim_sailfish_options so;
	struct rig r;
	fast_sim(&so);
	so.reset_at = 1500;
	fault_stream(&so, 3000, "reset", &r);
	ck_assert_uint_eq(sim_sailfish_resets(r.sim), 1);
	rig_stop(&r);
}
END_TEST

START_TEST(unplug_detected)
{
	struct sim_sailfish_options so;
	struct rig r;
	fast_sim(&so);
	so.unplug_at = 300;
	fault_stream(&so, 2000, "unplugged", &r);
	ck_assert(sim_sailfish_unplugged(r.sim));
	rig_stop(&r);
}
END_TEST

START_TEST(bad_stream_rejected)
{
	struct sim_sailfish_options so;
	struct s3g_options d;
	struct rig r;
	struct st_error err = {0};
	fast_sim(&so);
	fast_drv(&d);
	rig_start(&r, &so, &d);
	const uint8_t query[] = {2}, shortmove[] = {155, 0, 0};
	struct s3g_cmd c[2] = {{shortmove, sizeof(shortmove)}, {query, 1}};
	ck_assert_int_eq(s3g_stream(r.d, c, 1, NULL, NULL, NULL, NULL, &err), ST_ERR_ARG);
	ck_assert_ptr_nonnull(strstr(err.msg, "command 0"));
	ck_assert_int_eq(s3g_stream(r.d, c + 1, 1, NULL, NULL, NULL, NULL, &err), ST_ERR_ARG);
	ck_assert_uint_eq(sim_sailfish_executed(r.sim), 0);
	rig_stop(&r);
}
END_TEST

/* Action commands in an X3G file, counted with the firmware's lengths. */
static size_t x3g_count(const char *path, uint8_t *codes, size_t cap)
{
	FILE *f = fopen(path, "rb");
	uint8_t buf[65536];
	ck_assert_ptr_nonnull(f);
	size_t len = fread(buf, 1, sizeof(buf), f), off = 0, n = 0;
	fclose(f);
	while (off < len) {
		int k = s3g_action_length(buf + off, len - off);
		ck_assert_msg(k > 0, "undecodable X3G at byte %zu", off);
		if (n < cap)
			codes[n] = buf[off];
		n++;
		off += (size_t)k;
	}
	return n;
}

START_TEST(gpx_drives_simulator)
{
	if (system("command -v gpx >/dev/null 2>&1") != 0) {
		printf("s3g_suite: gpx not installed, skipping the real-host test "
		       "(make deps installs it)\n");
		return;
	}
	struct sim_sailfish_options so;
	struct st_error err = {0};
	struct sim_sailfish *sim;
	FILE *log = tmpfile();
	char gc[256], x3g[256], cmd[1024];
	snprintf(gc, sizeof(gc), "%s", tu_path("gpx_part.gcode"));
	snprintf(x3g, sizeof(x3g), "%s", tu_path("gpx_part.x3g"));
	FILE *g = fopen(gc, "w");
	ck_assert_ptr_nonnull(g);
	fprintf(g, "M104 S200 T0\nM140 S50\nM109 S200 T0\nM190 S50\nG21\nG90\n"
		   "G92 X0 Y0 Z0 A0\nG1 Z0.3 F1000\n");
	for (int i = 0; i < 300; i++)
		fprintf(g, "G1 X%d Y%d E%.3f F3000\n", 10 + (i % 20), 10 + (i / 20), 0.05 * (i + 1));
	fprintf(g, "M104 S0 T0\nM140 S0\n");
	fclose(g);
	char dir[256];
	snprintf(dir, sizeof(dir), "%s", gc);
	*strrchr(dir, '/') = '\0';
	snprintf(cmd, sizeof(cmd), "cd '%s' && gpx -m fcp '%s' '%s' >/dev/null 2>&1", dir, gc,
		 x3g);
	ck_assert_int_eq(system(cmd), 0);
	uint8_t codes[2048];
	size_t want = x3g_count(x3g, codes, sizeof(codes));
	ck_assert_uint_gt(want, 300);

	fast_sim(&so);
	so.baud = 115200; /* what gpx sets; a pty ignores it, our link pacing does not */
	so.speedup = 100;
	so.log_fp = log;
	ck_assert_int_eq(sim_sailfish_new(&so, &sim, &err), 0);
	ck_assert_int_eq(sim_sailfish_start_thread(sim, &err), 0);
	pid_t pid = fork();
	ck_assert_int_ge(pid, 0);
	if (pid == 0) {
		if (chdir(dir) != 0)
			_exit(127);
		int devnull = open("/dev/null", O_WRONLY);
		if (devnull >= 0) {
			dup2(devnull, 1);
			dup2(devnull, 2);
		}
		execlp("gpx", "gpx", "-s", "-m", "fcp", gc, sim_sailfish_slave_path(sim),
		       (char *)NULL);
		_exit(127);
	}
	int status = 0;
	double end = st_mono_s() + 30;
	while (waitpid(pid, &status, WNOHANG) == 0) {
		if (st_mono_s() > end) {
			kill(pid, SIGKILL);
			waitpid(pid, &status, 0);
			ck_abort_msg("gpx -s did not finish within 30 s");
		}
		usleep(20000);
	}
	ck_assert_msg(WIFEXITED(status) && WEXITSTATUS(status) == 0, "gpx -s failed: status %d",
		      status);
	/* gpx does not wait for the printer: let the simulator catch up */
	for (int k = 0; k < 1000 && sim_sailfish_executed(sim) < want; k++)
		usleep(10000);
	ck_assert_uint_eq(sim_sailfish_executed(sim), want);
	sim_sailfish_stop(sim);
	/* the simulator executed gpx's commands in the order of gpx's file */
	char line[512];
	size_t i = 0;
	fflush(log);
	rewind(log);
	while (fgets(line, sizeof(line), log)) {
		unsigned long long seq;
		unsigned code;
		ck_assert_int_eq(sscanf(line, "%llu %u", &seq, &code), 2);
		ck_assert_uint_eq(seq, i + 1);
		if (i < sizeof(codes))
			ck_assert_uint_eq(code, codes[i]);
		i++;
	}
	ck_assert_uint_eq(i, want);
	sim_sailfish_free(sim);
	fclose(log);
}
END_TEST

START_TEST(cli_options)
{
	char out[2048];
	ck_assert_int_eq(tu_run(out, sizeof(out), "sim --dialect sailfish --bufsize 4"), 2);
	ck_assert_ptr_nonnull(strstr(out, "--bufsize applies to --dialect marlin only"));
	ck_assert_int_eq(tu_run(out, sizeof(out), "sim --dialect marlin --buffer-size 512"), 2);
	ck_assert_ptr_nonnull(strstr(out, "--buffer-size applies to --dialect sailfish only"));
	ck_assert_int_eq(tu_run(out, sizeof(out), "sim --dialect sailfish --buffer-size 8"), 2);
	ck_assert_int_eq(tu_run(out, sizeof(out), "sim --dialect sailfish --unplug-at 0"), 2);
}
END_TEST

Suite *s3g_suite(void)
{
	Suite *s = suite_create("s3g");
	s3g_packets_tcases(s);
	TCase *link = tcase_create("simulator");
	tcase_set_timeout(link, 120); /* a noisy link costs a re-count before each packet */
	tcase_add_test(link, queries);
	tcase_add_test(link, stream_clean);
	tcase_add_test(link, stream_corrupt);
	tcase_add_test(link, stream_corrupt_replies);
	tcase_add_test(link, stream_recount_two_queries_when_empty);
	tcase_add_test(link, stream_crc_escape_resent);
	tcase_add_test(link, stream_query_escape_asked_again);
	tcase_add_test(link, stream_drift_absorbed);
	tcase_add_test(link, stream_small_buffer);
	tcase_add_test(link, overflow_resend);
	tcase_add_test(link, reset_detected);
	tcase_add_test(link, unplug_detected);
	tcase_add_test(link, bad_stream_rejected);
	tcase_add_test(link, gpx_drives_simulator);
	tcase_add_test(link, cli_options);
	suite_add_tcase(s, link);
	return s;
}
