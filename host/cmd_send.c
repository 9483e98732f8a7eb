/*
 * cmd_send.c - `stratum send FILE --port PATH --printer NAME [--json]
 * [--baud N]`: stream a file to a printer with progress on stderr and a
 * final report on stdout.  G-code goes to a Marlin printer here
 * (serial/marlin.h); a sailfish profile hands over to send_sailfish
 * (host/send_sailfish.c), which shares the options, progress, report and
 * stop flag below (host/send.h).
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
#include <strings.h>
#include <time.h>
#include <unistd.h>

#include "commands.h"
#include "gcode.h"
#include "marlin.h"
#include "profile.h"
#include "send.h"
#include "st_error.h"
#include "xport.h"

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

double send_now(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

bool send_has_ext(const char *path, const char *ext)
{
	size_t n = strlen(path), k = strlen(ext);
	return n > k && !strcasecmp(path + n - k, ext);
}

static void send_usage(FILE *out)
{
	fprintf(out,
		"usage: stratum send FILE --port PATH --printer NAME [--json] [--baud N]\n"
		"Streams FILE to the printer on PATH (a serial device, a pty or\n"
		"tcp://HOST:PORT); progress goes to stderr, the report to stdout (one JSON\n"
		"object with --json).  Ctrl-C stops safely: heaters and motors off.\n"
		"  Marlin printers: FILE.gcode, with line numbers, checksums and resends.\n"
		"  Sailfish printers (FlashForge Creator Pro): FILE.gcode, translated to X3G\n"
		"  as it streams (as 'stratum x3g' does), or FILE.x3g; S3G packets.\n");
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
			fprintf(stderr, SEND_CMD ": one file only ('%s' is extra)\n", s);
			return ST_EXIT_USAGE;
		}
		continue;
missing:
		fprintf(stderr, SEND_CMD ": %s needs a value\n", s);
		return ST_EXIT_USAGE;
	}
	if (!a->file || !a->port || !a->printer) {
		fprintf(stderr, SEND_CMD ": %s is required\n",
			!a->file ? "a FILE" : !a->port ? "--port" : "--printer");
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

void send_progress_start(struct send_progress *p)
{
	memset(p, 0, sizeof(*p));
	p->cmd = SEND_CMD;
	p->tag = "send";
	p->tty = isatty(STDERR_FILENO);
	p->last_decile = -1;
	p->t0 = send_now();
}

void send_progress_show(struct send_progress *p, const struct send_view *v)
{
	double frac = v->total ? (double)v->done / (double)v->total : 1.0;
	double el = send_now() - p->t0;
	char temps[96] = "", eta[32] = "", layer[32] = "";
	int ela = (int)el;

	if (v->tool)
		snprintf(temps, sizeof(temps), " T %.0f/%.0f", v->tool_actual, v->tool_target);
	if (v->bed)
		snprintf(temps + strlen(temps), sizeof(temps) - strlen(temps), " B %.0f/%.0f",
			 v->bed_actual, v->bed_target);
	if (frac > 0.01 && frac < 1) {
		double left = el / frac - el;
		snprintf(eta, sizeof(eta), " ETA %d:%02d", (int)(left / 60), (int)fmod(left, 60));
	}
	if (v->layer >= 0)
		snprintf(layer, sizeof(layer), " layer %ld", v->layer);
	if (p->tty) {
		int n = fprintf(stderr, "\r[%s] %3d%% %d:%02d %s %llu/%llu%s%s%s%s", p->tag,
				(int)(frac * 100), ela / 60, ela % 60, v->unit, (unsigned long long)v->done,
				(unsigned long long)v->total, layer, temps, eta,
				v->paused ? " (paused)" : "");
		for (size_t w = n > 0 ? (size_t)n : 0; w < p->width; w++)
			fputc(' ', stderr);
		if (n > 0 && (size_t)n > p->width)
			p->width = (size_t)n;
		fflush(stderr);
	} else {
		int decile = (int)(frac * 10);
		if (decile != p->last_decile) {
			p->last_decile = decile;
			fprintf(stderr, "%s: %d%% %s %llu/%llu%s%s%s\n", p->cmd, decile * 10, v->unit,
				(unsigned long long)v->done, (unsigned long long)v->total, layer,
				temps, eta);
		}
	}
}

void send_progress_end(struct send_progress *p)
{
	if (p->tty)
		fputc('\n', stderr);
}

/* What the Marlin progress callback needs. */
struct marlin_progress {
	struct send_progress p;
	uint64_t total; /* commands in the file */
};

void send_view_marlin(const struct marlin_status *st, uint64_t total, struct send_view *v)
{
	*v = (struct send_view){
		.unit = "line",
		.done = st->acked,
		.total = total,
		.layer = st->layer,
		.tool = st->tool[0].present,
		.bed = st->bed.present,
		.tool_actual = st->tool[0].actual,
		.tool_target = st->tool[0].target,
		.bed_actual = st->bed.actual,
		.bed_target = st->bed.target,
		.paused = st->paused,
	};
}

/* Marlin's status as the shared progress line. */
static void send_progress_cb(void *ctx, const struct marlin_status *st, uint64_t bytes_read)
{
	struct marlin_progress *mp = ctx;
	struct send_view v;

	(void)bytes_read;
	send_view_marlin(st, mp->total, &v);
	send_progress_show(&mp->p, &v);
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

json_t *send_report_json(const struct send_args *a, const struct send_summary *s)
{
	double cap = s->baud / 10.0;
	double bps = s->seconds > 0 ? (double)s->bytes / s->seconds : 0;
	json_t *o = json_object();

	if (!o)
		return NULL;
	json_object_set_new(o, "ok", json_boolean(s->ok));
	json_object_set_new(o, "file", json_string(a->file));
	json_object_set_new(o, "port", json_string(a->port));
	json_object_set_new(o, "printer", json_string(a->printer));
	json_object_set_new(o, "protocol", json_string(s->protocol));
	json_object_set_new(o, "firmware", json_string(s->firmware));
	json_object_set_new(o, "resends", json_integer((json_int_t)s->resends));
	json_object_set_new(o, "errors", json_integer((json_int_t)s->errors));
	json_object_set_new(o, "unknown_commands", json_integer((json_int_t)s->unknown_commands));
	json_object_set_new(o, "seconds", json_real(s->seconds));
	json_object_set_new(o, "bytes", json_integer((json_int_t)s->bytes));
	json_object_set_new(o, "bytes_written", json_integer((json_int_t)s->bytes_written));
	json_object_set_new(o, "bytes_per_s", json_real(bps));
	json_object_set_new(o, "baud", json_integer(s->baud));
	json_object_set_new(o, "link_fraction", json_real(cap > 0 ? bps / cap : 0));
	if (s->error)
		json_object_set_new(o, "error", json_string(s->error));
	return o;
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

void send_report_text(const struct send_args *a, const struct send_summary *s,
		      const char *detail)
{
	double cap = s->baud / 10.0;
	double ups = s->seconds > 0 ? (double)s->done / s->seconds : 0;
	double bps = s->seconds > 0 ? (double)s->bytes / s->seconds : 0;

	printf("%s %s: %llu %s in %.2f s\n", s->ok ? "sent" : "stopped", a->file,
	       (unsigned long long)s->done, s->unit, s->seconds);
	if (detail)
		printf("  %s\n", detail);
	printf("  %.0f %s/s, %.0f bytes/s = %.1f%% of the link (%ld baud = %.0f bytes/s)\n", ups,
	       s->unit, bps, cap > 0 ? 100.0 * bps / cap : 0, s->baud, cap);
}

/* The Marlin job's report, as text or one JSON object on stdout. */
static void send_report(const struct send_args *a, const struct marlin_status *st,
			const struct marlin_caps *caps, double seconds, long baud, bool ok,
			const char *error)
{
	struct send_summary s = {
		.ok = ok,
		.error = error,
		.protocol = "marlin",
		.firmware = caps->firmware_name,
		.unit = "lines",
		.done = st->acked,
		.resends = st->resends,
		.errors = st->line_errors + st->other_errors,
		.unknown_commands = st->unknown_commands,
		.bytes = st->bytes_acked,
		.bytes_written = st->bytes_written,
		.seconds = seconds,
		.baud = baud,
	};
	char detail[320];

	if (a->json) {
		json_t *o = send_report_json(a, &s);
		if (o) {
			json_object_set_new(o, "lines", json_integer((json_int_t)st->acked));
			json_object_set_new(o, "lines_per_s",
					    json_real(seconds > 0 ? (double)st->acked / seconds : 0));
			json_object_set_new(o, "resend_requests",
					    json_integer((json_int_t)st->resend_requests));
			json_object_set_new(o, "advanced_ok", json_boolean(caps->advanced_ok));
		}
		send_report_emit(o);
		return;
	}
	snprintf(detail, sizeof(detail),
		 "resends %llu (%llu requests), errors %llu, unknown commands %llu",
		 (unsigned long long)st->resends, (unsigned long long)st->resend_requests,
		 (unsigned long long)s.errors, (unsigned long long)st->unknown_commands);
	send_report_text(a, &s, detail);
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
	struct marlin_progress prog;
	volatile sig_atomic_t *stop;
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
	if (prof->protocol == PROFILE_PROTOCOL_SAILFISH) {
		status = send_sailfish(&a, prof);
		goto out_profile;
	}
	if (send_has_ext(a.file, ".x3g")) {
		fprintf(stderr, SEND_CMD ": %s is X3G, which only Sailfish printers take; printer "
				     "'%s' speaks %s: send it the G-code\n", a.file, a.printer,
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

	stop = send_catch_signals();

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
	send_progress_start(&prog.p);
	prog.total = commands;
	if (!a.json || prog.p.tty)
		fprintf(stderr, SEND_CMD ": %s on %s, %llu commands\n",
			marlin_caps(m)->firmware_name[0] ? marlin_caps(m)->firmware_name : "Marlin",
			xport_describe(x), (unsigned long long)commands);
	rc = marlin_stream_file(m, r, a.file, send_progress_cb, &prog, stop, &err);
	double seconds = send_now() - prog.p.t0;
	send_progress_end(&prog.p);
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
