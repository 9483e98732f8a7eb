/*
 * cmd_send.c - `stratum send FILE --port PATH --printer NAME [--json]
 * [--baud N]`: stream a file to a printer with progress on stderr and a
 * final report on stdout, through serial/printer.h whatever the printer's
 * dialect: G-code with line numbers and checksums to Marlin, G-code
 * translated to X3G as it streams (or an X3G file) to Sailfish.  The
 * progress line and the report (host/send.h) are shared with `stratum
 * print`.
 *
 * The whole file is checked before the port is opened, so a bad file sends
 * nothing.  Ctrl-C stops safely (heaters and motors off) and exits 130.
 */
#include <errno.h>
#include <jansson.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clio.h"
#include "commands.h"
#include "guard.h"
#include "printer.h"
#include "printer_profile.h"
#include "profile.h"
#include "send.h"
#include "st_error.h"

#define SEND_CMD "stratum send"

struct send_args {
	const char *file, *port, *printer;
	bool json;
	bool force; /* --force: past the wrong-printer guard (guard.h) */
	long baud;  /* 0 = the profile's */
	struct send_commands commands; /* --command: instead of FILE (host/send_command.c) */
};

/* The stop flag SIGINT/SIGTERM set (STYLE rule 10 exception). */
static volatile sig_atomic_t send_stop;

static void send_on_signal(int sig)
{
	(void)sig;
	send_stop = 1;
}

volatile sig_atomic_t *send_catch_signals(void)
{
	cmd_on_stop_signals(send_on_signal);
	return &send_stop;
}

/* Parse argv; returns 0, or an exit status (-1 = --help shown). */
static int send_parse(int argc, char **argv, struct send_args *a)
{
	const struct cmd_opt opts[] = {
	    CMD_OPT_FLAG("--force", &a->force, GUARD_FORCE_HELP),
	    CMD_OPT_FLAG("--json", &a->json, "the report as one JSON object on stdout"),
	    CMD_OPT_STRING("--port", 0, &a->port, 0, NULL, "PATH",
			   "a serial device, a pty, tcp://HOST:PORT or 'auto' (required)"),
	    CMD_OPT_PRINTER_NAME(&a->printer),
	    CMD_OPT_BAUD(&a->baud),
	    {"--command", 0, CMD_CUSTOM, &a->commands, 0, 0, 0, "a G-code line (64 at most)",
	     "LINE", "instead of FILE: send the G-code LINE and print the firmware's\n"
	     "reply on stdout; repeatable, in order (Marlin: Sailfish sends no text)",
	     send_command_add, NULL},
	};
	const struct cmd_spec spec = {
	    .cmd = SEND_CMD, CMD_TABLE(opts), .col = 18,
	    .head = "usage: stratum send FILE --port PATH --printer NAME [--json] [--baud N] "
		    "[--force]\n"
		    "       stratum send --command LINE... --port PATH --printer NAME [--json]\n"
		    "Streams FILE to the printer on PATH (a serial device, a pty or\n"
		    "tcp://HOST:PORT); progress goes to stderr, the report to stdout (one JSON\n"
		    "object with --json).  Ctrl-C stops safely: heaters and motors off.\n"
		    "  Marlin printers: FILE.gcode, with line numbers, checksums and resends.\n"
		    "  Sailfish printers (FlashForge Creator Pro): FILE.gcode, translated to X3G\n"
		    "  as it streams (as 'stratum x3g' does), or FILE.x3g; S3G packets.\n"
		    "FILE '-' streams the G-code on stdin.  G-code sliced for another printer\n"
		    "is refused (exit 2).\n",
	    .pos = &a->file, .npos = 1, .extra = "one file at a time ('%s' and '%s')"};
	int rc;

	memset(a, 0, sizeof(*a));
	rc = cmd_parse(&spec, argc, argv);
	if (rc)
		return rc;
	if (a->file && a->commands.n)
		return cmd_fail(SEND_CMD, ST_EXIT_USAGE, "give a FILE or --command, not both");
	if ((!a->file && !a->commands.n) || !a->port || !a->printer)
		return cmd_refuse(&spec, "%s is required",
				  !a->file && !a->commands.n ? "a FILE (or --command LINE)"
				  : !a->port		     ? "--port"
							     : "--printer");
	return 0;
}

void send_report_emit(json_t *o)
{
	char *text = o ? json_dumps(o, JSON_COMPACT) : NULL;
	if (text)
		printf("%s\n", text);
	else
		fprintf(stderr, SEND_CMD ": out of memory writing the report\n");
	free(text);
	json_decref(o);
}

/* One stream's progress line and the stop flag Ctrl-C sets. */
struct send_run {
	struct send_progress p;
	volatile sig_atomic_t *stop;
};

/* The stop flag as the printer's control hook. */
static enum printer_control send_run_control(void *ctx)
{
	return *((struct send_run *)ctx)->stop ? PRINTER_CANCEL : PRINTER_GO;
}

static void send_run_progress(void *ctx, const struct printer_progress *p)
{
	send_progress_show(&((struct send_run *)ctx)->p, p);
}

void send_warning(void *ctx, const char *path, uint64_t line, const char *msg)
{
	fprintf(stderr, "%s: %s:%llu: warning: %s\n", (const char *)ctx, path,
		(unsigned long long)line, msg);
}

int send_exit_for_check(int rc)
{
	return rc == ST_ERR_NOMEM || rc == ST_ERR_INTERNAL ? ST_EXIT_SOFTWARE : ST_EXIT_DATAERR;
}

int send_exit_for_open(int rc)
{
	return rc == ST_ERR_INTERNAL ? ST_EXIT_FAILURE
	       : rc == ST_ERR_NOMEM ? ST_EXIT_SOFTWARE : ST_EXIT_UNAVAILABLE;
}

int send_exit_for(const struct printer_result *res, int rc)
{
	switch (res->end) {
	case PRINTER_END_DONE: return ST_EXIT_OK;
	case PRINTER_END_CANCELLED:
	case PRINTER_END_STOPPED: return ST_EXIT_INTERRUPTED;
	case PRINTER_END_LINK_LOST: return ST_EXIT_UNAVAILABLE;
	default: return rc == ST_ERR_PARSE ? ST_EXIT_DATAERR : ST_EXIT_FAILURE;
	}
}

bool send_safe_stop(const char *cmd, struct printer *pr, const struct printer_result *res)
{
	struct st_error e = {0};

	if (!res->safe_stop)
		return false;
	if (printer_safe_stop(pr, &e))
		fprintf(stderr, "%s: safe stop: %s\n", cmd, e.msg);
	else
		fprintf(stderr, "%s: stopped safely: heaters and motors off\n", cmd);
	return true;
}

/* The report, as text or one JSON object on stdout. */
static void send_report(const struct send_args *a, const struct printer_ops *ops,
			const struct printer_file_info *info, const struct printer_job *job,
			const struct printer_result *res, const char *firmware, long baud,
			const char *error)
{
	const char *unit = res->last.unit ? res->last.unit : "line";
	double secs = res->last.seconds, cap = baud / 10.0;
	double bps = secs > 0 ? (double)res->bytes_acked / secs : 0;
	bool ok = res->end == PRINTER_END_DONE;
	json_t *o;

	if (!a->json) {
		printf("%s %s: %llu %ss in %.2f s\n", ok ? "sent" : "stopped", a->file,
		       (unsigned long long)res->last.done, unit, secs);
		printf("  %s\n", res->detail);
		printf("  %.0f %ss/s, %.0f bytes/s = %.1f%% of the link (%ld baud = %.0f bytes/s)\n",
		       secs > 0 ? (double)res->last.done / secs : 0, unit, bps,
		       cap > 0 ? 100.0 * bps / cap : 0, baud, cap);
		if (info->warnings)
			printf("  translator warnings %llu\n", (unsigned long long)info->warnings);
		return;
	}
	if ((o = json_object())) {
		cmd_json_set(o, "b:ok", ok, "s:file", a->file, "s:port", a->port,
			     "s:printer", a->printer, "s:protocol", ops->name, "s:firmware", firmware,
			     "I:resends", (json_int_t)res->last.resends,
			     "I:errors", (json_int_t)res->errors,
			     "I:unknown_commands", (json_int_t)res->unknown_commands,
			     "f:seconds", secs, "I:bytes", (json_int_t)res->bytes_acked,
			     "I:bytes_written", (json_int_t)res->bytes_written, "f:bytes_per_s", bps,
			     "I:baud", (json_int_t)baud, "f:link_fraction", cap > 0 ? bps / cap : 0,
			     NULL);
		if (error)
			cmd_json_set(o, "s:error", error, NULL);
		cmd_json_set(o, "s:input", job->x3g ? "x3g" : "gcode", NULL);
		if (!job->x3g)
			cmd_json_set(o, "I:warnings", (json_int_t)info->warnings, NULL);
		for (size_t i = 0; i < res->ncounters; i++)
			json_object_set_new(o, res->counters[i].name,
					    res->counters[i].real
						    ? json_real(res->counters[i].value)
						    : json_integer((json_int_t)res->counters[i].value));
	}
	send_report_emit(o);
}

static int send_run(int argc, char **argv, struct clio *io)
{
	struct send_args a;
	struct profile *prof = NULL;
	struct printer *pr = NULL;
	struct printer_options o;
	const struct printer_ops *ops;
	struct printer_file_info info;
	struct printer_result res;
	struct send_run run;
	struct printer_job job = {0};
	struct st_error err = {0};
	char firmware[96] = "", *port_auto = NULL;
	int status, rc;

	status = send_parse(argc, argv, &a);
	if (status)
		return status < 0 ? ST_EXIT_OK : status;
	if ((status = clio_input(io, &a.file, ".gcode"))) /* "-": G-code on stdin */
		return status;
	rc = profile_find(a.printer, &prof, &err);
	if (rc)
		return cmd_fail(SEND_CMD, profile_exit_status(rc), "%s", err.msg);
	if ((status = printer_profile_cli(SEND_CMD, prof, &a.port, a.baud, a.json, &port_auto, &o,
					  &ops)))
		goto out_profile;
	if (a.commands.n) {
		status = send_commands_run(&a.commands, ops, &o, a.printer, a.port, a.json);
		goto out_profile;
	}
	job.path = a.file;
	job.x3g = cmd_has_ext(a.file, ".x3g");
	if (job.x3g && !ops->takes_x3g) {
		status = cmd_fail(SEND_CMD, ST_EXIT_USAGE,
				  "%s is X3G, which only Sailfish printers take; printer '%s' "
				  "speaks %s: send it the G-code",
				  a.file, a.printer, profile_protocol_name(prof->protocol));
		goto out_profile;
	}
	if (!job.x3g && (status = guard_cli(SEND_CMD, a.file, prof, a.force)))
		goto out_profile;
	if ((rc = printer_check(ops, &o, &job, send_warning, (void *)SEND_CMD, &info, &err))) {
		status = cmd_fail(SEND_CMD, send_exit_for_check(rc), "%s%s", err.msg,
				  strstr(err.msg, "nothing was sent") ? "" : "; nothing was sent");
		goto out_profile;
	}
	run.stop = send_catch_signals();
	if ((rc = printer_open(ops, &o, &pr, &err))) {
		status = cmd_fail(SEND_CMD, send_exit_for_open(rc), "%s", err.msg);
		goto out_profile;
	}
	printer_describe(pr, firmware, sizeof(firmware));
	job.total = info.commands;
	job.control = send_run_control;
	job.progress = send_run_progress;
	job.ctx = &run;
	send_progress_start(&run.p);
	if (!a.json || run.p.tty)
		fprintf(stderr, SEND_CMD ": %s on %s, %llu commands%s\n", firmware, a.port,
			(unsigned long long)info.commands,
			ops->takes_x3g && !job.x3g ? " translated from G-code as they go" : "");
	rc = printer_stream(pr, &job, &res, &err);
	send_progress_end(&run.p);
	status = send_exit_for(&res, rc);
	if (status)
		fprintf(stderr, SEND_CMD ": %s\n", err.msg[0] ? err.msg : "the job was cancelled");
	send_safe_stop(SEND_CMD, pr, &res);
	send_report(&a, ops, &info, &job, &res, firmware, o.baud,
		    status ? (err.msg[0] ? err.msg : "the job was cancelled") : NULL);
	printer_close(pr);
out_profile:
	profile_free(prof);
	free(port_auto);
	return status;
}

/* "stratum send -" streams the G-code on stdin (clio.h). */
int cmd_send(int argc, char **argv)
{
	return clio_run(SEND_CMD, send_run, argc, argv);
}
