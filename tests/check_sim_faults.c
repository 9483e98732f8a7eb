/*
 * check_sim_faults.c - the simulated Marlin, part of the sim suite
 * (check_sim.c): RX overflow and the flush after a line error, corrupted
 * and dropped bytes, M112 and M108, unplug and reset faults, a command of
 * the simulated Sailfish split across packets, and printcore (Printrun) as
 * a host that is not ours.
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

/* After a line error Marlin empties its RX ring: the good lines already
 * waiting behind the bad one are dropped silently, so the host sees one
 * Error/Resend/ok, not one per line. */
START_TEST(line_error_flushes_rx)
{
	struct sim_marlin_options o;
	struct client c;
	char line[512], bad[64];
	fast_opts(&o);
	cl_start(&c, &o);
	/* G4 blocks for 0.3 s and, as in Marlin's main loop, nothing is read
	 * meanwhile; when it ends the queue fills from the ring, N5 is bad,
	 * the ring is read empty (N6, N7 lost) and the queued N2-N4 still run
	 * and earn their oks after the Resend. */
	cl_send_n(&c, 1, "G4 S30");
	cl_send_n(&c, 2, "G21");
	cl_send_n(&c, 3, "G21");
	cl_send_n(&c, 4, "G21");
	snprintf(bad, sizeof(bad), "N5 G21*%u\n", (unsigned)gcode_checksum("N5 G21", 6) ^ 1u);
	cl_send(&c, bad);
	cl_send_n(&c, 6, "G90");
	cl_send_n(&c, 7, "G90");
	cl_expect(&c, "ok", NULL, 0, 2.0);
	cl_next_is(&c, "Error:checksum mismatch, Last Line: 4");
	cl_next_is(&c, "Resend: 5");
	for (int k = 0; k < 4; k++)
		cl_next_is(&c, "ok");
	ck_assert_int_eq(cl_line(&c, line, sizeof(line), 0.5), -1);
	sim_marlin_stop(c.sim);
	ck_assert_str_eq(cl_log(&c), "1 G4 S30\n2 G21\n3 G21\n4 G21\n");
	cl_stop(&c);
}
END_TEST

START_TEST(rx_overflow)
{
	struct sim_marlin_options o;
	struct client c;
	char blast[2048], line[512];
	size_t len = 0;
	long n;
	fast_opts(&o);
	cl_start(&c, &o);
	cl_send_n(&c, 1, "G4 S30"); /* 0.3 s with the queue busy */
	for (n = 2; len < 1024; n++) {
		char cmd[40];
		snprintf(cmd, sizeof(cmd), "G1 X%ld F6000", n % 50);
		int k = gcode_format_numbered(blast + len, sizeof(blast) - len - 1, n, cmd);
		ck_assert_int_gt(k, 0);
		len += (size_t)k;
		blast[len++] = '\n';
	}
	blast[len] = '\0';
	cl_send(&c, blast);
	int resends = 0, oks = 0;
	/* The whole blast is on the wire within 10 ms, long before G4 ends:
	 * what the ring could not hold is lost, the rest runs, and the
	 * firmware waits for the end of the line it holds a piece of.  The
	 * host's next line shows the loss. */
	for (int phase = 0; phase < 2; phase++) {
		while (cl_line(&c, line, sizeof(line), 1.0) >= 0) {
			if (!strncmp(line, "Resend: ", 8))
				resends++;
			else if (!strcmp(line, "ok"))
				oks++;
		}
		if (!phase) {
			cl_send(&c, "\n");
			cl_send_n(&c, n, "G21");
		}
	}
	ck_assert_int_gt(resends, 0);
	ck_assert_int_gt(oks, 1);
	ck_assert_uint_gt(sim_marlin_dropped_bytes(c.sim), 0);
	/* Still alive and answering. */
	/* The newline ends whatever partial line the lost bytes left. */
	cl_send(&c, "\nM105\n");
	cl_expect(&c, "ok T:", NULL, 0, 2.0);
	cl_stop(&c);
}
END_TEST


START_TEST(m112_halts)
{
	struct sim_marlin_options o;
	struct client c;
	char line[512];
	fast_opts(&o);
	cl_start(&c, &o);
	cl_send_n(&c, 1, "G4 S100"); /* busy: M112 must not wait in line */
	cl_send(&c, "M112\n");
	cl_next_is(&c, "Error:Printer halted. kill() called!");
	ck_assert(sim_marlin_halted(c.sim));
	cl_send(&c, "M105\n");
	ck_assert_int_eq(cl_line(&c, line, sizeof(line), 0.3), -1);
	cl_stop(&c);
}
END_TEST

START_TEST(m108_breaks_wait)
{
	struct sim_marlin_options o;
	struct client c;
	fast_opts(&o);
	cl_start(&c, &o);
	double t0 = st_mono_s();
	cl_send_n(&c, 1, "M109 S300"); /* about 1.4 s of wall time */
	usleep(200000);
	cl_send_n(&c, 2, "M108"); /* acted on as it arrives, ahead of the queue */
	cl_expect(&c, "ok", NULL, 0, 2.0);
	cl_expect(&c, "ok", NULL, 0, 2.0);
	double dt = st_mono_s() - t0;
	ck_assert_msg(dt < 0.8, "M108 took %.2f s to break the wait", dt);
	cl_stop(&c);
}
END_TEST

START_TEST(unplug_at)
{
	struct sim_marlin_options o;
	struct client c;
	char line[512];
	int r;
	fast_opts(&o);
	o.unplug_at_line = 2;
	cl_start(&c, &o);
	cl_send_n(&c, 1, "G21");
	cl_next_is(&c, "ok");
	cl_send_n(&c, 2, "G21");
	r = cl_line(&c, line, sizeof(line), 2.0);
	ck_assert_int_eq(r, -2);
	ck_assert(sim_marlin_unplugged(c.sim));
	cl_stop(&c);
}
END_TEST

START_TEST(reset_at)
{
	struct sim_marlin_options o;
	struct client c;
	fast_opts(&o);
	o.reset_at_line = 2;
	cl_start(&c, &o);
	cl_send_n(&c, 1, "G21");
	cl_next_is(&c, "ok");
	cl_send_n(&c, 2, "G21");
	cl_next_is(&c, "start");
	cl_expect(&c, "echo:Hardcoded Default Settings Loaded", NULL, 0, 2.0);
	usleep(60000);
	cl_send_n(&c, 1, "G21"); /* line numbers were forgotten */
	cl_next_is(&c, "ok");
	cl_stop(&c);
}
END_TEST


/* A ping-pong host with resends gets every line through a noisy link, and
 * the execution log shows each line once, in order. */
START_TEST(corrupt_and_drop_recover)
{
	struct sim_marlin_options o;
	struct client c;
	char line[512], cmd[40], want[2048];
	size_t wl = 0;
	int resends = 0;
	fast_opts(&o);
	o.corrupt_p = 0.01;
	o.drop_p = 0.01;
	o.seed = 42;
	cl_start(&c, &o);
	long n = 1;
	double give_up = st_mono_s() + 8.0;
	while (n <= 40) {
		ck_assert_msg(st_mono_s() < give_up, "stuck at line %ld", n);
		snprintf(cmd, sizeof(cmd), "G1 X%ld Y%ld F6000", n, n % 7);
		cl_send(&c, "\n"); /* ends any fragment a lost newline left */
		cl_send_n(&c, n, cmd);
		int r;
		long next = n + 1;
		while ((r = cl_line(&c, line, sizeof(line), 0.3)) >= 0) {
			if (!strncmp(line, "Resend: ", 8)) {
				next = strtol(line + 8, NULL, 10);
				resends++;
			} else if (!strcmp(line, "ok")) {
				break;
			}
		}
		if (r < 0)
			next = n; /* nothing came back: send it again */
		n = next;
	}
	for (long k = 1; k <= 40; k++)
		wl += (size_t)snprintf(want + wl, sizeof(want) - wl, "%ld G1 X%ld Y%ld F6000\n", k, k,
				       k % 7);
	sim_marlin_stop(c.sim);
	ck_assert_int_gt(resends, 0);
	ck_assert_str_eq(cl_log(&c), want);
	cl_stop(&c);
}
END_TEST


/* Find an executable on $PATH; false if there is none. */
static bool find_on_path(const char *name, char *out, size_t cap)
{
	const char *path = getenv("PATH");
	while (path && *path) {
		const char *end = strchr(path, ':');
		size_t n = end ? (size_t)(end - path) : strlen(path);
		if (n && (size_t)snprintf(out, cap, "%.*s/%s", (int)n, path, name) < cap &&
		    access(out, X_OK) == 0)
			return true;
		path = end ? end + 1 : NULL;
	}
	return false;
}

/* A small print: comments, blank lines, heat-up waits, homing, a dwell, a
 * curved wall of 1200 short moves in six layers, fan and end code. */
static void write_print(const char *path)
{
	FILE *f = fopen(path, "w");
	ck_assert_ptr_nonnull(f);
	fputs("; generated by check_sim.c\n\nM140 S60\nM104 S200\nM190 S60\nM109 S200\n"
	      "G28 ; home\nG90\nM83\nG92 E0\nG4 P100\nM106 S255 (fan on)\n", f);
	for (int i = 0; i < 1200; i++) {
		double a = i * 0.05, r = 20.0 + 5.0 * sin(i * 0.013);
		if (i % 200 == 0)
			fprintf(f, ";LAYER_CHANGE\nG1 Z%.2f F600\n", 0.2 + 0.2 * (i / 200));
		fprintf(f, "G1 X%.3f Y%.3f E%.5f%s\n", 100 + r * cos(a), 100 + r * sin(a), 0.0321,
			i == 0 ? " F1800" : "");
	}
	fputs("M400\nM107\nM104 S0\nM140 S0\nM84\n", f);
	ck_assert_int_eq(fclose(f), 0);
}

/* Printrun's printcore, a stock host, streams a print to the simulator:
 * every command of the file is executed once, in order, numbered from 0
 * after printcore's "N-1 M110".  Skipped when printcore is not installed
 * (make bench installs it; it is not a build dependency). */
START_TEST(printcore_streams)
{
	char exe[4096], *line = NULL;
	size_t cap = 0;
	const char *gpath = tu_path("printcore-job.gcode");
	const char *opath = tu_path("printcore.out");
	struct sim_marlin_options o;
	struct sim_marlin *sim = NULL;
	struct st_error err = {0};

	if (!find_on_path("printcore", exe, sizeof(exe))) {
		fprintf(stderr, "sim: printcore_streams skipped: printcore is not on PATH "
				"(Debian package printcore; make bench installs it)\n");
		return;
	}
	write_print(gpath);

	/* What the firmware must run: the file's commands, cleaned as the
	 * simulator's log writes them. */
	FILE *gf = fopen(gpath, "r");
	ck_assert_ptr_nonnull(gf);
	size_t nwant = 0, wcap = 2048;
	char (*want)[GCODE_LINE_MAX + 1] = malloc(wcap * sizeof(*want));
	ck_assert_ptr_nonnull(want);
	ssize_t n;
	while ((n = getline(&line, &cap, gf)) >= 0) {
		struct gcode_line g;
		ck_assert_int_eq(gcode_parse(line, (size_t)n, 0, &g, NULL), 0);
		if (!g.text_len)
			continue;
		ck_assert_uint_lt(nwant, wcap);
		memcpy(want[nwant++], g.text, g.text_len + 1);
	}
	fclose(gf);

	sim_marlin_options_init(&o);
	o.speedup = 1000;
	o.baud = 1000000;
	o.log_fp = tmpfile();
	ck_assert_ptr_nonnull(o.log_fp);
	ck_assert_int_eq(sim_marlin_new(&o, &sim, &err), 0);
	ck_assert_int_eq(sim_marlin_start_thread(sim, &err), 0);

	pid_t pid = fork();
	ck_assert_int_ge(pid, 0);
	if (pid == 0) {
		int fd = open(opath, O_WRONLY | O_CREAT | O_TRUNC, 0644);
		if (fd >= 0) {
			dup2(fd, 1);
			dup2(fd, 2);
		}
		execl(exe, "printcore", "-b", "115200", sim_marlin_slave_path(sim), gpath,
		      (char *)NULL);
		_exit(127);
	}
	/* printcore sleeps 2 s after connecting and polls once a second */
	int status = 0;
	double give_up = st_mono_s() + 60.0;
	while (waitpid(pid, &status, WNOHANG) == 0) {
		if (st_mono_s() > give_up) {
			kill(pid, SIGKILL);
			waitpid(pid, &status, 0);
			ck_abort_msg("printcore did not finish within 60 s; its output is in %s",
				     opath);
		}
		usleep(20000);
	}
	sim_marlin_stop(sim);
	ck_assert_msg(WIFEXITED(status) && WEXITSTATUS(status) == 0,
		      "printcore failed (status %d); its output is in %s", status, opath);

	/* The log: printcore's connect probe (M105, unnumbered) and its M110
	 * lines (numbered -1) around the job, the job itself numbered 0... */
	size_t next = 0;
	rewind(o.log_fp);
	while ((n = getline(&line, &cap, o.log_fp)) >= 0) {
		long k;
		char *sp;
		if (n && line[n - 1] == '\n')
			line[--n] = '\0';
		if (!strcmp(line, "- M105") || !strcmp(line, "-1 M110"))
			continue;
		k = strtol(line, &sp, 10);
		ck_assert_msg(sp != line && *sp == ' ', "unexpected log line '%s'", line);
		ck_assert_msg(k >= 0 && (size_t)k == next,
			      "log line '%s': expected line number %zu (a command lost, doubled "
			      "or out of order)", line, next);
		ck_assert_uint_lt(next, nwant);
		ck_assert_str_eq(sp + 1, want[next]);
		next++;
	}
	ck_assert_msg(next == nwant, "only %zu of %zu commands executed", next, nwant);
	free(line);
	free(want);
	sim_marlin_free(sim);
	fclose(o.log_fp);
}
END_TEST

/* Lines of the Sailfish simulator's execution log (comments left out). */
static size_t sf_executed(const char *path)
{
	char line[512];
	size_t n = 0;
	FILE *log = fopen(path, "r");
	ck_assert_ptr_nonnull(log);
	while (fgets(line, sizeof(line), log))
		n += line[0] != '#';
	fclose(log);
	return n;
}

/*
 * Sailfish runs a command only once all its bytes are in the command
 * buffer (runCommandSlice: "check for completion"), however the packets
 * cut it.  The simulator ran a queue-point command as soon as its code
 * byte came, popped more bytes than the buffer held and replayed the
 * buffer's old contents for ever: the soak's 36 million executions after
 * a packet spoilt past CRC-8 (issue 17).
 */
START_TEST(sailfish_command_across_packets)
{
	struct sim_sailfish_options so;
	struct sim_sailfish *sim;
	struct xport_options xo = {.baudrate = 115200};
	struct xport *x;
	struct s3g *d;
	struct st_error err = {0};
	uint8_t move[26] = {142, 10}, resp[8];
	size_t n;
	char log[512];

	snprintf(log, sizeof(log), "%s", tu_path("sf-split.log"));
	sim_sailfish_options_init(&so);
	so.speedup = 1000;
	so.baud = 1000000;
	so.log_path = log;
	ck_assert_int_eq(sim_sailfish_new(&so, &sim, &err), 0);
	ck_assert_msg(xport_open(sim_sailfish_slave_path(sim), &xo, &x, &err) == 0, "%s", err.msg);
	ck_assert_int_eq(s3g_new(x, NULL, &d, &err), 0);
	ck_assert_int_eq(sim_sailfish_start_thread(sim, &err), 0);
	move[21] = 100; /* 100 us per step */
	move[13] = 0x80; /* Z's top byte: the second packet must look like an action */
	/* a byte that starts no command is skipped, not waited on */
	const uint8_t junk = 0xFE;
	ck_assert_msg(s3g_transact(d, &junk, 1, resp, sizeof(resp), &n, &err) == 0, "%s", err.msg);
	ck_assert_msg(s3g_transact(d, move, 13, resp, sizeof(resp), &n, &err) == 0, "%s", err.msg);
	ck_assert_uint_eq(resp[0], S3G_RC_OK);
	usleep(50000);
	ck_assert_uint_le(sf_executed(log), 1); /* thousands, before: the log spilled */
	ck_assert_msg(s3g_transact(d, move + 13, 13, resp, sizeof(resp), &n, &err) == 0, "%s",
		      err.msg);
	ck_assert_uint_eq(resp[0], S3G_RC_OK);
	usleep(50000);
	sim_sailfish_stop(sim);
	s3g_free(d);
	xport_close(x);
	sim_sailfish_free(sim); /* the log is complete once closed */
	ck_assert_uint_eq(sf_executed(log), 2); /* the skipped byte, the move */
}
END_TEST

void sim_faults_tcases(Suite *s)
{
	TCase *faults = tcase_create("faults");
	TCase *hosts = tcase_create("hosts");

	tcase_set_timeout(faults, 20);
	tcase_add_test(faults, rx_overflow);
	tcase_add_test(faults, line_error_flushes_rx);
	tcase_add_test(faults, corrupt_and_drop_recover);
	tcase_add_test(faults, m112_halts);
	tcase_add_test(faults, m108_breaks_wait);
	tcase_add_test(faults, unplug_at);
	tcase_add_test(faults, reset_at);
	tcase_add_test(faults, sailfish_command_across_packets);
	/* printcore spends 3 s on fixed sleeps; 1250 ping-pong lines follow */
	tcase_set_timeout(hosts, 90);
	tcase_add_test(hosts, printcore_streams);
	suite_add_tcase(s, faults);
	suite_add_tcase(s, hosts);
}
