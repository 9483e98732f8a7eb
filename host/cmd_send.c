/*
 * cmd_send.c - `stratum send FILE.gcode --port PATH --printer NAME [--json]
 * [--baud N]`: stream a G-code file to a Marlin printer (serial/marlin.h)
 * with progress on stderr and a final report on stdout.
 *
 * The whole file is checked before the port is opened, so a bad file sends
 * nothing.  Ctrl-C stops safely (marlin_safe_stop) and exits 130.
 */
#include <errno.h>
#include <jansson.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "commands.h"
#include "gcode.h"
#include "marlin.h"
#include "profile.h"
#include "st_error.h"
#include "xport.h"

#define SEND_CMD "stratum send"

/* The stop flag SIGINT/SIGTERM set (STYLE rule 10 exception). */
static volatile sig_atomic_t send_stop;

static void send_on_signal(int sig)
{
	(void)sig;
	send_stop = 1;
}

struct send_args {
	const char *file, *port, *printer;
	bool json;
	long baud; /* 0 = the profile's */
};

/* What the progress callback needs. */
struct send_progress {
	bool tty;
	uint64_t total;	     /* commands in the file */
	uint64_t file_bytes;
	double t0;
	int last_decile;     /* plain mode: last 10 % step printed */
	size_t width;
};

static double mono_now(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static void send_usage(FILE *out)
{
	fprintf(out,
		"usage: stratum send FILE.gcode --port PATH --printer NAME [--json] [--baud N]\n"
		"Streams FILE to a Marlin printer on PATH (a serial device, a pty or\n"
		"tcp://HOST:PORT) with line numbers, checksums and resends; progress goes to\n"
		"stderr, the report to stdout (one JSON object with --json).  Ctrl-C stops\n"
		"safely: heaters and motors off.\n");
}

/* Parse argv; returns 0, or an exit status (-1 = --help shown). */
static int send_parse(int argc, char **argv, struct send_args *a)
{
	memset(a, 0, sizeof(*a));
	for (int i = 1; i < argc; i++) {
		const char *s = argv[i], *v;
		if (!strcmp(s, "--help") || !strcmp(s, "-h")) {
			send_usage(stdout);
			return -1;
		} else if (!strcmp(s, "--json")) {
			a->json = true;
		} else if (cmd_is_opt(s, "--port")) {
			if (!(v = cmd_opt_value(argc, argv, &i, "--port")))
				goto missing;
			a->port = v;
		} else if (cmd_is_opt(s, "--printer")) {
			if (!(v = cmd_opt_value(argc, argv, &i, "--printer")))
				goto missing;
			a->printer = v;
		} else if (cmd_is_opt(s, "--baud")) {
			double b;
			if (!(v = cmd_opt_value(argc, argv, &i, "--baud")))
				goto missing;
			if (gcode_read_number(v, strlen(v), &b, NULL) || b < 300 || b > 10000000 ||
			    b != floor(b)) {
				fprintf(stderr, SEND_CMD ": --baud wants a whole number from 300 to "
							 "10000000, not '%s'\n", v);
				return ST_EXIT_USAGE;
			}
			a->baud = (long)b;
		} else if (s[0] == '-' && s[1]) {
			fprintf(stderr, SEND_CMD ": unknown option '%s'\n", s);
			send_usage(stderr);
			return ST_EXIT_USAGE;
		} else if (!a->file) {
			a->file = s;
		} else {
			fprintf(stderr, SEND_CMD ": one G-code file only ('%s' is extra)\n", s);
			return ST_EXIT_USAGE;
		}
		continue;
missing:
		fprintf(stderr, SEND_CMD ": %s needs a value\n", s);
		return ST_EXIT_USAGE;
	}
	if (!a->file || !a->port || !a->printer) {
		fprintf(stderr, SEND_CMD ": %s is required\n",
			!a->file ? "a G-code FILE" : !a->port ? "--port" : "--printer");
		send_usage(stderr);
		return ST_EXIT_USAGE;
	}
	return 0;
}

/* Read the whole file once: every line must parse and fit Marlin's
 * buffer.  Counts the commands.  Returns 0 or an exit status. */
static int send_check_file(FILE *f, const char *name, uint64_t *commands, uint64_t *bytes)
{
	struct gcode_reader *r;
	struct gcode_line g;
	struct st_error err = {0};
	int rc;

	*commands = 0;
	if (gcode_reader_new(f, name, &r, &err)) {
		fprintf(stderr, SEND_CMD ": %s\n", err.msg);
		return ST_EXIT_SOFTWARE;
	}
	while ((rc = gcode_reader_next(r, 0, &g, &err)) == 1) {
		if (g.kind == GCODE_KIND_HOST_ONLY || !g.text_len)
			continue;
		if (g.text_len > MARLIN_CMD_MAX) {
			fprintf(stderr,
				SEND_CMD ": %s: line %llu: the command is %zu bytes long; Marlin "
					 "takes at most %d (shorten it); nothing was sent\n",
				name, (unsigned long long)gcode_reader_line(r), g.text_len,
				MARLIN_CMD_MAX);
			gcode_reader_free(r);
			return ST_EXIT_DATAERR;
		}
		(*commands)++;
	}
	*bytes = gcode_reader_bytes(r);
	gcode_reader_free(r);
	if (rc < 0) {
		fprintf(stderr, SEND_CMD ": %s; nothing was sent\n", err.msg);
		return ST_EXIT_DATAERR;
	}
	return 0;
}

/* Progress: a redrawn line on a terminal, a line per 10 % otherwise. */
static void send_progress_cb(void *ctx, const struct marlin_status *st, uint64_t bytes_read)
{
	struct send_progress *p = ctx;
	double frac = p->total ? (double)st->acked / (double)p->total : 1.0;
	double el = mono_now() - p->t0;
	char temps[96] = "", eta[32] = "", layer[32] = "";
	(void)bytes_read;

	if (st->tool[0].present)
		snprintf(temps, sizeof(temps), " T %.0f/%.0f", st->tool[0].actual,
			 st->tool[0].target);
	if (st->bed.present)
		snprintf(temps + strlen(temps), sizeof(temps) - strlen(temps), " B %.0f/%.0f",
			 st->bed.actual, st->bed.target);
	if (frac > 0.01 && frac < 1) {
		double left = el / frac - el;
		snprintf(eta, sizeof(eta), " ETA %d:%02d", (int)(left / 60), (int)fmod(left, 60));
	}
	if (st->layer >= 0)
		snprintf(layer, sizeof(layer), " layer %ld", st->layer);
	if (p->tty) {
		int n = fprintf(stderr, "\r[send] %3d%% line %llu/%llu%s%s%s%s", (int)(frac * 100),
				(unsigned long long)st->acked, (unsigned long long)p->total, layer,
				temps, eta, st->paused ? " (paused)" : "");
		for (size_t w = n > 0 ? (size_t)n : 0; w < p->width; w++)
			fputc(' ', stderr);
		if (n > 0 && (size_t)n > p->width)
			p->width = (size_t)n;
		fflush(stderr);
	} else {
		int decile = (int)(frac * 10);
		if (decile != p->last_decile) {
			p->last_decile = decile;
			fprintf(stderr, SEND_CMD ": %d%% line %llu/%llu%s%s%s\n", decile * 10,
				(unsigned long long)st->acked, (unsigned long long)p->total, layer,
				temps, eta);
		}
	}
}

/* Exit status for a failed job. */
static int send_exit_for(const struct marlin_status *st, int rc)
{
	if (rc == ST_ERR_PARSE || rc == ST_ERR_ARG)
		return ST_EXIT_DATAERR;
	switch (st->fail) {
	case MARLIN_FAIL_LINK: return ST_EXIT_UNAVAILABLE;
	case MARLIN_FAIL_FIRMWARE: return ST_EXIT_FAILURE;
	case MARLIN_FAIL_PRINTER_CANCEL: return ST_EXIT_FAILURE;
	case MARLIN_FAIL_CANCELLED: return ST_EXIT_INTERRUPTED;
	default: return ST_EXIT_SOFTWARE;
	}
}

/* The final report, as text or one JSON object on stdout. */
static void send_report(const struct send_args *a, const struct marlin_status *st,
			const struct marlin_caps *caps, double seconds, long baud, bool ok,
			const char *error)
{
	double cap = baud / 10.0;
	double lps = seconds > 0 ? (double)st->acked / seconds : 0;
	double bps = seconds > 0 ? (double)st->bytes_acked / seconds : 0;
	uint64_t errors = st->line_errors + st->other_errors;

	if (a->json) {
		json_t *o = json_object();
		json_object_set_new(o, "ok", json_boolean(ok));
		json_object_set_new(o, "file", json_string(a->file));
		json_object_set_new(o, "port", json_string(a->port));
		json_object_set_new(o, "printer", json_string(a->printer));
		json_object_set_new(o, "firmware", json_string(caps->firmware_name));
		json_object_set_new(o, "lines", json_integer((json_int_t)st->acked));
		json_object_set_new(o, "resends", json_integer((json_int_t)st->resends));
		json_object_set_new(o, "resend_requests",
				    json_integer((json_int_t)st->resend_requests));
		json_object_set_new(o, "errors", json_integer((json_int_t)errors));
		json_object_set_new(o, "unknown_commands",
				    json_integer((json_int_t)st->unknown_commands));
		json_object_set_new(o, "seconds", json_real(seconds));
		json_object_set_new(o, "bytes", json_integer((json_int_t)st->bytes_acked));
		json_object_set_new(o, "bytes_written",
				    json_integer((json_int_t)st->bytes_written));
		json_object_set_new(o, "lines_per_s", json_real(lps));
		json_object_set_new(o, "bytes_per_s", json_real(bps));
		json_object_set_new(o, "baud", json_integer(baud));
		json_object_set_new(o, "link_fraction", json_real(cap > 0 ? bps / cap : 0));
		json_object_set_new(o, "advanced_ok", json_boolean(caps->advanced_ok));
		if (error)
			json_object_set_new(o, "error", json_string(error));
		char *text = json_dumps(o, JSON_COMPACT);
		if (text)
			printf("%s\n", text);
		free(text);
		json_decref(o);
		return;
	}
	printf("%s %s: %llu lines in %.2f s\n", ok ? "sent" : "stopped", a->file,
	       (unsigned long long)st->acked, seconds);
	printf("  resends %llu (%llu requests), errors %llu, unknown commands %llu\n",
	       (unsigned long long)st->resends, (unsigned long long)st->resend_requests,
	       (unsigned long long)errors, (unsigned long long)st->unknown_commands);
	printf("  %.0f lines/s, %.0f bytes/s = %.1f%% of the link (%ld baud = %.0f bytes/s)\n",
	       lps, bps, cap > 0 ? 100.0 * bps / cap : 0, baud, cap);
	if (st->last_warning[0])
		printf("  last warning: %s\n", st->last_warning);
}

int cmd_send(int argc, char **argv)
{
	struct send_args a;
	struct profile *prof = NULL;
	struct xport *x = NULL;
	struct marlin *m = NULL;
	struct gcode_reader *r = NULL;
	struct st_error err = {0};
	struct marlin_status st;
	struct send_progress prog = {0};
	uint64_t commands = 0, file_bytes = 0;
	FILE *f = NULL;
	int status, rc;

	status = send_parse(argc, argv, &a);
	if (status)
		return status < 0 ? ST_EXIT_OK : status;
	rc = profile_find(a.printer, &prof, &err);
	if (rc) {
		fprintf(stderr, SEND_CMD ": %s\n", err.msg);
		return st_exit_for(rc);
	}
	if (prof->protocol != PROFILE_PROTOCOL_MARLIN) {
		fprintf(stderr, SEND_CMD ": printer '%s' speaks %s; stratum send drives Marlin "
				     "printers only\n", a.printer,
			profile_protocol_name(prof->protocol));
		status = ST_EXIT_USAGE;
		goto out_profile;
	}
	f = fopen(a.file, "rb");
	if (!f) {
		fprintf(stderr, SEND_CMD ": cannot open %s: %s\n", a.file, strerror(errno));
		status = ST_EXIT_DATAERR;
		goto out_profile;
	}
	if ((status = send_check_file(f, a.file, &commands, &file_bytes)))
		goto out_file;
	rewind(f);

	struct xport_options xo = {0};
	long baud = a.baud ? a.baud : prof->baudrate;
	xo.baudrate = (int)baud;
	xo.dtr_reset = prof->dtr_reset;
	if (xport_open(a.port, &xo, &x, &err)) {
		fprintf(stderr, SEND_CMD ": %s\n", err.msg);
		status = ST_EXIT_UNAVAILABLE;
		goto out_file;
	}
	struct marlin_options mo;
	marlin_options_init(&mo);
	mo.rx_buffer = prof->rx_buffer_size > 0 ? (unsigned)prof->rx_buffer_size : 0;
	/* only a real serial device is reset by DTR; ptys and TCP are not */
	mo.expect_reset = prof->dtr_reset && xport_backend_of(x) == XPORT_BACKEND_SERIALPORT;
	if (marlin_new(x, &mo, &m, &err)) {
		fprintf(stderr, SEND_CMD ": %s\n", err.msg);
		status = ST_EXIT_SOFTWARE;
		goto out_port;
	}

	struct sigaction sa;
	memset(&sa, 0, sizeof(sa));
	sa.sa_handler = send_on_signal;
	sigemptyset(&sa.sa_mask);
	sigaction(SIGINT, &sa, NULL);
	sigaction(SIGTERM, &sa, NULL);

	rc = marlin_connect(m, &err);
	if (rc) {
		fprintf(stderr, SEND_CMD ": %s\n", err.msg);
		status = rc == ST_ERR_INTERNAL ? ST_EXIT_FAILURE : ST_EXIT_UNAVAILABLE;
		goto out_driver;
	}
	if (gcode_reader_new(f, a.file, &r, &err)) {
		fprintf(stderr, SEND_CMD ": %s\n", err.msg);
		status = ST_EXIT_SOFTWARE;
		goto out_driver;
	}
	prog.tty = isatty(STDERR_FILENO);
	prog.total = commands;
	prog.file_bytes = file_bytes;
	prog.last_decile = -1;
	prog.t0 = mono_now();
	if (!a.json || prog.tty)
		fprintf(stderr, SEND_CMD ": %s on %s, %llu commands\n",
			marlin_caps(m)->firmware_name[0] ? marlin_caps(m)->firmware_name : "Marlin",
			xport_describe(x), (unsigned long long)commands);
	rc = marlin_stream_file(m, r, a.file, send_progress_cb, &prog, &send_stop, &err);
	double seconds = mono_now() - prog.t0;
	if (prog.tty)
		fputc('\n', stderr);
	marlin_status(m, &st);
	if (rc == 0) {
		status = ST_EXIT_OK;
	} else {
		status = send_exit_for(&st, rc);
		fprintf(stderr, SEND_CMD ": %s\n", err.msg);
		if (st.fail == MARLIN_FAIL_CANCELLED || st.fail == MARLIN_FAIL_PRINTER_CANCEL ||
		    rc == ST_ERR_PARSE || rc == ST_ERR_ARG) {
			struct st_error e2 = {0};
			if (marlin_safe_stop(m, 10000, &e2))
				fprintf(stderr, SEND_CMD ": safe stop: %s\n", e2.msg);
			else
				fprintf(stderr, SEND_CMD ": stopped safely: heaters and motors "
							 "off\n");
		}
	}
	send_report(&a, &st, marlin_caps(m), seconds, baud, rc == 0, rc ? err.msg : NULL);
	gcode_reader_free(r);
out_driver:
	marlin_free(m);
out_port:
	xport_drain(x, 1000, NULL);
	xport_close(x);
out_file:
	fclose(f);
out_profile:
	profile_free(prof);
	return status;
}
