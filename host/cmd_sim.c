/*
 * cmd_sim.c - `stratum sim --dialect marlin|sailfish [options]`: run a
 * simulated printer on a pseudo-terminal until SIGINT/SIGTERM (docs/architecture.md
 * item 7).
 * Prints the pty path; --link PATH makes PATH a symlink to it, replaced
 * atomically and removed on exit.
 */
#include <errno.h>
#include <limits.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "commands.h"
#include "sim/marlin_sim.h"
#include "sim/sailfish_sim.h"
#include "st_error.h"

/* The one stop flag a signal handler may set (STYLE rule 10 exception). */
static volatile sig_atomic_t sim_stop_flag;

/* SIGINT/SIGTERM: ask the event loop to finish. */
static void sim_on_signal(int sig)
{
	(void)sig;
	sim_stop_flag = 1;
}

static const char sim_head[] =
    "usage: stratum sim --dialect marlin|sailfish [--link PATH] [--log FILE]\n"
    "                   [--speedup K] [--corrupt P] [--drop P] [--latency MS]\n"
    "                   [--reset-at N] [--unplug-at N] [--baud N] [--seed N]\n"
    "  marlin only:     [--rx-buffer N] [--bufsize N] [--advanced-ok]\n"
    "                   [--keep-rx] [--lose-ok P] [--no-firmware-name]\n"
    "                   [--freeze-at N [--freeze-s S]] [--busy-at N --busy-s S]\n"
    "  sailfish only:   [--buffer-size N] [--corrupt-replies P]\n"
    "\n"
    "Runs a simulated printer on a pseudo-terminal and prints its path; stops on\n"
    "Ctrl-C.  It answers as the firmware does, with its buffer sizes and the\n"
    "time its moves and heating take (docs/streaming.md).\n"
    "\n";

/* A number option of kind k in lo..hi (cut to a whole number); given: for one dialect only. */
#define SIM_NUMBER(name, k, dest, lo, hi, given, arg, help)                                    \
	{name, 0, k, dest, CMD_RANGE | CMD_TRUNCATE, lo, hi, "a number from %g to %g", arg, help, \
	 NULL, given}
#define SIM_FLAG(name, dest, help) \
	{name, 0, CMD_FLAG, dest, 0, 0, 0, NULL, NULL, help, NULL, &marlin_only}

/* Point link at target: symlink to a temp name, then rename over link. */
static int sim_make_link(const char *link, const char *target)
{
	char tmp[PATH_MAX];
	struct stat st;

	if (lstat(link, &st) == 0 && !S_ISLNK(st.st_mode))
		return cmd_fail(
		    "stratum sim", -1,
		    "--link %s exists and is not a symlink; remove it or choose another path",
		    link);
	if (snprintf(tmp, sizeof(tmp), "%s.tmp%ld", link, (long)getpid()) >= (int)sizeof(tmp))
		return cmd_fail("stratum sim", -1, "--link path is too long");
	unlink(tmp);
	if (symlink(target, tmp) < 0 || rename(tmp, link) < 0) {
		fprintf(stderr, "stratum sim: cannot create symlink %s -> %s: %s\n", link, target,
			strerror(errno));
		unlink(tmp);
		return -1;
	}
	return 0;
}

/* Remove link if it still points at target (another sim may own it now). */
static void sim_remove_link(const char *link, const char *target)
{
	char buf[PATH_MAX];
	ssize_t n = readlink(link, buf, sizeof(buf) - 1);
	if (n < 0)
		return;
	buf[n] = '\0';
	if (!strcmp(buf, target))
		unlink(link);
}

/*
 * Create the simulator of the chosen dialect (so non-NULL: sailfish), print
 * its pty path, serve until a signal, then clean up; the exit code.
 */
static int sim_serve(const struct sim_marlin_options *mo, const struct sim_sailfish_options *so,
		     const char *link)
{
	struct sim_marlin *m = NULL;
	struct sim_sailfish *sf = NULL;
	struct st_error err = {0};
	const char *path;
	int code = ST_EXIT_FAILURE; /* the link could not be made */
	int rc = so ? sim_sailfish_new(so, &sf, &err) : sim_marlin_new(mo, &m, &err);

	if (rc)
		return cmd_fail("stratum sim", rc == ST_ERR_ARG ? ST_EXIT_USAGE : ST_EXIT_SOFTWARE,
				"%s", err.msg);
	path = sf ? sim_sailfish_slave_path(sf) : sim_marlin_slave_path(m);
	if (link && sim_make_link(link, path))
		goto out_free;
	printf("%s\n", path);
	fflush(stdout);
	cmd_on_stop_signals(sim_on_signal);
	rc = sf ? sim_sailfish_run(sf, &sim_stop_flag, &err)
		: sim_marlin_run(m, &sim_stop_flag, &err);
	if (rc)
		fprintf(stderr, "stratum sim: %s\n", err.msg);
	else if (sf ? sim_sailfish_unplugged(sf) : sim_marlin_unplugged(m))
		fprintf(stderr, "stratum sim: link unplugged %s %ld as asked (--unplug-at)\n",
			sf ? "after command" : "at line", sf ? so->unplug_at : mo->unplug_at_line);
	if (link)
		sim_remove_link(link, path);
	code = rc ? ST_EXIT_SOFTWARE : ST_EXIT_OK;
out_free:
	sim_sailfish_free(sf);
	sim_marlin_free(m);
	return code;
}

int cmd_sim(int argc, char **argv)
{
	struct sim_marlin_options o;
	struct sim_sailfish_options so;
	const char *marlin_only = NULL, *sailfish_only = NULL;
	const char *dialect = NULL, *link = NULL;
	const long line_max = 2147483647;
	const struct cmd_opt opts[] = {
	    CMD_OPT_STRING("--dialect", 0, &dialect, 0, NULL, "D",
			   "marlin or sailfish: the firmware to simulate (required)"),
	    CMD_OPT_STRING("--link", 0, &link, 0, NULL, "PATH",
			   "make PATH a symlink to the pty while it runs"),
	    CMD_OPT_STRING("--log", 0, &o.log_path, 0, NULL, "FILE",
			   "write every executed command to FILE"),
	    SIM_NUMBER("--speedup", CMD_DOUBLE, &o.speedup, 1e-3, 1e6, NULL, "K",
		       "run moves, heating and boot K times faster, %g to\n%.0f (default %g)"),
	    SIM_NUMBER("--corrupt", CMD_DOUBLE, &o.corrupt_p, 0, 1, NULL, "P",
		       "flip a bit of each received byte with probability P"),
	    SIM_NUMBER("--drop", CMD_DOUBLE, &o.drop_p, 0, 1, NULL, "P",
		       "lose each received byte with probability P"),
	    SIM_NUMBER("--latency", CMD_UNSIGNED, &o.latency_ms, 0, 60000, NULL, "MS",
		       "wait MS ms before each reply line (%g to %g)"),
	    SIM_NUMBER("--reset-at", CMD_LONG, &o.reset_at_line, 1, line_max, NULL, "N",
		       "reset the board at line N (marlin) or at the N-th\n"
		       "executed command (sailfish)"),
	    SIM_NUMBER("--unplug-at", CMD_LONG, &o.unplug_at_line, 1, line_max, NULL, "N",
		       "pull the cable there (N as for --reset-at)"),
	    SIM_NUMBER("--baud", CMD_UNSIGNED, &o.baud, 300, 100000000, NULL, "N",
		       "link speed in bits/s, N/10 bytes/s, %.0f to %.0f\n(default %g)"),
	    SIM_NUMBER("--seed", CMD_U64, &o.seed, 0, 9007199254740992.0, NULL, "N",
		       "seed of the fault injection (0: a fixed default)"),
	    SIM_NUMBER("--rx-buffer", CMD_UNSIGNED, &o.rx_buffer, 8, 65536, &marlin_only, "N",
		       "marlin: receive ring, %g to %g bytes (RX_BUFFER_SIZE,\ndefault %g)"),
	    SIM_NUMBER("--bufsize", CMD_UNSIGNED, &o.bufsize, 1, 1024, &marlin_only, "N",
		       "marlin: command queue, %g to %g slots (BUFSIZE, default %g)"),
	    SIM_FLAG("--advanced-ok", &o.advanced_ok,
		     "marlin: answer \"ok N P B\" (ADVANCED_OK)"),
	    SIM_FLAG("--keep-rx", &o.keep_rx_on_error,
		     "marlin: keep the bytes behind a bad line in the receive\n"
		     "ring (32-bit boards; AVR boards flush it)"),
	    SIM_NUMBER("--lose-ok", CMD_DOUBLE, &o.reply_loss_p, 0, 1, &marlin_only, "P",
		       "marlin: lose each \"ok\" with probability P"),
	    SIM_FLAG("--no-firmware-name", &o.no_firmware_name,
		     "marlin: answer M115 with a bare \"ok\""),
	    SIM_NUMBER("--freeze-at", CMD_LONG, &o.freeze_at_line, 1, line_max, &marlin_only, "N",
		       "marlin: hang the board at line N"),
	    SIM_NUMBER("--freeze-s", CMD_DOUBLE, &o.freeze_s, 0, 86400, &marlin_only, "S",
		       "marlin: for S seconds (default: for ever)"),
	    SIM_NUMBER("--busy-at", CMD_LONG, &o.busy_at_line, 1, line_max, &marlin_only, "N",
		       "marlin: hold line N, answering \"busy: processing\""),
	    SIM_NUMBER("--busy-s", CMD_DOUBLE, &o.busy_s, 0, 86400, &marlin_only, "S",
		       "marlin: for S seconds"),
	    SIM_NUMBER("--buffer-size", CMD_UNSIGNED, &so.buffer_size, 64, 65536, &sailfish_only,
		       "N", "sailfish: command buffer, %g to %g bytes (default %g)"),
	    SIM_NUMBER("--corrupt-replies", CMD_DOUBLE, &so.reply_corrupt_p, 0, 1, &sailfish_only,
		       "P", "sailfish: flip a bit of each reply byte with probability P"),
	};
	const struct cmd_spec spec = {.cmd = "stratum sim", .head = sim_head, CMD_TABLE(opts),
				      .col = 23};
	int rc;

	sim_marlin_options_init(&o);
	sim_sailfish_options_init(&so);
	rc = cmd_parse(&spec, argc, argv);
	if (rc)
		return rc < 0 ? ST_EXIT_OK : rc;
	if (!dialect)
		return cmd_refuse(&spec, "--dialect is required (marlin or sailfish)");
	if (!strcmp(dialect, "sailfish")) {
		if (marlin_only)
			return cmd_fail("stratum sim", ST_EXIT_USAGE,
					"%s applies to --dialect marlin only", marlin_only);
		so.log_path = o.log_path;
		so.speedup = o.speedup;
		so.baud = o.baud;
		so.latency_ms = o.latency_ms;
		so.corrupt_p = o.corrupt_p;
		so.drop_p = o.drop_p;
		so.reset_at = o.reset_at_line;
		so.unplug_at = o.unplug_at_line;
		so.seed = o.seed;
		return sim_serve(NULL, &so, link);
	}
	if (strcmp(dialect, "marlin"))
		return cmd_fail("stratum sim", ST_EXIT_USAGE,
				"unknown --dialect '%s'; use marlin or sailfish", dialect);
	if (sailfish_only)
		return cmd_fail("stratum sim", ST_EXIT_USAGE,
				"%s applies to --dialect sailfish only", sailfish_only);

	return sim_serve(&o, NULL, link);
}
