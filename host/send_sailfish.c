/*
 * send_sailfish.c - the Sailfish half of `stratum send`: a G-code file is
 * translated to X3G as it streams (serial/x3g.h, one line at a time, so
 * memory stays bounded whatever the file's size), an X3G file is cut into
 * commands with x3g_decode, and the commands go out as S3G packets through
 * s3g_stream_pull (serial/s3g.h).
 *
 * As on the Marlin path, the whole file is checked before the port is
 * opened (a first translation or decoding pass whose output is dropped),
 * so a bad file sends nothing; that pass also counts the commands for the
 * progress line and shows the translator's warnings, once.  Ctrl-C stops
 * safely (s3g_cancel: abort, heaters off, motors off) and exits 130.
 */
#include <errno.h>
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"
#include "gcode.h"
#include "profile.h"
#include "s3g.h"
#include "send.h"
#include "sf_source.h"
#include "st_error.h"
#include "x3g.h"
#include "xport.h"

/* The prefix of messages: stratum send, or the command that called it. */
#define SF_CMD(a) ((a)->cmd ? (a)->cmd : SEND_CMD)

struct sf_job;

/* What the progress callback needs. */
struct sf_progress {
	struct send_progress p;
	const struct sfsrc_gcode *g; /* NULL for an X3G file */
	const struct sf_job *j;
	const struct send_args *a;
};

static void sf_result(const struct sf_job *j, const struct s3g_status *st, bool ok,
		      struct send_result *res);

/* Show a line's translator warnings, as stratum x3g does (check pass only). */
static void sf_show_warnings(void *ctx, const char *name, const struct x3g_warning *w, size_t n)
{
	const char *cmd = ctx ? ctx : SEND_CMD;

	for (size_t i = 0; i < n; i++)
		fprintf(stderr, "%s: %s:%llu: warning: %s\n", cmd, name,
			(unsigned long long)w[i].line, w[i].msg);
}

/* The S3G status as the shared progress line. */
static void sf_progress_cb(void *ctx, const struct s3g_status *st)
{
	struct sf_progress *sp = ctx;
	struct send_view v = {
		.unit = "command",
		.done = st->confirmed + st->skipped,
		.total = st->total,
		.layer = sp->g ? sp->g->layer : -1,
		.tool = st->tool_temp || st->tool_target,
		.bed = st->platform_temp || st->platform_target,
		.tool_actual = st->tool_temp,
		.tool_target = st->tool_target,
		.bed_actual = st->platform_temp,
		.bed_target = st->platform_target,
		.paused = st->build_state == S3G_BUILD_PAUSED,
	};
	const struct send_args *a = sp->a;

	send_progress_show(&sp->p, &v);
	if (a->progress) {
		struct send_result r;
		sf_result(sp->j, st, false, &r);
		a->progress(a->progress_ctx, &r);
	}
}

/* Everything one Sailfish job holds. */
struct sf_job {
	const struct send_args *a;
	const struct profile *prof;
	bool x3g;		 /* FILE is X3G, not G-code */
	FILE *f;
	struct x3g_machine m;
	struct x3g_options xo;
	char build[X3G_BUILD_NAME_MAX + 1];
	struct sfsrc_gcode g;
	struct sfsrc_x3g *x;
	uint64_t commands;	 /* in the file, from the check pass */
	uint64_t lines;		 /* G-code lines in the file */
	uint64_t warnings;	 /* translator warnings */
	char firmware[32];
};

/* Set up the source over j->f from its start; 0 or an error. */
static int sf_source_open(struct sf_job *j, bool show_warnings, struct st_error *err)
{
	int rc;

	if (fseeko(j->f, j->x3g ? 0 : (off_t)j->a->offset, SEEK_SET))
		return st_error_set(err, ST_ERR_IO, "%s: cannot seek: %s", j->a->file,
				    strerror(errno));
	if (j->x3g) {
		sfsrc_x3g_open(j->x, j->f);
		return 0;
	}
	j->g.warn = show_warnings ? sf_show_warnings : NULL;
	j->g.warn_ctx = (void *)SF_CMD(j->a); /* only read, as the prefix */
	if ((rc = sfsrc_gcode_open(&j->g, j->f, j->a->file, &j->m, &j->xo, err))) {
		sfsrc_gcode_close(&j->g);
		return rc;
	}
	j->g.pre = j->a->preamble;
	j->g.pre_len = j->a->preamble ? strlen(j->a->preamble) : 0;
	return 0;
}

static void sf_source_close(struct sf_job *j)
{
	if (!j->x3g)
		sfsrc_gcode_close(&j->g);
}

/* The check pass: every command translates or decodes; count them.
 * Returns 0 or an exit status (message printed; nothing was sent). */
static int sf_check_file(struct sf_job *j)
{
	struct st_error err = {0};
	struct s3g_cmd c;
	int rc;

	if ((rc = sf_source_open(j, true, &err))) {
		fprintf(stderr, "%s: %s: %s\n", SF_CMD(j->a), j->prof->path, err.msg);
		return rc == ST_ERR_ARG ? ST_EXIT_DATAERR : ST_EXIT_SOFTWARE;
	}
	j->commands = 0;
	while ((rc = j->x3g ? sfsrc_x3g_next(j->x, &c, &err) : sfsrc_gcode_next(&j->g, &c, &err)) > 0)
		j->commands++;
	if (!j->x3g) {
		j->lines = gcode_reader_line(j->g.r);
		j->warnings = x3g_warning_total(j->g.t);
	}
	sf_source_close(j);
	if (rc < 0) {
		if (j->x3g)
			fprintf(stderr, "%s: %s: %s; nothing was sent\n", SF_CMD(j->a), j->a->file, err.msg);
		else
			fprintf(stderr, "%s: %s; nothing was sent\n", SF_CMD(j->a), err.msg);
		return rc == ST_ERR_NOMEM || rc == ST_ERR_INTERNAL ? ST_EXIT_SOFTWARE
								   : ST_EXIT_DATAERR;
	}
	return 0;
}

/* Exit status of a stream that returned rc with status st. */
static int sf_exit_for(const struct s3g_status *st, int rc)
{
	if (rc == 0)
		return st->interrupted ? ST_EXIT_INTERRUPTED : ST_EXIT_OK;
	switch (st->fail) {
	case S3G_FAIL_PRINTER:
		return ST_EXIT_FAILURE;
	case S3G_FAIL_SOURCE:
		return rc == ST_ERR_PARSE || rc == ST_ERR_IO ? ST_EXIT_DATAERR : ST_EXIT_SOFTWARE;
	case S3G_FAIL_LINK:
		return ST_EXIT_UNAVAILABLE;
	default:
		return rc == ST_ERR_IO || rc == ST_ERR_RANGE ? ST_EXIT_UNAVAILABLE
							     : ST_EXIT_SOFTWARE;
	}
}

/* G-code lines done: all, or up to that of the last command taken; the
 * stream pulls one command ahead at most. */
static uint64_t sf_lines_done(const struct sf_job *j, const struct s3g_status *st, bool ok)
{
	uint64_t done = st->confirmed + st->skipped;

	return ok ? j->lines : done == 0 ? 0 : done == j->g.pulled ? j->g.line : j->g.prev_line;
}

/* What the job did, for a caller that reports it itself. */
static void sf_result(const struct sf_job *j, const struct s3g_status *st, bool ok,
		      struct send_result *res)
{
	memset(res, 0, sizeof(*res));
	res->ok = ok;
	res->done = st->confirmed + st->skipped;
	res->total = j->commands;
	res->lines = sf_lines_done(j, st, ok);
	res->layer = j->x3g ? -1 : j->g.layer;
	res->retries = st->retries;
	res->seconds = st->elapsed_s;
	res->tool_actual = st->tool_temp;
	res->tool_target = st->tool_target;
	res->bed_actual = st->platform_temp;
	res->bed_target = st->platform_target;
	snprintf(res->firmware, sizeof(res->firmware), "%s", j->firmware);
}

/* The report, as text or one JSON object on stdout. */
static void sf_report(const struct sf_job *j, const struct s3g_status *st, long baud, bool ok,
		      const char *error)
{
	uint64_t lines = sf_lines_done(j, st, ok);
	struct send_summary s = {
		.ok = ok,
		.error = error,
		.protocol = "sailfish",
		.firmware = j->firmware,
		.unit = "commands",
		.done = st->confirmed,
		.resends = st->retries,
		.errors = st->errors,
		.unknown_commands = st->skipped,
		/* confirmed commands as framed packets: start, length, CRC */
		.bytes = st->action_bytes + 3 * (uint64_t)st->confirmed,
		.bytes_written = st->bytes_out,
		.seconds = st->elapsed_s,
		.baud = baud,
	};
	double sec = st->elapsed_s, cap = baud / 10.0;
	double both = sec > 0 && cap > 0 ? (double)(st->bytes_out + st->bytes_in) / sec / cap : 0;
	char detail[320];

	if (j->a->result) {
		sf_result(j, st, ok, j->a->result);
		return;
	}
	if (j->a->json) {
		json_t *o = send_report_json(j->a, &s);
		if (o) {
			json_object_set_new(o, "input", json_string(j->x3g ? "x3g" : "gcode"));
			if (!j->x3g) {
				json_object_set_new(o, "lines", json_integer((json_int_t)lines));
				json_object_set_new(o, "lines_per_s",
						    json_real(sec > 0 ? (double)lines / sec : 0));
				json_object_set_new(o, "warnings",
						    json_integer((json_int_t)j->warnings));
			}
			json_object_set_new(o, "commands", json_integer((json_int_t)st->confirmed));
			json_object_set_new(o, "commands_total", json_integer((json_int_t)j->commands));
			json_object_set_new(o, "commands_per_s",
					    json_real(sec > 0 ? (double)st->confirmed / sec : 0));
			json_object_set_new(o, "packets", json_integer((json_int_t)st->packets));
			json_object_set_new(o, "retries", json_integer((json_int_t)st->retries));
			json_object_set_new(o, "overflows", json_integer((json_int_t)st->overflows));
			json_object_set_new(o, "timeouts", json_integer((json_int_t)st->timeouts));
			json_object_set_new(o, "resolved", json_integer((json_int_t)st->resolved));
			json_object_set_new(o, "dup_risk", json_integer((json_int_t)st->dup_risk));
			json_object_set_new(o, "bytes_read", json_integer((json_int_t)st->bytes_in));
			json_object_set_new(o, "link_fraction_both_ways", json_real(both));
		}
		send_report_emit(o);
		return;
	}
	snprintf(detail, sizeof(detail),
		 "%llu packets: retries %llu, errors %llu, unsupported commands %llu, buffer "
		 "overflows %llu, time-outs %llu (%llu settled by asking, %llu resent unsure)",
		 (unsigned long long)st->packets,
		 (unsigned long long)st->retries, (unsigned long long)st->errors,
		 (unsigned long long)st->skipped, (unsigned long long)st->overflows,
		 (unsigned long long)st->timeouts, (unsigned long long)st->resolved,
		 (unsigned long long)st->dup_risk);
	send_report_text(j->a, &s, detail);
	if (!j->x3g)
		printf("  G-code lines %llu of %llu, translator warnings %llu\n",
		       (unsigned long long)lines, (unsigned long long)j->lines,
		       (unsigned long long)j->warnings);
	printf("  link both ways %.1f%%\n", 100.0 * both);
}

/* Connect, stream, stop safely if need be, report; returns the exit status. */
static int sf_stream(struct sf_job *j, struct xport *x, long baud)
{
	struct s3g *d = NULL;
	struct st_error err = {0};
	struct s3g_status st;
	struct sf_progress prog = {.g = j->x3g ? NULL : &j->g, .j = j, .a = j->a};
	volatile sig_atomic_t *stop;
	uint16_t fw = 0;
	int rc, status;

	if (s3g_new(x, NULL, &d, &err)) {
		fprintf(stderr, "%s: %s\n", SF_CMD(j->a), err.msg);
		return ST_EXIT_SOFTWARE;
	}
	stop = send_catch_signals();
	/* the version query proves a Sailfish board answers S3G on the port */
	if (s3g_get_version(d, SFSRC_HOST_VERSION, &fw, &err)) {
		fprintf(stderr, "%s: no answer from a Sailfish printer on %s (%s); check "
				     "that it is switched on, not busy with an SD print, and that the "
				     "baud rate matches\n", SF_CMD(j->a), xport_describe(x), err.msg);
		s3g_free(d);
		return ST_EXIT_UNAVAILABLE;
	}
	snprintf(j->firmware, sizeof(j->firmware), "Sailfish %u.%u", fw / 100u, fw % 100u);
	if ((rc = sf_source_open(j, false, &err))) {
		fprintf(stderr, "%s: %s\n", SF_CMD(j->a), err.msg);
		s3g_free(d);
		return ST_EXIT_SOFTWARE;
	}
	send_progress_start(&prog.p);
	prog.p.cmd = SF_CMD(j->a);
	prog.p.tag = j->a->cmd ? "print" : "send";
	if (!j->a->json || prog.p.tty)
		fprintf(stderr, "%s: %s on %s, %llu commands%s\n", SF_CMD(j->a), j->firmware,
			xport_describe(x), (unsigned long long)j->commands,
			j->x3g ? "" : " translated from G-code as they go");
	rc = j->x3g ? s3g_stream_pull(d, sfsrc_x3g_next, j->x, j->commands, sf_progress_cb, &prog,
				      stop, &st, &err)
		    : s3g_stream_pull(d, sfsrc_gcode_next, &j->g, j->commands, sf_progress_cb, &prog,
				      stop, &st, &err);
	send_progress_end(&prog.p);
	status = sf_exit_for(&st, rc);
	if (rc)
		fprintf(stderr, "%s: %s\n", SF_CMD(j->a), err.msg);
	else if (st.interrupted)
		fprintf(stderr, "%s: the job was cancelled after command %zu of %llu\n", SF_CMD(j->a),
			st.confirmed + st.skipped, (unsigned long long)j->commands);
	/* the link still works: leave the printer safe */
	if (st.interrupted || (rc && st.fail != S3G_FAIL_LINK)) {
		struct st_error e2 = {0};
		if (s3g_cancel(d, &e2))
			fprintf(stderr, "%s: safe stop: %s; switch the printer off by hand\n", SF_CMD(j->a),
				e2.msg);
		else
			fprintf(stderr, "%s: stopped safely: build aborted, heaters and motors "
					     "off\n", SF_CMD(j->a));
	}
	sf_report(j, &st, baud, rc == 0 && !st.interrupted,
		  rc ? err.msg : st.interrupted ? "the job was cancelled" : NULL);
	sf_source_close(j);
	s3g_free(d);
	return status;
}

int send_sailfish(const struct send_args *a, const struct profile *prof)
{
	struct sf_job *j = calloc(1, sizeof(*j));
	struct st_error err = {0};
	struct xport *x = NULL;
	int status;

	if (!j || !(j->x = calloc(1, sizeof(*j->x)))) {
		fprintf(stderr, "%s: out of memory\n", SF_CMD(a));
		free(j);
		return ST_EXIT_SOFTWARE;
	}
	j->a = a;
	j->prof = prof;
	j->x3g = send_has_ext(a->file, ".x3g");
	if (!j->x3g) {
		if (cmd_x3g_machine(prof, &j->m, &j->xo.flavor, &err)) {
			fprintf(stderr, "%s: %s\n", SF_CMD(j->a), err.msg);
			status = ST_EXIT_DATAERR;
			goto out;
		}
		/* named as `stratum x3g FILE -o NAME.x3g` names it */
		x3g_build_name(a->file, j->build, sizeof(j->build));
		j->xo.build_name = j->build;
	}
	j->f = fopen(a->file, "rb");
	if (!j->f) {
		fprintf(stderr, "%s: cannot open %s: %s\n", SF_CMD(j->a), a->file, strerror(errno));
		status = ST_EXIT_DATAERR;
		goto out;
	}
	if ((status = sf_check_file(j)))
		goto out_file;

	struct xport_options xo = {0};
	long baud = a->baud ? a->baud : prof->baudrate;
	xo.baudrate = (int)baud;
	xo.dtr_reset = prof->dtr_reset;
	if (xport_open(a->port, &xo, &x, &err)) {
		fprintf(stderr, "%s: %s\n", SF_CMD(j->a), err.msg);
		status = ST_EXIT_UNAVAILABLE;
		goto out_file;
	}
	status = sf_stream(j, x, baud);
	xport_drain(x, 1000, NULL);
	xport_close(x);
out_file:
	fclose(j->f);
out:
	free(j->x);
	free(j);
	return status;
}
